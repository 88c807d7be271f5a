//! `robokrige holdout`: train on the first rows of a campaign, score on the
//! next ones (or cross-validate) — nominal, D-H calibration, the calibrated
//! model, universal Kriging with the kinematic trend, in JS and EJS.

use super::fit::KrigingArgs;
use super::progress::{steps, steps_of, with_bar};
use super::read_data;
use clap::Args;
use robokrige::Result;
use robokrige::calibration::CalibrationOptions;
use robokrige::cv::Folds;
use robokrige::dataset::Dataset;
use robokrige::holdout::{HyperRows, SplitExtras, holdout_cv_folds, holdout_split, split_rows};
use robokrige::kinematics::Robot;
use robokrige::methods::{Overrides, params_with};
use robokrige::params::ErrorModelParams;
use robokrige::report::holdout as report;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Rows 1..TRAIN train every model; rows TRAIN+1..TRAIN+TEST are predicted.
Models: nominal (no correction); D-H calibration (Levenberg–Marquardt on the
5n + 9 MD-H, tool and base errors, on the directions the campaign sees);
the calibrated model (that calibration, then Kriging JS or EJS on its
residual: what `fit --robot` makes); universal Kriging with
the kinematic trend (constant + identification-Jacobian rows; the GLS does the
calibration), JS and EJS. Kriging hyperparameters by --optimizer (BFGS by
default). With --cv, each model also reports the held-out rows it flags as
outside its coverage.

Example (the public UR10 data, series C):
  robokrige holdout ../shared/data/ipa-ur10/series_c_random_poses.csv \\
      --robot ur10 --tool=-0.14,0.30,92.82 --train 600 --test 300")]
pub struct HoldoutArgs {
    /// Measurement CSV with ex,ey,ez.
    data: PathBuf,
    /// Robot (preset name or robot file): the nominal kinematics of the D-H calibration and of the
    /// kinematic trend.
    #[arg(long)]
    robot: String,
    /// TCP offset in the flange frame, mm ("x,y,z"), if the errors were
    /// computed with one.
    #[arg(long)]
    tool: Option<String>,
    /// Training rows (the first ones) [default: 600]; with --cv or
    /// --groups, the first rows the Kriging hyperparameters are chosen on,
    /// once, held-out rows included [default with --cv: all rows: on UR10
    /// series C that lowers every Kriging row's CV error by 0.01–0.04 mm
    /// against 600, at about 3× the time; with --groups: each fold's
    /// training rows].
    #[arg(long)]
    train: Option<usize>,
    /// With --cv or --groups: choose the Kriging hyperparameters on each
    /// fold's training rows (one search per fold), so that no held-out row
    /// is seen [default with --groups].
    #[arg(long, conflicts_with = "train")]
    each_fold: bool,
    /// The calibrated models' calibration also identifies each joint's
    /// backlash (as `fit --backlash`); the D-H calibration row stays
    /// geometric.
    #[arg(long)]
    backlash: bool,
    /// Held-out rows after the training ones (without --cv) [default: 300].
    #[arg(long)]
    test: Option<usize>,
    /// Seed of the hyperparameter starts and, with --cv, of the fold partition.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    #[command(flatten)]
    kriging: KrigingArgs,
    /// Joints entered as (sin θ, cos θ): "auto" (range > 180° in the training
    /// rows), "none", or a list like "1,4,6".
    #[arg(long, default_value = "auto")]
    periodic: String,
    /// Also: EJS with the trend chosen by the GA (seed 004) among the
    /// quadratic and the kinematic candidates.
    #[arg(long)]
    ga: bool,
    /// Also: EJS with the PCC + PCA fusion (seed 003) of the quadratic and
    /// the kinematic candidates.
    #[arg(long)]
    pca: bool,
    /// Instead: K-fold CV on all rows (D-H calibration refitted per fold;
    /// Kriging at the ξ chosen on all rows, the first --train rows, or with
    /// --each-fold each fold's training rows, refitted per fold).
    /// Not with --test, --ga or --pca.
    #[arg(long, conflicts_with_all = ["test", "ga", "pca"])]
    cv: Option<usize>,
    /// Leave-one-group-out instead of random folds: one fold per value of
    /// this column (a cube, a cell, a day), as scikit-learn's
    /// LeaveOneGroupOut. The Kriging hyperparameters are chosen on each
    /// fold's training rows unless --train N says once on the first N.
    #[arg(long, value_name = "COLUMN", conflicts_with_all = ["cv", "test", "ga", "pca"])]
    groups: Option<String>,
    /// Write the table (and with --cv the per-fold figures) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// The base parameters of the Kriging fits of `a` on `rows` (options, and
/// the periodic joints those rows give), their fit's memory checked
/// (`option` takes fewer rows, if given).
fn base_params(a: &HoldoutArgs, rows: &Dataset, option: Option<&str>) -> Result<ErrorModelParams> {
    let o = Overrides::new().seed(a.seed).periodic(a.periodic.as_str());
    let base = params_with(None, &a.kriging.apply(o), rows)?;
    super::print_plan("holdout", base.check_fit_rows(rows.len(), option)?);
    // the calibrated models' calibration (the default one unless asked)
    Ok(if a.backlash {
        base.calibrate(Some(CalibrationOptions::default().with_backlash(true)))
    } else {
        base
    })
}

/// Where `a` asks the CV to choose the hyperparameters (`None`: the
/// default for its folds, [`HyperRows::default_for`]).
fn hyper_rows(a: &HoldoutArgs) -> Option<HyperRows> {
    if a.each_fold {
        Some(HyperRows::EachFold)
    } else {
        a.train.map(HyperRows::First)
    }
}

/// K-fold CV on all rows ([`robokrige::holdout::holdout_cv_folds`]).
fn run_cv(a: &HoldoutArgs, data: &Dataset, robot: &Robot, folds: &Folds) -> Result<()> {
    let base = base_params(a, data, None)?;
    let cv = with_bar(0, "cv", |pb| {
        holdout_cv_folds(data, robot, &base, folds, hyper_rows(a), &steps_of(pb))
    })?;
    say_part!("{}", report::cv(&a.data, (folds, data.len()), &base, &cv));
    super::json_to(a.json.as_deref(), &cv, "cv table")?;
    Ok(())
}

pub fn run(a: HoldoutArgs) -> Result<()> {
    super::check_files(&[Some(a.data.as_path())], &[a.json.as_deref()])?;
    let data = read_data(&a.data)?;
    let robot = robokrige::kinematics::load_robot_with_tool(&a.robot, a.tool.as_deref())?;
    robot.check_dataset(&data)?;
    super::warn(robot.limit_warnings(&data));
    if a.each_fold && a.cv.is_none() && a.groups.is_none() {
        return Err(robokrige::Error::InvalidParameter(
            "--each-fold chooses the hyperparameters per fold: it needs --cv K or --groups COLUMN"
                .into(),
        ));
    }
    if a.cv.is_some() || a.groups.is_some() {
        // --groups and --cv exclude each other (clap)
        let folds = Folds::new(a.groups.as_deref(), a.cv.unwrap_or_default(), a.seed);
        return run_cv(&a, &data, &robot, &folds);
    }
    let (train, test) = split_rows(&data, a.train, a.test)?;
    let base = base_params(&a, &train, Some("--train"))?;
    let extras = SplitExtras {
        pca: a.pca,
        ga: a.ga,
    };
    let split = with_bar(extras.models() as u64, "holdout", |pb| {
        holdout_split(&train, &test, &robot, &base, extras, &steps(pb))
    })?;
    let sizes = (train.len(), test.len());
    say_part!("{}", report::split(&a.data, sizes, &base, &split));
    super::json_to(a.json.as_deref(), &split.rows, "hold-out table")?;
    Ok(())
}
