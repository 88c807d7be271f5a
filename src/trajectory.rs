//! Commanded TCP trajectories: the points a controller is sent, in order.
//!
//! CSV columns: `id` (optional), `x,y,z` (mm, base frame) and optionally
//! `roll_deg,pitch_deg,yaw_deg` with `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
//! Without orientation columns the points are position-only targets.

use crate::{Error, Result};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::path::Path;

/// An ordered list of commanded TCP poses.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// TCP poses; orientation is identity when `has_orientation` is false.
    pub poses: Vec<Isometry3<f64>>,
    pub has_orientation: bool,
}

const HEADER: [&str; 7] = ["id", "x", "y", "z", "roll_deg", "pitch_deg", "yaw_deg"];

impl Trajectory {
    /// Full-pose trajectory.
    pub fn new(poses: Vec<Isometry3<f64>>) -> Self {
        Trajectory {
            poses,
            has_orientation: true,
        }
    }

    /// Number of points.
    pub fn len(&self) -> usize {
        self.poses.len()
    }

    /// Whether there are no points.
    pub fn is_empty(&self) -> bool {
        self.poses.is_empty()
    }

    /// Write as CSV (full f64 precision).
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        crate::output::write_atomic(path, |out| self.write_records(out))
    }

    fn write_records(&self, out: &mut dyn std::io::Write) -> std::io::Result<()> {
        let mut w = csv::Writer::from_writer(out);
        let ncol = if self.has_orientation { 7 } else { 4 };
        w.write_record(&HEADER[..ncol])?;
        for (k, p) in self.poses.iter().enumerate() {
            let t = p.translation.vector;
            let (r, pi, y) = p.rotation.euler_angles();
            let mut rec = vec![
                k.to_string(),
                t.x.to_string(),
                t.y.to_string(),
                t.z.to_string(),
            ];
            if self.has_orientation {
                rec.extend([r, pi, y].map(|a| a.to_degrees().to_string()));
            }
            w.write_record(&rec)?;
        }
        w.flush()
    }

    /// Read a trajectory CSV; errors name the line and column.
    pub fn read_csv(path: &Path) -> Result<Self> {
        let file = path.display().to_string();
        let mut r = csv::ReaderBuilder::new()
            .trim(csv::Trim::All)
            .flexible(true)
            .from_path(path)
            .map_err(|e| csv_io(path, e))?;
        let header: Vec<String> = r
            .headers()
            .map_err(|e| csv_io(path, e))?
            .iter()
            .map(str::to_string)
            .collect();
        let col = |name: &str| header.iter().position(|h| h == name);
        let pos: Vec<usize> = ["x", "y", "z"]
            .iter()
            .map(|c| col(c))
            .collect::<Option<_>>()
            .ok_or_else(|| Error::Input {
                source_name: file.clone(),
                message: "a trajectory needs columns x, y, z (mm)".into(),
            })?;
        let rot: Option<Vec<usize>> = ["roll_deg", "pitch_deg", "yaw_deg"]
            .iter()
            .map(|c| col(c))
            .collect();
        let mut poses = Vec::new();
        for rec in r.records() {
            let rec = rec.map_err(|e| csv_io(path, e))?;
            let line = rec.position().map_or(0, |p| p.line());
            if rec.len() != header.len() {
                return Err(Error::Csv {
                    file: file.clone(),
                    line,
                    column: None,
                    message: format!(
                        "row has {} cells but the header has {}",
                        rec.len(),
                        header.len()
                    ),
                });
            }
            let num = |i: usize| -> Result<f64> {
                let s = &rec[i];
                s.parse::<f64>()
                    .ok()
                    .filter(|v| v.is_finite())
                    .ok_or_else(|| Error::Csv {
                        file: file.clone(),
                        line,
                        column: Some(header[i].clone()),
                        message: format!("expected a finite number, found '{s}'"),
                    })
            };
            let t = Vector3::new(num(pos[0])?, num(pos[1])?, num(pos[2])?);
            let q = match &rot {
                Some(c) => UnitQuaternion::from_euler_angles(
                    num(c[0])?.to_radians(),
                    num(c[1])?.to_radians(),
                    num(c[2])?.to_radians(),
                ),
                None => UnitQuaternion::identity(),
            };
            poses.push(Isometry3::from_parts(Translation3::from(t), q));
        }
        if poses.is_empty() {
            return Err(Error::Input {
                source_name: file,
                message: "trajectory has no points".into(),
            });
        }
        Ok(Trajectory {
            poses,
            has_orientation: rot.is_some(),
        })
    }
}

fn csv_io(path: &Path, e: csv::Error) -> Error {
    Error::Input {
        source_name: path.display().to_string(),
        message: e.to_string(),
    }
}
