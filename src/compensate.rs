//! Feed-forward trajectory compensation with a fitted error model.
//!
//! The robot reaches `P + δ(s(P))` when commanded to `P`, where `s(P)` is the
//! extended joint vector `[θ, λ]` of the command: θ from the *nominal* inverse
//! kinematics (what the controller computes), λ from the visiting order
//! (`λ_i = sign(θ_i − θ_{i−1})`, seed 004 eq 19; a joint that does not move
//! keeps its λ; the first point's λ comes from the start pose).
//!
//! - **Single-step** (seed 003 eq 22): `Pm = Pd − δ̂(s(Pd))`.
//! - **Iterative** (seed 004 eqs 18–22): starting from `Pm_0 = Pd`,
//!   `θ_k = IK(Pm_{k−1})` (eq 18), `s_k = [θ_k, λ_k]` (eq 19),
//!   `δ̂_k = Kr(s_k)` (eq 20), `Pm_k = Pd − δ̂_k`, which is eq 22
//!   `Pm_k = Pm_{k−1} + ε_k` with `ε_k = δ̂_{k−1} − δ̂_k`. It stops when the
//!   trajectory RMSE of the change, `R_k = √(Σ_i |ε_{i,k}|² / n)` (eq 21 per
//!   point), is below a tolerance or after a maximum number of iterations.
//!   Single-step is the first iteration.
//!
//! **Direction reversals.** Where a joint reverses inside the path its steps
//! are tiny, and the correction itself can flip the sign of the step, hence λ,
//! hence δ̂ (by the backlash), which flips the correction back: the plain
//! fixed-point map has no fixed point there and iterates in a 2-cycle. So a
//! point whose λ changes between two iterations has its step size halved
//! (`Pm_k = Pm_{k−1} + α_i ε_k`, α_i ← α_i/2 at every flip): a bisection that
//! converges to the switching boundary, where either λ leaves about half the
//! backlash jump instead of all of it. On a dense path the switch point itself
//! creeps forward one point per iteration (the consistent command would hold
//! the joint still over several points), so the loop also stops when the
//! RMSE of the change has stalled (less than 10 % lower than two iterations
//! before) and reports it ([`Stop::Stalled`]) with the points whose λ
//! changed in the last iteration.
//!
//! **Motion history.** A model with history inputs (a joint's moves into the
//! pose for servo lag, the previous λ, the travel since a reversal) predicts
//! each point from the path that led to it: the predictions are made along
//! the start pose followed by the commands' joints ([`predict_along`]), so the
//! move into the first point is the one from the start, as the robot makes
//! it. A model without such inputs predicts every point alone; prepending the
//! start changes nothing for it.
//!
//! Only positions are corrected; each command keeps its target's orientation.
//! Points the IK cannot reach are reported by index ([`Error::Unreachable`]),
//! never passed through uncorrected.
//!
//! **Output.** The commands go to the controller as a trajectory CSV (TCP
//! poses, [`Trajectory::write_csv`]) or as a robot program of joint moves
//! ([`CommandsOutput`], [`crate::program`]): the joints of each command are
//! the nominal IK solutions the loop ends with ([`Compensated::joints`]),
//! seeded along the path, so the program makes the moves the controller's
//! own IK would.

use crate::kinematics::{IkOptions, Robot, all_reached, first_pass_joints, path_target};
use crate::predictor::ErrorPredictor;
use crate::program::{self, ProgramFormat, ProgramOptions, ProgramPose};
use crate::space::derive_directions;
use crate::trajectory::Trajectory;
use crate::{Error, Result};
use nalgebra::{Isometry3, Translation3, Vector3};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::{Path, PathBuf};

/// Options of [`compensate`]; `Default` is iterative, 1 µm, 10 iterations,
/// starting from the robot's home pose.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensationOptions {
    /// Iterate (seed 004) or stop after the single step (seed 003).
    pub iterative: bool,
    /// Stop when the RMSE of the change falls below this, mm.
    pub tol_mm: f64,
    /// Maximum iterations (the single step counts as one).
    pub max_iter: usize,
    /// Joint values the robot starts from (λ of the first point); `None` = home.
    pub start: Option<Vec<f64>>,
    /// IK seed per point for the first pass, e.g. the joints a pose list was
    /// taught with (keeps each pose on its own branch). Without hints each
    /// point is seeded from the previous point's solution, then from home.
    pub hints: Option<Vec<Vec<f64>>>,
    /// Options of the numerical IK that turns each command into joints.
    pub ik: IkOptions,
}

impl Default for CompensationOptions {
    fn default() -> Self {
        CompensationOptions {
            iterative: true,
            tol_mm: 1e-3,
            max_iter: 10,
            start: None,
            hints: None,
            ik: IkOptions::default(),
        }
    }
}

impl CompensationOptions {
    /// These options with the loop's settings: iterate or stop after the
    /// single step, the tolerance on the change (mm), the most iterations.
    pub fn iterations(self, iterative: bool, tol_mm: f64, max_iter: usize) -> Self {
        CompensationOptions {
            iterative,
            tol_mm,
            max_iter,
            ..self
        }
    }

    fn validate(&self) -> Result<()> {
        if self.tol_mm.is_nan() || self.tol_mm <= 0.0 || self.max_iter == 0 {
            return Err(Error::InvalidParameter(format!(
                "compensation needs tol > 0 and max-iter ≥ 1 (got tol {} mm, max-iter {})",
                self.tol_mm, self.max_iter
            )));
        }
        Ok(())
    }
}

/// One iteration of the loop.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Iteration {
    /// 1 = the single step.
    pub iteration: usize,
    /// `R_k`, RMSE over the points of the change of the command, mm (eq 21).
    pub rmse_change_mm: f64,
    /// Largest change of one point, mm.
    pub max_change_mm: f64,
    /// Mean predicted |δ̂| at the commands of this iteration, mm.
    pub mean_predicted_mm: f64,
    /// Points whose λ changed since the previous iteration (step halved).
    pub direction_flips: usize,
}

/// Why the compensation loop stopped.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Stop {
    /// Single-step mode.
    SingleStep,
    /// The RMSE of the change fell below the tolerance.
    Converged,
    /// The RMSE of the change stopped decreasing (direction reversals).
    Stalled,
    /// The iteration limit was reached.
    MaxIterations,
}

/// A compensated trajectory and how it was reached.
#[derive(Debug, Clone, PartialEq)]
pub struct Compensated {
    /// The corrected commands `Pm` (target orientation kept).
    pub commands: Trajectory,
    /// Nominal IK joints of the last evaluated commands (degrees; mm for a
    /// prismatic joint), one row per point.
    pub joints: Vec<Vec<f64>>,
    /// Direction coefficients λ (±1) of those joints in visiting order, one row per point.
    pub dir: Vec<Vec<f64>>,
    /// Predicted error δ̂ at those joints, mm.
    pub predicted: Vec<[f64; 3]>,
    /// One entry per iteration run, in order.
    pub history: Vec<Iteration>,
    /// Whether the change fell below the tolerance (always true for single-step).
    pub converged: bool,
    /// Why the loop stopped.
    pub stop: Stop,
    /// Points whose λ changed in the last iteration (direction reversals the
    /// feed-forward loop cannot settle), in order.
    pub unsettled: Vec<usize>,
}

impl Compensated {
    /// The commands as program moves, in order: the joints of each command
    /// ([`Compensated::joints`]), every one a point of the path — a motion
    /// target, not a measurement (`measure = false`, label `path`).
    pub fn program_poses(&self) -> Vec<ProgramPose> {
        self.joints
            .iter()
            .map(|q| ProgramPose::via(q.clone()).with_label("path"))
            .collect()
    }
}

/// Where the compensated commands go: a trajectory CSV, or a robot program
/// of their joints ([`Compensated::program_poses`]). Made before the
/// compensation, so that a program the robot cannot run (a KRL file name
/// that is not a KRL name, a SCARA in URScript) is refused before any work.
#[derive(Debug, Clone, PartialEq)]
pub struct CommandsOutput {
    path: PathBuf,
    program: Option<(ProgramFormat, ProgramOptions)>,
}

impl CommandsOutput {
    /// The output `path` for `robot`'s commands: a trajectory CSV when
    /// `format` is `None`, else a program in `format` named after the file
    /// ([`program::program_name`]), with the default speeds and settle time.
    pub fn new(path: &Path, format: Option<ProgramFormat>, robot: &Robot) -> Result<Self> {
        let program = match format {
            None => None,
            Some(f) => Some((
                f,
                ProgramOptions::for_file(path, f, robot.prismatic_joints())?,
            )),
        };
        Ok(CommandsOutput {
            path: path.to_path_buf(),
            program,
        })
    }

    /// Write `res`'s commands (atomically).
    pub fn write(&self, res: &Compensated) -> Result<()> {
        match &self.program {
            None => res.commands.write_csv(&self.path),
            Some((f, opts)) => program::write(&self.path, &res.program_poses(), *f, opts),
        }
    }
}

/// Nominal IK of every command (see [`first_pass_joints`] for the first
/// pass); later passes seed each point from its own previous solution (the
/// commands moved by a fraction of a millimetre), in parallel. Failures are
/// collected by index.
fn solve_joints(
    robot: &Robot,
    traj: &Trajectory,
    poses: &[Isometry3<f64>],
    start: &[f64],
    previous: Option<&[Vec<f64>]>,
    hints: Option<&[Vec<f64>]>,
    opts: &IkOptions,
) -> Result<Vec<Vec<f64>>> {
    let results: Vec<Result<Vec<f64>>> = match previous {
        None => first_pass_joints(robot, traj.has_orientation, poses, start, hints, opts),
        Some(prev) => poses
            .par_iter()
            .zip(prev)
            .map(|(p, q0)| robot.ik(&path_target(traj.has_orientation, p), q0, opts))
            .collect(),
    };
    all_reached(results)
}

/// `model`'s errors at the joints `q` (directions `dir`) visited in order
/// from `start`: predicted along `[start, q…]` and the start's own dropped,
/// so that history features (moves, previous λ) see the move from the start
/// into the first point. The start's λ is taken as +1 (its own history is
/// unknown).
pub fn predict_along<M: ErrorPredictor + ?Sized>(
    model: &M,
    start: &[f64],
    q: &[Vec<f64>],
    dir: &[Vec<f64>],
) -> Result<Vec<[f64; 3]>> {
    let path: Vec<Vec<f64>> = std::iter::once(start.to_vec())
        .chain(q.iter().cloned())
        .collect();
    let dirs: Vec<Vec<f64>> = std::iter::once(vec![1.0; start.len()])
        .chain(dir.iter().cloned())
        .collect();
    let mut out = model.predict_errors(&path, &dirs)?;
    out.remove(0);
    Ok(out)
}

/// Compensate the target trajectory `targets` for `robot` with `model`.
///
/// ```
/// use robokrige::compensate::{CompensationOptions, compensate};
/// use robokrige::{dataset::read_csv, kinematics, trajectory::Trajectory};
/// use robokrige::{kriging::KrigingOptions, model::ErrorModel, space::Space};
/// let dir = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/");
/// let data = read_csv(format!("{dir}comau_lhs.csv").as_ref())?;
/// let model = ErrorModel::fit(&data.select(&(0..60).collect::<Vec<_>>()), Space::Ejs,
///     &KrigingOptions::default())?;
/// let robot = kinematics::preset("comau-nj220")?;
/// let circle = Trajectory::read_csv(format!("{dir}comau_circle.csv").as_ref())?;
/// let out = compensate(&robot, &model, &circle, &CompensationOptions::default())?;
/// assert_eq!(out.commands.poses.len(), circle.poses.len()); // send these instead
/// # Ok::<(), robokrige::Error>(())
/// ```
pub fn compensate<M: ErrorPredictor + ?Sized>(
    robot: &Robot,
    model: &M,
    targets: &Trajectory,
    opts: &CompensationOptions,
) -> Result<Compensated> {
    opts.validate()?;
    if targets.is_empty() {
        return Err(Error::InvalidParameter(
            "the trajectory has no points".into(),
        ));
    }
    if model.n_joints() != robot.dof() {
        return Err(Error::JointCount {
            expected: robot.dof(),
            got: model.n_joints(),
        });
    }
    let start = robot.start_or_home(opts.start.as_deref())?;
    let n = targets.len();
    if let Some(h) = &opts.hints {
        if h.len() != n {
            return Err(Error::InvalidParameter(format!(
                "{} IK hints for {n} trajectory points",
                h.len()
            )));
        }
        for q in h {
            robot.check_len(q)?;
        }
    }
    let mut commands: Vec<Isometry3<f64>> = targets.poses.clone();
    let mut joints: Option<Vec<Vec<f64>>> = None;
    let mut history = Vec::new();
    let mut step = vec![1.0f64; n];
    let mut prev_dir: Option<Vec<Vec<f64>>> = None;
    let max_iter = if opts.iterative { opts.max_iter } else { 1 };
    loop {
        let q = solve_joints(
            robot,
            targets,
            &commands,
            &start,
            joints.as_deref(),
            opts.hints.as_deref(),
            &opts.ik,
        )?;
        let dir = derive_directions(&q, Some(&start));
        let pred = predict_along(model, &start, &q, &dir)?;
        let mut flipped = Vec::new();
        if let Some(pd) = &prev_dir {
            for (i, (a, b)) in dir.iter().zip(pd).enumerate() {
                if a != b {
                    flipped.push(i);
                    // bisection toward the λ switching boundary
                    step[i] *= 0.5;
                }
            }
        }
        let (mut sum2, mut max, mut mean_pred) = (0.0f64, 0.0f64, 0.0);
        let next: Vec<Isometry3<f64>> = (0..n)
            .map(|i| {
                let pd = &targets.poses[i];
                let d = Vector3::from(pred[i]);
                let old = commands[i].translation.vector;
                let change = (pd.translation.vector - d - old) * step[i];
                let c = change.norm();
                sum2 += c * c;
                max = max.max(c);
                mean_pred += d.norm() / n as f64;
                Isometry3::from_parts(Translation3::from(old + change), pd.rotation)
            })
            .collect();
        let rmse = (sum2 / n as f64).sqrt();
        history.push(Iteration {
            iteration: history.len() + 1,
            rmse_change_mm: rmse,
            max_change_mm: max,
            mean_predicted_mm: mean_pred,
            direction_flips: flipped.len(),
        });
        let k = history.len();
        let stop = if !opts.iterative {
            Some(Stop::SingleStep)
        } else if rmse < opts.tol_mm {
            Some(Stop::Converged)
        } else if k >= 4 && rmse > 0.9 * history[k - 3].rmse_change_mm {
            Some(Stop::Stalled)
        } else if k >= max_iter {
            Some(Stop::MaxIterations)
        } else {
            None
        };
        if let Some(stop) = stop {
            let converged = matches!(stop, Stop::SingleStep | Stop::Converged);
            // the final commands are `next`; their joints are solved for the report
            let q_final = solve_joints(robot, targets, &next, &start, Some(&q), None, &opts.ik)?;
            let dir_final = derive_directions(&q_final, Some(&start));
            let predicted = predict_along(model, &start, &q_final, &dir_final)?;
            return Ok(Compensated {
                commands: Trajectory {
                    poses: next,
                    has_orientation: targets.has_orientation,
                },
                joints: q_final,
                dir: dir_final,
                predicted,
                history,
                converged,
                stop,
                unsettled: flipped,
            });
        }
        commands = next;
        joints = Some(q);
        prev_dir = Some(dir);
    }
}
