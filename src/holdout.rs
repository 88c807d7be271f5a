//! Kriging beside the D-H calibration on held-out rows of a measured
//! campaign (issue 10's real-data table; issue 16's no-blow-up check).
//!
//! Five models are scored on rows they were not trained on: the D-H
//! calibration (Levenberg–Marquardt on the MD-H, tool and base errors), the
//! two-stage hybrid (D-H calibration, then Kriging JS or EJS on its residual)
//! and universal Kriging with the kinematic trend (the GLS does the
//! calibration), JS and EJS. [`holdout_cv`] is the K-fold version on all
//! rows; the CLI's `holdout` prints its table.
//!
//! Every Kriging fit starts from the caller's [`ErrorModelParams`] (Kriging
//! options and periodic joints); each model then sets its own space and
//! trend.

use crate::cv::kfold_partition;
use crate::dataset::Dataset;
use crate::kinematics::Robot;
use crate::model::ErrorModel;
use crate::params::{ErrorModelParams, TrendSpec};
use crate::physics::{Geometry, HybridModel, LmSummary, PhysicsModel, identify_mdh};
use crate::predictor::ErrorPredictor;
use crate::space::Space;
use crate::stats::spread;
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

/// D-H calibration (Levenberg–Marquardt, every parameter free; redundant
/// ones frozen) of `robot` on `data`, as a model.
pub fn calibrate(data: &Dataset, robot: &Robot) -> Result<(PhysicsModel, LmSummary)> {
    let (cal, lm) = identify_mdh(data, robot, &vec![None; robot.dof()])?;
    let model = PhysicsModel::new(
        "D-H calibration",
        robot.clone(),
        Geometry::Mdh { robot: cal },
    );
    Ok((model, lm))
}

/// `data` with its errors replaced by `errors − dh(q)`: what a hybrid's
/// Kriging stage learns.
pub fn residual(data: &Dataset, dh: &PhysicsModel) -> Result<Dataset> {
    let pred = dh.predict(&data.q, &data.dir)?;
    let mut r = data.clone();
    r.errors = Some(residuals(data.errors_or_err()?, &pred));
    Ok(r)
}

/// The models of [`holdout_cv`], in the order of its rows (after "nominal").
pub const CV_MODELS: [&str; 5] = [
    "D-H calibration (LM, refit per fold)",
    "hybrid: D-H calibration + Kriging JS",
    "hybrid: D-H calibration + Kriging EJS",
    "universal Kriging JS, kinematic trend",
    "universal Kriging EJS, kinematic trend",
];

/// The result of [`holdout_cv`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct HoldoutCv {
    /// "nominal" (no correction), then the [`CV_MODELS`].
    pub rows: Vec<HoldoutRow>,
    /// Max 3D error of each of the [`CV_MODELS`] in each fold, mm.
    pub fold_max_mm: Vec<[f64; 5]>,
    /// The same over the held-out rows the model does not flag as outside
    /// its coverage ([`ErrorModel::coverage`]; the D-H calibration flags
    /// none), mm.
    pub fold_max_covered_mm: Vec<[f64; 5]>,
    /// Rows each of the [`CV_MODELS`] flagged when they were held out.
    pub flagged: Vec<Vec<usize>>,
    /// Rows the Kriging hyperparameters were chosen on (the first ones).
    pub hyper_rows: usize,
    /// Wall time of choosing the hyperparameters, s.
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

/// K-fold CV (fold partition from `seed`) of the five models on all rows.
/// The D-H calibration is refitted on every training fold. The Kriging
/// models keep the hyperparameters (ξ, nugget) chosen with `base` (Kriging
/// options and periodic joints; space and trend set per model) on the
/// first `hyper_rows` rows and are refitted on every training fold at those
/// values: the hybrid on the fold's own calibration residual, the
/// kinematic-trend model on the fold. `progress(done, message)` is called
/// before each of the `k + 1` steps.
pub fn holdout_cv(
    data: &Dataset,
    robot: &Robot,
    base: &ErrorModelParams,
    k: usize,
    seed: u64,
    hyper_rows: usize,
    progress: &dyn Fn(usize, &str),
) -> Result<HoldoutCv> {
    let fold = kfold_partition(data.len(), k, seed)?;
    let errors = data.errors_or_err()?;
    let m = data.len();
    if hyper_rows < 10 {
        return Err(Error::InvalidParameter(format!(
            "the hyperparameters need at least 10 rows, not {hyper_rows}"
        )));
    }
    let first = data.select(&(0..hyper_rows.min(m)).collect::<Vec<_>>());
    progress(
        0,
        &format!("hyperparameters on the first {} rows", first.len()),
    );
    let t_hyper = Instant::now();
    let first_resid = residual(&first, &calibrate(&first, robot)?.0)?;
    let spaces = [Space::Js, Space::Ejs];
    let mut hybrid_t = Vec::new();
    let mut kin_t = Vec::new();
    for space in spaces {
        hybrid_t.push(fit_plain(&first_resid, space, base)?);
        kin_t.push(fit_kinematic(&first, space, base, robot)?);
    }
    let hyper_seconds = t_hyper.elapsed().as_secs_f64();
    let mut pred = vec![vec![[0.0; 3]; m]; 5];
    let mut secs = [0.0; 5];
    let mut fold_max_mm = Vec::with_capacity(k);
    let mut fold_max_covered_mm = Vec::with_capacity(k);
    let mut flagged = vec![Vec::new(); 5];
    for f in 0..k {
        progress(f + 1, &format!("fold {}", f + 1));
        let (test, train): (Vec<usize>, Vec<usize>) = (0..m).partition(|&i| fold[i] == f);
        let (tr, held) = (data.select(&train), data.select(&test));
        let t = Instant::now();
        let (dh, _) = calibrate(&tr, robot)?;
        let dh_secs = t.elapsed().as_secs_f64();
        secs[0] += dh_secs;
        let mut worst = [0.0f64; 5];
        let mut worst_covered = [0.0f64; 5];
        // predictions of model `slot` on the held-out rows, and the rows it
        // flags as outside its coverage
        let mut put = |slot: usize, p: Vec<[f64; 3]>, flags: Vec<usize>| {
            for (j, v) in p.into_iter().enumerate() {
                let e = errors[test[j]];
                let err = e.minus(&v).norm();
                worst[slot] = worst[slot].max(err);
                if !flags.contains(&j) {
                    worst_covered[slot] = worst_covered[slot].max(err);
                }
                pred[slot][test[j]] = v;
            }
            flagged[slot].extend(flags.iter().map(|&j| test[j]));
        };
        put(0, dh.predict(&held.q, &held.dir)?, Vec::new());
        let resid = residual(&tr, &dh)?;
        for s in 0..2 {
            let t = Instant::now();
            let h = HybridModel {
                physics: dh.clone(),
                residual: hybrid_t[s].refit_at_hyperparameters(&resid)?,
            };
            secs[1 + s] += dh_secs + t.elapsed().as_secs_f64();
            let (_, flags) = predicted(&h.residual, &held)?;
            put(1 + s, h.predict(&held.q, &held.dir)?, flags);
            let t = Instant::now();
            let uk = kin_t[s].refit_at_hyperparameters(&tr)?;
            secs[3 + s] += t.elapsed().as_secs_f64();
            let (mean, flags) = predicted(&uk, &held)?;
            put(3 + s, mean, flags);
        }
        fold_max_mm.push(worst);
        fold_max_covered_mm.push(worst_covered);
    }
    let mut rows = vec![score("nominal", errors, &vec![[0.0; 3]; m], 0.0)];
    for (i, n) in CV_MODELS.iter().enumerate() {
        rows.push(score(n, errors, &pred[i], secs[i]));
    }
    Ok(HoldoutCv {
        rows,
        fold_max_mm,
        fold_max_covered_mm,
        flagged: flagged
            .into_iter()
            .map(|mut f| {
                f.sort_unstable();
                f
            })
            .collect(),
        hyper_rows: first.len(),
        hyper_seconds,
    })
}

/// `model`'s predicted mean on `held`, and the rows it flags as outside its
/// coverage (joint range, prediction std, or a correction far beyond its
/// trend).
fn predicted(model: &ErrorModel, held: &Dataset) -> Result<(Vec<[f64; 3]>, Vec<usize>)> {
    let p = model.predict(&held.q, &held.dir)?;
    let flags = model
        .coverage(&held.q, &held.dir, &p.mean, Some(&p.std))?
        .into_iter()
        .map(|w| w.index)
        .collect();
    Ok((p.mean, flags))
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

/// The result of [`holdout_split`].
#[derive(Debug, Clone, PartialEq)]
pub struct HoldoutSplit {
    /// "nominal", then the five models, then the extras asked for.
    pub rows: Vec<HoldoutRow>,
    /// The D-H calibration on the training rows.
    pub calibration: LmSummary,
}

/// Train every model on `train`, score it on `test` (rows it never saw):
/// nominal, the D-H calibration, the hybrid and the kinematic-trend Kriging
/// in JS and EJS, and the `extras`. The Kriging fits start from `base`
/// (Kriging options and periodic joints; space and trend set per model).
/// `progress(message)` is called before each model.
pub fn holdout_split(
    train: &Dataset,
    test: &Dataset,
    robot: &Robot,
    base: &ErrorModelParams,
    extras: SplitExtras,
    progress: &dyn Fn(&str),
) -> Result<HoldoutSplit> {
    use crate::methods::{PAPER_GA_FOLDS, PAPER_PCC_THRESHOLD, PAPER_VARIANCE_SHARE};
    let truth = test.errors_or_err()?.to_vec();
    let mut rows = vec![score("nominal", &truth, &vec![[0.0; 3]; truth.len()], 0.0)];
    progress("D-H calibration");
    let t0 = Instant::now();
    let (dh, calibration) = calibrate(train, robot)?;
    let dh_secs = t0.elapsed().as_secs_f64();
    rows.push(score(
        "D-H calibration (LM)",
        &truth,
        &dh.predict_errors(&test.q, &test.dir)?,
        dh_secs,
    ));
    let resid = residual(train, &dh)?;
    for space in [Space::Js, Space::Ejs] {
        let label = format!("{space:?}").to_uppercase();
        progress(&format!("hybrid {label}"));
        let t0 = Instant::now();
        let h = HybridModel {
            physics: dh.clone(),
            residual: fit_plain(&resid, space, base)?,
        };
        let secs = dh_secs + t0.elapsed().as_secs_f64();
        rows.push(score(
            &format!("hybrid: D-H calibration + Kriging {label}"),
            &truth,
            &h.predict(&test.q, &test.dir)?,
            secs,
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

/// Kriging in `space` with the options' trend, from `base`, on `data`.
fn fit_plain(data: &Dataset, space: Space, base: &ErrorModelParams) -> Result<ErrorModel> {
    base.clone()
        .space(space)
        .trend(TrendSpec::Options)
        .check()?
        .fit(data)
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
            fold_max_mm: Vec::new(),
            fold_max_covered_mm: vec![[1.0, 0.5, 0.0, 2.0, 0.1], [0.5, 0.7, 0.0, 1.0, 0.3]],
            flagged: vec![Vec::new(); 5],
            hyper_rows: 10,
            hyper_seconds: 0.0,
        };
        assert_eq!(cv.max_covered_mm(), [1.0, 0.7, 0.0, 2.0, 0.3]);
    }
}
