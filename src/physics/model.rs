//! The physics-based model: identified geometry + bidirectional lookup tables.

use super::BidirectionalTable;
use crate::compensate::Compensated;
use crate::kinematics::{JointKind, Robot};
use crate::model::{CoverageWarning, ErrorModel, RobotRecord};
use crate::predictor::ErrorPredictor;
use crate::{Error, Result};
use nalgebra::{Isometry3, Point3, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Format tag of a saved physics model (its JSON `format` field).
pub const PHYSICS_FORMAT: &str = "robokrige-physics-model";
/// Version of the physics-model file format this crate writes.
pub const PHYSICS_VERSION: u32 = 1;

/// Identified SCARA geometry of seed 000 (eqs 3, 18, 23), in the reference
/// CS of §2.4: Z along the J1 axis average line, origin on it, X along link 1
/// at `θ̂1 = 0`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ScaraGeometry {
    /// Nominal length of link 1, `L1`, mm.
    pub l1_mm: f64,
    /// Nominal length of link 2, `L2`, mm.
    pub l2_mm: f64,
    /// Length error of link 1, `ΔL1 = ‖Q2 − Q1‖ − L1` (the exact form of eq 12), mm.
    pub dl1_mm: f64,
    /// Length error of link 2, `ΔL2 = R2 − L2` (eq 13), mm.
    pub dl2_mm: f64,
    /// Angular offset of J2, `θ20` (eq 14), degrees.
    pub theta20_deg: f64,
    /// Parallelism of the J2 to the J1 average line (eq 22): the plane
    /// `z = a·x' + b·y' + z1` of the J2 indexing test in link-1 coordinates
    /// of the reference CS; `a`, `b` in mm/mm (small angles, rad), `z1` in mm.
    /// The TCP's Z (eq 23) is this plane plus the commanded height change
    /// `Z*(q) − Z*(rest)`.
    ///
    /// This field is the slope `a`, along x'.
    pub parallel_a: f64,
    /// Slope `b` of the J2 plane along y' (mm/mm, a small angle in rad).
    pub parallel_b: f64,
    /// Height `z1` of the J2 plane at the link-1 origin, mm.
    pub z1_mm: f64,
    /// Commanded pose of the indexing tests (its nominal z is the Z origin).
    pub rest: Vec<f64>,
}

/// How the model maps the estimated joint angles θ̂ to a TCP position.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case", tag = "kind")]
pub enum Geometry {
    /// Seed 000: planar SCARA with parallelism (eq 23).
    Scara(ScaraGeometry),
    /// Seed 002 eqs 1–2: an MD-H chain with identified parameter errors.
    Mdh {
        /// The robot with its identified MD-H, tool and base errors applied.
        robot: Robot,
    },
}

/// A physics-based error model (seed 000 eq 3, seed 002 eqs 1–2):
///
/// `θ̂_n = θ*_n + Δθ_n,map(θ*_n, λ_n)` (eq 4, linear interpolation in the
/// bidirectional table of each axis that has one), then the identified
/// geometry gives the TCP `P̂(θ̂)` in the reference CS, and `frame` maps it
/// into the measurement frame. The predicted error is `frame·P̂ − P_nom(θ*)`,
/// the same convention as the measured `ex, ey, ez`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsModel {
    /// Format tag, [`PHYSICS_FORMAT`].
    pub format: String,
    /// File format version; loading needs [`PHYSICS_VERSION`].
    pub version: u32,
    /// One line on how it was identified.
    pub description: String,
    /// The robot as the controller knows it.
    pub nominal: Robot,
    /// The identified geometry: θ̂ → TCP position in the reference CS.
    pub geometry: Geometry,
    /// Measurement frame ← reference CS.
    pub frame: Isometry3<f64>,
    /// Angular positioning deviation per joint, degrees (`None`: no table).
    pub apd: Vec<Option<BidirectionalTable>>,
    /// Radial error motion per joint (seed 000 eqs 18–20), mm; SCARA J1/J2 only.
    pub radial: Vec<Option<BidirectionalTable>>,
}

impl PhysicsModel {
    /// A model with no lookup tables (the conventional D-H model).
    pub fn new(description: impl Into<String>, nominal: Robot, geometry: Geometry) -> Self {
        let n = nominal.dof();
        PhysicsModel {
            format: PHYSICS_FORMAT.into(),
            version: PHYSICS_VERSION,
            description: description.into(),
            nominal,
            geometry,
            frame: Isometry3::identity(),
            apd: vec![None; n],
            radial: vec![None; n],
        }
    }

    /// The same model without angular positioning deviations and radial error
    /// motions: the conventional D-H model (seed 000 eq 2).
    pub fn dh_only(&self) -> Self {
        let n = self.nominal.dof();
        PhysicsModel {
            description: format!("{} (D-H parameters only)", self.description),
            apd: vec![None; n],
            radial: vec![None; n],
            ..self.clone()
        }
    }

    /// Whether any joint has a lookup table.
    pub fn has_tables(&self) -> bool {
        self.apd.iter().chain(&self.radial).any(Option::is_some)
    }

    /// Estimated joint angles `θ̂` (eq 4) for commanded `q`, directions `dir`.
    pub fn joint_estimate(&self, q: &[f64], dir: &[f64]) -> Vec<f64> {
        q.iter()
            .zip(dir)
            .zip(&self.apd)
            .map(|((qi, di), t)| qi + t.as_ref().map_or(0.0, |t| t.at(*qi, *di)))
            .collect()
    }

    /// Predicted TCP position in the measurement frame.
    pub fn tcp(&self, q: &[f64], dir: &[f64]) -> Vector3<f64> {
        let th = self.joint_estimate(q, dir);
        let p = match &self.geometry {
            Geometry::Mdh { robot } => robot.fk_unchecked(&th).translation.vector,
            Geometry::Scara(g) => self.scara_tcp(g, q, dir, &th),
        };
        (self.frame * Point3::from(p)).coords
    }

    /// Seed 000 eq 18 (XY, with radial error motion) and eq 23 (Z).
    fn scara_tcp(&self, g: &ScaraGeometry, q: &[f64], dir: &[f64], th: &[f64]) -> Vector3<f64> {
        let radial = |j: usize| {
            self.radial
                .get(j)
                .and_then(Option::as_ref)
                .map_or(0.0, |t| t.at(q[j], dir[j]))
        };
        let r1 = g.l1_mm + g.dl1_mm + radial(0);
        let r2 = g.l2_mm + g.dl2_mm + radial(1);
        let t1 = th[0].to_radians();
        let t12 = (th[0] + th[1] + g.theta20_deg).to_radians();
        let x = r1 * t1.cos() + r2 * t12.cos();
        let y = r1 * t1.sin() + r2 * t12.sin();
        // link-1 coordinates of the TCP, then the J2 plane (eq 22)
        let (s1, c1) = t1.sin_cos();
        let (xl, yl) = (c1 * x + s1 * y, -s1 * x + c1 * y);
        let z_cmd = self.nominal.fk_unchecked(q).translation.vector.z
            - self.nominal.fk_unchecked(&g.rest).translation.vector.z;
        let z = z_cmd + g.parallel_a * xl + g.parallel_b * yl + g.z1_mm;
        Vector3::new(x, y, z)
    }

    /// Predicted errors `frame·P̂(θ̂) − P_nom(θ*)` for many poses.
    pub fn predict(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        check_rows(self.nominal.dof(), q, dir)?;
        Ok(q.iter()
            .zip(dir)
            .map(|(qk, dk)| {
                let nom = self.nominal.fk_unchecked(qk).translation.vector;
                (self.tcp(qk, dk) - nom).into()
            })
            .collect())
    }

    /// Checks after loading: format, version, table shapes, joint kinds.
    pub fn validate(&self) -> Result<()> {
        if self.format != PHYSICS_FORMAT {
            return Err(Error::InvalidParameter(format!(
                "not a robokrige physics model (format '{}')",
                self.format
            )));
        }
        if self.version != PHYSICS_VERSION {
            return Err(Error::InvalidParameter(format!(
                "physics model version {} is not supported (this build reads {PHYSICS_VERSION})",
                self.version
            )));
        }
        let n = self.nominal.dof();
        if self.apd.len() != n || self.radial.len() != n {
            return Err(Error::JointCount {
                expected: n,
                got: self.apd.len(),
            });
        }
        for (j, t) in self.apd.iter().chain(&self.radial).enumerate() {
            if let Some(t) = t {
                t.validate()?;
                if self.nominal.links[j % n].kind != JointKind::Revolute {
                    return Err(Error::InvalidParameter(format!(
                        "joint {} is prismatic but has an angular lookup table",
                        j % n + 1
                    )));
                }
            }
        }
        match &self.geometry {
            Geometry::Mdh { robot } if robot.dof() != n => Err(Error::JointCount {
                expected: n,
                got: robot.dof(),
            }),
            Geometry::Scara(g) if n < 2 || g.rest.len() != n => Err(Error::InvalidParameter(
                "SCARA geometry needs the indexing rest pose of every joint".into(),
            )),
            _ => Ok(()),
        }
    }

    /// Write as pretty JSON.
    pub fn save(&self, path: &Path) -> Result<()> {
        save_json(path, self, "physics model")
    }

    /// Read and validate.
    pub fn load(path: &Path) -> Result<Self> {
        let m: PhysicsModel = load_json(path, "physics model")?;
        m.validate()?;
        Ok(m)
    }

    /// Error unless the model is for `robot`: its nominal robot's
    /// kinematic table and tool (`source_name`: the model, for the
    /// message), as [`ErrorModel::check_robot`] for a Kriging model.
    pub fn check_robot(&self, robot: &Robot, source_name: &str) -> Result<()> {
        RobotRecord::of(&self.nominal).check(robot, source_name)
    }
}

/// Physics model first, universal Kriging on what it leaves (a hybrid):
/// `δ̂ = δ̂_phys(θ, λ) + δ̂_UK(θ, λ)`, the Kriging model fitted to the
/// residuals `e − δ̂_phys` of the training campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct HybridModel {
    /// The physics stage, `δ̂_phys`.
    pub physics: PhysicsModel,
    /// The Kriging stage `δ̂_UK`, fitted to the physics model's residuals.
    pub residual: ErrorModel,
}

impl HybridModel {
    /// Predicted errors.
    pub fn predict(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        let a = self.physics.predict(q, dir)?;
        let b = self.residual.predict_mean(q, dir)?;
        Ok(a.iter()
            .zip(&b)
            .map(|(u, v)| [u[0] + v[0], u[1] + v[1], u[2] + v[2]])
            .collect())
    }
}

fn check_rows(n: usize, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<()> {
    if q.len() != dir.len() {
        return Err(Error::InvalidParameter(format!(
            "{} joint rows but {} direction rows",
            q.len(),
            dir.len()
        )));
    }
    for r in q.iter().chain(dir) {
        if r.len() != n {
            return Err(Error::JointCount {
                expected: n,
                got: r.len(),
            });
        }
    }
    Ok(())
}

pub(crate) fn save_json<T: Serialize>(path: &Path, v: &T, what: &str) -> Result<()> {
    let text = serde_json::to_string_pretty(v).map_err(|e| Error::Json {
        context: format!("writing {what} {}", path.display()),
        source: e,
    })?;
    crate::output::write_text(path, &text)
}

pub(crate) fn load_json<T: for<'de> Deserialize<'de>>(path: &Path, what: &str) -> Result<T> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
        path: path.to_path_buf(),
        source: e,
    })?;
    serde_json::from_str(&text).map_err(|e| Error::Json {
        context: format!("{}: not a valid {what}", path.display()),
        source: e,
    })
}

/// A saved model of either kind, chosen by the file's `format` tag: what
/// `compensate --model` accepts.
#[derive(Debug, Clone, PartialEq)]
pub enum AnyModel {
    /// A universal-Kriging error model file.
    Kriging(Box<ErrorModel>),
    /// A physics model file (`format` = [`PHYSICS_FORMAT`]).
    Physics(Box<PhysicsModel>),
}

impl AnyModel {
    /// Load a Kriging or physics model file.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::Io {
            path: path.to_path_buf(),
            source: e,
        })?;
        let is_physics = serde_json::from_str::<serde_json::Value>(&text)
            .ok()
            .and_then(|v| v.get("format").and_then(|f| f.as_str()).map(String::from))
            .is_some_and(|f| f == PHYSICS_FORMAT);
        if is_physics {
            Ok(AnyModel::Physics(Box::new(PhysicsModel::load(path)?)))
        } else {
            Ok(AnyModel::Kriging(Box::new(ErrorModel::from_json(
                &text,
                &path.display().to_string(),
            )?)))
        }
    }

    /// [`AnyModel::load`] of a model for `robot`, refused with the file's
    /// name when it is for another ([`AnyModel::check_robot`]).
    pub fn load_for(path: &Path, robot: &Robot) -> Result<Self> {
        let mut model = Self::load(path)?;
        model.check_robot(robot, &path.display().to_string())?;
        if let AnyModel::Kriging(m) = &mut model {
            m.fill_joint_kinds(robot);
        }
        Ok(model)
    }

    /// Error unless the model is for `robot`: a Kriging model checks the
    /// robot it records ([`ErrorModel::check_robot`]), a physics model its
    /// nominal robot's kinematic table and tool (`source_name`: the model
    /// file, for the message).
    pub fn check_robot(&self, robot: &Robot, source_name: &str) -> Result<()> {
        match self {
            AnyModel::Kriging(m) => m.check_robot(robot, source_name),
            AnyModel::Physics(m) => m.check_robot(robot, source_name),
        }
    }

    /// The points of the compensation `res` that leave a Kriging model's
    /// coverage ([`ErrorModel::coverage`] at the means the compensation
    /// used; no standard deviations, which would need the m × m factor);
    /// none for a physics model.
    pub fn coverage_of(&self, res: &Compensated) -> Result<Vec<CoverageWarning>> {
        match self {
            AnyModel::Kriging(m) => m.coverage(&res.joints, &res.dir, &res.predicted, None),
            AnyModel::Physics(_) => Ok(Vec::new()),
        }
    }

    /// Short label: "EJS", "JS", "physics".
    pub fn label(&self) -> String {
        match self {
            AnyModel::Kriging(m) => format!("{:?}", m.space()).to_uppercase(),
            AnyModel::Physics(_) => "physics".into(),
        }
    }

    /// One phrase: "a Kriging Ejs model", "a physics model (…)".
    pub fn describe(&self) -> String {
        match self {
            AnyModel::Kriging(m) => format!("a Kriging {:?} model", m.space()),
            AnyModel::Physics(m) => format!(
                "a physics model ({})",
                if m.has_tables() {
                    "D-H + lookup tables"
                } else {
                    "D-H only"
                }
            ),
        }
    }
}

impl ErrorPredictor for PhysicsModel {
    fn n_joints(&self) -> usize {
        self.nominal.dof()
    }
    fn predict_errors(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        self.predict(q, dir)
    }
}

impl ErrorPredictor for HybridModel {
    fn n_joints(&self) -> usize {
        self.physics.nominal.dof()
    }
    fn predict_errors(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        self.predict(q, dir)
    }
}

impl ErrorPredictor for AnyModel {
    fn n_joints(&self) -> usize {
        match self {
            AnyModel::Kriging(m) => m.n_joints(),
            AnyModel::Physics(m) => ErrorPredictor::n_joints(m.as_ref()),
        }
    }
    fn predict_errors(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        match self {
            AnyModel::Kriging(m) => m.predict_mean(q, dir),
            AnyModel::Physics(m) => m.predict(q, dir),
        }
    }
}
