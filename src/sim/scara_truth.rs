//! The seed 000 parameters a perfect identification would find on a
//! simulated SCARA — for *checking* `physics::identify_scara`, never used by it.

use super::TrueRobot;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Effective `ΔL1`, `ΔL2`, `θ20` of a simulated SCARA and its true angular
/// positioning deviation in the convention of seed 000 eq 11 (relative to the
/// mean of both directions at the rest angle).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaraTruth {
    /// Effective length error of link 1, `ΔL1` (J1–J2 distance in the TCP's
    /// horizontal plane minus the nominal L1), mm.
    pub dl1_mm: f64,
    /// Effective length error of link 2, `ΔL2` (J2–TCP distance in that plane
    /// minus the nominal L2), mm.
    pub dl2_mm: f64,
    /// Effective angular offset of J2, `θ20` (seed 000 eq 14), degrees in [−180, 180).
    pub theta20_deg: f64,
    /// Rest pose of the indexing tests.
    pub rest: Vec<f64>,
}

impl ScaraTruth {
    /// Geometry of `robot` (J1, J2 the SCARA axes) with the other joints at
    /// `rest`, measured in the horizontal plane of the TCP (where a tracker
    /// sees it): a J2 axis tilted by β shifts by `h·tan β` at height `h`.
    pub fn of(robot: &TrueRobot, rest: &[f64]) -> Self {
        let n = robot.dof();
        // J2 at its rest angle turned by the direction-mean deviation
        let mut qa: Vec<f64> = (0..n)
            .map(|j| rest[j] + 0.5 * (mean_dev(robot, j, rest[j])))
            .collect();
        qa[0] = 0.0;
        let frames = robot.actual.frames(&qa);
        let tcp = frames[n + 1].translation.vector;
        // the J2 axis line where it crosses the TCP's height (it may be tilted)
        let o = frames[1].translation.vector;
        let z = frames[1].rotation * Vector3::z();
        let j2 = o + z * ((tcp.z - o.z) / z.z);
        let l1 = robot.nominal.links[0].a_mm;
        let l2 = robot.nominal.links[1].a_mm;
        let v2 = tcp - j2;
        let ang = |v: &Vector3<f64>| v.y.atan2(v.x);
        let mut t20 = (ang(&v2) - ang(&j2)).to_degrees() - rest[1];
        t20 = (t20 + 180.0).rem_euclid(360.0) - 180.0;
        ScaraTruth {
            dl1_mm: j2.x.hypot(j2.y) - l1,
            dl2_mm: v2.x.hypot(v2.y) - l2,
            theta20_deg: t20,
            rest: rest.to_vec(),
        }
    }

    /// True `Δθ_map(θ*, λ)` of joint `j` (0-based), degrees.
    pub fn apd(robot: &TrueRobot, j: usize, rest: f64, q: f64, dir: f64) -> f64 {
        robot.deviation[j].at(q, dir) - 0.5 * mean_dev(robot, j, rest)
    }
}

/// `Δθ(q, +1) + Δθ(q, −1)` (twice the direction mean).
fn mean_dev(robot: &TrueRobot, j: usize, q: f64) -> f64 {
    robot.deviation[j].at(q, 1.0) + robot.deviation[j].at(q, -1.0)
}
