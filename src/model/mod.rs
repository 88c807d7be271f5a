//! The TCP error model: one universal-Kriging model per output axis
//! (ex, ey, ez), each with its own ξ and trend (`docs/ARCHITECTURE.md`,
//! "The pipeline", step 3), over JS or EJS inputs z-scored by one shared
//! [`Normalizer`].
//!
//! `fit` returns a model, `predict` is pure; `save`/`load` write a versioned
//! JSON that predicts bit-identically after loading.

mod coverage;
mod file;
mod fit;
mod interval;
mod record;

pub use coverage::{
    CampaignPrediction, CoverageIssue, CoverageWarning, GROSS_FACTOR, LEAN_CORRELATION, LOO_SAMPLE,
    TREND_SIGMAS, Z95,
};
pub use fit::{check_fit_memory, check_fit_rows};
pub(crate) use fit::{fit_outputs, solve_outputs, with_linear_columns};
pub use interval::LooCheck;
pub use record::RobotRecord;

use crate::calibration::Calibration;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::inputs::InputMap;
use crate::kriging::{FitReport, KrigingModel, KrigingOptions, Pred, Trend};
use crate::selection::Selection;
use crate::space::{Normalizer, Space};
use crate::{Error, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Format tag and version of saved models.
pub const MODEL_FORMAT: &str = "robokrige-error-model";
/// Version 4 may hold a kinematic calibration (`calibration`): the model is
/// then the calibration plus Kriging of what it leaves. Version 3 stores the input map (space, periodic joints, extras, names,
/// normalisation) as one field, `inputs`; versions 1 and 2 kept those parts
/// at the top level and the periodic joints in the options, and still load.
/// Version 2 stopped storing the Cholesky factor (O(m·d) files; it is
/// recomputed when first needed).
/// Version 5 may hold a harmonic whose phase is counted from a joint value
/// other than 0 ([`Feature::Harmonic`]'s `centre_deg`), which a build
/// before it would ignore. Version 6 may hold a calibration with the
/// joints' backlash ([`Calibration::backlash`]), which a build before it
/// would ignore too.
pub const MODEL_VERSION: u32 = 6;
/// The version a model with a phase-referenced harmonic and no backlash
/// is written as.
pub const MODEL_VERSION_PHASE: u32 = 5;
/// The version a model with a calibration and no phase-referenced
/// harmonic is written as, readable by the builds before that field.
pub const MODEL_VERSION_CALIBRATED: u32 = 4;
/// The version a model without a calibration (and no phase-referenced
/// harmonic) is written as: such a file is a version-3 model, readable by
/// the builds before calibration.
pub const MODEL_VERSION_UNCALIBRATED: u32 = 3;
/// Oldest model-file version that loads.
pub const MODEL_VERSION_MIN: u32 = 1;

/// Output axis names.
pub const AXES: [&str; 3] = ["ex", "ey", "ez"];

/// A fitted TCP error model δ̂(s) = (δ̂x, δ̂y, δ̂z).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorModel {
    /// File format tag, [`MODEL_FORMAT`].
    pub(crate) format: String,
    /// File format version, [`MODEL_VERSION_MIN`]..=[`MODEL_VERSION`].
    pub(crate) version: u32,
    /// How a pose becomes the inputs: space, periodic joints, extras and
    /// the normalisation fitted on the training rows.
    pub(crate) inputs: InputMap,
    /// The Kriging options the model was fitted with.
    pub(crate) options: KrigingOptions,
    /// One model per axis, in [`AXES`] order.
    pub(crate) outputs: Vec<KrigingModel>,
    /// One fit report per axis (ln ψ, ξ, nugget, evaluations, time).
    pub(crate) reports: Vec<FitReport>,
    /// Basis selection that chose the trends (PCC+PCA or GA), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) selection: Option<Selection>,
    /// Joint range `(min, max)` of the training campaign, degrees, per joint
    /// (empty in files written before it was recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) joint_range: Vec<(f64, f64)>,
    /// The robot the campaign was measured on, when the fit was told
    /// ([`ErrorModel::record_robot`]; the kinematic trend records it itself).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) robot: Option<RobotRecord>,
    /// The robokrige version that fitted the model (empty in older files).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub(crate) software: String,
    /// The kinematic calibration the Kriging outputs sit on, if any: the
    /// model predicts `δ̂_cal(q, λ) + δ̂_UK(s)`, the Kriging outputs having
    /// been fitted to `e − δ̂_cal(q, λ)`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub(crate) calibration: Option<Box<Calibration>>,
    /// The leave-one-out check of the intervals, computed when first
    /// needed ([`ErrorModel::loo_check`]).
    #[serde(skip)]
    pub(crate) loo: interval::LooCache,
}

/// This crate's version, recorded in every model it fits.
pub const SOFTWARE: &str = concat!("robokrige ", env!("CARGO_PKG_VERSION"));

/// Predicted errors with their standard deviations (√MSE), mm.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// Predicted error `[δx, δy, δz]` per point, mm.
    pub mean: Vec<[f64; 3]>,
    /// Its standard deviation per axis (of the mean, without the
    /// measurement noise), mm: the Kriging part's √MSE calibrated on the
    /// model's leave-one-out residuals ([`LooCheck::mean_std`]), and
    /// with a calibration its variance away from the campaign.
    pub std: Vec<[f64; 3]>,
}

impl ErrorModel {
    /// Fit the three outputs of `data` (which needs `ex,ey,ez`) in `space`
    /// with the given options' trend. Outputs and starts run in parallel.
    /// No joint is periodic here: periodic joints, extra inputs and the
    /// other trends are set on `params::ErrorModelParams`.
    ///
    /// ```
    /// use robokrige::{dataset::read_csv, kriging::KrigingOptions, model::ErrorModel, space::Space};
    /// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
    /// let data = read_csv(path.as_ref())?.select(&(0..60).collect::<Vec<_>>());
    /// let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default())?;
    /// assert!(model.options().get_nugget()); // tracker data is noisy
    /// # Ok::<(), robokrige::Error>(())
    /// ```
    pub fn fit(data: &Dataset, space: Space, opts: &KrigingOptions) -> Result<Self> {
        ErrorModel::fit_with_extras(data, space, &[], opts, &[], None)
    }

    /// File format tag, [`MODEL_FORMAT`].
    pub fn format(&self) -> &str {
        &self.format
    }

    /// File format version ([`MODEL_VERSION`] once loaded).
    pub fn version(&self) -> u32 {
        self.version
    }

    /// JS `[θ]` or EJS `[θ, λ]` (seed 003 eq 5).
    pub fn space(&self) -> Space {
        self.inputs.space()
    }

    /// Joints of the robot (columns q1..qN of the campaign).
    pub fn n_joints(&self) -> usize {
        self.inputs.n_joints()
    }

    /// Name of every input column, space encoding first, then the extras.
    pub fn input_names(&self) -> &[String] {
        self.inputs.names()
    }

    /// Z-score of the input columns, fitted on the training rows.
    pub fn input_norm(&self) -> &Normalizer {
        self.inputs.normalizer()
    }

    /// Joints entered as `(sin θ, cos θ)`, 0-based ([`InputMap::periodic`]).
    pub fn periodic(&self) -> &[usize] {
        self.inputs.periodic()
    }

    /// The Kriging options the model was fitted with.
    pub fn options(&self) -> &KrigingOptions {
        &self.options
    }

    /// The three output models, in [`AXES`] order.
    pub fn outputs(&self) -> &[KrigingModel] {
        &self.outputs
    }

    /// The three fit reports (ln ψ, ξ, nugget, evaluations, time), in
    /// [`AXES`] order.
    pub fn reports(&self) -> &[FitReport] {
        &self.reports
    }

    /// Extra inputs after `[θ, λ]` (effects added by `diagnose`).
    pub fn extras(&self) -> &[Feature] {
        self.inputs.extras()
    }

    /// The covariates the model reads (a measured column such as `temp_c`,
    /// alone or inside a product or a lag), each once, with the value a
    /// prediction from poses alone takes ([`ErrorModel::predict`]).
    pub fn covariates(&self) -> Vec<(String, Option<f64>)> {
        let mut out: Vec<(String, Option<f64>)> = Vec::new();
        for (name, reference) in self.extras().iter().filter_map(Feature::covariate) {
            if !out.iter().any(|(n, _)| n == name) {
                out.push((name.to_string(), reference));
            }
        }
        out
    }

    /// The model with covariate `name` held at `value` in predictions from
    /// poses alone (a compensation run at that temperature or payload).
    pub fn at_covariate(mut self, name: &str, value: f64) -> Result<Self> {
        if !value.is_finite() {
            return Err(Error::InvalidParameter(format!(
                "covariate '{name}' = {value}: a finite value is needed"
            )));
        }
        if !self.inputs.set_covariate_reference(name, value) {
            let used: Vec<String> = self.covariates().into_iter().map(|(n, _)| n).collect();
            return Err(Error::InvalidParameter(format!(
                "the model does not use covariate '{name}' (it uses: {})",
                if used.is_empty() {
                    "none".to_string()
                } else {
                    used.join(", ")
                }
            )));
        }
        Ok(self)
    }

    /// The basis selection that chose the trends (PCC+PCA or GA), if any.
    pub fn selection(&self) -> Option<&Selection> {
        self.selection.as_ref()
    }

    /// Joint range `(min, max)` of the training campaign per joint, degrees
    /// (empty for files written before it was recorded).
    pub fn joint_range(&self) -> &[(f64, f64)] {
        &self.joint_range
    }

    /// The robot the campaign was measured on, when the fit was told.
    pub fn robot(&self) -> Option<&RobotRecord> {
        self.robot.as_ref()
    }

    /// The robokrige version that fitted the model (empty in older files).
    pub fn software(&self) -> &str {
        &self.software
    }

    /// Training rows m.
    pub fn n_train(&self) -> usize {
        self.outputs.first().map_or(0, |o| o.data.x_train.len())
    }

    /// The noise standard deviation of each output (mm), what its nugget
    /// attributes to measurement noise ([`KrigingModel::noise_std`]).
    pub fn noise_std(&self) -> [f64; 3] {
        std::array::from_fn(|a| self.outputs.get(a).map_or(0.0, KrigingModel::noise_std))
    }

    /// The linear trend term of input column `column` (by name, e.g.
    /// `step@150`), per output: its GLS coefficient and standard error in mm
    /// per unit of the raw column (`β·y_std/σ_col`, from
    /// [`KrigingModel::beta_std_errors`]); `(0, 0)` on an output whose
    /// trend has no term for it (a column of another axis,
    /// [`Feature::column_axes`]). `None` when the column is not an input, or
    /// has a linear term of its own on no output of a polynomial trend.
    pub fn trend_coefficient(&self, column: &str) -> Option<[(f64, f64); 3]> {
        let i = self.input_names().iter().position(|n| n == column)?;
        let scale = self.input_norm().std.get(i).copied().filter(|s| *s > 0.0)?;
        let mut out = [(0.0, 0.0); 3];
        let mut found = false;
        for (o, k) in out.iter_mut().zip(&self.outputs) {
            let Trend::Monomials(m) = &k.data.trend else {
                return None;
            };
            let Some(t) = m
                .exponents
                .iter()
                .position(|e| e.iter().enumerate().all(|(d, &x)| x == u8::from(d == i)))
            else {
                continue;
            };
            let se = k.beta_std_errors();
            let unit = k.data.y_std / scale;
            *o = (k.data.beta[t] * unit, se[t] * unit);
            found = true;
        }
        found.then_some(out)
    }

    /// This model's hyperparameters, with the curvature its search ended
    /// with, as warm starts of a fit on similar data, one per output
    /// (`HyperSpec::Warm` of the error-model params).
    pub fn warm_starts(&self) -> Vec<crate::kriging::Hyperparameters> {
        let d = self.correlation_dims();
        self.reports
            .iter()
            .map(|r| crate::kriging::Hyperparameters::of(r, d))
            .collect()
    }

    /// Input dimensions that enter the correlation: `[θ, λ]` encoded and the
    /// extras that are not trend-only (those come first, see
    /// `params::ErrorModelParams::extras`).
    pub fn correlation_dims(&self) -> usize {
        self.inputs.corr_dims()
    }

    /// Warnings about the conditioning of the fit: an output whose correlation
    /// matrix needed more diagonal jitter than DACE's `(10 + m)·eps` to be
    /// factorised (near-duplicate poses, very long correlation lengths).
    pub fn conditioning_warnings(&self) -> Vec<String> {
        self.reports
            .iter()
            .zip(AXES)
            .filter_map(|(r, ax)| {
                let m = self.n_train();
                let base = self
                    .options
                    .min_jitter
                    .unwrap_or((10.0 + m as f64) * f64::EPSILON);
                (r.jitter > 1.5 * base).then(|| {
                    format!(
                        "{ax}: the correlation matrix was numerically singular (near-duplicate poses?); jitter {:.1e} was added to its diagonal",
                        r.jitter
                    )
                })
            })
            .collect()
    }

    /// Predict at poses `q` approached in directions `dir` (ignored in JS).
    /// Extra inputs are computed from the pose sequence
    /// ([`Feature::columns_from_poses`]).
    pub fn predict(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Prediction> {
        self.check_rows(q, dir)?;
        let mut p = self.predict_inputs(&self.inputs.encode(q, dir)?)?;
        self.add_calibration(q, dir, &mut p)?;
        Ok(p)
    }

    /// The kinematic calibration under the Kriging outputs, if the model
    /// was fitted with one (`ErrorModelParams::calibrate`).
    pub fn calibration(&self) -> Option<&Calibration> {
        self.calibration.as_deref()
    }

    /// The options a refit identifies its calibration with: the model's
    /// own, or the defaults for a model without a calibration.
    pub fn calibration_options(&self) -> crate::calibration::CalibrationOptions {
        self.calibration()
            .map_or_else(Default::default, |c| c.options().clone())
    }

    /// The file version this model is written as: the oldest that holds
    /// it. 6 with a calibration's backlash, else 5 with a phase-referenced
    /// harmonic, else 4 with a calibration and 3 without.
    pub(crate) fn file_version(&self) -> u32 {
        if self
            .calibration
            .as_ref()
            .is_some_and(|c| !c.backlash().is_empty())
        {
            MODEL_VERSION
        } else if self.extras().iter().any(Feature::has_phase_reference) {
            MODEL_VERSION_PHASE
        } else if self.calibration.is_some() {
            MODEL_VERSION_CALIBRATED
        } else {
            MODEL_VERSION_UNCALIBRATED
        }
    }

    /// This model with `calibration` under its Kriging outputs, which must
    /// have been fitted to what it leaves ([`Calibration::residual`]): the
    /// model then predicts `δ̂_cal + δ̂_UK`. What `diagnose --calibrate`
    /// does with the model it improved on the calibration's residual.
    /// Replaces a calibration the model already had.
    pub fn with_calibration(mut self, calibration: Calibration) -> Self {
        self.calibration = Some(Box::new(calibration));
        self.version = self.file_version();
        self
    }

    /// Add the calibration's kinematic error `δ̂_cal(q, λ)` (if any) to the
    /// Kriging outputs' predicted means, and to their MSE the calibration's
    /// variance beyond its largest over the campaign,
    /// `max(0, Var δ̂_cal(q) − max_campaign Var δ̂_cal)`
    /// ([`Calibration::predict_variance`]): where it was measured, the
    /// Kriging of the calibration's residual already carries the
    /// calibration's error (it was fitted to it); away from there it
    /// cannot, and the calibration's extra uncertainty is added.
    fn add_calibration(&self, q: &[Vec<f64>], dir: &[Vec<f64>], p: &mut Prediction) -> Result<()> {
        if let Some(c) = &self.calibration {
            add_to(&mut p.mean, &c.predict(q, dir)?);
            let base = c.campaign_variance();
            for (s, v) in p.std.iter_mut().zip(c.predict_variance(q, dir)?) {
                *s = std::array::from_fn(|a| (s[a] * s[a] + (v[a] - base[a]).max(0.0)).sqrt());
            }
        }
        Ok(())
    }

    /// The map from poses to this model's normalised inputs: space,
    /// periodic joints, extras and normalisation.
    pub fn input_map(&self) -> &InputMap {
        &self.inputs
    }

    fn predict_inputs(&self, s: &[Vec<f64>]) -> Result<Prediction> {
        // the first standard deviation needs each output's m × m factor,
        // which then stays with the model: known before it is allocated
        let m = self.n_train();
        let missing = self.outputs.iter().filter(|o| !o.has_factors()).count() as u64;
        if missing > 0 {
            crate::memory::check(
                &format!(
                    "prediction standard deviations of a {m}-row model ({missing} m × m factor(s))"
                ),
                missing * crate::memory::square_bytes(m),
                &format!(
                    "predict the mean only (`compensate` does), or fit on fewer rows; or raise {}",
                    crate::memory::LIMIT_ENV
                ),
            )?;
        }
        let per_axis: Vec<Vec<Pred>> = if m > crate::kriging::model::KEEP_FACTOR_MAX_M {
            // large models: one factorisation at a time, each multi-threaded
            self.outputs
                .iter()
                .map(|o| o.predict(s))
                .collect::<Result<_>>()?
        } else {
            self.outputs
                .par_iter()
                .map(|o| o.predict(s))
                .collect::<Result<_>>()?
        };
        let check = self.loo_check()?;
        let mut mean = vec![[0.0; 3]; s.len()];
        let mut std = vec![[0.0; 3]; s.len()];
        for (a, preds) in per_axis.iter().enumerate() {
            for (k, p) in preds.iter().enumerate() {
                mean[k][a] = p.mean;
                std[k][a] = check.mean_std(a, p.mse);
            }
        }
        Ok(Prediction { mean, std })
    }

    /// How far (mm, 3D) the predicted error at joints `q` moves when every
    /// joint's direction `dir` is reversed: what an assumed λ can be worth
    /// (0 in joint space, which ignores λ).
    pub fn direction_sensitivity(&self, q: &[f64], dir: &[f64]) -> Result<f64> {
        if self.space() == Space::Js {
            return Ok(0.0);
        }
        let flipped: Vec<f64> = dir.iter().map(|v| -v).collect();
        let p = self.predict_mean(&[q.to_vec(), q.to_vec()], &[dir.to_vec(), flipped])?;
        Ok((0..3)
            .map(|k| (p[0][k] - p[1][k]).powi(2))
            .sum::<f64>()
            .sqrt())
    }

    /// The predicted error only (no standard deviation), mm: the fast path
    /// for compensation.
    ///
    /// ```
    /// # use robokrige::{dataset::read_csv, kriging::KrigingOptions, model::ErrorModel, space::Space};
    /// # let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
    /// # let data = read_csv(path.as_ref())?.select(&(0..60).collect::<Vec<_>>());
    /// # let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default())?;
    /// // joints (degrees) and directions λ = ±1 of two commanded poses
    /// let q = vec![vec![5.0, -10.0, 20.0, 0.0, 30.0, 0.0]; 2];
    /// let dir = vec![vec![1.0; 6], vec![-1.0; 6]];
    /// let errors = model.predict_mean(&q, &dir)?; // [ex, ey, ez] in mm per pose
    /// assert_eq!(errors.len(), 2);
    /// # Ok::<(), robokrige::Error>(())
    /// ```
    pub fn predict_mean(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        self.check_rows(q, dir)?;
        let s = self.inputs.encode(q, dir)?;
        let per_axis: Vec<Vec<f64>> = self
            .outputs
            .par_iter()
            .map(|m| m.predict_mean(&s))
            .collect();
        let mut mean: Vec<[f64; 3]> = (0..q.len())
            .map(|k| [per_axis[0][k], per_axis[1][k], per_axis[2][k]])
            .collect();
        if let Some(c) = &self.calibration {
            add_to(&mut mean, &c.predict(q, dir)?);
        }
        Ok(mean)
    }

    fn check_rows(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<()> {
        if q.len() != dir.len() {
            return Err(Error::InvalidParameter(
                "q and dir have different row counts".into(),
            ));
        }
        for r in q.iter().chain(dir) {
            if r.len() != self.n_joints() {
                return Err(Error::JointCount {
                    expected: self.n_joints(),
                    got: r.len(),
                });
            }
        }
        Ok(())
    }

    /// Predict for every row of a dataset (extra inputs from its columns).
    pub fn predict_dataset(&self, data: &Dataset) -> Result<Prediction> {
        self.check_rows(&data.q, &data.dir)?;
        let mut p = self.predict_inputs(&self.inputs.encode_dataset(data)?)?;
        self.add_calibration(&data.q, &data.dir, &mut p)?;
        Ok(p)
    }
}

/// `a += b`, row by row.
fn add_to(a: &mut [[f64; 3]], b: &[[f64; 3]]) {
    for (x, y) in a.iter_mut().zip(b) {
        *x = [x[0] + y[0], x[1] + y[1], x[2] + y[2]];
    }
}

impl crate::predictor::ErrorPredictor for ErrorModel {
    fn n_joints(&self) -> usize {
        self.inputs.n_joints()
    }
    fn predict_errors(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        self.predict_mean(q, dir)
    }
}
