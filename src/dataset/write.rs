//! Writing the measurement CSV (format: see the [module docs](super)).
//!
//! Column order: `id`, `q1..qN`, `dir1..dirN` (always, as `1`/`-1`),
//! `ex,ey,ez` and `x,y,z` when present, numeric covariates, text columns.
//! Numbers use Rust's shortest round-trip `Display` for `f64`; missing (NaN)
//! covariate values are written as empty cells. Reading the output back gives
//! an equal [`Dataset`] except that `dir_source` becomes [`DirSource::Given`](super::DirSource::Given)
//! (and that ids and text cells come back trimmed of surrounding whitespace).

use std::io::{self, Write};
use std::path::Path;

use super::Dataset;
use crate::{Error, Result};

/// Write `d` to the file at `path` (created or truncated).
///
/// The dataset is checked with [`Dataset::validate`] first; nothing is
/// written when that fails.
pub fn write_csv(path: &Path, d: &Dataset) -> Result<()> {
    d.validate()?;
    crate::output::write_atomic(path, |w| write_records(w, d))
}

/// Write `d` as CSV to any writer. I/O failures are reported as
/// [`Error::Io`] with the path `<writer>`.
pub fn write_csv_to(writer: impl Write, d: &Dataset) -> Result<()> {
    d.validate()?;
    write_records(writer, d).map_err(|e| Error::io("<writer>", e))
}

/// Header and rows of a validated dataset.
fn write_records(writer: impl Write, d: &Dataset) -> io::Result<()> {
    let mut wtr = csv::Writer::from_writer(writer);
    wtr.write_record(header(d)).map_err(io::Error::from)?;
    for i in 0..d.len() {
        wtr.write_record(row(d, i)).map_err(io::Error::from)?;
    }
    wtr.flush()
}

/// Column names in output order.
fn header(d: &Dataset) -> Vec<String> {
    let n = d.n_joints();
    let mut h = Vec::new();
    if d.ids.is_some() {
        h.push("id".to_string());
    }
    h.extend((1..=n).map(|k| format!("q{k}")));
    h.extend((1..=n).map(|k| format!("dir{k}")));
    if d.errors.is_some() {
        h.extend(["ex", "ey", "ez"].map(String::from));
    }
    if d.positions.is_some() {
        h.extend(["x", "y", "z"].map(String::from));
    }
    h.extend(d.covariates.iter().map(|c| c.name.clone()));
    h.extend(d.text.iter().map(|t| t.name.clone()));
    h
}

/// Cells of row `i`, in the order of [`header`].
fn row(d: &Dataset, i: usize) -> Vec<String> {
    let mut r = Vec::new();
    if let Some(ids) = &d.ids {
        r.push(ids[i].clone());
    }
    r.extend(d.q[i].iter().map(f64::to_string));
    r.extend(
        d.dir[i]
            .iter()
            .map(|&v| if v > 0.0 { "1" } else { "-1" }.to_string()),
    );
    for triplets in [&d.errors, &d.positions].into_iter().flatten() {
        r.extend(triplets[i].iter().map(f64::to_string));
    }
    r.extend(d.covariates.iter().map(|c| covariate_cell(c.values[i])));
    r.extend(d.text.iter().map(|t| t.values[i].clone()));
    r
}

/// A covariate value, or an empty cell when missing.
fn covariate_cell(v: f64) -> String {
    if v.is_nan() {
        String::new()
    } else {
        v.to_string()
    }
}
