//! Robot files: a robot described in TOML or JSON, and the presets in the same
//! format.
//!
//! A robot file is the MD-H table of seed 003 eq 1, one `[[joints]]` entry per
//! joint from the base out, plus the tool and base frames:
//!
//! ```toml
//! name = "abb-irb2600-12-165"            # required
//! convention = "datasheet D-H, theta = q" # optional, one sentence
//!
//! [[joints]]
//! kind = "revolute"          # or "prismatic"; default revolute
//! theta_offset_deg = 0.0     # θ = sign·q + θ_offset (revolute); default 0
//! d_mm = 445.0               # default 0
//! a_mm = 150.0               # default 0
//! alpha_deg = -90.0          # default 0
//! beta_deg = 0.0             # Hayati's twist about y; default 0 (plain D-H)
//! sign = 1.0                 # +1 or −1; default +1
//! limits = [-180.0, 180.0]   # hard limits; default ±360° (required for prismatic)
//! work_range = [-20.0, 20.0] # campaign range; default: the limits
//! home = 0.0                 # campaign start / IK seed; default: middle of work_range
//!
//! [tool]                     # flange ← TCP; default identity
//! xyz_mm = [0.0, 0.0, 200.0]
//! rpy_deg = [0.0, 0.0, 0.0]  # R = Rz(yaw)·Ry(pitch)·Rx(roll)
//!
//! [base]                     # world ← robot base; default identity
//! xyz_mm = [0.0, 0.0, 0.0]
//! ```
//!
//! Units are those of the API: degrees for angles and revolute joint values,
//! mm for lengths and prismatic joint values. Unknown keys are rejected, so a
//! misspelt `alpha` does not silently become 0.

use super::{JointKind, MdhLink, Robot};
use crate::{Error, Result};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// A rigid frame in a robot file: translation in mm, roll–pitch–yaw in
/// degrees (`R = Rz(yaw)·Ry(pitch)·Rx(roll)`).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameSpec {
    /// Translation, mm.
    #[serde(default)]
    pub xyz_mm: [f64; 3],
    /// Roll, pitch, yaw, degrees.
    #[serde(default)]
    pub rpy_deg: [f64; 3],
}

impl FrameSpec {
    /// The frame as an isometry.
    pub fn isometry(&self) -> Isometry3<f64> {
        let [r, p, y] = self.rpy_deg.map(f64::to_radians);
        Isometry3::from_parts(
            Translation3::from(Vector3::from(self.xyz_mm)),
            UnitQuaternion::from_euler_angles(r, p, y),
        )
    }

    /// The frame spec of an isometry (inverse of [`FrameSpec::isometry`]).
    pub fn of(iso: &Isometry3<f64>) -> Self {
        let (r, p, y) = iso.rotation.euler_angles();
        // `+ 0.0` turns −0 into 0 (files say 0.0, not -0.0)
        let xyz: [f64; 3] = iso.translation.vector.into();
        FrameSpec {
            xyz_mm: xyz.map(|v| v + 0.0),
            rpy_deg: [r, p, y].map(|v| v.to_degrees() + 0.0),
        }
    }
}

/// One joint of a robot file: its MD-H link and its ranges.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct JointSpec {
    /// Revolute (default) or prismatic.
    #[serde(default = "revolute")]
    pub kind: JointKind,
    /// θ offset, degrees.
    #[serde(default)]
    pub theta_offset_deg: f64,
    /// d, mm.
    #[serde(default)]
    pub d_mm: f64,
    /// a, mm.
    #[serde(default)]
    pub a_mm: f64,
    /// α, degrees.
    #[serde(default)]
    pub alpha_deg: f64,
    /// β (Hayati), degrees.
    #[serde(default)]
    pub beta_deg: f64,
    /// +1 or −1.
    #[serde(default = "plus_one")]
    pub sign: f64,
    /// Hard limits `[min, max]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub limits: Option<[f64; 2]>,
    /// Campaign range `[min, max]`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub work_range: Option<[f64; 2]>,
    /// Home value.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub home: Option<f64>,
}

fn revolute() -> JointKind {
    JointKind::Revolute
}

fn plus_one() -> f64 {
    1.0
}

/// The contents of a robot file (see the module docs for the format).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct RobotFile {
    /// The robot's name (recorded in model files).
    pub name: String,
    /// One sentence on the parameter source and the angle convention.
    #[serde(default)]
    pub convention: String,
    /// The MD-H chain from the base out.
    pub joints: Vec<JointSpec>,
    /// Flange ← TCP.
    #[serde(default)]
    pub tool: FrameSpec,
    /// World ← robot base.
    #[serde(default)]
    pub base: FrameSpec,
}

/// Default hard limits of a revolute joint without `limits`, degrees.
pub const DEFAULT_REVOLUTE_LIMITS: (f64, f64) = (-360.0, 360.0);

impl RobotFile {
    /// Parse TOML text (`source_name` names the file in messages).
    pub fn from_toml(text: &str, source_name: &str) -> Result<Self> {
        toml::from_str(text).map_err(|e| Error::Input {
            source_name: source_name.into(),
            message: format!("not a robot file: {}", e.message()),
        })
    }

    /// Parse JSON text.
    pub fn from_json(text: &str, source_name: &str) -> Result<Self> {
        serde_json::from_str(text).map_err(|e| Error::Input {
            source_name: source_name.into(),
            message: format!("not a robot file: {e}"),
        })
    }

    /// The robot file of a robot (every field written out).
    pub fn of(robot: &Robot) -> Self {
        let joints = robot
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| JointSpec {
                kind: l.kind,
                theta_offset_deg: l.theta_offset_deg,
                d_mm: l.d_mm,
                a_mm: l.a_mm,
                alpha_deg: l.alpha_deg,
                beta_deg: l.beta_deg,
                sign: l.sign,
                limits: robot.limits.get(i).map(|&(a, b)| [a, b]),
                work_range: robot.work_ranges.get(i).map(|&(a, b)| [a, b]),
                home: robot.home.get(i).copied(),
            })
            .collect();
        RobotFile {
            name: robot.name.clone(),
            convention: robot.convention.clone(),
            joints,
            tool: FrameSpec::of(&robot.tool),
            base: FrameSpec::of(&robot.base),
        }
    }

    /// The file as TOML text.
    pub fn to_toml(&self) -> Result<String> {
        toml::to_string(self)
            .map_err(|e| Error::InvalidParameter(format!("robot file as TOML: {e}")))
    }

    /// The robot file of `robot` as TOML text under a comment line with
    /// its number of joints and [`table_digest`] (what `robot show` prints
    /// and `robot calibrated` writes).
    pub fn text_of(robot: &Robot) -> Result<String> {
        Ok(format!(
            "# {} joints, kinematic-table digest {}\n{}",
            robot.dof(),
            table_digest(robot),
            RobotFile::of(robot).to_toml()?
        ))
    }

    /// The robot, after checking every value (`source_name` for messages).
    pub fn robot(&self, source_name: &str) -> Result<Robot> {
        let bad = |message: String| Error::Input {
            source_name: source_name.into(),
            message,
        };
        if self.name.trim().is_empty() {
            return Err(bad("the robot has no name".into()));
        }
        if self.joints.is_empty() {
            return Err(bad("the robot has no [[joints]]".into()));
        }
        let frames = [("tool", &self.tool), ("base", &self.base)];
        for (what, f) in frames {
            if f.xyz_mm.iter().chain(&f.rpy_deg).any(|v| !v.is_finite()) {
                return Err(bad(format!("{what}: every value must be finite")));
            }
        }
        let mut links = Vec::with_capacity(self.joints.len());
        let (mut limits, mut work_ranges, mut home) = (vec![], vec![], vec![]);
        for (i, j) in self.joints.iter().enumerate() {
            let at = |m: String| bad(format!("joint {}: {m}", i + 1));
            let values = [j.theta_offset_deg, j.d_mm, j.a_mm, j.alpha_deg, j.beta_deg];
            if values.iter().any(|v| !v.is_finite()) {
                return Err(at("every MD-H value must be finite".into()));
            }
            if j.sign != 1.0 && j.sign != -1.0 {
                return Err(at(format!("sign must be 1 or -1, not {}", j.sign)));
            }
            let lim = match (j.limits, j.kind) {
                (Some([a, b]), _) => (a, b),
                (None, JointKind::Revolute) => DEFAULT_REVOLUTE_LIMITS,
                (None, JointKind::Prismatic) => {
                    return Err(at("a prismatic joint needs limits = [min, max] (mm)".into()));
                }
            };
            check_range(lim, "limits").map_err(at)?;
            let work = j.work_range.map_or(lim, |[a, b]| (a, b));
            check_range(work, "work_range").map_err(at)?;
            if work.0 < lim.0 || work.1 > lim.1 {
                return Err(at(format!(
                    "work_range [{}, {}] leaves the limits [{}, {}]",
                    work.0, work.1, lim.0, lim.1
                )));
            }
            let h = j.home.unwrap_or(0.5 * (work.0 + work.1));
            if !h.is_finite() || h < work.0 || h > work.1 {
                return Err(at(format!(
                    "home {h} is outside work_range [{}, {}]",
                    work.0, work.1
                )));
            }
            links.push(MdhLink {
                kind: j.kind,
                theta_offset_deg: j.theta_offset_deg,
                d_mm: j.d_mm,
                a_mm: j.a_mm,
                alpha_deg: j.alpha_deg,
                beta_deg: j.beta_deg,
                sign: j.sign,
            });
            limits.push(lim);
            work_ranges.push(work);
            home.push(h);
        }
        Ok(Robot {
            name: self.name.clone(),
            convention: self.convention.clone(),
            links,
            base: self.base.isometry(),
            tool: self.tool.isometry(),
            limits,
            work_ranges,
            home,
        })
    }
}

fn check_range((lo, hi): (f64, f64), what: &str) -> std::result::Result<(), String> {
    if lo.is_finite() && hi.is_finite() && lo < hi {
        Ok(())
    } else {
        Err(format!("{what} [{lo}, {hi}] must be finite with min < max"))
    }
}

/// Read a robot file: TOML, or JSON when the name ends in `.json`.
pub fn read_robot_file(path: &Path) -> Result<Robot> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let name = path.display().to_string();
    let is_json = path
        .extension()
        .is_some_and(|e| e.eq_ignore_ascii_case("json"));
    let file = if is_json {
        RobotFile::from_json(&text, &name)?
    } else {
        RobotFile::from_toml(&text, &name)?
    };
    file.robot(&name)
}

/// A robot by preset name or robot-file path: a preset name wins; anything
/// else is read as a file. The error for a name that is neither lists the
/// presets.
pub fn load_robot(spec: &str) -> Result<Robot> {
    if let Some(robot) = super::presets::try_preset(spec) {
        return robot;
    }
    let path = Path::new(spec);
    if path.is_file() {
        return read_robot_file(path);
    }
    Err(Error::UnknownRobot {
        name: spec.to_string(),
        known: super::PRESET_NAMES.join(", "),
    })
}

/// [`load_robot`], with its tool translation replaced by `tool`, "x,y,z"
/// in mm (the flange-frame TCP offset; the tool's rotation is kept:
/// [`Robot::with_tool_translation`]).
pub fn load_robot_with_tool(spec: &str, tool: Option<&str>) -> Result<Robot> {
    let robot = load_robot(spec)?;
    let Some(t) = tool else { return Ok(robot) };
    let bad = || Error::InvalidParameter(format!("--tool '{t}': expected x,y,z in mm"));
    let v: Vec<f64> = t
        .split(',')
        .map(|x| x.trim().parse::<f64>())
        .collect::<std::result::Result<_, _>>()
        .map_err(|_| bad())?;
    let xyz: [f64; 3] = v.try_into().map_err(|_| bad())?;
    robot.with_tool_translation(xyz).map_err(|_| bad())
}

/// [`load_robot_with_tool`] of an optional robot: `None` without one.
pub fn load_optional_robot(spec: Option<&str>, tool: Option<&str>) -> Result<Option<Robot>> {
    spec.map(|s| load_robot_with_tool(s, tool)).transpose()
}

/// Serde `deserialize_with` for a robot stored in a file: its whole table, or
/// (files written before robot files existed) a preset's name.
pub fn robot_or_preset_name<'de, D>(d: D) -> std::result::Result<Box<Robot>, D::Error>
where
    D: serde::Deserializer<'de>,
{
    #[derive(Deserialize)]
    #[serde(untagged)]
    enum Stored {
        Table(Box<Robot>),
        Name(String),
    }
    match Stored::deserialize(d)? {
        Stored::Table(r) => Ok(r),
        Stored::Name(n) => super::preset(&n)
            .map(Box::new)
            .map_err(serde::de::Error::custom),
    }
}

/// A 64-bit FNV-1a digest of the kinematic table (every link's MD-H values
/// and the base frame) as 16 hex digits: two robots with the same digest have
/// the same nominal kinematics up to the tool. Names, limits and ranges are
/// not part of it.
pub fn table_digest(robot: &Robot) -> String {
    let mut text = String::new();
    for l in &robot.links {
        let kind = match l.kind {
            JointKind::Revolute => 'R',
            JointKind::Prismatic => 'P',
        };
        text.push_str(&format!(
            "{kind} {:?} {:?} {:?} {:?} {:?} {:?};",
            l.theta_offset_deg, l.d_mm, l.a_mm, l.alpha_deg, l.beta_deg, l.sign
        ));
    }
    let b = FrameSpec::of(&robot.base);
    text.push_str(&format!("base {:?} {:?}", b.xyz_mm, b.rpy_deg));
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for byte in text.bytes() {
        h ^= u64::from(byte);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    format!("{h:016x}")
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn defaults_fill_a_minimal_file() {
        let f = RobotFile::from_toml(
            "name = \"two-link\"\n[[joints]]\na_mm = 300.0\n[[joints]]\na_mm = 200.0\nlimits = [-90.0, 90.0]\n",
            "t",
        )
        .unwrap();
        let r = f.robot("t").unwrap();
        assert_eq!(r.dof(), 2);
        assert_eq!(r.limits, vec![DEFAULT_REVOLUTE_LIMITS, (-90.0, 90.0)]);
        assert_eq!(r.work_ranges[1], (-90.0, 90.0));
        assert_eq!(r.home, vec![0.0, 0.0]);
        assert_eq!(r.links[0].sign, 1.0);
        assert_eq!(r.tool, Isometry3::identity());
    }

    #[test]
    fn misspelt_keys_and_bad_values_are_refused() {
        let e = RobotFile::from_toml("name = \"x\"\n[[joints]]\nalpha = 90.0\n", "f.toml")
            .unwrap_err()
            .to_string();
        assert!(e.contains("f.toml") && e.contains("alpha"), "{e}");
        let f = RobotFile::from_toml("name = \"x\"\n[[joints]]\nsign = 2.0\n", "f").unwrap();
        assert!(
            f.robot("f")
                .unwrap_err()
                .to_string()
                .contains("joint 1: sign")
        );
        let f =
            RobotFile::from_toml("name = \"x\"\n[[joints]]\nkind = \"prismatic\"\n", "f").unwrap();
        assert!(
            f.robot("f")
                .unwrap_err()
                .to_string()
                .contains("needs limits")
        );
        let f = RobotFile::from_toml(
            "name = \"x\"\n[[joints]]\nlimits = [-10.0, 10.0]\nwork_range = [-20.0, 5.0]\n",
            "f",
        )
        .unwrap();
        assert!(
            f.robot("f")
                .unwrap_err()
                .to_string()
                .contains("leaves the limits")
        );
    }

    #[test]
    fn frames_round_trip_through_rpy() {
        let spec = FrameSpec {
            xyz_mm: [1.0, -2.0, 3.0],
            rpy_deg: [10.0, -20.0, 30.0],
        };
        let back = FrameSpec::of(&spec.isometry());
        for k in 0..3 {
            assert!((back.xyz_mm[k] - spec.xyz_mm[k]).abs() < 1e-12);
            assert!((back.rpy_deg[k] - spec.rpy_deg[k]).abs() < 1e-9);
        }
    }
}
