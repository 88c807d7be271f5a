//! Hooke–Jeeves pattern search (exploratory moves + pattern moves).

use super::{Bounds, OptimResult, StopReason, Tracker};

/// Options of [`hooke_jeeves`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct HjOptions {
    /// Initial step (absolute, in the units of x).
    pub initial_step: f64,
    /// Stop when the step is below `tol`.
    pub tol: f64,
    /// Step reduction factor when no exploratory move improves.
    pub shrink: f64,
    /// Objective evaluation budget.
    pub max_evals: usize,
}

impl Default for HjOptions {
    fn default() -> Self {
        HjOptions {
            initial_step: 0.5,
            tol: 0.02,
            shrink: 0.5,
            max_evals: 2_000,
        }
    }
}

/// Minimise `f` over `bounds` from `x0` by Hooke–Jeeves.
///
/// Exploratory move: for each coordinate try `+h`, then `−h`, keep any
/// improvement (points clamped into the box). If the sweep improved on the
/// base point, make the pattern move `x_new + (x_new − x_base)` and explore
/// around it, keeping it if it beats the new base; otherwise `h ← shrink·h`.
pub fn hooke_jeeves<F: FnMut(&[f64]) -> f64>(
    f: F,
    x0: &[f64],
    bounds: &Bounds,
    opts: &HjOptions,
) -> OptimResult {
    let mut t = Tracker::new(f, opts.max_evals.max(1));
    let mut base = bounds.clamp(x0);
    let mut f_base = t.eval(&base).unwrap_or(f64::INFINITY);
    let mut h = opts.initial_step;
    let mut iterations = 0;
    let stop = loop {
        if h < opts.tol {
            break StopReason::MeshTolerance;
        }
        if t.evals >= t.budget {
            break StopReason::Budget;
        }
        iterations += 1;
        let (x_new, f_new) = explore(&mut t, &base, f_base, h, bounds);
        if f_new < f_base {
            // pattern move
            let pattern: Vec<f64> = x_new.iter().zip(&base).map(|(n, b)| 2.0 * n - b).collect();
            let pattern = bounds.clamp(&pattern);
            base = x_new;
            f_base = f_new;
            if let Some(fp) = t.eval(&pattern) {
                let (xp, fpe) = explore(&mut t, &pattern, fp, h, bounds);
                if fpe < f_base {
                    base = xp;
                    f_base = fpe;
                }
            }
        } else {
            h *= opts.shrink;
        }
    };
    OptimResult {
        x: base,
        f: f_base,
        evals: t.evals,
        iterations,
        stop,
    }
}

fn explore<F: FnMut(&[f64]) -> f64>(
    t: &mut Tracker<F>,
    x0: &[f64],
    f0: f64,
    h: f64,
    bounds: &Bounds,
) -> (Vec<f64>, f64) {
    let mut x = x0.to_vec();
    let mut fx = f0;
    for i in 0..x.len() {
        for sign in [1.0, -1.0] {
            let old = x[i];
            x[i] = (old + sign * h).clamp(bounds.lo[i], bounds.hi[i]);
            if x[i] == old {
                continue;
            }
            match t.eval(&x) {
                Some(v) if v < fx => {
                    fx = v;
                    break;
                }
                Some(_) => x[i] = old,
                None => {
                    x[i] = old;
                    return (x, fx);
                }
            }
        }
    }
    (x, fx)
}
