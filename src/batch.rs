//! A fleet: one campaign per robot, each fitted and cross-validated the same
//! way, in parallel, with one report per campaign and a summary table.
//!
//! Every campaign `NAME.csv` of a folder is fitted with the recommended
//! settings ([`KrigingOptions::recommended`]: nugget, correlation family by
//! CV, periodic joints where the data spans more than 180°) and scored by
//! K-fold CV at the fitted hyperparameters (closed form, eq 21 of seed 003
//! without the refit). Its robot is `NAME.robot.toml` (or `.json`) beside it
//! when that exists, else the batch's robot, else none; a given robot is
//! calibrated first (the calibrated model, as
//! [`BatchOptions::calibration`] says) and recorded in the model
//! ([`ErrorModel::record_robot`]). A campaign that
//! fails is reported with its error and does not stop the others.

use crate::calibration::CalibrationOptions;
use crate::cv::cross_validate_closed_form;
use crate::dataset::read_csv;
use crate::kinematics::{Robot, read_robot_file};
use crate::kriging::KrigingOptions;
use crate::model::ErrorModel;
use crate::params::ErrorModelParams;
use crate::space::{Space, periodic_joints};
use crate::stats::{ErrorSummary, summarize};
use crate::{Error, Result};
use rayon::prelude::*;
use serde::Serialize;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// What a batch does with each campaign.
#[derive(Debug, Clone, PartialEq)]
pub struct BatchOptions {
    /// CV folds.
    pub folds: usize,
    /// Seed of the folds and of the fit's starts.
    pub seed: u64,
    /// Robot of campaigns without their own robot file.
    pub robot: Option<Robot>,
    /// How a campaign's robot is calibrated first (the calibrated model
    /// of `fit --robot`); `None`: Kriging of the raw error. Without a
    /// robot there is nothing to calibrate.
    pub calibration: Option<CalibrationOptions>,
}

impl Default for BatchOptions {
    fn default() -> Self {
        BatchOptions {
            folds: 10,
            seed: 1,
            robot: None,
            calibration: Some(CalibrationOptions::default()),
        }
    }
}

/// The report of one campaign.
#[derive(Debug, Clone, Serialize)]
pub struct CampaignReport {
    /// The campaign file.
    pub campaign: PathBuf,
    /// Rows fitted.
    pub rows: usize,
    /// The robot's name and where it came from (`NAME.robot.toml` or the batch's).
    pub robot: Option<String>,
    /// The measured errors before any model (what a compensation starts from).
    pub measured: ErrorSummary,
    /// Out-of-fold residuals of the model.
    pub cv: ErrorSummary,
    /// The correlation family chosen per axis.
    pub correlation: Vec<String>,
    /// What the calibration identified
    /// ([`crate::calibration::Calibration::summary_line`]); `None` for
    /// Kriging of the raw error.
    pub calibration: Option<String>,
    /// Wall time of fit and CV, s.
    pub seconds: f64,
    /// The fitted model (saved by the caller).
    #[serde(skip)]
    pub model: ErrorModel,
}

/// The campaign files of `folder`: every `*.csv`, sorted by name.
pub fn campaigns(folder: &Path) -> Result<Vec<PathBuf>> {
    let entries = std::fs::read_dir(folder).map_err(|e| Error::io(folder, e))?;
    let mut out: Vec<PathBuf> = entries
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| p.is_file() && p.extension().is_some_and(|x| x.eq_ignore_ascii_case("csv")))
        .collect();
    out.sort();
    if out.is_empty() {
        return Err(Error::Input {
            source_name: folder.display().to_string(),
            message: "no campaign (*.csv) in this folder".into(),
        });
    }
    // `a.csv` and `a.CSV` would write one `a.model.json` (and on a
    // case-insensitive file system, so would `A.csv`)
    for (i, f) in out.iter().enumerate() {
        let name = campaign_name(f).to_lowercase();
        if let Some(g) = out[..i]
            .iter()
            .find(|g| campaign_name(g).to_lowercase() == name)
        {
            return Err(Error::Input {
                source_name: folder.display().to_string(),
                message: format!(
                    "{} and {} would write the same model and report files (NAME.model.json): rename one",
                    g.display(),
                    f.display()
                ),
            });
        }
    }
    Ok(out)
}

/// The robot file beside a campaign (`NAME.robot.toml` or `NAME.robot.json`).
pub fn robot_beside(campaign: &Path) -> Option<PathBuf> {
    let stem = campaign.file_stem()?.to_str()?;
    ["toml", "json"]
        .into_iter()
        .map(|ext| campaign.with_file_name(format!("{stem}.robot.{ext}")))
        .find(|p| p.is_file())
}

/// Fit and cross-validate one campaign (see the module docs).
pub fn run_campaign(campaign: &Path, opts: &BatchOptions) -> Result<CampaignReport> {
    let t0 = Instant::now();
    let data = read_csv(campaign)?;
    let errors = data.errors_or_err()?.to_vec();
    let robot = match robot_beside(campaign) {
        Some(p) => Some(read_robot_file(&p)?),
        None => opts.robot.clone(),
    };
    if let Some(r) = &robot {
        r.check_dataset(&data)?;
    }
    let kriging = KrigingOptions {
        seed: opts.seed,
        ..KrigingOptions::recommended()
    };
    let mut params = ErrorModelParams::new()
        .space(Space::Ejs)
        .periodic(periodic_joints(&data.q))
        .kriging(kriging);
    if let (Some(r), Some(c)) = (&robot, &opts.calibration) {
        params = params.robot(r.clone()).calibrate(Some(c.clone()));
    }
    let mut model = params.check()?.fit(&data)?;
    if let Some(r) = &robot {
        model.record_robot(r)?;
    }
    let cv = cross_validate_closed_form(&data, &model, opts.folds, opts.seed)?;
    Ok(CampaignReport {
        campaign: campaign.to_path_buf(),
        rows: data.len(),
        robot: robot.as_ref().map(|r| r.name.clone()),
        measured: summarize(&errors),
        cv: cv.summary,
        correlation: model.outputs.iter().map(|o| o.corr().to_string()).collect(),
        calibration: model.calibration().map(|c| c.summary_line()),
        seconds: t0.elapsed().as_secs_f64(),
        model,
    })
}

/// [`run_campaign`] on every campaign, in parallel; `done` is called as each
/// finishes (in any order). The results are in the order of `campaigns`.
pub fn run_batch(
    campaigns: &[PathBuf],
    opts: &BatchOptions,
    done: &(dyn Fn(&Path, &Result<CampaignReport>) + Sync),
) -> Vec<Result<CampaignReport>> {
    campaigns
        .par_iter()
        .map(|c| {
            let r = run_campaign(c, opts);
            done(c, &r);
            r
        })
        .collect()
}

/// Refuse an output folder that is the campaign folder `folder` (its files
/// would be read as campaigns next time), and create it.
pub fn prepare_output(folder: &Path, output: &Path) -> Result<()> {
    if let (Ok(x), Ok(y)) = (folder.canonicalize(), output.canonicalize())
        && x == y
    {
        return Err(Error::InvalidParameter(
            "the output folder is the campaign folder: its files would be read as campaigns next time; choose another".into(),
        ));
    }
    std::fs::create_dir_all(output).map_err(|e| Error::io(output, e))
}

/// Write every campaign of `files` that succeeded (`results`, the same
/// order) into the folder `out` ([`write_campaign`]).
///
/// A campaign whose files cannot be written becomes a failed one (its
/// result the write error), so that the others are still written and the
/// summary says which failed.
pub fn write_campaigns(out: &Path, files: &[PathBuf], results: &mut [Result<CampaignReport>]) {
    for (file, r) in files.iter().zip(results.iter_mut()) {
        if let Ok(rep) = r
            && let Err(e) = write_campaign(out, &campaign_name(file), rep)
        {
            *r = Err(e);
        }
    }
}

/// Write campaign `name`'s model and report into the folder `out`:
/// `NAME.model.json` and `NAME.report.json` (pretty JSON).
pub fn write_campaign(out: &Path, name: &str, rep: &CampaignReport) -> Result<()> {
    rep.model.save(&out.join(format!("{name}.model.json")))?;
    let text = crate::output::json_text(rep, "campaign report")?;
    crate::output::write_text(&out.join(format!("{name}.report.json")), &text)
}

/// An error that counts the failed campaigns of `results` (listed in the
/// summary CSV `summary`), if any failed.
pub fn check_failures(results: &[Result<CampaignReport>], summary: &Path) -> Result<()> {
    let failed = results.iter().filter(|r| r.is_err()).count();
    if failed == 0 {
        return Ok(());
    }
    Err(Error::InvalidParameter(format!(
        "{failed} of {} campaign(s) failed (listed above and in {})",
        results.len(),
        summary.display()
    )))
}

/// A campaign's name: its file stem (`campaign` when it has none).
pub fn campaign_name(file: &Path) -> String {
    file.file_stem()
        .and_then(|s| s.to_str())
        .unwrap_or("campaign")
        .to_string()
}

/// The columns of the fleet summary CSV ([`write_summary`]).
pub const SUMMARY_COLUMNS: [&str; 11] = [
    "campaign",
    "rows",
    "robot",
    "measured_mean_3d_mm",
    "cv_rmse_x_mm",
    "cv_rmse_y_mm",
    "cv_rmse_z_mm",
    "cv_mean_3d_mm",
    "correlation",
    "seconds",
    "status",
];

/// Write the fleet summary CSV to `path` (atomically): one row per
/// campaign of `campaigns` with its result of `results` (the same order):
/// the columns of [`SUMMARY_COLUMNS`], the correlation families joined by
/// `/`, status `ok`; a failed campaign has only its name and the status
/// `failed: <error>`.
pub fn write_summary(
    path: &Path,
    campaigns: &[PathBuf],
    results: &[Result<CampaignReport>],
) -> Result<()> {
    crate::output::write_atomic(path, |out| {
        let mut w = csv::Writer::from_writer(out);
        w.write_record(SUMMARY_COLUMNS)?;
        for (file, r) in campaigns.iter().zip(results) {
            w.write_record(summary_row(&campaign_name(file), r))?;
        }
        w.flush()
    })
}

/// One campaign's row of the summary CSV.
fn summary_row(name: &str, r: &Result<CampaignReport>) -> Vec<String> {
    match r {
        Ok(rep) => {
            let cv = rep.cv.rms_mm;
            vec![
                name.to_string(),
                rep.rows.to_string(),
                rep.robot.clone().unwrap_or_default(),
                rep.measured.mean_3d_mm.to_string(),
                cv[0].to_string(),
                cv[1].to_string(),
                cv[2].to_string(),
                rep.cv.mean_3d_mm.to_string(),
                rep.correlation.join("/"),
                rep.seconds.to_string(),
                "ok".into(),
            ]
        }
        Err(e) => {
            let mut row = vec![String::new(); SUMMARY_COLUMNS.len()];
            row[0] = name.to_string();
            row[10] = format!("failed: {e}");
            row
        }
    }
}
