//! Simulate a COMAU campaign with the library and summarise it.
//! Run: `cargo run --release --example simulate_campaign`.

use robokrige::kinematics::preset;
use robokrige::sim::{CampaignKind, CampaignSpec, SimOutput, simulate};
use robokrige::stats::summarize;

fn main() -> robokrige::Result<()> {
    let robot = preset("comau-nj220")?;
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, 1);
    spec.poses = 100;
    let (SimOutput::Measurements(data), truth) = simulate(&robot, &spec)? else {
        unreachable!("an LHS campaign is measured");
    };
    let s = summarize(data.errors_or_err()?);
    println!(
        "{} poses: mean 3D error {:.3} mm, max {:.3} mm; noise floor {:?} mm",
        data.len(),
        s.mean_3d_mm,
        s.max_3d_mm,
        truth.noise_floor_mm.unwrap_or_default()
    );
    Ok(())
}
