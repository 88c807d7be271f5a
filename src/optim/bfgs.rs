//! Box-constrained BFGS with central finite-difference gradients: a local
//! polish for smooth objectives once a pattern search has found the basin.

use super::{Bounds, OptimResult, StopReason, Tracker};

/// Options of [`bfgs`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BfgsOptions {
    /// Finite-difference step (units of x).
    pub h: f64,
    /// Stop when the projected gradient's largest component is below this.
    pub gtol: f64,
    /// Longest step per iteration (units of x).
    pub max_step: f64,
    /// Iteration cap (reaching it stops with [`StopReason::MeshTolerance`]).
    pub max_iter: usize,
    /// Objective evaluation budget, finite-difference gradients included.
    pub max_evals: usize,
}

impl Default for BfgsOptions {
    fn default() -> Self {
        BfgsOptions {
            h: 1e-4,
            gtol: 1e-9,
            max_step: 0.25,
            max_iter: 30,
            max_evals: 1000,
        }
    }
}

/// Minimise `f` from `x0` by BFGS on the inverse Hessian with an Armijo
/// backtracking line search. Gradients are central differences (one-sided at
/// a bound); coordinates held at a bound by their gradient are frozen for the
/// step (projected gradient). Never returns a point worse than `x0`.
pub fn bfgs<F: FnMut(&[f64]) -> f64>(
    f: F,
    x0: &[f64],
    bounds: &Bounds,
    opts: &BfgsOptions,
) -> OptimResult {
    let d = x0.len();
    let mut t = Tracker::new(f, opts.max_evals.max(1));
    let mut x = bounds.clamp(x0);
    let mut fx = t.eval(&x).unwrap_or(f64::INFINITY);
    let mut hinv = identity(d);
    let mut prev: Option<(Vec<f64>, Vec<f64>)> = None; // (s, g_old)
    let mut iterations = 0;
    let stop = loop {
        let Some(g) = gradient(&mut t, &x, fx, bounds, opts.h) else {
            break StopReason::Budget;
        };
        if let Some((s, g_old)) = prev.take() {
            let y: Vec<f64> = g.iter().zip(&g_old).map(|(a, b)| a - b).collect();
            bfgs_update(&mut hinv, &s, &y);
        }
        let (free, gmax) = free_set(&x, &g, bounds);
        if gmax < opts.gtol || iterations >= opts.max_iter {
            break StopReason::MeshTolerance;
        }
        iterations += 1;
        let mut p = newton_direction(&hinv, &g, &free);
        let mut slope: f64 = p.iter().zip(&g).map(|(a, b)| a * b).sum();
        if slope >= 0.0 {
            hinv = identity(d);
            p = (0..d).map(|i| if free[i] { -g[i] } else { 0.0 }).collect();
            slope = p.iter().zip(&g).map(|(a, b)| a * b).sum();
        }
        let norm = p.iter().map(|v| v * v).sum::<f64>().sqrt();
        let mut step = if norm > opts.max_step {
            opts.max_step / norm
        } else {
            1.0
        };
        let mut accepted = None;
        for _ in 0..20 {
            let trial: Vec<f64> = bounds.clamp(
                &x.iter()
                    .zip(&p)
                    .map(|(a, b)| a + step * b)
                    .collect::<Vec<_>>(),
            );
            let Some(ft) = t.eval(&trial) else { break };
            if ft < fx + 1e-4 * step * slope.min(0.0) && ft < fx {
                accepted = Some((trial, ft));
                break;
            }
            step *= 0.5;
        }
        let Some((xn, fxn)) = accepted else {
            break StopReason::MeshTolerance;
        };
        let s: Vec<f64> = xn.iter().zip(&x).map(|(a, b)| a - b).collect();
        prev = Some((s, g));
        x = xn;
        fx = fxn;
        if t.evals >= t.budget {
            break StopReason::Budget;
        }
    };
    OptimResult {
        x,
        f: fx,
        evals: t.evals,
        iterations,
        stop,
    }
}

/// Coordinates not held at a bound by their gradient, and the largest
/// gradient component among them (the projected-gradient test).
pub(super) fn free_set(x: &[f64], g: &[f64], bounds: &Bounds) -> (Vec<bool>, f64) {
    let free: Vec<bool> = (0..x.len())
        .map(|i| !((x[i] <= bounds.lo[i] && g[i] > 0.0) || (x[i] >= bounds.hi[i] && g[i] < 0.0)))
        .collect();
    let gmax = (0..x.len())
        .filter(|&i| free[i])
        .map(|i| g[i].abs())
        .fold(0.0, f64::max);
    (free, gmax)
}

/// `p = −H g` on the free coordinates, 0 on the others.
pub(super) fn newton_direction(hinv: &[Vec<f64>], g: &[f64], free: &[bool]) -> Vec<f64> {
    (0..g.len())
        .map(|i| {
            if free[i] {
                -(0..g.len())
                    .filter(|&j| free[j])
                    .map(|j| hinv[i][j] * g[j])
                    .sum::<f64>()
            } else {
                0.0
            }
        })
        .collect()
}

pub(super) fn identity(d: usize) -> Vec<Vec<f64>> {
    (0..d)
        .map(|i| (0..d).map(|j| if i == j { 1.0 } else { 0.0 }).collect())
        .collect()
}

/// Central differences (one-sided where a bound is within h); `None` when
/// the budget runs out.
fn gradient<F: FnMut(&[f64]) -> f64>(
    t: &mut Tracker<F>,
    x: &[f64],
    fx: f64,
    bounds: &Bounds,
    h: f64,
) -> Option<Vec<f64>> {
    let mut g = vec![0.0; x.len()];
    let mut z = x.to_vec();
    for i in 0..x.len() {
        let (up, down) = (x[i] + h <= bounds.hi[i], x[i] - h >= bounds.lo[i]);
        z[i] = if up { x[i] + h } else { x[i] };
        let fp = if up { t.eval(&z)? } else { fx };
        z[i] = if down { x[i] - h } else { x[i] };
        let fm = if down { t.eval(&z)? } else { fx };
        z[i] = x[i];
        let span = (if up { h } else { 0.0 }) + (if down { h } else { 0.0 });
        g[i] = if span > 0.0 { (fp - fm) / span } else { 0.0 };
    }
    Some(g)
}

/// `H ← (I − ρsyᵀ) H (I − ρysᵀ) + ρssᵀ`, skipped unless `sᵀy > 0`.
pub(super) fn bfgs_update(h: &mut [Vec<f64>], s: &[f64], y: &[f64]) {
    let sy: f64 = s.iter().zip(y).map(|(a, b)| a * b).sum();
    if sy
        <= 1e-12
            * s.iter().map(|v| v * v).sum::<f64>().sqrt()
            * y.iter().map(|v| v * v).sum::<f64>().sqrt()
    {
        return;
    }
    let rho = 1.0 / sy;
    let d = s.len();
    let hy: Vec<f64> = (0..d)
        .map(|i| (0..d).map(|j| h[i][j] * y[j]).sum())
        .collect();
    let yhy: f64 = y.iter().zip(&hy).map(|(a, b)| a * b).sum();
    for i in 0..d {
        for j in 0..d {
            h[i][j] += -rho * (hy[i] * s[j] + s[i] * hy[j]) + (rho * rho * yhy + rho) * s[i] * s[j];
        }
    }
}
