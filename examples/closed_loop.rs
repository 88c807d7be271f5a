//! fit → CV → compensate → diagnose (`cargo run --release --example closed_loop`).
use robokrige::compensate::{CompensationOptions, compensate};
use robokrige::cv::cross_validate_refit;
use robokrige::dataset::read_csv;
use robokrige::diagnose::{DiagnoseOptions, diagnose};
use robokrige::kinematics;
use robokrige::kriging::KrigingOptions;
use robokrige::model::ErrorModel;
use robokrige::space::Space;
use robokrige::trajectory::Trajectory;
use std::path::Path;

fn main() -> robokrige::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let data = read_csv(&dir.join("comau_lhs.csv"))?;
    let opts = KrigingOptions::recommended();
    let model = ErrorModel::fit(&data, Space::Ejs, &opts)?; // EJS, nugget, family by CV
    // 2. honest accuracy: 10-fold CV, refitted in every fold
    let cv = cross_validate_refit(&data, 10, 1, |t| ErrorModel::fit(t, Space::Ejs, &opts))?;
    println!("CV mean 3D error {:.4} mm", cv.summary.mean_3d_mm);
    // 3. pre-compensate the Ø100 mm circle for the nominal controller
    let robot = kinematics::preset("comau-nj220")?;
    let circle = Trajectory::read_csv(&dir.join("comau_circle.csv"))?;
    let comp = compensate(&robot, &model, &circle, &CompensationOptions::default())?;
    println!(
        "compensated: {} iterations, {:?}",
        comp.history.len(),
        comp.stop
    );
    // 4. what is the model missing? (a campaign with a tracker bump in it)
    let bumped = read_csv(&dir.join("comau_tracker_step.csv"))?;
    let found = diagnose(&bumped, &DiagnoseOptions::default(), &|_| {})?;
    for e in found.effects.iter().filter(|e| e.accepted) {
        println!("added {} (q {:.4})", e.label, e.q_value);
    }
    let (before, after) = (found.before.pooled_rmse_mm, found.after.pooled_rmse_mm);
    println!("CV RMSE {before:.4} -> {after:.4} mm");
    Ok(())
}
