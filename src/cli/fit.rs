//! `robokrige fit` and `robokrige predict`.

use super::progress::{ga, with_spinner};
use clap::Args;
use robokrige::Result;
use robokrige::calibration::CalibrationOptions;
use robokrige::dataset::Dataset;
use robokrige::kinematics::load_optional_robot;
use robokrige::kriging::{CorrChoice, OptimizerKind, TrendKind};
use robokrige::methods::{Method, Overrides, params_with};
use robokrige::model::ErrorModel;
use robokrige::params::ErrorModelParams;
use robokrige::report::{fit as report, predict};
use robokrige::space::Space;
use std::path::PathBuf;

/// The Kriging options of `fit`, `cv` and `holdout`. An option not given
/// keeps the library's default ([`robokrige::methods::Overrides`]).
#[derive(Debug, Args)]
pub struct KrigingArgs {
    /// Correlation family, one length scale per input (h² = Σ ξ_k Δs_k²);
    /// by default each output's family is chosen by closed-form 10-fold CV
    /// (the `recommended` method). `gaussian` is the papers' [default: auto].
    #[arg(long, value_enum)]
    corr: Option<CorrChoice>,
    /// Hyperparameter search [default: bfgs].
    #[arg(long, value_enum)]
    optimizer: Option<OptimizerKind>,
    /// Interpolate the measurements exactly (no nugget), as the papers' Kriging.
    /// By default a nugget (measurement-noise variance) is estimated with the
    /// correlation parameters: tracker data is noisy.
    #[arg(long, conflicts_with = "nugget")]
    no_nugget: bool,
    /// Estimate a nugget: the default; kept so that older scripts still run.
    #[arg(long, hide = true)]
    nugget: bool,
}

impl KrigingArgs {
    /// `o` with the options given.
    pub fn apply(&self, o: Overrides) -> Overrides {
        let nugget = (self.no_nugget || self.nugget).then_some(self.nugget);
        o.with(self.corr, Overrides::corr)
            .with(self.optimizer, Overrides::optimizer)
            .with(nugget, Overrides::nugget)
    }
}

/// Model choices shared by `fit` and `cv`. An option not given keeps the
/// library's default ([`robokrige::methods::Overrides`]); `--method` refuses
/// the model options (the library's rule and message).
#[derive(Debug, Args)]
#[command(group(
    clap::ArgGroup::new("calibration_flags")
        .args(["no_calibrate", "calibration_noise", "geometric", "backlash"])
        .multiple(true)
        .requires("robot")
))]
pub struct ModelArgs {
    /// Input space [default: ejs].
    #[arg(long, value_enum)]
    space: Option<Space>,
    /// Trend of every output [default: constant].
    #[arg(long, value_enum)]
    trend: Option<TrendKind>,
    #[command(flatten)]
    kriging: KrigingArgs,
    /// Starting points (centre + LHS points) [default: 8 for bfgs, 4 for gps].
    #[arg(long)]
    starts: Option<usize>,
    /// Seed of the LHS starts.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Joints entered as (sin θ, cos θ) so θ and θ ± 360° coincide: "auto"
    /// (those whose range in the data exceeds 180°), "none", or "1,4,6"
    /// [default: auto].
    #[arg(long)]
    periodic: Option<String>,
    /// The measured robot: a preset name or a robot file (TOML/JSON). The
    /// model records it, and `compensate` refuses another; `--kinematic` uses
    /// its Jacobian.
    #[arg(long)]
    robot: Option<String>,
    /// TCP offset in the flange frame, mm ("x,y,z"), for `--robot`.
    #[arg(long, requires = "robot")]
    tool: Option<String>,
    /// Add the kinematic-error basis (rows of the robot's identification
    /// Jacobian, seed 003 eq 4) to the trend: one fit calibrates and krigs
    /// (no separate calibration then: the calibration options are refused).
    #[arg(long, conflicts_with = "calibration_flags")]
    kinematic: bool,
    #[command(flatten)]
    calibration: CalibrationArgs,
}

/// The calibration options of `fit`, `cv`, `holdout` (through
/// [`ModelArgs`]) and `batch`.
#[derive(Debug, Args)]
pub struct CalibrationArgs {
    /// Kriging of the raw error. By default a campaign with a robot is
    /// calibrated first (MD-H, tool and base errors by Levenberg–Marquardt
    /// on the directions the campaign sees, then the joints' periodic
    /// errors) and Kriging fits what the calibration leaves; the model file
    /// holds both.
    #[arg(long)]
    no_calibrate: bool,
    /// Residual noise per coordinate (mm) that decides which calibration
    /// directions the campaign sees [default: estimated from a first fit].
    #[arg(long, value_name = "MM", conflicts_with = "no_calibrate")]
    calibration_noise: Option<f64>,
    /// Calibrate the MD-H, tool and base errors only: no periodic (gear)
    /// errors of the joints.
    #[arg(long, conflicts_with = "no_calibrate")]
    geometric: bool,
    /// Also identify each joint's backlash in the calibration (a joint
    /// offset that follows the direction the joint approached from), the
    /// geometry fitted beside it. Off by default: for robots whose gears
    /// have play; on a UR10 (harmonic drives) it made the model worse.
    #[arg(long, conflicts_with = "no_calibrate")]
    backlash: bool,
}

impl CalibrationArgs {
    /// Whether any calibration option was given.
    pub fn any(&self) -> bool {
        self.no_calibrate || self.calibration_noise.is_some() || self.geometric || self.backlash
    }

    /// The calibration asked for: `None` with `--no-calibrate`.
    pub fn options(&self) -> Option<CalibrationOptions> {
        (!self.no_calibrate).then(|| {
            CalibrationOptions::new(!self.geometric, self.calibration_noise)
                .with_backlash(self.backlash)
        })
    }
}

impl ModelArgs {
    /// The fit parameters of `method` (`None`: these options) for `data`
    /// ([`params_with`]: the library's rules and defaults).
    pub fn resolve(&self, method: Option<&str>, data: &Dataset) -> Result<ErrorModelParams> {
        let method = method.map(Method::from_name).transpose()?;
        params_with(method, &self.overrides()?, data)
    }

    /// The flags given, as the library's overrides.
    fn overrides(&self) -> Result<Overrides> {
        let robot = load_optional_robot(self.robot.as_deref(), self.tool.as_deref())?;
        let o = Overrides::new()
            .seed(self.seed)
            .kinematic(self.kinematic)
            .calibrate(self.calibration.options())
            .with(self.space, Overrides::space)
            .with(self.trend, Overrides::trend)
            .with(self.starts, Overrides::starts)
            .with(self.periodic.as_deref(), Overrides::periodic)
            .with(robot, Overrides::robot);
        Ok(self.kriging.apply(o))
    }
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige fit datasets/comau_lhs.csv --space ejs --trend constant --optimizer gps -o model.json")]
pub struct FitArgs {
    /// Measurement CSV with q1..qN, optional dir1..dirN, and ex,ey,ez.
    data: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Fit a named method instead (recommended, js-hj, ejs-hj, ejs-gps, ejs-pca, ejs-ga):
    /// each fixes its own settings, so the model options (--space, --trend,
    /// --corr, --optimizer, --no-nugget, --starts, --periodic) are refused with it.
    #[arg(long)]
    method: Option<String>,
    /// Output model JSON.
    #[arg(short, long)]
    output: PathBuf,
    /// Write the fit report (input, settings, per-axis fits) as JSON to FILE
    /// ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run_fit(a: FitArgs) -> Result<()> {
    let (data_path, output) = (a.data.as_path(), a.output.as_path());
    super::check_files(&[Some(data_path)], &[Some(output), a.json.as_deref()])?;
    let data = super::read_data(data_path)?;
    let params = a.model.resolve(a.method.as_deref(), &data)?.check()?;
    if let Some(r) = params.params().get_robot() {
        super::warn(r.limit_warnings(&data));
    }
    super::print_plan("fit", params.params().check_fit_rows(data.len(), None)?);
    let t0 = std::time::Instant::now();
    let model = match &a.method {
        Some(name) => with_spinner(name, |pb| params.fit_with_progress(&data, &ga(pb)))?,
        None => params.fit(&data)?,
    };
    let secs = t0.elapsed().as_secs_f64();
    super::warn(model.conditioning_warnings());
    model.save(output)?;
    let fit = (params.params(), a.method.as_deref());
    let v = report::json((data_path, output), &model, fit, (data.len(), secs));
    super::json_to(a.json.as_deref(), &v, "fit report")?;
    say_part!("{}", report::summary(&model, data.len(), secs, output));
    Ok(())
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige predict model.json datasets/comau_verify.csv -o predicted.csv")]
pub struct PredictArgs {
    /// Model JSON written by `robokrige fit`.
    model: PathBuf,
    /// Poses CSV (q1..qN, optional dir1..dirN; errors, if present, are compared).
    poses: PathBuf,
    /// Output CSV: id, q, dir, pred_ex.., std_ex.. (√MSE of the predicted
    /// error, the calibration's uncertainty included, measurement noise
    /// not), std_new_ex.. (of a new measurement: with the nugget's noise),
    /// and the measured ex.. if given.
    #[arg(short, long)]
    output: PathBuf,
    /// Write a summary (and, with measured errors, before/after statistics) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run_predict(a: PredictArgs) -> Result<()> {
    let (model_path, poses, output) = (a.model.as_path(), a.poses.as_path(), a.output.as_path());
    super::check_files(
        &[Some(model_path), Some(poses)],
        &[Some(output), a.json.as_deref()],
    )?;
    let model = ErrorModel::load(model_path)?;
    let data = super::read_data(poses)?;
    let p = model.predict_campaign(&data)?;
    super::warn(predict::direction_warning(poses, &data, &p));
    super::print_coverage(&p.coverage, data.len(), data.ids.as_deref());
    p.write(output, &data)?;
    let (v, text) = predict::summary(&data, &p, output);
    super::json_to(a.json.as_deref(), &v, "prediction summary")?;
    say_part!("{text}");
    Ok(())
}
