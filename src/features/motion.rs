//! The memory of a joint's moves into each pose ([`Feature::Moves`],
//! [`Feature::MovesJacobian`]): `h_k = Δq_k + keep_k·h_(k−1)`, with the
//! share kept counted in poses (`e^(−1/τ)`) or in time ([`Clock`]).

use super::Feature;
use crate::dataset::Dataset;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// The memory of a joint's moves counted in time ([`Feature::Moves`]): each
/// earlier move decays by `e^(−Δt/τ_s)` over the interval `Δt` between two
/// poses, from a time column. A robot that pauses between poses settles
/// further than one that goes on at once; a memory in poses cannot tell.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Clock {
    /// The time column's name (seconds).
    pub column: String,
    /// Memory τ_s, seconds (> 0).
    pub tau_s: f64,
    /// Interval between poses where none is measured (predictions from poses
    /// alone: the campaign's median interval); `None`: such predictions are
    /// refused.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub interval_s: Option<f64>,
}

impl Clock {
    pub(super) fn validate(&self, joint: usize) -> Result<()> {
        let ok = |v: f64| v.is_finite() && v > 0.0;
        if !ok(self.tau_s)
            || self
                .interval_s
                .is_some_and(|v| !(v.is_finite() && v >= 0.0))
        {
            return Err(Error::InvalidParameter(format!(
                "moves of joint {joint}: the clock's tau_s must be finite and > 0 and its interval_s finite and ≥ 0, got {} and {:?}",
                self.tau_s, self.interval_s
            )));
        }
        Ok(())
    }

    /// The share of the earlier moves kept at each row of `data`:
    /// `e^(−Δt/τ_s)` over the intervals of its time column (0 for the first
    /// row; a negative interval counts as 0).
    pub(super) fn keep_in(&self, data: &Dataset) -> Result<Vec<f64>> {
        let t = Feature::Covariate {
            name: self.column.clone(),
            reference: None,
        }
        .columns(data)?
        .remove(0);
        Ok((0..t.len())
            .map(|i| {
                if i == 0 {
                    0.0
                } else {
                    (-(t[i] - t[i - 1]).max(0.0) / self.tau_s).exp()
                }
            })
            .collect())
    }

    /// The same at the reference interval, for `m` poses without times.
    pub(super) fn keep_at_reference(&self, m: usize, joint: usize) -> Result<Vec<f64>> {
        let dt = self.interval_s.ok_or_else(|| {
            Error::InvalidParameter(format!(
                "the model uses the moves of joint {joint} with a memory in time column '{}': predict from a CSV that has that column",
                self.column
            ))
        })?;
        Ok(steady_keep(m, (-dt / self.tau_s).exp()))
    }
}

pub(super) fn moves_name(joint: usize, tau_poses: f64, clock: Option<&Clock>) -> String {
    if let Some(c) = clock {
        format!("moves{joint}(τ={:.3}s)", c.tau_s)
    } else if tau_poses > 0.0 {
        format!("moves{joint}(τ={tau_poses:.2})")
    } else {
        format!("move{joint}")
    }
}

/// The share `k` of the earlier moves kept at each of `m` rows (0 for the
/// first).
fn steady_keep(m: usize, k: f64) -> Vec<f64> {
    (0..m).map(|i| if i == 0 { 0.0 } else { k }).collect()
}

/// The memory of a joint's moves along `m` poses without times: `e^(−1/τ)`
/// in poses (τ = 0: none), or the clock's at its reference interval.
pub(super) fn memory(
    m: usize,
    joint: usize,
    tau_poses: f64,
    clock: &Option<Clock>,
) -> Result<Vec<f64>> {
    match clock {
        Some(c) => c.keep_at_reference(m, joint),
        None if tau_poses > 0.0 => Ok(steady_keep(m, (-1.0 / tau_poses).exp())),
        None => Ok(steady_keep(m, 0.0)),
    }
}

/// Joint `joint`'s moves into each pose `q` with the memory `keep`: one
/// column, or through `robot`'s position Jacobian the TCP displacement
/// (three columns).
pub(super) fn moves_columns(
    q: &[Vec<f64>],
    joint: usize,
    robot: Option<&crate::kinematics::Robot>,
    keep: &[f64],
) -> Result<Vec<Vec<f64>>> {
    let h = moves(q, joint, keep);
    let Some(r) = robot else {
        return Ok(vec![h]);
    };
    let mut cols: Vec<Vec<f64>> = (0..3).map(|_| Vec::with_capacity(q.len())).collect();
    for (qi, hi) in q.iter().zip(&h) {
        let jac = r.position_jacobian(qi)?;
        for (a, c) in cols.iter_mut().enumerate() {
            c.push(jac[(a, joint - 1)] * hi);
        }
    }
    Ok(cols)
}

/// `h_k = Δq_k + keep_k·h_(k−1)` of 1-based joint `joint` (Δq_0 = 0).
fn moves(q: &[Vec<f64>], joint: usize, keep: &[f64]) -> Vec<f64> {
    let j = joint - 1;
    let mut h = 0.0;
    (0..q.len())
        .map(|i| {
            let step = if i == 0 { 0.0 } else { q[i][j] - q[i - 1][j] };
            h = step + keep[i] * h;
            h
        })
        .collect()
}
