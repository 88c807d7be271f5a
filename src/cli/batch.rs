//! `batch`: every campaign of a folder, one robot each, in parallel.

use super::fit::CalibrationArgs;
use clap::Args;
use robokrige::Result;
use robokrige::batch::{
    BatchOptions, campaigns, check_failures, prepare_output, run_batch, write_campaigns,
    write_summary,
};
use robokrige::kinematics::load_robot;
use robokrige::report::batch as report;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Fits every campaign NAME.csv of FOLDER with the recommended settings (EJS,
nugget, correlation family by CV, periodic joints auto) and scores it by
K-fold CV at the fitted hyperparameters. A campaign's robot is
NAME.robot.toml (or .json) beside it, else --robot. Writes OUT/NAME.model.json
and OUT/NAME.report.json per campaign and OUT/summary.csv; a campaign that
fails is listed with its error and does not stop the others (exit 1 at the end).

Example:
  robokrige batch fleet/ -o fleet_results/ --robot comau-nj220

Many machines: run the same command per campaign folder as a job array, e.g.
Slurm `#SBATCH --array=0-99` with `robokrige batch fleet/cell_$SLURM_ARRAY_TASK_ID
-o results/cell_$SLURM_ARRAY_TASK_ID` (docs/FLEET.md).")]
pub struct BatchArgs {
    /// Folder of campaign CSVs.
    folder: PathBuf,
    /// Output folder (created; must not be FOLDER).
    #[arg(short, long)]
    output: PathBuf,
    /// Robot (preset name or robot file) of campaigns without NAME.robot.toml.
    #[arg(long)]
    robot: Option<String>,
    #[command(flatten)]
    calibration: CalibrationArgs,
    /// CV folds.
    #[arg(long, default_value_t = 10)]
    folds: usize,
    /// Seed of the folds and of the fit's starts.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Write the summary (every campaign's report) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(a: BatchArgs) -> Result<()> {
    let files = campaigns(&a.folder)?;
    if a.calibration.any()
        && a.robot.is_none()
        && files
            .iter()
            .all(|f| robokrige::batch::robot_beside(f).is_none())
    {
        return Err(robokrige::Error::InvalidParameter(
            "the calibration options need a robot: --robot, or a NAME.robot.toml beside a campaign"
                .into(),
        ));
    }
    prepare_output(&a.folder, &a.output)?;
    let summary_csv = a.output.join("summary.csv");
    super::check_files(&[], &[Some(summary_csv.as_path()), a.json.as_deref()])?;
    let opts = BatchOptions {
        folds: a.folds,
        seed: a.seed,
        robot: a.robot.as_deref().map(load_robot).transpose()?,
        calibration: a.calibration.options(),
    };
    let (n, folder) = (files.len(), a.folder.display());
    eprintln!("batch: {n} campaign(s) in {folder}, in parallel");
    let mut results = super::progress::with_bar(files.len() as u64, "campaigns", |pb| {
        run_batch(&files, &opts, &|c, r| {
            pb.inc(1);
            if let Err(e) = r {
                pb.println(format!("  {}: failed: {e}", c.display()));
            }
        })
    });
    write_campaigns(&a.output, &files, &mut results);
    say_part!("{}", report::table(&files, &results));
    write_summary(&summary_csv, &files, &results)?;
    say!("summary -> {}", summary_csv.display());
    let v = report::json(&files, &results);
    super::json_to(a.json.as_deref(), &v, "batch summary")?;
    check_failures(&results, &summary_csv)
}
