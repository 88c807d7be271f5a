//! A custom trend basis: universal Kriging with a hand-picked set of monomials
//! in the normalised EJS inputs (here the constant, every λ_j, and θ2·θ3),
//! compared with the constant trend by closed-form 10-fold CV.
//! Run: `cargo run --release --example custom_basis`.

use robokrige::cv::cross_validate_closed_form;
use robokrige::dataset::read_csv;
use robokrige::kriging::{KrigingOptions, Monomials, Trend, TrendModel};
use robokrige::model::ErrorModel;
use robokrige::params::{ErrorModelParams, TrendSpec};
use robokrige::space::Space;
use std::path::Path;

fn main() -> robokrige::Result<()> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let data = read_csv(&dir.join("comau_lhs.csv"))?;
    let n = data.n_joints();
    let d = Space::Ejs.dim(n); // [θ1..θ6, λ1..λ6]
    let mut exponents = vec![vec![0u8; d]]; // 1
    for j in 0..n {
        let mut e = vec![0u8; d];
        e[n + j] = 1; // λ_j
        exponents.push(e);
    }
    let mut e = vec![0u8; d];
    e[1] = 1;
    e[2] = 1; // θ2·θ3
    exponents.push(e);
    let basis = Monomials { dim: d, exponents };
    let names = Space::Ejs.names(n);
    let terms: Vec<String> = (0..basis.len())
        .map(|j| basis.term_name(j, &names))
        .collect();
    println!("custom trend: {}", terms.join(" + "));
    let opts = KrigingOptions::default();
    let trend = Trend::from(basis);
    let custom = ErrorModelParams::new()
        .kriging(opts.clone())
        .trend(TrendSpec::PerAxis(Box::new([
            trend.clone(),
            trend.clone(),
            trend,
        ])))
        .check()?
        .fit(&data)?;
    let constant = ErrorModel::fit(&data, Space::Ejs, &opts)?;
    for (name, m) in [("constant", &constant), ("custom", &custom)] {
        let cv = cross_validate_closed_form(&data, m, 10, 1)?;
        println!(
            "{name:>8} trend: closed-form 10-fold CV mean 3D error {:.4} mm, RMSE x/y/z {:.4} / {:.4} / {:.4}",
            cv.summary.mean_3d_mm, cv.summary.rms_mm[0], cv.summary.rms_mm[1], cv.summary.rms_mm[2]
        );
    }
    Ok(())
}
