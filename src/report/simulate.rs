//! `simulate`: the summary of a simulated campaign.

use crate::sim::{SimOutput, Truth};
use crate::stats::summarize;
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// The summary of a simulated campaign `out` written to `output`, its truth
/// to `truth_path` (the JSON of `simulate --json`): for measurements the
/// rows, the error statistics, the truth's noise floor and direction
/// spread; for a trajectory its points.
pub fn json(out: &SimOutput, truth: &Truth, (output, truth_path): (&Path, &Path)) -> Value {
    match out {
        SimOutput::Measurements(d) => {
            let s = summarize(d.errors.as_deref().unwrap_or(&[]));
            serde_json::json!({
                "output": output, "truth": truth_path, "rows": d.q.len(),
                "error": s,
                "noise_floor_mm": truth.noise_floor_mm,
                "direction_spread_mm": truth.direction_spread_mm,
            })
        }
        SimOutput::Trajectory(t) => {
            serde_json::json!({"output": output, "truth": truth_path, "points": t.len()})
        }
    }
}

/// What `simulate` prints, from its [`json`] summary.
pub fn summary(s: &Value) -> String {
    let f = |v: &Value| v.as_f64().map_or("-".into(), |x| format!("{x:.4}"));
    let v3 = |v: &Value| {
        v.as_array().map_or("-".into(), |a| {
            a.iter().map(&f).collect::<Vec<_>>().join(" / ")
        })
    };
    let mut out = format!(
        "wrote {} ({})\n",
        s["output"].as_str().unwrap_or(""),
        s["truth"]
            .as_str()
            .map_or(String::new(), |t| format!("truth: {t}"))
    );
    if let Some(n) = s.get("points") {
        let _ = writeln!(out, "trajectory points: {n}");
        return out;
    }
    let e = &s["error"];
    let _ = writeln!(out, "rows: {}", s["rows"]);
    let _ = writeln!(
        out,
        "3D error (mm): mean {}  std {}  min {}  max {}",
        f(&e["mean_3d_mm"]),
        f(&e["std_3d_mm"]),
        f(&e["min_3d_mm"]),
        f(&e["max_3d_mm"])
    );
    let _ = writeln!(out, "per-axis RMS x / y / z (mm): {}", v3(&e["rms_mm"]));
    let _ = writeln!(
        out,
        "direction spread |δ(λ=+1) − δ(λ=−1)| x / y / z (mm, truth, mean over poses): {}",
        v3(&s["direction_spread_mm"])
    );
    let _ = writeln!(
        out,
        "noise floor σ x / y / z (mm, truth): {}",
        v3(&s["noise_floor_mm"])
    );
    out
}
