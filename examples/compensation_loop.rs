//! The compensation loop in a few lines: fit an EJS model, compensate the
//! shipped Ø100 mm circle iteratively, print the iteration history, and run
//! nominal and compensated commands on the simulated robot.
//! Run: `cargo run --release --example compensation_loop`.

use robokrige::compensate::{CompensationOptions, compensate};
use robokrige::dataset::read_csv;
use robokrige::kinematics;
use robokrige::kriging::KrigingOptions;
use robokrige::model::ErrorModel;
use robokrige::sim::{Truth, execute, rng_for};
use robokrige::space::Space;
use robokrige::stats::position_error_table;
use robokrige::trajectory::Trajectory;
use std::path::Path;

fn main() -> robokrige::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let data = read_csv(&dir.join("comau_lhs.csv"))?;
    let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default())?;
    let robot = kinematics::preset("comau-nj220")?;
    let circle = Trajectory::read_csv(&dir.join("comau_circle.csv"))?;
    let comp = compensate(&robot, &model, &circle, &CompensationOptions::default())?;
    for it in &comp.history {
        println!(
            "iteration {}: RMSE of the change {:.5} mm, λ flips {}",
            it.iteration, it.rmse_change_mm, it.direction_flips
        );
    }
    println!("stopped: {:?}", comp.stop);
    // check on the simulator (its truth is used only here, never in the engine)
    let text = std::fs::read_to_string(dir.join("comau_circle.truth.json"))
        .map_err(|e| robokrige::Error::io(&dir, e))?;
    let truth: Truth = serde_json::from_str(&text).map_err(|e| robokrige::Error::Json {
        context: "truth".into(),
        source: e,
    })?;
    let mut rng = rng_for(1, "example");
    for (name, commands) in [("nominal", &circle), ("compensated", &comp.commands)] {
        let run = execute(
            &truth.robot,
            commands,
            &robot.home,
            None,
            &truth.spec.effects,
            &mut rng,
        )?;
        let errors: Vec<[f64; 3]> = run
            .measured
            .iter()
            .zip(&circle.poses)
            .map(|(m, p)| {
                let t = p.translation.vector;
                [m[0] - t[0], m[1] - t[1], m[2] - t[2]]
            })
            .collect();
        let t = position_error_table(&errors);
        println!(
            "{name:>12}: mean 3D error {:.4} mm, max {:.4} mm",
            t.mean_abs_mm, t.max_abs_mm
        );
    }
    Ok(())
}
