//! Serial-robot kinematics on the MD-H chain of seed 003 eq 1 / seed 004 eq 1.
//!
//! Link `i` (joint `i`) contributes
//!
//! `T_i = Rot(z, θ_i) · Tr(z, d_i) · Tr(x, a_i) · Rot(x, α_i) · Rot(y, β_i)`
//!
//! which is the *standard* (distal) Denavit–Hartenberg transform followed by
//! Hayati's extra rotation `β` about the new y axis (β = 0 gives plain D-H, so
//! published D-H tables map over unchanged). The whole chain is
//! `base · T_1 ⋯ T_n · tool`.
//!
//! Units at the API: joint values in **degrees** (revolute) or **mm**
//! (prismatic); lengths in mm. A joint value `q_i` enters the chain as
//! `θ_i = sign_i·q_i + θ_offset_i` (revolute) or `d_i + sign_i·q_i` (prismatic),
//! so a preset can follow its controller's zero and sign conventions.

mod calib;
mod ik;
mod locate;
mod path;
mod presets;
mod robot_file;

pub use calib::{
    ErrorChain, IDENTIFICATION_STEP, apply_errors, calib_len, calib_names, identification_jacobian,
    identification_jacobian_cols,
};
pub use ik::{IkOptions, IkTarget};
pub use locate::{TrackerFit, errors_from_positions, import_for, locate_imported, locate_tracker};
pub use path::{all_reached, first_pass_joints, path_target};
pub use presets::{PRESET_NAMES, preset, preset_file};
pub use robot_file::{
    DEFAULT_REVOLUTE_LIMITS, FrameSpec, JointSpec, RobotFile, load_optional_robot, load_robot,
    load_robot_with_tool, read_robot_file, robot_or_preset_name, table_digest,
};

use crate::{Error, Result};
use nalgebra::{Isometry3, Matrix3xX, Matrix6xX, Translation3, UnitQuaternion, Vector3};

/// The unit of a joint value as a suffix to a number: " mm" for a
/// prismatic joint, "°" for a revolute one (`12.5°`, `190 mm`, as every
/// joint value in a message is written; [`Robot::joint_unit`]).
pub fn unit_suffix(prismatic: bool) -> &'static str {
    if prismatic { " mm" } else { "°" }
}
use serde::{Deserialize, Serialize};

/// What a joint's variable moves.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
pub enum JointKind {
    /// The joint value rotates about the previous frame's z axis (θ).
    Revolute,
    /// The joint value translates along the previous frame's z axis (d).
    Prismatic,
}

/// One link of the MD-H chain (seed 003 eq 1); angles in degrees, lengths in mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct MdhLink {
    /// Whether the joint variable is the angle θ (revolute) or the offset d (prismatic).
    pub kind: JointKind,
    /// Constant added to `sign·q` to give θ (revolute) or the fixed θ (prismatic), degrees.
    pub theta_offset_deg: f64,
    /// Offset along z_{i−1}, mm (for a prismatic joint, added to `sign·q`).
    pub d_mm: f64,
    /// Length along x_i, mm.
    pub a_mm: f64,
    /// Twist about x_i, degrees.
    pub alpha_deg: f64,
    /// Hayati's extra twist about y_i, degrees (0 for a plain D-H link).
    pub beta_deg: f64,
    /// +1 or −1: the controller's positive direction relative to the D-H z axis.
    pub sign: f64,
}

impl MdhLink {
    /// A revolute link with sign +1 and β = 0 (plain standard D-H).
    pub fn revolute(theta_offset_deg: f64, d_mm: f64, a_mm: f64, alpha_deg: f64) -> Self {
        MdhLink {
            kind: JointKind::Revolute,
            theta_offset_deg,
            d_mm,
            a_mm,
            alpha_deg,
            beta_deg: 0.0,
            sign: 1.0,
        }
    }

    /// A prismatic link with sign +1 and β = 0.
    pub fn prismatic(theta_deg: f64, d_mm: f64, a_mm: f64, alpha_deg: f64) -> Self {
        MdhLink {
            kind: JointKind::Prismatic,
            ..MdhLink::revolute(theta_deg, d_mm, a_mm, alpha_deg)
        }
    }

    /// The same link with the controller sign set.
    pub fn with_sign(mut self, sign: f64) -> Self {
        self.sign = sign;
        self
    }

    /// `(θ, d)` in (rad, mm) for joint value `q` (deg or mm).
    pub fn theta_d(&self, q: f64) -> (f64, f64) {
        match self.kind {
            JointKind::Revolute => (
                (self.sign * q + self.theta_offset_deg).to_radians(),
                self.d_mm,
            ),
            JointKind::Prismatic => (
                self.theta_offset_deg.to_radians(),
                self.d_mm + self.sign * q,
            ),
        }
    }

    /// `T_i` of seed 003 eq 1 at joint value `q`.
    pub fn transform(&self, q: f64) -> Isometry3<f64> {
        let (theta, d) = self.theta_d(q);
        let rz = UnitQuaternion::from_axis_angle(&Vector3::z_axis(), theta);
        let rx = UnitQuaternion::from_axis_angle(&Vector3::x_axis(), self.alpha_deg.to_radians());
        let ry = UnitQuaternion::from_axis_angle(&Vector3::y_axis(), self.beta_deg.to_radians());
        // Rot(z,θ)·Tr(z,d)·Tr(x,a): the translation (a, 0, d) expressed after Rot(z,θ).
        let t = rz * Vector3::new(self.a_mm, 0.0, 0.0) + Vector3::new(0.0, 0.0, d);
        Isometry3::from_parts(Translation3::from(t), rz * rx * ry)
    }
}

/// A serial robot: MD-H links, base and tool transforms, joint limits.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Robot {
    /// Preset or user name.
    pub name: String,
    /// One sentence on the parameter source and the angle convention.
    pub convention: String,
    /// The MD-H links, base to flange, one per joint.
    pub links: Vec<MdhLink>,
    /// World ← robot base (identity for the presets).
    pub base: Isometry3<f64>,
    /// Flange ← TCP.
    pub tool: Isometry3<f64>,
    /// Per-joint hard limits `(min, max)`, degrees or mm.
    pub limits: Vec<(f64, f64)>,
    /// Per-joint default working ranges for measurement campaigns.
    pub work_ranges: Vec<(f64, f64)>,
    /// A comfortable pose inside `work_ranges` (campaign start, IK seed).
    pub home: Vec<f64>,
}

impl Robot {
    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.links.len()
    }

    /// Whether each joint is prismatic (its values in mm, not degrees).
    pub fn prismatic_joints(&self) -> Vec<bool> {
        self.links
            .iter()
            .map(|l| l.kind == JointKind::Prismatic)
            .collect()
    }

    /// Error unless the campaign `data` has one joint column per joint of
    /// this robot; the message names the file and the robot.
    pub fn check_dataset(&self, data: &crate::dataset::Dataset) -> Result<()> {
        if data.n_joints() == self.dof() {
            return Ok(());
        }
        Err(crate::Error::Input {
            source_name: data.source.clone(),
            message: format!(
                "has {} joint columns (q1..q{}) but robot '{}' has {} joints; choose the robot that was measured with --robot",
                data.n_joints(),
                data.n_joints(),
                self.name,
                self.dof()
            ),
        })
    }

    /// A warning per joint of `data` that leaves this robot's limits: how
    /// many rows, and the furthest value (a campaign of another robot, or
    /// angles in another convention, fits without error otherwise).
    pub fn limit_warnings(&self, data: &crate::dataset::Dataset) -> Vec<String> {
        let unit = |j: usize| self.joint_unit(j);
        (0..self.dof().min(data.n_joints()))
            .filter_map(|j| {
                let (lo, hi) = self.limits[j];
                let out: Vec<f64> = data
                    .q
                    .iter()
                    .map(|q| q[j])
                    .filter(|v| *v < lo || *v > hi)
                    .collect();
                let worst = out
                    .iter()
                    .copied()
                    .max_by(|a, b| (a - a.clamp(lo, hi)).abs().total_cmp(&(b - b.clamp(lo, hi)).abs()))?;
                Some(format!(
                    "{}: q{} of {} row(s) outside the limits of robot '{}', [{lo}, {hi}]{u} (up to {worst:.2}{u}): is this the robot that was measured, with its joint convention?",
                    data.source,
                    j + 1,
                    out.len(),
                    self.name,
                    u = unit(j)
                ))
            })
            .collect()
    }

    /// This robot with its TCP offset replaced: the tool's translation set
    /// to `xyz` (mm, in the flange frame), its rotation kept. What
    /// `--tool x,y,z` and Python's `tool=(x, y, z)` do.
    pub fn with_tool_translation(mut self, xyz: [f64; 3]) -> Result<Robot> {
        if !xyz.iter().all(|v| v.is_finite()) {
            return Err(Error::InvalidParameter(format!(
                "tool ({}, {}, {}): expected finite x, y, z in mm",
                xyz[0], xyz[1], xyz[2]
            )));
        }
        self.tool = Isometry3::from_parts(
            Translation3::new(xyz[0], xyz[1], xyz[2]),
            self.tool.rotation,
        );
        Ok(self)
    }

    /// Error unless `q` has one value per joint.
    pub fn check_len(&self, q: &[f64]) -> Result<()> {
        if q.len() == self.dof() {
            Ok(())
        } else {
            Err(Error::JointCount {
                expected: self.dof(),
                got: q.len(),
            })
        }
    }

    /// The unit of joint `j`'s values as a suffix to a number: "°", or
    /// " mm" for a prismatic joint (`format!("{v}{}", robot.joint_unit(j))`
    /// gives `12.5°` and `190 mm`, as every joint value in a message is
    /// written). A joint this robot does not have gets "°".
    pub fn joint_unit(&self, j: usize) -> &'static str {
        unit_suffix(self.links.get(j).map(|l| l.kind) == Some(JointKind::Prismatic))
    }

    /// The joints a run starts from: `start`, checked to have one value per
    /// joint and to lie within the joint limits, or by default the home
    /// pose.
    pub fn start_or_home(&self, start: Option<&[f64]>) -> Result<Vec<f64>> {
        let given = start.is_some();
        let start = start.unwrap_or(&self.home).to_vec();
        self.check_len(&start)?;
        let outside: Vec<String> = start
            .iter()
            .zip(&self.limits)
            .enumerate()
            .filter(|(_, (v, (lo, hi)))| !(*v >= lo && *v <= hi))
            .map(|(j, (v, (lo, hi)))| {
                let u = self.joint_unit(j);
                format!("q{} = {v}{u} not in [{lo}, {hi}]{u}", j + 1)
            })
            .collect();
        if !outside.is_empty() {
            return Err(Error::InvalidParameter(format!(
                "the {} is outside the limits of robot '{}': {}",
                if given {
                    "start pose"
                } else {
                    "robot's home pose"
                },
                self.name,
                outside.join(", ")
            )));
        }
        Ok(start)
    }

    /// Frames `F_0 = base, F_1 = base·T_1, …, F_n`, then the TCP frame `F_n·tool`
    /// (n + 2 frames). Panics only if `q.len() != dof` — use [`Robot::fk`] for checked input.
    pub fn frames(&self, q: &[f64]) -> Vec<Isometry3<f64>> {
        assert_eq!(q.len(), self.dof(), "joint vector length");
        let mut out = Vec::with_capacity(self.dof() + 2);
        let mut f = self.base;
        out.push(f);
        for (link, &qi) in self.links.iter().zip(q) {
            f *= link.transform(qi);
            out.push(f);
        }
        out.push(f * self.tool);
        out
    }

    /// Forward kinematics: the TCP pose in the world frame (seed 003 eq 2 with δT = 0).
    pub fn fk(&self, q: &[f64]) -> Result<Isometry3<f64>> {
        self.check_len(q)?;
        Ok(self.fk_unchecked(q))
    }

    /// [`Robot::fk`] without the length check (hot loops that already checked).
    pub fn fk_unchecked(&self, q: &[f64]) -> Isometry3<f64> {
        let mut f = self.base;
        for (link, &qi) in self.links.iter().zip(q) {
            f *= link.transform(qi);
        }
        f * self.tool
    }

    /// TCP position, mm.
    pub fn position(&self, q: &[f64]) -> Result<Vector3<f64>> {
        Ok(self.fk(q)?.translation.vector)
    }

    /// Geometric Jacobian of the TCP, 6 × n: rows 0–2 linear velocity (mm),
    /// rows 3–5 angular velocity, per **radian** of a revolute joint and per mm
    /// of a prismatic one (multiply by π/180 for per-degree).
    ///
    /// Column i: revolute `sign_i·[z_{i−1} × (p − o_{i−1}); z_{i−1}]`,
    /// prismatic `sign_i·[z_{i−1}; 0]`.
    pub fn jacobian(&self, q: &[f64]) -> Result<Matrix6xX<f64>> {
        self.check_len(q)?;
        let frames = self.frames(q);
        let p = frames[self.dof() + 1].translation.vector;
        let mut j = Matrix6xX::zeros(self.dof());
        for (i, link) in self.links.iter().enumerate() {
            let z = frames[i].rotation * Vector3::z();
            let o = frames[i].translation.vector;
            let (lin, ang) = match link.kind {
                JointKind::Revolute => (z.cross(&(p - o)), z),
                JointKind::Prismatic => (z, Vector3::zeros()),
            };
            j.fixed_view_mut::<3, 1>(0, i).copy_from(&(lin * link.sign));
            j.fixed_view_mut::<3, 1>(3, i).copy_from(&(ang * link.sign));
        }
        Ok(j)
    }

    /// Position Jacobian ∂p/∂q, 3 × n (same units as [`Robot::jacobian`]).
    pub fn position_jacobian(&self, q: &[f64]) -> Result<Matrix3xX<f64>> {
        Ok(self.jacobian(q)?.fixed_rows::<3>(0).into_owned())
    }

    /// Whether every joint value lies within its hard limits.
    pub fn within_limits(&self, q: &[f64]) -> bool {
        q.iter()
            .zip(&self.limits)
            .all(|(v, (lo, hi))| *v >= *lo && *v <= *hi)
    }

    /// Radians per API unit for joint i (π/180 for revolute, 1 for prismatic).
    pub fn unit_scale(&self, i: usize) -> f64 {
        match self.links[i].kind {
            JointKind::Revolute => std::f64::consts::PI / 180.0,
            JointKind::Prismatic => 1.0,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn single_link_matches_closed_form() {
        let l = MdhLink {
            beta_deg: 0.0,
            ..MdhLink::revolute(10.0, 5.0, 100.0, 90.0)
        };
        let t = l.transform(20.0);
        let th = 30f64.to_radians();
        let p = t.translation.vector;
        assert!((p - Vector3::new(100.0 * th.cos(), 100.0 * th.sin(), 5.0)).norm() < 1e-12);
        // z_1 = Rz(θ)·Rx(90°)·z = (sin θ, −cos θ, 0)
        let z = t.rotation * Vector3::z();
        assert!((z - Vector3::new(th.sin(), -th.cos(), 0.0)).norm() < 1e-12);
    }
}
