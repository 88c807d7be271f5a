//! Levenberg–Marquardt for nonlinear least squares `min_x ½‖r(x)‖²`.
//!
//! Like the other minimisers in [`crate::optim`] it knows nothing about the
//! problem: it takes a closure returning the residual vector `r(x)` (length
//! `m`) and its Jacobian `J(x)` (`m × n`), a start `x0` and an
//! [`LmOptions`]. [`numerical_jacobian`] builds `J` by central differences
//! when no analytic Jacobian is at hand. A problem whose Jacobian costs far
//! more than its residual implements [`LeastSquares`] instead
//! ([`levenberg_marquardt_on`]): its Jacobian is then evaluated only at the
//! points the method accepts, not at every trial step.
//!
//! # The step
//!
//! With the Marquardt scaling `D = diag(d_j)`, `d_j` the Euclidean norm of
//! column `j` of `J` (at `x0`, then `d_j ← max(d_j, ‖J_j‖)` after every
//! accepted step, as in MINPACK), the damped Gauss–Newton step `δ` solves
//!
//! ```text
//! (JᵀJ + λ D²) δ = −Jᵀ r.
//! ```
//!
//! It is never formed that way: in the scaled variables `u = D δ` it is the
//! linear least-squares problem
//!
//! ```text
//! min_u ‖ [ J D⁻¹ ] u + [ r ] ‖
//!       ‖ [ √λ I  ]     [ 0 ] ‖ ,
//! ```
//!
//! solved by Householder QR: once per Jacobian `J D⁻¹ = Q R`, and for each
//! trial `λ` a small QR of `[R; √λ I]` (no normal equations, no inverse).
//! Because the scaled columns have unit norm at `x0`, `λ` is relative to the
//! diagonal of `JᵀJ` (Nielsen's `τ`), so `lambda0` is dimensionless.
//!
//! # Acceptance and damping
//!
//! The gain ratio `ρ = (C(x) − C(x + δ)) / (L(0) − L(δ))` compares the actual
//! decrease of `C = ½‖r‖²` with the decrease predicted by the linear model
//! `L(δ) = ½‖r + J δ‖²`. A step is accepted when both decreases are positive
//! (`ρ > 0`); then `λ ← λ · max(1/3, 1 − (2ρ − 1)³)` and `ν ← 2`. Otherwise it
//! is rejected, `λ ← λ ν`, `ν ← 2ν` (Nielsen 1999; Madsen, Nielsen & Tingleff
//! 2004). A trial point whose residual or Jacobian is not finite is a rejected
//! step, not an error.
//!
//! # Stopping rules (checked in this order)
//!
//! - [`LmStop::SmallGradient`]: `‖D⁻¹ Jᵀ r‖_∞ ≤ tol_grad` (the gradient in
//!   the scaled variables, in the units of `r`), or no parameter left to fit.
//! - [`LmStop::MaxIterations`]: `max_iter` trial steps have been evaluated.
//! - [`LmStop::SmallStep`]: the step just tried satisfied
//!   `‖D δ‖ ≤ tol_step · (‖D x‖ + tol_step)` (relative, Nielsen's `ε₂`). The
//!   small step is still evaluated and kept if it is accepted (as in MINPACK),
//!   so the last quadratically convergent step is not thrown away; if it is
//!   rejected, λ has grown so large that no useful step is left.
//! - [`LmStop::SmallCostDecrease`]: an accepted step whose actual and predicted
//!   decreases are both `≤ tol_cost · C(x)` (MINPACK's `ftol`).
//!
//! # Rank deficiency
//!
//! Redundant parameters are common in kinematic calibration (a translation
//! along a joint axis duplicated by the next link's `d`, a base rotation
//! duplicated by a joint offset). At `x0` the singular values `σ` of the
//! column-normalised Jacobian give the numerical rank `k = #{σ > rank_tol ·
//! σ_max}`. If `k < n`, `n − k` parameters are frozen at their `x0` values
//! (the minimum-change solution) and reported in
//! [`LmResult::unidentifiable`]; the others are iterated.
//!
//! **Freezing rule.** The `k` parameters kept are chosen by greedy column
//! pivoting (Businger–Golub pivoted QR, i.e. modified Gram–Schmidt) on the
//! column-normalised Jacobian at `x0`: repeatedly keep the column with the
//! largest norm after projecting out the columns already kept. A candidate
//! replaces the current best only if its norm is larger by a relative
//! `1e-8`, so near-ties go to the **lower index**: of two identical columns the
//! earlier parameter is kept and the later one frozen. Order the parameters by
//! preference to control which of a redundant group survives. The rule is a
//! deterministic heuristic for the best-conditioned subset, not an exhaustive
//! search.
use nalgebra::{DMatrix, DVector, SVD};

use crate::{Error, Result};

/// Options of [`levenberg_marquardt`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LmOptions {
    /// Maximum number of trial steps (each is one linear solve and one
    /// evaluation of the residual and Jacobian).
    pub max_iter: usize,
    /// Relative step tolerance: stop when `‖D δ‖ ≤ tol_step (‖D x‖ + tol_step)`.
    pub tol_step: f64,
    /// Stop when the scaled gradient `‖D⁻¹ Jᵀ r‖_∞ ≤ tol_grad` (units of `r`).
    pub tol_grad: f64,
    /// Stop when an accepted step decreases the cost (actual and predicted) by
    /// at most `tol_cost` times the cost.
    pub tol_cost: f64,
    /// Initial damping, relative to the unit diagonal of the scaled `JᵀJ`.
    pub lambda0: f64,
    /// Relative singular-value threshold for the numerical rank of the
    /// column-normalised Jacobian.
    pub rank_tol: f64,
}

impl Default for LmOptions {
    fn default() -> Self {
        LmOptions {
            max_iter: 100,
            tol_step: 1e-10,
            tol_grad: 1e-12,
            tol_cost: 1e-14,
            lambda0: 1e-3,
            rank_tol: 1e-9,
        }
    }
}

/// Why [`levenberg_marquardt`] stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum LmStop {
    /// The scaled step fell below `tol_step` relative to the scaled `x`.
    SmallStep,
    /// The scaled gradient fell below `tol_grad` (or nothing was left to fit).
    SmallGradient,
    /// An accepted step decreased the cost by less than `tol_cost` relative.
    SmallCostDecrease,
    /// `max_iter` trial steps were spent.
    MaxIterations,
}

/// Outcome of [`levenberg_marquardt`].
#[derive(Debug, Clone, PartialEq)]
pub struct LmResult {
    /// Solution (frozen parameters keep their `x0` values).
    pub x: Vec<f64>,
    /// `½‖r(x)‖²`.
    pub cost: f64,
    /// `‖r(x)‖ / √m`.
    pub rms: f64,
    /// Trial steps evaluated (accepted or rejected).
    pub iterations: usize,
    /// Calls of the residual-and-Jacobian closure (including the one at `x0`).
    pub evaluations: usize,
    /// Why it stopped.
    pub stop: LmStop,
    /// Numerical rank of the column-normalised `J(x)` at the solution
    /// (singular values above `rank_tol · σ_max`).
    pub rank: usize,
    /// Indices (ascending) of the parameters found unidentifiable at `x0` and
    /// held fixed there; see the module documentation for the rule.
    pub unidentifiable: Vec<usize>,
    /// Standard errors `sqrt(diag((JᵀJ)⁺)) · rms`, with `JᵀJ` restricted to the
    /// fitted parameters (so they are conditional on the frozen ones).
    /// `f64::INFINITY` for frozen parameters, for parameters involved in a
    /// direction that became rank-deficient at the solution, and wherever the
    /// value would not be finite.
    pub std_errors: Vec<f64>,
}

fn invalid(msg: impl std::fmt::Display) -> Error {
    Error::InvalidParameter(format!("levenberg_marquardt: {msg}"))
}

/// Central-difference Jacobian of `f` at `x`: column `j` is
/// `(f(x + h_j e_j) − f(x − h_j e_j)) / (2 h_j)`. Spends `2n` evaluations
/// (one if `x` is empty, to learn the number of rows).
///
/// Errors (`InvalidParameter`, message starting with `numerical_jacobian:`):
/// `h.len() != x.len()`, a step that is not finite and positive, or
/// evaluations of different lengths. Errors of `f` are passed on.
pub fn numerical_jacobian<F>(mut f: F, x: &[f64], h: &[f64]) -> Result<DMatrix<f64>>
where
    F: FnMut(&[f64]) -> Result<DVector<f64>>,
{
    let n = x.len();
    if h.len() != n {
        return Err(Error::InvalidParameter(format!(
            "numerical_jacobian: {} steps for {} parameters",
            h.len(),
            n
        )));
    }
    if let Some((j, s)) = h
        .iter()
        .enumerate()
        .find(|(_, s)| !(s.is_finite() && **s > 0.0))
    {
        return Err(Error::InvalidParameter(format!(
            "numerical_jacobian: step {j} is {s}, must be finite and > 0"
        )));
    }
    if n == 0 {
        let m = f(x)?.len();
        return Ok(DMatrix::zeros(m, 0));
    }
    let mut xp = x.to_vec();
    let mut jac: Option<DMatrix<f64>> = None;
    for j in 0..n {
        xp[j] = x[j] + h[j];
        let fp = f(&xp)?;
        xp[j] = x[j] - h[j];
        let fm = f(&xp)?;
        xp[j] = x[j];
        // the actual distance between the two points, which may differ from
        // 2h by rounding of x ± h
        let width = (x[j] + h[j]) - (x[j] - h[j]);
        let m = jac.as_ref().map_or(fp.len(), |jm| jm.nrows());
        if fp.len() != m || fm.len() != m {
            return Err(Error::InvalidParameter(format!(
                "numerical_jacobian: evaluations of lengths {}, {} and {m}",
                fp.len(),
                fm.len()
            )));
        }
        let jm = jac.get_or_insert_with(|| DMatrix::zeros(m, n));
        jm.set_column(j, &((fp - fm) / width));
    }
    Ok(jac.expect("n > 0"))
}

/// Minimise `½‖r(x)‖²` from `x0` by Levenberg–Marquardt (see the module
/// documentation for the step, the damping, the stopping rules and the
/// treatment of unidentifiable parameters).
///
/// `residual_and_jacobian(x)` returns `(r(x), J(x))` with `J` of size
/// `m × x.len()`; `m` must not change between calls.
///
/// Errors: `InvalidParameter` (message starting with `levenberg_marquardt:`)
/// for an empty `x0`, invalid options, an empty residual, a residual or
/// Jacobian that is not finite at `x0`, or a residual/Jacobian size mismatch
/// at any point; errors returned by the closure are passed on.
pub fn levenberg_marquardt<F>(
    residual_and_jacobian: F,
    x0: &[f64],
    opts: &LmOptions,
) -> Result<LmResult>
where
    F: FnMut(&[f64]) -> Result<(DVector<f64>, DMatrix<f64>)>,
{
    levenberg_marquardt_on(
        &mut Together {
            f: residual_and_jacobian,
            jacobian: None,
        },
        x0,
        opts,
    )
}

/// A nonlinear least-squares problem `min_x ½‖r(x)‖²` for
/// [`levenberg_marquardt_on`], whose Jacobian is asked for separately: only
/// at `x0` and at the points the method accepts.
pub trait LeastSquares {
    /// `r(x)`, of the same length `m` at every point.
    fn residual(&mut self, x: &[f64]) -> Result<DVector<f64>>;
    /// `J(x)` (`m × x.len()`), asked for right after `residual(x)` at the
    /// same `x`.
    fn jacobian(&mut self, x: &[f64]) -> Result<DMatrix<f64>>;
}

/// A closure returning `(r, J)` together, as a [`LeastSquares`]: the
/// Jacobian of the last residual is kept until it is asked for.
struct Together<F> {
    f: F,
    jacobian: Option<DMatrix<f64>>,
}

impl<F> LeastSquares for Together<F>
where
    F: FnMut(&[f64]) -> Result<(DVector<f64>, DMatrix<f64>)>,
{
    fn residual(&mut self, x: &[f64]) -> Result<DVector<f64>> {
        let (r, j) = (self.f)(x)?;
        check_sizes(&r, &j, r.len(), x.len())?;
        self.jacobian = Some(j);
        Ok(r)
    }

    fn jacobian(&mut self, x: &[f64]) -> Result<DMatrix<f64>> {
        match self.jacobian.take() {
            Some(j) => Ok(j),
            None => Ok((self.f)(x)?.1),
        }
    }
}

/// [`levenberg_marquardt`] on a [`LeastSquares`] problem: the same steps
/// and results, with the Jacobian evaluated only where a step is accepted
/// (a rejected trial costs one residual).
pub fn levenberg_marquardt_on<P: LeastSquares>(
    problem: &mut P,
    x0: &[f64],
    opts: &LmOptions,
) -> Result<LmResult> {
    let n = x0.len();
    if n == 0 {
        return Err(invalid("x0 is empty"));
    }
    if x0.iter().any(|v| !v.is_finite()) {
        return Err(invalid("x0 is not finite"));
    }
    validate_options(opts)?;
    let (r, jac) = start(problem, x0)?;

    // Marquardt scaling and the identifiable subset, both from J(x0).
    let mut d: Vec<f64> = (0..n).map(|j| jac.column(j).norm()).collect();
    let free = select_identifiable(&jac, &d, opts.rank_tol);
    let unidentifiable: Vec<usize> = (0..n).filter(|j| !free.contains(j)).collect();
    for dj in d.iter_mut() {
        if *dj == 0.0 {
            *dj = 1.0;
        }
    }
    let mut st = LmState {
        x: x0.to_vec(),
        cost: 0.5 * r.norm_squared(),
        r,
        jac,
        d,
        lambda: opts.lambda0,
        nu: 2.0,
        iterations: 0,
        evaluations: 1,
    };
    let stop = loop {
        let Some(lin) = st.linearise(&free, opts) else {
            break LmStop::SmallGradient;
        };
        if let Some(stop) = st.trial_steps(problem, &lin, &free, opts)? {
            break stop;
        }
    };

    let m = st.r.len();
    let rms = (2.0 * st.cost / m as f64).sqrt();
    let rank = numerical_rank(&st.jac, opts.rank_tol);
    let std_errors = standard_errors(&st.jac, &free, n, rms, opts.rank_tol);
    Ok(LmResult {
        x: st.x,
        cost: st.cost,
        rms,
        iterations: st.iterations,
        evaluations: st.evaluations,
        stop,
        rank,
        unidentifiable,
        std_errors,
    })
}

/// The residual and Jacobian at `x0`, checked: a non-empty residual, sizes
/// that agree, finite values.
fn start<P: LeastSquares>(problem: &mut P, x0: &[f64]) -> Result<(DVector<f64>, DMatrix<f64>)> {
    let r = problem.residual(x0)?;
    let jac = problem.jacobian(x0)?;
    let m = r.len();
    if m == 0 {
        return Err(invalid("the residual vector is empty"));
    }
    check_sizes(&r, &jac, m, x0.len())?;
    if r.iter().any(|v| !v.is_finite()) {
        return Err(invalid("the residual at x0 is not finite"));
    }
    if jac.iter().any(|v| !v.is_finite()) {
        return Err(invalid("the Jacobian at x0 is not finite"));
    }
    Ok((r, jac))
}

/// The iterate of [`levenberg_marquardt`]: the point, its residual and
/// Jacobian, the cost `C = ½‖r‖²`, the Marquardt scaling `d`, the damping
/// `λ` and its growth factor `ν`, and the counters.
struct LmState {
    x: Vec<f64>,
    r: DVector<f64>,
    jac: DMatrix<f64>,
    cost: f64,
    d: Vec<f64>,
    lambda: f64,
    nu: f64,
    iterations: usize,
    evaluations: usize,
}

/// A point, its residual, Jacobian and cost.
type Point = (Vec<f64>, DVector<f64>, DMatrix<f64>, f64);

/// The linear model at the current point, in the scaled free variables:
/// `J D⁻¹ = Q R`, `Qᵀ r` (its first `p` rows) and `‖D x‖`.
struct Linearisation {
    rr: DMatrix<f64>,
    qtr: DVector<f64>,
    dx_norm: f64,
}

impl LmState {
    /// The QR of the scaled Jacobian of the free parameters, or `None` when
    /// the scaled gradient `‖D⁻¹ Jᵀ r‖_∞ ≤ tol_grad` (or nothing is free).
    fn linearise(&self, free: &[usize], opts: &LmOptions) -> Option<Linearisation> {
        let (m, k, d) = (self.r.len(), free.len(), &self.d);
        let js = DMatrix::from_fn(m, k, |i, c| self.jac[(i, free[c])] / d[free[c]]);
        let g = js.tr_mul(&self.r);
        if k == 0 || g.amax() <= opts.tol_grad {
            return None;
        }
        let qr = js.qr();
        let rr = qr.r();
        let p = rr.nrows();
        let mut qtr_full = self.r.clone();
        qr.q_tr_mul(&mut qtr_full);
        let qtr = qtr_full.rows(0, p).into_owned();
        let dx_norm = free
            .iter()
            .map(|&j| (d[j] * self.x[j]).powi(2))
            .sum::<f64>()
            .sqrt();
        Some(Linearisation { rr, qtr, dx_norm })
    }

    /// Trial steps at this linearisation until one is accepted (`None`: go
    /// on from the new point) or a stopping rule holds (`Some`).
    fn trial_steps<P: LeastSquares>(
        &mut self,
        problem: &mut P,
        lin: &Linearisation,
        free: &[usize],
        opts: &LmOptions,
    ) -> Result<Option<LmStop>> {
        let (m, n) = (self.r.len(), self.x.len());
        loop {
            if self.iterations >= opts.max_iter {
                return Ok(Some(LmStop::MaxIterations));
            }
            if !self.lambda.is_finite() {
                return Ok(Some(LmStop::SmallStep));
            }
            let Some(u) = damped_step(&lin.rr, &lin.qtr, self.lambda) else {
                // λ too small for a (numerically) singular R: damp more
                self.lambda = (self.lambda * self.nu).max(f64::MIN_POSITIVE);
                self.nu *= 2.0;
                continue;
            };
            let small_step = u.norm() <= opts.tol_step * (lin.dx_norm + opts.tol_step);
            let ru = &lin.rr * &u;
            let predicted = -lin.qtr.dot(&ru) - 0.5 * ru.norm_squared();
            let mut x_new = self.x.clone();
            for (c, &j) in free.iter().enumerate() {
                x_new[j] += u[c] / self.d[j];
            }
            self.iterations += 1;
            let r_new = problem.residual(&x_new)?;
            self.evaluations += 1;
            if r_new.len() != m {
                return Err(invalid(format_args!(
                    "the residual has {} entries, expected {m}",
                    r_new.len()
                )));
            }
            if r_new.iter().all(|v| v.is_finite()) {
                let cost_new = 0.5 * r_new.norm_squared();
                let actual = self.cost - cost_new;
                // the Jacobian only where the step would be accepted; a
                // Jacobian that is not finite rejects it
                let jac_new = if actual > 0.0 && predicted > 0.0 {
                    let jac = problem.jacobian(&x_new)?;
                    check_sizes(&r_new, &jac, m, n)?;
                    Some(jac).filter(|j| j.iter().all(|v| v.is_finite()))
                } else {
                    None
                };
                if let Some(jac_new) = jac_new {
                    let cost = self.cost;
                    let small = actual <= opts.tol_cost * cost && predicted <= opts.tol_cost * cost;
                    let rho = actual / predicted;
                    self.accept((x_new, r_new, jac_new, cost_new), rho, free);
                    return Ok(if small_step {
                        Some(LmStop::SmallStep)
                    } else if small {
                        Some(LmStop::SmallCostDecrease)
                    } else {
                        None
                    });
                }
            }
            if small_step {
                return Ok(Some(LmStop::SmallStep));
            }
            self.lambda *= self.nu;
            self.nu *= 2.0;
        }
    }

    /// Move to an accepted point `(x, r, J, C)` of gain ratio `rho`:
    /// `λ ← λ · max(1/3, 1 − (2ρ − 1)³)`, `ν ← 2`, `d_j ← max(d_j, ‖J_j‖)`.
    fn accept(&mut self, point: Point, rho: f64, free: &[usize]) {
        let (x, r, jac, cost) = point;
        self.cost = cost;
        self.x = x;
        self.r = r;
        self.jac = jac;
        self.lambda *= (1.0 - (2.0 * rho - 1.0).powi(3)).max(1.0 / 3.0);
        self.lambda = self.lambda.max(f64::MIN_POSITIVE);
        self.nu = 2.0;
        for &j in free {
            self.d[j] = self.d[j].max(self.jac.column(j).norm());
        }
    }
}

fn validate_options(o: &LmOptions) -> Result<()> {
    for (name, v) in [
        ("tol_step", o.tol_step),
        ("tol_grad", o.tol_grad),
        ("tol_cost", o.tol_cost),
    ] {
        if !(v.is_finite() && v >= 0.0) {
            return Err(invalid(format_args!(
                "{name} = {v}, must be finite and ≥ 0"
            )));
        }
    }
    if !(o.lambda0.is_finite() && o.lambda0 > 0.0) {
        return Err(invalid(format_args!(
            "lambda0 = {}, must be finite and > 0",
            o.lambda0
        )));
    }
    if !(0.0..1.0).contains(&o.rank_tol) {
        return Err(invalid(format_args!(
            "rank_tol = {}, must be in [0, 1)",
            o.rank_tol
        )));
    }
    Ok(())
}

fn check_sizes(r: &DVector<f64>, jac: &DMatrix<f64>, m: usize, n: usize) -> Result<()> {
    if r.len() != m {
        return Err(invalid(format_args!(
            "the residual has {} entries, expected {m}",
            r.len()
        )));
    }
    if jac.nrows() != m || jac.ncols() != n {
        return Err(invalid(format_args!(
            "the Jacobian is {}×{}, expected {m}×{n} (residuals × parameters)",
            jac.nrows(),
            jac.ncols()
        )));
    }
    Ok(())
}

/// `J` with column `j` divided by `norms[j]` (zero columns stay zero).
fn normalised(jac: &DMatrix<f64>, norms: &[f64]) -> DMatrix<f64> {
    let mut a = jac.clone();
    for (j, &s) in norms.iter().enumerate() {
        if s > 0.0 {
            a.column_mut(j).unscale_mut(s);
        } else {
            a.column_mut(j).fill(0.0);
        }
    }
    a
}

/// Singular values (descending) and, if asked, `Vᵀ` of `a` (non-empty).
fn svd(a: DMatrix<f64>, compute_v: bool) -> SVD<f64, nalgebra::Dyn, nalgebra::Dyn> {
    SVD::try_new(a, false, compute_v, f64::EPSILON, 0).expect("SVD without iteration limit")
}

/// Rank of the column-normalised `jac`: singular values `> rank_tol · σ_max`.
fn numerical_rank(jac: &DMatrix<f64>, rank_tol: f64) -> usize {
    let norms: Vec<f64> = jac.column_iter().map(|c| c.norm()).collect();
    let a = normalised(jac, &norms);
    let s = svd(a, false).singular_values;
    let smax = s.max();
    if smax <= 0.0 {
        return 0;
    }
    s.iter().filter(|&&v| v > rank_tol * smax).count()
}

/// Indices (ascending) of the parameters to fit: all of them if the
/// column-normalised `J` has full numerical rank, otherwise `rank` of them
/// chosen by greedy column pivoting with near-ties going to the lower index.
fn select_identifiable(jac: &DMatrix<f64>, norms: &[f64], rank_tol: f64) -> Vec<usize> {
    let n = jac.ncols();
    let rank = numerical_rank(jac, rank_tol);
    if rank == n {
        return (0..n).collect();
    }
    let mut cols: Vec<DVector<f64>> = normalised(jac, norms)
        .column_iter()
        .map(|c| c.into_owned())
        .collect();
    let mut kept = Vec::with_capacity(rank);
    let mut taken = vec![false; n];
    for _ in 0..rank {
        let mut best: Option<(usize, f64)> = None;
        for (j, c) in cols.iter().enumerate() {
            if taken[j] {
                continue;
            }
            let nj = c.norm();
            if best.is_none_or(|(_, nb)| nj > nb * (1.0 + 1e-8)) {
                best = Some((j, nj));
            }
        }
        let Some((p, np)) = best else { break };
        if np <= 0.0 {
            break;
        }
        taken[p] = true;
        kept.push(p);
        let q = &cols[p] / np;
        for (j, c) in cols.iter_mut().enumerate() {
            if !taken[j] {
                // project twice ("twice is enough") for orthogonality
                for _ in 0..2 {
                    let a = q.dot(c);
                    c.axpy(-a, &q, 1.0);
                }
            }
        }
    }
    kept.sort_unstable();
    kept
}

/// Solve `min ‖[R; √λ I] u + [qtr; 0]‖` by QR of the stacked matrix.
fn damped_step(rr: &DMatrix<f64>, qtr: &DVector<f64>, lambda: f64) -> Option<DVector<f64>> {
    let (p, k) = rr.shape();
    let sl = lambda.sqrt();
    let mut a = DMatrix::zeros(p + k, k);
    a.view_mut((0, 0), (p, k)).copy_from(rr);
    for i in 0..k {
        a[(p + i, i)] = sl;
    }
    let mut b = DVector::zeros(p + k);
    b.rows_mut(0, p).copy_from(qtr);
    b.neg_mut();
    let qr = a.qr();
    qr.q_tr_mul(&mut b);
    let top = qr.r();
    let u = top.solve_upper_triangular(&b.rows(0, k).into_owned())?;
    u.iter().all(|v| v.is_finite()).then_some(u)
}

/// `sqrt(diag((J_fᵀJ_f)⁺)) · rms` for the free parameters, `∞` for the rest.
fn standard_errors(
    jac: &DMatrix<f64>,
    free: &[usize],
    n: usize,
    rms: f64,
    rank_tol: f64,
) -> Vec<f64> {
    let mut out = vec![f64::INFINITY; n];
    if free.is_empty() {
        return out;
    }
    let jf = jac.select_columns(free.iter());
    let s: Vec<f64> = jf.column_iter().map(|c| c.norm()).collect();
    let dec = svd(normalised(&jf, &s), true);
    let sv = &dec.singular_values;
    let vt = dec.v_t.as_ref().expect("V computed");
    let smax = sv.max();
    if smax <= 0.0 {
        return out;
    }
    for (c, &j) in free.iter().enumerate() {
        if s[c] <= 0.0 {
            continue;
        }
        let mut var = 0.0;
        let mut covered = 0.0;
        let mut lost = false;
        for (kk, &sk) in sv.iter().enumerate() {
            let v = vt[(kk, c)];
            covered += v * v;
            if sk > rank_tol * smax {
                var += (v / sk).powi(2);
            } else if v.abs() > 1e-6 {
                lost = true;
            }
        }
        // fewer singular values than parameters (m < k): part of this
        // parameter's direction is in the null space
        lost |= 1.0 - covered > 1e-10;
        let se = var.sqrt() / s[c] * rms;
        if !lost && se.is_finite() {
            out[j] = se;
        }
    }
    out
}
