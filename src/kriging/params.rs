//! One output's fit, in linfa's shape: [`KrigingParams`] (trend, options
//! with the correlation choice, [`Tuning`]) → [`KrigingParams::check`] →
//! [`ValidKrigingParams::fit`]`(x, y)`.
//!
//! Every single-output fit of the crate goes through here: the search of
//! ξ (and ν) by minimising ln ψ (seed 003 eq 14), a local search from a
//! warm start, and the solve at given hyperparameters (CV folds, refits,
//! the GA's fitness), each with a fixed family or the family chosen by CV.
//!
//! With `R = R(ξ) + νI` (correlation family of the options, eq 8 for the
//! Gaussian), trend matrix `F` and response `y` z-scored:
//!
//! ```text
//! β̂ = (FᵀR⁻¹F)⁻¹ FᵀR⁻¹y                      (eq 11, by Cholesky + QR)
//! σ̂² = (y − Fβ̂)ᵀ R⁻¹ (y − Fβ̂) / m            (eq 13)
//! ln ψ(ξ, ν) = ln|R| / m + ln σ̂²              (eq 14, minimised over log10 ξ, ν)
//! ŷ(s) = f(s)ᵀβ̂ + r(s)ᵀ R⁻¹ (y − Fβ̂)          (eq 10)
//! ```
//!
//! `kriging/problem.rs` holds those steps; `fit.rs` prepares the data and
//! runs the search; `family.rs` chooses the family.

use super::{CorrChoice, FitReport, KrigingModel, KrigingOptions, TrainingInputs, Trend};
use crate::{Error, Result};

/// Correlation hyperparameters of one output: ξ (one per correlation
/// input, ≥ 0) and the nugget ν (≥ 0), with the BFGS inverse Hessian there
/// (log10 ξ, log10 ν) when a fit left it — the curvature a warm start
/// begins with.
#[derive(Debug, Clone, PartialEq)]
pub struct Hyperparameters {
    pub(crate) theta: Vec<f64>,
    pub(crate) nugget: f64,
    pub(crate) inverse_hessian: Option<Vec<Vec<f64>>>,
}

impl Hyperparameters {
    /// ξ = `theta` and ν = `nugget`, without curvature.
    pub fn new(theta: Vec<f64>, nugget: f64) -> Self {
        Hyperparameters {
            theta,
            nugget,
            inverse_hessian: None,
        }
    }

    /// The hyperparameters a fit ended at (its first `corr_dims` ξ: the
    /// correlation inputs), with its curvature.
    pub fn of(report: &FitReport, corr_dims: usize) -> Self {
        Hyperparameters {
            theta: report.theta[..corr_dims.min(report.theta.len())].to_vec(),
            nugget: report.nugget,
            inverse_hessian: report.inverse_hessian.clone(),
        }
    }

    /// ξ, one per correlation input.
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// The nugget ν.
    pub fn nugget(&self) -> f64 {
        self.nugget
    }

    /// The BFGS inverse Hessian (log10 ξ, log10 ν), if known.
    pub fn inverse_hessian(&self) -> Option<&[Vec<f64>]> {
        self.inverse_hessian.as_deref()
    }

    fn validate(&self) -> Result<()> {
        if self.theta.iter().any(|t| !t.is_finite() || *t < 0.0)
            || self.nugget.is_nan()
            || self.nugget < 0.0
        {
            return Err(Error::InvalidParameter(
                "hyperparameters need finite ξ ≥ 0 and a nugget ≥ 0".into(),
            ));
        }
        Ok(())
    }
}

/// Where one output's hyperparameters come from.
#[derive(Debug, Clone, PartialEq, Default)]
#[non_exhaustive]
pub enum Tuning {
    /// Searched with the options' optimiser from its multistart (the
    /// default).
    #[default]
    Search,
    /// A local search from these: BFGS on the analytic gradient with the
    /// default optimiser (from their curvature when it is known),
    /// Hooke–Jeeves (initial step 0.25 in log10 units) with the papers'.
    /// For refits on data close to a fitted model's — CV folds, one more
    /// trend term — where the multistart would find the same basin at
    /// several times the cost (egobox's `theta_init`). ν is ignored without
    /// a nugget; values are clamped into the box.
    Warm(Hyperparameters),
    /// No search: solve at these (with the options' fixed family and least
    /// jitter; ν is used as given, nugget option or not).
    Fixed(Hyperparameters),
}

/// The parameters of one output's fit, set by builder methods.
#[derive(Debug, Clone, PartialEq)]
pub struct KrigingParams {
    trend: Trend,
    options: KrigingOptions,
    tuning: Tuning,
    corr_dims: Option<usize>,
    names: Option<Vec<String>>,
}

/// [`KrigingParams`] that passed [`KrigingParams::check`]: only these fit.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidKrigingParams(KrigingParams);

impl KrigingParams {
    /// A fit with the trend candidates `trend` (linearly dependent ones are
    /// dropped on the training rows), [`KrigingOptions::default`], the
    /// hyperparameters searched, every input a correlation input.
    pub fn new(trend: Trend) -> Self {
        KrigingParams {
            trend,
            options: KrigingOptions::default(),
            tuning: Tuning::Search,
            corr_dims: None,
            names: None,
        }
    }

    /// The options: correlation choice, optimiser, nugget, box, seed.
    pub fn options(mut self, options: KrigingOptions) -> Self {
        self.options = options;
        self
    }

    /// The correlation family, or its choice by CV (sets the options').
    pub fn corr(mut self, choice: impl Into<CorrChoice>) -> Self {
        self.options.corr = choice.into();
        self
    }

    /// Where the hyperparameters come from.
    pub fn tuning(mut self, tuning: Tuning) -> Self {
        self.tuning = tuning;
        self
    }

    /// Only the first `d` input columns enter the correlation; the others
    /// are *trend-only* inputs (a step or harmonic regressor) with ξ = 0,
    /// which enter `f(s)` but not `R`. All columns by default.
    pub fn correlation_inputs(mut self, d: usize) -> Self {
        self.corr_dims = Some(d);
        self
    }

    /// Names of the input columns, for the report's trend terms (`s1`, `s2`,
    /// … by default).
    pub fn names(mut self, names: Vec<String>) -> Self {
        self.names = Some(names);
        self
    }

    /// The trend candidates.
    pub fn get_trend(&self) -> &Trend {
        &self.trend
    }

    /// The options.
    pub fn get_options(&self) -> &KrigingOptions {
        &self.options
    }

    /// Where the hyperparameters come from.
    pub fn get_tuning(&self) -> &Tuning {
        &self.tuning
    }

    /// Check the options and the tuning, before any data.
    pub fn check(self) -> Result<ValidKrigingParams> {
        self.options.validate()?;
        match &self.tuning {
            Tuning::Search => {}
            Tuning::Warm(h) => h.validate()?,
            Tuning::Fixed(h) => {
                h.validate()?;
                if self.options.corr.is_by_cv() {
                    return Err(Error::InvalidParameter(
                        "fixed hyperparameters need a fixed correlation family, not its choice by CV"
                            .into(),
                    ));
                }
            }
        }
        Ok(ValidKrigingParams(self))
    }
}

impl ValidKrigingParams {
    /// The parameters.
    pub fn params(&self) -> &KrigingParams {
        &self.0
    }

    /// Fit one output: normalised inputs `x` (m rows), response `y` (m
    /// values, original units). The report says how: ξ, ν, ln ψ, the trend
    /// terms kept and dropped, the search's cost, and with
    /// [`CorrChoice::ByCv`] every family's score.
    pub fn fit(&self, x: &[Vec<f64>], y: &[f64]) -> Result<(KrigingModel, FitReport)> {
        let p = &self.0;
        let width = x.first().map_or(0, Vec::len);
        let d = p.corr_dims.unwrap_or(width);
        if d > width || x.iter().any(|r| r.len() != width) {
            return Err(Error::InvalidParameter(format!(
                "inputs of {width} columns cannot have {d} correlation inputs, and every row needs {width}"
            )));
        }
        let inputs = if d == width {
            TrainingInputs::new(x)
        } else {
            TrainingInputs::new(&x.iter().map(|r| r[..d].to_vec()).collect::<Vec<_>>())
        };
        let names = p
            .names
            .clone()
            .unwrap_or_else(|| (1..=width).map(|k| format!("s{k}")).collect());
        if names.len() != width {
            return Err(Error::InvalidParameter(format!(
                "{} input names for {width} input columns",
                names.len()
            )));
        }
        let job = super::fit::Job {
            x,
            inputs: &inputs,
            y,
            trend: &p.trend,
            names: &names,
            opts: &p.options,
        };
        let start = match &p.tuning {
            Tuning::Search => None,
            Tuning::Warm(h) => Some(h),
            // `check` refused fixed hyperparameters with the family by CV
            Tuning::Fixed(h) => return job.solve_at(p.options.corr.fixed().unwrap_or_default(), h),
        };
        match p.options.corr {
            CorrChoice::Fixed(corr) => job.search(corr, start),
            CorrChoice::ByCv { folds } => super::family::choose_by_cv(&job, folds, start),
        }
    }
}
