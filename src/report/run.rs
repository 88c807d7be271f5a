//! `run`: the record of the steps that ran.

use serde_json::{Value, json};
use std::path::Path;

/// One step as `run --json` records it: its number (from 1) and argument
/// list, and once it ran, its wall time (s) and its error, if any.
pub fn step(step: usize, argv: &[String], ran: Option<(f64, Option<String>)>) -> Value {
    match ran {
        None => json!({"step": step, "command": argv}),
        Some((seconds, error)) => json!({
            "step": step, "command": argv, "seconds": seconds, "error": error,
        }),
    }
}

/// The JSON of `run --json`: the config file, the folder its paths are
/// relative to, and its `steps`.
pub fn json(config: &Path, folder: &Path, steps: &[Value]) -> Value {
    json!({"config": config, "folder": folder, "steps": steps})
}
