//! Bench binary: EJS&GA basis selection (seed 004) over the 91 quadratic
//! candidates on the shipped COMAU campaign (m = 300), all three outputs,
//! including the ξ fits before and after. Prints the wall time, the selected
//! sizes and the fitness history. Run: `cargo bench --bench ga_selection`.

mod common;

use robokrige::kriging::KrigingOptions;
use robokrige::params::{ErrorModelParams, TrendSpec};
use robokrige::selection::Selection;
use std::time::Instant;

fn main() {
    let data = common::campaign();
    let t0 = Instant::now();
    let model = ErrorModelParams::new()
        .kriging(KrigingOptions::default())
        .trend(TrendSpec::Ga {
            folds: 10,
            kinematic: None,
        })
        .check()
        .and_then(|p| p.fit(&data))
        .expect("GA fit");
    let Some(Selection::Ga { outputs: ga }) = model.selection() else {
        panic!("the GA fit records its selection");
    };
    let secs = t0.elapsed().as_secs_f64();
    println!("EJS&GA selection + fit of ex, ey, ez: {secs:.2} s");
    for ((axis, r), out) in ["ex", "ey", "ez"].iter().zip(ga).zip(model.reports()) {
        let hist: Vec<String> = r
            .history
            .iter()
            .step_by(5)
            .map(|v| format!("{v:.4}"))
            .collect();
        println!(
            "  {axis}: {} terms of {} ({} dropped as dependent), CV-RMSE {:.4} mm after {} generations ({} chromosomes); best every 5 generations: {}",
            out.trend_terms.len(),
            r.candidates,
            r.dropped.len(),
            r.cv_rmse_mm,
            r.generations,
            r.evaluations,
            hist.join(" ")
        );
    }
}
