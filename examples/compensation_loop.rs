//! The compensation loop in a few lines: fit an EJS model, compensate the
//! shipped Ø100 mm circle iteratively, print the iteration history, and run
//! nominal and compensated commands on the simulated robot.
//! Run: `cargo run --release --example compensation_loop`.

use robokrige::compensate::{CompensationOptions, compensate};
use robokrige::dataset::read_csv;
use robokrige::kinematics;
use robokrige::kriging::KrigingOptions;
use robokrige::model::ErrorModel;
use robokrige::space::Space;
use robokrige::study::{Targets, evaluate, load_truth};
use std::path::Path;

fn main() -> robokrige::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let data = read_csv(&dir.join("comau_lhs.csv"))?;
    let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default())?;
    let robot = kinematics::preset("comau-nj220")?;
    let targets = Targets::read(&dir.join("comau_circle.csv"), &robot, None, &robot.home)?;
    let comp = compensate(
        &robot,
        &model,
        &targets.traj,
        &CompensationOptions::default(),
    )?;
    for it in &comp.history {
        println!(
            "iteration {}: RMSE of the change {:.5} mm, λ flips {}",
            it.iteration, it.rmse_change_mm, it.direction_flips
        );
    }
    println!("stopped: {:?}", comp.stop);
    // check on the simulator (its truth is used only here, never in the engine)
    let truth_path = dir.join("comau_circle.truth.json");
    let truth = load_truth(&truth_path)?;
    let (ev, _) = evaluate(
        &truth_path,
        &truth,
        &targets,
        &comp.commands,
        &robot.home,
        1,
    )?;
    for (name, t) in [("nominal", ev.before), ("compensated", ev.after)] {
        println!(
            "{name:>12}: mean 3D error {:.4} mm, max {:.4} mm",
            t.mean_abs_mm, t.max_abs_mm
        );
    }
    Ok(())
}
