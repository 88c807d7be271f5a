//! A plan's files: the region read from a task file, the plan written as
//! CSV.

use super::{Plan, PoseSet, Region};
use crate::dataset::Dataset;
use crate::kinematics::{IkOptions, Robot, all_reached, first_pass_joints};
use crate::program::{self, ProgramFormat, ProgramOptions, ProgramPose};
use crate::space::derive_directions;
use crate::trajectory::{TargetFile, read_target_file};
use crate::{Error, Result};
use std::path::Path;

impl Region {
    /// The region of a plan: the task file `path` ([`Region::from_file`]),
    /// else the `pool`'s poses, else the robot's working ranges.
    pub fn from_options(
        path: Option<&Path>,
        pool: Option<&Dataset>,
        robot: &Robot,
    ) -> Result<Self> {
        match (path, pool) {
            (Some(path), _) => Region::from_file(path, robot),
            (None, Some(p)) => Ok(Region::Poses(p.into())),
            (None, None) => Ok(Region::WorkRange),
        }
    }

    /// The poses of a task file: a joint-pose list (`q1..qN`, with its
    /// directions given or derived from its order), or TCP targets
    /// (`x,y,z[,roll,pitch,yaw]`) solved by the robot's nominal inverse
    /// kinematics along the path from its home pose, the directions those
    /// joint moves realise.
    pub fn from_file(path: &Path, robot: &Robot) -> Result<Region> {
        match read_target_file(path)? {
            TargetFile::Joints(d) => {
                robot.check_dataset(&d)?;
                // a task the robot cannot run is not a region to plan for
                let out: Vec<usize> = (0..d.len())
                    .filter(|&i| !robot.within_limits(&d.q[i]))
                    .collect();
                if let Some(&first) = out.first() {
                    return Err(Error::Input {
                        source_name: path.display().to_string(),
                        message: format!(
                            "{} of its {} poses are outside the joint limits of robot '{}' (the first at data row {}): the robot cannot run this task",
                            out.len(),
                            d.len(),
                            robot.name,
                            first + 1
                        ),
                    });
                }
                Ok(Region::Poses(PoseSet::from(&d)))
            }
            TargetFile::Tcp(traj) => {
                let q = all_reached(first_pass_joints(
                    robot,
                    traj.has_orientation,
                    &traj.poses,
                    &robot.home,
                    None,
                    &IkOptions::default(),
                ))?;
                let dir = derive_directions(&q, Some(&robot.home));
                Ok(Region::Poses(PoseSet { q, dir }))
            }
        }
    }
}

impl Plan {
    /// Write the moves as CSV: `id,q1..qN,dir1..dirN,measure,source` —
    /// `measure` 1 for a pose to measure, 0 for a via-point; `source` the
    /// pool row (0-based, pool order) or candidate a measured pose came
    /// from, empty for a via-point. The directions are those the order
    /// realises, so the file is a measurement CSV's pose columns as the
    /// robot will visit them.
    pub fn write_csv(&self, path: &Path) -> Result<()> {
        let n = self.moves.first().map_or(0, |m| m.q.len());
        crate::output::write_atomic(path, |out| {
            let mut w = csv::Writer::from_writer(out);
            let mut header = vec!["id".to_string()];
            header.extend((1..=n).map(|i| format!("q{i}")));
            header.extend((1..=n).map(|i| format!("dir{i}")));
            header.extend(["measure".into(), "source".into()]);
            w.write_record(&header)?;
            for (k, m) in self.moves.iter().enumerate() {
                let mut rec = vec![k.to_string()];
                rec.extend(m.q.iter().map(f64::to_string));
                rec.extend(m.dir.iter().map(|d| format!("{d}")));
                rec.push(if m.measure { "1" } else { "0" }.into());
                rec.push(m.pose.map_or(String::new(), |i| self.chosen[i].to_string()));
                w.write_record(&rec)?;
            }
            w.flush()
        })
    }

    /// Refuse, before any planning, an output the plan could not be
    /// written to in `format` ([`Plan::write`]): a program that `robot`'s
    /// controller cannot take, or a file that names no valid program
    /// ([`ProgramOptions::for_file`]).
    pub fn check_output(path: &Path, format: ProgramFormat, robot: &Robot) -> Result<()> {
        if format != ProgramFormat::Csv {
            ProgramOptions::for_file(path, format, robot.prismatic_joints())?;
        }
        Ok(())
    }

    /// Write the plan in `format`: [`Plan::write_csv`] for CSV, else a
    /// program of joint moves for `robot`'s controller
    /// ([`crate::program`]), measured poses and via-points marked, each
    /// measured pose labelled with its source row.
    pub fn write(&self, path: &Path, format: ProgramFormat, robot: &Robot) -> Result<()> {
        if format == ProgramFormat::Csv {
            return self.write_csv(path);
        }
        let opts = ProgramOptions::for_file(path, format, robot.prismatic_joints())?;
        let poses: Vec<ProgramPose> = self
            .moves
            .iter()
            .map(|m| match m.pose {
                Some(i) if m.measure => ProgramPose::measured(m.q.clone())
                    .with_label(format!("source {}", self.chosen[i])),
                _ => ProgramPose::via(m.q.clone()),
            })
            .collect();
        program::write(path, &poses, format, &opts)
    }

    /// The poses to measure, in the order they are visited.
    pub fn measured_moves(&self) -> impl Iterator<Item = &super::PlannedMove> {
        self.moves.iter().filter(|m| m.measure)
    }
}
