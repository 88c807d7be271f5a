//! `batch`: every campaign of a folder, one robot each, in parallel.

use clap::Args;
use robokrige::batch::{
    BatchOptions, CampaignReport, campaign_name, campaigns, run_batch, write_summary,
};
use robokrige::report::batch as report;
use robokrige::{Error, Result};
use std::path::{Path, PathBuf};

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
    /// Kriging of the raw error. By default a campaign with a robot is
    /// calibrated first (as `fit --robot`) and Kriging fits what the
    /// calibration leaves.
    #[arg(long)]
    no_calibrate: bool,
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
    let same = |x: &Path, y: &Path| match (x.canonicalize(), y.canonicalize()) {
        (Ok(x), Ok(y)) => x == y,
        _ => false,
    };
    if same(&a.folder, &a.output) {
        return Err(Error::InvalidParameter(
            "the output folder is the campaign folder: its files would be read as campaigns next time; choose another".into(),
        ));
    }
    std::fs::create_dir_all(&a.output).map_err(|e| Error::io(&a.output, e))?;
    let summary_csv = a.output.join("summary.csv");
    let mut outputs = vec![summary_csv.as_path()];
    outputs.extend(a.json.as_deref());
    robokrige::output::check_outputs(&[], &outputs)?;
    let opts = BatchOptions {
        folds: a.folds,
        seed: a.seed,
        robot: a
            .robot
            .as_deref()
            .map(robokrige::kinematics::load_robot)
            .transpose()?,
        calibrate: !a.no_calibrate,
    };
    eprintln!(
        "batch: {} campaign(s) in {}, in parallel",
        files.len(),
        a.folder.display()
    );
    let pb = super::progress::bar(files.len() as u64, "campaigns");
    let results = run_batch(&files, &opts, &|c, r| {
        pb.inc(1);
        if let Err(e) = r {
            pb.println(format!("  {}: failed: {e}", c.display()));
        }
    });
    pb.finish_and_clear();
    say!("{}", report::header());
    let mut reports = Vec::new();
    for (file, r) in files.iter().zip(&results) {
        let name = campaign_name(file);
        if let Ok(rep) = r {
            write_campaign(&a.output, &name, rep)?;
        }
        say!("{}", report::row(&name, r));
        reports.push(match r {
            Ok(rep) => serde_json::json!({"campaign": name, "report": rep}),
            Err(e) => serde_json::json!({"campaign": name, "error": e.to_string()}),
        });
    }
    write_summary(&summary_csv, &files, &results)?;
    say!("summary -> {}", summary_csv.display());
    if let Some(p) = &a.json {
        super::write_json(p, &reports, "batch summary")?;
    }
    let failed = results.iter().filter(|r| r.is_err()).count();
    if failed > 0 {
        return Err(Error::InvalidParameter(format!(
            "{failed} of {} campaign(s) failed (listed above and in {})",
            files.len(),
            summary_csv.display()
        )));
    }
    Ok(())
}

fn write_campaign(out: &Path, name: &str, rep: &CampaignReport) -> Result<()> {
    rep.model.save(&out.join(format!("{name}.model.json")))?;
    super::write_json(
        &out.join(format!("{name}.report.json")),
        rep,
        "campaign report",
    )
}
