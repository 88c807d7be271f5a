//! Studies on a simulated robot: compensation targets from a trajectory or a
//! pose list, the simulator's truth file, and the evaluation of commands run
//! on the true robot (before / after). The CLI's `compensate`, `evaluate`,
//! `demo`, `diagnose` and `physics` and the examples all use these.

pub mod diagnosis;

use crate::compensate::{Compensated, CompensationOptions, compensate};
use crate::kinematics::{Robot, table_digest};
use crate::predictor::ErrorPredictor;
use crate::sim::{Truth, execute, rng_for};
use crate::stats::{PositionErrorTable, position_error_table};
use crate::trajectory::{TargetFile, Trajectory, read_target_file};
use crate::vec3::Vec3;
use crate::{Error, Result};
use nalgebra::{Isometry3, UnitQuaternion};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// A tool orientation given for position-only targets: roll, pitch, yaw
/// (degrees), and the name the caller took it by (an option, a keyword),
/// for the messages.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GivenOrientation<'a> {
    /// Roll, pitch, yaw, degrees.
    pub rpy_deg: &'a [f64],
    /// How the user gave it, e.g. `--orientation`.
    pub named: &'a str,
}

/// Target poses, and for a q1..qN pose list the joints as IK hints.
#[derive(Debug, Clone, PartialEq)]
pub struct Targets {
    /// The TCP poses to reach, in visiting order.
    pub traj: Trajectory,
    /// Joints of each target when they came from a pose list (IK hints).
    pub hints: Option<Vec<Vec<f64>>>,
    /// Warnings of the pose list (repeated poses, …), for the caller to show.
    pub warnings: Vec<String>,
    /// Position-only targets that took the tool orientation of the start
    /// pose (no `--orientation`): an unreachable target may be the start's
    /// fault, not the trajectory's ([`Targets::explain`]).
    pub orientation_from_start: bool,
}

impl Targets {
    /// Targets at the nominal TCP poses of joint vectors `q` (hints = `q`).
    pub fn from_joints(robot: &Robot, q: &[Vec<f64>]) -> Result<Self> {
        Ok(Targets {
            traj: Trajectory::new(q.iter().map(|q| robot.fk(q)).collect::<Result<_>>()?),
            hints: Some(q.to_vec()),
            warnings: Vec::new(),
            orientation_from_start: false,
        })
    }

    /// Error unless `commands` (read from `source`) has one point per
    /// target.
    pub fn check_commands(&self, commands: &Trajectory, source: &Path) -> Result<()> {
        if commands.len() != self.traj.len() {
            return Err(Error::Input {
                source_name: source.display().to_string(),
                message: format!(
                    "has {} points but the target trajectory has {}",
                    commands.len(),
                    self.traj.len()
                ),
            });
        }
        Ok(())
    }

    /// Options of a compensation of these targets from `start`: their
    /// joints as IK hints, everything else at its default.
    pub fn compensation_options(&self, start: &[f64]) -> CompensationOptions {
        CompensationOptions {
            start: Some(start.to_vec()),
            hints: self.hints.clone(),
            ..CompensationOptions::default()
        }
    }

    /// Targets along a trajectory (no hints).
    pub fn from_trajectory(traj: Trajectory) -> Self {
        Targets {
            traj,
            hints: None,
            warnings: Vec::new(),
            orientation_from_start: false,
        }
    }

    /// `e` with what the targets add to it: an [`Error::Unreachable`] of
    /// targets that took the start pose's orientation says so, since a
    /// start whose tool points elsewhere than the task needs makes
    /// reachable positions unreachable; `ways` says how to give the
    /// orientation, in the caller's words (options, keywords or columns).
    pub fn explain(&self, e: Error, ways: &str) -> Error {
        match e {
            Error::Unreachable { indices, first } if self.orientation_from_start => {
                Error::Unreachable {
                    indices,
                    first: format!(
                        "{first}; the trajectory has positions only, and every target takes the tool orientation of the start pose: if the positions are within reach, give {ways}"
                    ),
                }
            }
            e => e,
        }
    }

    /// Read a target file: a trajectory CSV (`x,y,z[,roll,pitch,yaw]`) or a
    /// q1..qN pose list, whose nominal TCP poses become the targets, then
    /// [`Targets::orient`] them.
    pub fn read(
        path: &Path,
        robot: &Robot,
        orientation: Option<GivenOrientation>,
        start: &[f64],
    ) -> Result<Self> {
        let targets = match read_target_file(path)? {
            TargetFile::Joints(d) => {
                robot.check_dataset(&d)?;
                let mut t = Targets::from_joints(robot, &d.q)?;
                t.warnings = d.warnings();
                t
            }
            TargetFile::Tcp(t) => Targets::from_trajectory(t),
        };
        targets
            .orient(robot, orientation, start)
            .map_err(|e| match e {
                Error::InvalidParameter(m) => {
                    Error::InvalidParameter(format!("{m} ({})", path.display()))
                }
                e => e,
            })
    }

    /// Give position-only targets of a six-axis robot one tool
    /// orientation: `orientation`, else the orientation of the pose
    /// `start`, which [`Targets::orientation_from_start`] then records.
    /// An orientation given to targets that have their own (joint poses,
    /// roll, pitch, yaw columns) or to a robot of fewer than six joints is
    /// an error.
    pub fn orient(
        mut self,
        robot: &Robot,
        orientation: Option<GivenOrientation>,
        start: &[f64],
    ) -> Result<Self> {
        let t = &mut self.traj;
        if let Some(o) = orientation
            && (t.has_orientation || self.hints.is_some() || robot.dof() < 6)
        {
            return Err(Error::InvalidParameter(format!(
                "{} (roll, pitch, yaw) is for position-only (x, y, z) targets of a six-axis robot, not for {}",
                o.named,
                if self.hints.is_some() {
                    "joint poses (their orientations come from the joints)"
                } else if t.has_orientation {
                    "targets with their own roll, pitch, yaw"
                } else {
                    "a robot with fewer than six joints"
                }
            )));
        }
        if t.has_orientation || robot.dof() < 6 {
            return Ok(self);
        }
        let rot = match orientation.map(|o| (o.rpy_deg, o.named)) {
            Some((&[r, p, y], _)) if [r, p, y].iter().all(|v| v.is_finite()) => {
                UnitQuaternion::from_euler_angles(r.to_radians(), p.to_radians(), y.to_radians())
            }
            Some((a, named)) => {
                return Err(Error::InvalidParameter(format!(
                    "{named} needs three finite angles: roll, pitch, yaw (deg), not {a:?}"
                )));
            }
            None => {
                self.orientation_from_start = true;
                robot.fk(start)?.rotation
            }
        };
        for p in &mut t.poses {
            *p = Isometry3::from_parts(p.translation, rot);
        }
        t.has_orientation = true;
        Ok(self)
    }
}

/// Read a simulator truth file (`robokrige simulate` writes it beside a campaign).
pub fn load_truth(path: &Path) -> Result<Truth> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let truth: Truth = serde_json::from_str(&text).map_err(|e| Error::Json {
        context: format!("{}: not a simulator truth file", path.display()),
        source: e,
    })?;
    if truth.format != crate::sim::campaign::TRUTH_FORMAT {
        return Err(Error::Input {
            source_name: path.display().to_string(),
            message: format!("format '{}' is not a simulator truth", truth.format),
        });
    }
    for e in &truth.spec.effects {
        e.validate().map_err(|e| Error::Input {
            source_name: path.display().to_string(),
            message: e.to_string(),
        })?;
    }
    Ok(truth)
}

/// Error unless the truth's nominal robot has `robot`'s kinematic table.
pub fn check_truth_robot(truth: &Truth, robot: &Robot, path: &Path) -> Result<()> {
    let nominal = &truth.robot.nominal;
    if table_digest(nominal) != table_digest(robot) {
        return Err(Error::Input {
            source_name: path.display().to_string(),
            message: format!(
                "the truth is for robot '{}', not '{}' (their kinematic tables differ)",
                nominal.name, robot.name
            ),
        });
    }
    Ok(())
}

/// The robot a simulator truth's runs are compared on: `robot` (a preset
/// name or a robot file), which must have the kinematic table of the
/// truth's nominal robot ([`check_truth_robot`]), or by default that
/// nominal robot.
pub fn truth_robot(truth: &Truth, robot: Option<&str>, truth_path: &Path) -> Result<Robot> {
    let Some(name) = robot else {
        return Ok(truth.robot.nominal.clone());
    };
    let robot = crate::kinematics::load_robot(name)?;
    check_truth_robot(truth, &robot, truth_path)?;
    Ok(robot)
}

/// Errors `measured − target` (mm) of running `commands` on the truth's robot
/// from `start`.
pub fn run_on(
    truth: &Truth,
    commands: &Trajectory,
    targets: &Targets,
    start: &[f64],
    rng: &mut impl rand::Rng,
) -> Result<Vec<[f64; 3]>> {
    let ex = execute(
        &truth.robot,
        commands,
        start,
        targets.hints.as_deref(),
        &truth.spec.effects,
        rng,
    )?;
    Ok(ex
        .measured
        .iter()
        .zip(&targets.traj.poses)
        .map(|(m, p)| m.minus(&p.translation.vector.into()))
        .collect())
}

/// Measured errors (mm) of the nominal and the compensated runs.
pub type Runs = (Vec<[f64; 3]>, Vec<[f64; 3]>);

/// Before / after errors of a compensation measured on the simulated robot.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Evaluation {
    /// The truth file.
    pub truth: PathBuf,
    /// Seed of the simulated measurement noise.
    pub seed: u64,
    /// Points of the trajectory.
    pub points: usize,
    /// Errors of the nominal commands (the targets themselves).
    pub before: PositionErrorTable,
    /// Errors of the compensated commands.
    pub after: PositionErrorTable,
    /// `100 (1 − after/before)` of the mean |δ|, %.
    pub reduction_mean_abs_pct: f64,
    /// `100 (1 − after/before)` of the max |δ|, %.
    pub reduction_max_abs_pct: f64,
}

/// Run the nominal commands (the targets) and `commands` on the truth's
/// robot with the same noise stream (`seed`), and compare.
pub fn evaluate(
    truth_path: &Path,
    truth: &Truth,
    targets: &Targets,
    commands: &Trajectory,
    start: &[f64],
    seed: u64,
) -> Result<(Evaluation, Runs)> {
    let mut rng = rng_for(seed, "evaluate");
    let before = run_on(truth, &targets.traj, targets, start, &mut rng)?;
    let after = run_on(truth, commands, targets, start, &mut rng)?;
    let (b, a) = (position_error_table(&before), position_error_table(&after));
    Ok((
        Evaluation {
            truth: truth_path.to_path_buf(),
            seed,
            points: targets.traj.len(),
            reduction_mean_abs_pct: 100.0 * (1.0 - a.mean_abs_mm / b.mean_abs_mm),
            reduction_max_abs_pct: 100.0 * (1.0 - a.max_abs_mm / b.max_abs_mm),
            before: b,
            after: a,
        },
        (before, after),
    ))
}

/// [`evaluate`] on the simulator truth file `truth_path`, checked to be
/// for `robot` ([`check_truth_robot`]).
pub fn evaluate_on_file(
    truth_path: &Path,
    robot: &Robot,
    targets: &Targets,
    commands: &Trajectory,
    start: &[f64],
    seed: u64,
) -> Result<(Evaluation, Runs)> {
    let truth = load_truth(truth_path)?;
    check_truth_robot(&truth, robot, truth_path)?;
    evaluate(truth_path, &truth, targets, commands, start, seed)
}

/// A file of compensated commands evaluated on the simulated robot
/// ([`evaluate_file`]).
#[derive(Debug, Clone)]
pub struct FileEvaluation {
    /// The command file.
    pub file: PathBuf,
    /// Its file name (`compensated` if it has none).
    pub name: String,
    /// Before / after error tables.
    pub evaluation: Evaluation,
    /// The measured errors of the nominal and of these commands' runs.
    pub runs: Runs,
}

/// Read the commands of the trajectory CSV `path` (one per target) and
/// [`evaluate`] them.
pub fn evaluate_file(
    truth: (&Path, &Truth),
    targets: &Targets,
    path: &Path,
    start: &[f64],
    seed: u64,
) -> Result<FileEvaluation> {
    let commands = Trajectory::read_csv(path)?;
    targets.check_commands(&commands, path)?;
    let (evaluation, runs) = evaluate(truth.0, truth.1, targets, &commands, start, seed)?;
    let name = path.file_name().and_then(|s| s.to_str());
    Ok(FileEvaluation {
        file: path.to_path_buf(),
        name: name.unwrap_or("compensated").to_string(),
        evaluation,
        runs,
    })
}

/// The measured errors of a nominal and a compensated run as named runs,
/// `before` and `after` ([`named_runs`] names the nominal run `before` too).
pub fn before_after((before, after): Runs) -> Vec<(String, Vec<[f64; 3]>)> {
    vec![("before".into(), before), ("after".into(), after)]
}

/// The measured errors of `evals` as named runs: the nominal run (the
/// same in each, taken from the first) as `before`, then each file's.
pub fn named_runs(evals: &[FileEvaluation]) -> Vec<(String, Vec<[f64; 3]>)> {
    let before = evals
        .first()
        .map(|e| ("before".to_string(), e.runs.0.clone()));
    let after = evals.iter().map(|e| (e.name.clone(), e.runs.1.clone()));
    before.into_iter().chain(after).collect()
}

/// How a trajectory file gives its targets' orientation: what an
/// unreachable position-only target says to give ([`Targets::explain`])
/// where there is no option for it.
pub const TRAJECTORY_ORIENTATION: &str =
    "the task's orientation as the trajectory's roll_deg, pitch_deg, yaw_deg columns (degrees)";

/// A compensation and its evaluation on the simulated robot.
#[derive(Debug, Clone)]
pub struct CompensatedRun {
    /// The compensation: commands and the iteration history.
    pub compensation: Compensated,
    /// Before / after error tables.
    pub evaluation: Evaluation,
    /// The measured errors of the nominal and the compensated runs.
    pub runs: Runs,
}

/// Iterative feed-forward compensation of `targets` with `model`, then
/// [`evaluate`]: the nominal and the compensated commands run on the
/// truth's simulated robot from `start`, with the same noise stream (`seed`).
pub fn compensate_and_evaluate<M: ErrorPredictor + ?Sized>(
    robot: &Robot,
    model: &M,
    truth_path: &Path,
    truth: &Truth,
    targets: &Targets,
    start: &[f64],
    seed: u64,
) -> Result<CompensatedRun> {
    let opts = targets.compensation_options(start);
    let compensation = compensate(robot, model, &targets.traj, &opts)
        .map_err(|e| targets.explain(e, TRAJECTORY_ORIENTATION))?;
    let (evaluation, runs) = evaluate(
        truth_path,
        truth,
        targets,
        &compensation.commands,
        start,
        seed,
    )?;
    Ok(CompensatedRun {
        compensation,
        evaluation,
        runs,
    })
}

/// [`compensate_and_evaluate`] with each of `models`, in order, on the same
/// targets, truth, start and noise seed: the models compared on the same
/// simulated runs.
pub fn compensate_and_evaluate_each<M: ErrorPredictor + ?Sized>(
    robot: &Robot,
    models: &[&M],
    truth_path: &Path,
    truth: &Truth,
    targets: &Targets,
    start: &[f64],
    seed: u64,
) -> Result<Vec<CompensatedRun>> {
    models
        .iter()
        .map(|m| compensate_and_evaluate(robot, *m, truth_path, truth, targets, start, seed))
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn an_unreachable_target_of_the_start_pose_orientation_says_so() {
        let unreachable = || Error::Unreachable {
            indices: vec![0, 1],
            first: "inverse kinematics did not converge".into(),
        };
        let mut t = Targets::from_trajectory(Trajectory::new(Vec::new()));
        assert_eq!(
            t.explain(unreachable(), "WAYS").to_string(),
            unreachable().to_string()
        );
        t.orientation_from_start = true;
        let e = t.explain(unreachable(), "WAYS").to_string();
        assert!(
            e.contains("did not converge; the trajectory has positions only"),
            "{e}"
        );
        assert!(e.ends_with("give WAYS"), "{e}");
        // other errors pass unchanged
        let other = t
            .explain(Error::InvalidParameter("x".into()), "WAYS")
            .to_string();
        assert_eq!(other, Error::InvalidParameter("x".into()).to_string());
    }
}
