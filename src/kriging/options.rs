//! What a fit is asked to do (`KrigingOptions`: trend kind, correlation
//! choice, optimiser, nugget, box, seed) and what it reports (`FitReport`).

use super::{CorrChoice, Correlation, FAMILY_FOLDS, FamilyScore, Monomials, Trend};
use crate::cancel::Cancel;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Built-in trends.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "lowercase")]
pub enum TrendKind {
    /// `[1]`: an unknown constant mean (ordinary Kriging).
    #[cfg_attr(
        feature = "cli",
        value(help = "An unknown constant mean (ordinary Kriging)")
    )]
    Constant,
    /// `[1, s1, …, sd]`: constant plus every input.
    #[cfg_attr(feature = "cli", value(help = "Constant plus every input"))]
    Linear,
    /// Every monomial of degree ≤ 2: `(d+1)(d+2)/2` terms.
    #[cfg_attr(feature = "cli", value(help = "Every monomial of degree ≤ 2"))]
    Quadratic,
}

impl TrendKind {
    /// This trend in `dim` variables, as a [`Trend`].
    pub fn trend(self, dim: usize) -> Trend {
        self.monomials(dim).into()
    }

    /// The monomials of this trend in `dim` variables.
    pub fn monomials(self, dim: usize) -> Monomials {
        match self {
            TrendKind::Constant => Monomials::constant(dim),
            TrendKind::Linear => Monomials::linear(dim),
            TrendKind::Quadratic => Monomials::quadratic(dim),
        }
    }
}

/// Hyperparameter optimiser.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
#[serde(rename_all = "kebab-case")]
pub enum OptimizerKind {
    /// Projected BFGS with the analytic gradient of ln ψ
    /// ([`super::KrigingProblem::psi_grad`], `optim::quasi_newton`) from the box
    /// centre and LHS starts (the default).
    #[cfg_attr(
        feature = "cli",
        value(help = "Projected BFGS on the analytic likelihood gradient, 8 starts (default)")
    )]
    Bfgs,
    /// Generalised pattern search from several LHS starts (seed 003 §III.B).
    #[cfg_attr(
        feature = "cli",
        value(help = "Generalised pattern search from several LHS starts")
    )]
    Gps,
    /// Hooke–Jeeves from the box centre (the JS&HJ / EJS&HJ baseline).
    #[cfg_attr(
        feature = "cli",
        value(name = "hj", help = "Hooke–Jeeves from the centre of the box")
    )]
    HookeJeeves,
}

impl OptimizerKind {
    /// Starting points when none are given: 8 for BFGS, the papers' 4 for
    /// GPS (Hooke–Jeeves runs from the box centre only).
    pub const fn default_starts(self) -> usize {
        match self {
            OptimizerKind::Bfgs => 8,
            OptimizerKind::Gps | OptimizerKind::HookeJeeves => 4,
        }
    }
}

/// Fitting options. `Default`: constant trend, Gaussian correlation, a
/// nugget estimated (tracker data is noisy), projected BFGS on
/// the analytic gradient from 8 starts. [`KrigingOptions::recommended`]
/// adds the family choice by CV (the `recommended` method, the CLI's
/// default); the papers' set-ups are interpolating and name GPS or
/// Hooke–Jeeves explicitly (`Method` in the `methods` module).
///
/// The fields are private: set them with the builder methods named after
/// them, read them with `get_` and the name (clap's convention), and check
/// the whole with [`KrigingOptions::validate`] (every fit does):
///
/// ```
/// use robokrige::kriging::{KrigingOptions, OptimizerKind};
/// let o = KrigingOptions::default()
///     .optimizer(OptimizerKind::Gps)
///     .starts(4)
///     .nugget(false);
/// assert_eq!(o.get_starts(), 4);
/// o.validate()?;
/// # Ok::<(), robokrige::Error>(())
/// ```
///
/// The joints entered as (sin θ, cos θ) are not an option of the Kriging
/// core but of the inputs (`params::ErrorModelParams::periodic`,
/// `inputs::InputMap`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(from = "OptionsRecord", into = "OptionsRecord")]
pub struct KrigingOptions {
    /// Trend `F β` in the normalised inputs (constant by default).
    pub(crate) trend: TrendKind,
    /// The correlation family, or how it is chosen (Gaussian, eq 8, by
    /// default).
    pub(crate) corr: CorrChoice,
    /// How the hyperparameters are searched (BFGS by default).
    pub(crate) optimizer: OptimizerKind,
    /// Estimate a nugget ν (noise-to-signal variance ratio) with ξ.
    pub(crate) nugget: bool,
    /// Box for `log10 ξ_k`.
    pub(crate) log10_theta: (f64, f64),
    /// Box for `log10 ν` when the nugget is estimated.
    pub(crate) log10_nugget: (f64, f64),
    /// Starting points (the centre plus LHS points): of the whole box for
    /// GPS (the papers' set-up uses 4), of an inner start box for BFGS.
    pub(crate) starts: usize,
    /// Seed of the LHS starts.
    pub(crate) seed: u64,
    /// Objective evaluations per start.
    pub(crate) max_evals: usize,
    /// GPS mesh tolerance, in log10 units (Hooke–Jeeves, the cheap baseline,
    /// stops at its own coarser step, `HjOptions::default().tol`).
    pub(crate) tol: f64,
    /// Smallest diagonal jitter ε tried (`None`: DACE's `(10 + m)·eps`).
    pub(crate) min_jitter: Option<f64>,
    /// Finish GPS with a finite-difference BFGS polish of the winning start
    /// (ψ to gradient-method precision; ~30 % more evaluations).
    pub(crate) polish: bool,
    /// Rows ξ is converged on by the default optimiser: a campaign with
    /// more converges on a seeded subset of this many (its multistart on at
    /// most as many), then solves once on all rows at that ξ
    /// ([`super::converge_subset`]). [`super::REFINE_ROWS`] by default;
    /// lower it to trade a little likelihood for speed on whole campaigns
    /// (`diagnose` does, above its `refit_rows`). GPS and Hooke–Jeeves
    /// search on all rows.
    #[serde(default = "default_converge_rows")]
    pub(crate) converge_rows: usize,
    /// Stops the fit between likelihood evaluations when cancelled
    /// ([`crate::cancel`]); never saved, not part of equality, and not kept
    /// by a fitted model.
    pub(crate) cancel: Cancel,
}

/// Smallest [`KrigingOptions::converge_rows`].
pub const MIN_CONVERGE_ROWS: usize = 50;

impl Default for KrigingOptions {
    fn default() -> Self {
        KrigingOptions {
            trend: TrendKind::Constant,
            corr: CorrChoice::Fixed(Correlation::Gaussian),
            optimizer: OptimizerKind::Bfgs,
            nugget: true,
            log10_theta: (-6.0, 2.0),
            log10_nugget: (-8.0, -0.5),
            starts: OptimizerKind::Bfgs.default_starts(),
            seed: 1,
            max_evals: 2_000,
            tol: 1e-2,
            min_jitter: None,
            polish: true,
            converge_rows: super::REFINE_ROWS,
            cancel: Cancel::never(),
        }
    }
}

fn default_converge_rows() -> usize {
    super::REFINE_ROWS
}

impl KrigingOptions {
    /// The engine's best model for noisy tracker data: the defaults (a
    /// nugget, BFGS) with each output's correlation family chosen by
    /// closed-form K-fold CV ([`CorrChoice::ByCv`]).
    pub fn recommended() -> Self {
        KrigingOptions {
            corr: CorrChoice::AUTO,
            ..KrigingOptions::default()
        }
    }

    /// Check ranges once, before fitting.
    pub fn validate(&self) -> Result<()> {
        let ok_box = |(a, b): (f64, f64)| a.is_finite() && b.is_finite() && a < b;
        if !ok_box(self.log10_theta) || !ok_box(self.log10_nugget) {
            return Err(Error::InvalidParameter(
                "log10 bounds must be finite with lo < hi".into(),
            ));
        }
        if self.min_jitter.is_some_and(|j| !(j > 0.0 && j < 1e-6)) {
            return Err(Error::InvalidParameter(
                "min_jitter must be in (0, 1e-6)".into(),
            ));
        }
        if self.starts == 0 || self.max_evals == 0 || self.tol.is_nan() || self.tol <= 0.0 {
            return Err(Error::InvalidParameter(
                "starts, max_evals and tol must be positive".into(),
            ));
        }
        if self.converge_rows < MIN_CONVERGE_ROWS {
            return Err(Error::InvalidParameter(format!(
                "converge_rows is {}: ξ needs at least {MIN_CONVERGE_ROWS} rows to converge on",
                self.converge_rows
            )));
        }
        if let CorrChoice::ByCv { folds } = self.corr
            && folds < 2
        {
            return Err(Error::InvalidParameter(format!(
                "choosing the correlation family by CV needs at least 2 folds, not {folds}"
            )));
        }
        Ok(())
    }
}

/// Builder setters, one per field, named after it.
impl KrigingOptions {
    /// The trend `F β` in the normalised inputs: constant `[1]`, linear
    /// `[1, s_1, …, s_d]` or every monomial of degree ≤ 2.
    pub fn trend(mut self, kind: TrendKind) -> Self {
        self.trend = kind;
        self
    }

    /// The correlation family `R_ij = k(h_ij)`, `h_ij² = Σ_k ξ_k (s_ik − s_jk)²`,
    /// fixed (Gaussian `exp(−h²)`, seed 003 eq 8, by default) or chosen per
    /// output by closed-form K-fold CV ([`CorrChoice::ByCv`]). A
    /// [`Correlation`] converts into a fixed choice.
    pub fn corr(mut self, choice: impl Into<CorrChoice>) -> Self {
        self.corr = choice.into();
        self
    }

    /// How ξ (and ν) are searched: BFGS on the analytic gradient of ln ψ,
    /// GPS or Hooke–Jeeves. The number of starts is not changed: set
    /// [`KrigingOptions::starts`] to [`OptimizerKind::default_starts`] when
    /// switching.
    pub fn optimizer(mut self, kind: OptimizerKind) -> Self {
        self.optimizer = kind;
        self
    }

    /// Estimate a nugget ν with ξ: the correlation matrix becomes
    /// `R + ν I` (ν = noise-to-signal variance ratio), so the model smooths
    /// instead of interpolating. `false`: interpolate, as the papers.
    pub fn nugget(mut self, on: bool) -> Self {
        self.nugget = on;
        self
    }

    /// The search box `(lo, hi)` of every `log10 ξ_k` (finite, lo < hi;
    /// `(−6, 2)` by default).
    pub fn log10_theta(mut self, bounds: (f64, f64)) -> Self {
        self.log10_theta = bounds;
        self
    }

    /// The search box `(lo, hi)` of `log10 ν` when the nugget is estimated
    /// (finite, lo < hi; `(−8, −0.5)` by default).
    pub fn log10_nugget(mut self, bounds: (f64, f64)) -> Self {
        self.log10_nugget = bounds;
        self
    }

    /// Starting points (the box centre plus LHS points, ≥ 1): of the whole
    /// box for GPS, of an inner start box for BFGS.
    pub fn starts(mut self, n: usize) -> Self {
        self.starts = n;
        self
    }

    /// Seed of the LHS starts (and of the subset ξ converges on).
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// Objective evaluations per start (≥ 1).
    pub fn max_evals(mut self, n: usize) -> Self {
        self.max_evals = n;
        self
    }

    /// GPS mesh tolerance in log10 units (> 0).
    pub fn tol(mut self, tol: f64) -> Self {
        self.tol = tol;
        self
    }

    /// Smallest diagonal jitter ε tried when `R` does not factorise, in
    /// (0, 1e-6); `None`: DACE's `(10 + m)·eps`.
    pub fn min_jitter(mut self, jitter: Option<f64>) -> Self {
        self.min_jitter = jitter;
        self
    }

    /// Finish GPS with a finite-difference BFGS polish of the winning start
    /// (ψ to gradient-method precision; ~30 % more evaluations).
    pub fn polish(mut self, on: bool) -> Self {
        self.polish = on;
        self
    }

    /// Rows ξ is converged on by the default optimiser (≥
    /// [`MIN_CONVERGE_ROWS`]): a campaign with more converges on a seeded
    /// subset of this many, then solves once on all rows at that ξ
    /// ([`super::converge_subset`]; [`super::REFINE_ROWS`] by default).
    pub fn converge_rows(mut self, rows: usize) -> Self {
        self.converge_rows = rows;
        self
    }

    /// The token that stops the fit: once it is cancelled, every further
    /// likelihood evaluation returns at once and the fit ends with
    /// [`Error::Interrupted`]. [`Cancel::never`] by default; a fitted
    /// model keeps no token (its options have the default).
    pub fn cancel(mut self, token: Cancel) -> Self {
        self.cancel = token;
        self
    }
}

/// Getters, one per field: `get_` and its name.
impl KrigingOptions {
    /// [`KrigingOptions::trend`]'s value.
    pub fn get_trend(&self) -> TrendKind {
        self.trend
    }

    /// [`KrigingOptions::corr`]'s value.
    pub fn get_corr(&self) -> CorrChoice {
        self.corr
    }

    /// [`KrigingOptions::optimizer`]'s value.
    pub fn get_optimizer(&self) -> OptimizerKind {
        self.optimizer
    }

    /// [`KrigingOptions::nugget`]'s value.
    pub fn get_nugget(&self) -> bool {
        self.nugget
    }

    /// [`KrigingOptions::log10_theta`]'s value.
    pub fn get_log10_theta(&self) -> (f64, f64) {
        self.log10_theta
    }

    /// [`KrigingOptions::log10_nugget`]'s value.
    pub fn get_log10_nugget(&self) -> (f64, f64) {
        self.log10_nugget
    }

    /// [`KrigingOptions::starts`]'s value.
    pub fn get_starts(&self) -> usize {
        self.starts
    }

    /// [`KrigingOptions::seed`]'s value.
    pub fn get_seed(&self) -> u64 {
        self.seed
    }

    /// [`KrigingOptions::max_evals`]'s value.
    pub fn get_max_evals(&self) -> usize {
        self.max_evals
    }

    /// [`KrigingOptions::tol`]'s value.
    pub fn get_tol(&self) -> f64 {
        self.tol
    }

    /// [`KrigingOptions::min_jitter`]'s value.
    pub fn get_min_jitter(&self) -> Option<f64> {
        self.min_jitter
    }

    /// [`KrigingOptions::polish`]'s value.
    pub fn get_polish(&self) -> bool {
        self.polish
    }

    /// [`KrigingOptions::converge_rows`]'s value.
    pub fn get_converge_rows(&self) -> usize {
        self.converge_rows
    }

    /// [`KrigingOptions::cancel`]'s value.
    pub fn get_cancel(&self) -> &Cancel {
        &self.cancel
    }
}

/// How one output's fit went. Equality ignores the wall time.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitReport {
    /// ξ at the optimum, one per input column (0 for trend-only inputs).
    pub theta: Vec<f64>,
    /// Nugget ν at the optimum (0 when not estimated).
    pub nugget: f64,
    /// ln ψ at the optimum (eq 14); `f64::MIN` when it is −∞ ([`super::storable_ln_psi`]).
    pub ln_psi: f64,
    /// Process variance σ² of the normalised response (eq 13).
    pub sigma2: f64,
    /// Diagonal jitter ε that made R factorisable.
    pub jitter: f64,
    /// Trend terms used, by name.
    pub trend_terms: Vec<String>,
    /// Trend terms dropped as linearly dependent on the training rows.
    pub dropped_terms: Vec<String>,
    /// Optimiser of the hyperparameter search.
    pub optimizer: OptimizerKind,
    /// Starting points the search ran from (0 when nothing was searched).
    pub starts: usize,
    /// Objective evaluations of the whole search, summed over all starts (0
    /// when nothing was searched).
    pub evals: usize,
    /// Rows the hyperparameters were converged on: all of them (m), or a
    /// subset on campaigns over [`super::REFINE_ROWS`] rows (the model itself is
    /// solved on all rows); 0 when nothing was searched.
    #[serde(default)]
    pub search_rows: usize,
    /// Wall time of the fit; not saved, so that a model file depends only on
    /// the data and the options (byte-identical for the same command).
    #[serde(skip)]
    pub seconds: f64,
    /// The BFGS inverse Hessian at the optimum (log10 units), for a warm
    /// start ([`super::Hyperparameters::of`]); not saved.
    #[serde(skip)]
    pub inverse_hessian: Option<Vec<Vec<f64>>>,
    /// With [`CorrChoice::ByCv`]: every family's closed-form K-fold score,
    /// the chosen one lowest.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub families: Vec<FamilyScore>,
}

impl PartialEq for FitReport {
    fn eq(&self, o: &Self) -> bool {
        self.theta == o.theta
            && self.nugget == o.nugget
            && self.ln_psi == o.ln_psi
            && self.sigma2 == o.sigma2
            && self.jitter == o.jitter
            && self.trend_terms == o.trend_terms
            && self.dropped_terms == o.dropped_terms
            && self.optimizer == o.optimizer
            && self.starts == o.starts
            && self.evals == o.evals
            && self.search_rows == o.search_rows
            && self.families == o.families
    }
}

/// [`KrigingOptions`] as model files store them (the layout of every
/// version): the family choice as `corr` + `corr_auto` (+ `corr_folds`
/// when not [`FAMILY_FOLDS`]).
#[derive(Serialize, Deserialize)]
struct OptionsRecord {
    trend: TrendKind,
    #[serde(default)]
    corr: Correlation,
    #[serde(default)]
    corr_auto: bool,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    corr_folds: Option<usize>,
    optimizer: OptimizerKind,
    nugget: bool,
    log10_theta: (f64, f64),
    log10_nugget: (f64, f64),
    starts: usize,
    seed: u64,
    max_evals: usize,
    tol: f64,
    min_jitter: Option<f64>,
    polish: bool,
    #[serde(default = "default_converge_rows")]
    converge_rows: usize,
}

impl From<OptionsRecord> for KrigingOptions {
    fn from(r: OptionsRecord) -> Self {
        KrigingOptions {
            trend: r.trend,
            corr: if r.corr_auto {
                CorrChoice::ByCv {
                    folds: r.corr_folds.unwrap_or(FAMILY_FOLDS),
                }
            } else {
                CorrChoice::Fixed(r.corr)
            },
            optimizer: r.optimizer,
            nugget: r.nugget,
            log10_theta: r.log10_theta,
            log10_nugget: r.log10_nugget,
            starts: r.starts,
            seed: r.seed,
            max_evals: r.max_evals,
            tol: r.tol,
            min_jitter: r.min_jitter,
            polish: r.polish,
            converge_rows: r.converge_rows,
            cancel: Cancel::never(),
        }
    }
}

impl From<KrigingOptions> for OptionsRecord {
    fn from(o: KrigingOptions) -> Self {
        let (corr, corr_auto, corr_folds) = match o.corr {
            CorrChoice::Fixed(c) => (c, false, None),
            CorrChoice::ByCv { folds } => (
                Correlation::Gaussian,
                true,
                (folds != FAMILY_FOLDS).then_some(folds),
            ),
        };
        OptionsRecord {
            trend: o.trend,
            corr,
            corr_auto,
            corr_folds,
            optimizer: o.optimizer,
            nugget: o.nugget,
            log10_theta: o.log10_theta,
            log10_nugget: o.log10_nugget,
            starts: o.starts,
            seed: o.seed,
            max_evals: o.max_evals,
            tol: o.tol,
            min_jitter: o.min_jitter,
            polish: o.polish,
            converge_rows: o.converge_rows,
        }
    }
}
