//! Subcommands. Exit codes: 0 ok, 1 failed (bad data, numerical failure),
//! 2 bad usage (clap).

/// Text of the report: standard output, or standard error when a
/// `--json -` has claimed standard output for the JSON.
macro_rules! say_part {
    ($($t:tt)*) => {
        if $crate::cli::text_to_stderr() {
            eprint!($($t)*)
        } else {
            print!($($t)*)
        }
    };
}

/// A line of the text report ([`say_part!`] with a newline).
macro_rules! say {
    ($($t:tt)*) => {
        say_part!("{}\n", format_args!($($t)*))
    };
}

mod batch;
mod compensate;
mod cv;
mod demo;
mod diagnose;
mod fit;
mod holdout;
mod import;
mod physics;
mod plan;
mod progress;
mod robot;
mod run;
mod simulate;

use clap::{CommandFactory, Parser, Subcommand};
use robokrige::Result;
use robokrige::model::CoverageWarning;
use robokrige::report::predict;
use serde::Serialize;
use std::path::Path;

/// robokrige: Kriging error models over the extended joint space [θ, λ] for
/// industrial robot accuracy.
#[derive(Debug, Parser)]
#[command(name = "robokrige", version, about, long_about = None)]
pub struct Cli {
    #[command(subcommand)]
    pub command: Command,
}

#[derive(Debug, Subcommand)]
pub enum Command {
    /// Run the main job on the default COMAU campaign and write a report.
    Demo(demo::DemoArgs),
    /// Simulate a laser-tracker campaign on a "true robot" (geometric errors,
    /// backlash, compliance, noise, optional undeclared effects).
    Simulate(simulate::SimulateArgs),
    /// Fit a universal-Kriging TCP error model over JS or EJS.
    Fit(fit::FitArgs),
    /// Predict TCP errors with a fitted model.
    Predict(fit::PredictArgs),
    /// K-fold cross-validation of a model choice.
    Cv(cv::CvArgs),
    /// Pre-compensate a trajectory with a fitted model (single-step or iterative).
    Compensate(compensate::CompensateArgs),
    /// Run target and compensated trajectories on a simulated robot and compare.
    Evaluate(compensate::EvaluateArgs),
    /// Find what the model misses, trace it to an effect, add it, report before/after.
    Diagnose(diagnose::DiagnoseArgs),
    /// Physics-based models (seeds 000, 002): identify from indexing tests, compare with Kriging.
    #[command(subcommand)]
    Physics(physics::PhysicsCommand),
    /// Train on the first rows of a campaign, score on the next: nominal, D-H
    /// calibration, hybrid, Kriging with the kinematic trend (JS and EJS).
    Holdout(holdout::HoldoutArgs),
    /// Turn a tracker or controller export (own columns, delimiter, decimal
    /// comma, units) into a measurement CSV; locate the tracker for errors.
    Import(import::ImportArgs),
    /// Run the steps of a config file (robokrige.toml): each a subcommand
    /// with its options, exactly as on the command line.
    Run(run::RunArgs),
    /// Fit and cross-validate every campaign of a folder (one robot each), in
    /// parallel: a report per campaign and a summary table.
    Batch(batch::BatchArgs),
    /// Robot files: show a preset or check your own (MD-H table, limits, tool, base).
    #[command(subcommand)]
    Robot(robot::RobotCommand),
    /// Plan a campaign: which poses to measure next (IMSE), from which side, in
    /// which order, and when to stop.
    Plan(plan::PlanArgs),
}

static TEXT_TO_STDERR: std::sync::atomic::AtomicBool = std::sync::atomic::AtomicBool::new(false);

/// Whether text reports go to standard error (see [`say!`]).
pub fn text_to_stderr() -> bool {
    TEXT_TO_STDERR.load(std::sync::atomic::Ordering::Relaxed)
}

/// Whether the command line sends JSON to standard output (`--json -`).
fn json_to_stdout(args: &[String]) -> bool {
    args.iter().any(|a| a == "--json=-") || args.windows(2).any(|w| w[0] == "--json" && w[1] == "-")
}

/// Run a parsed command.
pub fn run(cli: Cli) -> Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if let Some(why) = robokrige::config::dash_refusal(&Cli::command(), &args) {
        return Err(robokrige::Error::InvalidParameter(why));
    }
    TEXT_TO_STDERR.store(json_to_stdout(&args), std::sync::atomic::Ordering::Relaxed);
    dispatch(cli.command)
}

/// Run one subcommand (also each step of `run CONFIG`).
fn dispatch(command: Command) -> Result<()> {
    match command {
        Command::Run(a) => run::run(a),
        Command::Batch(a) => batch::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Fit(a) => fit::run_fit(a),
        Command::Robot(a) => robot::run(a),
        Command::Import(a) => import::run(a),
        Command::Predict(a) => fit::run_predict(a),
        Command::Cv(a) => cv::run(a),
        Command::Compensate(a) => compensate::run_compensate(a),
        Command::Evaluate(a) => compensate::run_evaluate(a),
        Command::Diagnose(a) => diagnose::run(a),
        Command::Physics(a) => physics::run(a),
        Command::Holdout(a) => holdout::run(a),
        Command::Plan(a) => plan::run(a),
    }
}

/// Write `value` as pretty JSON (with a final newline) to the file of a
/// `--json FILE` option, if given (`context` names it in an error); `-` is
/// standard output.
pub fn json_to(path: Option<&Path>, value: &impl Serialize, context: &str) -> Result<()> {
    let Some(path) = path else { return Ok(()) };
    let text = robokrige::output::json_text(value, context)?;
    if robokrige::output::is_stdout(path) {
        print!("{text}");
        return Ok(());
    }
    robokrige::output::write_text(path, &text)
}

/// Check a command's files before any work; `None`s are options not given.
pub use robokrige::output::check_given as check_files;

/// Print the plan of a large fit or diagnosis, as a command's memory
/// check returned it ([`robokrige::model::check_fit_rows`]).
pub fn print_plan(command: &str, plan: Option<impl std::fmt::Display>) {
    if let Some(plan) = plan {
        eprintln!("{command}: {plan}");
    }
}

/// Read a measurement CSV and print its plausibility warnings on stderr.
pub fn read_data(path: &Path) -> Result<robokrige::dataset::Dataset> {
    let d = robokrige::dataset::read_csv(path)?;
    warn(d.warnings());
    Ok(d)
}

/// Print `warnings` on stderr, a `warning: ` line each.
pub fn warn<W: std::fmt::Display>(warnings: impl IntoIterator<Item = W>) {
    for w in warnings {
        eprintln!("warning: {w}");
    }
}

/// Print the points that leave the campaign's coverage (at most 20 listed).
pub fn print_coverage(warnings: &[CoverageWarning], total: usize, ids: Option<&[String]>) {
    eprint!("{}", predict::coverage(warnings, total, ids));
}
