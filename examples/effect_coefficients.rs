//! The effects a diagnosis added, fitted on other campaigns: their trend
//! coefficients (mm per unit, 95 %) on each, and the difference of the
//! first two. With a campaign and the same campaign with an effect planted
//! into it, the difference is the planted part, the robot's own response
//! taken out (the README's "Planted into the real rows").
//!
//! ```sh
//! robokrige diagnose planted.csv --json diag.json
//! cargo run --release --example effect_coefficients -- diag.json original.csv planted.csv
//! ```

use robokrige::diagnose::{DiagnoseOptions, fit_with_effects};
use robokrige::features::Feature;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let [report, campaigns @ ..] = args.as_slice() else {
        return Err(
            "usage: effect_coefficients DIAGNOSIS.json CAMPAIGN.csv [CAMPAIGN.csv …]".into(),
        );
    };
    let json: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(report)?)?;
    let extras: Vec<Feature> = serde_json::from_value(json["extras"].clone())?;
    let columns: Vec<String> = extras.iter().flat_map(Feature::names).collect();
    let mut all = Vec::new();
    for path in campaigns {
        let data = robokrige::dataset::read_csv(path.as_ref())?;
        // as `diagnose` fits it (a whole campaign: ξ converged on its
        // seeded subset of `refit_rows`, then one solve on all rows)
        let o = DiagnoseOptions::default().for_rows(data.len());
        let model = fit_with_effects(&data, &o, &extras)?;
        println!("{path} ({} rows):", data.len());
        let coef: Vec<Option<[(f64, f64); 3]>> =
            columns.iter().map(|c| model.trend_coefficient(c)).collect();
        for (c, v) in columns.iter().zip(&coef) {
            if let Some(v) = v {
                println!(
                    "  {c}: {:.4} / {:.4} / {:.4} ± {:.4} / {:.4} / {:.4}",
                    v[0].0,
                    v[1].0,
                    v[2].0,
                    1.96 * v[0].1,
                    1.96 * v[1].1,
                    1.96 * v[2].1
                );
            }
        }
        all.push(coef);
    }
    if let [a, b, ..] = all.as_slice() {
        println!("second − first:");
        for (c, (x, y)) in columns.iter().zip(a.iter().zip(b)) {
            if let (Some(x), Some(y)) = (x, y) {
                println!(
                    "  {c}: {:.4} / {:.4} / {:.4}",
                    y[0].0 - x[0].0,
                    y[1].0 - x[1].0,
                    y[2].0 - x[2].0
                );
            }
        }
    }
    Ok(())
}
