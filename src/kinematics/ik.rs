//! Numerical inverse kinematics: damped least squares (Levenberg–Marquardt
//! damping) on position and, optionally, orientation.
//!
//! Step: `Δq = Jᵀ (J Jᵀ + μ² I)⁻¹ e = (JᵀJ + μ² I)⁻¹ Jᵀ e`, solved in the
//! smaller of the two spaces (joint space for a robot with fewer joints than
//! task rows, e.g. a 4-axis SCARA on a 6-row pose task, where `J Jᵀ` is
//! singular), with `e = [p* − p; L·log(R* Rᵀ)]` where the
//! orientation error is weighted by a length `L` (mm per rad) so both parts are
//! comparable. μ shrinks after an accepted step and grows after a rejected one.
//! Every iterate is clamped into the joint limits. The solver is local: it
//! converges to the solution nearest the seed (the previous trajectory point).

use super::Robot;
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Isometry3, UnitQuaternion, Vector3};

/// What the TCP must reach.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkTarget {
    /// TCP position, mm.
    pub position: Vector3<f64>,
    /// TCP orientation; `None` solves for position only (e.g. 4-axis SCARA, or
    /// a redundant task).
    pub orientation: Option<UnitQuaternion<f64>>,
}

impl IkTarget {
    /// Full pose target.
    pub fn pose(p: &Isometry3<f64>) -> Self {
        IkTarget {
            position: p.translation.vector,
            orientation: Some(p.rotation),
        }
    }

    /// Position-only target.
    pub fn position(p: Vector3<f64>) -> Self {
        IkTarget {
            position: p,
            orientation: None,
        }
    }
}

/// Options of [`Robot::ik`]; `Default` suits mm-scale industrial robots.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct IkOptions {
    /// Iteration cap of the damped least-squares loop.
    pub max_iter: usize,
    /// Position tolerance, mm.
    pub tol_mm: f64,
    /// Orientation tolerance, rad.
    pub tol_rad: f64,
    /// Weight of orientation errors, mm per rad.
    pub orientation_weight_mm: f64,
    /// Initial damping μ (mm).
    pub damping: f64,
}

impl Default for IkOptions {
    fn default() -> Self {
        IkOptions {
            max_iter: 200,
            tol_mm: 1e-7,
            tol_rad: 1e-10,
            orientation_weight_mm: 1000.0,
            damping: 1e-3,
        }
    }
}

impl Robot {
    /// Joint values reaching `target`, starting from `seed` (same units as the
    /// API: degrees / mm). Returns [`Error::IkNotConverged`] when the target is
    /// not reached within the limits and iteration budget.
    pub fn ik(&self, target: &IkTarget, seed: &[f64], opts: &IkOptions) -> Result<Vec<f64>> {
        self.check_len(seed)?;
        let n = self.dof();
        let mut q: Vec<f64> = seed.to_vec();
        self.clamp(&mut q);
        let mut e = self.ik_error(&q, target, opts);
        let mut mu = opts.damping;
        let mut iterations = 0;
        for _ in 0..opts.max_iter {
            iterations += 1;
            if self.ik_done(&e, target, opts) {
                return Ok(q);
            }
            let j = self.task_jacobian(&q, target, opts);
            let Some(dq) = dls_step(&j, &e, mu) else {
                mu *= 10.0;
                continue;
            };
            let mut trial = q.clone();
            for i in 0..n {
                trial[i] += dq[i] / self.unit_scale(i);
            }
            self.clamp(&mut trial);
            let e_trial = self.ik_error(&trial, target, opts);
            if e_trial.norm() < e.norm() {
                q = trial;
                e = e_trial;
                mu = (mu * 0.3).max(1e-9);
            } else {
                mu *= 10.0;
                if mu > 1e9 {
                    break;
                }
            }
        }
        if self.ik_done(&e, target, opts) {
            return Ok(q);
        }
        let pos = e.rows(0, 3).norm();
        let ori = if e.len() > 3 {
            e.rows(3, 3).norm() / opts.orientation_weight_mm
        } else {
            0.0
        };
        Err(Error::IkNotConverged {
            iterations,
            position_mm: pos,
            orientation_rad: ori,
        })
    }

    /// [`Robot::ik`] from each of `seeds` in turn; the first solution wins,
    /// otherwise the last seed's error is returned.
    pub fn ik_from_any(
        &self,
        target: &IkTarget,
        seeds: &[&[f64]],
        opts: &IkOptions,
    ) -> Result<Vec<f64>> {
        let mut last = Err(Error::InvalidParameter("no IK seed given".into()));
        for seed in seeds {
            last = self.ik(target, seed, opts);
            if last.is_ok() {
                break;
            }
        }
        last
    }

    fn clamp(&self, q: &mut [f64]) {
        for (v, (lo, hi)) in q.iter_mut().zip(&self.limits) {
            *v = v.clamp(*lo, *hi);
        }
    }

    fn ik_done(&self, e: &DVector<f64>, target: &IkTarget, opts: &IkOptions) -> bool {
        let pos_ok = e.rows(0, 3).norm() <= opts.tol_mm;
        let ori_ok = target.orientation.is_none()
            || e.rows(3, 3).norm() <= opts.tol_rad * opts.orientation_weight_mm;
        pos_ok && ori_ok
    }

    /// Task-space error `[p* − p; L·log(R* Rᵀ)]` (3 or 6 rows).
    fn ik_error(&self, q: &[f64], target: &IkTarget, opts: &IkOptions) -> DVector<f64> {
        let pose = self.fk_unchecked(q);
        let dp = target.position - pose.translation.vector;
        match target.orientation {
            None => DVector::from_column_slice(dp.as_slice()),
            Some(r) => {
                let w = (r * pose.rotation.inverse()).scaled_axis() * opts.orientation_weight_mm;
                DVector::from_iterator(6, dp.iter().chain(w.iter()).copied())
            }
        }
    }

    fn task_jacobian(&self, q: &[f64], target: &IkTarget, opts: &IkOptions) -> DMatrix<f64> {
        let j = self.jacobian(q).expect("length checked");
        let rows = if target.orientation.is_some() { 6 } else { 3 };
        let mut out = DMatrix::zeros(rows, self.dof());
        for c in 0..self.dof() {
            for r in 0..rows {
                let w = if r >= 3 {
                    opts.orientation_weight_mm
                } else {
                    1.0
                };
                out[(r, c)] = j[(r, c)] * w;
            }
        }
        out
    }
}

/// The damped least-squares step `(JᵀJ + μ² I)⁻¹ Jᵀ e` (= `Jᵀ(JJᵀ + μ² I)⁻¹ e`),
/// by Cholesky of the smaller Gram matrix; `None` if it is not positive definite.
fn dls_step(j: &DMatrix<f64>, e: &DVector<f64>, mu: f64) -> Option<DVector<f64>> {
    let (m, n) = j.shape();
    if n < m {
        let g = j.transpose() * j + DMatrix::identity(n, n) * (mu * mu);
        Some(g.cholesky()?.solve(&(j.transpose() * e)))
    } else {
        let g = j * j.transpose() + DMatrix::identity(m, m) * (mu * mu);
        Some(j.transpose() * g.cholesky()?.solve(e))
    }
}
