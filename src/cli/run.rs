//! `run CONFIG`: repeatable runs from a config file. Each step is a
//! subcommand with its options, turned into the same argument list the
//! command line would give ([`robokrige::config`]) and parsed by the same
//! parser, so a step does exactly what the flags do.

use clap::{Args, CommandFactory, Parser};
use robokrige::report::run as report;
use robokrige::{Error, Result, config};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
The config file (TOML) lists steps; each names a subcommand and sets its
options by their long names (positional arguments by their names: data,
traj, export, …). Top-level keys are defaults for every step that has that
option. Paths are relative to the config file's folder. Flags are true/false;
a list repeats the option.

Example robokrige.toml:
  data = \"datasets/comau_lhs.csv\"     # every step that takes `data`
  robot = \"comau-nj220\"

  [[step]]
  command = \"fit\"
  output = \"model.json\"

  [[step]]
  command = \"cv\"
  folds = 10
  json = \"cv.json\"

  [[step]]
  command = \"compensate\"
  model = \"model.json\"
  traj = \"datasets/comau_circle.csv\"
  output = \"circle_comp.csv\"
  iterative = true

Example:
  robokrige run robokrige.toml            # run the steps in order
  robokrige run robokrige.toml --dry-run  # print the equivalent command lines")]
pub struct RunArgs {
    /// The config file (TOML).
    config: PathBuf,
    /// Print each step's command line without running it.
    #[arg(long)]
    dry_run: bool,
    /// Write what ran (each step's command line and outcome) as JSON to FILE
    /// ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(a: RunArgs) -> Result<()> {
    let source = a.config.display().to_string();
    let steps = config::read_steps(&a.config, &super::Cli::command())?;
    let folder = config::folder(&a.config);
    let json_out = a.json.as_deref().map(config::output_path);
    // no step, nor the log, may write over the config (resolved before the
    // working folder changes)
    robokrige::output::protect(&a.config);
    super::check_files(&[], &[json_out.as_deref()])?;
    std::env::set_current_dir(&folder).map_err(|e| Error::io(&folder, e))?;
    let ran = config::run_steps(
        (&source, &steps),
        a.dry_run,
        |line: &str| say!("{line}"),
        |argv: &[String]| super::Cli::try_parse_from(argv),
        |cli| super::dispatch(cli.command),
    );
    // the log is written when a step failed too: it says which and why
    let v = report::json(&a.config, &folder, &ran.log);
    super::json_to(json_out.as_deref(), &v, "run log")?;
    ran.failure.map_or(Ok(()), Err)
}
