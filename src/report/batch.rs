//! `batch`: the fleet's table, one line per campaign.

use crate::Result;
use crate::batch::{CampaignReport, campaign_name};
use std::path::PathBuf;

/// The JSON of `batch --json`: each campaign of `files` with its report
/// or its error (`results`, the same order).
pub fn json(files: &[PathBuf], results: &[Result<CampaignReport>]) -> serde_json::Value {
    let reports: Vec<serde_json::Value> = files
        .iter()
        .zip(results)
        .map(|(file, r)| match r {
            Ok(rep) => serde_json::json!({"campaign": campaign_name(file), "report": rep}),
            Err(e) => serde_json::json!({"campaign": campaign_name(file), "error": e.to_string()}),
        })
        .collect();
    serde_json::Value::Array(reports)
}

/// The fleet table: a header, then one line per campaign of `files` with
/// its report or its error (`results`, the same order).
pub fn table(files: &[PathBuf], results: &[Result<CampaignReport>]) -> String {
    let mut s = header() + "\n";
    for (file, r) in files.iter().zip(results) {
        s += &(row(&campaign_name(file), r) + "\n");
    }
    s
}

/// The header of the fleet table.
fn header() -> String {
    format!(
        "{:<28} {:>6} {:<20} {:>10} {:>26} {:>9} {:>7}",
        "campaign", "rows", "robot", "measured", "CV RMSE x / y / z (mm)", "CV mean", "s"
    )
}

/// Campaign `name`'s line: rows, robot, the measured mean 3D error, the CV
/// RMSE per axis and mean 3D error, the wall time; or its error.
fn row(name: &str, r: &Result<CampaignReport>) -> String {
    match r {
        Ok(rep) => {
            let cv = rep.cv.rms_mm;
            format!(
                "{:<28} {:>6} {:<20} {:>10.4} {:>8.4} / {:.4} / {:.4} {:>9.4} {:>7.1}",
                name,
                rep.rows,
                rep.robot.as_deref().unwrap_or("-"),
                rep.measured.mean_3d_mm,
                cv[0],
                cv[1],
                cv[2],
                rep.cv.mean_3d_mm,
                rep.seconds
            )
        }
        Err(e) => format!("{name:<28} failed: {e}"),
    }
}
