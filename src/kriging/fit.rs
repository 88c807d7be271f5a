//! The steps of one output's fit ([`super::ValidKrigingParams::fit`]):
//! prepare the data (drop dependent trend columns, z-score the response),
//! then either solve at given ξ, ν or search them by minimising ln ψ (seed
//! 003 eq 14) and solve at the optimum.

use super::{
    CoefficientPrior, Correlation, FitReport, Hyperparameters, KrigingModel, KrigingOptions,
    KrigingProblem, OptimizerKind, Search, TrainingInputs, Trend, TrendModel, converge_bfgs,
    independent_columns, ln_psi_objective, optimise, storable_ln_psi, supported_columns,
    trend_matrix,
};
use crate::optim::{self, Bounds, HjOptions};
use crate::space::Normalizer;
use crate::{Error, Result};
use std::time::Instant;

/// Relative tolerance of the screen of a shared trend's columns in one
/// output's fit ([`fit_columns`]), and of the per-axis screen of the
/// kinematic trend (`selection::KINEMATIC_AXIS_TOL` is this).
pub const SHARED_SCREEN_TOL: f64 = 1e-3;

/// Rows a shared trend column's new component must be spread over in that
/// screen (`selection::KINEMATIC_MIN_SUPPORT` is this).
pub const SHARED_SCREEN_SUPPORT: f64 = 10.0;

/// The columns of `trend`'s matrix `f` on the training rows that one
/// output's fit keeps, and those it drops: the linearly independent ones (relative tolerance
/// 1e-9). A trend whose coefficients the outputs share
/// ([`TrendModel::shared_key`]) gets them from all outputs together
/// ([`super::share_coefficients`]); its own fit only chooses ξ and σ², and
/// its columns are screened as one output's GLS needs to stay well
/// conditioned (each kept column independent to 1e-3 and spread over 10
/// rows, [`supported_columns`]): without it, columns dependent on one axis
/// but not on three make the likelihood's gradient lose digits.
pub fn fit_columns(trend: &Trend, f: &faer::Mat<f64>) -> (Vec<usize>, Vec<usize>) {
    if trend.has_shared() {
        supported_columns(f, SHARED_SCREEN_TOL, SHARED_SCREEN_SUPPORT)
    } else {
        independent_columns(f, 1e-9)
    }
}

/// One output's fit: normalised inputs `x` (m rows; `inputs` holds their
/// first `inputs.d` columns, the correlation inputs — the others are
/// trend-only), response `y` in original units, trend candidates, input
/// names and options.
pub(super) struct Job<'a> {
    pub x: &'a [Vec<f64>],
    pub inputs: &'a TrainingInputs,
    pub y: &'a [f64],
    pub trend: &'a Trend,
    pub names: &'a [String],
    pub opts: &'a KrigingOptions,
}

/// One output's data prepared for fitting: dependent trend terms dropped,
/// response z-scored.
struct Prepared {
    trend: Trend,
    /// The Bayesian prior of each kept trend column ([`TrendModel::prior`]).
    prior: Vec<CoefficientPrior>,
    f: faer::Mat<f64>,
    y_norm: Vec<f64>,
    y_mean: f64,
    y_std: f64,
    trend_terms: Vec<String>,
    dropped_terms: Vec<String>,
}

impl Job<'_> {
    /// The job on the rows `rows` only.
    pub(super) fn rows<R>(&self, rows: &[usize], then: impl FnOnce(&Job) -> R) -> R {
        let x: Vec<Vec<f64>> = rows.iter().map(|&i| self.x[i].clone()).collect();
        let y: Vec<f64> = rows.iter().map(|&i| self.y[i]).collect();
        let inputs = self.inputs.select(rows);
        then(&Job {
            x: &x,
            inputs: &inputs,
            y: &y,
            ..*self
        })
    }

    fn prepare(&self) -> Result<Prepared> {
        let (x, y, trend) = (self.x, self.y, self.trend);
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
        let f = trend_matrix(trend, x);
        let (kept, dropped) = fit_columns(trend, &f);
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
            prior: (0..trend_kept.len()).map(|j| trend_kept.prior(j)).collect(),
            f: faer::Mat::from_fn(m, kept.len(), |i, j| f[(i, kept[j])]),
            y_norm: y.iter().map(|v| (v - y_mean) / y_std).collect(),
            y_mean,
            y_std,
            trend_terms: (0..trend_kept.len())
                .map(|j| trend_kept.term_name(j, self.names))
                .collect(),
            dropped_terms: dropped
                .iter()
                .map(|&j| trend.term_name(j, self.names))
                .collect(),
            trend: trend_kept,
        })
    }

    /// Solve at the given ξ and ν (no search): the model and a report
    /// without search figures.
    pub(super) fn solve_at(
        &self,
        corr: Correlation,
        at: &Hyperparameters,
    ) -> Result<(KrigingModel, FitReport)> {
        let t0 = Instant::now();
        let p = self.prepare()?;
        if at.theta.len() != self.inputs.d {
            return Err(Error::InvalidParameter(format!(
                "{} correlation parameters for {} correlation inputs",
                at.theta.len(),
                self.inputs.d
            )));
        }
        let problem = self.problem(&corr, &p);
        let sol = problem.solve(&at.theta, at.nugget)?;
        self.finish(sol, p, corr, at.theta.clone(), at.nugget, None, t0)
    }

    /// Search ξ (and ν with the nugget option) by minimising ln ψ: the
    /// options' multistart, or a local search from `start`; then solve at
    /// the optimum.
    pub(super) fn search(
        &self,
        corr: Correlation,
        start: Option<&Hyperparameters>,
    ) -> Result<(KrigingModel, FitReport)> {
        let t0 = Instant::now();
        let opts = self.opts;
        let d = self.inputs.d;
        let p = self.prepare()?;
        let problem = self.problem(&corr, &p);
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
        let search = if p.y_norm.iter().all(|v| *v == 0.0) {
            None
        } else {
            let search = match start {
                Some(w) => self.local_search(&problem, w, &bounds, &unpack)?,
                None => optimise(&problem, &bounds, &unpack, opts),
            };
            // a cancelled search stops at +∞ points: not a numerical failure
            opts.cancel.check()?;
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
        let (theta, nugget) = unpack(&best_x);
        let sol = problem.solve(&theta, nugget)?;
        self.finish(sol, p, corr, theta, nugget, search, t0)
    }

    fn problem<'p>(&'p self, corr: &'p Correlation, p: &'p Prepared) -> KrigingProblem<'p> {
        KrigingProblem {
            min_jitter: self.opts.min_jitter,
            corr,
            inputs: self.inputs,
            f: &p.f,
            y: &p.y_norm,
            prior: &p.prior,
        }
    }

    /// The local search from a warm start `w`: BFGS from its curvature with
    /// the default optimiser, Hooke–Jeeves (initial step 0.25 in log10
    /// units) otherwise.
    fn local_search(
        &self,
        problem: &KrigingProblem,
        w: &Hyperparameters,
        bounds: &Bounds,
        unpack: &super::search::Unpack<'_>,
    ) -> Result<Search> {
        let (opts, d) = (self.opts, self.inputs.d);
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
            return Ok(converge_bfgs(problem, &z0, hinv, bounds, unpack, opts));
        }
        let obj = ln_psi_objective(problem, unpack, &opts.cancel);
        let hj = HjOptions {
            initial_step: 0.25,
            max_evals: opts.max_evals,
            ..HjOptions::default()
        };
        Ok(Search {
            best: optim::hooke_jeeves(obj, &z0, bounds, &hj),
            starts: 1,
            rows: self.y.len(),
            inverse_hessian: None,
        })
    }

    /// The model of the solution at `(theta, nugget)` and its report.
    #[allow(clippy::too_many_arguments)]
    fn finish(
        &self,
        sol: super::Solution,
        p: Prepared,
        corr: Correlation,
        mut theta: Vec<f64>,
        nugget: f64,
        search: Option<Search>,
        t0: Instant,
    ) -> Result<(KrigingModel, FitReport)> {
        // trend-only inputs (beyond `inputs.d`) do not enter the correlation
        theta.resize(self.x.first().map_or(theta.len(), Vec::len), 0.0);
        let report = FitReport {
            theta: theta.clone(),
            nugget,
            ln_psi: storable_ln_psi(sol.value.ln_psi),
            sigma2: sol.value.sigma2,
            jitter: sol.value.jitter,
            trend_terms: p.trend_terms,
            dropped_terms: p.dropped_terms,
            optimizer: self.opts.optimizer,
            starts: search.as_ref().map_or(0, |s| s.starts),
            evals: search.as_ref().map_or(0, |s| s.best.evals),
            search_rows: search.as_ref().map_or(0, |s| s.rows),
            seconds: t0.elapsed().as_secs_f64(),
            inverse_hessian: search.and_then(|s| s.inverse_hessian),
            families: Vec::new(),
        };
        let model = KrigingModel::from_solution(
            sol,
            p.trend,
            corr,
            theta,
            nugget,
            self.x.to_vec(),
            p.y_mean,
            p.y_std,
        )?;
        Ok((model, report))
    }
}
