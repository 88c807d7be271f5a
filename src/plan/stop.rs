//! When to stop measuring: the held-out error forecast as a function of the
//! number of poses.
//!
//! Two measurements of the same model meet here. The planner's curve
//! `IMSE(m + k)` ([`super::Plan::imse_curve`]) is the model's own MSE of
//! the latent error over the region, after k more planned poses; a
//! closed-form 10-fold CV of the fitted model gives the held-out error *now*
//! (`RMS_cv`, 3D, which includes the measurement noise). The forecast
//!
//! ```text
//! RMS(m + k) = √(a · IMSE(m + k) + ν²),   a = (RMS_cv² − ν²) / IMSE(m)
//! ```
//!
//! (ν²: the model's noise variance summed over x, y, z, the repeatability
//! floor) scales the model's MSE so that it meets the CV error at the
//! campaign measured, and falls with the planned poses as the MSE does; the
//! mean 3D error is that RMS times the ratio mean/RMS of the CV residuals.
//! A target below the floor `√ν²·ratio` is unreachable by more poses.

use super::{HyperSource, Plan};
use crate::cv::cross_validate_closed_form;
use crate::dataset::Dataset;
use crate::model::ErrorModel;
use crate::{Error, Result};

/// Folds of the CV that anchors the forecast.
pub const FORECAST_FOLDS: usize = 10;

/// The forecast of the held-out mean 3D error with the number of poses.
#[derive(Debug, Clone, PartialEq)]
pub struct Forecast {
    /// Poses measured when the forecast was made.
    pub measured: usize,
    /// Closed-form CV mean 3D error at `measured`, mm.
    pub cv_mean_3d: f64,
    /// The repeatability floor: the mean 3D error with infinitely many
    /// poses (the model's noise), mm.
    pub floor_mean_3d: f64,
    /// Forecast mean 3D error after `k` more planned poses (`k` = 0, 1, …,
    /// the plan's length), mm.
    pub mean_3d: Vec<f64>,
}

/// What the forecast says of a target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// Already met by the campaign measured.
    Met,
    /// Met after this many more poses of the plan.
    After(usize),
    /// Not within the plan's poses, though above the floor: plan more.
    BeyondPlan,
    /// Below the repeatability floor: no number of poses reaches it.
    Unreachable,
}

impl Forecast {
    /// The forecast for `model`, fitted on exactly the rows of `campaign`,
    /// and the planner's `imse_curve` (mm², from that campaign on).
    pub fn new(model: &ErrorModel, campaign: &Dataset, imse_curve: &[f64]) -> Result<Self> {
        let Some(&imse0) = imse_curve.first() else {
            return Err(Error::InvalidParameter(
                "a forecast needs the planner's IMSE curve (a plan by the model)".into(),
            ));
        };
        let (rms, ratio) = cv_error(model, campaign)?;
        let noise2: f64 = model.noise_std().iter().map(|s| s * s).sum();
        let a = ((rms * rms - noise2) / imse0.max(f64::MIN_POSITIVE)).max(0.0);
        let mean_3d = imse_curve
            .iter()
            .map(|i| (a * i + noise2).sqrt() * ratio)
            .collect();
        Ok(Forecast {
            measured: campaign.len(),
            cv_mean_3d: rms * ratio,
            floor_mean_3d: noise2.sqrt() * ratio,
            mean_3d,
        })
    }

    /// The forecast of `plan` when its hyperparameters were re-estimated on
    /// `campaign` ([`Forecast::new`] with the plan's model and IMSE curve);
    /// `None` otherwise.
    pub fn of_plan(plan: &Plan, campaign: Option<&Dataset>) -> Result<Option<Self>> {
        match (&plan.model, plan.source, campaign) {
            (Some(m), HyperSource::Campaign, Some(c)) => {
                Forecast::new(m, c, &plan.imse_curve).map(Some)
            }
            _ => Ok(None),
        }
    }

    /// When the target mean 3D error `target_mm` is met.
    pub fn verdict(&self, target_mm: f64) -> Verdict {
        if self.cv_mean_3d <= target_mm {
            return Verdict::Met;
        }
        if let Some(k) = self.mean_3d.iter().position(|e| *e <= target_mm) {
            return Verdict::After(k);
        }
        if target_mm <= self.floor_mean_3d {
            Verdict::Unreachable
        } else {
            Verdict::BeyondPlan
        }
    }
}

/// The closed-form 10-fold CV ([`cross_validate_closed_form`]: the Kriging
/// parts' residuals with ξ, ν and the calibration held, β re-estimated per
/// fold) of `model` on its campaign: the RMS 3D error and the ratio of the
/// mean 3D error to it.
fn cv_error(model: &ErrorModel, campaign: &Dataset) -> Result<(f64, f64)> {
    let k = FORECAST_FOLDS.min(campaign.len());
    let s = cross_validate_closed_form(campaign, model, k, 1)?.summary;
    let rms = s.rms_mm.iter().map(|r| r * r).sum::<f64>().sqrt();
    Ok((rms, if rms > 0.0 { s.mean_3d_mm / rms } else { 1.0 }))
}
