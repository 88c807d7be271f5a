//! `robokrige fit` and `robokrige predict`.

use clap::{Args, ValueEnum};
use robokrige::calibration::CalibrationOptions;
use robokrige::kriging::CorrChoice;
use robokrige::kriging::{Correlation, OptimizerKind, TrendKind};
use robokrige::methods::{Method, Overrides, params_with};
use robokrige::model::{AXES, ErrorModel};
use robokrige::params::ErrorModelParams;
use robokrige::report::fit as report;
use robokrige::space::Space;
use robokrige::{Error, Result};
use std::path::PathBuf;

#[derive(Debug, Clone, Copy, ValueEnum)]
pub enum CorrArg {
    /// exp(−h²), seed 003 eq 8 (the papers').
    Gaussian,
    /// Matérn ν = 5/2.
    Matern52,
    /// Matérn ν = 3/2.
    Matern32,
    /// exp(−h) (Matérn ν = 1/2).
    Exponential,
    /// Each output's family chosen by closed-form 10-fold CV among the four.
    Auto,
}

impl CorrArg {
    /// The options' correlation choice.
    pub fn choice(self) -> CorrChoice {
        match self {
            CorrArg::Gaussian => Correlation::Gaussian.into(),
            CorrArg::Matern52 => Correlation::Matern52.into(),
            CorrArg::Matern32 => Correlation::Matern32.into(),
            CorrArg::Exponential => Correlation::Exponential.into(),
            CorrArg::Auto => CorrChoice::AUTO,
        }
    }
}

/// Model choices shared by `fit` and `cv`. An option not given keeps the
/// library's default ([`robokrige::methods::Overrides`]); `--method` refuses
/// the model options (the library's rule and message).
#[derive(Debug, Args)]
pub struct ModelArgs {
    /// Input space [default: ejs].
    #[arg(long, value_enum)]
    space: Option<Space>,
    /// Trend of every output [default: constant].
    #[arg(long, value_enum)]
    trend: Option<TrendKind>,
    /// Correlation family, one length scale per input (h² = Σ ξ_k Δs_k²);
    /// by default each output's family is chosen by closed-form 10-fold CV
    /// (the `recommended` method). `gaussian` is the papers' [default: auto].
    #[arg(long, value_enum)]
    corr: Option<CorrArg>,
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
    /// (no separate calibration then).
    #[arg(long)]
    kinematic: bool,
    /// With --robot: Kriging of the raw error. By default a robot is
    /// calibrated first (MD-H, tool and base errors by Levenberg–Marquardt
    /// on the directions the campaign sees) and Kriging fits what the
    /// calibration leaves; the model file holds both.
    #[arg(long, requires = "robot")]
    no_calibrate: bool,
    /// Residual noise per coordinate (mm) that decides which calibration
    /// directions the campaign sees [default: estimated from a first fit].
    #[arg(
        long,
        value_name = "MM",
        requires = "robot",
        conflicts_with = "no_calibrate"
    )]
    calibration_noise: Option<f64>,
}

impl ModelArgs {
    /// The fit parameters of `method` (`None`: these options) for `data`
    /// ([`params_with`]: the library's rules and defaults).
    pub fn resolve(
        &self,
        method: Option<&str>,
        data: &robokrige::dataset::Dataset,
    ) -> Result<ErrorModelParams> {
        let method = method.map(Method::from_name).transpose()?;
        params_with(method, &self.overrides()?, data)
    }

    /// The flags given, as the library's overrides.
    fn overrides(&self) -> Result<Overrides> {
        let mut o = Overrides::new()
            .seed(self.seed)
            .kinematic(self.kinematic)
            .calibrate((!self.no_calibrate).then_some(CalibrationOptions {
                noise_mm: self.calibration_noise,
                ..CalibrationOptions::default()
            }));
        if let Some(v) = self.space {
            o = o.space(v);
        }
        if let Some(v) = self.trend {
            o = o.trend(v);
        }
        if let Some(v) = self.corr {
            o = o.corr(v.choice());
        }
        if let Some(v) = self.optimizer {
            o = o.optimizer(v);
        }
        if self.no_nugget || self.nugget {
            o = o.nugget(self.nugget);
        }
        if let Some(v) = self.starts {
            o = o.starts(v);
        }
        if let Some(v) = &self.periodic {
            o = o.periodic(v.as_str());
        }
        if let Some(r) = &self.robot {
            o = o.robot(robokrige::kinematics::load_robot_with_tool(
                r,
                self.tool.as_deref(),
            )?);
        }
        Ok(o)
    }
}

/// Fit a universal-Kriging error model (one per axis ex, ey, ez) to a campaign.
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
    let mut outputs = vec![a.output.as_path()];
    outputs.extend(a.json.as_deref());
    robokrige::output::check_outputs(&[&a.data], &outputs)?;
    let data = super::read_data(&a.data)?;
    let params = a.model.resolve(a.method.as_deref(), &data)?.check()?;
    super::plan_fit(
        "fit",
        data.len(),
        params.params().get_kriging().get_optimizer(),
        None,
    )?;
    let t0 = std::time::Instant::now();
    let model = match &a.method {
        Some(name) => {
            let pb = super::progress::spinner(name);
            let progress = |axis: usize, generation: usize, best: f64| {
                pb.set_message(format!(
                    "GA {} generation {generation}: best CV RMSE {best:.4} mm",
                    AXES[axis]
                ));
            };
            let model = params.fit_with_progress(&data, &progress);
            pb.finish_and_clear();
            model?
        }
        None => params.fit(&data)?,
    };
    let settings = params.params().settings();
    let secs = t0.elapsed().as_secs_f64();
    for w in model.conditioning_warnings() {
        eprintln!("warning: {w}");
    }
    model.save(&a.output)?;
    if let Some(path) = &a.json {
        let settings: serde_json::Map<String, serde_json::Value> = settings
            .into_iter()
            .map(|(k, v)| (k.to_string(), v.into()))
            .collect();
        let v = serde_json::json!({"data": a.data, "model": a.output, "rows": data.len(),
            "settings": settings, "method": a.method, "robot": model.robot(),
            "seconds": secs, "outputs": model.reports(), "selection": model.selection(),
            "calibration": model.calibration().map(|c| c.identifiability())});
        super::write_json(path, &v, "fit report")?;
    }
    say_part!(
        "{}",
        report::summary(&model, data.len(), secs, &a.output.display().to_string())
    );
    Ok(())
}

/// Predict TCP errors (mean and standard deviation per axis) at poses.
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
    let mut outputs = vec![a.output.as_path()];
    outputs.extend(a.json.as_deref());
    robokrige::output::check_outputs(&[&a.model, &a.poses], &outputs)?;
    let model = ErrorModel::load(&a.model)?;
    let data = super::read_data(&a.poses)?;
    if data.n_joints() != model.n_joints() {
        return Err(Error::Input {
            source_name: a.poses.display().to_string(),
            message: format!(
                "has {} joints but the model was fitted on {}",
                data.n_joints(),
                model.n_joints()
            ),
        });
    }
    let pred = model.predict_dataset(&data)?;
    let derived = data.dir_source == robokrige::dataset::DirSource::Derived;
    let assumed = match data.q.first() {
        Some(q0) if derived => model.direction_sensitivity(q0, &data.dir[0])?,
        _ => 0.0,
    };
    if assumed > 0.0 {
        let warning =
            robokrige::report::predict::direction_warning(&a.poses, data.n_joints(), assumed);
        eprintln!("{warning}");
    }
    let coverage = model.coverage(&data.q, &data.dir, &pred.mean, Some(&pred.std))?;
    super::print_coverage(&coverage, data.len(), data.ids.as_deref());
    robokrige::dataset::write_predictions(
        &a.output,
        &data,
        &pred.mean,
        &pred.std,
        model.noise_std(),
    )?;
    let (v, line) = robokrige::report::predict::summary(&data, &pred.mean, &coverage, &a.output);
    if let Some(path) = &a.json {
        super::write_json(path, &v, "prediction summary")?;
    }
    if let Some(line) = line {
        say!("{line}");
    }
    say!("wrote {}", a.output.display());
    Ok(())
}
