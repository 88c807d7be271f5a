//! An identified SCARA model against the simulator's truth: for *checking*
//! the identification on simulated data (`physics identify --truth`), never
//! used by it.

use super::{Geometry, PhysicsModel};
use crate::sim::{ScaraTruth, TrueRobot};
use serde::Serialize;

/// A SCARA model's identification against the true robot it was simulated
/// on: the true effective geometry (compare with the model's
/// [`ScaraGeometry`](super::ScaraGeometry)) and each APD table's error.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TruthCheck {
    /// The true `ΔL1`, `ΔL2`, `θ20` at the model's rest pose.
    pub truth: ScaraTruth,
    /// Every joint with an APD table, in joint order.
    pub apd: Vec<ApdCheck>,
}

/// The error (identified − true) of one joint's APD table over its entries.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ApdCheck {
    /// The joint, 1-based.
    pub joint: usize,
    /// Root mean square of the entries' errors, degrees.
    pub rms_deg: f64,
    /// Largest absolute error of an entry, degrees.
    pub max_deg: f64,
    /// Entries compared (both directions of every angle).
    pub entries: usize,
}

impl PhysicsModel {
    /// This model against the true robot `truth` ([`ScaraTruth`]); `None`
    /// unless it has a SCARA geometry (seed 000).
    pub fn check_against(&self, truth: &TrueRobot) -> Option<TruthCheck> {
        let Geometry::Scara(g) = &self.geometry else {
            return None;
        };
        let mut apd = Vec::new();
        for (j, tab) in self.apd.iter().enumerate() {
            let Some(tab) = tab else { continue };
            let (mut sq, mut mx, mut k) = (0.0, 0.0_f64, 0);
            for (i, q) in tab.angles_deg.iter().enumerate() {
                for (d, v) in [(1.0, tab.plus[i]), (-1.0, tab.minus[i])] {
                    let e = v - ScaraTruth::apd(truth, j, g.rest[j], *q, d);
                    sq += e * e;
                    mx = mx.max(e.abs());
                    k += 1;
                }
            }
            apd.push(ApdCheck {
                joint: j + 1,
                rms_deg: (sq / k as f64).sqrt(),
                max_deg: mx,
                entries: k,
            });
        }
        Some(TruthCheck {
            truth: ScaraTruth::of(truth, &g.rest),
            apd,
        })
    }
}
