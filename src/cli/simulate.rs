//! `robokrige simulate`.

use clap::Args;
use robokrige::report::simulate as report;
use robokrige::sim::{CampaignKind, CampaignSpec, Effect, parse_ranges, simulate, truth_path_for};
use robokrige::{Result, kinematics};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
The same --robot and --seed always give the same true robot, whatever the
--kind, so a training campaign, its verification poses and a trajectory can
be made separately. The simulator's truth (true parameters, effects, noise
floor) goes to a JSON beside the CSV, never into it.

Examples:
  robokrige simulate --robot comau-nj220 --poses 300 --seed 1 -o comau_lhs.csv
  robokrige simulate --kind verify --poses 30 --seed 1 -o comau_verify.csv
  robokrige simulate --kind circle --seed 1 -o circle.csv
  robokrige simulate --robot scara-rh3frh5515 --kind indexing --seed 1 -o scara_idx.csv
  robokrige simulate --robot ur10 --kind cubes --cubes 4 --edge 300 --poses 600 -o cubes.csv
  robokrige simulate --seed 2 --effect temperature:delta_k=6,tau_s=1200 -o warm.csv

Effects (repeatable --effect NAME[:key=value,...]; defaults in brackets):
  temperature  delta_k [6], tau_s [1200], expansion_per_k [4e-5]  -> drift with time_s/temp_c
  payload      kg [0/60/120] (levels in equal blocks of rows)      -> payload_kg column
  harmonic     joint [2], period_deg [7.5], amp_deg [0.004], phase_rad [0]
  tracker-step row [150], until [none: to the end; a row: put back there, a bump],
               dx [0.15], dy [-0.1], dz [0.1] (mm, no column records it)
  crosstalk    joint [1], from [2], gain_deg [0.01]  (joint deviates by gain*sin(q_from))
  hysteresis   joint [2], amp_deg [0.01], travel_deg [20]  (joint deviates by
               λ*amp*(1 - exp(-s/travel)), s its travel since its last reversal)
  lag          joint [2], gain [0.0005], tau_poses [0]  (servo lag: joint stops short
               by gain*h, h = its move into the pose + exp(-1/tau)*h of the pose before)")]
pub struct SimulateArgs {
    /// Robot: a preset (comau-nj220, kuka-kr30ha, ur10, scara-rh3frh5515) or a robot file (TOML/JSON; see `robokrige robot --help`).
    #[arg(long, default_value = "comau-nj220")]
    robot: String,
    /// Campaign kind.
    #[arg(long, value_enum, default_value = "lhs")]
    kind: CampaignKind,
    /// Number of poses (lhs 300, verify 30, cubes 600) or circle points (72); not for indexing or crosstalk.
    #[arg(long)]
    poses: Option<usize>,
    /// Seed of the true robot and of the campaign.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Undeclared effect NAME[:key=value,...]; repeat for several.
    #[arg(long = "effect", value_name = "SPEC")]
    effects: Vec<String>,
    /// Joint ranges overriding the preset's, e.g. "-20:20,-40:0,-150:-100,-15:15,-55:15,-15:15" (degrees).
    #[arg(long, allow_hyphen_values = true)]
    ranges: Option<String>,
    /// Circle diameter, mm (--kind circle) [default: 100].
    #[arg(long, allow_hyphen_values = true)]
    diameter: Option<f64>,
    /// Forward/backward passes per indexed joint (--kind indexing, crosstalk) [default: 3].
    #[arg(long)]
    cycles: Option<usize>,
    /// ISO 9283 cubes (--kind cubes) [default: 4]; --poses is shared equally among them.
    #[arg(long)]
    cubes: Option<usize>,
    /// Cube edge, mm (--kind cubes) [default: 300].
    #[arg(long, value_name = "MM", allow_hyphen_values = true)]
    edge: Option<f64>,
    /// Output CSV.
    #[arg(short, long)]
    output: PathBuf,
    /// Truth sidecar JSON [default: OUTPUT with .truth.json].
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Write the summary as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(a: SimulateArgs) -> Result<()> {
    let mut spec = CampaignSpec::new(a.kind, a.seed)
        .sizes(a.poses, a.diameter, a.cycles)
        .cube_sizes(a.cubes, a.edge);
    spec.effects = Effect::parse_all(&a.effects)?;
    spec.ranges = a.ranges.as_deref().map(parse_ranges).transpose()?;
    spec.validate()?;
    let robot = kinematics::load_robot(&a.robot)?;
    robokrige::output::create_folder_of(&a.output)?;
    let truth_path = a.truth.clone().unwrap_or_else(|| truth_path_for(&a.output));
    let outputs = [Some(&*a.output), Some(&*truth_path), a.json.as_deref()];
    super::check_files(&[], &outputs)?;
    let (out, truth) = simulate(&robot, &spec)?;
    super::json_to(Some(&truth_path), &truth, "truth")?;
    out.write_csv(&a.output)?;
    let summary = report::json(&out, &truth, (&a.output, &truth_path));
    say_part!("{}", report::summary(&summary));
    super::json_to(a.json.as_deref(), &summary, "summary")?;
    Ok(())
}
