//! What a fit is asked to do (`KrigingOptions`: trend kind, correlation,
//! optimiser, nugget, box, seed, warm starts) and what it reports
//! (`FitReport`).

use super::{Correlation, FamilyScore, Monomials, Trend};
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
    /// centre and LHS starts (the default; issue 16).
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
/// nugget estimated (tracker data is noisy: issue 17), projected BFGS on
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
pub struct KrigingOptions {
    /// Trend `F β` in the normalised inputs (constant by default).
    pub(crate) trend: TrendKind,
    /// Correlation family ([`Correlation`]; Gaussian, eq 8, by default).
    #[serde(default)]
    pub(crate) corr: Correlation,
    /// Choose the family per output by closed-form K-fold CV
    /// ([`super::fit_output_auto`]); `corr` is then ignored.
    #[serde(default)]
    pub(crate) corr_auto: bool,
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
    /// Warm starts, one per output (empty: none): each output's search is a
    /// local one from its `(ξ, ν)` instead of the multistart (egobox's
    /// `theta_init`). For refits on data close to a fitted model's — CV
    /// folds, one more trend term — where the multistart would find the same
    /// basin at several times the cost. Not saved with a model.
    #[serde(skip)]
    pub(crate) warm_start: Vec<WarmStart>,
}

/// A starting point of the hyperparameter search ([`KrigingOptions::warm_start`]):
/// ξ (one per correlation input) and the nugget ν (ignored without one),
/// with the curvature there when a fit left it ([`WarmStart::of`]).
#[derive(Debug, Clone, PartialEq)]
pub struct WarmStart {
    /// ξ, one per correlation input (≥ 0).
    pub(crate) theta: Vec<f64>,
    /// Nugget ν (≥ 0; ignored when the nugget is not estimated).
    pub(crate) nugget: f64,
    /// The BFGS inverse Hessian there (in log10 ξ, log10 ν), if known: the
    /// local search then starts with the curvature it ended with (used only
    /// when its size matches the search).
    pub(crate) inverse_hessian: Option<Vec<Vec<f64>>>,
}

impl WarmStart {
    /// A start at ξ = `theta` (one per correlation input, ≥ 0) and nugget
    /// ν = `nugget` (≥ 0), without curvature: the local search begins with
    /// the identity as its inverse Hessian.
    pub fn new(theta: Vec<f64>, nugget: f64) -> Self {
        WarmStart {
            theta,
            nugget,
            inverse_hessian: None,
        }
    }

    /// ξ, one per correlation input.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// The nugget ν.
    pub fn nugget(&self) -> f64 {
        self.nugget
    }

    /// The BFGS inverse Hessian (log10 ξ, log10 ν) the search starts with, if known.
    pub fn inverse_hessian(&self) -> Option<&[Vec<f64>]> {
        self.inverse_hessian.as_deref()
    }

    /// The hyperparameters a fit ended at, and its curvature.
    pub fn of(report: &FitReport, corr_dims: usize) -> Self {
        WarmStart {
            theta: report.theta[..corr_dims.min(report.theta.len())].to_vec(),
            nugget: report.nugget,
            inverse_hessian: report.inverse_hessian.clone(),
        }
    }
}

/// Smallest [`KrigingOptions::converge_rows`].
pub const MIN_CONVERGE_ROWS: usize = 50;

impl Default for KrigingOptions {
    fn default() -> Self {
        KrigingOptions {
            trend: TrendKind::Constant,
            corr: Correlation::Gaussian,
            corr_auto: false,
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
            warm_start: Vec::new(),
        }
    }
}

fn default_converge_rows() -> usize {
    super::REFINE_ROWS
}

impl KrigingOptions {
    /// The engine's best model for noisy tracker data: the defaults (a
    /// nugget, BFGS) with each output's correlation family chosen by
    /// closed-form K-fold CV ([`super::fit_output_auto`]).
    pub fn recommended() -> Self {
        KrigingOptions {
            corr_auto: true,
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
        if self.warm_start.iter().any(|w| {
            w.theta.iter().any(|t| !t.is_finite() || *t < 0.0)
                || w.nugget.is_nan()
                || w.nugget < 0.0
        }) {
            return Err(Error::InvalidParameter(
                "warm starts need finite ξ ≥ 0 and a nugget ≥ 0".into(),
            ));
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

    /// The correlation family `R_ij = k(h_ij)`, `h_ij² = Σ_k ξ_k (s_ik − s_jk)²`
    /// (Gaussian `exp(−h²)`, seed 003 eq 8, by default; ignored with
    /// [`KrigingOptions::corr_auto`]).
    pub fn corr(mut self, family: Correlation) -> Self {
        self.corr = family;
        self
    }

    /// Choose each output's family by closed-form K-fold CV
    /// ([`super::fit_output_auto`]) instead of [`KrigingOptions::corr`].
    pub fn corr_auto(mut self, on: bool) -> Self {
        self.corr_auto = on;
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

    /// Warm starts, one per output (or none): each output's search is a
    /// local one from its `(ξ, ν)` instead of the multistart. For refits on
    /// data close to a fitted model's (`model::ErrorModel::warm_starts`).
    /// Not saved with a model.
    pub fn warm_start(mut self, starts: Vec<WarmStart>) -> Self {
        self.warm_start = starts;
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
    pub fn get_corr(&self) -> Correlation {
        self.corr
    }

    /// [`KrigingOptions::corr_auto`]'s value.
    pub fn get_corr_auto(&self) -> bool {
        self.corr_auto
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

    /// [`KrigingOptions::warm_start`]'s value.
    pub fn get_warm_start(&self) -> &[WarmStart] {
        &self.warm_start
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
    /// start ([`WarmStart::of`]); not saved.
    #[serde(skip)]
    pub inverse_hessian: Option<Vec<Vec<f64>>>,
    /// With [`KrigingOptions::corr_auto`]: every family's closed-form
    /// K-fold score, the chosen one lowest ([`super::fit_output_auto`]).
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
