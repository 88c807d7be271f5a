//! `robot`: show a robot file (a preset's or your own), checked.

use clap::{Args, Subcommand};
use robokrige::Result;
use robokrige::kinematics::{self, RobotFile};
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
#[command(after_help = "\
A robot file describes a serial robot for every --robot option: its MD-H
table (one [[joints]] entry per axis: kind, theta_offset_deg, d_mm, a_mm,
alpha_deg, beta_deg, sign, limits, work_range, home), its tool and its base.
TOML, or JSON when the name ends in .json. Unknown keys are refused.

Examples:
  robokrige robot show ur10 -o myrobot.toml     # start from a preset
  robokrige robot show examples/robots/abb-irb2600.toml
  robokrige simulate --robot examples/robots/abb-irb2600.toml -o abb.csv")]
pub enum RobotCommand {
    /// Check a robot (preset name or file) and print it as a robot file,
    /// every default written out, with its kinematic-table digest.
    Show(ShowArgs),
    /// Write the identified kinematics of a calibrated model (`fit --robot`)
    /// as a robot file: load it into a controller, or use it as --robot for
    /// nominal-only work.
    Calibrated(CalibratedArgs),
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige fit campaign.csv --robot ur10 -o model.json
  robokrige robot calibrated model.json -o ur10-calibrated.toml")]
pub struct CalibratedArgs {
    /// A model file fitted with a calibration (`fit --robot R`).
    model: PathBuf,
    /// The robot file to write (TOML).
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the calibration's identifiability report (directions
    /// seen, observability indices, per-parameter values and standard
    /// errors) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
Examples:
  robokrige robot show comau-nj220
  robokrige robot show myrobot.toml --json -")]
pub struct ShowArgs {
    /// A preset name (comau-nj220, kuka-kr30ha, ur10, scara-rh3frh5515) or a
    /// robot file.
    robot: String,
    /// Write the robot file (TOML) here instead of printing it.
    #[arg(short, long)]
    output: Option<PathBuf>,
    /// Write it as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(command: RobotCommand) -> Result<()> {
    match command {
        RobotCommand::Show(s) => show(s),
        RobotCommand::Calibrated(c) => calibrated(c),
    }
}

fn calibrated(a: CalibratedArgs) -> Result<()> {
    super::check_files(
        &[Some(a.model.as_path())],
        &[Some(a.output.as_path()), a.json.as_deref()],
    )?;
    let cal = robokrige::model::ErrorModel::load_calibration(&a.model)?;
    let robot = cal.calibrated_robot();
    let text = RobotFile::text_of(&robot)?;
    robokrige::output::write_text(&a.output, &text)?;
    let report = cal.identifiability();
    super::json_to(a.json.as_deref(), report, "identifiability report")?;
    say!("{}: {}", robot.name, cal.summary_line());
    super::warn(robokrige::report::fit::not_in_robot_file(&cal));
    say!("calibrated robot file -> {}", a.output.display());
    Ok(())
}

fn show(a: ShowArgs) -> Result<()> {
    let robot = kinematics::load_robot(&a.robot)?;
    let digest = kinematics::table_digest(&robot);
    super::json_to(a.json.as_deref(), &RobotFile::of(&robot), "robot file")?;
    let text = RobotFile::text_of(&robot)?;
    match &a.output {
        Some(path) => {
            robokrige::output::write_text(path, &text)?;
            eprintln!("robot '{}' ({digest}) -> {}", robot.name, path.display());
        }
        None if !a.json.as_deref().is_some_and(robokrige::output::is_stdout) => say_part!("{text}"),
        None => {}
    }
    Ok(())
}
