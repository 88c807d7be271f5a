//! `robokrige compensate` and `robokrige evaluate`.

use super::progress::spinner;
use clap::Args;
use robokrige::Result;
use robokrige::compensate::{Compensated, CompensationOptions, compensate};
use robokrige::kinematics::{self, Robot};
use robokrige::physics::AnyModel;
use robokrige::plot::{Labels, error_along_path};
use robokrige::report::compensate as report;
use robokrige::study::{Targets, check_truth_robot, evaluate, load_truth};
use robokrige::trajectory::Trajectory;
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

/// The targets of `path` (see [`Targets::read`]), its warnings shown.
pub(super) fn read_targets(
    path: &Path,
    robot: &Robot,
    orientation: Option<&[f64]>,
    start: &[f64],
) -> Result<Targets> {
    let t = Targets::read(path, robot, orientation, start)?;
    for w in &t.warnings {
        eprintln!("warning: {w}");
    }
    Ok(t)
}

/// The measured 3D error along the trajectory, one line per run.
fn plot(path: &Path, title: &str, runs: &[(String, Vec<[f64; 3]>)]) -> Result<()> {
    let labels = Labels {
        title,
        x: "trajectory point",
        y: "measured 3D position error (mm)",
    };
    error_along_path(path, &labels, runs)?;
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
    let robot = robokrige::kinematics::load_robot_with_tool(&a.robot, a.tool.as_deref())?;
    let model = AnyModel::load(&a.model)?;
    model.check_robot(&robot, &a.model.display().to_string())?;
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
    let output = a.output.display().to_string();
    let text = report::iterations(&res, a.iterative, &model.describe(), secs, &output);
    say_part!("{text}");
    if let Some(w) = report::stop_warning(&res, a.tol, a.max_iter) {
        eprintln!("{w}");
    }
    let mut eval = None;
    if let Some(tp) = &a.truth {
        let truth = load_truth(tp)?;
        check_truth_robot(&truth, &robot, tp)?;
        let (ev, (before, after)) = evaluate(tp, &truth, &targets, &res.commands, &start, a.seed)?;
        say_part!("{}", report::evaluation(&tp.display().to_string(), &ev));
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
        let files = report::Files {
            targets: &a.traj,
            output: &a.output,
            model: &a.model,
        };
        let run = (&res, a.iterative, secs);
        let v = report::json(files, (&robot.name, &model), run, eval.as_ref());
        super::write_json(path, &v, "compensation report")?;
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
            check_truth_robot(&truth, &robot, &a.truth)?;
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
        targets.check_commands(&commands, path)?;
        let (ev, (before, after)) =
            evaluate(&a.truth, &truth, &targets, &commands, &start, a.seed)?;
        if k == 0 {
            say!("{}", report::table_line("before (nominal)", &ev.before));
            runs.push(("before".to_string(), before));
        }
        let name = path
            .file_name()
            .and_then(|s| s.to_str())
            .unwrap_or("compensated")
            .to_string();
        say!("{}", report::table_line(&name, &ev.after));
        say!("{}", report::reduction_line(&format!("{:<22} ", ""), &ev));
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
