//! Commanded TCP trajectories: the points a controller is sent, in order.
//!
//! CSV columns: `id` (optional), `x,y,z` (mm, base frame) and optionally
//! `roll_deg,pitch_deg,yaw_deg` with `R = Rz(yaw)·Ry(pitch)·Rx(roll)`.
//! Without orientation columns the points are position-only targets.

use crate::dataset::table::{Table, triplet};
use crate::dataset::{number, position_value};
use crate::{Error, Result};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use std::path::Path;

/// An ordered list of commanded TCP poses.
#[derive(Debug, Clone, PartialEq)]
pub struct Trajectory {
    /// TCP poses; orientation is identity when `has_orientation` is false.
    pub poses: Vec<Isometry3<f64>>,
    /// Whether the poses carry a target orientation (CSV with
    /// `roll_deg,pitch_deg,yaw_deg`); otherwise they are position-only targets.
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

    /// Read a trajectory CSV with the rules of the measurement reader
    /// ([`crate::dataset`]: BOM, trimming, blank lines, line numbers with any
    /// line ending, no empty header cell); errors name the line and column.
    /// The orientation columns are all three or none.
    pub fn read_csv(path: &Path) -> Result<Self> {
        let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
        Self::read_csv_from(&bytes, &path.display().to_string())
    }

    /// [`Trajectory::read_csv`] of a whole file's bytes; `src` names it.
    pub fn read_csv_from(bytes: &[u8], src: &str) -> Result<Self> {
        Self::from_table(&Table::read(bytes, src, "with x,y,z")?, src)
    }

    /// The trajectory of an already read [`Table`].
    fn from_table(table: &Table, src: &str) -> Result<Self> {
        let header_err = |message: String| Error::Csv {
            file: src.to_string(),
            line: table.header_line,
            column: None,
            message,
        };
        let Ok(Some(pos)) = triplet(&table.header, ["x", "y", "z"]) else {
            return Err(header_err(format!(
                "a trajectory needs columns x, y, z (mm) (found: {})",
                table.header.join(", ")
            )));
        };
        let rot = triplet(&table.header, ["roll_deg", "pitch_deg", "yaw_deg"])
            .map_err(|msg| header_err(format!("{msg} (position-only targets)")))?;
        let mut poses = Vec::with_capacity(table.rows.len());
        for (line, rec) in &table.rows {
            let cell = |i: usize, parse: fn(&str) -> std::result::Result<f64, String>| {
                parse(&rec[i]).map_err(|message| Error::Csv {
                    file: src.to_string(),
                    line: *line,
                    column: Some(table.header[i].clone()),
                    message,
                })
            };
            let t = Vector3::new(
                cell(pos[0], position_value)?,
                cell(pos[1], position_value)?,
                cell(pos[2], position_value)?,
            );
            let q = match rot {
                Some(c) => UnitQuaternion::from_euler_angles(
                    cell(c[0], number)?.to_radians(),
                    cell(c[1], number)?.to_radians(),
                    cell(c[2], number)?.to_radians(),
                ),
                None => UnitQuaternion::identity(),
            };
            poses.push(Isometry3::from_parts(Translation3::from(t), q));
        }
        if poses.is_empty() {
            return Err(Error::Input {
                source_name: src.to_string(),
                message: "trajectory has no points; add one row per target after the header".into(),
            });
        }
        Ok(Trajectory {
            poses,
            has_orientation: rot.is_some(),
        })
    }
}

/// What a target file holds.
#[derive(Debug, Clone, PartialEq)]
pub enum TargetFile {
    /// TCP poses: columns `x,y,z` and optionally `roll_deg,pitch_deg,yaw_deg`.
    Tcp(Trajectory),
    /// Joint poses: columns `q1..qN` (a measurement CSV or a pose list).
    Joints(crate::dataset::Dataset),
}

/// Read a target file, telling the two kinds apart by the header (with
/// the rules of the CSV table reader): a `q1` column makes it a joint-pose list — in
/// a measurement CSV, `x,y,z` are the *measured* positions, not targets.
pub fn read_target_file(path: &Path) -> Result<TargetFile> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    let src = path.display().to_string();
    let table = Table::read(
        &bytes,
        &src,
        "with x,y,z (TCP targets) or q1..qN (joint poses)",
    )?;
    if table.column("q1").is_some() {
        Ok(TargetFile::Joints(crate::dataset::from_table(
            &table, &src,
        )?))
    } else {
        Ok(TargetFile::Tcp(Trajectory::from_table(&table, &src)?))
    }
}
