//! Kriging beside the D-H calibration on held-out rows of a measured
//! campaign.
//!
//! Five models are scored on rows they were not trained on: the D-H
//! calibration ([`crate::calibration`]: Levenberg–Marquardt on the MD-H,
//! tool and base directions the campaign sees), the calibrated model (that
//! calibration, then Kriging JS or EJS on its residual, one model file) and
//! universal Kriging with the kinematic trend (the GLS does the
//! calibration), JS and EJS. [`holdout_cv`] is the K-fold (or grouped)
//! version on all rows; the CLI's `holdout` prints its table.
//!
//! Every Kriging fit starts from the caller's [`ErrorModelParams`] (Kriging
//! options and periodic joints); each model then sets its own space, trend
//! and calibration.

use crate::calibration::{Calibration, CalibrationOptions, calibrate, calibrate_both};
use crate::cv::Folds;
use crate::dataset::Dataset;
use crate::kinematics::Robot;
use crate::model::{ErrorModel, GROSS_FACTOR};
use crate::params::{ErrorModelParams, TrendSpec};
use crate::space::Space;
use crate::stats::{PredictiveScores, predictive_scores, spread};
use crate::vec3::{Vec3, norms, residuals};
use crate::{Error, Result};
use serde::Serialize;
use std::time::Instant;

/// One model's held-out errors.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HoldoutRow {
    /// The model's name, e.g. one of [`CV_MODELS`] or "nominal".
    pub model: String,
    /// Mean of the 3D error |e − ê| over the held-out rows, mm.
    pub mean_mm: f64,
    /// Largest 3D error |e − ê| over the held-out rows, mm.
    pub max_mm: f64,
    /// RMS of e − ê per axis (x, y, z), mm.
    pub rms_xyz_mm: [f64; 3],
    /// Wall time of the model's fits (all folds), s.
    pub seconds: f64,
}

/// Scores `pred` against the measured `truth`.
pub fn score(name: &str, truth: &[[f64; 3]], pred: &[[f64; 3]], seconds: f64) -> HoldoutRow {
    let r = residuals(truth, pred);
    let d = norms(&r);
    let s = spread(&d);
    let rms = |a: usize| (r.iter().map(|e| e[a] * e[a]).sum::<f64>() / r.len() as f64).sqrt();
    HoldoutRow {
        model: name.into(),
        mean_mm: s.mean,
        max_mm: s.max,
        rms_xyz_mm: [rms(0), rms(1), rms(2)],
        seconds,
    }
}

/// The models of [`holdout_cv`], in the order of its rows (after "nominal").
pub const CV_MODELS: [&str; 5] = [
    "D-H calibration (LM, refit per fold)",
    "calibrated model: D-H calibration + Kriging JS",
    "calibrated model: D-H calibration + Kriging EJS",
    "universal Kriging JS, kinematic trend",
    "universal Kriging EJS, kinematic trend",
];

/// The result of [`holdout_cv`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HoldoutCv {
    /// "nominal" (no correction), then the [`CV_MODELS`].
    pub rows: Vec<HoldoutRow>,
    /// Per model of [`CV_MODELS`]: interval coverage, NLPD, flag rate and
    /// recall on the held-out rows. The D-H calibration's interval is
    /// `±1.96 √(s² + Var δ̂_cal)` with `s` its residual noise per coordinate
    /// ([`Calibration::predict_variance`]); it flags none.
    pub scores: Vec<PredictiveScores>,
    /// Max 3D error of each of the [`CV_MODELS`] in each fold, mm.
    pub fold_max_mm: Vec<[f64; 5]>,
    /// The same over the held-out rows the model does not flag as outside
    /// its coverage ([`ErrorModel::coverage`]; the D-H calibration flags
    /// none), mm.
    pub fold_max_covered_mm: Vec<[f64; 5]>,
    /// Rows each of the [`CV_MODELS`] flagged when they were held out.
    pub flagged: Vec<Vec<usize>>,
    /// Rows where each of the [`CV_MODELS`] made a gross error held out
    /// (3D error over [`GROSS_FACTOR`] × its held-out 3D RMS,
    /// [`crate::stats::gross_rows`]).
    pub gross: Vec<Vec<usize>>,
    /// Folds (random or one per group).
    pub folds: usize,
    /// Where the Kriging hyperparameters were chosen: the first rows (how
    /// many), or each fold's training rows.
    pub hyper: HyperRows,
    /// Wall time of choosing the hyperparameters, s (with
    /// [`HyperRows::EachFold`], the folds' searches added up).
    pub hyper_seconds: f64,
}

impl HoldoutCv {
    /// Max 3D error of each of the [`CV_MODELS`] over all folds, on the
    /// held-out rows it does not flag ([`fold_max_covered_mm`](Self::fold_max_covered_mm)), mm.
    pub fn max_covered_mm(&self) -> [f64; 5] {
        self.fold_max_covered_mm
            .iter()
            .fold([0.0f64; 5], |a, b| std::array::from_fn(|i| a[i].max(b[i])))
    }
}

/// Where a hold-out CV chooses the Kriging hyperparameters (ξ, the nugget
/// and the family) of the models it refits per fold.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum HyperRows {
    /// Once, on the campaign's first `n` rows (at least 10), every fold
    /// refitted at them: one search in all. With random folds the held-out
    /// rows are interleaved with the training ones, and the search having
    /// seen them changes little (on UR10 series C, all rows lower every
    /// Kriging row's CV error by 0.01–0.04 mm against the first 600).
    First(usize),
    /// On each fold's training rows: no held-out row is seen, at one
    /// search per fold. What a grouped CV asks ("does the model carry over
    /// to a cube, a cell, a day it has not seen?") needs it: a search that
    /// has seen the held-out group may pick length scales that only its
    /// rows justify (on a simulated ABB campaign of four cubes, one cube
    /// held out, the universal-Kriging JS model's max error went from
    /// 1.84× the D-H calibration's to 1.03×).
    EachFold,
}

impl HyperRows {
    /// The default for `folds` on a campaign of `rows` rows: each fold's
    /// training rows for a grouped CV, all rows once for random folds.
    pub fn default_for(folds: &Folds, rows: usize) -> HyperRows {
        match folds {
            Folds::Groups(_) => HyperRows::EachFold,
            Folds::Random { .. } => HyperRows::First(rows),
        }
    }
}

/// [`holdout_cv`] over the partition `folds` of `data` ([`Folds::partition`]),
/// the hyperparameters chosen as `hyper` says ([`HyperRows::default_for`]
/// when `None`); `progress(done, steps, message)` is called before each of
/// the `steps` = k + 1 steps.
pub fn holdout_cv_folds(
    data: &Dataset,
    robot: &Robot,
    base: &ErrorModelParams,
    folds: &Folds,
    hyper: Option<HyperRows>,
    progress: &dyn Fn(usize, usize, &str),
) -> Result<HoldoutCv> {
    let fold = folds.partition(data)?;
    let steps = fold.iter().max().map_or(0, |x| x + 1) + 1;
    let hyper = hyper.unwrap_or_else(|| HyperRows::default_for(folds, data.len()));
    let progress = |done: usize, what: &str| progress(done, steps, what);
    holdout_cv(data, robot, base, &fold, hyper, &progress)
}

/// Predictions of one model on the held-out rows, gathered over the folds.
struct Gathered {
    mean: Vec<[f64; 3]>,
    std: Vec<[f64; 3]>,
    flagged: Vec<bool>,
}

/// Campaigns up to this many rows cross-validate their folds at once: a
/// fold's D-H calibration and refits leave a core idle part of the time,
/// and two folds' models (m × m factors per output) stay small. Larger
/// campaigns run one fold at a time, which also keeps their peak memory.
pub const PARALLEL_FOLD_ROWS: usize = 1000;

/// Cross-validation of the five models on all rows, `fold[i]` being the
/// fold of row `i` (0..k: a seeded random partition,
/// [`crate::stats::kfold_partition`], or one fold per group,
/// [`crate::stats::group_partition`]). The D-H calibration is identified
/// on every training fold. The Kriging models choose their hyperparameters
/// (ξ, nugget, family) with `base` (Kriging options and periodic joints;
/// space, trend and calibration set per model) where `hyper` says, and are
/// refitted on every training fold at those values: the calibrated model on
/// top of the fold's own calibration, the kinematic-trend model on the
/// fold. `progress(done, message)` is called before each of the `k + 1`
/// steps.
pub fn holdout_cv(
    data: &Dataset,
    robot: &Robot,
    base: &ErrorModelParams,
    fold: &[usize],
    hyper: HyperRows,
    progress: &dyn Fn(usize, &str),
) -> Result<HoldoutCv> {
    let errors = data.errors_or_err()?;
    let m = data.len();
    let k = crate::stats::fold_count(fold, m)?;
    let t_hyper = Instant::now();
    // the hyperparameters chosen once (the models whose ξ the folds keep)
    let (once, hyper) = match hyper {
        HyperRows::First(n) => {
            if n < 10 {
                return Err(Error::InvalidParameter(format!(
                    "the hyperparameters need at least 10 rows, not {n}"
                )));
            }
            let first = data.select(&(0..n.min(m)).collect::<Vec<_>>());
            progress(
                0,
                &format!("hyperparameters on the first {} rows", first.len()),
            );
            let models = hyperparameter_models(&first, robot, base)?;
            (Some(models), HyperRows::First(first.len()))
        }
        HyperRows::EachFold => {
            for f in 0..k {
                let n = fold.iter().filter(|&&g| g != f).count();
                if n < 10 {
                    return Err(Error::InvalidParameter(format!(
                        "fold {} of {k} (numbered by first appearance) holds out {} of the {m} rows and leaves {n} to train on: choosing the hyperparameters on each fold's training rows needs at least 10, and a fold that small cannot be fitted at all: split that group into smaller ones, or use random folds (--cv K)",
                        f + 1,
                        m - n
                    )));
                }
            }
            progress(0, "hyperparameters on each fold's training rows");
            (None, HyperRows::EachFold)
        }
    };
    let mut hyper_seconds = t_hyper.elapsed().as_secs_f64();
    let mut got: Vec<Gathered> = (0..5)
        .map(|_| Gathered {
            mean: vec![[0.0; 3]; m],
            std: vec![[0.0; 3]; m],
            flagged: vec![false; m],
        })
        .collect();
    let mut secs = [0.0; 5];
    let mut fold_max_mm = Vec::with_capacity(k);
    let mut fold_max_covered_mm = Vec::with_capacity(k);
    // a fold's predictions into the gathered ones, and its worst errors
    let mut merge = |out: FoldOut| {
        let mut worst = [0.0f64; 5];
        let mut worst_covered = [0.0f64; 5];
        for (slot, p) in out.held.iter().enumerate() {
            for (j, &i) in out.test.iter().enumerate() {
                let err = errors[i].minus(&p.mean[j]).norm();
                let flagged = p.flags.contains(&j);
                worst[slot] = worst[slot].max(err);
                if !flagged {
                    worst_covered[slot] = worst_covered[slot].max(err);
                }
                let g = &mut got[slot];
                g.mean[i] = p.mean[j];
                g.std[i] = p.std[j];
                g.flagged[i] = flagged;
            }
            secs[slot] += out.secs[slot];
        }
        hyper_seconds += out.hyper_secs;
        fold_max_mm.push(worst);
        fold_max_covered_mm.push(worst_covered);
    };
    let run_fold = |f: usize| -> Result<FoldOut> {
        match &once {
            Some((calibrated, kinematic)) => fold_out(data, fold, f, robot, calibrated, kinematic),
            None => {
                let t = Instant::now();
                let train: Vec<usize> = (0..m).filter(|&i| fold[i] != f).collect();
                let (calibrated, kinematic) =
                    hyperparameter_models(&data.select(&train), robot, base)?;
                let hyper_secs = t.elapsed().as_secs_f64();
                let mut out = fold_out(data, fold, f, robot, &calibrated, &kinematic)?;
                out.hyper_secs = hyper_secs;
                Ok(out)
            }
        }
    };
    // a fold that fails names itself and its sizes (a group too large
    // leaves too few rows to train on)
    let in_fold = |f: usize| -> Result<FoldOut> {
        run_fold(f).map_err(|e| {
            if e.is_interrupted() {
                return e;
            }
            let held = fold.iter().filter(|&&g| g == f).count();
            crate::Error::InvalidParameter(format!(
                "fold {} of {k} ({held} rows held out, {} to train on): {e}",
                f + 1,
                m - held
            ))
        })
    };
    if m <= PARALLEL_FOLD_ROWS {
        // small folds at once: each fold's calibration and refits leave a
        // core idle part of the time, and their memory is small
        use rayon::prelude::*;
        progress(1, &format!("{k} folds"));
        let outs: Vec<Result<FoldOut>> = (0..k).into_par_iter().map(in_fold).collect();
        for out in outs {
            merge(out?);
        }
    } else {
        for f in 0..k {
            progress(f + 1, &format!("fold {}", f + 1));
            merge(in_fold(f)?);
        }
    }
    let mut rows = vec![score("nominal", errors, &vec![[0.0; 3]; m], 0.0)];
    for (i, n) in CV_MODELS.iter().enumerate() {
        rows.push(score(n, errors, &got[i].mean, secs[i]));
    }
    let scores = got
        .iter()
        .map(|g| predictive_scores(errors, &g.mean, &g.std, &g.flagged, GROSS_FACTOR))
        .collect();
    Ok(HoldoutCv {
        rows,
        scores,
        fold_max_mm,
        fold_max_covered_mm,
        flagged: got
            .iter()
            .map(|g| (0..m).filter(|&i| g.flagged[i]).collect())
            .collect(),
        gross: got
            .iter()
            .map(|g| crate::stats::gross_rows(errors, &g.mean, GROSS_FACTOR))
            .collect(),
        folds: k,
        hyper,
        hyper_seconds,
    })
}

/// One fold's held-out rows and, per model (the D-H calibration, then
/// [`CV_MODELS`]), its predictions there and its wall time; and the time
/// of choosing its own hyperparameters ([`HyperRows::EachFold`]).
struct FoldOut {
    test: Vec<usize>,
    held: [Held; 5],
    secs: [f64; 5],
    hyper_secs: f64,
}

/// Fold `f`: the D-H calibration identified on its training rows, the
/// calibrated models refitted on that calibration and the kinematic-trend
/// models refitted, each at the hyperparameters of `calibrated` / `kinematic`
/// (JS, EJS), and their predictions on the held-out rows.
fn fold_out(
    data: &Dataset,
    fold: &[usize],
    f: usize,
    robot: &Robot,
    calibrated: &[ErrorModel],
    kinematic: &[ErrorModel],
) -> Result<FoldOut> {
    let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| fold[i] == f);
    let (tr, held) = (data.select(&train), data.select(&test));
    let t = Instant::now();
    // the D-H row's geometric calibration and, from the same geometric
    // fit, the calibrated models' own (the joint harmonics, and the
    // backlash when asked, besides)
    // (one fit serves both: each row is charged its time)
    let (dh, cal) = calibrate_both(&tr, robot, &calibrated[0].calibration_options())?;
    let dh_secs = t.elapsed().as_secs_f64();
    let s = dh.identifiability().noise_mm;
    let dh_held = Held {
        mean: dh.predict(&held.q, &held.dir)?,
        std: dh
            .predict_variance(&held.q, &held.dir)?
            .iter()
            .map(|v| v.map(|x| (x + s * s).sqrt()))
            .collect(),
        flags: Vec::new(),
    };
    // space `sp` (JS, EJS): the calibrated and the kinematic-trend model's
    // predictions and times
    let pair = |sp: usize| -> Result<(Held, Held, f64, f64)> {
        let t = Instant::now();
        let c = calibrated[sp].refit_with_calibration(&tr, cal.clone())?;
        let c_secs = dh_secs + t.elapsed().as_secs_f64();
        let c_held = predicted(&c, &held)?;
        let t = Instant::now();
        let uk = kinematic[sp].refit(&tr)?;
        let k_secs = t.elapsed().as_secs_f64();
        Ok((c_held, predicted(&uk, &held)?, c_secs, k_secs))
    };
    let (c_js, k_js, cs_js, ks_js) = pair(0)?;
    let (c_ejs, k_ejs, cs_ejs, ks_ejs) = pair(1)?;
    let secs = [dh_secs, cs_js, cs_ejs, ks_js, ks_ejs];
    Ok(FoldOut {
        test,
        held: [dh_held, c_js, c_ejs, k_js, k_ejs],
        secs,
        hyper_secs: 0.0,
    })
}

/// A model's predictions on held-out rows.
struct Held {
    /// Predicted errors, mm.
    mean: Vec<[f64; 3]>,
    /// Standard deviation of a new measurement per axis, mm.
    std: Vec<[f64; 3]>,
    /// Held-out rows (0-based among them) flagged as outside its coverage.
    flags: Vec<usize>,
}

/// `model`'s predicted mean on `held`, the standard deviation of a new
/// measurement and the rows it flags ([`ErrorModel::predict_checked`]).
fn predicted(model: &ErrorModel, held: &Dataset) -> Result<Held> {
    let c = model.predict_checked(held)?;
    Ok(Held {
        mean: c.prediction.mean,
        std: c.std_new,
        flags: c.flagged.unwrap_or_default(),
    })
}

/// Training rows of a hold-out split when none are given.
pub const DEFAULT_TRAIN: usize = 600;
/// Held-out rows after the training ones when none are given.
pub const DEFAULT_TEST: usize = 300;

/// The first `train` rows of `data` ([`DEFAULT_TRAIN`] if not given) and
/// the `test` rows after them ([`DEFAULT_TEST`]): at least 10 and 1 rows,
/// within the campaign.
pub fn split_rows(
    data: &Dataset,
    train: Option<usize>,
    test: Option<usize>,
) -> Result<(Dataset, Dataset)> {
    let (n_train, n_test) = (train.unwrap_or(DEFAULT_TRAIN), test.unwrap_or(DEFAULT_TEST));
    if n_train < 10 || n_test < 1 || n_train + n_test > data.len() {
        return Err(Error::InvalidParameter(format!(
            "--train {n_train} --test {n_test} need at least 10 + 1 and at most {} rows",
            data.len()
        )));
    }
    let rows = |r: std::ops::Range<usize>| data.select(&r.collect::<Vec<_>>());
    Ok((rows(0..n_train), rows(n_train..n_train + n_test)))
}

/// What [`holdout_split`] scores beyond the five models.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub struct SplitExtras {
    /// Also EJS with the PCC + PCA fusion (seed 003) of the quadratic and
    /// the kinematic candidates.
    pub pca: bool,
    /// Also EJS with the trend chosen by the GA (seed 004) among the same.
    pub ga: bool,
}

impl SplitExtras {
    /// The models [`holdout_split`] trains (one `progress` call each):
    /// the D-H calibration, the calibrated and kinematic-trend models in JS
    /// and EJS, and these extras.
    pub fn models(self) -> usize {
        5 + usize::from(self.pca) + usize::from(self.ga)
    }
}

/// The result of [`holdout_split`].
#[derive(Debug, Clone, PartialEq)]
pub struct HoldoutSplit {
    /// "nominal", then the five models, then the extras asked for.
    pub rows: Vec<HoldoutRow>,
    /// The calibrated models' calibration on the training rows.
    pub calibration: Calibration,
}

/// Train every model on `train`, score it on `test` (rows it never saw):
/// nominal, the D-H calibration, the hybrid and the kinematic-trend Kriging
/// in JS and EJS, and the `extras`. The Kriging fits start from `base`
/// (Kriging options and periodic joints; space and trend set per model).
/// `progress(done, message)` is called before each model, `done` counting
/// it (1 to [`SplitExtras::models`]).
pub fn holdout_split(
    train: &Dataset,
    test: &Dataset,
    robot: &Robot,
    base: &ErrorModelParams,
    extras: SplitExtras,
    progress: &dyn Fn(usize, &str),
) -> Result<HoldoutSplit> {
    use crate::methods::{PAPER_GA_FOLDS, PAPER_PCC_THRESHOLD, PAPER_VARIANCE_SHARE};
    let started = std::cell::Cell::new(0);
    let progress = |what: &str| {
        started.set(started.get() + 1);
        progress(started.get(), what);
    };
    let truth = test.errors_or_err()?.to_vec();
    let mut rows = vec![score("nominal", &truth, &vec![[0.0; 3]; truth.len()], 0.0)];
    progress("D-H calibration");
    let t0 = Instant::now();
    // (one fit serves both: each row is charged its time)
    let (dh, calibration) = calibrate_both(train, robot, &calibration_options(base))?;
    let dh_secs = t0.elapsed().as_secs_f64();
    rows.push(score(
        "D-H calibration (LM)",
        &truth,
        &dh.predict(&test.q, &test.dir)?,
        dh_secs,
    ));
    for space in [Space::Js, Space::Ejs] {
        let label = format!("{space:?}").to_uppercase();
        progress(&format!("calibrated model {label}"));
        let t0 = Instant::now();
        let c = fit_calibrated(train, space, base, &calibration)?;
        rows.push(score(
            &format!("calibrated model: D-H calibration + Kriging {label}"),
            &truth,
            &c.predict_mean(&test.q, &test.dir)?,
            dh_secs + t0.elapsed().as_secs_f64(),
        ));
        progress(&format!("UK kinematic trend {label}"));
        let t0 = Instant::now();
        let m = fit_kinematic(train, space, base, robot)?;
        rows.push(score(
            &format!("universal Kriging {label}, kinematic trend"),
            &truth,
            &m.predict_mean(&test.q, &test.dir)?,
            t0.elapsed().as_secs_f64(),
        ));
    }
    let kinematic = Some(Box::new(robot.clone()));
    let mut selected = Vec::new();
    if extras.pca {
        let trend = TrendSpec::PccPca {
            threshold: PAPER_PCC_THRESHOLD,
            variance_share: PAPER_VARIANCE_SHARE,
            kinematic: kinematic.clone(),
        };
        let name = "universal Kriging EJS, PCC + PCA fusion of quadratic + kinematic candidates";
        selected.push(("PCC + PCA", name, trend));
    }
    if extras.ga {
        let trend = TrendSpec::Ga {
            folds: PAPER_GA_FOLDS,
            kinematic,
        };
        let name = "universal Kriging EJS, GA-selected quadratic + kinematic trend";
        selected.push(("GA selection", name, trend));
    }
    for (what, name, trend) in selected {
        progress(what);
        let t0 = Instant::now();
        let m = base
            .clone()
            .space(Space::Ejs)
            .trend(trend)
            .check()?
            .fit(train)?;
        let pred = m.predict_mean(&test.q, &test.dir)?;
        rows.push(score(name, &truth, &pred, t0.elapsed().as_secs_f64()));
    }
    Ok(HoldoutSplit { rows, calibration })
}

/// The calibrated model in `space`: the calibration `cal` (identified on
/// `data`, shared by the models of one training set), then Kriging with the
/// options' trend on its residual, from `base` — what
/// `ErrorModelParams::calibrate` fits, without identifying `cal` again.
fn fit_calibrated(
    data: &Dataset,
    space: Space,
    base: &ErrorModelParams,
    cal: &Calibration,
) -> Result<ErrorModel> {
    let model = base
        .clone()
        .space(space)
        .trend(TrendSpec::Options)
        .robot(cal.nominal().clone())
        .calibrate(None)
        .check()?
        .fit(&cal.residual(data)?)?;
    Ok(model.with_calibration(cal.clone()))
}

/// The Kriging models whose hyperparameters the folds keep, fitted on
/// `first`: the calibrated models (JS, EJS) on one D-H calibration, and the
/// kinematic-trend models (JS, EJS). The four searches run at once: each
/// output's search ends on one core while the others' go on.
fn hyperparameter_models(
    first: &Dataset,
    robot: &Robot,
    base: &ErrorModelParams,
) -> Result<(Vec<ErrorModel>, Vec<ErrorModel>)> {
    use rayon::prelude::*;
    let first_cal = calibrate(first, robot, &calibration_options(base))?;
    let mut fits: Vec<ErrorModel> = [
        (Space::Js, false),
        (Space::Ejs, false),
        (Space::Js, true),
        (Space::Ejs, true),
    ]
    .into_par_iter()
    .map(|(space, kinematic)| {
        if kinematic {
            fit_kinematic(first, space, base, robot)
        } else {
            fit_calibrated(first, space, base, &first_cal)
        }
    })
    .collect::<Result<_>>()?;
    let kinematic = fits.split_off(2);
    Ok((fits, kinematic))
}

/// The calibration of the calibrated models: `base`'s
/// ([`ErrorModelParams::calibrate`], e.g. with the backlash), else the
/// default one.
fn calibration_options(base: &ErrorModelParams) -> CalibrationOptions {
    base.get_calibration().cloned().unwrap_or_default()
}

/// Universal Kriging with the kinematic trend of `robot`, from `base`, on `data`.
fn fit_kinematic(
    data: &Dataset,
    space: Space,
    base: &ErrorModelParams,
    robot: &Robot,
) -> Result<ErrorModel> {
    base.clone()
        .space(space)
        .trend(TrendSpec::Kinematic(Box::new(robot.clone())))
        .calibrate(None)
        .check()?
        .fit(data)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn max_covered_is_the_worst_fold_per_model() {
        let cv = HoldoutCv {
            rows: Vec::new(),
            scores: Vec::new(),
            folds: 2,
            fold_max_mm: Vec::new(),
            fold_max_covered_mm: vec![[1.0, 0.5, 0.0, 2.0, 0.1], [0.5, 0.7, 0.0, 1.0, 0.3]],
            flagged: vec![Vec::new(); 5],
            gross: vec![Vec::new(); 5],
            hyper: HyperRows::First(10),
            hyper_seconds: 0.0,
        };
        assert_eq!(cv.max_covered_mm(), [1.0, 0.7, 0.0, 2.0, 0.3]);
    }
}
