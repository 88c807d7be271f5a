//! `robokrige plan`: which poses to measure next, in which order.

use super::read_data;
use clap::Args;
use robokrige::Result;
use robokrige::cancel::Cancel;
use robokrige::model::ErrorModel;
use robokrige::plan::stop::Forecast;
use robokrige::plan::{Plan, PlanInputs, PlanParams, Region, TrackerView};
use robokrige::program::ProgramFormat;
use robokrige::report::plan as report;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Poses are chosen to lower the integrated prediction variance (IMSE) of the
error model over the region that matters, each joint's approach direction
planned too; the order realises the directions, with pre-position moves
(measure = 0) where needed. Without measurements or a prior model the first
batch covers the region; measure it and plan again with --campaign.

Examples:
  robokrige plan --robot ur10 --budget 50 -o batch1.csv
  robokrige plan --robot ur10 --budget 50 --campaign measured.csv -o batch2.csv --target-mm 0.2
  robokrige plan --robot ur10 --budget 100 --region task.csv --format urscript -o plan.script")]
pub struct PlanArgs {
    /// The robot: a preset name or a robot file (TOML/JSON).
    #[arg(long)]
    robot: String,
    /// TCP offset in the flange frame, mm ("x,y,z"), replacing the robot's tool.
    #[arg(long)]
    tool: Option<String>,
    /// Poses to plan.
    #[arg(long)]
    budget: usize,
    /// Output: the plan (CSV: id, q, dir, measure, source; or a robot program).
    #[arg(short, long)]
    output: PathBuf,
    /// Output format.
    #[arg(long, value_enum, default_value = "csv")]
    format: ProgramFormat,
    /// What has been measured so far (measurement CSV with ex,ey,ez):
    /// the hyperparameters are re-estimated on it, and the plan continues it.
    #[arg(long)]
    campaign: Option<PathBuf>,
    /// A prior model file (e.g. a robot of the same type): its
    /// hyperparameters until enough of this robot is measured.
    #[arg(long)]
    prior: Option<PathBuf>,
    /// Choose among the poses of this file only (their errors are ignored).
    #[arg(long)]
    pool: Option<PathBuf>,
    /// The region that matters: a task's poses (q1..qN) or TCP path
    /// (x,y,z[,roll_deg,...]) [default: the pool, else the robot's working ranges].
    #[arg(long)]
    region: Option<PathBuf>,
    /// Poses of the first batch when no hyperparameters are known yet.
    #[arg(long, default_value_t = 50)]
    first_batch: usize,
    /// Candidates drawn in the working ranges (without --pool).
    #[arg(long, default_value_t = 5000)]
    candidates: usize,
    /// Region points the integrated MSE averages over.
    #[arg(long, default_value_t = 1000)]
    region_points: usize,
    /// How far back a pre-position move starts, degrees (mm for prismatic joints).
    #[arg(long, default_value_t = 5.0)]
    via_step: f64,
    /// Measure in K passes over the region, each a tour of the next run of
    /// poses in the order chosen (1: one tour of all, the shortest path).
    /// More passes keep a slow change over the measurement (a warm-up, a
    /// tracker step) from following the joint space, at a longer path.
    #[arg(long, value_name = "K", default_value_t = 1)]
    passes: usize,
    /// Tracker position in the robot base frame, mm ("x,y,z"): plan only poses it sees.
    #[arg(long, value_delimiter = ',', allow_hyphen_values = true, num_args = 1)]
    tracker: Option<Vec<f64>>,
    /// Largest tracker–reflector distance, mm (with --tracker).
    #[arg(long, requires = "tracker")]
    max_range: Option<f64>,
    /// Largest angle between the reflector's axis (tool z) and the line to
    /// the tracker, degrees (with --tracker).
    #[arg(long, requires = "tracker")]
    max_incidence: Option<f64>,
    /// The held-out mean 3D error wanted, mm: say how many more poses it
    /// needs, or that it is below the repeatability floor.
    #[arg(long)]
    target_mm: Option<f64>,
    /// Write the plan's summary (chosen rows, IMSE curve, forecast) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Seed of the candidates and the region sample.
    #[arg(long, default_value_t = 1)]
    seed: u64,
}

pub fn run(a: PlanArgs) -> Result<()> {
    let inputs = [&a.campaign, &a.pool, &a.region, &a.prior].map(Option::as_deref);
    super::check_files(&inputs, &[Some(a.output.as_path()), a.json.as_deref()])?;
    if let Some(t) = a.target_mm.filter(|t| !(t.is_finite() && *t > 0.0)) {
        return Err(robokrige::Error::InvalidParameter(format!(
            "--target-mm must be a positive error in mm, not {t}"
        )));
    }
    let robot = robokrige::kinematics::load_robot_with_tool(&a.robot, a.tool.as_deref())?;
    Plan::check_output(&a.output, a.format, &robot)?;
    let campaign = a.campaign.as_deref().map(read_data).transpose()?;
    let pool = a.pool.as_deref().map(read_data).transpose()?;
    let prior = a.prior.as_deref().map(ErrorModel::load).transpose()?;
    let region = Region::from_options(a.region.as_deref(), pool.as_ref(), &robot)?;
    let tracker = a.tracker.as_deref();
    let view = TrackerView::from_options(tracker, a.max_range, a.max_incidence)?;
    let params = PlanParams::new(a.budget)
        .first_batch(a.first_batch)
        .candidates(a.candidates)
        .region_points(a.region_points)
        .via_step(a.via_step)
        .passes(a.passes)
        .seed(a.seed)
        .tracker(view);
    let mut plan = params.check()?.plan(&PlanInputs {
        robot: &robot,
        campaign: campaign.as_ref(),
        prior: prior.as_ref(),
        pool: pool.as_ref(),
        region: &region,
    })?;
    plan.write(&a.output, a.format, &robot)?;
    let forecast = Forecast::of_plan(&mut plan, &robot, campaign.as_ref(), &Cancel::new())?;
    let v = report::json(&plan, forecast.as_ref());
    super::json_to(a.json.as_deref(), &v, "plan")?;
    say_part!("{}", report::text(&plan, forecast.as_ref(), a.target_mm));
    say!("wrote {}", a.output.display());
    Ok(())
}
