//! The options of a diagnosis ([`DiagnoseOptions`]: builder setters named
//! after its fields, `get_*` getters, `validate`), their defaults and
//! limits, and the least number of sign-flip resamples a round of F
//! candidates needs ([`min_resamples`]: a p-value is at least
//! `1/(1 + resamples)`, so one real effect among F reaches `q ≤ fdr` only
//! when `F/(1 + resamples) ≤ fdr`).

use crate::kriging::KrigingOptions;
use crate::params::ErrorModelParams;
use crate::space::Space;
use crate::{Error, Result};

/// Options of [`diagnose`](super::diagnose); `Default` is EJS with the default optimiser
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
    /// or its worth at the noise floor ([`Worth`](super::Worth)): a candidate is
    /// *significant* when its q-value is within `fdr` and its closed-form CV
    /// drop is worth this (a detectable but negligible effect is ranked,
    /// with a note, not flagged), and it is *kept* when the refit CV
    /// confirms the drop. A candidate whose statistic comes from
    /// re-estimated ξ stays significant only if that confirmation succeeds.
    pub(crate) min_gain: f64,
    /// The measured robot: enables the joint cross-talk candidates (Jacobian).
    pub(crate) robot: Option<crate::kinematics::Robot>,
    /// Candidates (largest statistic first) tested again at the ξ the model
    /// would choose with them ([`gls::refit_systems`](super::gls::refit_systems)).
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
    /// was used ([`Diagnosis::cv_mode`](super::Diagnosis::cv_mode)).
    pub(crate) refit_rows: usize,
    /// Most rows the candidate test scans ([`ScanRows`](super::ScanRows)): above it, the
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
    /// The default options on the base model `method`
    /// ([`base_params`](super::base_params): ejs, js, or a paper's method,
    /// with a nugget if `nugget`), `seed` seeding its fit, the folds and
    /// the resamples: the set-up of `robokrige diagnose`.
    pub fn of_method(method: &str, seed: u64, nugget: bool) -> Result<Self> {
        let base = super::base_params(method, seed, nugget)?;
        Ok(DiagnoseOptions::default().base(&base).seed(seed))
    }

    /// The options as [`diagnose`](super::diagnose) runs them on a campaign of `rows` rows:
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

    pub(super) fn validate(&self) -> Result<()> {
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
    /// The space and Kriging options of a base model ([`base_params`](super::base_params)).
    pub fn base(self, params: &ErrorModelParams) -> Self {
        self.space(params.get_space())
            .kriging(params.get_kriging().clone())
    }
    /// The token that stops the diagnosis ([`crate::cancel`]; the Kriging
    /// options' token, so set it after [`DiagnoseOptions::base`] or
    /// [`DiagnoseOptions::kriging`]): read by every fit, between rounds,
    /// re-estimations and batches of resamples. A cancelled diagnosis
    /// returns [`Error::Interrupted`].
    pub fn cancel(mut self, token: crate::cancel::Cancel) -> Self {
        self.kriging.cancel = token;
        self
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
    /// or its worth at the noise floor ([`Worth`](super::Worth)): a candidate is
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
    /// would choose with them ([`gls::refit_systems`](super::gls::refit_systems)).
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
    /// was used ([`Diagnosis::cv_mode`](super::Diagnosis::cv_mode)).
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
    /// scanned ([`Diagnosis::scanned_rows`](super::Diagnosis::scanned_rows)).
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
