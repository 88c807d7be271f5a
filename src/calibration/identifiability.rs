//! Which directions of the kinematic parameters a campaign can see.
//!
//! # Scaling: a prior per parameter
//!
//! The identification Jacobian `J` (3m × P, `∂P/∂p` of every measured
//! coordinate, [`crate::kinematics::identification_jacobian`]) mixes mm per
//! degree and mm per mm. Its columns are put on one footing by the prior
//! scale `τ_j` of each parameter: `τ_j` is the change of parameter `j` alone
//! that would move the campaign's TCPs by as much as the whole observed error,
//!
//! ```text
//! τ_j = ρ₀ √(3m) / ‖J_j‖,      ρ₀ = RMS of the measured error per coordinate,
//! ```
//!
//! so that `p = D w`, `D = diag(τ)`, with `w ~ N(0, I)` a priori: no
//! parameter is assumed to explain more than the error that was measured.
//! A parameter that moves no measured coordinate (`‖J_j‖ = 0`) gets `τ_j = 0`
//! and stays nominal.
//!
//! # The identifiable subspace
//!
//! With the thin SVD `J D = U Σ Vᵀ`, the coordinate `c_i = v_iᵀ w` along
//! the right singular vector `v_i` has prior information 1 and data
//! information `σ_i² / s²`, `s` the residual standard deviation per
//! coordinate (measurement noise plus whatever the kinematic model cannot
//! represent). The campaign determines `c_i` better than the prior does when
//!
//! ```text
//! σ_i > s.
//! ```
//!
//! The directions below that threshold are *not seen by this campaign*: they
//! are fixed at their nominal value (`c_i = 0`), which is the truncated-SVD
//! (minimum-norm) solution. The threshold is tied to the noise, not a
//! relative rank constant: a larger or better-spread campaign sees more
//! directions, a noisier one fewer.
//!
//! # Observability indices
//!
//! On the kept singular values `σ_1 ≥ … ≥ σ_k` of the scaled Jacobian:
//! - `O1 = (σ_1 σ_2 ⋯ σ_k)^{1/k} / √m` (Borm & Menq 1991),
//! - `O3 = σ_k` (Nahvi & Hollerbach 1996, the minimum singular value),
//! - the condition number `σ_1 / σ_k` (Driels & Pathre's O2, inverted).

use nalgebra::{DMatrix, DVector};
use serde::{Deserialize, Serialize};

/// The SVD of the scaled identification Jacobian at the nominal parameters.
#[derive(Debug, Clone)]
pub(crate) struct ScaledJacobian {
    /// Prior scale `τ_j` of each parameter (0: not moved by any coordinate).
    pub tau: Vec<f64>,
    /// Singular values `σ_i` of `J D`, descending.
    pub sigma: Vec<f64>,
    /// Right singular vectors `v_i` (P × r, columns in the order of `sigma`).
    pub v: DMatrix<f64>,
}

/// Relative size below which a singular value of the scaled Jacobian is
/// numerically zero: central differences of step `h` resolve a column to
/// about `√ε` relative, so smaller directions are indistinguishable from
/// rounding.
pub(crate) const NUMERICAL_RANK_TOL: f64 = 1.5e-8;

impl ScaledJacobian {
    /// Scale `jac` (3m × P) by the prior of each parameter (`rho0`: RMS of
    /// the measured error per coordinate, mm) and take its SVD.
    pub fn new(jac: &DMatrix<f64>, rho0: f64) -> Self {
        let rows = jac.nrows() as f64;
        let tau: Vec<f64> = (0..jac.ncols())
            .map(|j| {
                let n = jac.column(j).norm();
                if n > 0.0 && n.is_finite() {
                    rho0 * rows.sqrt() / n
                } else {
                    0.0
                }
            })
            .collect();
        let mut scaled = jac.clone();
        for (j, t) in tau.iter().enumerate() {
            scaled.column_mut(j).scale_mut(*t);
        }
        let svd = scaled.svd(false, true);
        let v_t = svd.v_t.expect("SVD asked for V");
        let mut order: Vec<usize> = (0..svd.singular_values.len()).collect();
        order.sort_by(|&a, &b| svd.singular_values[b].total_cmp(&svd.singular_values[a]));
        let sigma: Vec<f64> = order.iter().map(|&i| svd.singular_values[i]).collect();
        let v = DMatrix::from_fn(jac.ncols(), order.len(), |r, c| v_t[(order[c], r)]);
        ScaledJacobian { tau, sigma, v }
    }

    /// Directions above the numerical rank (what any fit can move).
    pub fn numerical_rank(&self) -> usize {
        let top = self.sigma.first().copied().unwrap_or(0.0);
        self.sigma
            .iter()
            .filter(|s| **s > NUMERICAL_RANK_TOL * top)
            .count()
    }

    /// Directions the campaign sees above the noise `s` (and above the
    /// numerical rank).
    pub fn seen_above(&self, s: f64) -> usize {
        self.sigma
            .iter()
            .take(self.numerical_rank())
            .filter(|x| **x > s)
            .count()
    }

    /// The map `T = D V_k` (P × k) from the coordinates `u` of the first `k`
    /// directions to parameter errors `p = T u`.
    pub fn basis(&self, k: usize) -> DMatrix<f64> {
        let mut t = self.v.columns(0, k).into_owned();
        for (j, tau) in self.tau.iter().enumerate() {
            t.row_mut(j).scale_mut(*tau);
        }
        t
    }

    /// The posterior variance of each direction's coordinate `c_i` (in
    /// prior units) with the first `k` fitted and the rest at nominal:
    /// `1 / (1 + σ_i²/s²)` — about `s²/σ_i²` for a direction the campaign
    /// sees, about 1 (the prior) for one it does not.
    pub fn posterior_variances(&self, s: f64) -> Vec<f64> {
        self.sigma
            .iter()
            .map(|x| {
                if s > 0.0 {
                    1.0 / (1.0 + (x / s).powi(2))
                } else {
                    0.0
                }
            })
            .collect()
    }

    /// The report for the first `k` directions kept, residual std `s`,
    /// parameter values `p` named `names`, on `m` poses.
    pub fn report(
        &self,
        k: usize,
        s: f64,
        p: &[f64],
        names: &[String],
        m: usize,
    ) -> Identifiability {
        let kept = &self.sigma[..k];
        let o1 = if k > 0 {
            (kept.iter().map(|x| x.ln()).sum::<f64>() / k as f64).exp() / (m as f64).sqrt()
        } else {
            0.0
        };
        let parameters = names
            .iter()
            .enumerate()
            .map(|(j, name)| {
                let row = self.v.row(j);
                let share: f64 = (0..k).map(|i| row[i] * row[i]).sum();
                // std of p_j = τ_j s ‖(V_k Σ_k⁻¹)_j‖
                let var: f64 = (0..k).map(|i| (row[i] / kept[i]).powi(2)).sum();
                ParameterReport {
                    name: name.clone(),
                    value: p[j],
                    std_error: self.tau[j] * s * var.sqrt(),
                    identified_share: if self.tau[j] > 0.0 { share } else { 0.0 },
                }
            })
            .collect();
        Identifiability {
            parameters_total: names.len(),
            directions_seen: k,
            noise_mm: s,
            singular_values: self.sigma.clone(),
            condition_number: if k > 0 {
                kept[0] / kept[k - 1]
            } else {
                f64::INFINITY
            },
            o1,
            o3: kept.last().copied().unwrap_or(0.0),
            parameters,
        }
    }
}

/// Serde `deserialize_with` for a ratio JSON cannot hold when infinite:
/// `null` (what serde_json writes for a non-finite number) reads as +∞.
fn infinite_when_null<'de, D: serde::Deserializer<'de>>(d: D) -> Result<f64, D::Error> {
    Ok(Option::<f64>::deserialize(d)?.unwrap_or(f64::INFINITY))
}

/// One calibration parameter: its identified error and how much of it the
/// campaign saw.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ParameterReport {
    /// `theta_off1`, `d1`, …, `tool_x`, …, `base_rz`.
    pub name: String,
    /// Identified error (degrees or mm), added to the nominal value.
    pub value: f64,
    /// Its standard error (degrees or mm), conditional on the directions
    /// fixed at nominal.
    pub std_error: f64,
    /// Share of the parameter's scaled axis inside the identified subspace
    /// (`Σ_{i≤k} V_ji²`): 1 fully identified, 0 fixed at nominal.
    pub identified_share: f64,
}

impl ParameterReport {
    /// Whether the campaign saw most of this parameter (share ≥ ½).
    pub fn identified(&self) -> bool {
        self.identified_share >= 0.5
    }
}

/// What a campaign can identify of a robot's kinematic parameters (see the
/// module documentation for the scaling and the threshold).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Identifiability {
    /// Parameters of the error model (`5n + 9`).
    pub parameters_total: usize,
    /// Directions of the scaled Jacobian the campaign sees above the noise
    /// (`σ_i > s`); the others are fixed at nominal.
    pub directions_seen: usize,
    /// Residual standard deviation per coordinate `s` the threshold used, mm.
    pub noise_mm: f64,
    /// Every singular value of the scaled Jacobian, descending.
    pub singular_values: Vec<f64>,
    /// `σ_1 / σ_k` over the directions kept; infinite when none is kept
    /// (`null` in a model file).
    #[serde(deserialize_with = "infinite_when_null")]
    pub condition_number: f64,
    /// Borm & Menq's observability index `(σ_1 ⋯ σ_k)^{1/k} / √m`.
    pub o1: f64,
    /// Nahvi & Hollerbach's `O3 = σ_k`, the smallest kept singular value.
    pub o3: f64,
    /// Per parameter: value, standard error, identified share.
    pub parameters: Vec<ParameterReport>,
}

impl Identifiability {
    /// Names of the parameters the campaign identified (share ≥ ½).
    pub fn identified_names(&self) -> Vec<&str> {
        self.parameters
            .iter()
            .filter(|p| p.identified())
            .map(|p| p.name.as_str())
            .collect()
    }

    /// Names of the parameters mostly fixed at nominal (share < ½).
    pub fn fixed_names(&self) -> Vec<&str> {
        self.parameters
            .iter()
            .filter(|p| !p.identified())
            .map(|p| p.name.as_str())
            .collect()
    }
}

/// `‖v‖ / √len`: the RMS of a residual vector.
pub(crate) fn rms(v: &DVector<f64>) -> f64 {
    if v.is_empty() {
        0.0
    } else {
        v.norm() / (v.len() as f64).sqrt()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_direction_below_the_noise_is_not_seen() {
        // two parameters: one moves the coordinates strongly, the other is an
        // almost exact copy of the first (their difference is tiny)
        let m = 30;
        let jac = DMatrix::from_fn(m, 2, |r, c| {
            let base = 1.0 + (r as f64 * 0.37).sin();
            if c == 0 {
                base
            } else {
                base + 1e-4 * (r as f64 * 1.3).cos()
            }
        });
        let sj = ScaledJacobian::new(&jac, 0.5);
        assert_eq!(sj.numerical_rank(), 2);
        // the sum direction is seen at any noise the data allow
        assert_eq!(sj.seen_above(0.01), 1);
        // with no noise both are seen
        assert_eq!(sj.seen_above(0.0), 2);
        let rep = sj.report(1, 0.01, &[0.1, 0.1], &["a".into(), "b".into()], m);
        assert_eq!(rep.directions_seen, 1);
        // each parameter is half inside the seen direction (a + b)
        for p in &rep.parameters {
            assert!((p.identified_share - 0.5).abs() < 1e-3, "{p:?}");
        }
        assert!(rep.condition_number == 1.0 && rep.o3 == rep.singular_values[0]);
    }

    #[test]
    fn a_parameter_that_moves_nothing_has_no_prior() {
        let jac = DMatrix::from_fn(12, 2, |r, c| if c == 0 { r as f64 + 1.0 } else { 0.0 });
        let sj = ScaledJacobian::new(&jac, 0.3);
        assert_eq!(sj.tau[1], 0.0);
        assert_eq!(sj.numerical_rank(), 1);
        let t = sj.basis(1);
        assert_eq!(t[(1, 0)], 0.0);
    }
}
