//! `robokrige diagnose`.

use super::progress::with_spinner;
use clap::Args;
use robokrige::Result;
use robokrige::dataset::Dataset;
use robokrige::diagnose::{DiagnoseOptions, DiagnosePlan, Diagnosis};
use robokrige::kinematics::load_optional_robot;
use robokrige::plot::effect_plots;
use robokrige::report::diagnose::{self as report, Extras, Names};
use robokrige::study::Targets;
use robokrige::study::diagnosis::{CompensationComparison, DiagnosisBase};
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Candidates: every numeric covariate column not in the model (alone, × joint
angles, × one joint angle, lagged), drift and a change point in the measurement
order, harmonics of each joint over a scanned period range (also through the
Jacobian with --robot), cross-joint products, direction history, and the
motion into each pose (a joint's last moves with a scanned memory, their size,
the TCP's last move with --robot, the time since the previous pose with a time
column).
Each is tried inside the current model (its columns join the trend at the
model's correlation parameters, refitted for the strongest few): statistic,
the leave-one-out gain maximised over its parameter scan; p-value against
sign-flipped pseudo-campaigns of the fitted model; Benjamini–Hochberg across
candidates; score, the closed-form K-fold CV drop. The best significant one
(q within the FDR and ≥ 2 % lower CV RMSE; for one tested at re-estimated
parameters, also confirmed by the refit CV) is added the way its kind needs
(trend terms for a step, harmonic, interaction, cross-talk, a lag through
the Jacobian or a product with a joint angle; an input dimension for a
covariate, the order, direction history or a joint's moves), and the model
is cross-validated again, until nothing significant remains. Each added
effect is reported with its size (trend coefficients, 95 % intervals) and an
\"after\" check: explained, or only partly modelled.

Example:
  robokrige diagnose datasets/comau_tracker_step.csv --json diag.json --report diag.md --plots diag/")]
pub struct DiagnoseArgs {
    /// Measurement CSV (any extra numeric columns are candidate covariates).
    data: PathBuf,
    /// Base model (constant trend, nugget): ejs or js (BFGS on the analytic
    /// gradient; CV folds warm-started from the full fit), or the papers'
    /// js-hj, ejs-hj, ejs-gps (the method's own set-up, with a nugget
    /// unless --no-nugget).
    #[arg(long, default_value = "ejs")]
    method: String,
    /// Fit the base model as an interpolator (no nugget). The default
    /// estimates a nugget: measured data has noise, and an interpolating
    /// model both stays far above the noise floor and leaves smooth
    /// structure that makes smooth candidates look significant.
    #[arg(long)]
    no_nugget: bool,
    /// Folds K of the cross-validation every candidate is judged by.
    #[arg(long, default_value_t = 10)]
    folds: usize,
    /// Seed of the fold partition, the permutations and the fits.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sign-flip resamples of each candidate's null distribution (its p-value).
    #[arg(long, default_value_t = 1999)]
    permutations: usize,
    /// False-discovery rate (Benjamini–Hochberg).
    #[arg(long, default_value_t = 0.05)]
    fdr: f64,
    /// Effects added at most (one per round).
    #[arg(long, default_value_t = 3)]
    max_effects: usize,
    /// Joints entered as (sin θ, cos θ): "none" (default), "auto" (range >
    /// 180°), or "1,4,6". Default none: on UR10 series B the interpolating
    /// Hooke–Jeeves fits with auto encoding blew up in some folds.
    #[arg(long, default_value = "none")]
    periodic: String,
    /// Use only the first N rows.
    #[arg(long)]
    rows: Option<usize>,
    /// Above this many rows, every CV is closed-form at the hyperparameters
    /// of the model fitted on all rows (not refitted per fold), and every
    /// fit (the models compared, each candidate's re-estimated ξ) converges
    /// ξ on one seeded subset of this many rows, then solves on all rows:
    /// a whole campaign of thousands of rows in minutes.
    #[arg(long, default_value_t = robokrige::diagnose::DEFAULT_REFIT_ROWS)]
    refit_rows: usize,
    /// Most rows the candidate test scans: above it, candidates are scanned
    /// on this many rows spread evenly over the campaign, while the models
    /// with and without an effect are fitted and cross-validated on all
    /// rows (a 12 000-row campaign in minutes, not hours).
    #[arg(long, default_value_t = robokrige::diagnose::DEFAULT_SCAN_ROWS)]
    scan_rows: usize,
    /// Write the result as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write a Markdown report.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Folder for residual-vs-effect plots (SVG) of every accepted effect.
    #[arg(long)]
    plots: Option<PathBuf>,
    /// Save the final model (with the added effects) here.
    #[arg(long)]
    model_out: Option<PathBuf>,
    /// Robot (preset name or robot file): the campaign's calibration is
    /// diagnosed (see --no-calibrate), and joint cross-talk candidates are
    /// added (through its Jacobian); with --traj and --truth, also
    /// compensates the trajectory with the model before and after and
    /// reports the errors.
    #[arg(long)]
    robot: Option<String>,
    /// TCP offset x,y,z (mm) on the robot's flange, replacing its tool (with --robot).
    #[arg(long, requires = "robot", allow_hyphen_values = true)]
    tool: Option<String>,
    /// With --robot: diagnose the raw error. By default a robot is
    /// calibrated first (a D-H calibration by Levenberg–Marquardt on all
    /// rows, as `fit --robot`) and its residual is diagnosed: on real data
    /// it leaves a far smaller misfit than Kriging of the raw error, so
    /// smaller effects show. The models written (--model-out) and compared
    /// (--traj) then hold the calibration and the Kriging of its residual.
    #[arg(long, requires = "robot", conflicts_with = "calibrate")]
    no_calibrate: bool,
    /// Calibrate first: the default with --robot; kept so that older
    /// scripts still run.
    #[arg(long, hide = true, requires = "robot")]
    calibrate: bool,
    /// Trajectory to compensate with the model before and after the effects
    /// were added (TCP x,y,z CSV, or joints q1..qN), with --robot and --truth.
    #[arg(long, requires_all = ["robot", "truth"])]
    traj: Option<PathBuf>,
    /// Simulator truth JSON of the campaign (`robokrige simulate` writes it):
    /// runs the compensated trajectory on the simulated robot to measure it
    /// (with --traj).
    #[arg(long, requires_all = ["robot", "traj"])]
    truth: Option<PathBuf>,
}

fn options(a: &DiagnoseArgs, data: &Dataset) -> Result<DiagnoseOptions> {
    Ok(DiagnoseOptions::of_method(&a.method, a.seed, !a.no_nugget)?
        .periodic(robokrige::space::parse_periodic(&a.periodic, &data.q)?)
        .folds(a.folds)
        .permutations(a.permutations)
        .fdr(a.fdr)
        .max_effects(a.max_effects)
        .refit_rows(a.refit_rows)
        .scan_rows(a.scan_rows)
        .robot(load_optional_robot(a.robot.as_deref(), a.tool.as_deref())?))
}

pub fn run(a: DiagnoseArgs) -> Result<()> {
    let inputs = [Some(&*a.data), a.traj.as_deref(), a.truth.as_deref()];
    let outputs = [
        a.json.as_deref(),
        a.report.as_deref(),
        a.model_out.as_deref(),
    ];
    super::check_files(&inputs, &outputs)?;
    let data = super::read_data(&a.data)?.head(a.rows.unwrap_or(usize::MAX));
    let opts = options(&a, &data)?;
    let calibrate = (a.calibrate || a.no_calibrate).then_some(a.calibrate);
    let base = DiagnosisBase::new(data, &opts, calibrate)?;
    say_part!("{}", report::calibrated_base(&base));
    let plan = DiagnosePlan::check_options(&base.data, &opts, ("--rows", "--scan-rows"))?;
    super::print_plan("diagnose", plan);
    let d = with_spinner("diagnose", |pb| {
        base.diagnose(&opts, &|msg| pb.set_message(msg.to_string()))
    })?;
    let names = Names {
        data: &a.data,
        method: &a.method,
    };
    say_part!("{}", report::summary(&d, names));
    let plots = match &a.plots {
        Some(dir) => effect_plots(dir, &base.data, &d)?,
        None => Vec::new(),
    };
    say_part!("{}", report::plot_lines(a.plots.as_deref(), &plots));
    let compensation = write_and_compare_models(&a, &base, &opts, &d)?;
    let v = report::json(&d, names, compensation.as_ref())?;
    super::json_to(a.json.as_deref(), &v, "diagnosis")?;
    if let Some(path) = &a.report {
        let extras = Extras {
            compensation: a.traj.as_deref().zip(compensation.as_ref()),
            plots: &plots,
        };
        robokrige::output::write_text(path, &report::markdown(&d, names, extras))?;
        say!("report: {}", path.display());
    }
    Ok(())
}

/// With `--model-out`: save the model with the added effects; with
/// `--traj` (and `--robot`, `--truth`): compare the models before and after
/// compensating it on the simulated robot.
fn write_and_compare_models(
    a: &DiagnoseArgs,
    base: &DiagnosisBase,
    opts: &DiagnoseOptions,
    d: &Diagnosis,
) -> Result<Option<CompensationComparison>> {
    if a.model_out.is_none() && a.traj.is_none() {
        return Ok(None);
    }
    let after = base.model(opts, &d.extras)?;
    if let Some(p) = &a.model_out {
        after.save(p)?;
        say!("model with the added effects: {}", p.display());
    }
    // (--traj and --truth without --robot are rejected by clap)
    let (Some(robot), Some(traj), Some(truth_path)) = (opts.get_robot(), &a.traj, &a.truth) else {
        return Ok(None);
    };
    let targets = Targets::read(traj, robot, None, &robot.home)?;
    super::warn(&targets.warnings);
    let c = base.compare_compensation(opts, &after, (robot, &targets), truth_path, a.seed)?;
    say!("{}", report::compensation_line(traj, &c));
    Ok(Some(c))
}
