//! Text reports of the studies: the tables and summaries the command line
//! prints, and the Markdown files it writes. Each is a function of a
//! study's result (and of the few names the caller gives it), returning
//! the text; printing and writing stay with the caller. The charts are
//! `plot`'s.
//!
//! Numbers are formatted for reading (mm to 4 decimals, most often), not
//! for round trips: the JSON outputs carry the full values.

pub mod batch;
pub mod compensate;
pub mod cv;
pub mod demo;
pub mod diagnose;
pub mod fit;
pub mod holdout;
pub mod import;
pub mod physics;
pub mod plan;
pub mod predict;
pub mod run;
pub mod simulate;

/// `x / y / z` to 4 decimals (mm).
pub fn xyz(v: &[f64; 3]) -> String {
    format!("{:.4} / {:.4} / {:.4}", v[0], v[1], v[2])
}

/// The 95 % interval coverage per axis, `x / y / z` to 3 decimals.
fn coverage3(sc: &crate::stats::PredictiveScores) -> String {
    let c = &sc.coverage_95;
    format!("{:.3} / {:.3} / {:.3}", c[0], c[1], c[2])
}

/// The settings of a fit ([`ErrorModelParams::settings`](crate::params::ErrorModelParams::settings))
/// as a JSON object of strings.
fn settings(params: &crate::params::ErrorModelParams) -> serde_json::Value {
    let map: serde_json::Map<String, serde_json::Value> = params
        .settings()
        .into_iter()
        .map(|(k, v)| (k.to_string(), serde_json::Value::String(v)))
        .collect();
    serde_json::Value::Object(map)
}
