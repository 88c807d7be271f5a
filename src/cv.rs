//! K-fold cross-validation (seed 003 eq 21; seed 004 eq 16).
//!
//! A seeded random partition of the rows into K folds of (nearly) equal size.
//! Two modes, named in every result:
//!
//! - *refit*: for each fold the model is refitted (hyperparameters
//!   re-optimised) on the other K − 1 folds and predicts the held-out fold;
//! - *closed-form*: ξ, the input normalisation and the nugget are those of one
//!   fit on all rows; each fold's residuals come from the bordered-system
//!   identity of [`KrigingModel::held_out_residuals`](crate::kriging::KrigingModel::held_out_residuals)
//!   (Dubrule 1983) — one factorisation instead of K fits.
//!
//! The out-of-fold residuals `e_cv = δ − δ̂` are returned in measurement order,
//! with their statistics.

use crate::dataset::Dataset;
use crate::methods::Method;
use crate::model::{ErrorModel, GROSS_FACTOR};
use crate::params::ValidErrorModelParams;
use crate::selection::GaProgress;
use crate::stats::{ErrorSummary, PredictiveScores, predictive_scores, summarize};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::time::Instant;

pub use crate::stats::{group_partition, kfold_partition};

/// How the folds of a cross-validation were predicted.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum CvMode {
    /// The model refitted (hyperparameters re-optimised) on every training fold.
    #[default]
    Refit,
    /// ξ, normalisation and nugget of one fit on all rows; each fold's
    /// residuals from the bordered system (fast).
    ClosedForm,
}

impl CvMode {
    /// `refit` or `closed-form`, as in results and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            CvMode::Refit => "refit",
            CvMode::ClosedForm => "closed-form",
        }
    }

    /// The mode called `name` ([`CvMode::name`]).
    pub fn from_name(name: &str) -> Result<CvMode> {
        [CvMode::Refit, CvMode::ClosedForm]
            .into_iter()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                Error::InvalidParameter(format!("mode '{name}': expected 'refit' or 'closed-form'"))
            })
    }
}

impl std::fmt::Display for CvMode {
    /// The name, padded and aligned as a string would be (`{:<12}`).
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.pad(self.name())
    }
}

/// A mode equals its name (`mode == "refit"`).
impl PartialEq<&str> for CvMode {
    fn eq(&self, other: &&str) -> bool {
        self.name() == *other
    }
}

/// Result of a cross-validation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CvResult {
    /// Number of folds K.
    pub folds: usize,
    /// Seed of the random fold partition ([`kfold_partition`]).
    pub seed: u64,
    /// How the folds were predicted: refit (hyperparameters re-optimised per
    /// fold) or closed form (one fit's ξ and nugget on all rows); serialised
    /// as `"refit"` or `"closed-form"`.
    pub mode: CvMode,
    /// Fold of every row.
    pub fold: Vec<usize>,
    /// Out-of-fold residuals δ − δ̂ (mm), measurement order.
    pub residuals: Vec<[f64; 3]>,
    /// Statistics of the residuals (RMSE per axis = `rms_mm`, eq 17).
    pub summary: ErrorSummary,
    /// Wall-clock time of the whole cross-validation, seconds.
    pub seconds: f64,
    /// Closed form only: the model's own expectation of its leave-one-out
    /// RMSE per axis, mm ([`crate::kriging::HeldOut::expected_loo_rmse`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected_loo_rmse_mm: Option<[f64; 3]>,
    /// Refit mode: how honest the held-out predictive intervals and the
    /// coverage flags were ([`PredictiveScores`]); `None` in closed form and
    /// for models with extra inputs.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub scores: Option<PredictiveScores>,
}

/// K-fold CV refitting the model on every training fold with `fit`.
///
/// ```
/// use robokrige::{cv::cross_validate_refit, dataset::read_csv};
/// use robokrige::{kriging::KrigingOptions, model::ErrorModel, space::Space};
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
/// let data = read_csv(path.as_ref())?.select(&(0..60).collect::<Vec<_>>());
/// let opts = KrigingOptions::default();
/// let cv = cross_validate_refit(&data, 5, 1, |t| ErrorModel::fit(t, Space::Ejs, &opts))?;
/// assert_eq!(cv.residuals.len(), 60); // one out-of-fold residual per row
/// println!("mean 3D error {:.4} mm", cv.summary.mean_3d_mm);
/// # Ok::<(), robokrige::Error>(())
/// ```
pub fn cross_validate_refit<F>(data: &Dataset, k: usize, seed: u64, fit: F) -> Result<CvResult>
where
    F: Fn(&Dataset) -> Result<ErrorModel>,
{
    let fold = kfold_partition(data.len(), k, seed)?;
    let mut res = cross_validate_folds(data, &fold, fit)?;
    res.seed = seed;
    Ok(res)
}

/// Cross-validation refitting the model with `fit` on every training
/// fold, `fold[i]` being the fold of row `i` (0..k, every fold non-empty):
/// a random partition ([`kfold_partition`]) or one fold per group
/// ([`group_partition`], leave-one-group-out). The result's `seed` is 0.
pub fn cross_validate_folds<F>(data: &Dataset, fold: &[usize], fit: F) -> Result<CvResult>
where
    F: Fn(&Dataset) -> Result<ErrorModel>,
{
    let t0 = Instant::now();
    let errors = data.errors_or_err()?;
    let m = data.len();
    let k = crate::stats::fold_count(fold, m)?;
    let mut residuals = vec![[0.0; 3]; m];
    let mut mean = vec![[0.0; 3]; m];
    let mut std = vec![[0.0; 3]; m];
    let mut flagged = vec![false; m];
    let mut scored = true;
    for f in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..m).partition(|&i| fold[i] == f);
        let model = fit(&data.select(&train))?;
        let held = data.select(&test);
        let checked = model.predict_checked(&held)?;
        // flags need the poses alone: a model with extra inputs is not scored
        match &checked.flagged {
            Some(rows) => rows.iter().for_each(|&j| flagged[test[j]] = true),
            None => scored = false,
        }
        let pred = &checked.prediction;
        for (j, &i) in test.iter().enumerate() {
            mean[i] = pred.mean[j];
            std[i] = checked.std_new[j];
            for a in 0..3 {
                residuals[i][a] = errors[i][a] - pred.mean[j][a];
            }
        }
    }
    Ok(CvResult {
        folds: k,
        seed: 0,
        mode: CvMode::Refit,
        summary: summarize(&residuals),
        fold: fold.to_vec(),
        residuals,
        seconds: t0.elapsed().as_secs_f64(),
        expected_loo_rmse_mm: None,
        scores: scored.then(|| predictive_scores(errors, &mean, &std, &flagged, GROSS_FACTOR)),
    })
}

/// K-fold CV in closed form at the hyperparameters of `model`, which must
/// have been fitted on exactly the rows of `data`, in order.
pub fn cross_validate_closed_form(
    data: &Dataset,
    model: &ErrorModel,
    k: usize,
    seed: u64,
) -> Result<CvResult> {
    let t0 = Instant::now();
    data.errors_or_err()?;
    let m = data.len();
    let x = model.input_map().encode_dataset(data)?;
    if model.outputs.iter().any(|o| o.data.x_train != x) {
        return Err(Error::InvalidParameter(format!(
            "closed-form CV needs the model fitted on exactly these {m} rows, in order"
        )));
    }
    let fold = kfold_partition(m, k, seed)?;
    let blocks = crate::stats::fold_blocks(&fold);
    let mut residuals = vec![[0.0; 3]; m];
    let mut expected = [0.0; 3];
    for (a, out) in model.outputs.iter().enumerate() {
        let h = out.held_out(&blocks)?;
        for (r, v) in residuals.iter_mut().zip(h.residuals) {
            r[a] = v;
        }
        expected[a] = h.expected_loo_rmse;
    }
    Ok(CvResult {
        folds: k,
        seed,
        mode: CvMode::ClosedForm,
        summary: summarize(&residuals),
        fold,
        residuals,
        seconds: t0.elapsed().as_secs_f64(),
        expected_loo_rmse_mm: Some(expected),
        scores: None,
    })
}

/// Rows of the largest training set of a `k`-fold CV of `rows` rows
/// ([`kfold_partition`]'s smallest fold held out): what a fit in a fold
/// must be sized for.
pub fn largest_training_rows(rows: usize, k: usize) -> usize {
    rows - rows / k.max(1)
}

/// The memory check of a `k`-fold CV of named methods on `rows` rows
/// ([`crate::model::check_fit_rows`]): the largest training fold
/// ([`largest_training_rows`]), sized as a GPS search on all its rows.
pub fn check_methods_rows(rows: usize, k: usize) -> Result<Option<crate::kriging::FitPlan>> {
    let train = largest_training_rows(rows, k);
    crate::model::check_fit_rows(train, crate::kriging::OptimizerKind::Gps, None)
}

/// K-fold CV of a named method, refitting it ([`Method::params`] with
/// `seed`, no nugget for the papers' methods) on every training fold, its
/// trend selection included; the folds come from `seed` too. `fold_done`
/// is called after each fold's fit, `ga` with the GA's generations.
pub fn cross_validate_method(
    data: &Dataset,
    method: Method,
    k: usize,
    seed: u64,
    fold_done: &dyn Fn(),
    ga: GaProgress,
) -> Result<CvResult> {
    let params = method.params(seed, false).check()?;
    cross_validate_refit(data, k, seed, |train| {
        let model = params.fit_with_progress(train, ga);
        fold_done();
        model
    })
}

/// How [`closed_form_model`] chose the hyperparameters on a subset.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HyperSubset {
    /// The first rows ξ and the nugget were chosen on.
    pub rows: usize,
    /// Wall time of that fit, s.
    pub seconds: f64,
    /// Wall time of the factorisation of all rows at those values, s.
    pub refit_seconds: f64,
}

/// The model of a closed-form CV ([`cross_validate_closed_form`]) of
/// `data`: `params` fitted on all rows or, with `hyper_rows = Some(n)`, ξ
/// and the nugget chosen on the first `n < data.len()` rows and all rows
/// then factorised once at those values ([`ErrorModel::refit`]):
/// the way to CV thousands of rows. The subset's figures come with it.
pub fn closed_form_model(
    data: &Dataset,
    params: &ValidErrorModelParams,
    hyper_rows: Option<usize>,
) -> Result<(ErrorModel, Option<HyperSubset>)> {
    let Some(n) = hyper_rows else {
        return Ok((params.fit(data)?, None));
    };
    if n >= data.len() {
        return Err(Error::InvalidParameter(format!(
            "hyperparameters on the first {n} rows: the campaign has only {} rows",
            data.len()
        )));
    }
    let t = Instant::now();
    let sub = params.fit(&data.select(&(0..n).collect::<Vec<_>>()))?;
    let seconds = t.elapsed().as_secs_f64();
    let t = Instant::now();
    let model = sub.refit(data)?;
    let subset = HyperSubset {
        rows: n,
        seconds,
        refit_seconds: t.elapsed().as_secs_f64(),
    };
    Ok((model, Some(subset)))
}

/// How a cross-validation partitions the rows.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Folds {
    /// `k` folds of a seeded random partition ([`kfold_partition`]).
    Random {
        /// Number of folds K.
        k: usize,
        /// Seed of the partition.
        seed: u64,
    },
    /// Leave-one-group-out: one fold per value of this column of the
    /// campaign ([`Dataset::group_labels`], [`group_partition`]).
    Groups(String),
}

impl Folds {
    /// Leave-one-group-out over the column `groups` when one is named,
    /// else `k` random folds seeded by `seed`.
    pub fn new(groups: Option<&str>, k: usize, seed: u64) -> Folds {
        groups.map_or(Folds::Random { k, seed }, |g| Folds::Groups(g.into()))
    }

    /// The fold of every row of `data`.
    pub fn partition(&self, data: &Dataset) -> Result<Vec<usize>> {
        match self {
            Folds::Random { k, seed } => kfold_partition(data.len(), *k, *seed),
            Folds::Groups(column) => group_partition(&data.group_labels(column)?),
        }
    }
}

/// A cross-validation of one model choice, as `robokrige cv` runs it.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct CvPlan {
    /// Refit in every fold, or closed form at one fit's hyperparameters.
    pub mode: CvMode,
    /// The partition (random folds only in closed form).
    pub folds: Folds,
    /// Closed form only: ξ and the nugget chosen on the first N rows
    /// ([`closed_form_model`]).
    pub hyper_rows: Option<usize>,
}

impl CvPlan {
    /// Refuse a plan that does not suit a campaign of `rows` rows: rows
    /// for the hyperparameters outside the closed form, or not fewer than
    /// the campaign's, and groups in closed form.
    pub fn validate(&self, rows: usize) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(m));
        if self.hyper_rows.is_some() && self.mode != CvMode::ClosedForm {
            return bad(
                "--hyper-rows is for --mode closed-form (refit mode searches ξ in every fold)"
                    .into(),
            );
        }
        if let Some(n) = self.hyper_rows.filter(|&n| n >= rows) {
            return bad(format!(
                "--hyper-rows {n}: the campaign has only {rows} rows; give fewer, or leave it out to choose ξ on all rows"
            ));
        }
        if self.mode == CvMode::ClosedForm && matches!(self.folds, Folds::Groups(_)) {
            return bad("leave-one-group-out CV refits in every fold: not in closed form".into());
        }
        Ok(())
    }

    /// Cross-validate `params` on `data`: refitted on every training fold
    /// ([`cross_validate_folds`]; `progress(done, k)` after each fold), or
    /// in closed form at the hyperparameters of one fit
    /// ([`closed_form_model`], [`cross_validate_closed_form`]), whose
    /// subset's figures come with the result. The result's time covers the
    /// whole run, that fit included; its seed is the partition's (0 for
    /// groups).
    pub fn run(
        &self,
        data: &Dataset,
        params: &ValidErrorModelParams,
        progress: &dyn Fn(usize, usize),
    ) -> Result<(CvResult, Option<HyperSubset>)> {
        self.validate(data.len())?;
        let t0 = Instant::now();
        let (mut res, subset) = match (self.mode, &self.folds) {
            (CvMode::ClosedForm, Folds::Random { k, seed }) => {
                let (model, subset) = closed_form_model(data, params, self.hyper_rows)?;
                (cross_validate_closed_form(data, &model, *k, *seed)?, subset)
            }
            // refit (validate refuses groups in closed form)
            (_, folds) => {
                data.errors_or_err()?;
                let fold = folds.partition(data)?;
                let k = fold.iter().max().map_or(0, |f| f + 1);
                let done = std::cell::Cell::new(0);
                progress(0, k);
                let mut res = cross_validate_folds(data, &fold, |train| {
                    params.params().get_cancel().check()?;
                    let m = params.fit(train);
                    done.set(done.get() + 1);
                    progress(done.get(), k);
                    m
                })?;
                if let Folds::Random { seed, .. } = folds {
                    res.seed = *seed;
                }
                (res, None)
            }
        };
        res.seconds = t0.elapsed().as_secs_f64();
        Ok((res, subset))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_mode_reads_and_writes_as_its_name() {
        for m in [CvMode::Refit, CvMode::ClosedForm] {
            let json = serde_json::to_string(&m).unwrap();
            assert_eq!(json, format!("\"{}\"", m.name()));
            assert_eq!(serde_json::from_str::<CvMode>(&json).unwrap(), m);
            assert_eq!(CvMode::from_name(m.name()).unwrap(), m);
        }
        assert_eq!(format!("[{:<8}]", CvMode::Refit), "[refit   ]");
        assert!(CvMode::ClosedForm == "closed-form");
        let err = CvMode::from_name("fast").unwrap_err().to_string();
        assert!(err.contains("mode 'fast'"), "{err}");
    }

    #[test]
    fn partition_is_balanced_seeded_and_checked() {
        let f = kfold_partition(23, 5, 1).unwrap();
        let mut counts = [0; 5];
        for &x in &f {
            counts[x] += 1;
        }
        assert!(counts.iter().all(|&c| c == 4 || c == 5));
        assert_eq!(f, kfold_partition(23, 5, 1).unwrap());
        assert_ne!(f, kfold_partition(23, 5, 2).unwrap());
        assert!(kfold_partition(3, 5, 1).is_err());
        assert!(kfold_partition(10, 1, 1).is_err());
        // the largest training set holds out the smallest fold (4 rows)
        assert_eq!(largest_training_rows(23, 5), 19);
    }

    fn campaign(rows: usize) -> Dataset {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
        crate::dataset::read_csv(path.as_ref())
            .unwrap()
            .select(&(0..rows).collect::<Vec<_>>())
    }

    #[test]
    fn closed_form_model_on_a_subset_keeps_its_hyperparameters() {
        use crate::kriging::KrigingOptions;
        let data = campaign(40);
        let opts = KrigingOptions::default().starts(2);
        let params = crate::params::ErrorModelParams::new()
            .kriging(opts)
            .check()
            .unwrap();
        let (full, none) = closed_form_model(&data, &params, None).unwrap();
        assert!(none.is_none());
        assert_eq!(full, params.fit(&data).unwrap());
        let (model, subset) = closed_form_model(&data, &params, Some(25)).unwrap();
        assert_eq!(subset.unwrap().rows, 25);
        let sub = params
            .fit(&data.select(&(0..25).collect::<Vec<_>>()))
            .unwrap();
        for (a, b) in model.outputs().iter().zip(sub.outputs()) {
            assert_eq!(a.data().theta, b.data().theta);
        }
        // fitted on all rows, so the closed form runs on it
        assert!(cross_validate_closed_form(&data, &model, 5, 1).is_ok());
        assert!(closed_form_model(&data, &params, Some(40)).is_err());
    }

    #[test]
    fn method_cv_refits_the_method_in_every_fold() {
        let data = campaign(30);
        let folds = std::sync::atomic::AtomicUsize::new(0);
        let done = || {
            folds.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        };
        let cv = cross_validate_method(&data, Method::EjsHj, 3, 1, &done, &|_, _, _| {}).unwrap();
        assert_eq!(folds.into_inner(), 3);
        let params = Method::EjsHj.params(1, false).check().unwrap();
        let by_hand = cross_validate_refit(&data, 3, 1, |t| params.fit(t)).unwrap();
        assert_eq!(cv.residuals, by_hand.residuals);
    }
}
