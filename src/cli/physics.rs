//! `robokrige physics identify | compare`.

use super::progress::{steps_of, with_bar};
use super::read_data;
use clap::{Args, Subcommand};
use robokrige::Result;
use robokrige::kinematics;
use robokrige::methods::Method;
use robokrige::physics::{
    CompareOptions, DEFAULT_ROBOT, check_training_campaign, compare, identify_campaigns,
};
use robokrige::report::physics as report;
use std::path::PathBuf;

#[derive(Debug, Subcommand)]
pub enum PhysicsCommand {
    /// Identify a physics model from indexing tests (and, for a six-axis
    /// robot, a measurement campaign for the D-H errors).
    Identify(IdentifyArgs),
    /// Simulate a robot and compare nominal, D-H, D-H + APD, Kriging JS/EJS
    /// and the hybrid on prediction and compensation.
    Compare(CompareArgs),
    /// Seed 000 §5.2: J1's deviation at several J2 angles against an
    /// identified SCARA model (cross-talk).
    Crosstalk(CrosstalkArgs),
    /// Seed 004 eqs 29–35: move a campaign measured in the tracker's frame
    /// into the robot's base frame (SVD registration onto the nominal TCP
    /// positions) and recompute ex, ey, ez.
    Register(RegisterArgs),
    /// Seed 002's probing example: a straightedge probed at three locations,
    /// straightness with the nominal, D-H and D-H + APD models (Table 2).
    Probing(ProbingArgs),
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige simulate --robot scara-rh3frh5515 --kind crosstalk --seed 1 -o xt.csv
  robokrige physics identify datasets/scara_indexing.csv -o scara_physics.json
  robokrige physics crosstalk xt.csv --model scara_physics.json")]
pub struct CrosstalkArgs {
    /// Cross-talk test CSV (J1 indexed with J2 held at several angles; `axis` = 1).
    data: PathBuf,
    /// Physics model identified from the indexing tests of the same set-up.
    #[arg(long)]
    model: PathBuf,
    /// Write the cross-talk tables and the fit as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
The tracker frame is found by SVD registration of the measured points onto
the nominal robot's (seed 004 eqs 29–35); the errors are then recomputed in
the base frame.

Example:
  robokrige simulate --robot comau-nj220 --poses 200 --seed 1 -o c.csv
  robokrige physics register c.csv --robot comau-nj220 -o c_base.csv")]
pub struct RegisterArgs {
    /// Campaign with q.. and the measured x,y,z in the tracker's frame.
    data: PathBuf,
    /// The robot (preset or robot file) whose nominal kinematics give the base frame.
    #[arg(long)]
    robot: String,
    /// Output CSV: the same rows, x,y,z in the base frame, ex,ey,ez recomputed.
    #[arg(short, long)]
    output: PathBuf,
    /// Write the registration (transform, residuals) as JSON to FILE ("-":
    /// standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige physics probing --robot kuka-kr30ha --seed 1 --json probing.json")]
pub struct ProbingArgs {
    /// Six-axis robot preset of the simulated set-up.
    #[arg(long, default_value = "kuka-kr30ha")]
    robot: String,
    /// Seed of the simulated robot and its noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Switch the tracker and repeatability noise off (the systematic part alone).
    #[arg(long)]
    noise_free: bool,
    /// Write the straightness table as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
A SCARA (seed 000) is identified from its J1 and J2 indexing tests alone:
reference frame from the J1 plane and circle, link errors ΔL1, ΔL2, the J2
offset θ20, bidirectional APD and radial-error-motion tables, parallelism of
J2 to J1. A six-axis robot (seed 002) gets its APD tables from the indexing
tests (circle-point analysis of every axis whose TCP circle is ≥ 50 mm) and its
MD-H, tool and base errors by Levenberg–Marquardt on --train.

Example:
  robokrige physics identify datasets/scara_indexing.csv --robot scara-rh3frh5515 \\
      -o scara_physics.json --truth datasets/scara_indexing.truth.json")]
pub struct IdentifyArgs {
    /// Indexing-test CSV (columns q.., dir.., x,y,z and `axis`).
    indexing: PathBuf,
    /// Robot: preset name or robot file.
    #[arg(long, default_value = DEFAULT_ROBOT)]
    robot: String,
    /// Measurement campaign with ex,ey,ez for the Levenberg–Marquardt D-H
    /// calibration (needed for a six-axis robot, unused for a SCARA).
    #[arg(long)]
    train: Option<PathBuf>,
    /// Output model (D-H + tables), usable with `compensate --model`.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the D-H-only model here.
    #[arg(long)]
    dh_output: Option<PathBuf>,
    /// Simulator truth of the indexing campaign: print identified vs true.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Write the identification report as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
Everything is simulated from --seed: the true robot, its indexing tests, a
Latin-hypercube training campaign for Kriging, a Ø--path-mm circle path run
forward and back, and --verify-poses random poses. Every model predicts the
path's and the poses' errors (score: measured − predicted) and compensates
them (iterative feed-forward; score: measured − target on the true robot).

Example:
  robokrige physics compare --robot scara-rh3frh5515 --seed 1 --report compare.md")]
pub struct CompareArgs {
    /// Robot (preset name or robot file) of the simulated set-up (SCARA: seed 000; six-axis: seed 002).
    #[arg(long, default_value = "scara-rh3frh5515")]
    robot: String,
    /// Seed of everything simulated.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Poses of the Latin-hypercube campaign the Kriging models train on.
    #[arg(long, default_value_t = 300)]
    train_poses: usize,
    /// Points of the circle path.
    #[arg(long, default_value_t = 72)]
    path_points: usize,
    /// Diameter of the circle path, mm.
    #[arg(long, default_value_t = 100.0)]
    path_mm: f64,
    /// Random verification poses.
    #[arg(long, default_value_t = 50)]
    verify_poses: usize,
    /// Kriging method of the JS row.
    #[arg(long, default_value = "js-hj")]
    js: String,
    /// Kriging method of the EJS row and of the hybrid's residual model.
    #[arg(long, default_value = "ejs-gps")]
    ejs: String,
    /// Estimate a nugget in the papers' Kriging methods too (default: they
    /// interpolate; `recommended` always estimates one).
    #[arg(long)]
    nugget: bool,
    /// Write the comparison table as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Markdown report.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Write path plots here (seed 000 Figs 9–11): the measured path and
    /// each model's prediction, errors magnified ×1000 in XY.
    #[arg(long)]
    plots: Option<PathBuf>,
}

pub fn run(command: PhysicsCommand) -> Result<()> {
    match command {
        PhysicsCommand::Identify(a) => run_identify(a),
        PhysicsCommand::Compare(a) => run_compare(a),
        PhysicsCommand::Probing(a) => run_probing(a),
        PhysicsCommand::Crosstalk(a) => run_crosstalk(a),
        PhysicsCommand::Register(a) => run_register(a),
    }
}

fn run_identify(a: IdentifyArgs) -> Result<()> {
    let inputs = [Some(&*a.indexing), a.train.as_deref(), a.truth.as_deref()];
    let outputs = [Some(&*a.output), a.dh_output.as_deref(), a.json.as_deref()];
    super::check_files(&inputs, &outputs)?;
    let robot = kinematics::load_robot(&a.robot)?;
    // repeated poses are the design of an indexing test: no warning for them
    let indexing = robokrige::dataset::read_csv(&a.indexing)?;
    // refused before the training campaign is read
    check_training_campaign(&robot, a.train.is_some())?;
    let train = a.train.as_deref().map(read_data).transpose()?;
    let id = identify_campaigns(&robot, &a.robot, &indexing, train.as_ref())?;
    id.full.save(&a.output)?;
    if let Some(p) = &a.dh_output {
        id.dh.save(p)?;
    }
    say_part!("{}", report::identification(&id));
    if let Some(tp) = &a.truth {
        let truth = robokrige::study::load_truth(tp)?;
        say_part!("{}", report::against_truth(&id, &truth));
    }
    say!("model: {}", a.output.display());
    super::json_to(a.json.as_deref(), &id, "identification report")?;
    Ok(())
}

fn run_compare(a: CompareArgs) -> Result<()> {
    super::check_files(&[], &[a.json.as_deref(), a.report.as_deref()])?;
    let opts = CompareOptions {
        robot: a.robot.clone(),
        seed: a.seed,
        train_poses: a.train_poses,
        path_points: a.path_points,
        path_mm: a.path_mm,
        verify_poses: a.verify_poses,
        js: Method::from_name(&a.js)?,
        ejs: Method::from_name(&a.ejs)?,
        nugget: a.nugget,
    };
    let t0 = std::time::Instant::now();
    let res = with_bar(1, "compare", |pb| compare(&opts, &steps_of(pb)))?;
    let text = report::comparison(&res, t0.elapsed().as_secs_f64());
    say_part!("{text}");
    if let Some(p) = &a.report {
        robokrige::output::write_text(p, &text)?;
    }
    super::json_to(a.json.as_deref(), &res, "comparison")?;
    if let Some(dir) = &a.plots {
        for f in robokrige::plot::path_plots(&res, dir)? {
            say!("plot: {}", f.display());
        }
    }
    Ok(())
}

fn run_probing(a: ProbingArgs) -> Result<()> {
    super::check_files(&[], &[a.json.as_deref()])?;
    let (rows, how) = robokrige::physics::probing_example(&a.robot, a.seed, !a.noise_free)?;
    let setup = (a.robot.as_str(), a.seed, !a.noise_free);
    say_part!("{}", report::probing(&rows, &how, setup));
    super::json_to(a.json.as_deref(), &rows, "probing table")?;
    Ok(())
}

fn run_crosstalk(a: CrosstalkArgs) -> Result<()> {
    let inputs = [Some(a.data.as_path()), Some(a.model.as_path())];
    super::check_files(&inputs, &[a.json.as_deref()])?;
    let model = robokrige::physics::PhysicsModel::load(&a.model)?;
    let data = robokrige::dataset::read_csv(&a.data)?;
    let r = robokrige::physics::identify_crosstalk(&data, &model)?;
    say_part!("{}", report::crosstalk(&r));
    super::json_to(a.json.as_deref(), &r, "cross-talk report")?;
    Ok(())
}

fn run_register(a: RegisterArgs) -> Result<()> {
    let (data_path, output) = (a.data.as_path(), a.output.as_path());
    super::check_files(&[Some(data_path)], &[Some(output), a.json.as_deref()])?;
    let robot = kinematics::load_robot(&a.robot)?;
    let data = read_data(data_path)?;
    let (out, reg) = robokrige::physics::register_campaign(&data, &robot)?;
    robokrige::dataset::write_csv(output, &out)?;
    say_part!("{}", report::registration(&reg, out.len(), output));
    let v = report::registration_json((data_path, output), &robot.name, out.len(), &reg);
    super::json_to(a.json.as_deref(), &v, "registration")?;
    Ok(())
}
