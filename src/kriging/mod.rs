//! Universal Kriging (seed 003 eqs 6–14; seed 004 eqs 6–14; DACE).
//!
//! - [`trend`]: trend models `f(s)` ([`TrendModel`], [`Monomials`]).
//! - [`corr`]: correlation models ([`CorrelationModel`], [`Gaussian`], eq 8).
//! - [`problem`]: ψ(ξ) and the solve at fixed ξ — the whole algorithm on a page.
//! - [`model`]: the fitted predictor and its MSE (eqs 10, 12).
//!
//! [`fit_output`] fits one output: drop linearly dependent trend columns,
//! minimise ln ψ over `log10 ξ` (and `log10 ν` with an estimated nugget) with
//! Hooke–Jeeves or multistart GPS, then solve at the optimum.

pub mod corr;
mod family;
mod fastexp;
mod fused;
pub mod model;
pub mod problem;
pub mod trend;

pub use corr::{Correlation, CorrelationModel, Gaussian, TrainingInputs};
pub use family::{FAMILY_FOLDS, FamilyScore, fit_output_auto};
pub use fused::FusedBasis;
pub use model::{KrigingModel, KrigingModelData, Pred};
pub use problem::{KrigingProblem, PsiValue, Solution, Workspace, storable_ln_psi};
pub use trend::{
    KinematicTrend, Monomials, Trend, TrendModel, independent_columns, support, supported_columns,
    trend_matrix,
};

use crate::optim::{self, Bounds, GpsOptions, HjOptions, OptimResult};
use crate::space::Normalizer;
use crate::{Error, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::time::Instant;

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
    /// ([`KrigingProblem::psi_grad`], [`optim::quasi_newton`]) from the box
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

/// Fitting options (plain data). `Default`: constant trend, Gaussian
/// correlation, a nugget estimated (tracker data is noisy: issue 17),
/// projected BFGS on the analytic gradient from 8 starts.
/// [`KrigingOptions::recommended`] adds the family choice by CV (the
/// `recommended` method, the CLI's default); the papers' set-ups are
/// interpolating and name GPS or Hooke–Jeeves explicitly
/// (`Method` in the `methods` module).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KrigingOptions {
    /// Trend `F β` in the normalised inputs (constant by default).
    pub trend: TrendKind,
    /// Correlation family ([`Correlation`]; Gaussian, eq 8, by default).
    #[serde(default)]
    pub corr: Correlation,
    /// Choose the family per output by closed-form K-fold CV
    /// ([`fit_output_auto`]); `corr` is then ignored.
    #[serde(default)]
    pub corr_auto: bool,
    /// How the hyperparameters are searched (BFGS by default).
    pub optimizer: OptimizerKind,
    /// Estimate a nugget ν (noise-to-signal variance ratio) with ξ.
    pub nugget: bool,
    /// Box for `log10 ξ_k`.
    pub log10_theta: (f64, f64),
    /// Box for `log10 ν` when the nugget is estimated.
    pub log10_nugget: (f64, f64),
    /// Starting points (the centre plus LHS points): of the whole box for
    /// GPS (the papers' set-up uses 4), of an inner start box for BFGS.
    pub starts: usize,
    /// Seed of the LHS starts.
    pub seed: u64,
    /// Objective evaluations per start.
    pub max_evals: usize,
    /// GPS mesh tolerance, in log10 units (Hooke–Jeeves, the cheap baseline,
    /// stops at its own coarser step, `HjOptions::default().tol`).
    pub tol: f64,
    /// Smallest diagonal jitter ε tried (`None`: DACE's `(10 + m)·eps`).
    pub min_jitter: Option<f64>,
    /// Finish GPS with a finite-difference BFGS polish of the winning start
    /// (ψ to gradient-method precision; ~30 % more evaluations).
    pub polish: bool,
    /// Joints (0-based) entered as `(sin θ, cos θ)` instead of θ
    /// ([`crate::space::Space::encode`]); empty = none.
    #[serde(default)]
    pub periodic: Vec<usize>,
    /// Warm starts, one per output (empty: none): each output's search is a
    /// local one from its `(ξ, ν)` instead of the multistart (egobox's
    /// `theta_init`). For refits on data close to a fitted model's — CV
    /// folds, one more trend term — where the multistart would find the same
    /// basin at several times the cost. Not saved with a model.
    #[serde(skip)]
    pub warm_start: Vec<WarmStart>,
}

/// A starting point of the hyperparameter search ([`KrigingOptions::warm_start`]):
/// ξ (one per correlation input) and the nugget ν (ignored without one).
#[derive(Debug, Clone, PartialEq)]
pub struct WarmStart {
    /// ξ, one per correlation input (≥ 0).
    pub theta: Vec<f64>,
    /// Nugget ν (≥ 0; ignored when the nugget is not estimated).
    pub nugget: f64,
    /// The BFGS inverse Hessian there (in log10 ξ, log10 ν), if known: the
    /// local search then starts with the curvature it ended with (used only
    /// when its size matches the search).
    pub inverse_hessian: Option<Vec<Vec<f64>>>,
}

impl WarmStart {
    /// The hyperparameters a fit ended at, and its curvature.
    pub fn of(report: &FitReport, corr_dims: usize) -> Self {
        WarmStart {
            theta: report.theta[..corr_dims.min(report.theta.len())].to_vec(),
            nugget: report.nugget,
            inverse_hessian: report.inverse_hessian.clone(),
        }
    }
}

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
            periodic: Vec::new(),
            warm_start: Vec::new(),
        }
    }
}

impl KrigingOptions {
    /// The engine's best model for noisy tracker data: the defaults (a
    /// nugget, BFGS) with each output's correlation family chosen by
    /// closed-form K-fold CV ([`fit_output_auto`]).
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

/// How one output's fit went. Equality ignores the wall time.
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct FitReport {
    /// ξ at the optimum, one per input column (0 for trend-only inputs).
    pub theta: Vec<f64>,
    /// Nugget ν at the optimum (0 when not estimated).
    pub nugget: f64,
    /// ln ψ at the optimum (eq 14); `f64::MIN` when it is −∞ ([`storable_ln_psi`]).
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
    /// subset on campaigns over [`REFINE_ROWS`] rows (the model itself is
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
    /// K-fold score, the chosen one lowest ([`fit_output_auto`]).
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

/// One output's data prepared for fitting: dependent trend terms dropped,
/// response z-scored.
struct Prepared {
    trend: Trend,
    f: faer::Mat<f64>,
    y_norm: Vec<f64>,
    y_mean: f64,
    y_std: f64,
    trend_terms: Vec<String>,
    dropped_terms: Vec<String>,
}

fn prepare(x: &[Vec<f64>], y: &[f64], trend: &Trend, names: &[String]) -> Result<Prepared> {
    let m = x.len();
    if y.len() != m {
        return Err(Error::InvalidParameter(format!(
            "{} inputs but {} responses",
            m,
            y.len()
        )));
    }
    if y.iter().any(|v| !v.is_finite()) {
        return Err(Error::InvalidParameter(
            "response has non-finite values".into(),
        ));
    }
    let (kept, dropped) = independent_columns(&trend_matrix(trend, x), 1e-9);
    if kept.len() >= m {
        return Err(Error::InvalidParameter(format!(
            "{} independent trend terms need more than {m} rows",
            kept.len()
        )));
    }
    let trend_kept = trend.subset(&kept);
    // a constant response is represented exactly (mean = the value, y_norm = 0)
    let (y_mean, y_std) = if y.iter().all(|v| *v == y[0]) {
        (y[0], 1.0)
    } else {
        let yn = Normalizer::fit_column(y);
        (yn.mean[0], yn.std[0])
    };
    Ok(Prepared {
        f: trend_matrix(&trend_kept, x),
        y_norm: y.iter().map(|v| (v - y_mean) / y_std).collect(),
        y_mean,
        y_std,
        trend_terms: (0..trend_kept.len())
            .map(|j| trend_kept.term_name(j, names))
            .collect(),
        dropped_terms: dropped.iter().map(|&j| trend.term_name(j, names)).collect(),
        trend: trend_kept,
    })
}

/// Fit one output at a **given** ξ and nugget ν (no optimisation): normalised
/// inputs `x`, response `y` in original units, trend candidates `trend`;
/// `min_jitter` as in [`KrigingOptions`]. As in [`fit_output`], `inputs`
/// (and ξ) may cover only the first columns of `x`, the rest being
/// trend-only.
pub fn fit_output_at(
    x: &[Vec<f64>],
    inputs: &TrainingInputs,
    y: &[f64],
    trend: &Trend,
    theta: &[f64],
    nugget: f64,
    min_jitter: Option<f64>,
) -> Result<KrigingModel> {
    let at = Hyperparameters {
        corr: Correlation::Gaussian,
        theta,
        nugget,
        min_jitter,
    };
    fit_output_with(x, inputs, y, trend, &at)
}

/// Fixed hyperparameters of a fit: family, ξ, ν and the least jitter.
#[derive(Debug, Clone, Copy)]
pub struct Hyperparameters<'a> {
    /// Correlation family.
    pub corr: Correlation,
    /// ξ, one per correlation input.
    pub theta: &'a [f64],
    /// Nugget ν (0: interpolation).
    pub nugget: f64,
    /// Least jitter, as in [`KrigingOptions`].
    pub min_jitter: Option<f64>,
}

/// [`fit_output_at`] with any correlation family.
pub fn fit_output_with(
    x: &[Vec<f64>],
    inputs: &TrainingInputs,
    y: &[f64],
    trend: &Trend,
    at: &Hyperparameters,
) -> Result<KrigingModel> {
    let Hyperparameters {
        corr,
        theta,
        nugget,
        min_jitter,
    } = *at;
    let names: Vec<String> = (1..=theta.len()).map(|k| format!("s{k}")).collect();
    let p = prepare(x, y, trend, &names)?;
    if theta.len() != inputs.d
        || theta.iter().any(|t| !t.is_finite() || *t < 0.0)
        || nugget.is_nan()
        || nugget < 0.0
    {
        return Err(Error::InvalidParameter(
            "theta must be d finite values ≥ 0 and the nugget ≥ 0".into(),
        ));
    }
    let problem = KrigingProblem {
        min_jitter,
        corr: &corr,
        inputs,
        f: &p.f,
        y: &p.y_norm,
    };
    let sol = problem.solve(theta, nugget)?;
    let mut theta = theta.to_vec();
    theta.resize(x.first().map_or(theta.len(), Vec::len), 0.0);
    KrigingModel::from_solution(sol, p.trend, theta, nugget, x.to_vec(), p.y_mean, p.y_std)
        .map(|m| m.with_corr(corr))
}

/// Fit one output at normalised inputs `x` (m rows) on response `y` (original
/// units), with the trend candidates `trend` (dependent ones are dropped),
/// choosing ξ (and ν) by minimising ln ψ. `inputs` is `x` prepared for the
/// correlation fill; `names` name the inputs. `inputs` may hold only the
/// first columns of `x`: the others are *trend-only* inputs (a step or
/// harmonic regressor), with ξ = 0, so they enter `f(s)` but not `R`.
pub fn fit_output(
    x: &[Vec<f64>],
    inputs: &TrainingInputs,
    y: &[f64],
    trend: &Trend,
    names: &[String],
    opts: &KrigingOptions,
) -> Result<(KrigingModel, FitReport)> {
    fit_output_from(x, inputs, y, trend, names, opts, None)
}

/// [`fit_output`] with an optional warm start `(ξ, ν)`: a local search from
/// there instead of the multistart — BFGS on the analytic gradient with the
/// default optimiser (`converge_bfgs`), Hooke–Jeeves (initial step 0.25 in
/// log10 units) with the papers' — for re-estimating ξ after a small change
/// of the data or the model (a CV fold, one more trend term). `ν` is ignored
/// without a nugget; values are clamped into the box.
pub fn fit_output_from(
    x: &[Vec<f64>],
    inputs: &TrainingInputs,
    y: &[f64],
    trend: &Trend,
    names: &[String],
    opts: &KrigingOptions,
    start: Option<&WarmStart>,
) -> Result<(KrigingModel, FitReport)> {
    opts.validate()?;
    let t0 = Instant::now();
    let d = inputs.d;
    let p = prepare(x, y, trend, names)?;
    let problem = KrigingProblem {
        min_jitter: opts.min_jitter,
        corr: &opts.corr,
        inputs,
        f: &p.f,
        y: &p.y_norm,
    };
    let mut bounds = Bounds::uniform(d, opts.log10_theta.0, opts.log10_theta.1);
    if opts.nugget {
        bounds.lo.push(opts.log10_nugget.0);
        bounds.hi.push(opts.log10_nugget.1);
    }
    let unpack = |z: &[f64]| -> (Vec<f64>, f64) {
        let theta = z[..d].iter().map(|v| 10f64.powf(*v)).collect();
        let nugget = if opts.nugget { 10f64.powf(z[d]) } else { 0.0 };
        (theta, nugget)
    };
    // a constant response has nothing to learn: any ξ reproduces it exactly
    let constant_response = p.y_norm.iter().all(|v| *v == 0.0);
    let search = if constant_response {
        None
    } else {
        let search = match start {
            Some(w) => {
                if w.theta.len() != d {
                    return Err(Error::InvalidParameter(format!(
                        "warm start has {} correlation parameters, the inputs {d}",
                        w.theta.len()
                    )));
                }
                let mut z0: Vec<f64> = w.theta.iter().map(|t| t.max(1e-300).log10()).collect();
                if opts.nugget {
                    z0.push(w.nugget.max(1e-300).log10());
                }
                let z0: Vec<f64> = z0
                    .iter()
                    .zip(bounds.lo.iter().zip(&bounds.hi))
                    .map(|(z, (lo, hi))| z.clamp(*lo, *hi))
                    .collect();
                if opts.optimizer == OptimizerKind::Bfgs {
                    let hinv = w
                        .inverse_hessian
                        .clone()
                        .filter(|h| h.len() == z0.len() && h.iter().all(|r| r.len() == z0.len()));
                    converge_bfgs(&problem, &z0, hinv, &bounds, &unpack, opts)
                } else {
                    let obj = ln_psi_objective(&problem, &unpack);
                    let hj = HjOptions {
                        initial_step: 0.25,
                        max_evals: opts.max_evals,
                        ..HjOptions::default()
                    };
                    Search {
                        best: optim::hooke_jeeves(obj, &z0, &bounds, &hj),
                        starts: 1,
                        rows: p.y_norm.len(),
                        inverse_hessian: None,
                    }
                }
            }
            None => optimise(&problem, &bounds, &unpack, opts),
        };
        if !search.best.f.is_finite() {
            return Err(Error::Numerical(
                "no hyperparameter in the box gave a finite likelihood".into(),
            ));
        }
        Some(search)
    };
    let best_x = search
        .as_ref()
        .map_or_else(|| bounds.center(), |s| s.best.x.clone());
    let (mut theta, nugget) = unpack(&best_x);
    let sol = problem.solve(&theta, nugget)?;
    // trend-only inputs (beyond `inputs.d`) do not enter the correlation
    theta.resize(x.first().map_or(d, Vec::len), 0.0);
    let report = FitReport {
        theta: theta.clone(),
        nugget,
        ln_psi: storable_ln_psi(sol.value.ln_psi),
        sigma2: sol.value.sigma2,
        jitter: sol.value.jitter,
        trend_terms: p.trend_terms,
        dropped_terms: p.dropped_terms,
        optimizer: opts.optimizer,
        starts: search.as_ref().map_or(0, |s| s.starts),
        evals: search.as_ref().map_or(0, |s| s.best.evals),
        search_rows: search.as_ref().map_or(0, |s| s.rows),
        seconds: t0.elapsed().as_secs_f64(),
        inverse_hessian: search.and_then(|s| s.inverse_hessian),
        families: Vec::new(),
    };
    let model =
        KrigingModel::from_solution(sol, p.trend, theta, nugget, x.to_vec(), p.y_mean, p.y_std)?
            .with_corr(opts.corr);
    Ok((model, report))
}

/// Maps an optimiser point (log10 ξ, and log10 ν with a nugget) to (ξ, ν).
type Unpack<'a> = dyn Fn(&[f64]) -> (Vec<f64>, f64) + Sync + 'a;

/// `z ↦ ln ψ(unpack(z))` with its own workspace; +∞ where R cannot be
/// factorised or the likelihood is degenerate.
fn ln_psi_objective<'a>(
    problem: &'a KrigingProblem,
    unpack: &'a Unpack<'_>,
) -> impl FnMut(&[f64]) -> f64 + 'a {
    let mut ws = Workspace::new(problem.m(), problem.f.ncols());
    move |z: &[f64]| {
        let (theta, nugget) = unpack(z);
        problem
            .psi(&theta, nugget, &mut ws)
            .map_or(f64::INFINITY, |v| v.ln_psi)
    }
}

/// `z ↦ (ln ψ, ∇ ln ψ)` with its own workspace; +∞ where R cannot be
/// factorised or the likelihood is degenerate.
fn ln_psi_grad_objective<'a>(
    problem: &'a KrigingProblem,
    unpack: &'a Unpack<'_>,
) -> impl FnMut(&[f64], &mut [f64]) -> f64 + 'a {
    let mut ws = Workspace::new(problem.m(), problem.f.ncols());
    move |z: &[f64], g: &mut [f64]| {
        let (theta, nugget) = unpack(z);
        problem
            .psi_grad(&theta, nugget, &mut ws, g)
            .map_or(f64::INFINITY, |v| v.ln_psi)
    }
}

/// Box of the BFGS starting points in log10 ξ: correlation lengths from
/// ~0.3 to ~30 input standard deviations (the UR10 campaigns' best basins
/// have ξ of 4–13 on q1–q3). A start at large ξ sits on a plateau
/// (R ≈ I, the gradient vanishes) and a start at tiny ξ on the jitter
/// ladder; the search itself still ranges over the whole box.
const START_LOG10_THETA: (f64, f64) = (-3.0, 1.0);
/// The same for log10 ν.
const START_LOG10_NUGGET: (f64, f64) = (-5.0, -1.0);
/// BFGS iterations of the screening stage.
const SCREEN_ITER: usize = 8;
/// Starts that run to convergence after the successive halving (with the
/// default 8 starts: the better half after [`SCREEN_ITER`] iterations). Two
/// finalists missed the GPS basin on the UR10 kinematic-trend fits (ey
/// ln ψ −1.76 against −1.96).
const FINALISTS: usize = 4;

/// Campaigns up to this many rows search ξ on all of them.
pub const SEARCH_ROWS: usize = 1000;
/// Campaigns up to this many rows converge ξ on all of them; larger ones
/// converge on a subset of this size, then solve once on all rows.
pub const REFINE_ROWS: usize = 3000;

/// How a fit of m rows will run and what it will hold in memory, known
/// before anything is allocated.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct FitPlan {
    /// Training rows.
    pub rows: usize,
    /// Rows of the multistart stage (BFGS) or of the whole search (GPS, HJ).
    pub search_rows: usize,
    /// Rows ξ is converged on.
    pub refine_rows: usize,
    /// Outputs fitted one after another (each factorisation then uses all
    /// threads) instead of in parallel.
    pub sequential_outputs: bool,
    /// Estimated peak memory, bytes.
    pub bytes: u64,
}

impl FitPlan {
    /// The plan for `outputs` outputs of `rows` rows with `optimizer`, on
    /// `threads` threads: the largest of the search's workspaces (three
    /// m × m matrices per running start with the gradient), the final
    /// solve's factor per output running at once, plus the factors a fitted
    /// model keeps (up to m = 4096).
    pub fn new(rows: usize, outputs: usize, optimizer: OptimizerKind, threads: usize) -> Self {
        let sq = |m: usize| crate::memory::square_bytes(m);
        let (search_rows, refine_rows, per_ws) = match optimizer {
            OptimizerKind::Bfgs => (rows.min(SEARCH_ROWS), rows.min(REFINE_ROWS), 3),
            _ => (rows, rows, 2),
        };
        let sequential_outputs = rows > REFINE_ROWS;
        let running = threads.max(1) as u64;
        let search = running * per_ws * sq(search_rows).max(sq(refine_rows));
        let at_once = if sequential_outputs {
            1
        } else {
            outputs.min(threads.max(1)) as u64
        };
        let solve = at_once * sq(rows);
        let kept = if rows <= model::KEEP_FACTOR_MAX_M {
            outputs as u64 * sq(rows)
        } else {
            0
        };
        FitPlan {
            rows,
            search_rows,
            refine_rows,
            sequential_outputs,
            bytes: search.max(solve) + kept,
        }
    }

    /// The most rows whose plan fits in `bytes`.
    pub fn max_rows(bytes: u64, outputs: usize, optimizer: OptimizerKind, threads: usize) -> usize {
        let (mut lo, mut hi) = (1usize, 1usize << 20);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if Self::new(mid, outputs, optimizer, threads).bytes <= bytes {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    }
}

impl std::fmt::Display for FitPlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} rows, about {} of memory",
            self.rows,
            crate::memory::human(self.bytes)
        )?;
        if self.refine_rows < self.rows {
            write!(
                f,
                "; ξ searched on {} rows and converged on {}, then one solve on all {} rows",
                self.search_rows, self.refine_rows, self.rows
            )?;
        } else if self.search_rows < self.rows {
            write!(
                f,
                "; starts screened on {} rows, ξ converged on all rows",
                self.search_rows
            )?;
        }
        Ok(())
    }
}

/// The default search, sized to the campaign (issue 16 §2):
/// - m ≤ [`SEARCH_ROWS`]: [`multistart_bfgs`] on all rows;
/// - m ≤ [`REFINE_ROWS`]: the multistart on a seeded random subset of
///   [`SEARCH_ROWS`] rows finds the basin, then BFGS converges on **all**
///   rows from there: the result is a stationary point of the full
///   likelihood, at a few dozen full evaluations instead of hundreds;
/// - larger: the same with the convergence on a subset of [`REFINE_ROWS`]
///   rows; [`fit_output_from`] then solves once on all rows at that ξ.
fn optimise_bfgs(
    problem: &KrigingProblem,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> Search {
    let m = problem.m();
    if m <= SEARCH_ROWS {
        let (best, starts, hinv) = multistart_bfgs(problem, bounds, unpack, opts);
        return Search {
            best,
            starts,
            rows: m,
            inverse_hessian: Some(hinv),
        };
    }
    let sub = SubsetData::new(problem, &row_subset(m, SEARCH_ROWS, opts.seed));
    let (found, starts, hinv) = multistart_bfgs(&sub.problem(problem), bounds, unpack, opts);
    // the subset's curvature is a far better start than the identity (on
    // 2 773 UR10 rows: 40 full-data iterations instead of 67)
    let mut r = converge_bfgs(problem, &found.x, Some(hinv), bounds, unpack, opts);
    r.best.evals += found.evals;
    r.starts = starts;
    r
}

/// Tolerances of the convergence on all rows of a large campaign, where one
/// evaluation costs about a second at m = 2 773: iterations that gain less
/// than 1e-7 in ln ψ (ξ moving along a flat valley, the predictor
/// unchanged) stop it.
fn full_data_tolerance() -> optim::QuasiNewtonOptions {
    optim::QuasiNewtonOptions {
        gtol: 1e-4,
        ftol: 1e-7,
        ..optim::QuasiNewtonOptions::default()
    }
}

/// How a hyperparameter search went: the best point, the starts, the rows
/// of its last stage and, for BFGS, the inverse Hessian there.
struct Search {
    best: OptimResult,
    starts: usize,
    rows: usize,
    inverse_hessian: Option<Hessian>,
}

/// BFGS from `x0` (inverse Hessian `hinv`, or the identity) to convergence
/// on all rows, or on a seeded subset of [`REFINE_ROWS`] rows when there are
/// more (one start).
fn converge_bfgs(
    problem: &KrigingProblem,
    x0: &[f64],
    hinv: Option<Hessian>,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> Search {
    let m = problem.m();
    let full = optim::QuasiNewtonOptions {
        max_evals: opts.max_evals,
        ..if m > SEARCH_ROWS {
            full_data_tolerance()
        } else {
            optim::QuasiNewtonOptions::default()
        }
    };
    let refine_rows = m.min(REFINE_ROWS);
    let refine_sub = (refine_rows < m).then(|| {
        SubsetData::new(
            problem,
            &row_subset(m, refine_rows, opts.seed.wrapping_add(1)),
        )
    });
    let refine = refine_sub.as_ref().map(|s| s.problem(problem));
    let obj = ln_psi_grad_objective(refine.as_ref().unwrap_or(problem), unpack);
    let (best, h) = optim::quasi_newton_warm(obj, x0, hinv, bounds, &full);
    Search {
        best,
        starts: 1,
        rows: refine_rows,
        inverse_hessian: Some(h),
    }
}

/// A problem's data restricted to some rows.
struct SubsetData {
    inputs: TrainingInputs,
    f: faer::Mat<f64>,
    y: Vec<f64>,
}

impl SubsetData {
    fn new(problem: &KrigingProblem, rows: &[usize]) -> Self {
        SubsetData {
            inputs: problem.inputs.select(rows),
            f: faer::Mat::from_fn(rows.len(), problem.f.ncols(), |i, j| {
                problem.f[(rows[i], j)]
            }),
            y: rows.iter().map(|&i| problem.y[i]).collect(),
        }
    }

    /// The same problem on these rows.
    fn problem<'a>(&'a self, like: &KrigingProblem<'a>) -> KrigingProblem<'a> {
        KrigingProblem {
            min_jitter: like.min_jitter,
            corr: like.corr,
            inputs: &self.inputs,
            f: &self.f,
            y: &self.y,
        }
    }
}

/// `k` of `m` row indices, drawn without replacement from `seed`, sorted.
fn row_subset(m: usize, k: usize, seed: u64) -> Vec<usize> {
    use rand::SeedableRng;
    use rand::seq::SliceRandom;
    let mut idx: Vec<usize> = (0..m).collect();
    // a stream of its own: the seed mixed with a fixed odd constant
    let mut rng =
        rand::rngs::StdRng::seed_from_u64(seed.wrapping_mul(0x9e37_79b9_7f4a_7c15) ^ 0x5b57_e7a1);
    idx.shuffle(&mut rng);
    idx.truncate(k);
    idx.sort_unstable();
    idx
}

/// Projected BFGS on the analytic gradient from several starts (the centre
/// of the start box and LHS points in it, `opts.starts` in all), by
/// successive halving: every start runs [`SCREEN_ITER`] iterations in
/// parallel; the better half continues for twice as many, and so on until
/// [`FINALISTS`] remain, which run to convergence; the best wins (ties by
/// start order). Runs continue with their own inverse Hessian. The
/// likelihood is multimodal, and a ranking after a few iterations favours
/// the basin that explains everything as noise (the nugget at its bound):
/// on the UR10 hybrid residual, keeping the best quarter after 8 iterations
/// missed the basin GPS finds on 2 of 3 outputs (ln ψ −0.80 against −1.02
/// on ey); the better half, converged, finds it.
fn multistart_bfgs(
    problem: &KrigingProblem,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> (OptimResult, usize, Hessian) {
    let d = problem.inputs.d;
    let mut start_box = bounds.clone();
    for k in 0..bounds.dim() {
        let (lo, hi) = if k < d {
            START_LOG10_THETA
        } else {
            START_LOG10_NUGGET
        };
        start_box.lo[k] = lo.clamp(bounds.lo[k], bounds.hi[k]);
        start_box.hi[k] = hi.clamp(bounds.lo[k], bounds.hi[k]);
    }
    let starts = optim::lhs_starts(&start_box, opts.starts, opts.seed);
    let full_iter = optim::QuasiNewtonOptions::default().max_iter;
    // a pool of `n` runs stops after `iters` iterations, or converges once
    // only the finalists are left
    let limit = |n: usize, iters: usize| optim::QuasiNewtonOptions {
        max_iter: if n <= FINALISTS { full_iter } else { iters },
        max_evals: opts.max_evals,
        ..optim::QuasiNewtonOptions::default()
    };
    // (start index, from, inverse Hessian) → (start index, result, its
    // inverse Hessian): runs continue where they stopped
    let run = |pool: Vec<(usize, Vec<f64>, Option<Hessian>)>, o: optim::QuasiNewtonOptions| {
        pool.into_par_iter()
            .map(|(i, x, h)| {
                let obj = ln_psi_grad_objective(problem, unpack);
                let (r, h) = optim::quasi_newton_warm(obj, &x, h, bounds, &o);
                (i, r, h)
            })
            .collect::<Vec<(usize, OptimResult, Hessian)>>()
    };
    let mut iters = SCREEN_ITER;
    let mut pool = run(
        starts
            .iter()
            .enumerate()
            .map(|(i, x)| (i, x.clone(), None))
            .collect(),
        limit(starts.len(), iters),
    );
    let mut evals: usize = pool.iter().map(|p| p.1.evals).sum();
    while pool.len() > FINALISTS {
        // successive halving: the better half (start order breaks ties)
        // continues for twice as many iterations
        pool.sort_by(|a, b| a.1.f.total_cmp(&b.1.f).then(a.0.cmp(&b.0)));
        pool.truncate(pool.len().div_ceil(2));
        iters *= 2;
        let o = limit(pool.len(), iters);
        pool = run(
            pool.into_iter()
                .map(|(i, r, h)| (i, r.x, Some(h)))
                .collect(),
            o,
        );
        evals += pool.iter().map(|p| p.1.evals).sum::<usize>();
    }
    // the first of the best (start order breaks ties)
    pool.sort_by(|a, b| a.1.f.total_cmp(&b.1.f).then(a.0.cmp(&b.0)));
    let (_, mut best, hinv) = pool.into_iter().next().expect("at least one start");
    best.evals = evals;
    (best, starts.len(), hinv)
}

/// A BFGS inverse Hessian approximation.
type Hessian = Vec<Vec<f64>>;

/// Mesh size at which every GPS start stops before the first selection.
const SCREEN_MESH: f64 = 0.25;

/// Minimise ln ψ; returns the best result (evals summed over all runs) and the
/// number of starts.
///
/// GPS uses successive halving over its starts: every start runs (in
/// parallel) to a mesh of [`SCREEN_MESH`]; the better half continues to a mesh
/// four times finer, and so on until one remains, which is polished to
/// `opts.tol`. Losing starts stop early, and the choice between the last
/// candidates is made on nearly converged values. With `opts.polish` the
/// winner then gets finite-difference BFGS steps ([`optim::bfgs`]): ψ is
/// smooth there, and this reaches the last digits a pattern search would need
/// thousands of evaluations for (on the COMAU campaign ψ drops by another
/// ~1e-6 relative, to the precision of SMT's gradient-based optimiser).
fn optimise(
    problem: &KrigingProblem,
    bounds: &Bounds,
    unpack: &Unpack<'_>,
    opts: &KrigingOptions,
) -> Search {
    let m = problem.m();
    let done = |best: OptimResult, starts: usize| Search {
        best,
        starts,
        rows: m,
        inverse_hessian: None,
    };
    let run = |x0: &[f64], initial_mesh: f64, tol: f64| {
        let obj = ln_psi_objective(problem, unpack);
        match opts.optimizer {
            OptimizerKind::Gps => optim::gps(
                obj,
                x0,
                bounds,
                &GpsOptions {
                    initial_mesh,
                    mesh_tol: tol,
                    max_evals: opts.max_evals,
                    ..GpsOptions::default()
                },
            ),
            // Bfgs returned before `run` is used
            OptimizerKind::HookeJeeves | OptimizerKind::Bfgs => optim::hooke_jeeves(
                obj,
                x0,
                bounds,
                &HjOptions {
                    max_evals: opts.max_evals,
                    ..HjOptions::default()
                },
            ),
        }
    };
    match opts.optimizer {
        OptimizerKind::HookeJeeves => return done(run(&bounds.center(), 0.5, opts.tol), 1),
        OptimizerKind::Bfgs => return optimise_bfgs(problem, bounds, unpack, opts),
        OptimizerKind::Gps => {}
    }
    let starts = optim::lhs_starts(bounds, opts.starts, opts.seed);
    let mut mesh = SCREEN_MESH.max(opts.tol);
    let (_, mut pool) = optim::multistart(&starts, |x0| run(x0, 0.5, mesh));
    let mut evals: usize = pool.iter().map(|r| r.evals).sum();
    loop {
        // stable sort: ties keep start order, so the result is deterministic
        pool.sort_by(|a, b| a.f.total_cmp(&b.f));
        pool.truncate(pool.len().div_ceil(2));
        if pool.len() == 1 && mesh <= opts.tol {
            break;
        }
        let next = if pool.len() == 1 {
            opts.tol
        } else {
            (mesh / 4.0).max(opts.tol)
        };
        let (_, refined) = optim::multistart(
            &pool.iter().map(|r| r.x.clone()).collect::<Vec<_>>(),
            |x0| run(x0, mesh, next),
        );
        evals += refined.iter().map(|r| r.evals).sum::<usize>();
        // a refinement never returns a worse point than it started from
        pool = refined;
        mesh = next;
    }
    let mut best = pool.swap_remove(0);
    if !opts.polish {
        best.evals = evals;
        return done(best, starts.len());
    }
    let obj = ln_psi_objective(problem, unpack);
    let mut polished = optim::bfgs(obj, &best.x, bounds, &optim::BfgsOptions::default());
    polished.evals += evals;
    done(polished, starts.len())
}
