//! `cv`: a cross-validation's figures, and the table of methods compared.

use crate::cv::CvResult;
use std::fmt::Write as _;

/// What `cv` prints for one model choice: `how` it was cross-validated
/// (e.g. "10-fold CV"), of which file (`data`) of how many `rows`, with
/// which settings (`settings`, a line), then the per-axis RMSE, the 3D
/// error and the predictive scores.
pub fn summary(res: &CvResult, how: &str, (data, rows): (&str, usize), settings: &str) -> String {
    let s = &res.summary;
    let mut out = format!(
        "{how} ({}) of {data} on {rows} rows ({settings}), {:.1} s\n",
        res.mode, res.seconds
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

/// The header of the methods table (seed 003 Table 2: range, mean, std of
/// the 3D error, plus per-axis RMSE and the time).
pub fn methods_header() -> String {
    format!(
        "{:<11} {:>18} {:>9} {:>9} {:>26} {:>8}",
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
