//! Bench binary that prints what criterion does not: for a full fit of the
//! three outputs (GPS, default options) on the shipped COMAU campaign, the ψ
//! evaluations spent, the ln ψ reached per axis and the wall time, for the
//! constant, linear and quadratic trends.
//! Run: `cargo bench --bench kriging_summary`. Timings with statistics:
//! `cargo bench --bench kriging` (criterion).

mod common;

use robokrige::kriging::{KrigingOptions, TrendKind};
use robokrige::model::ErrorModel;
use robokrige::space::Space;
use std::time::Instant;

fn main() {
    let data = common::campaign();
    for kind in [TrendKind::Constant, TrendKind::Linear, TrendKind::Quadratic] {
        let opts = KrigingOptions::default().trend(kind);
        let t0 = Instant::now();
        let model = ErrorModel::fit(&data, Space::Ejs, &opts).expect("fit");
        let secs = t0.elapsed().as_secs_f64();
        let evals: usize = model.reports().iter().map(|r| r.evals).sum();
        let lp: Vec<String> = model
            .reports()
            .iter()
            .map(|r| format!("{:.4}", r.ln_psi))
            .collect();
        println!(
            "{kind:?}: fit of ex, ey, ez in {secs:.2} s, {evals} ψ evaluations, ln ψ = [{}]",
            lp.join(", ")
        );
    }
}
