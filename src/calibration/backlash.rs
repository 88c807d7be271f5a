//! The backlash of the joints: the play of a joint's gears.
//!
//! A joint with play stops short of its commanded value by the same amount
//! from either side. Approached in the direction `λ_j = ±1` (the direction
//! it last moved, the campaign's `dir` columns), joint `j` reaches
//!
//! ```text
//! q_j + b_j λ_j        (b_j the half backlash, degrees; mm for a prismatic joint),
//! ```
//!
//! and, to first order, the TCP moves by `J_j(q) b_j λ_j`: a column of the
//! identification Jacobian (the joint's offset `Δθ_off`) with its sign
//! flipped at every pose approached from below.
//!
//! # Why the calibration identifies it
//!
//! A campaign's directions are not random with respect to its poses: a
//! joint reaches the poses of one region from one side, those of another
//! from the other. A geometric calibration that lacks the backlash then
//! bends its MD-H, tool and base errors to take up part of it, and the
//! bent parameters are wrong where the campaign did not measure. On a
//! simulated UR10 campaign of four ISO 9283 cubes, each cube held out in
//! turn, the calibrated models (Kriging JS / EJS of the calibration's
//! residual) went from 0.444 / 0.405 to 0.095 / 0.099 mm held-out mean 3D
//! error (`holdout --groups cube --backlash`). It is off
//! by default ([`super::CalibrationOptions::backlash`]): on UR10 series B
//! the search keeps joints whose "backlash" stands for other structure,
//! and the calibrated Kriging models got worse; on two 100 mm cubes it
//! made the far poses worse.
//!
//! # Which joints: a forward search tied to the noise
//!
//! On the residual `r` (3m, stacked x, y, z per pose) of the geometric
//! fit, each joint that the campaign approaches from both sides gives one
//! column `b_j = J_j(q) λ_j`. With `b̃_j` the column made orthogonal to the
//! geometric directions the campaign sees and to the joints already kept
//! (Frisch–Waugh), keeping it lowers the residual sum of squares by
//! `Δ = (b̃_jᵀ r)² / b̃_jᵀ b̃_j`, which is `s²·χ²₁` without a backlash (`s²`
//! the residual variance per coordinate, re-estimated from what is left
//! after each joint kept). The joint of largest `Δ` is kept
//! while `Δ / s²` passes the level-`α/n` bound of χ²₁ (Laurent & Massart's,
//! as for the joint harmonics; `α =` [`super::harmonics::FALSE_ALARM`],
//! `n` the joints searched: Bonferroni over them). The half backlashes are
//! then the least squares of `r` on the kept columns beside the geometric
//! directions, with covariance `s² (B̃ᵀB̃)⁻¹`; the caller refits the
//! geometry on the joints as they are reached, along the same directions.
//!
//! Kept as identified instead (the backlash fitted to what the geometry
//! leaves), the geometry holds the part of a backlash that acts as a joint
//! offset over the campaign's directions, and poses approached otherwise
//! are off by it.

use super::harmonics::{Basis, FALSE_ALARM, chi2_bound};
use crate::Result;
use nalgebra::{DMatrix, DVector, Matrix3xX};
use serde::{Deserialize, Serialize};

/// The half backlash of one joint: it reaches `q + b·λ`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointBacklash {
    /// 1-based joint.
    pub joint: usize,
    /// The half backlash `b`, degrees (mm for a prismatic joint).
    pub half_deg: f64,
    /// `Δ / s²` when it was kept: χ²₁ if there were no backlash.
    pub evidence: f64,
    /// RMS over the campaign's poses of the TCP displacement it causes (3D,
    /// mm): what it matters at the tool, whatever the joint's lever.
    pub tcp_rms_mm: f64,
}

impl JointBacklash {
    /// The half backlash with its unit on `robot`: degrees, or mm for a
    /// prismatic joint.
    pub fn display_on(&self, robot: &crate::kinematics::Robot) -> String {
        let unit = robot.joint_unit(self.joint.wrapping_sub(1));
        format!("{:+.4}{unit}", self.half_deg)
    }

    /// Error unless the joint is one of `n` and the half backlash finite.
    pub fn validate(&self, n: usize) -> std::result::Result<(), String> {
        if self.joint == 0 || self.joint > n {
            return Err(format!(
                "a backlash of joint {} on a {n}-joint robot",
                self.joint
            ));
        }
        if !self.half_deg.is_finite() {
            return Err(format!("the backlash of q{} is not finite", self.joint));
        }
        Ok(())
    }
}

/// `λ` as ±1, or 0 for a zero or missing direction (not `f64::signum`,
/// which is 1 at zero).
fn sign(lambda: Option<f64>) -> f64 {
    match lambda {
        Some(v) if v > 0.0 => 1.0,
        Some(v) if v < 0.0 => -1.0,
        _ => 0.0,
    }
}

/// The joints `q` as reached from the directions `dir` (`λ_j = ±1`; a zero
/// or a missing direction leaves the joint as commanded).
pub fn reached(backlash: &[JointBacklash], q: &[f64], dir: &[f64]) -> Vec<f64> {
    let mut out = q.to_vec();
    for b in backlash {
        out[b.joint - 1] += b.half_deg * sign(dir.get(b.joint - 1).copied());
    }
    out
}

/// The backlash found on a campaign, with its coefficients' covariance.
#[derive(Debug, Clone)]
pub(crate) struct BacklashFit {
    /// The joints kept, with their half backlash.
    pub backlash: Vec<JointBacklash>,
    /// Covariance of the half backlashes, degrees², row-major `n × n`.
    pub covariance: Vec<f64>,
}

/// The column `J_j(q_k) λ_kj` of joint `j` (0-based), stacked (3m).
pub(crate) fn column(jac: &[Matrix3xX<f64>], dirs: &[Vec<f64>], j: usize) -> DVector<f64> {
    DVector::from_iterator(
        3 * jac.len(),
        jac.iter()
            .zip(dirs)
            .flat_map(|(jq, d)| (0..3).map(move |a| jq[(a, j)] * sign(d.get(j).copied()))),
    )
}

/// Joints the campaign approaches from both sides.
pub(crate) fn reversing(dirs: &[Vec<f64>], n: usize) -> Vec<usize> {
    (0..n)
        .filter(|&j| {
            let pos = dirs.iter().any(|d| d.get(j).is_some_and(|v| *v > 0.0));
            let neg = dirs.iter().any(|d| d.get(j).is_some_and(|v| *v < 0.0));
            pos && neg
        })
        .collect()
}

/// The forward search and fit of the module documentation on the geometric
/// residual `r_geo`, beside the `geometric` directions seen (3m × k), with
/// the per-pose joint Jacobians per degree `jac`. `None` when no joint
/// passes.
pub(crate) fn search(
    jac: &[Matrix3xX<f64>],
    dirs: &[Vec<f64>],
    geometric: &DMatrix<f64>,
    r_geo: &DVector<f64>,
) -> Result<Option<BacklashFit>> {
    let n = jac.first().map_or(0, |j| j.ncols());
    if dirs.len() != jac.len() {
        return Ok(None);
    }
    let candidates = reversing(dirs, n);
    if candidates.is_empty() {
        return Ok(None);
    }
    let bound = chi2_bound(1, FALSE_ALARM / candidates.len() as f64);
    let cols: Vec<DVector<f64>> = candidates.iter().map(|&j| column(jac, dirs, j)).collect();
    // the geometric directions' basis: grown with the joints kept below,
    // and as it is for the coefficients
    let g = Basis::new(geometric.column_iter().map(|c| c.into_owned()), r_geo);
    let mut basis = g.clone();
    let mut kept: Vec<(usize, f64)> = Vec::new();
    loop {
        let noise = basis.noise();
        if !(noise.is_finite() && noise > 0.0) {
            break;
        }
        let best = cols
            .iter()
            .enumerate()
            .filter(|(i, _)| !kept.iter().any(|(k, _)| k == i))
            .map(|(i, c)| {
                let w = basis.project_out(c);
                let ww = w.norm_squared();
                let gain = if ww > 1e-8 * c.norm_squared() {
                    w.dot(basis.residual()).powi(2) / ww
                } else {
                    0.0
                };
                (i, gain / noise)
            })
            .max_by(|a, b| a.1.total_cmp(&b.1));
        match best {
            Some((i, evidence)) if evidence > bound => {
                basis.push(&cols[i]);
                kept.push((i, evidence));
            }
            _ => break,
        }
    }
    if kept.is_empty() {
        return Ok(None);
    }
    kept.sort_by_key(|(i, _)| candidates[*i]);
    let kept: Vec<(usize, usize, f64)> = kept
        .into_iter()
        .map(|(i, evidence)| (candidates[i], i, evidence))
        .collect();
    let noise = basis.noise();
    // the half backlashes beside the geometric directions (Frisch–Waugh)
    let (beta, covariance) = g.fit_beside(
        kept.iter().map(|(_, i, _)| cols[*i].clone()),
        r_geo,
        noise,
        "the joints' backlash columns",
    )?;
    let m = jac.len() as f64;
    Ok(Some(BacklashFit {
        backlash: kept
            .iter()
            .zip(beta.iter())
            .map(|((j, i, evidence), &half)| JointBacklash {
                joint: j + 1,
                half_deg: half,
                evidence: *evidence,
                tcp_rms_mm: (&cols[*i] * half).norm() / m.sqrt(),
            })
            .collect(),
        covariance,
    }))
}

/// At each pose, per axis, the TCP displacement of a unit half backlash of
/// each joint of `backlash` (`out[k][a][i]`), with the joint Jacobians per
/// degree `jac` and the directions `dirs` (a pose without one: zero, the
/// joint at the middle of its play).
pub(crate) fn unit_columns(
    backlash: &[JointBacklash],
    jac: &[Matrix3xX<f64>],
    dirs: &[Vec<f64>],
) -> Vec<[Vec<f64>; 3]> {
    jac.iter()
        .enumerate()
        .map(|(k, jq)| {
            let d = dirs.get(k).map_or(&[][..], Vec::as_slice);
            std::array::from_fn(|a| {
                backlash
                    .iter()
                    .map(|b| {
                        let j = b.joint - 1;
                        jq[(a, j)] * sign(d.get(j).copied())
                    })
                    .collect()
            })
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_joint_reaches_its_value_shifted_by_the_backlash_in_its_direction() {
        let b = [JointBacklash {
            joint: 2,
            half_deg: 0.05,
            evidence: 0.0,
            tcp_rms_mm: 0.0,
        }];
        assert_eq!(reached(&b, &[10.0, 20.0], &[1.0, 1.0]), vec![10.0, 20.05]);
        assert_eq!(reached(&b, &[10.0, 20.0], &[1.0, -1.0]), vec![10.0, 19.95]);
        // no direction known: as commanded
        assert_eq!(reached(&b, &[10.0, 20.0], &[1.0, 0.0]), vec![10.0, 20.0]);
        assert_eq!(reached(&b, &[10.0, 20.0], &[]), vec![10.0, 20.0]);
        assert!(b[0].validate(2).is_ok());
        assert!(b[0].validate(1).is_err());
    }
}
