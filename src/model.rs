//! The TCP error model: one universal-Kriging model per output axis
//! (ex, ey, ez), each with its own ξ and trend (DESIGN.md §3), over JS or EJS
//! inputs z-scored by one shared [`Normalizer`].
//!
//! `fit` returns a model, `predict` is pure; `save`/`load` write a versioned
//! JSON that predicts bit-identically after loading.

use crate::dataset::Dataset;
use crate::features::Feature;
use crate::inputs::InputMap;
use crate::kriging::{
    FitReport, KrigingModel, KrigingOptions, Pred, TrainingInputs, fit_output_from,
};
use crate::space::{Normalizer, Space};
use crate::{Error, Result};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Per joint `(min, max)` of the rows.
fn joint_range(q: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let n = q.first().map_or(0, Vec::len);
    (0..n)
        .map(|j| {
            q.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                    (lo.min(r[j]), hi.max(r[j]))
                })
        })
        .collect()
}

/// The plan of a 3-output fit of `rows` rows ([`crate::kriging::FitPlan`]),
/// refused with [`Error::Memory`] when its estimated peak exceeds the
/// memory limit ([`crate::memory`]); the message says how to fit the most
/// rows that fit: `subset(rows)` (e.g. "`--rows 5000`"), or raising the limit.
pub fn check_fit_memory(
    rows: usize,
    optimizer: crate::kriging::OptimizerKind,
    subset: impl Fn(usize) -> String,
) -> Result<crate::kriging::FitPlan> {
    let threads = rayon::current_num_threads();
    let plan = crate::kriging::FitPlan::new(rows, 3, optimizer, threads);
    if let Some((limit, _)) = crate::memory::limit() {
        let fits = crate::kriging::FitPlan::max_rows(limit, 3, optimizer, threads);
        crate::memory::check(
            &format!("a fit of {rows} rows"),
            plan.bytes,
            &format!(
                "fit at most {fits} rows ({}), or raise {}",
                subset(fits),
                crate::memory::LIMIT_ENV
            ),
        )?;
    }
    Ok(plan)
}

/// Format tag and version of saved models.
pub const MODEL_FORMAT: &str = "robokrige-error-model";
/// Version 2 stores no Cholesky factor (O(m·d) files; it is recomputed when
/// first needed). Version 1 files, which store it, still load.
pub const MODEL_VERSION: u32 = 2;
/// Oldest model-file version that loads.
pub const MODEL_VERSION_MIN: u32 = 1;

/// Output axis names.
pub const AXES: [&str; 3] = ["ex", "ey", "ez"];

/// A fitted TCP error model δ̂(s) = (δ̂x, δ̂y, δ̂z).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ErrorModel {
    /// File format tag, [`MODEL_FORMAT`].
    pub format: String,
    /// File format version, [`MODEL_VERSION_MIN`]..=[`MODEL_VERSION`].
    pub version: u32,
    /// JS `[θ]` or EJS `[θ, λ]` (seed 003 eq 5).
    pub space: Space,
    /// Joints of the robot (columns q1..qN of the campaign).
    pub n_joints: usize,
    /// Name of every input column, space encoding first, then the extras.
    pub input_names: Vec<String>,
    /// Z-score of the input columns, fitted on the training rows.
    pub input_norm: Normalizer,
    /// The options the model was fitted with (periodic joints included).
    pub options: KrigingOptions,
    /// One model per axis, in [`AXES`] order.
    pub outputs: Vec<KrigingModel>,
    /// One fit report per axis (ln ψ, ξ, nugget, evaluations, time).
    pub reports: Vec<FitReport>,
    /// Extra inputs after `[θ, λ]` (effects added by `diagnose`).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub extras: Vec<Feature>,
    /// Basis selection that chose the trends (PCC+PCA or GA), if any.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub selection: Option<crate::basis::Selection>,
    /// Joint range `(min, max)` of the training campaign, degrees, per joint
    /// (empty in files written before it was recorded).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub joint_range: Vec<(f64, f64)>,
    /// The robot the campaign was measured on, when the fit was told
    /// ([`ErrorModel::record_robot`]; the kinematic trend records it itself).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub robot: Option<RobotRecord>,
    /// The robokrige version that fitted the model (empty in older files).
    #[serde(default, skip_serializing_if = "String::is_empty")]
    pub software: String,
}

/// Which robot a model was fitted for: its name, the digest of its kinematic
/// table ([`crate::kinematics::table_digest`]) and its tool. A model predicts
/// the TCP error of that robot with that tool only.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RobotRecord {
    /// The robot's name.
    pub name: String,
    /// Digest of the MD-H table and base frame.
    pub table_digest: String,
    /// Flange ← TCP: translation (mm) and roll–pitch–yaw (degrees).
    pub tool: crate::kinematics::FrameSpec,
}

/// Tool frames closer than this (mm, and degrees) are the same tool.
const TOOL_TOLERANCE: f64 = 1e-6;

impl RobotRecord {
    /// The record of `robot`.
    pub fn of(robot: &crate::kinematics::Robot) -> Self {
        RobotRecord {
            name: robot.name.clone(),
            table_digest: crate::kinematics::table_digest(robot),
            tool: crate::kinematics::FrameSpec::of(&robot.tool),
        }
    }

    /// Error unless `robot` has this record's kinematic table and tool; the
    /// message names both robots (`source_name`: the model file).
    pub fn check(&self, robot: &crate::kinematics::Robot, source_name: &str) -> Result<()> {
        let other = RobotRecord::of(robot);
        let refuse = |what: String| {
            Err(Error::Input {
                source_name: source_name.into(),
                message: format!(
                    "the model was fitted for robot '{}' but the robot given is '{}': {what}; give the robot (and --tool) the campaign was measured with, or refit",
                    self.name, other.name
                ),
            })
        };
        if other.table_digest != self.table_digest {
            return refuse(format!(
                "their kinematic tables differ (digest {} vs {})",
                self.table_digest, other.table_digest
            ));
        }
        let dist =
            |a: [f64; 3], b: [f64; 3]| (0..3).map(|k| (a[k] - b[k]).abs()).fold(0.0, f64::max);
        if dist(self.tool.xyz_mm, other.tool.xyz_mm) > TOOL_TOLERANCE
            || dist(self.tool.rpy_deg, other.tool.rpy_deg) > TOOL_TOLERANCE
        {
            return refuse(format!(
                "their tools differ ({:?} mm vs {:?} mm)",
                self.tool.xyz_mm, other.tool.xyz_mm
            ));
        }
        Ok(())
    }
}

/// This crate's version, recorded in every model it fits.
pub const SOFTWARE: &str = concat!("robokrige ", env!("CARGO_PKG_VERSION"));

/// Why a prediction point is outside what the training data covers.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum CoverageIssue {
    /// A joint outside the campaign's range.
    JointRange {
        /// 0-based joint.
        joint: usize,
        /// The joint's value at the point, degrees (mm if prismatic).
        value_deg: f64,
        /// Smallest value of that joint in the training campaign.
        min_deg: f64,
        /// Largest value of that joint in the training campaign.
        max_deg: f64,
    },
    /// The prediction's standard deviation is a large share of the prior
    /// (process) standard deviation: no training pose is near.
    Uncertain {
        /// Output axis (0 x, 1 y, 2 z).
        axis: usize,
        /// The prediction's standard deviation √MSE, mm.
        std_mm: f64,
        /// The process standard deviation σ of that output, mm.
        process_std_mm: f64,
    },
    /// The Kriging correction `r(s)ᵀγ` departs from the trend-only
    /// prediction by more than the process σ allows: a trend that
    /// extrapolates wildly, corrected by the GP near the data only.
    TrendDisagrees {
        /// Output axis (0 x, 1 y, 2 z).
        axis: usize,
        /// The correction `r(s)ᵀγ` added to the trend, mm.
        correction_mm: f64,
        /// The process standard deviation σ of that output, mm.
        process_std_mm: f64,
    },
}

impl std::fmt::Display for CoverageIssue {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CoverageIssue::JointRange {
                joint,
                value_deg,
                min_deg,
                max_deg,
            } => write!(
                f,
                "q{} = {value_deg:.2}° outside the campaign's [{min_deg:.2}, {max_deg:.2}]°",
                joint + 1
            ),
            CoverageIssue::Uncertain {
                axis,
                std_mm,
                process_std_mm,
            } => write!(
                f,
                "{} std {std_mm:.4} mm is {:.0} % of the prior {process_std_mm:.4} mm (far from every training pose)",
                AXES[*axis],
                100.0 * std_mm / process_std_mm
            ),
            CoverageIssue::TrendDisagrees {
                axis,
                correction_mm,
                process_std_mm,
            } => write!(
                f,
                "{} Kriging correction {correction_mm:.3} mm is {:.1} process σ ({process_std_mm:.4} mm) from the trend",
                AXES[*axis],
                correction_mm.abs() / process_std_mm
            ),
        }
    }
}

/// A prediction point with its coverage issues.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CoverageWarning {
    /// 0-based index of the point.
    pub index: usize,
    /// Every way the point leaves what the data covers.
    pub issues: Vec<CoverageIssue>,
}

/// Share of the process standard deviation above which a prediction's
/// standard deviation counts as "far from the data" (the Kriging std tends
/// to the process std away from every training pose).
pub const UNCERTAIN_SHARE: f64 = 0.7;
/// Process σ's by which the Kriging correction may depart from the trend.
pub const TREND_SIGMAS: f64 = 6.0;

/// Predicted errors with their standard deviations (√MSE), mm.
#[derive(Debug, Clone, PartialEq)]
pub struct Prediction {
    /// Predicted error `[δx, δy, δz]` per point, mm.
    pub mean: Vec<[f64; 3]>,
    /// Its standard deviation per axis, mm.
    pub std: Vec<[f64; 3]>,
}

impl ErrorModel {
    /// Fit the three outputs of `data` (which needs `ex,ey,ez`) in `space`
    /// with the given options' trend. Outputs and starts run in parallel.
    ///
    /// ```
    /// use robokrige::{dataset::read_csv, kriging::KrigingOptions, model::ErrorModel, space::Space};
    /// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
    /// let data = read_csv(path.as_ref())?.select(&(0..60).collect::<Vec<_>>());
    /// let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default())?;
    /// assert!(model.options.nugget); // tracker data is noisy
    /// # Ok::<(), robokrige::Error>(())
    /// ```
    pub fn fit(data: &Dataset, space: Space, opts: &KrigingOptions) -> Result<Self> {
        let trend = opts
            .trend
            .trend(space.encoded_dim(data.n_joints(), &opts.periodic));
        Self::fit_with_trend(data, space, opts, &[trend.clone(), trend.clone(), trend])
    }

    /// Universal Kriging with the kinematic-error trend (issue 10; seed 003
    /// eq 4): each output's trend is `opts.trend`'s monomials plus the rows of
    /// `robot`'s identification Jacobian for the calibration parameters that
    /// are identifiable on `data` as a whole and, on that output's axis
    /// alone, seen and well conditioned ([`kinematic_trends`]). One fit thus
    /// does the kinematic calibration (the trend's β) and Kriging of what
    /// remains.
    pub fn fit_kinematic(
        data: &Dataset,
        space: Space,
        opts: &KrigingOptions,
        robot: &crate::kinematics::Robot,
    ) -> Result<Self> {
        let trends = kinematic_trends(data, space, opts, robot)?;
        let mut model = Self::fit_with_trend(data, space, opts, &trends)?;
        model.record_robot(robot)?;
        Ok(model)
    }

    /// Record the robot (and tool) the campaign was measured with, so that
    /// commands given another robot refuse the model ([`RobotRecord::check`]).
    /// Error if the robot's joint count differs from the model's.
    pub fn record_robot(&mut self, robot: &crate::kinematics::Robot) -> Result<()> {
        if robot.dof() != self.n_joints {
            return Err(Error::JointCount {
                expected: self.n_joints,
                got: robot.dof(),
            });
        }
        self.robot = Some(RobotRecord::of(robot));
        Ok(())
    }

    /// Error if the model records a robot other than `robot`, or has another
    /// joint count (`source_name`: the model file, for the message). A model
    /// that records no robot passes on its joint count alone.
    pub fn check_robot(&self, robot: &crate::kinematics::Robot, source_name: &str) -> Result<()> {
        if robot.dof() != self.n_joints {
            return Err(Error::Input {
                source_name: source_name.into(),
                message: format!(
                    "the model has {} joints but robot '{}' has {}",
                    self.n_joints,
                    robot.name,
                    robot.dof()
                ),
            });
        }
        match &self.robot {
            Some(r) => r.check(robot, source_name),
            None => Ok(()),
        }
    }

    /// EJS&PCA of seed 003: for each output, PCC + PCA fusion
    /// ([`crate::basis::pcc_pca`]) of the monomials of degree ≤ 2 in the
    /// normalised inputs, selected on `data` only (so inside each training fold
    /// when used in a refit CV), then the fit with that trend.
    pub fn fit_pcc_pca(
        data: &Dataset,
        space: Space,
        opts: &KrigingOptions,
        threshold: f64,
        variance_share: f64,
    ) -> Result<(Self, Vec<crate::basis::PccPcaReport>)> {
        Self::fit_pcc_pca_with(data, space, opts, threshold, variance_share, None)
    }

    /// [`ErrorModel::fit_pcc_pca`] with, when `kinematic` names a robot, the
    /// rows of its identification Jacobian among the candidates (issue 10).
    pub fn fit_pcc_pca_with(
        data: &Dataset,
        space: Space,
        opts: &KrigingOptions,
        threshold: f64,
        variance_share: f64,
        kinematic: Option<&crate::kinematics::Robot>,
    ) -> Result<(Self, Vec<crate::basis::PccPcaReport>)> {
        let errors = data.errors_or_err()?;
        let (map, x) = InputMap::fit(data, space, &opts.periodic, &[])?;
        let d = map.dim();
        let names = map.names();
        let quad = KrigingOptions {
            trend: crate::kriging::TrendKind::Quadratic,
            ..opts.clone()
        };
        let candidates: [crate::kriging::Trend; 3] = match kinematic {
            Some(robot) => kinematic_candidates(data, space, &quad, robot)?,
            None => std::array::from_fn(|_| crate::kriging::Monomials::quadratic(d).into()),
        };
        let mut trends = Vec::with_capacity(3);
        let mut reports = Vec::with_capacity(3);
        for a in 0..3 {
            let y: Vec<f64> = errors.iter().map(|e| e[a]).collect();
            let (basis, report) = crate::basis::pcc_pca(
                &candidates[a],
                &x,
                &y,
                threshold,
                variance_share,
                data.len() / 2,
                names,
            )?;
            trends.push(crate::kriging::Trend::Fused(basis));
            reports.push(report);
        }
        let trends: [crate::kriging::Trend; 3] = trends.try_into().expect("three outputs");
        let mut model = Self::fit_with_trend(data, space, opts, &trends)?;
        model.selection = Some(crate::basis::Selection::PccPca {
            outputs: reports.clone(),
        });
        Ok((model, reports))
    }

    /// Fit with extra inputs `extras` after `[θ, λ]`: each gets a linear
    /// trend term next to the options' trend in `[θ, λ]`, and those that are
    /// not [`Feature::trend_only`] are also input dimensions of the
    /// correlation. The model stores the extras with the correlation inputs
    /// first (the order of its input columns).
    pub fn fit_with_extras(
        data: &Dataset,
        space: Space,
        opts: &KrigingOptions,
        extras: &[Feature],
    ) -> Result<Self> {
        let mut extras = extras.to_vec();
        extras.sort_by_key(Feature::trend_only);
        let extras = &extras[..];
        let d0 = space.encoded_dim(data.n_joints(), &opts.periodic);
        let extra_dims: usize = extras.iter().map(|f| f.names().len()).sum();
        let mut terms = opts.trend.monomials(d0);
        terms.dim = d0 + extra_dims;
        for e in &mut terms.exponents {
            e.resize(d0 + extra_dims, 0);
        }
        for k in 0..extra_dims {
            let mut e = vec![0u8; d0 + extra_dims];
            e[d0 + k] = 1;
            terms.exponents.push(e);
        }
        let trend = crate::kriging::Trend::from(terms);
        Self::fit_inner(
            data,
            space,
            opts,
            &[trend.clone(), trend.clone(), trend],
            extras,
        )
    }

    /// Fit with a (possibly different) trend candidate set per output.
    pub fn fit_with_trend(
        data: &Dataset,
        space: Space,
        opts: &KrigingOptions,
        trends: &[crate::kriging::Trend; 3],
    ) -> Result<Self> {
        Self::fit_inner(data, space, opts, trends, &[])
    }

    fn fit_inner(
        data: &Dataset,
        space: Space,
        opts: &KrigingOptions,
        trends: &[crate::kriging::Trend; 3],
        extras: &[Feature],
    ) -> Result<Self> {
        opts.validate()?;
        let errors = data.errors_or_err()?;
        if data.len() < 3 {
            return Err(Error::Input {
                source_name: data.source.clone(),
                message: format!(
                    "{} rows are too few to fit a model (need at least 3)",
                    data.len()
                ),
            });
        }
        let n = data.n_joints();
        let (map, x) = InputMap::fit(data, space, &opts.periodic, extras)?;
        let corr_dims = map.corr_dims();
        let inputs = TrainingInputs::new(
            &x.iter()
                .map(|r| r[..corr_dims].to_vec())
                .collect::<Vec<_>>(),
        );
        if !matches!(opts.warm_start.len(), 0 | 3) {
            return Err(Error::InvalidParameter(format!(
                "warm starts must be one per output (3), not {}",
                opts.warm_start.len()
            )));
        }
        let plan = check_fit_memory(data.len(), opts.optimizer, |n| {
            format!("a subset of {n} rows")
        })?;
        let fit_axis = |a: usize| {
            let y: Vec<f64> = errors.iter().map(|e| e[a]).collect();
            let fit = if opts.corr_auto {
                crate::kriging::fit_output_auto
            } else {
                fit_output_from
            };
            fit(
                &x,
                &inputs,
                &y,
                &trends[a],
                map.names(),
                opts,
                opts.warm_start.get(a),
            )
        };
        // large campaigns: one output at a time, one m × m factor in memory
        let fits: Vec<Result<(KrigingModel, FitReport)>> = if plan.sequential_outputs {
            (0..3).map(fit_axis).collect()
        } else {
            (0..3).into_par_iter().map(fit_axis).collect()
        };
        let mut outputs = Vec::with_capacity(3);
        let mut reports = Vec::with_capacity(3);
        for (a, f) in fits.into_iter().enumerate() {
            let (m, r) = f.map_err(|e| Error::Axis {
                axis: AXES[a],
                source: Box::new(e),
            })?;
            outputs.push(m);
            reports.push(r);
        }
        Ok(ErrorModel {
            format: MODEL_FORMAT.into(),
            version: MODEL_VERSION,
            space,
            n_joints: n,
            input_names: map.names().to_vec(),
            input_norm: map.normalizer().clone(),
            // a warm start is how this fit began, not what the model is
            options: KrigingOptions {
                warm_start: Vec::new(),
                ..opts.clone()
            },
            outputs,
            reports,
            extras: extras.to_vec(),
            selection: None,
            joint_range: joint_range(&data.q),
            robot: None,
            software: SOFTWARE.into(),
        })
    }

    /// Refit on `data` at this model's correlation parameters ξ and nugget
    /// (no search): the way to scale to thousands of rows when the O(m³)
    /// search is too slow — choose ξ on a subset, then one factorisation on
    /// everything (issue 10). Same space, options and kind of trend; a
    /// kinematic trend is rebuilt for `data` (its parameters and the input
    /// normalisation are re-derived), a polynomial one reused. The reports
    /// keep the subset's search figures (ln ψ, evaluations).
    pub fn refit_at_hyperparameters(&self, data: &Dataset) -> Result<Self> {
        if !self.extras.is_empty() {
            return Err(Error::InvalidParameter(
                "refit at fixed hyperparameters does not support extra inputs".into(),
            ));
        }
        let t0 = std::time::Instant::now();
        let errors = data.errors_or_err()?;
        self.check_rows(&data.q, &data.dir)?;
        let trends: [crate::kriging::Trend; 3] = match &self.outputs[0].data.trend {
            crate::kriging::Trend::Kinematic(k) => {
                kinematic_trends(data, self.space, &self.options, &k.robot)?
            }
            _ => std::array::from_fn(|a| self.outputs[a].data.trend.clone()),
        };
        let (map, x) = InputMap::fit(data, self.space, &self.options.periodic, &[])?;
        let input_norm = map.normalizer().clone();
        let inputs = TrainingInputs::new(&x);
        let fits: Vec<Result<KrigingModel>> = (0..3)
            .into_par_iter()
            .map(|a| {
                let y: Vec<f64> = errors.iter().map(|e| e[a]).collect();
                let r = &self.reports[a];
                let at = crate::kriging::Hyperparameters {
                    corr: self.outputs[a].corr(),
                    theta: &r.theta,
                    nugget: r.nugget,
                    min_jitter: self.options.min_jitter,
                };
                crate::kriging::fit_output_with(&x, &inputs, &y, &trends[a], &at)
            })
            .collect();
        let mut outputs = Vec::with_capacity(3);
        for (a, f) in fits.into_iter().enumerate() {
            outputs.push(f.map_err(|e| Error::Axis {
                axis: AXES[a],
                source: Box::new(e),
            })?);
        }
        let secs = t0.elapsed().as_secs_f64();
        let reports = self
            .reports
            .iter()
            .map(|r| FitReport {
                seconds: secs,
                ..r.clone()
            })
            .collect();
        Ok(ErrorModel {
            input_norm,
            outputs,
            reports,
            joint_range: joint_range(&data.q),
            ..self.clone()
        })
    }

    /// This model's hyperparameters as warm starts of a refit on similar data
    /// ([`KrigingOptions::warm_start`]), one per output.
    pub fn warm_starts(&self) -> Vec<crate::kriging::WarmStart> {
        let d = self.correlation_dims();
        self.reports
            .iter()
            .map(|r| crate::kriging::WarmStart::of(r, d))
            .collect()
    }

    /// Input dimensions that enter the correlation: `[θ, λ]` encoded and the
    /// extras that are not trend-only (those come first, see
    /// [`ErrorModel::fit_with_extras`]).
    pub fn correlation_dims(&self) -> usize {
        self.input_names.len() - crate::features::trend_only_dims(&self.extras)
    }

    /// Warnings about the conditioning of the fit: an output whose correlation
    /// matrix needed more diagonal jitter than DACE's `(10 + m)·eps` to be
    /// factorised (near-duplicate poses, very long correlation lengths).
    pub fn conditioning_warnings(&self) -> Vec<String> {
        self.reports
            .iter()
            .zip(AXES)
            .filter_map(|(r, ax)| {
                let m = self.outputs.first().map_or(0, |o| o.data.x_train.len());
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
        self.predict_inputs(&self.input_map().encode(q, dir)?)
    }

    /// The map from poses to this model's normalised inputs.
    pub fn input_map(&self) -> InputMap {
        InputMap::from_parts(
            self.space,
            self.n_joints,
            &self.options.periodic,
            &self.extras,
            &self.input_names,
            &self.input_norm,
        )
    }

    fn predict_inputs(&self, s: &[Vec<f64>]) -> Result<Prediction> {
        // the first standard deviation needs each output's m × m factor,
        // which then stays with the model: known before it is allocated
        let m = self.outputs.first().map_or(0, |o| o.data.x_train.len());
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
        let mut mean = vec![[0.0; 3]; s.len()];
        let mut std = vec![[0.0; 3]; s.len()];
        for (a, preds) in per_axis.iter().enumerate() {
            for (k, p) in preds.iter().enumerate() {
                mean[k][a] = p.mean;
                std[k][a] = p.mse.sqrt();
            }
        }
        Ok(Prediction { mean, std })
    }

    /// How far (mm, 3D) the predicted error at joints `q` moves when every
    /// joint's direction `dir` is reversed: what an assumed λ can be worth
    /// (0 in joint space, which ignores λ).
    pub fn direction_sensitivity(&self, q: &[f64], dir: &[f64]) -> Result<f64> {
        if self.space == Space::Js {
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
        let s = self.input_map().encode(q, dir)?;
        let per_axis: Vec<Vec<f64>> = self
            .outputs
            .par_iter()
            .map(|m| m.predict_mean(&s))
            .collect();
        Ok((0..q.len())
            .map(|k| [per_axis[0][k], per_axis[1][k], per_axis[2][k]])
            .collect())
    }

    fn check_rows(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<()> {
        if q.len() != dir.len() {
            return Err(Error::InvalidParameter(
                "q and dir have different row counts".into(),
            ));
        }
        for r in q.iter().chain(dir) {
            if r.len() != self.n_joints {
                return Err(Error::JointCount {
                    expected: self.n_joints,
                    got: r.len(),
                });
            }
        }
        Ok(())
    }

    /// Predict for every row of a dataset (extra inputs from its columns).
    pub fn predict_dataset(&self, data: &Dataset) -> Result<Prediction> {
        self.check_rows(&data.q, &data.dir)?;
        self.predict_inputs(&self.input_map().encode_dataset(data)?)
    }

    /// The points of a prediction that leave what the training data
    /// covers (issue 16 §3): a joint outside the campaign's range, a
    /// standard deviation over [`UNCERTAIN_SHARE`] of the process std, or a
    /// Kriging correction more than [`TREND_SIGMAS`] process σ from the
    /// trend-only prediction. `mean` is this model's predicted mean at `q`,
    /// `dir`; `std` its standard deviations when they were computed (the
    /// std check is skipped without them, so a caller that needs only the
    /// mean, like compensation, never pays for the m × m factor). Only
    /// points with an issue are listed, in order.
    pub fn coverage(
        &self,
        q: &[Vec<f64>],
        dir: &[Vec<f64>],
        mean: &[[f64; 3]],
        std: Option<&[[f64; 3]]>,
    ) -> Result<Vec<CoverageWarning>> {
        self.check_rows(q, dir)?;
        let s = self.input_map().encode(q, dir)?;
        let trend: Vec<Vec<f64>> = self.outputs.iter().map(|o| o.predict_trend(&s)).collect();
        let mut out = Vec::new();
        for (k, qk) in q.iter().enumerate() {
            let mut issues = Vec::new();
            for (j, (&v, &(lo, hi))) in qk.iter().zip(&self.joint_range).enumerate() {
                if v < lo || v > hi {
                    issues.push(CoverageIssue::JointRange {
                        joint: j,
                        value_deg: v,
                        min_deg: lo,
                        max_deg: hi,
                    });
                }
            }
            for (a, o) in self.outputs.iter().enumerate() {
                let process = o.process_std();
                if let Some(s) = std
                    .map(|s| s[k][a])
                    .filter(|s| *s > UNCERTAIN_SHARE * process)
                {
                    issues.push(CoverageIssue::Uncertain {
                        axis: a,
                        std_mm: s,
                        process_std_mm: process,
                    });
                }
                let correction = mean[k][a] - trend[a][k];
                if correction.abs() > TREND_SIGMAS * process {
                    issues.push(CoverageIssue::TrendDisagrees {
                        axis: a,
                        correction_mm: correction,
                        process_std_mm: process,
                    });
                }
            }
            if !issues.is_empty() {
                out.push(CoverageWarning { index: k, issues });
            }
        }
        Ok(out)
    }

    /// Write as JSON, atomically. The text is loaded back first: a model
    /// that would not load (issue 18: a `y_std` that overflowed to `null`)
    /// is never written.
    pub fn save(&self, path: &Path) -> Result<()> {
        let text = self.to_json()?;
        Self::from_json(&text, &path.display().to_string()).map_err(|e| {
            Error::Numerical(format!(
                "refusing to write {}: the model would not load back ({e})",
                path.display()
            ))
        })?;
        crate::output::write_text(path, &text)
    }

    /// The model file's JSON text.
    pub fn to_json(&self) -> Result<String> {
        serde_json::to_string(self).map_err(|e| Error::Json {
            context: "model".into(),
            source: e,
        })
    }

    /// The ranges of a loaded model's values (issue 18 §4: a model file
    /// with ξ < 0, an input scale of 0 or `y_std = 1e308` predicted NaN or
    /// constants). Shapes are checked by the caller; ξ, ν, σ² and
    /// finiteness by [`KrigingModel`]'s own loader.
    fn check_values(&self) -> std::result::Result<(), String> {
        use crate::dataset::{MAX_ABS_ERROR_MM, MAX_ABS_JOINT};
        if self.n_joints == 0 {
            return Err("n_joints is 0".into());
        }
        self.input_norm
            .validate(crate::dataset::MAX_ABS_COVARIATE)
            .map_err(|why| format!("input_norm: {why}"))?;
        if !self.joint_range.is_empty() && self.joint_range.len() != self.n_joints {
            return Err(format!(
                "joint_range has {} entries for {} joints",
                self.joint_range.len(),
                self.n_joints
            ));
        }
        for (j, &(lo, hi)) in self.joint_range.iter().enumerate() {
            if !(lo.abs() <= MAX_ABS_JOINT && hi.abs() <= MAX_ABS_JOINT && lo <= hi) {
                return Err(format!("joint_range[{j}] = ({lo}, {hi}) is not a range"));
            }
        }
        for (axis, o) in AXES.iter().zip(&self.outputs) {
            let (mean, scale) = o.output_scale();
            if mean.is_nan() || mean.abs() > MAX_ABS_ERROR_MM {
                return Err(format!(
                    "output {axis}: y_mean = {mean:e} mm is not a TCP error"
                ));
            }
            if !(scale > 0.0 && scale <= 2.0 * MAX_ABS_ERROR_MM) {
                return Err(format!(
                    "output {axis}: y_std = {scale:e} mm is not a scale of TCP errors"
                ));
            }
            if o.data.x_train.iter().flatten().any(|v| v.abs() > 1e6) {
                return Err(format!(
                    "output {axis}: a normalised training input is beyond ±1e6"
                ));
            }
        }
        self.options.validate().map_err(|e| format!("options: {e}"))
    }

    /// Read a model saved by [`ErrorModel::save`], checking format and version.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        Self::from_json(&text, &path.display().to_string())
    }

    /// Parse a saved model from JSON text (`source_name` for messages).
    pub fn from_json(text: &str, source_name: &str) -> Result<Self> {
        let head: serde_json::Value = serde_json::from_str(text).map_err(|e| Error::Json {
            context: source_name.into(),
            source: e,
        })?;
        let format = head.get("format").and_then(|v| v.as_str()).unwrap_or("");
        let version = head.get("version").and_then(|v| v.as_u64()).unwrap_or(0);
        let known = u64::from(MODEL_VERSION_MIN)..=u64::from(MODEL_VERSION);
        if format != MODEL_FORMAT || !known.contains(&version) {
            return Err(Error::Input {
                source_name: source_name.into(),
                message: format!(
                    "not a robokrige error model of version {MODEL_VERSION_MIN}–{MODEL_VERSION} (found format '{format}', version {version}); refit it with this version"
                ),
            });
        }
        let mut model: ErrorModel = serde_json::from_value(head).map_err(|e| Error::Json {
            context: source_name.into(),
            source: e,
        })?;
        let dim = model
            .space
            .encoded_dim(model.n_joints, &model.options.periodic)
            + model.extras.iter().map(|f| f.names().len()).sum::<usize>();
        let extras_ok = model
            .extras
            .iter()
            .all(|f| f.validate(model.n_joints).is_ok());
        if model.outputs.len() != 3
            || model.input_norm.mean.len() != dim
            || model.outputs.iter().any(|o| o.dim() != dim)
            || !extras_ok
        {
            return Err(Error::Input {
                source_name: source_name.into(),
                message: "model file is inconsistent (outputs or input dimension)".into(),
            });
        }
        model.check_values().map_err(|why| Error::Input {
            source_name: source_name.into(),
            message: format!("model file holds an impossible value: {why}"),
        })?;
        // held in memory (and saved again) in the current form
        model.version = MODEL_VERSION;
        Ok(model)
    }
}

/// Relative tolerance of the per-axis screen of kinematic trend columns
/// ([`kinematic_trends`]): a column is kept when its component orthogonal to
/// the columns kept before it has at least this share of its norm (the
/// column-scaled trend matrix then stays well conditioned: ≲ 10⁴ on the
/// campaigns of issue 16 §3, against 10⁷–10¹⁰ without the screen). A column
/// whose independent share is r has its β amplified ~1/r.
pub const KINEMATIC_AXIS_TOL: f64 = 1e-3;

/// Rows a kinematic trend column's new component must be spread over, on
/// its axis, to be kept ([`crate::kriging::supported_columns`]): the rule of
/// thumb of ten observations per coefficient.
pub const KINEMATIC_MIN_SUPPORT: f64 = 10.0;

/// Share of a parameter's 3-axis Jacobian norm below which one axis's
/// column counts as zero: the parameter does not move that axis, and what
/// the finite differences give is rounding noise (e.g. `dPz/dtheta_off1`,
/// ~1e-9 against ~10 on x and y).
pub const KINEMATIC_ZERO_TOL: f64 = 1e-6;

/// The per-axis trends of [`ErrorModel::fit_kinematic`]: the options'
/// monomials plus, for output axis `a`, the identification-Jacobian rows
/// `∂P_a/∂p_j` of the calibration parameters that are
///
/// 1. identifiable on `data` as a whole (greedy rank revelation of the
///    stacked, column-normalised `3m × (5n + 9)` Jacobian, relative
///    tolerance `1e-7`; earlier parameters win),
/// 2. seen by axis `a` (its column is more than [`KINEMATIC_ZERO_TOL`] of
///    the stacked column, not finite-difference noise), and
/// 3. independent of the monomials and the earlier parameters *on this axis
///    alone*: greedy rank revelation of the axis's own trend matrix with
///    relative tolerance [`KINEMATIC_AXIS_TOL`].
///
/// Each output's GLS sees only its own axis, and a set of columns that is
/// well conditioned when the three axes are stacked can be nearly dependent
/// on one axis (e.g. `dPy/dd6` ≈ the constant when the wrist axis keeps its
/// direction over the campaign). Kept, such columns get opposite β of
/// 10⁴–10⁷ mm that cancel on the training poses only: a held-out pose where
/// they do not cancel (the home pose of a campaign whose tool points one
/// way) is predicted millimetres to metres off. Likewise a column that is
/// rounding noise on the training poses but not zero elsewhere.
pub fn kinematic_trends(
    data: &Dataset,
    space: Space,
    opts: &KrigingOptions,
    robot: &crate::kinematics::Robot,
) -> Result<[crate::kriging::Trend; 3]> {
    kinematic_trend_set(data, space, opts, robot, Some(KINEMATIC_AXIS_TOL))
}

/// The kinematic *candidates* of the basis selections (PCC + PCA, GA): as
/// [`kinematic_trends`] without the per-axis independence screen (step 3),
/// which the selections do themselves (PCA fusion, the GA's own screen).
pub fn kinematic_candidates(
    data: &Dataset,
    space: Space,
    opts: &KrigingOptions,
    robot: &crate::kinematics::Robot,
) -> Result<[crate::kriging::Trend; 3]> {
    kinematic_trend_set(data, space, opts, robot, None)
}

fn kinematic_trend_set(
    data: &Dataset,
    space: Space,
    opts: &KrigingOptions,
    robot: &crate::kinematics::Robot,
    axis_tol: Option<f64>,
) -> Result<[crate::kriging::Trend; 3]> {
    use crate::kinematics::{calib_len, identification_jacobian};
    use crate::kriging::{independent_columns, supported_columns};
    let n = data.n_joints();
    robot.check_dataset(data)?;
    let np = calib_len(n);
    let m = data.len();
    let rows: Vec<[Vec<f64>; 3]> = data
        .q
        .par_iter()
        .map(|q| identification_jacobian(robot, q))
        .collect();
    let mut f = faer::Mat::<f64>::zeros(3 * m, np);
    for (i, r) in rows.iter().enumerate() {
        for a in 0..3 {
            for k in 0..np {
                f[(3 * i + a, k)] = r[a][k];
            }
        }
    }
    let (kept, _) = independent_columns(&f, 1e-7);
    let (map, x) = InputMap::fit(data, space, &opts.periodic, &[])?;
    let norm = map.normalizer();
    let d = map.dim();
    let nj = d - space.dim(n) + n; // joint columns
    let poly = opts.trend.monomials(d);
    let norm2 = |a: Option<usize>, k: usize| -> f64 {
        let axes = a.map_or(0..3, |a| a..a + 1);
        rows.iter()
            .map(|r| axes.clone().map(|b| r[b][k] * r[b][k]).sum::<f64>())
            .sum()
    };
    // the monomial columns of every axis's trend matrix
    let fp = axis_tol.map(|_| crate::kriging::trend_matrix(&poly, &x));
    let axis_params = |a: usize| -> Vec<usize> {
        let seen: Vec<usize> = kept
            .iter()
            .copied()
            .filter(|&k| norm2(Some(a), k) > KINEMATIC_ZERO_TOL.powi(2) * norm2(None, k))
            .collect();
        let (Some(tol), Some(fp)) = (axis_tol, &fp) else {
            return seen;
        };
        // the axis's trend matrix: monomials of the normalised inputs, then
        // the Jacobian rows; monomials and earlier parameters win
        let np0 = poly.exponents.len();
        let mut fa = faer::Mat::<f64>::zeros(m, np0 + seen.len());
        for i in 0..m {
            for j in 0..np0 {
                fa[(i, j)] = fp[(i, j)];
            }
            for (c, &k) in seen.iter().enumerate() {
                fa[(i, np0 + c)] = rows[i][a][k];
            }
        }
        let (cols, _) = supported_columns(&fa, tol, KINEMATIC_MIN_SUPPORT);
        cols.iter()
            .filter(|&&j| j >= np0)
            .map(|&j| seen[j - np0])
            .collect()
    };
    let make = |axis: usize| {
        crate::kriging::Trend::Kinematic(Box::new(crate::kriging::KinematicTrend {
            robot: robot.clone(),
            axis,
            params: axis_params(axis),
            joint_mean: norm.mean[..nj].to_vec(),
            joint_std: norm.std[..nj].to_vec(),
            periodic: opts.periodic.clone(),
            poly: poly.clone(),
        }))
    };
    Ok([make(0), make(1), make(2)])
}

impl crate::predictor::ErrorPredictor for ErrorModel {
    fn n_joints(&self) -> usize {
        self.n_joints
    }
    fn predict_errors(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>> {
        self.predict_mean(q, dir)
    }
}
