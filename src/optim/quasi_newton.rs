//! Projected BFGS with analytic gradients: the default hyperparameter search.
//! For box-constrained smooth objectives of a few dozen variables at most,
//! such as ln ψ over `(log10 ξ, log10 ν)`.
//!
//! Each iteration:
//! 1. the *free* set is every coordinate not held at a bound by its gradient
//!    (`x_i = lo_i` with `g_i > 0`, or `x_i = hi_i` with `g_i < 0`);
//! 2. the step is `p = −H g` on the free set, H the BFGS inverse Hessian
//!    (reset to a scaled identity if p is not a descent direction);
//! 3. a backtracking Armijo search along the projected path
//!    `x(α) = clamp(x + αp)`, with `f(x(α)) ≤ f(x) + c₁ gᵀ(x(α) − x)`;
//! 4. `H ← (I − ρsyᵀ)H(I − ρysᵀ) + ρssᵀ` when `sᵀy > 0`, the first update
//!    preceded by the scaling `H = (sᵀy / yᵀy) I` (Nocedal & Wright eq 6.20).
//!
//! It stops when the largest free gradient component is below `gtol`, when
//! an iteration lowers f by less than `ftol·max(1, |f|)` (the `factr` test of
//! L-BFGS-B) or than `fatol`, on the iteration or evaluation budget, or when no step along
//! the projected path lowers f. With d ≤ 13 the dense d × d inverse Hessian
//! costs nothing next to one evaluation, so the limited-memory form of
//! L-BFGS-B buys nothing here; the projection does what its Cauchy-point
//! step does for the coordinates at a bound.
//!
//! Why not argmin: its L-BFGS is unconstrained, and the hyperparameters of
//! irrelevant inputs sit on the box's lower edge (ξ → 0) in most fits, which
//! a projection handles exactly and a reparametrisation of the box would
//! flatten into a vanishing gradient.

use super::bfgs::{bfgs_update, free_set, identity, newton_direction};
use super::{Bounds, OptimResult, StopReason};

/// Options of [`quasi_newton`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct QuasiNewtonOptions {
    /// Stop when the largest free gradient component is below this.
    pub gtol: f64,
    /// Stop when an iteration lowers f by less than `ftol·max(1, |f|)`.
    pub ftol: f64,
    /// Stop when an iteration lowers f by less than this (absolute; 0: off).
    pub fatol: f64,
    /// Longest step per iteration (units of x).
    pub max_step: f64,
    /// Iteration limit.
    pub max_iter: usize,
    /// Evaluation limit (value and gradient count as one).
    pub max_evals: usize,
}

impl Default for QuasiNewtonOptions {
    fn default() -> Self {
        QuasiNewtonOptions {
            gtol: 1e-5,
            ftol: 1e-10,
            fatol: 0.0,
            max_step: 1.0,
            max_iter: 200,
            max_evals: 400,
        }
    }
}

/// Minimise `f` from `x0` in the box. `fg(x, g)` returns `f(x)` and writes
/// `∇f(x)` into `g`; it returns `f64::INFINITY` (or NaN) where f cannot be
/// evaluated, and the search backs off from there. Never returns a point
/// worse than the clamped start.
pub fn quasi_newton<F>(fg: F, x0: &[f64], bounds: &Bounds, opts: &QuasiNewtonOptions) -> OptimResult
where
    F: FnMut(&[f64], &mut [f64]) -> f64,
{
    quasi_newton_warm(fg, x0, None, bounds, opts).0
}

/// [`quasi_newton`] from a given inverse Hessian approximation (e.g. the
/// one a run on a subset of the data ended with), returning the final one
/// too. `None` starts from the identity, scaled after the first step.
pub fn quasi_newton_warm<F>(
    fg: F,
    x0: &[f64],
    hinv0: Option<Vec<Vec<f64>>>,
    bounds: &Bounds,
    opts: &QuasiNewtonOptions,
) -> (OptimResult, Vec<Vec<f64>>)
where
    F: FnMut(&[f64], &mut [f64]) -> f64,
{
    let (r, h, _) = quasi_newton_resume(fg, x0, None, hinv0, bounds, opts);
    (r, h)
}

/// [`quasi_newton_warm`] that can resume a run: when `known` gives
/// `f(x0)` and `∇f(x0)` (`x0` inside the box) they are not evaluated again,
/// so the iterations are those of a restart from `x0`, one evaluation fewer
/// (the result's `evals` counts only new evaluations). Returns the
/// gradient at the result's point too, for the next resumption.
pub fn quasi_newton_resume<F>(
    mut fg: F,
    x0: &[f64],
    known: Option<(f64, &[f64])>,
    hinv0: Option<Vec<Vec<f64>>>,
    bounds: &Bounds,
    opts: &QuasiNewtonOptions,
) -> (OptimResult, Vec<Vec<f64>>, Vec<f64>)
where
    F: FnMut(&[f64], &mut [f64]) -> f64,
{
    if let Some((_, g0)) = known {
        assert_eq!(g0.len(), x0.len(), "gradient length");
    }
    let d = x0.len();
    let warm = hinv0
        .as_ref()
        .is_some_and(|h| h.len() == d && h.iter().all(|r| r.len() == d));
    let evals = std::cell::Cell::new(0);
    let mut eval = |x: &[f64], g: &mut [f64]| {
        evals.set(evals.get() + 1);
        let v = fg(x, g);
        if v.is_nan() { f64::INFINITY } else { v }
    };
    let mut x = bounds.clamp(x0);
    let mut g = vec![0.0; d];
    let mut fx = match known {
        Some((f0, g0)) if x == x0 => {
            g.copy_from_slice(g0);
            f0
        }
        _ => eval(&x, &mut g),
    };
    let (mut hinv, mut scaled) = match hinv0 {
        Some(h) if warm => (h, true),
        _ => (identity(d), false),
    };
    let mut iterations = 0;
    let mut gn = vec![0.0; d];
    let stop = loop {
        if !fx.is_finite() {
            break StopReason::Budget;
        }
        let (free, gmax) = free_set(&x, &g, bounds);
        if gmax < opts.gtol {
            break StopReason::MeshTolerance;
        }
        if iterations >= opts.max_iter || evals.get() >= opts.max_evals {
            break StopReason::Budget;
        }
        iterations += 1;
        let p = descent_direction(&mut hinv, &mut scaled, &g, &free);
        let Some((xn, fxn)) =
            line_search(&mut eval, &evals, (&x, fx, &g), &p, &mut gn, bounds, opts)
        else {
            break StopReason::MeshTolerance;
        };
        let s: Vec<f64> = xn.iter().zip(&x).map(|(a, b)| a - b).collect();
        let y: Vec<f64> = gn.iter().zip(&g).map(|(a, b)| a - b).collect();
        if !scaled {
            scaled = initial_scaling(&mut hinv, &s, &y);
        }
        bfgs_update(&mut hinv, &s, &y);
        let small = fx - fxn < (opts.ftol * fx.abs().max(1.0)).max(opts.fatol);
        x = xn;
        fx = fxn;
        g.copy_from_slice(&gn);
        if small {
            break StopReason::MeshTolerance;
        }
    };
    (
        OptimResult {
            x,
            f: fx,
            evals: evals.get(),
            iterations,
            stop,
        },
        hinv,
        g,
    )
}

/// `p = −H g` on the free set; when that is not a descent direction
/// (`pᵀg ≥ 0`), H is reset to the identity (unscaled) and `p = −g` there.
fn descent_direction(
    hinv: &mut Vec<Vec<f64>>,
    scaled: &mut bool,
    g: &[f64],
    free: &[bool],
) -> Vec<f64> {
    let d = g.len();
    let mut p = newton_direction(hinv, g, free);
    if p.iter().zip(g).map(|(a, b)| a * b).sum::<f64>() >= 0.0 {
        *hinv = identity(d);
        *scaled = false;
        p = (0..d).map(|i| if free[i] { -g[i] } else { 0.0 }).collect();
    }
    p
}

/// Backtracking Armijo search along the projected path
/// `x(α) = clamp(x + αp)`, α halved from `min(1, max_step/‖p‖)` at most 30
/// times: the first point with `f(x(α)) ≤ f(x) + 10⁻⁴ gᵀ(x(α) − x)`, its
/// gradient left in `gn`. `None` when the path no longer descends
/// (`gᵀ(x(α) − x) ≥ 0`), the budget is spent, or no trial is accepted.
fn line_search<F>(
    eval: &mut F,
    evals: &std::cell::Cell<usize>,
    (x, fx, g): (&[f64], f64, &[f64]),
    p: &[f64],
    gn: &mut [f64],
    bounds: &Bounds,
    opts: &QuasiNewtonOptions,
) -> Option<(Vec<f64>, f64)>
where
    F: FnMut(&[f64], &mut [f64]) -> f64,
{
    let norm = p.iter().map(|v| v * v).sum::<f64>().sqrt();
    let mut alpha = if norm > opts.max_step {
        opts.max_step / norm
    } else {
        1.0
    };
    for _ in 0..30 {
        if evals.get() >= opts.max_evals {
            return None;
        }
        let trial = bounds.clamp(
            &x.iter()
                .zip(p)
                .map(|(a, b)| a + alpha * b)
                .collect::<Vec<_>>(),
        );
        let decrease: f64 = g
            .iter()
            .zip(trial.iter().zip(x))
            .map(|(gi, (t, xi))| gi * (t - xi))
            .sum();
        if decrease >= 0.0 {
            return None; // the projected path no longer descends
        }
        let ft = eval(&trial, gn);
        if ft <= fx + 1e-4 * decrease {
            return Some((trial, ft));
        }
        alpha *= 0.5;
    }
    None
}

/// Before the first BFGS update: `H = (sᵀy / yᵀy) I` when `sᵀy > 0`
/// (Nocedal & Wright eq 6.20). Returns whether H is now scaled.
fn initial_scaling(hinv: &mut Vec<Vec<f64>>, s: &[f64], y: &[f64]) -> bool {
    let sy: f64 = s.iter().zip(y).map(|(a, b)| a * b).sum();
    if sy > 0.0 {
        let yy: f64 = y.iter().map(|v| v * v).sum();
        let gamma = sy / yy;
        *hinv = identity(s.len());
        for (i, row) in hinv.iter_mut().enumerate() {
            row[i] = gamma;
        }
        return true;
    }
    false
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Resuming a run from its known value and gradient takes the same
    /// iterations as starting it again from the same point, one evaluation
    /// fewer.
    #[test]
    fn resume_equals_warm_restart_without_the_first_evaluation() {
        let fg = |x: &[f64], g: &mut [f64]| {
            g[0] = 2.0 * (x[0] - 1.0) + x[1];
            g[1] = 8.0 * (x[1] + 0.5) + x[0];
            (x[0] - 1.0).powi(2) + 4.0 * (x[1] + 0.5).powi(2) + x[0] * x[1]
        };
        let b = Bounds::uniform(2, -3.0, 3.0);
        let short = QuasiNewtonOptions {
            max_iter: 2,
            ..QuasiNewtonOptions::default()
        };
        let (first, h) = quasi_newton_warm(fg, &[2.5, 2.0], None, &b, &short);
        let mut g0 = [0.0; 2];
        let f0 = fg(&first.x, &mut g0);
        let o = QuasiNewtonOptions::default();
        let (warm, hw) = quasi_newton_warm(fg, &first.x, Some(h.clone()), &b, &o);
        let (resumed, hr, gr) = quasi_newton_resume(fg, &first.x, Some((f0, &g0)), Some(h), &b, &o);
        let mut g_end = [0.0; 2];
        fg(&resumed.x, &mut g_end);
        assert_eq!(gr, g_end, "the gradient returned is the one at the result");
        assert_eq!(warm.x, resumed.x);
        assert_eq!(warm.f, resumed.f);
        assert_eq!(hw, hr);
        assert_eq!(warm.iterations, resumed.iterations);
        assert_eq!(warm.evals, resumed.evals + 1);
    }

    /// An ill-scaled quadratic with one coordinate pushed onto its bound: the
    /// free coordinates converge, the bound one stays on the bound.
    #[test]
    fn converges_on_an_ill_scaled_quadratic_with_an_active_bound() {
        let t = [0.3, -0.7, 1.1, 2.5];
        let w = [1.0, 300.0, 0.02, 5.0];
        let fg = |x: &[f64], g: &mut [f64]| {
            let mut f = 0.0;
            for i in 0..4 {
                f += w[i] * (x[i] - t[i]).powi(2);
                g[i] = 2.0 * w[i] * (x[i] - t[i]);
            }
            f
        };
        let b = Bounds::uniform(4, -2.0, 2.0);
        let r = quasi_newton(
            fg,
            &[0.0; 4],
            &b,
            &QuasiNewtonOptions {
                gtol: 1e-9,
                ftol: 0.0,
                ..QuasiNewtonOptions::default()
            },
        );
        for (x, t) in r.x.iter().zip(&t).take(3) {
            assert!((x - t).abs() < 1e-6, "{r:?}");
        }
        assert_eq!(r.x[3], 2.0);
        assert!(r.evals < 60, "{} evaluations", r.evals);
    }

    /// Rosenbrock from the classic start, and a start where the objective is
    /// infinite nearby: the search backs off instead of stopping.
    #[test]
    fn rosenbrock_and_infinite_regions() {
        let fg = |x: &[f64], g: &mut [f64]| {
            if x[0] > 1.5 {
                return f64::INFINITY;
            }
            g[0] = -2.0 * (1.0 - x[0]) - 400.0 * x[0] * (x[1] - x[0] * x[0]);
            g[1] = 200.0 * (x[1] - x[0] * x[0]);
            (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2)
        };
        let b = Bounds::uniform(2, -2.0, 2.0);
        let r = quasi_newton(
            fg,
            &[-1.2, 1.0],
            &b,
            &QuasiNewtonOptions {
                gtol: 1e-8,
                ftol: 0.0,
                ..QuasiNewtonOptions::default()
            },
        );
        assert!(r.f < 1e-10, "{r:?}");
        assert!((r.x[0] - 1.0).abs() < 1e-4);
    }
}
