//! Universal Kriging (seed 003 eqs 6–14; seed 004 eqs 6–14; DACE).
//!
//! - [`trend`]: trend models `f(s)` ([`TrendModel`], [`Monomials`]).
//! - [`corr`]: correlation models ([`CorrelationModel`], [`Gaussian`], eq 8).
//! - [`problem`]: ψ(ξ) and the solve at fixed ξ — the whole algorithm on a page.
//! - [`model`]: the fitted predictor and its MSE (eqs 10, 12).
//! - `options`: what a fit is asked ([`KrigingOptions`]) and reports ([`FitReport`]).
//! - `search`: the hyperparameter search sized to the campaign ([`FitPlan`]).
//!
//! [`fit_output`] fits one output: drop linearly dependent trend columns,
//! minimise ln ψ over `log10 ξ` (and `log10 ν` with an estimated nugget) with
//! projected BFGS on the analytic gradient (default), Hooke–Jeeves or
//! multistart GPS, then solve at the optimum.

pub mod corr;
mod dense;
mod family;
mod fastexp;
mod fma;
mod fused;
pub mod model;
mod options;
pub mod problem;
mod search;
pub mod trend;

pub use corr::{Correlation, CorrelationModel, Gaussian, TrainingInputs};
pub use family::{FAMILY_FOLDS, FamilyScore, fit_output_auto};
pub use fused::FusedBasis;
pub use model::{HeldOut, KrigingModel, KrigingModelData, Pred};
pub use options::{
    FitReport, KrigingOptions, MIN_CONVERGE_ROWS, OptimizerKind, TrendKind, WarmStart,
};
pub use problem::{KrigingProblem, PsiValue, Solution, Workspace, storable_ln_psi};
pub use search::{FitPlan, REFINE_ROWS, SEARCH_ROWS, converge_subset};
use search::{Search, converge_bfgs, ln_psi_objective, optimise, row_subset};
pub use trend::{
    KinematicTrend, Monomials, Trend, TrendModel, independent_columns, support, supported_columns,
    trend_matrix,
};

use crate::optim::{self, Bounds, HjOptions};
use crate::space::Normalizer;
use crate::{Error, Result};
use std::time::Instant;

/// One output's data prepared for fitting: dependent trend terms dropped,
/// response z-scored.
struct Prepared {
    trend: Trend,
    /// Which kept trend columns get the Bayesian prior ([`TrendModel::has_prior`]).
    prior: Vec<bool>,
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
        prior: (0..trend_kept.len())
            .map(|j| trend_kept.has_prior(j))
            .collect(),
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
        prior: &p.prior,
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
        prior: &p.prior,
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
