//! Close the loop: find what the model still gets wrong, trace it to an
//! effect the model lacks, add it, and report before and after.
//!
//! 1. **Residuals**: out-of-fold K-fold CV residuals of the current model
//!    (refit on every training fold), per axis, in measurement order.
//! 2. **Candidates** ([`scan::families`]): every numeric covariate not in the
//!    model (alone, interacting with the joint angles, with one joint angle,
//!    lagged); the measurement order (drift, and a change-point scan);
//!    harmonics of each joint over a scanned period range; cross-joint
//!    products; direction history; the motion into each pose (a joint's
//!    moves with a scanned memory, their size, the TCP's move, the time
//!    since the previous pose).
//! 3. **Tracing** ([`scan::test_families`], [`gls`]): each grid point is
//!    tried inside the current model (its columns join the trend at the
//!    model's ξ and nugget); a family's statistic is its best leave-one-out
//!    gain (for the strongest few at the ξ re-estimated with them), its
//!    p-value a test against sign-flipped pseudo-campaigns of the fitted
//!    model, Benjamini–Hochberg across families, and its score the
//!    closed-form K-fold CV drop.
//! 4. **Adding**: the significant family with the most evidence (its
//!    leave-one-out gain beyond the mean of its null distribution: what
//!    scanning its grid finds by chance is taken off), kinds of effect not
//!    yet in the model first (so that harmonic after harmonic does not
//!    crowd out a step or a drift the data shows clearly), has its feature
//!    join the
//!    model the way its kind needs ([`crate::features::Feature`]): a step,
//!    harmonic, interaction or cross-talk basis as trend terms; a covariate,
//!    the order or direction history as an input dimension with a linear
//!    trend term. The model is refitted and cross-validated again (refit per
//!    fold); it is kept only if the CV RMSE drops by at least `min_gain`, or
//!    by what that is worth at the noise floor ([`Worth`]), and
//!    the loop repeats until nothing significant remains or `max_effects`.
//! 5. **Report**: CV statistics before and after every accepted effect, its
//!    size (trend coefficients with 95 % intervals) and its "after" check
//!    ([`AfterCheck`]): did the model with it reach the level a campaign
//!    without it would, estimated from the data (the model's own
//!    leave-one-out expectation: its nugget's noise plus its interpolation
//!    error), and did it deliver what its test promised?

mod describe;
pub mod gls;
mod plan;
mod rounds;
mod rows;
pub mod scan;

use crate::cv::{CvMode, cross_validate_closed_form, cross_validate_refit, kfold_partition};
use crate::dataset::{Covariate, Dataset};
use crate::features::Feature;
use crate::kriging::{Hyperparameters, KrigingOptions};
use crate::methods::Method;
use crate::model::ErrorModel;
use crate::params::ErrorModelParams;
use crate::space::Space;
use crate::stats::summarize;
use crate::{Error, Result};
pub use plan::DiagnosePlan;
pub use rows::ScanRows;
pub use scan::EffectKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Significant candidates per round whose refit CV is tried before giving up.
const CONFIRMATIONS: usize = 3;

/// Options of [`diagnose`]; `Default` is EJS with the default optimiser
/// (BFGS on the analytic gradient) and a nugget (measurement noise: without one, the interpolating model cannot
/// approach the noise floor), 10 folds, 1999 permutations, FDR 5 %, at most
/// 3 effects.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Input space of every model fitted: JS `[θ]` or EJS `[θ, λ]`.
    pub(crate) space: Space,
    /// Joints (0-based) entered as `(sin θ, cos θ)` in every model fitted
    /// ([`crate::params::ErrorModelParams::periodic`]); empty by default.
    pub(crate) periodic: Vec<usize>,
    /// Kriging options of every fit (trend, correlation, nugget, optimiser).
    pub(crate) kriging: KrigingOptions,
    /// Number of CV folds K.
    pub(crate) folds: usize,
    /// Seed of the fold partition and of the resamples.
    pub(crate) seed: u64,
    /// Most sign-flip resamples per candidate (a sign-flip permutation test;
    /// a clearly null candidate stops after a batch or two). Raised to
    /// [`min_resamples`] of the round's candidates when lower, so that one
    /// real effect among F candidates can reach `q ≤ fdr` (its p-value is at
    /// least `1/(1 + resamples)`); the report gives the number used.
    pub(crate) permutations: usize,
    /// False-discovery rate for the Benjamini–Hochberg step.
    pub(crate) fdr: f64,
    /// Most effects added before the loop stops.
    pub(crate) max_effects: usize,
    /// Relative drop of the pooled CV RMSE an effect must bring to count,
    /// or its worth at the noise floor ([`Worth`]): a candidate is
    /// *significant* when its q-value is within `fdr` and its closed-form CV
    /// drop is worth this (a detectable but negligible effect is ranked,
    /// with a note, not flagged), and it is *kept* when the refit CV
    /// confirms the drop. A candidate whose statistic comes from
    /// re-estimated ξ stays significant only if that confirmation succeeds.
    pub(crate) min_gain: f64,
    /// The measured robot: enables the joint cross-talk candidates (Jacobian).
    pub(crate) robot: Option<crate::kinematics::Robot>,
    /// Candidates (largest statistic first) tested again at the ξ the model
    /// would choose with them ([`gls::refit_systems`]).
    pub(crate) refine: usize,
    /// Largest campaign on which every CV refits each fold and every fit
    /// converges ξ on all rows. Above it (a whole real campaign) each CV is
    /// closed-form at the hyperparameters of the model fitted on all rows
    /// ([`crate::cv::cross_validate_closed_form`]: ten refits of an m × m
    /// likelihood search saved per comparison, and a model with and one
    /// without an effect are compared alike), and every fit — the models
    /// compared and each re-estimation of ξ for a candidate — converges ξ
    /// on the same seeded subset of this many rows, then solves on all of
    /// them ([`KrigingOptions::converge_rows`]). The report says which CV
    /// was used ([`Diagnosis::cv_mode`]).
    pub(crate) refit_rows: usize,
    /// Most rows the candidate test scans ([`ScanRows`]): above it, the
    /// candidates are scanned on this many rows spread evenly over the
    /// campaign, at the model's hyperparameters refactorised on them, while
    /// every model compared is still fitted and cross-validated on all rows.
    pub(crate) scan_rows: usize,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            space: Space::Ejs,
            periodic: Vec::new(),
            kriging: KrigingOptions {
                nugget: true,
                ..KrigingOptions::default()
            },
            folds: 10,
            seed: 1,
            permutations: 1999,
            fdr: 0.05,
            max_effects: 3,
            min_gain: 0.02,
            robot: None,
            refine: 6,
            refit_rows: DEFAULT_REFIT_ROWS,
            scan_rows: DEFAULT_SCAN_ROWS,
        }
    }
}

impl DiagnoseOptions {
    /// The options as [`diagnose`] runs them on a campaign of `rows` rows:
    /// above [`DiagnoseOptions::refit_rows`] (a whole campaign, closed-form
    /// CV) every fit converges ξ on one seeded subset of at most that many
    /// rows, then solves on all rows.
    pub fn for_rows(&self, rows: usize) -> DiagnoseOptions {
        let mut o = self.clone();
        if rows > self.refit_rows {
            o.kriging.converge_rows = o.kriging.converge_rows.min(o.refit_rows);
        }
        o
    }

    fn validate(&self) -> Result<()> {
        if self.permutations < 19 || !(self.fdr > 0.0 && self.fdr < 1.0) || self.min_gain < 0.0 {
            return Err(Error::InvalidParameter(
                "diagnose needs ≥ 19 permutations, 0 < fdr < 1 and min_gain ≥ 0".into(),
            ));
        }
        if self.scan_rows < MIN_SCAN_ROWS {
            return Err(Error::InvalidParameter(format!(
                "diagnose scan_rows is {}: the candidate test needs at least {MIN_SCAN_ROWS} rows",
                self.scan_rows
            )));
        }
        if self.refit_rows < 100 {
            return Err(Error::InvalidParameter(format!(
                "diagnose refit_rows is {}: re-estimating ξ needs at least 100 rows",
                self.refit_rows
            )));
        }
        self.kriging.validate()
    }
}

/// Builder setters (named after the fields; they document each option) and
/// getters (`get_*`).
impl DiagnoseOptions {
    /// Input space of every model fitted: JS `[θ]` or EJS `[θ, λ]`.
    pub fn space(mut self, space: Space) -> Self {
        self.space = space;
        self
    }
    /// Joints (0-based) entered as `(sin θ, cos θ)` in every model fitted
    /// ([`crate::params::ErrorModelParams::periodic`]); empty by default.
    pub fn periodic(mut self, joints: Vec<usize>) -> Self {
        self.periodic = joints;
        self
    }
    /// Kriging options of every fit (trend, correlation, nugget, optimiser).
    pub fn kriging(mut self, kriging: KrigingOptions) -> Self {
        self.kriging = kriging;
        self
    }
    /// The space and Kriging options of a base model ([`base_params`]).
    pub fn base(self, params: &ErrorModelParams) -> Self {
        self.space(params.get_space())
            .kriging(params.get_kriging().clone())
    }
    /// Number of CV folds K.
    pub fn folds(mut self, k: usize) -> Self {
        self.folds = k;
        self
    }
    /// Seed of the fold partition and of the resamples.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }
    /// Most sign-flip resamples per candidate (a sign-flip permutation test;
    /// a clearly null candidate stops after a batch or two). Raised to
    /// [`min_resamples`] of the round's candidates when lower, so that one
    /// real effect among F candidates can reach `q ≤ fdr` (its p-value is at
    /// least `1/(1 + resamples)`); the report gives the number used.
    pub fn permutations(mut self, n: usize) -> Self {
        self.permutations = n;
        self
    }
    /// False-discovery rate for the Benjamini–Hochberg step.
    pub fn fdr(mut self, rate: f64) -> Self {
        self.fdr = rate;
        self
    }
    /// Most effects added before the loop stops.
    pub fn max_effects(mut self, n: usize) -> Self {
        self.max_effects = n;
        self
    }
    /// Relative drop of the pooled CV RMSE an effect must bring to count,
    /// or its worth at the noise floor ([`Worth`]): a candidate is
    /// *significant* when its q-value is within `fdr` and its closed-form CV
    /// drop is worth this (a detectable but negligible effect is ranked,
    /// with a note, not flagged), and it is *kept* when the refit CV
    /// confirms the drop. A candidate whose statistic comes from
    /// re-estimated ξ stays significant only if that confirmation succeeds.
    pub fn min_gain(mut self, gain: f64) -> Self {
        self.min_gain = gain;
        self
    }
    /// The measured robot: enables the joint cross-talk candidates (Jacobian).
    pub fn robot(mut self, robot: Option<crate::kinematics::Robot>) -> Self {
        self.robot = robot;
        self
    }
    /// Candidates (largest statistic first) tested again at the ξ the model
    /// would choose with them ([`gls::refit_systems`]).
    pub fn refine(mut self, n: usize) -> Self {
        self.refine = n;
        self
    }
    /// Largest campaign on which every CV refits each fold and every fit
    /// converges ξ on all rows. Above it (a whole real campaign) each CV is
    /// closed-form at the hyperparameters of the model fitted on all rows
    /// ([`crate::cv::cross_validate_closed_form`]: ten refits of an m × m
    /// likelihood search saved per comparison, and a model with and one
    /// without an effect are compared alike), and every fit — the models
    /// compared and each re-estimation of ξ for a candidate — converges ξ
    /// on the same seeded subset of this many rows, then solves on all of
    /// them ([`KrigingOptions::converge_rows`]). The report says which CV
    /// was used ([`Diagnosis::cv_mode`]).
    pub fn refit_rows(mut self, rows: usize) -> Self {
        self.refit_rows = rows;
        self
    }
    /// Most rows the candidate test scans: above it, the candidate families
    /// are built and tested on this many rows spread evenly over the
    /// campaign (in measurement order; each row keeps the history features
    /// of the whole campaign), at the current model's hyperparameters
    /// refactorised on them — the test's memory grows as rows × scanned
    /// values and its time as rows³, and a step is scanned at every scanned
    /// row.
    /// The models with and without a candidate are still fitted and
    /// cross-validated on all rows, so the effects added and the CV figures
    /// are those of the whole campaign; a step or block edge found on the
    /// scanned rows is placed among the campaign rows since the scanned row
    /// before it by the CV residuals of all rows. The report gives the rows
    /// scanned ([`Diagnosis::scanned_rows`]).
    pub fn scan_rows(mut self, rows: usize) -> Self {
        self.scan_rows = rows;
        self
    }

    /// The input space of every model fitted.
    pub fn get_space(&self) -> Space {
        self.space
    }
    /// The joints (0-based) entered as (sin θ, cos θ).
    pub fn get_periodic(&self) -> &[usize] {
        &self.periodic
    }
    /// The Kriging options of every fit.
    pub fn get_kriging(&self) -> &KrigingOptions {
        &self.kriging
    }
    /// The number of CV folds K.
    pub fn get_folds(&self) -> usize {
        self.folds
    }
    /// The seed of the fold partition and of the resamples.
    pub fn get_seed(&self) -> u64 {
        self.seed
    }
    /// The most sign-flip resamples per candidate.
    pub fn get_permutations(&self) -> usize {
        self.permutations
    }
    /// The false-discovery rate of the Benjamini–Hochberg step.
    pub fn get_fdr(&self) -> f64 {
        self.fdr
    }
    /// The most effects added before the loop stops.
    pub fn get_max_effects(&self) -> usize {
        self.max_effects
    }
    /// The relative drop of the pooled CV RMSE an effect must bring.
    pub fn get_min_gain(&self) -> f64 {
        self.min_gain
    }
    /// The measured robot (enables the cross-talk candidates).
    pub fn get_robot(&self) -> Option<&crate::kinematics::Robot> {
        self.robot.as_ref()
    }
    /// The candidates tested again at re-estimated ξ.
    pub fn get_refine(&self) -> usize {
        self.refine
    }
    /// The largest campaign on which every CV refits each fold.
    pub fn get_refit_rows(&self) -> usize {
        self.refit_rows
    }
    /// The most rows the candidate test scans.
    pub fn get_scan_rows(&self) -> usize {
        self.scan_rows
    }
}

/// Default of [`DiagnoseOptions::refit_rows`].
pub const DEFAULT_REFIT_ROWS: usize = 1200;

/// Default of [`DiagnoseOptions::scan_rows`]: all 2 773 rows of the largest
/// real campaign at hand (UR10 series C, diagnosed in about 2 minutes)
/// are scanned; a grid campaign of 12 000 rows is scanned on every fourth.
pub const DEFAULT_SCAN_ROWS: usize = 3000;

/// Least [`DiagnoseOptions::scan_rows`].
pub const MIN_SCAN_ROWS: usize = 200;

/// Resamples a round with `families` candidates needs so that a single
/// real effect can be significant after Benjamini–Hochberg: its smallest
/// p-value `1/(1 + P)` times `families` must stay within `fdr`.
pub fn min_resamples(families: usize, fdr: f64) -> usize {
    (families as f64 / fdr).ceil() as usize
}

/// When a drop of the CV error is worth an effect: the pooled CV
/// RMSE falls by the share `g` (`min_gain`), **or** the CV mean squared
/// error falls by what that share is worth at the noise floor,
/// `(1 − (1 − g)²)·σ̄_ν²` with σ̄_ν the model's noise (its nugget, pooled over
/// the axes; without a nugget only the first). At the noise floor the two agree; the second keeps a clear
/// effect from hiding behind an under-fitted base model whose CV RMSE is
/// far above the noise (a 0.12 mm tracker bump in real UR10 rows lowered an
/// EJS model's CV RMSE by only 1.2 %).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Worth {
    /// Share of the mean squared error, `1 − (1 − g)²`.
    share: f64,
    /// Absolute drop of the mean squared error, mm².
    floor_mse: f64,
}

impl Worth {
    /// For relative gain `min_gain` and a model with noise `noise_mm` per axis.
    pub fn new(min_gain: f64, noise_mm: &[f64; 3]) -> Self {
        let share = 1.0 - (1.0 - min_gain).powi(2);
        let noise2 = noise_mm.iter().map(|v| v * v).sum::<f64>() / 3.0;
        Worth {
            share,
            // an interpolating model (no nugget) has no noise estimate
            floor_mse: if noise2 > 0.0 {
                share * noise2
            } else {
                f64::INFINITY
            },
        }
    }

    /// Whether a drop of the mean squared error from `before` to `after`
    /// (mm², pooled per axis) is worth an effect.
    pub fn counts(&self, before: f64, after: f64) -> bool {
        let drop = before - after;
        drop > 0.0 && (drop >= self.share * before || drop >= self.floor_mse)
    }

    /// The absolute drop of the mean squared error that counts, mm².
    pub fn floor_mse(&self) -> f64 {
        self.floor_mse
    }
}

/// CV statistics of one model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CvStats {
    /// Per-axis RMSE of the out-of-fold residuals, mm.
    pub cv_rmse_mm: [f64; 3],
    /// RMSE pooled over the axes, mm.
    pub pooled_rmse_mm: f64,
    /// Mean of the out-of-fold 3D error |δ − δ̂|, mm.
    pub mean_3d_mm: f64,
    /// Largest out-of-fold 3D error |δ − δ̂|, mm.
    pub max_3d_mm: f64,
    /// Extra inputs of the model.
    pub extras: Vec<String>,
    /// The model's noise standard deviation per axis (mm), from its nugget
    /// ([`ErrorModel::noise_std`]).
    #[serde(default)]
    pub noise_mm: [f64; 3],
    /// How the folds were predicted ([`crate::cv::CvResult::mode`]):
    /// refit, or closed form above [`DiagnoseOptions::refit_rows`].
    #[serde(default)]
    pub mode: CvMode,
    /// Closed-form CV only: the model's own expectation of its
    /// leave-one-out RMSE per axis on all rows, mm
    /// ([`crate::cv::CvResult::expected_loo_rmse_mm`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected_loo_rmse_mm: Option<[f64; 3]>,
    /// Out-of-fold residuals δ − δ̂ (mm), measurement order; not serialised.
    #[serde(skip)]
    pub residuals: Vec<[f64; 3]>,
}

fn cv_stats(res: crate::cv::CvResult, extras: &[Feature], model: &ErrorModel) -> CvStats {
    let residuals = res.residuals;
    let s = summarize(&residuals);
    CvStats {
        mode: res.mode,
        expected_loo_rmse_mm: res.expected_loo_rmse_mm,
        noise_mm: model.noise_std(),
        cv_rmse_mm: s.rms_mm,
        pooled_rmse_mm: (s.rms_mm.iter().map(|v| v * v).sum::<f64>() / 3.0).sqrt(),
        mean_3d_mm: s.mean_3d_mm,
        max_3d_mm: s.max_3d_mm,
        extras: extras.iter().flat_map(Feature::names).collect(),
        residuals,
    }
}

/// One candidate as ranked in one round.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectReport {
    /// Round of the loop (1-based) in which it was ranked.
    pub round: usize,
    /// What kind of effect the candidate is.
    pub kind: EffectKind,
    /// Column(s) or joint(s) it comes from, e.g. `["temp_c"]`, `["q2"]`, `["row"]`.
    pub source: Vec<String>,
    /// Short description, e.g. "temp_c × joint angles".
    pub label: String,
    /// Parameters of the best grid point (e.g. `period_deg`, `row`).
    pub params: BTreeMap<String, f64>,
    /// A 95 % support interval of each scanned parameter: the range over
    /// the grid points whose leave-one-out gain is within `χ²₁(95 %)` times
    /// the model's expected leave-one-out variance of the best (for a step,
    /// the rows it may be at).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params_ci: BTreeMap<String, [f64; 2]>,
    /// Out of sample: relative drop of the closed-form K-fold CV squared
    /// error with the candidate in the trend ([`gls`]).
    pub score: f64,
    /// Leave-one-out gain of the best grid point as a share of the model's
    /// leave-one-out squared error (the test statistic, relative).
    pub explained: f64,
    /// Sign-flip test p-value `(1 + exceedances) / (1 + resamples)`, before the
    /// multiple-testing correction.
    pub p_value: f64,
    /// The statistic beyond what scanning its grid finds by chance (minus
    /// its null distribution's mean), as a share of the model's leave-one-out
    /// SSE: the ranking of significant candidates.
    #[serde(default)]
    pub evidence: f64,
    /// Benjamini–Hochberg adjusted p-value.
    pub q_value: f64,
    /// Counted as a discovery: q-value within `fdr` and a closed-form CV drop
    /// of at least `min_gain`; a candidate tested at re-estimated ξ loses it
    /// when the refit CV does not confirm the drop.
    pub significant: bool,
    /// Added to the model (significant, best of its round, and it lowered the CV RMSE).
    pub accepted: bool,
    /// Other significant candidates of the round that explain nearly the same
    /// residual component (cosine ≥ 0.9) with a score within 20 % of this
    /// one: the data cannot tell them apart (e.g. payload blocks and time).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confounded_with: Vec<String>,
    /// Why a significant best candidate was not kept, or why a candidate
    /// with q within the FDR is not counted as significant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Scored at the correlation parameters refitted with the candidate in
    /// the trend (the strongest few of a round), else at the model's own;
    /// its p-value is the model's own but for a kind the GP can soak up
    /// ([`EffectKind::pose_function`]).
    #[serde(default)]
    pub refit_xi: bool,
    /// Sign-flip resamples run before its p-value settled.
    #[serde(default)]
    pub resamples: usize,
    /// For an added effect: its trend coefficients with 95 % intervals
    /// (the size of a step in mm, the share of a move left as lag, …).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub size: Vec<Coefficient>,
    /// For an added effect: how much of what it promised the refit model
    /// delivers, and how close the CV RMSE came to the model's own level.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after_check: Option<AfterCheck>,
    /// What would be added to the model if it were accepted; not serialised.
    #[serde(skip)]
    pub add: Vec<Feature>,
}

/// One trend coefficient of an added effect, per axis: the GLS estimate
/// and its 95 % interval (± 1.96 standard errors, [`ErrorModel::trend_coefficient`]),
/// in mm per unit of the column (for a step, the step in mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Coefficient {
    /// The model's input column, e.g. `step@150`.
    pub column: String,
    /// Estimate per axis (x, y, z).
    pub estimate: [f64; 3],
    /// Half-width of the 95 % interval per axis.
    pub ci95: [f64; 3],
}

/// The "after" check of an added effect: did the model with it
/// reach the level of a campaign without it?
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AfterCheck {
    /// Drop of the pooled CV RMSE the closed-form test promised (share).
    pub promised: f64,
    /// Drop of the pooled CV RMSE the refit model reached (share).
    pub achieved: f64,
    /// CV RMSE of the model with the effect, per axis (mm).
    pub cv_rmse_mm: [f64; 3],
    /// The level a campaign without the effect would reach, estimated from
    /// the data: the refit model's own expectation of its leave-one-out
    /// error, its nugget's noise plus its interpolation error, per axis (mm).
    pub level_mm: [f64; 3],
    /// The nugget's noise alone, per axis (mm).
    pub noise_mm: [f64; 3],
    /// Only partly modelled: it delivers under half of what it promised,
    /// the CV RMSE stays above 1.3× the level, or a candidate of the same
    /// source is still significant in the next round.
    pub partly: bool,
    /// The verdict in words.
    pub verdict: String,
}

impl EffectReport {
    /// The variable this effect is traced to, with its label and its value
    /// on every row of `data` (the x axis of a residual plot): the phase of
    /// a harmonic, the row for a drift or a step, the covariate, or the
    /// feature's first column. Empty when nothing would be added.
    pub fn traced_variable(&self, data: &Dataset) -> (String, Vec<f64>) {
        match self.add.first() {
            Some(Feature::Harmonic { joint, period_deg }) => (
                format!("phase of q{joint} in its {period_deg:.3}° period (deg)"),
                data.q
                    .iter()
                    .map(|r| r[joint - 1].rem_euclid(*period_deg))
                    .collect(),
            ),
            Some(Feature::Row | Feature::Step { .. }) => (
                "measurement order (row)".into(),
                (0..data.len()).map(|i| i as f64).collect(),
            ),
            Some(f @ Feature::Covariate { name, .. }) => (
                name.clone(),
                f.columns(data).map(|c| c[0].clone()).unwrap_or_default(),
            ),
            Some(f) => (
                f.names()[0].clone(),
                f.columns_from_poses(&data.q, &data.dir)
                    .map(|c| c[0].clone())
                    .unwrap_or_default(),
            ),
            None => (String::new(), Vec::new()),
        }
    }
}

/// The result of [`diagnose`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Input space of the models.
    pub space: Space,
    /// Number of CV folds K.
    pub folds: usize,
    /// Seed of the fold partition and of the resamples.
    pub seed: u64,
    /// Most sign-flip resamples per candidate, as used (the option, raised
    /// to [`min_resamples`] of the largest round when lower).
    pub permutations: usize,
    /// Candidate families tested in the first round, and the grid points
    /// (parameter values) they scan in all: the multiple testing the
    /// false-discovery control pays for.
    #[serde(default)]
    pub candidates: [usize; 2],
    /// False-discovery rate of the Benjamini–Hochberg step.
    pub fdr: f64,
    /// CV statistics of the model as given (no extra input).
    pub before: CvStats,
    /// CV statistics of the final model (equal to `before` when nothing was added).
    pub after: CvStats,
    /// CV statistics after each accepted effect, in order.
    pub steps: Vec<CvStats>,
    /// Every candidate of every round, each round ranked: the significant
    /// ones by evidence, then the others by score.
    pub effects: Vec<EffectReport>,
    /// Extra inputs of the final model.
    pub extras: Vec<Feature>,
    /// Rows of the campaign (every model compared was fitted and
    /// cross-validated on all of them; 0 in reports written before it was
    /// recorded).
    #[serde(default)]
    pub rows: usize,
    /// Rows the candidate test scanned ([`DiagnoseOptions::scan_rows`]):
    /// all `rows`, or an evenly spread subset of them, on which every
    /// candidate's statistic, p-value, score and evidence were computed
    /// (0 in reports written before it was recorded: all).
    #[serde(default)]
    pub scanned_rows: usize,
    /// Covariates left out of the candidates because they do not vary over
    /// the rows used ([`scan::constant_covariate`]).
    #[serde(default)]
    pub dropped_covariates: Vec<scan::DroppedCovariate>,
    /// Wall-clock time of the whole diagnosis, seconds.
    pub seconds: f64,
}

impl Diagnosis {
    /// How every CV of the diagnosis was run ([`CvStats::mode`]).
    pub fn cv_mode(&self) -> CvMode {
        self.before.mode
    }
}

/// Precompute the columns of `extras` on the whole campaign (named like the
/// feature, so they keep their values inside CV folds).
pub fn with_columns(data: &Dataset, extras: &[Feature]) -> Result<Dataset> {
    let mut work = data.clone();
    for f in extras {
        let cols = f.columns(&work)?;
        for (name, values) in f.names().into_iter().zip(cols) {
            if work.covariate(&name).is_none() {
                work.covariates.push(Covariate {
                    name,
                    values,
                    missing: 0,
                });
            }
        }
    }
    Ok(work)
}

/// The model with `extras` fitted on all of `data`, and its K-fold CV. Each
/// fold is refitted with a local search warm-started at the full model's
/// hyperparameters and curvature ([`crate::kriging::Tuning::Warm`]): a fold
/// holds 90 % of the rows, so its optimum lies in the same basin, and the
/// multistart would find it again at several times the cost. With `from`
/// (the current model) the full fit too is a local search from `from`, so
/// that the model with the effect is compared with the model without it in
/// the same basin of the multimodal likelihood (the candidate was found
/// there: [`gls::refit_systems`]); see [`extended_starts`].
fn cross_validated(
    data: &Dataset,
    extras: &[Feature],
    o: &DiagnoseOptions,
    from: Option<&ErrorModel>,
) -> Result<(CvStats, ErrorModel)> {
    let work = with_columns(data, extras)?;
    let start = from.and_then(|m| extended_starts(m, extras));
    let model = ErrorModel::fit_with_extras(
        &work,
        o.space,
        &o.periodic,
        &o.kriging,
        extras,
        start.as_deref(),
    )?;
    let warm = model.warm_starts();
    let res = if data.len() > o.refit_rows {
        cross_validate_closed_form(&work, &model, o.folds, o.seed)?
    } else {
        cross_validate_refit(&work, o.folds, o.seed, |train| {
            ErrorModel::fit_with_extras(
                train,
                o.space,
                &o.periodic,
                &o.kriging,
                extras,
                Some(&warm),
            )
        })?
    };
    Ok((cv_stats(res, extras, &model), model))
}

/// Warm starts for the model of `extras` from `from`, whose extras they
/// extend (`None` otherwise: another feature, or a correlation input not
/// after `from`'s): a candidate of trend terms only keeps
/// `from`'s ξ, ν and curvature; one that adds input dimensions (a
/// covariate, a joint's moves) starts each new dimension as weakly as
/// `from`'s weakest correlation input (its smallest ξ), so that the search
/// starts from the model the candidate was tested in — the effect as trend
/// terms, the GP unchanged — and lengthens or shortens the new scale from
/// there. A search from scratch lands in another basin of the likelihood,
/// whose CV then says more about the basin than about the effect (on all
/// 2 773 rows of UR10 series C, a planted lag and a planted temperature
/// drift were found but not confirmed that way).
fn extended_starts(from: &ErrorModel, extras: &[Feature]) -> Option<Vec<Hyperparameters>> {
    // a model's correlation inputs are its extras that are not trend-only,
    // in their order (`ErrorModel::extras` holds them first)
    let inputs =
        |e: &[Feature]| -> Vec<Feature> { e.iter().filter(|f| !f.trend_only()).cloned().collect() };
    if !from.extras().iter().all(|f| extras.contains(f))
        || !inputs(extras).starts_with(&inputs(from.extras()))
    {
        return None;
    }
    let new_dims = crate::features::correlation_dims(extras)
        .checked_sub(crate::features::correlation_dims(from.extras()))?;
    let starts = from.warm_starts();
    if new_dims == 0 {
        return Some(starts);
    }
    Some(
        starts
            .into_iter()
            .map(|w| {
                let weakest = w.theta.iter().copied().fold(f64::INFINITY, f64::min);
                let mut theta = w.theta;
                theta.extend(std::iter::repeat_n(weakest, new_dims));
                Hyperparameters::new(theta, w.nugget)
            })
            .collect(),
    )
}

/// The range of every parameter over the grid points of a support set (their
/// parameters).
fn support_interval<'a>(
    support: impl IntoIterator<Item = &'a BTreeMap<String, f64>>,
) -> BTreeMap<String, [f64; 2]> {
    let mut out: BTreeMap<String, [f64; 2]> = BTreeMap::new();
    for params in support {
        for (k, v) in params {
            let e = out.entry(k.clone()).or_insert([*v, *v]);
            e[0] = e[0].min(*v);
            e[1] = e[1].max(*v);
        }
    }
    out
}

/// The trend coefficients of the columns `add` brings, with 95 % intervals.
fn coefficients(model: &ErrorModel, add: &[Feature]) -> Vec<Coefficient> {
    add.iter()
        .flat_map(Feature::names)
        .filter_map(|column| {
            let c = model.trend_coefficient(&column)?;
            Some(Coefficient {
                estimate: c.map(|(b, _)| b),
                ci95: c.map(|(_, se)| 1.96 * se),
                column,
            })
        })
        .collect()
}

impl EffectReport {
    /// Add `text` to the report's note (after any note it has: "ranked
    /// before …; not added: …").
    fn add_note(&mut self, text: String) {
        self.note = Some(match self.note.take() {
            Some(n) => format!("{n}; {text}"),
            None => text,
        });
    }
}

/// The significant candidates of `tested` other than `k` that explain what
/// `k` explains: a score at least [`SAME_SCORE`] of its, and a fitted
/// component of the residuals within cosine [`SAME_FIT`] of its.
fn alike(
    tested: &[scan::Tested],
    fams: &[scan::Family],
    residuals: &[[f64; 3]],
    k: usize,
    significant: &dyn Fn(&scan::Tested) -> bool,
) -> Vec<usize> {
    let fit = |t: &scan::Tested| scan::fitted(&t.point(&fams[t.family]).columns, residuals);
    let top = fit(&tested[k]);
    (0..tested.len())
        .filter(|&i| {
            i != k && significant(&tested[i]) && tested[i].score >= SAME_SCORE * tested[k].score
        })
        .filter(|&i| scan::similarity(&top, &fit(&tested[i])) >= SAME_FIT)
        .collect()
}

/// Occam's rule for the first candidate of `tested` (in its ranked order):
/// of the candidates [`alike`] it, one that adds fewer model columns (its
/// features' names) goes first — a temperature drift is "temp_c", one
/// input, not "temp_c × one joint angle", whose three trend columns happen
/// to carry it as well. Returns the new first's index and the label it
/// overtook.
fn prefer_simpler(
    tested: &mut Vec<scan::Tested>,
    fams: &[scan::Family],
    residuals: &[[f64; 3]],
    significant: &dyn Fn(&scan::Tested) -> bool,
) -> Option<(usize, String)> {
    let size = |t: &scan::Tested| -> usize {
        t.point(&fams[t.family])
            .add
            .iter()
            .map(|f| f.names().len())
            .sum()
    };
    let first = tested
        .iter()
        .position(|t| significant(t) && t.score > 0.0)?;
    let simpler = alike(tested, fams, residuals, first, significant)
        .into_iter()
        .filter(|&i| size(&tested[i]) < size(&tested[first]))
        .min_by_key(|&i| (size(&tested[i]), i))?;
    let over = fams[tested[first].family].label.clone();
    let t = tested.remove(simpler);
    tested.insert(first, t);
    Some((first, over))
}

/// A step or block edge found on scanned rows ([`ScanRows`]) is at its
/// scanned row or at one of the campaign rows just before it
/// ([`ScanRows::gap`]): each is placed at the row of its gap that best
/// splits the CV residuals of all rows — least squares, the levels on either
/// side the mean residual of the [`PLACE_WINDOW`] spacings of rows before
/// and after the gap — and the support interval is widened to the gaps.
fn place_steps(report: &mut EffectReport, rows: &ScanRows, residuals: &[[f64; 3]]) {
    let window = PLACE_WINDOW * rows.total().div_ceil(rows.len().max(1));
    let mut moved = Vec::new();
    for f in report.add.iter_mut() {
        let Feature::Step { row } = f else { continue };
        let gap = rows.gap(*row);
        let (a, b) = (*gap.start(), *gap.end());
        let before = a.saturating_sub(window)..a;
        let after = b..(b + window).min(residuals.len());
        if a == b || before.is_empty() || after.is_empty() {
            continue;
        }
        let mean = |r: std::ops::Range<usize>| -> [f64; 3] {
            let n = r.len() as f64;
            std::array::from_fn(|x| r.clone().map(|i| residuals[i][x]).sum::<f64>() / n)
        };
        let (lo, hi) = (mean(before), mean(after));
        let d2 = |e: &[f64; 3], l: &[f64; 3]| (0..3).map(|x| (e[x] - l[x]).powi(2)).sum::<f64>();
        // rows a..b are ambiguous: before the step at lo, from it on at hi
        let cost = |c: usize| -> f64 {
            (a..b)
                .map(|i| d2(&residuals[i], if i < c { &lo } else { &hi }))
                .sum()
        };
        let best = (a..=b)
            .min_by(|&x, &y| cost(x).total_cmp(&cost(y)))
            .unwrap_or(b);
        for v in report.params.values_mut() {
            if *v == *row as f64 {
                *v = best as f64;
            }
        }
        moved.push(format!("{} → {best} (rows {a}–{b})", *row));
        *row = best;
    }
    for (key, ci) in report.params_ci.iter_mut() {
        if key.ends_with("row") {
            ci[0] = *rows.gap(ci[0] as usize).start() as f64;
        }
    }
    if !moved.is_empty() {
        report.add_note(format!(
            "found on {} scanned rows, placed between them by the CV residuals of all rows: {}",
            rows.len(),
            moved.join(", ")
        ));
    }
}

/// Rows on either side of a gap that set the levels [`place_steps`] splits
/// it between, in spacings of the scanned rows.
const PLACE_WINDOW: usize = 8;

/// Cosine similarity of fitted components above which two candidates
/// explain the same.
const SAME_FIT: f64 = 0.9;
/// Share of the first candidate's score a simpler one needs to go first.
const SAME_SCORE: f64 = 0.8;

/// A CV RMSE above this multiple of the level a campaign without the effect
/// would reach counts as only partly modelled (the target an added effect
/// must meet).
pub const AFTER_LEVEL_RATIO: f64 = 1.3;

/// The "after" check of an added effect: `promised` and `achieved` drops of
/// the pooled CV RMSE, the CV `after`, the refit model's own leave-one-out
/// `level` per axis, and the label of a candidate of the same source still
/// significant in round `round`.
fn after_check(
    promised: f64,
    achieved: f64,
    after: &CvStats,
    level: [f64; 3],
    again: Option<String>,
    round: usize,
) -> AfterCheck {
    let pooled = |v: &[f64; 3]| (v.iter().map(|x| x * x).sum::<f64>() / 3.0).sqrt();
    let ratio = after.pooled_rmse_mm / pooled(&level).max(f64::MIN_POSITIVE);
    let mut why = Vec::new();
    if achieved < 0.5 * promised {
        why.push(format!(
            "the refit model lowers the CV RMSE by {:.1} %, under half the {:.1} % its test promised",
            100.0 * achieved,
            100.0 * promised
        ));
    }
    if ratio > AFTER_LEVEL_RATIO {
        why.push(format!(
            "the CV RMSE stays at {ratio:.2}× the level of a campaign without it ({:.4} mm)",
            pooled(&level)
        ));
    }
    if let Some(label) = again {
        why.push(format!(
            "'{label}', of the same source, is still significant in round {round}"
        ));
    }
    let partly = !why.is_empty();
    let verdict = if partly {
        format!("found, but only partly modelled: {}", why.join("; "))
    } else {
        format!(
            "explained: CV RMSE {:.4} mm, {ratio:.2}× the level of a campaign without it ({:.4} mm: noise {:.4} mm plus interpolation)",
            after.pooled_rmse_mm,
            pooled(&level),
            pooled(&after.noise_mm)
        )
    };
    AfterCheck {
        promised,
        achieved,
        cv_rmse_mm: after.cv_rmse_mm,
        level_mm: level,
        noise_mm: after.noise_mm,
        partly,
        verdict,
    }
}

/// The base model a diagnosis starts from, by name, as fit parameters
/// (their space and Kriging options; [`DiagnoseOptions::base`]):
/// - `ejs` (the default) and `js`: BFGS, constant trend, the Gaussian
///   family, in that space (`robokrige fit --space S --corr gaussian`);
/// - the papers' methods whose trend is the options' and whose family is
///   fixed, `js-hj`, `ejs-hj` and `ejs-gps`: the method's own set-up
///   ([`Method::params`]: space, optimiser, starts).
///
/// `nugget` estimates a nugget in either (the default of `diagnose`:
/// measured data has noise); for a method that is [`Method::params`]'s own
/// switch, so `--method ejs-gps --no-nugget` is exactly `ejs-gps`.
pub fn base_params(name: &str, seed: u64, nugget: bool) -> Result<ErrorModelParams> {
    let space = match name {
        "ejs" => Some(Space::Ejs),
        "js" => Some(Space::Js),
        _ => None,
    };
    if let Some(space) = space {
        let opts = KrigingOptions::default().nugget(nugget).seed(seed);
        return Ok(ErrorModelParams::new().space(space).kriging(opts));
    }
    match Method::from_name(name) {
        Ok(m @ (Method::JsHj | Method::EjsHj | Method::EjsGps)) => Ok(m.params(seed, nugget)),
        _ => Err(Error::InvalidParameter(format!(
            "diagnose supports the base models ejs, js, js-hj, ejs-hj or ejs-gps, not '{name}'"
        ))),
    }
}

/// The model of `data` with `extras` as inputs, fitted with the options of
/// `o` (after a diagnosis: its improved model, `extras` = [`Diagnosis::extras`];
/// with no extras: the model as it was).
pub fn fit_with_effects(
    data: &Dataset,
    o: &DiagnoseOptions,
    extras: &[Feature],
) -> Result<ErrorModel> {
    let work = with_columns(data, extras)?;
    ErrorModelParams::new()
        .space(o.space)
        .periodic(o.periodic.clone())
        .kriging(o.kriging.clone())
        .extras(extras.to_vec())
        .check()?
        .fit(&work)
}

/// Run the loop on `data` (which needs `ex,ey,ez`). `progress` receives one
/// line per step.
///
/// ```no_run
/// use robokrige::{dataset::read_csv, diagnose::{DiagnoseOptions, diagnose}};
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_tracker_step.csv");
/// let data = read_csv(path.as_ref())?;
/// let found = diagnose(&data, &DiagnoseOptions::default(), &|line| eprintln!("{line}"))?;
/// for e in found.effects.iter().filter(|e| e.accepted) {
///     println!("added {} (q {:.4})", e.label, e.q_value); // the step at row 150
/// }
/// # Ok::<(), robokrige::Error>(())
/// ```
pub fn diagnose(data: &Dataset, o: &DiagnoseOptions, progress: &dyn Fn(&str)) -> Result<Diagnosis> {
    o.validate()?;
    let t0 = std::time::Instant::now();
    let errors = data.errors_or_err()?;
    // the rows the candidates are scanned on (all, up to `scan_rows`), and
    // their fold partition
    let rows = ScanRows::spread(data.len(), o.scan_rows);
    let scan_fold = kfold_partition(rows.len(), o.folds, o.seed)?;
    DiagnosePlan::new(data, o).check(
        |n| format!("a subset, e.g. `Dataset::select` of {n} rows"),
        |n| format!("`DiagnoseOptions::scan_rows({n})`"),
    )?;
    // a whole campaign: every fit converges ξ on the same seeded subset
    let o = &o.for_rows(data.len());
    let scan_errors: std::borrow::Cow<[[f64; 3]]> = if rows.is_all() {
        errors.into()
    } else {
        progress(&format!(
            "scanning the candidates on {} of the {} rows, evenly spread (one in {:.1})",
            rows.len(),
            data.len(),
            data.len() as f64 / rows.len() as f64
        ));
        rows.pick(errors).into()
    };
    let campaign = rounds::Campaign {
        data,
        errors,
        rows: &rows,
        fold: &scan_fold,
        scan_errors: &scan_errors,
        o,
    };
    progress("cross-validating the current model");
    let (before, model) = cross_validated(data, &[], o, None)?;
    let mut state = rounds::Rounds::new(model, before, o.permutations);
    for round in 1..=o.max_effects + 1 {
        if !state.round(&campaign, round, progress)? {
            break;
        }
    }
    Ok(state.into_diagnosis(o, data, &rows, t0.elapsed().as_secs_f64()))
}

#[cfg(test)]
mod tests {
    use super::*;
    use scan::{Family, GridPoint, Tested};

    fn family(label: &str, columns: Vec<Vec<f64>>, add: Vec<Feature>) -> Family {
        Family {
            kind: EffectKind::Covariate,
            source: vec!["t".into()],
            label: label.into(),
            grid: vec![GridPoint {
                params: BTreeMap::new(),
                columns,
                add,
            }],
            zoom: None,
        }
    }

    fn tested(family: usize, score: f64) -> Tested {
        Tested {
            family,
            best: 0,
            explained: score,
            p_value: 0.001,
            q_value: 0.01,
            score,
            resamples: 999,
            refit: false,
            cv_sse_before: 1.0,
            evidence: score,
            support: Vec::new(),
            refined: None,
        }
    }

    /// Occam's rule: of two significant candidates that explain the same
    /// residual, the one with fewer model columns goes first; one that
    /// explains something else, or is not significant, does not.
    #[test]
    fn a_simpler_candidate_that_explains_the_same_is_ranked_first() {
        let m = 40;
        let t: Vec<f64> = (0..m).map(|i| i as f64 / m as f64).collect();
        let wiggle: Vec<f64> = (0..m).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        let resid: Vec<[f64; 3]> = t.iter().map(|v| [*v, -*v, 0.5 * v]).collect();
        let cov = |name: &str| Feature::Covariate {
            name: name.into(),
            reference: None,
        };
        let fams = vec![
            // three columns (the drift among them) against one
            family(
                "t × joint angles",
                vec![t.clone(), t.iter().map(|v| v * v).collect(), wiggle.clone()],
                vec![cov("a"), cov("b"), cov("c")],
            ),
            family("t (alone)", vec![t.clone()], vec![cov("t")]),
            family("something else", vec![wiggle], vec![cov("w")]),
        ];
        let all = |_: &Tested| true;
        let mut order = vec![tested(0, 0.90), tested(1, 0.85)];
        let moved = prefer_simpler(&mut order, &fams, &resid, &all);
        assert_eq!(moved, Some((0, "t × joint angles".to_string())));
        assert_eq!(order[0].family, 1);
        // not significant: it stays where it is
        let mut order = vec![tested(0, 0.90), tested(1, 0.85)];
        let only_first = |x: &Tested| x.family == 0;
        assert_eq!(prefer_simpler(&mut order, &fams, &resid, &only_first), None);
        assert_eq!(order[0].family, 0);
        // fewer columns, but it explains another part of the residual
        let mut order = vec![tested(0, 0.90), tested(2, 0.85)];
        assert_eq!(prefer_simpler(&mut order, &fams, &resid, &all), None);
        // too weak a score to stand in for the first
        let mut order = vec![tested(0, 0.90), tested(1, 0.50)];
        assert_eq!(prefer_simpler(&mut order, &fams, &resid, &all), None);
    }
}
