//! `robokrige compensate` and `robokrige evaluate`.

use super::progress::spinner;
use clap::Args;
use nalgebra::{Isometry3, UnitQuaternion};
use robokrige::compensate::{Compensated, CompensationOptions, Stop, compensate};
use robokrige::kinematics::{self, Robot};
use robokrige::physics::AnyModel;
use robokrige::plot::{Labels, Series, xy_plot};
use robokrige::sim::{Truth, execute, rng_for};
use robokrige::stats::{PositionErrorTable, position_error_table};
use robokrige::trajectory::{TargetFile, Trajectory};
use robokrige::{Error, Result};
use serde::Serialize;
use std::path::{Path, PathBuf};

/// Pre-compensate a trajectory with a fitted error model (feed-forward).
#[derive(Debug, Args)]
#[command(after_help = "\
TRAJ.csv is either a trajectory (x,y,z[,roll_deg,pitch_deg,yaw_deg]) or a pose
list with q1..qN columns, whose nominal TCP poses become the targets.

Example:
  robokrige fit datasets/comau_lhs.csv --method ejs-gps -o ejs.json
  robokrige compensate --model ejs.json --robot comau-nj220 datasets/comau_circle.csv \\
      -o circle_comp.csv --iterative --truth datasets/comau_circle.truth.json --plot circle.svg")]
pub struct CompensateArgs {
    /// Target trajectory CSV, in visiting order.
    traj: PathBuf,
    /// Fitted model JSON (`robokrige fit`).
    #[arg(long)]
    model: PathBuf,
    /// The robot whose nominal kinematics the controller uses: a preset name
    /// or a robot file (TOML/JSON). Must be the robot the model records.
    #[arg(long)]
    robot: String,
    /// TCP offset in the flange frame, mm ("x,y,z"), replacing the robot's tool.
    #[arg(long)]
    tool: Option<String>,
    /// Output: the corrected commands as a trajectory CSV.
    #[arg(short, long)]
    output: PathBuf,
    /// Iterate (seed 004) instead of the single step (seed 003).
    #[arg(long)]
    iterative: bool,
    /// Stop iterating when the RMSE of the change is below this (mm; with --iterative).
    #[arg(long, default_value_t = 1e-3, requires = "iterative")]
    tol: f64,
    /// Maximum iterations (with --iterative).
    #[arg(long, default_value_t = 10, requires = "iterative")]
    max_iter: usize,
    /// Joint values the robot starts from, comma-separated [default: home].
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    start: Option<Vec<f64>>,
    /// Tool orientation for position-only trajectories (roll,pitch,yaw deg)
    /// [default: the start pose's orientation].
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    orientation: Option<Vec<f64>>,
    /// Simulator truth: also run the nominal and compensated commands on the
    /// simulated robot and report the errors before and after.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Seed of the simulated measurement noise (with --truth).
    #[arg(long, default_value_t = 1, requires = "truth")]
    seed: u64,
    /// Before/after plot (SVG, with --truth).
    #[arg(long, requires = "truth")]
    plot: Option<PathBuf>,
    /// Write the iteration history (and the evaluation) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Run target and compensated trajectories on a simulated robot and compare.
#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige evaluate --truth datasets/comau_circle.truth.json datasets/comau_circle.csv circle_comp.csv --json eval.json")]
pub struct EvaluateArgs {
    /// Target trajectory (x,y,z,… or q1..qN poses).
    traj: PathBuf,
    /// Compensated command trajectories to compare (one or more).
    #[arg(required = true)]
    compensated: Vec<PathBuf>,
    /// Simulator truth JSON (`robokrige simulate` writes it).
    #[arg(long)]
    truth: PathBuf,
    /// Robot: preset name or robot file (checked against the truth's nominal robot) [default: the truth's].
    #[arg(long)]
    robot: Option<String>,
    /// Joint values the robot starts from [default: home].
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true)]
    start: Option<Vec<f64>>,
    /// Seed of the measurement noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Plot the 3D error along the path, nominal and each compensated
    /// trajectory (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
    /// Write the errors (mean, max, RMS per axis) of every trajectory as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

/// Target poses, and for a q1..qN pose list the joints as IK hints.
pub(super) struct Targets {
    pub(super) traj: Trajectory,
    pub(super) hints: Option<Vec<Vec<f64>>>,
}

/// Targets from a trajectory CSV or from the nominal FK of a q1..qN pose list.
pub(super) fn read_targets(
    path: &Path,
    robot: &Robot,
    orientation: Option<&[f64]>,
    start: &[f64],
) -> Result<Targets> {
    let mut hints = None;
    let mut t = match robokrige::trajectory::read_target_file(path)? {
        TargetFile::Joints(d) => {
            for w in d.warnings() {
                eprintln!("warning: {w}");
            }
            robot.check_dataset(&d)?;
            let t = Trajectory::new(d.q.iter().map(|q| robot.fk(q)).collect::<Result<_>>()?);
            hints = Some(d.q);
            t
        }
        TargetFile::Tcp(t) => t,
    };
    if orientation.is_some() && (t.has_orientation || hints.is_some() || robot.dof() < 6) {
        return Err(Error::InvalidParameter(format!(
            "--orientation is for position-only (x,y,z) trajectories of a six-axis robot; {} {}",
            path.display(),
            if hints.is_some() {
                "is a pose list (its orientations come from the joints)"
            } else if t.has_orientation {
                "has its own roll,pitch,yaw columns"
            } else {
                "is for a robot with fewer than six joints"
            }
        )));
    }
    if !t.has_orientation && robot.dof() >= 6 {
        let rot = match orientation {
            Some(&[r, p, y]) => {
                UnitQuaternion::from_euler_angles(r.to_radians(), p.to_radians(), y.to_radians())
            }
            Some(_) => {
                return Err(Error::InvalidParameter(
                    "--orientation needs three angles: roll,pitch,yaw (deg)".into(),
                ));
            }
            None => robot.fk(start)?.rotation,
        };
        for p in &mut t.poses {
            *p = Isometry3::from_parts(p.translation, rot);
        }
        t.has_orientation = true;
    }
    Ok(Targets { traj: t, hints })
}

pub(super) fn load_truth(path: &Path) -> Result<Truth> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    let truth: Truth = serde_json::from_str(&text).map_err(|e| Error::Json {
        context: format!("{}: not a simulator truth file", path.display()),
        source: e,
    })?;
    if truth.format != robokrige::sim::campaign::TRUTH_FORMAT {
        return Err(Error::Input {
            source_name: path.display().to_string(),
            message: format!("format '{}' is not a simulator truth", truth.format),
        });
    }
    Ok(truth)
}

/// Errors `measured − target` of running `commands` on the truth's robot.
fn run_on(
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
        .map(|(m, p)| {
            let t = p.translation.vector;
            [m[0] - t[0], m[1] - t[1], m[2] - t[2]]
        })
        .collect())
}

/// Measured errors (mm) of the nominal and the compensated runs.
pub(super) type Runs = (Vec<[f64; 3]>, Vec<[f64; 3]>);

#[derive(Serialize)]
pub(super) struct Evaluation {
    truth: PathBuf,
    seed: u64,
    points: usize,
    pub(super) before: PositionErrorTable,
    pub(super) after: PositionErrorTable,
    reduction_mean_abs_pct: f64,
    reduction_max_abs_pct: f64,
}

pub(super) fn evaluation(
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

fn norms(e: &[[f64; 3]]) -> Vec<(f64, f64)> {
    e.iter()
        .enumerate()
        .map(|(i, v)| (i as f64, (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt()))
        .collect()
}

fn print_table(label: &str, t: &PositionErrorTable) {
    say!(
        "  {label:<22} mean x/y/z {:>8.4} {:>8.4} {:>8.4}   |δ| mean {:.4}  std {:.4}  min {:.4}  max {:.4}",
        t.mean_mm[0],
        t.mean_mm[1],
        t.mean_mm[2],
        t.mean_abs_mm,
        t.std_abs_mm,
        t.min_abs_mm,
        t.max_abs_mm
    );
}

fn plot(path: &Path, title: &str, runs: &[(String, Vec<[f64; 3]>)]) -> Result<()> {
    let series: Vec<Series> = runs
        .iter()
        .map(|(n, e)| Series::line(n.clone(), norms(e)))
        .collect();
    let labels = Labels {
        title,
        x: "trajectory point",
        y: "measured 3D position error (mm)",
    };
    xy_plot(path, &labels, &series, false)?;
    say!("plot: {}", path.display());
    Ok(())
}

pub fn run_compensate(a: CompensateArgs) -> Result<()> {
    let mut inputs = vec![a.traj.as_path(), a.model.as_path()];
    inputs.extend(a.truth.as_deref());
    let mut outputs = vec![a.output.as_path()];
    outputs.extend(a.plot.as_deref());
    outputs.extend(a.json.as_deref());
    robokrige::output::check_outputs(&inputs, &outputs)?;
    let robot = super::robot_with_tool(&a.robot, a.tool.as_deref())?;
    let model = AnyModel::load(&a.model)?;
    let model_name = a.model.display().to_string();
    match &model {
        AnyModel::Kriging(m) => m.check_robot(&robot, &model_name)?,
        AnyModel::Physics(m) => {
            robokrige::model::RobotRecord::of(&m.nominal).check(&robot, &model_name)?
        }
    }
    let start = a.start.clone().unwrap_or_else(|| robot.home.clone());
    robot.check_len(&start)?;
    let targets = read_targets(&a.traj, &robot, a.orientation.as_deref(), &start)?;
    let opts = CompensationOptions {
        iterative: a.iterative,
        tol_mm: a.tol,
        max_iter: a.max_iter,
        start: Some(start.clone()),
        hints: targets.hints.clone(),
        ..CompensationOptions::default()
    };
    let pb = spinner("compensate");
    let t0 = std::time::Instant::now();
    let res = compensate(&robot, &model, &targets.traj, &opts);
    pb.finish_and_clear();
    let res: Compensated = res?;
    let secs = t0.elapsed().as_secs_f64();
    if let AnyModel::Kriging(m) = &model {
        // the means the compensation used; no standard deviations (they
        // would need the m × m factor)
        let coverage = m.coverage(&res.joints, &res.dir, &res.predicted, None)?;
        super::print_coverage(&coverage, res.joints.len(), None);
    }
    res.commands.write_csv(&a.output)?;
    say!(
        "{} {} points with {} in {secs:.3} s -> {}",
        if a.iterative {
            "iteratively compensated"
        } else {
            "compensated (single step)"
        },
        targets.traj.len(),
        model.describe(),
        a.output.display()
    );
    for it in &res.history {
        say!(
            "  iteration {:>2}: RMSE of the change {:.5} mm (max {:.5}), mean predicted |δ̂| {:.4} mm, λ flips {}",
            it.iteration,
            it.rmse_change_mm,
            it.max_change_mm,
            it.mean_predicted_mm,
            it.direction_flips
        );
    }
    match res.stop {
        Stop::Stalled => eprintln!(
            "warning: the change stalled above {} mm at direction reversals; λ still switching at points {}",
            a.tol,
            list(&res.unsettled)
        ),
        Stop::MaxIterations => eprintln!(
            "warning: the change did not fall below {} mm in {} iterations",
            a.tol, a.max_iter
        ),
        Stop::Converged | Stop::SingleStep => {}
    }
    let mut eval = None;
    if let Some(tp) = &a.truth {
        let truth = load_truth(tp)?;
        check_robot(&truth, &robot, tp)?;
        let (ev, (before, after)) =
            evaluation(tp, &truth, &targets, &res.commands, &start, a.seed)?;
        say!(
            "on the simulated robot ({}), measured error vs target (mm):",
            tp.display()
        );
        print_table("before (nominal)", &ev.before);
        print_table("after (compensated)", &ev.after);
        say!(
            "  reduction: mean |δ| {:.1} %, max |δ| {:.1} %",
            ev.reduction_mean_abs_pct,
            ev.reduction_max_abs_pct
        );
        if let Some(p) = &a.plot {
            let name = a
                .traj
                .file_stem()
                .and_then(|s| s.to_str())
                .unwrap_or("trajectory");
            let mode = if a.iterative {
                "iterative"
            } else {
                "single-step"
            };
            let space = model.label();
            let title = format!("{name}: {mode} compensation, {space} model");
            plot(
                p,
                &title,
                &[("before".into(), before), ("after".into(), after)],
            )?;
        }
        eval = Some(ev);
    }
    if let Some(path) = &a.json {
        let mut v = serde_json::json!({
            "targets": a.traj, "output": a.output, "model": a.model, "robot": robot.name,
            "space": match &model {
                AnyModel::Kriging(m) => serde_json::to_value(m.space).expect("plain enum"),
                AnyModel::Physics(_) => "physics".into(),
            }, "iterative": a.iterative, "converged": res.converged,
            "stop": res.stop, "unsettled": res.unsettled,
            "iterations": res.history, "seconds": secs,
        });
        if let Some(ev) = eval {
            v["before"] = serde_json::to_value(ev.before).expect("plain numbers");
            v["after"] = serde_json::to_value(ev.after).expect("plain numbers");
            v["evaluation"] = serde_json::to_value(&ev).expect("plain numbers");
        }
        super::write_json(path, &v, "compensation report")?;
    }
    Ok(())
}

/// Up to 12 indices, then an ellipsis.
fn list(v: &[usize]) -> String {
    let mut s: Vec<String> = v.iter().take(12).map(usize::to_string).collect();
    if v.len() > 12 {
        s.push(format!("… ({} in all)", v.len()));
    }
    s.join(", ")
}

/// Error unless the truth's nominal robot has `robot`'s kinematic table.
fn check_robot(truth: &Truth, robot: &Robot, path: &Path) -> Result<()> {
    let nominal = &truth.robot.nominal;
    if kinematics::table_digest(nominal) != kinematics::table_digest(robot) {
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

pub fn run_evaluate(a: EvaluateArgs) -> Result<()> {
    let mut inputs = vec![a.traj.as_path(), a.truth.as_path()];
    inputs.extend(a.compensated.iter().map(PathBuf::as_path));
    let outputs: Vec<&Path> = a.plot.iter().chain(&a.json).map(PathBuf::as_path).collect();
    robokrige::output::check_outputs(&inputs, &outputs)?;
    let truth = load_truth(&a.truth)?;
    let robot = match &a.robot {
        Some(name) => {
            let robot = kinematics::load_robot(name)?;
            check_robot(&truth, &robot, &a.truth)?;
            robot
        }
        None => truth.robot.nominal.clone(),
    };
    let start = a.start.clone().unwrap_or_else(|| robot.home.clone());
    robot.check_len(&start)?;
    let targets = read_targets(&a.traj, &robot, None, &start)?;
    let mut runs = Vec::new();
    let mut reports = Vec::new();
    say!("measured error vs target on the simulated robot (mm):");
    for (k, path) in a.compensated.iter().enumerate() {
        let commands = Trajectory::read_csv(path)?;
        if commands.len() != targets.traj.len() {
            return Err(Error::Input {
                source_name: path.display().to_string(),
                message: format!(
                    "has {} points but the target trajectory has {}",
                    commands.len(),
                    targets.traj.len()
                ),
            });
        }
        let (ev, (before, after)) =
            evaluation(&a.truth, &truth, &targets, &commands, &start, a.seed)?;
        if k == 0 {
            print_table("before (nominal)", &ev.before);
            runs.push(("before".to_string(), before));
        }
        let name = path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("compensated")
            .to_string();
        print_table(&name, &ev.after);
        say!(
            "  {:<22} reduction: mean |δ| {:.1} %, max |δ| {:.1} %",
            "",
            ev.reduction_mean_abs_pct,
            ev.reduction_max_abs_pct
        );
        runs.push((name.clone(), after));
        reports.push(serde_json::json!({"file": path, "evaluation": ev}));
    }
    if let Some(p) = &a.plot {
        plot(p, "measured error before and after compensation", &runs)?;
    }
    if let Some(path) = &a.json {
        let first = &reports[0]["evaluation"];
        let v = serde_json::json!({
            "truth": a.truth, "targets": a.traj, "seed": a.seed,
            "before": first["before"], "after": first["after"], "compensated": reports,
        });
        super::write_json(path, &v, "evaluation")?;
    }
    Ok(())
}
