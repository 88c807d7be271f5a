//! `robokrige compensate` and `robokrige evaluate`.

use super::progress::with_spinner;
use clap::Args;
use robokrige::Result;
use robokrige::compensate::{CommandsOutput, compensate};
use robokrige::physics::AnyModel;
use robokrige::program::ProgramFormat;
use robokrige::report::compensate as report;
use robokrige::study::{
    GivenOrientation, Targets, before_after, evaluate_file, evaluate_on_file, load_truth,
    named_runs, truth_robot,
};
use std::path::{Path, PathBuf};

#[derive(Debug, Args)]
#[command(after_help = "\
TRAJ.csv is either a trajectory (x,y,z[,roll_deg,pitch_deg,yaw_deg]) or a pose
list with q1..qN columns, whose nominal TCP poses become the targets.

Example:
  robokrige fit datasets/comau_lhs.csv --method ejs-gps -o ejs.json
  robokrige compensate --model ejs.json --robot comau-nj220 datasets/comau_circle.csv \\
      -o circle_comp.csv --iterative --truth datasets/comau_circle.truth.json --plot circle.svg
  robokrige compensate --model ejs.json --robot comau-nj220 datasets/comau_circle.csv \\
      -o circle_comp.src --iterative --format krl")]
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
    /// Output: the corrected commands as a trajectory CSV, or with
    /// --format a robot program of their joints.
    #[arg(short, long)]
    output: PathBuf,
    /// Write the commands' joints (nominal IK) as a program of joint moves
    /// instead of a trajectory CSV; every move is a path point ("via").
    #[arg(long, value_enum)]
    format: Option<ProgramFormat>,
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
    /// The value of a covariate the model uses (e.g. temp_c=24.5) while the
    /// trajectory runs; repeat for several. Without it a covariate takes
    /// its value at the start of the measured campaign, with a warning.
    #[arg(long = "covariate", value_name = "NAME=VALUE", value_parser = parse_covariate)]
    covariates: Vec<(String, f64)>,
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

/// The measured 3D error along the trajectory, one line per run.
fn plot(path: &Path, title: &str, runs: &[(String, Vec<[f64; 3]>)]) -> Result<()> {
    robokrige::plot::measured_errors(path, title, runs)?;
    say!("plot: {}", path.display());
    Ok(())
}

pub fn run_compensate(a: CompensateArgs) -> Result<()> {
    let inputs = [Some(&*a.traj), Some(&*a.model), a.truth.as_deref()];
    let outputs = [Some(&*a.output), a.plot.as_deref(), a.json.as_deref()];
    super::check_files(&inputs, &outputs)?;
    let robot = robokrige::kinematics::load_robot_with_tool(&a.robot, a.tool.as_deref())?;
    let commands_out = CommandsOutput::new(&a.output, a.format, &robot)?;
    let model = at_covariates(
        AnyModel::load_for(&a.model, &robot)?,
        &a.covariates,
        &a.traj,
    )?;
    let start = robot.start_or_home(a.start.as_deref())?;
    let targets = Targets::read(
        &a.traj,
        &robot,
        a.orientation.as_deref().map(|rpy_deg| GivenOrientation {
            rpy_deg,
            named: "--orientation",
        }),
        &start,
    )?;
    super::warn(&targets.warnings);
    let opts = targets.compensation_options(&start);
    let opts = opts.iterations(a.iterative, a.tol, a.max_iter);
    let t0 = std::time::Instant::now();
    let res = with_spinner("compensate", |_| {
        compensate(&robot, &model, &targets.traj, &opts)
    })
    .map_err(|e| {
        targets.explain(
            e,
            "the task's orientation with --orientation roll,pitch,yaw, or a start pose (--start) whose tool points as the task needs",
        )
    })?;
    let secs = t0.elapsed().as_secs_f64();
    super::print_coverage(&model.coverage_of(&res)?, res.joints.len(), None);
    commands_out.write(&res)?;
    let text = report::iterations(&res, a.iterative, &model.describe(), secs, &a.output);
    say_part!("{text}");
    super::warn(report::stop_warning(&res, a.tol, a.max_iter));
    let mut eval = None;
    if let Some(tp) = &a.truth {
        let (ev, runs) = evaluate_on_file(tp, &robot, &targets, &res.commands, &start, a.seed)?;
        say_part!("{}", report::evaluation(tp, &ev));
        if let Some(p) = &a.plot {
            let title = report::plot_title(&a.traj, a.iterative, &model);
            plot(p, &title, &before_after(runs))?;
        }
        eval = Some(ev);
    }
    let files = report::Files {
        targets: &a.traj,
        output: &a.output,
        model: &a.model,
    };
    let run = (&res, a.iterative, secs);
    let v = report::json(files, (&robot.name, &model), run, eval.as_ref());
    super::json_to(a.json.as_deref(), &v, "compensation report")
}

/// `NAME=VALUE` of `--covariate`.
fn parse_covariate(s: &str) -> std::result::Result<(String, f64), String> {
    let (name, value) = s
        .split_once('=')
        .ok_or_else(|| format!("'{s}': expected NAME=VALUE, e.g. temp_c=24.5"))?;
    let v: f64 = value
        .trim()
        .parse()
        .map_err(|_| format!("'{s}': the value '{value}' is not a number"))?;
    if name.trim().is_empty() || !v.is_finite() {
        return Err(format!("'{s}': expected NAME=VALUE with a finite value"));
    }
    Ok((name.trim().to_string(), v))
}

/// The model with the covariates `given` held at their values; a warning
/// for each covariate it uses that is not given (the value it takes, and
/// that a column of that name in `traj` is not read).
fn at_covariates(model: AnyModel, given: &[(String, f64)], traj: &Path) -> Result<AnyModel> {
    let AnyModel::Kriging(m) = model else {
        if let Some((name, _)) = given.first() {
            return Err(robokrige::Error::InvalidParameter(format!(
                "--covariate {name}: a physics model uses no covariate"
            )));
        }
        return Ok(model);
    };
    let mut m = *m;
    let used = m.covariates();
    for (name, value) in given {
        m = m.at_covariate(name, *value)?;
    }
    // the trajectory's header only (Targets::read reads the file)
    let mut header = String::new();
    if let Ok(f) = std::fs::File::open(traj) {
        use std::io::BufRead;
        let _ = std::io::BufReader::new(f).read_line(&mut header);
    }
    for (name, reference) in used {
        if given.iter().any(|(n, _)| *n == name) {
            continue;
        }
        let note = if header.split(',').any(|c| c.trim() == name) {
            format!(
                " ({} has a '{name}' column; compensate does not read it)",
                traj.display()
            )
        } else {
            String::new()
        };
        let Some(v) = reference else {
            return Err(robokrige::Error::InvalidParameter(format!(
                "the model uses covariate '{name}' and records no value for it{note}: give the value the trajectory runs at with --covariate {name}=VALUE"
            )));
        };
        super::warn([format!(
            "the model uses covariate '{name}': compensating at {v} (its value at the start of the measured campaign){note}; give the value the trajectory runs at with --covariate {name}=VALUE"
        )]);
    }
    Ok(AnyModel::Kriging(Box::new(m)))
}

pub fn run_evaluate(a: EvaluateArgs) -> Result<()> {
    let mut inputs = vec![Some(&*a.traj), Some(&*a.truth)];
    inputs.extend(a.compensated.iter().map(|p| Some(p.as_path())));
    super::check_files(&inputs, &[a.plot.as_deref(), a.json.as_deref()])?;
    let truth = load_truth(&a.truth)?;
    let robot = truth_robot(&truth, a.robot.as_deref(), &a.truth)?;
    let start = robot.start_or_home(a.start.as_deref())?;
    let targets = Targets::read(&a.traj, &robot, None, &start)?;
    super::warn(&targets.warnings);
    let mut evals = Vec::new();
    say!("measured error vs target on the simulated robot (mm):");
    for path in &a.compensated {
        let e = evaluate_file((&a.truth, &truth), &targets, path, &start, a.seed)?;
        say_part!("{}", report::file_evaluation(&e, evals.is_empty()));
        evals.push(e);
    }
    if let Some(p) = &a.plot {
        let title = "measured error before and after compensation";
        plot(p, title, &named_runs(&evals))?;
    }
    let v = report::evaluations_json(&a.truth, &a.traj, a.seed, &evals);
    super::json_to(a.json.as_deref(), &v, "evaluation")
}
