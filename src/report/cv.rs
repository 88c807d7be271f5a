//! `cv`: a cross-validation's figures, and the table of methods compared.

use crate::cv::{CvResult, Folds, HyperSubset};
use crate::methods::Method;
use crate::params::ErrorModelParams;
use crate::{Error, Result};
use serde_json::{Value, json};
use std::fmt::Write as _;
use std::path::Path;

/// How a CV of `k` folds partitioned the rows: `10-fold CV`, or
/// `leave-one-group-out CV over the 4 groups of 'cube'`.
pub fn how(folds: &Folds, k: usize) -> String {
    match folds {
        Folds::Random { .. } => format!("{k}-fold CV"),
        Folds::Groups(col) => format!("leave-one-group-out CV over the {k} groups of '{col}'"),
    }
}

/// The lines of a closed-form CV whose hyperparameters were chosen on a
/// subset of the campaign's `rows` rows: that fit, and the refit of all
/// rows; empty when they were chosen on all rows (`h` is `None`).
pub fn hyper_subset(h: Option<&HyperSubset>, rows: usize) -> String {
    let Some(h) = h else {
        return String::new();
    };
    format!(
        "hyperparameters chosen on the first {} rows in {:.1} s\nrefit on all {rows} rows at those values in {:.1} s\n",
        h.rows, h.seconds, h.refit_seconds
    )
}

/// The JSON of `cv --json` for one model choice: the result, the data
/// file and the settings ([`ErrorModelParams::settings`]).
pub fn json(res: &CvResult, data: &Path, params: &ErrorModelParams) -> Result<Value> {
    let mut v = serde_json::to_value(res)
        .map_err(|e| Error::InvalidParameter(format!("cv result: {e}")))?;
    if let Some(o) = v.as_object_mut() {
        o.insert("data".into(), json!(data));
        o.insert("settings".into(), super::settings(params));
    }
    Ok(v)
}

/// What `cv` prints for one model choice: how it was cross-validated
/// (`folds`, [`how`]), of which file (`data`) of how many `rows`, with
/// which settings ([`ErrorModelParams::settings_line`]), then the per-axis
/// RMSE, the 3D error and the predictive scores.
pub fn summary(
    res: &CvResult,
    folds: &Folds,
    (data, rows): (&Path, usize),
    params: &ErrorModelParams,
) -> String {
    let s = &res.summary;
    let mut out = format!(
        "{} ({}) of {} on {rows} rows ({}), {:.1} s\n",
        how(folds, res.folds),
        res.mode,
        data.display(),
        params.settings_line(),
        res.seconds
    );
    let _ = writeln!(
        out,
        "  RMSE x / y / z (mm): {:.4} / {:.4} / {:.4}",
        s.rms_mm[0], s.rms_mm[1], s.rms_mm[2]
    );
    let _ = writeln!(
        out,
        "  3D error (mm): mean {:.4}  std {:.4}  range [{:.4}, {:.4}]",
        s.mean_3d_mm, s.std_3d_mm, s.min_3d_mm, s.max_3d_mm
    );
    if let Some(sc) = &res.scores {
        let _ = writeln!(
            out,
            "  95 % interval coverage x / y / z: {}  NLPD {:.3}  flagged {:.1} % of rows, {}",
            super::coverage3(sc),
            sc.nlpd,
            100.0 * sc.flag_rate,
            match sc.flag_recall {
                Some(r) => format!("{:.0} % of the {} gross errors", 100.0 * r, sc.gross_rows),
                None => "no gross error".into(),
            }
        );
    }
    out
}

/// The header of the methods table of a `folds`-fold CV of `rows` rows
/// with the fold seed `seed` (seed 003 Table 2: range, mean, std of the 3D
/// error, plus per-axis RMSE and the time): what was done, then the
/// columns.
pub fn methods_header(folds: usize, rows: usize, seed: u64) -> String {
    format!(
        "{folds}-fold CV (refit: selection and hyperparameters inside every training fold) on {rows} rows, fold seed {seed}\n{:<11} {:>18} {:>9} {:>9} {:>26} {:>8}",
        "method", "range (mm)", "mean", "std", "RMSE x / y / z (mm)", "time"
    )
}

/// One method's row of the methods table.
pub fn methods_row(name: &str, res: &CvResult) -> String {
    let s = &res.summary;
    format!(
        "{:<11} [{:.4}, {:.4}] {:>9.4} {:>9.4}   {:.4} / {:.4} / {:.4} {:>7.1}s",
        name,
        s.min_3d_mm,
        s.max_3d_mm,
        s.mean_3d_mm,
        s.std_3d_mm,
        s.rms_mm[0],
        s.rms_mm[1],
        s.rms_mm[2],
        res.seconds
    )
}

/// The JSON of `cv --methods --json`: the data file, the folds and their
/// seed, and each method's CV figures.
pub fn methods_json(data: &Path, folds: usize, seed: u64, results: &[(Method, CvResult)]) -> Value {
    let rows: Vec<Value> = results
        .iter()
        .map(|(m, res)| {
            let s = &res.summary;
            json!({
                "name": m.name(), "cv_mode": res.mode, "cv_rmse_mm": s.rms_mm,
                "mean_3d_mm": s.mean_3d_mm, "max_3d_mm": s.max_3d_mm, "std_3d_mm": s.std_3d_mm,
                "min_3d_mm": s.min_3d_mm, "box_3d_mm": s.box_3d_mm, "seconds": res.seconds,
            })
        })
        .collect();
    json!({"data": data, "folds": folds, "seed": seed, "methods": rows})
}
