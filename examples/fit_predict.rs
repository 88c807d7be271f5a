//! Fit an EJS Kriging error model on the shipped COMAU campaign and predict
//! the verification poses. Run: `cargo run --release --example fit_predict`.

use robokrige::dataset::read_csv;
use robokrige::kriging::KrigingOptions;
use robokrige::model::ErrorModel;
use robokrige::space::Space;
use robokrige::stats::summarize;
use std::path::Path;

fn main() -> robokrige::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let train = read_csv(&dir.join("comau_lhs.csv"))?;
    let verify = read_csv(&dir.join("comau_verify.csv"))?;
    let model = ErrorModel::fit(&train, Space::Ejs, &KrigingOptions::default())?;
    let pred = model.predict_dataset(&verify)?;
    let measured = verify.errors_or_err()?;
    let residual: Vec<[f64; 3]> = measured
        .iter()
        .zip(&pred.mean)
        .map(|(m, p)| [m[0] - p[0], m[1] - p[1], m[2] - p[2]])
        .collect();
    println!(
        "verification poses: mean 3D error {:.3} mm; model residual {:.3} mm",
        summarize(measured).mean_3d_mm,
        summarize(&residual).mean_3d_mm
    );
    Ok(())
}
