//! `robokrige fit` and `robokrige predict`.

use clap::{Args, ValueEnum};
use robokrige::calibration::CalibrationOptions;
use robokrige::kriging::{Correlation, OptimizerKind, TrendKind};
use robokrige::methods::{CorrName, Method, Overrides, params_with};
use robokrige::model::{AXES, ErrorModel};
use robokrige::params::ErrorModelParams;
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
    /// The library's name of this choice.
    pub fn name(self) -> CorrName {
        match self {
            CorrArg::Gaussian => CorrName::Family(Correlation::Gaussian),
            CorrArg::Matern52 => CorrName::Family(Correlation::Matern52),
            CorrArg::Matern32 => CorrName::Family(Correlation::Matern32),
            CorrArg::Exponential => CorrName::Family(Correlation::Exponential),
            CorrArg::Auto => CorrName::Auto,
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
            o = o.corr(v.name());
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
    let space = model.space();
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
    say!(
        "fitted {} rows in {:?} space ({}, {}) in {secs:.2} s -> {}",
        data.len(),
        space,
        if model.options().get_corr_auto() {
            let c: Vec<String> = model
                .outputs()
                .iter()
                .map(|o| o.corr().to_string())
                .collect();
            format!("correlation by CV: {}", c.join(" / "))
        } else {
            format!("{} correlation", model.outputs()[0].corr())
        },
        if model.options().get_nugget() {
            "nugget estimated"
        } else {
            "interpolating"
        },
        a.output.display()
    );
    for (ax, r) in AXES.iter().zip(model.reports()) {
        if !r.families.is_empty() {
            let t: Vec<String> = r
                .families
                .iter()
                .map(|f| format!("{} {:.4}", f.corr, f.cv_rmse))
                .collect();
            say!("  {ax}: family by 10-fold CV RMSE (mm): {}", t.join(", "));
        }
        let lt: Vec<String> = r
            .theta
            .iter()
            .map(|t| format!("{:.2}", t.log10()))
            .collect();
        say!(
            "  {ax}: ln ψ {:.4}  σ² {:.4}  nugget {:.2e}  trend terms {} (dropped {})  evals {}  {:.2} s\n      log10 ξ = [{}]",
            r.ln_psi,
            r.sigma2,
            r.nugget,
            r.trend_terms.len(),
            r.dropped_terms.len(),
            r.evals,
            r.seconds,
            lt.join(", ")
        );
    }
    print_selection(&model);
    if let Some(c) = model.calibration() {
        print_calibration(c);
    }
    Ok(())
}

/// The calibration under a model: what the campaign identified.
pub fn print_calibration(c: &robokrige::calibration::Calibration) {
    say!("  calibration: {}", c.summary_line());
    let id = c.identifiability();
    let fixed = id.fixed_names();
    if !fixed.is_empty() {
        say!(
            "  fixed at nominal (the campaign does not see them): {}",
            fixed.join(" ")
        );
    }
}

/// One line per output of what PCC+PCA or the GA selected.
fn print_selection(model: &ErrorModel) {
    use robokrige::selection::Selection;
    match &model.selection() {
        Some(Selection::PccPca { outputs }) => {
            for (ax, r) in AXES.iter().zip(outputs) {
                say!(
                    "  {ax} PCC+PCA: {} candidates ranked ({} dependent dropped), {} with |r| > {}, {} components ({:.1} % of variance)",
                    r.ranking.len(),
                    r.dropped.len(),
                    r.selected,
                    r.threshold,
                    r.components,
                    100.0 * r.explained
                );
            }
        }
        Some(Selection::Ga { outputs }) => {
            for (ax, r) in AXES.iter().zip(outputs) {
                say!(
                    "  {ax} GA: {} of {} candidates ({} dependent dropped), CV RMSE {:.4} mm after {} generations: {}",
                    r.selected.len(),
                    r.candidates,
                    r.dropped.len(),
                    r.cv_rmse_mm,
                    r.generations,
                    r.selected.join(" ")
                );
            }
        }
        None => {}
    }
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
        eprintln!(
            "warning: {} has no dir1..dir{} columns: λ is derived from the row order, and the \
             first pose gets λ = +1 on every joint (assumed; a joint that has not moved yet keeps it). \
             Reversing it changes that pose's prediction by {assumed:.3} mm: give the dir columns, or put \
             the pose the robot came from first.",
            a.poses.display(),
            data.n_joints()
        );
    }
    let coverage = model.coverage(&data.q, &data.dir, &pred.mean, Some(&pred.std))?;
    super::print_coverage(&coverage, data.len(), data.ids.as_deref());
    let noise = model.noise_std();
    robokrige::output::write_atomic(&a.output, |out| {
        let mut w = csv::Writer::from_writer(out);
        let n = data.n_joints();
        let mut header = vec!["id".to_string()];
        header.extend((1..=n).map(|i| format!("q{i}")));
        header.extend((1..=n).map(|i| format!("dir{i}")));
        header.extend(AXES.iter().map(|a| format!("pred_{a}")));
        header.extend(AXES.iter().map(|a| format!("std_{a}")));
        header.extend(AXES.iter().map(|a| format!("std_new_{a}")));
        if data.errors.is_some() {
            header.extend(AXES.iter().map(|a| a.to_string()));
        }
        w.write_record(&header)?;
        for k in 0..data.len() {
            let id = data.ids.as_ref().map_or(k.to_string(), |v| v[k].clone());
            let mut row = vec![id];
            row.extend(data.q[k].iter().map(f64::to_string));
            row.extend(data.dir[k].iter().map(|d| format!("{d}")));
            row.extend(pred.mean[k].iter().map(f64::to_string));
            row.extend(pred.std[k].iter().map(f64::to_string));
            row.extend((0..3).map(|a| pred.std[k][a].hypot(noise[a]).to_string()));
            if let Some(e) = &data.errors {
                row.extend(e[k].iter().map(f64::to_string));
            }
            w.write_record(&row)?;
        }
        w.flush()
    })?;
    if let Some(e) = &data.errors {
        let resid = robokrige::vec3::residuals(e, &pred.mean);
        let before = robokrige::stats::summarize(e);
        let after = robokrige::stats::summarize(&resid);
        if let Some(path) = &a.json {
            let v = serde_json::json!({"poses": data.len(), "output": a.output,
                "measured": before, "after_subtracting_prediction": after,
                "coverage_warnings": coverage});
            super::write_json(path, &v, "prediction summary")?;
        }
        say!(
            "{} poses: mean 3D error {:.4} mm; after subtracting the prediction {:.4} mm (max {:.4} → {:.4})",
            data.len(),
            before.mean_3d_mm,
            after.mean_3d_mm,
            before.max_3d_mm,
            after.max_3d_mm
        );
    }
    if let (None, Some(path)) = (&data.errors, &a.json) {
        let v = serde_json::json!({"poses": data.len(), "output": a.output,
            "coverage_warnings": coverage});
        super::write_json(path, &v, "prediction summary")?;
    }
    say!("wrote {}", a.output.display());
    Ok(())
}
