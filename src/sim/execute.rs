//! Running a commanded trajectory on the true robot and measuring it, as the
//! check of a compensation (seed 004 §IV.B.3): the controller solves the
//! *nominal* inverse kinematics of every command (seeded from the previous
//! point), the joints reach their actual values (angular deviation with the
//! λ of the visiting order, compliance) plus repeatability noise, and the
//! tracker adds its noise to the true TCP position.

use super::{Effect, TrueRobot, gaussian};
use crate::Result;
use crate::kinematics::{IkOptions, all_reached, first_pass_joints};
use crate::space::derive_directions;
use crate::trajectory::Trajectory;
use nalgebra::Vector3;
use rand::Rng;

/// What a run of a trajectory produced.
#[derive(Debug, Clone, PartialEq)]
pub struct Execution {
    /// Nominal IK joints of the commands (degrees or mm), one row per point.
    pub joints: Vec<Vec<f64>>,
    /// Direction coefficients λ (±1) of those joints in visiting order.
    pub dir: Vec<Vec<f64>>,
    /// Measured TCP positions (with noise), mm.
    pub measured: Vec<[f64; 3]>,
}

/// Execute `commands` on `robot` starting from joints `start`, in the state
/// at the start of a campaign (default pose context: no payload, reference
/// temperature, no tracker step) but with the joint-side `effects` (gear
/// harmonic, cross-talk, hysteresis, servo lag) that act whenever the robot
/// moves, drawing the noise
/// from `rng`.
/// The controller's IK seeds each point from `hints` (if given), then from the
/// previous point, the start and the home pose ([`first_pass_joints`]).
pub fn execute(
    robot: &TrueRobot,
    commands: &Trajectory,
    start: &[f64],
    hints: Option<&[Vec<f64>]>,
    effects: &[Effect],
    rng: &mut impl Rng,
) -> Result<Execution> {
    let nominal = &robot.nominal;
    nominal.check_len(start)?;
    let joints = all_reached(first_pass_joints(
        nominal,
        commands.has_orientation,
        &commands.poses,
        start,
        hints,
        &IkOptions::default(),
    ))?;
    let dir = derive_directions(&joints, Some(start));
    let travel = super::effects::travel_since_reversal(&joints, &dir, Some(start));
    let lag = super::effects::lag_deviations(effects, &joints, start);
    let ctx = Default::default();
    let measured = joints
        .iter()
        .zip(&dir)
        .zip(&travel)
        .zip(lag)
        .map(|(((q, d), s), lagged)| {
            let mut qa = robot.actual_joints(q, d, &ctx);
            let mut extra = lagged;
            for e in effects {
                e.joint_deviation(q, &mut extra);
                e.history_deviation(d, s, &mut extra);
            }
            for (a, x) in qa.iter_mut().zip(&extra) {
                *a += x + gaussian(rng, robot.noise.repeatability_sigma_deg);
            }
            let p = robot.tcp(&qa, &ctx);
            let sigma = robot.noise.tracker_sigma(&p);
            (p + Vector3::from_fn(|_, _| gaussian(rng, sigma))).into()
        })
        .collect();
    Ok(Execution {
        joints,
        dir,
        measured,
    })
}
