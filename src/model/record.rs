//! Which robot a model was fitted for, so that a model is never applied to
//! another robot or tool.

use super::ErrorModel;
use crate::kinematics::Robot;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Which robot a model was fitted for: its name, the digest of its kinematic
/// table ([`crate::kinematics::table_digest`]) and its tool. A model predicts
/// the TCP error of that robot with that tool only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotRecord {
    /// The robot's name.
    pub name: String,
    /// Digest of the MD-H table and base frame.
    pub table_digest: String,
    /// Flange ← TCP: translation (mm) and roll–pitch–yaw (degrees).
    pub tool: crate::kinematics::FrameSpec,
    /// Which joints are prismatic (their values in mm, not degrees); empty
    /// in model files written before it was recorded.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub prismatic: Vec<bool>,
}

/// Tool frames closer than this (mm, and degrees) are the same tool.
const TOOL_TOLERANCE: f64 = 1e-6;

impl RobotRecord {
    /// The record of `robot`.
    pub fn of(robot: &Robot) -> Self {
        RobotRecord {
            name: robot.name.clone(),
            table_digest: crate::kinematics::table_digest(robot),
            tool: crate::kinematics::FrameSpec::of(&robot.tool),
            prismatic: robot.prismatic_joints(),
        }
    }

    /// Error unless `robot` has this record's kinematic table and tool; the
    /// message names both robots (`source_name`: the model file).
    pub fn check(&self, robot: &Robot, source_name: &str) -> Result<()> {
        let other = RobotRecord::of(robot);
        let refuse = |what: String| {
            Err(Error::Input {
                source_name: source_name.into(),
                message: format!(
                    "the model was fitted for robot '{}' but the robot given is '{}': {what}; give the robot (and --tool) the campaign was measured with, or refit",
                    self.name, other.name
                ),
            })
        };
        if other.table_digest != self.table_digest {
            return refuse(format!(
                "their kinematic tables differ (digest {} vs {})",
                self.table_digest, other.table_digest
            ));
        }
        let dist =
            |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max);
        if dist(self.tool.xyz_mm, other.tool.xyz_mm) > TOOL_TOLERANCE
            || dist(self.tool.rpy_deg, other.tool.rpy_deg) > TOOL_TOLERANCE
        {
            return refuse(format!(
                "their tools differ ({:?} mm vs {:?} mm)",
                self.tool.xyz_mm, other.tool.xyz_mm
            ));
        }
        Ok(())
    }
}

impl ErrorModel {
    /// Record the robot (and tool) the campaign was measured with, so that
    /// commands given another robot refuse the model ([`RobotRecord::check`]).
    /// Error if the robot's joint count differs from the model's.
    pub fn record_robot(&mut self, robot: &Robot) -> Result<()> {
        if robot.dof() != self.n_joints() {
            return Err(Error::JointCount {
                expected: self.n_joints(),
                got: robot.dof(),
            });
        }
        self.robot = Some(RobotRecord::of(robot));
        Ok(())
    }

    /// Error if the model records a robot other than `robot`, or has another
    /// joint count (`source_name`: the model file, for the message). A model
    /// that records no robot passes on its joint count alone.
    pub fn check_robot(&self, robot: &Robot, source_name: &str) -> Result<()> {
        if robot.dof() != self.n_joints() {
            return Err(Error::Input {
                source_name: source_name.into(),
                message: format!(
                    "the model has {} joints but robot '{}' has {}",
                    self.n_joints(),
                    robot.name,
                    robot.dof()
                ),
            });
        }
        match &self.robot {
            Some(r) => r.check(robot, source_name),
            None => Ok(()),
        }
    }

    /// Which of the recorded robot's joints are prismatic, from `robot`
    /// (already checked to be that robot), when the file predates the
    /// record of it: the units of the coverage warnings.
    pub(crate) fn fill_joint_kinds(&mut self, robot: &Robot) {
        if let Some(r) = self.robot.as_mut().filter(|r| r.prismatic.is_empty()) {
            r.prismatic = robot.prismatic_joints();
        }
    }
}
