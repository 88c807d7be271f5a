//! Box-constrained minimisers. They know nothing about
//! Kriging: the derivative-free ones take an objective closure `FnMut(&[f64]) -> f64` (return
//! `f64::INFINITY` for a point that cannot be evaluated) and a [`Bounds`].
//!
//! - [`hooke_jeeves`]: exploratory coordinate moves + pattern moves, step
//!   halving (DACE's `boxmin` family; cheap, local).
//! - [`gps`]: generalised pattern search (Torczon 1997; Audet & Dennis 2003):
//!   polls the positive spanning set `{±e_i}` on a mesh, expands the mesh on a
//!   successful poll and contracts it on a failed one, until the mesh size is
//!   below a tolerance or the evaluation budget is spent.
//! - [`bfgs`]: box-constrained BFGS with finite-difference gradients, to
//!   polish a smooth minimum found by a pattern search.
//! - [`quasi_newton`]: projected BFGS with analytic gradients (the default
//!   hyperparameter search; takes `FnMut(&[f64], &mut [f64]) -> f64`).
//! - [`ga`]: genetic algorithm over bit strings (basis selection, seed 004).
//! - [`levenberg_marquardt`]: Levenberg–Marquardt for nonlinear least squares
//!   `min ½‖r(x)‖²` (takes residuals and Jacobian, not a scalar objective;
//!   Marquardt scaling, QR-solved damped steps, unidentifiable parameters
//!   detected and frozen); [`numerical_jacobian`] by central differences.
//! - [`multistart`]: runs a local method from several starts in parallel (rayon)
//!   and keeps the best; [`lhs_starts`] draws the starts.

mod bfgs;
mod ga;
mod gps;
mod hooke_jeeves;
mod lm;
mod quasi_newton;

pub use bfgs::{BfgsOptions, bfgs};
pub use ga::{GaOptions, GaResult, ga};
pub use gps::{GpsOptions, gps};
pub use hooke_jeeves::{HjOptions, hooke_jeeves};
pub use lm::{
    LeastSquares, LmOptions, LmResult, LmStop, levenberg_marquardt, levenberg_marquardt_on,
    numerical_jacobian,
};
pub use quasi_newton::{QuasiNewtonOptions, quasi_newton, quasi_newton_resume, quasi_newton_warm};

use rand::RngExt;
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Box `lo ≤ x ≤ hi`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Bounds {
    /// Lower bound per dimension.
    pub lo: Vec<f64>,
    /// Upper bound per dimension.
    pub hi: Vec<f64>,
}

impl Bounds {
    /// The same interval in every one of `d` dimensions.
    pub fn uniform(d: usize, lo: f64, hi: f64) -> Self {
        Bounds {
            lo: vec![lo; d],
            hi: vec![hi; d],
        }
    }

    /// Dimension.
    pub fn dim(&self) -> usize {
        self.lo.len()
    }

    /// Whether `x` lies in the box.
    pub fn contains(&self, x: &[f64]) -> bool {
        x.iter()
            .zip(self.lo.iter().zip(&self.hi))
            .all(|(v, (l, h))| v >= l && v <= h)
    }

    /// `x` clamped into the box.
    pub fn clamp(&self, x: &[f64]) -> Vec<f64> {
        x.iter()
            .zip(self.lo.iter().zip(&self.hi))
            .map(|(v, (l, h))| v.clamp(*l, *h))
            .collect()
    }

    /// Centre of the box.
    pub fn center(&self) -> Vec<f64> {
        self.lo
            .iter()
            .zip(&self.hi)
            .map(|(l, h)| 0.5 * (l + h))
            .collect()
    }
}

/// Outcome of a minimisation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct OptimResult {
    /// Best point found.
    pub x: Vec<f64>,
    /// Objective at `x`.
    pub f: f64,
    /// Objective evaluations spent.
    pub evals: usize,
    /// Iterations (polls / exploratory sweeps).
    pub iterations: usize,
    /// Why it stopped.
    pub stop: StopReason,
}

/// Why a minimiser stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum StopReason {
    /// Mesh / step size below tolerance: a local minimum to that resolution.
    MeshTolerance,
    /// Evaluation budget spent.
    Budget,
}

/// Counts evaluations and remembers the best point.
pub(crate) struct Tracker<F> {
    f: F,
    pub evals: usize,
    pub budget: usize,
}

impl<F: FnMut(&[f64]) -> f64> Tracker<F> {
    pub fn new(f: F, budget: usize) -> Self {
        Tracker {
            f,
            evals: 0,
            budget,
        }
    }

    /// `f(x)`, with NaN mapped to +∞; `None` once the budget is spent.
    pub fn eval(&mut self, x: &[f64]) -> Option<f64> {
        if self.evals >= self.budget {
            return None;
        }
        self.evals += 1;
        let v = (self.f)(x);
        Some(if v.is_nan() { f64::INFINITY } else { v })
    }
}

/// `n` Latin-hypercube points in the box, reproducible from `seed`; the box
/// centre is always the first start.
pub fn lhs_starts(bounds: &Bounds, n: usize, seed: u64) -> Vec<Vec<f64>> {
    let mut out = vec![bounds.center()];
    if n <= 1 {
        out.truncate(n);
        return out;
    }
    let mut rng = crate::stats::rng_for(seed, "optim-lhs-starts");
    let ranges: Vec<(f64, f64)> = bounds
        .lo
        .iter()
        .copied()
        .zip(bounds.hi.iter().copied())
        .collect();
    let k = n - 1;
    let mut cols: Vec<Vec<f64>> = Vec::new();
    for (lo, hi) in &ranges {
        let mut perm: Vec<usize> = (0..k).collect();
        for i in (1..k).rev() {
            perm.swap(i, rng.random_range(0..=i));
        }
        cols.push(
            perm.iter()
                .map(|&s| lo + (hi - lo) * (s as f64 + rng.random::<f64>()) / k as f64)
                .collect(),
        );
    }
    out.extend((0..k).map(|i| cols.iter().map(|c| c[i]).collect()));
    out
}

/// Run `local` from every start in parallel; return the best result and all
/// results in start order (ties broken by start order, so the outcome does not
/// depend on thread scheduling).
pub fn multistart<L>(starts: &[Vec<f64>], local: L) -> (OptimResult, Vec<OptimResult>)
where
    L: Fn(&[f64]) -> OptimResult + Sync,
{
    let all: Vec<OptimResult> = starts.par_iter().map(|x0| local(x0)).collect();
    let best = all
        .iter()
        .min_by(|a, b| a.f.total_cmp(&b.f))
        .cloned()
        .expect("at least one start");
    (best, all)
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Rosenbrock in 2D and a shifted quadratic in 6D: both methods reach the
    /// minimum to the mesh tolerance.
    #[test]
    fn both_methods_find_smooth_minima() {
        let b = Bounds::uniform(6, -3.0, 3.0);
        let target = [0.3, -1.2, 2.0, 0.0, -0.5, 1.1];
        let quad = |x: &[f64]| {
            x.iter()
                .zip(&target)
                .map(|(a, t)| (a - t) * (a - t) * 3.0)
                .sum::<f64>()
        };
        let r = gps(quad, &b.center(), &b, &GpsOptions::default());
        assert!(r.f < 1e-5, "gps {r:?}");
        let r = hooke_jeeves(
            quad,
            &b.center(),
            &b,
            &HjOptions {
                tol: 1e-4,
                ..HjOptions::default()
            },
        );
        assert!(r.f < 1e-6, "hj {r:?}");
        let b2 = Bounds::uniform(2, -2.0, 2.0);
        let rosen = |x: &[f64]| (1.0 - x[0]).powi(2) + 100.0 * (x[1] - x[0] * x[0]).powi(2);
        let r = gps(
            rosen,
            &[-1.0, 1.0],
            &b2,
            &GpsOptions {
                mesh_tol: 1e-7,
                max_evals: 100_000,
                ..GpsOptions::default()
            },
        );
        assert!(r.f < 1e-4, "gps rosenbrock {r:?}");
    }

    #[test]
    fn bfgs_polishes_an_ill_scaled_quadratic_and_respects_bounds() {
        let b = Bounds::uniform(4, -2.0, 2.0);
        // minimum at (0.3, −0.7, 1.1, 2.5) → the last coordinate ends on its bound
        let f = |x: &[f64]| {
            let t = [0.3, -0.7, 1.1, 2.5];
            let w = [1.0, 30.0, 0.2, 5.0];
            (0..4).map(|i| w[i] * (x[i] - t[i]).powi(2)).sum::<f64>()
                + 0.5 * (x[0] - t[0]) * (x[1] - t[1])
        };
        let r = bfgs(
            f,
            &[0.0; 4],
            &b,
            &BfgsOptions {
                max_iter: 50,
                max_evals: 5000,
                gtol: 1e-9,
                ..BfgsOptions::default()
            },
        );
        assert!(
            (r.x[0] - 0.3).abs() < 1e-5
                && (r.x[1] + 0.7).abs() < 1e-5
                && (r.x[2] - 1.1).abs() < 1e-4,
            "{r:?}"
        );
        assert_eq!(r.x[3], 2.0);
        assert!(r.f <= f(&[0.0; 4]));
    }

    #[test]
    fn minimisers_stay_in_the_box_and_respect_budget() {
        let b = Bounds::uniform(3, 0.0, 1.0);
        let lin = |x: &[f64]| {
            assert!(
                x.iter().all(|v| (0.0..=1.0).contains(v)),
                "left the box: {x:?}"
            );
            -x.iter().sum::<f64>()
        };
        let r = gps(lin, &[0.5; 3], &b, &GpsOptions::default());
        assert!((r.f + 3.0).abs() < 1e-9);
        let r = gps(
            lin,
            &[0.5; 3],
            &b,
            &GpsOptions {
                max_evals: 5,
                ..GpsOptions::default()
            },
        );
        assert_eq!(r.evals, 5);
        assert_eq!(r.stop, StopReason::Budget);
        let r = hooke_jeeves(lin, &[0.5; 3], &b, &HjOptions::default());
        assert!((r.f + 3.0).abs() < 1e-9);
    }

    #[test]
    fn multistart_is_deterministic_and_picks_the_global_basin() {
        let b = Bounds::uniform(1, -4.0, 4.0);
        // two basins: x = -2 (f = 0) and x = 2.5 (f = 1)
        let f = |x: &[f64]| ((x[0] + 2.0).powi(2)).min((x[0] - 2.5).powi(2) + 1.0);
        let starts = lhs_starts(&b, 6, 42);
        assert_eq!(starts.len(), 6);
        let (best, all) = multistart(&starts, |x0| gps(f, x0, &b, &GpsOptions::default()));
        assert!(best.f < 1e-6 && (best.x[0] + 2.0).abs() < 1e-3);
        let (best2, _) = multistart(&starts, |x0| gps(f, x0, &b, &GpsOptions::default()));
        assert_eq!(best, best2);
        assert_eq!(all.len(), 6);
    }
}
