//! The prediction CSV (`robokrige predict -o`): one row per pose of a
//! [`Dataset`], in its order.
//!
//! Columns: `id` (the dataset's ids, else the 0-based row index),
//! `q1..qN`, `dir1..dirN`, then per axis `a ∈ {ex, ey, ez}`:
//!
//! | column | meaning |
//! |---|---|
//! | `pred_a` | predicted error `δ̂_a`, mm |
//! | `std_a` | `√MSE` of the predicted error, calibrated on the model's leave-one-out residuals (the calibration's uncertainty included, measurement noise not), mm |
//! | `std_new_a` | of a new measurement: `√(std_a² + σ_a²)`, `σ_a` the model's noise standard deviation (from its nugget), mm |
//! | `a` | the measured error, when the dataset has errors |
//!
//! Numbers use Rust's shortest round-trip `Display` for `f64`.

use super::Dataset;
use crate::Result;
use std::path::Path;

/// The error axes, in column order.
const AXES: [&str; 3] = ["ex", "ey", "ez"];

/// Write the predictions `mean` ± `std` (one per row of `data`) and the
/// model's noise standard deviation per axis `noise_std` to `path`
/// (atomically, see [`crate::output::write_atomic`]).
pub fn write_predictions(
    path: &Path,
    data: &Dataset,
    mean: &[[f64; 3]],
    std: &[[f64; 3]],
    noise_std: [f64; 3],
) -> Result<()> {
    crate::output::write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        w.write_record(header(data))?;
        for k in 0..data.len() {
            let id = data.ids.as_ref().map_or(k.to_string(), |v| v[k].clone());
            let mut row = vec![id];
            row.extend(data.q[k].iter().map(f64::to_string));
            row.extend(data.dir[k].iter().map(|d| format!("{d}")));
            row.extend(mean[k].iter().map(f64::to_string));
            row.extend(std[k].iter().map(f64::to_string));
            row.extend((0..3).map(|a| std[k][a].hypot(noise_std[a]).to_string()));
            if let Some(e) = &data.errors {
                row.extend(e[k].iter().map(f64::to_string));
            }
            w.write_record(&row)?;
        }
        w.flush()
    })
}

/// Column names in output order.
fn header(data: &Dataset) -> Vec<String> {
    let n = data.n_joints();
    let mut header = vec!["id".to_string()];
    header.extend((1..=n).map(|i| format!("q{i}")));
    header.extend((1..=n).map(|i| format!("dir{i}")));
    header.extend(AXES.iter().map(|a| format!("pred_{a}")));
    header.extend(AXES.iter().map(|a| format!("std_{a}")));
    header.extend(AXES.iter().map(|a| format!("std_new_{a}")));
    if data.errors.is_some() {
        header.extend(AXES.iter().map(|a| a.to_string()));
    }
    header
}
