//! When to stop measuring: the held-out error forecast as a function of the
//! number of poses.
//!
//! Two measurements of the same model meet here. The planner's curve
//! `IMSE(m + k)` ([`super::Plan::imse_curve`]) is the model's own MSE of
//! the latent error over the region, after k more planned poses; a 10-fold
//! CV of the fitted model gives the held-out error *now* (`RMS_cv`, 3D,
//! which includes the measurement noise ν², summed over x, y, z).
//!
//! - **The CV.** Up to [`FULL_REFIT_ROWS`] rows every training fold is
//!   fitted as the model was: the calibration identified and ξ, ν searched
//!   anew. Above, a calibrated model's folds re-identify the calibration
//!   and refit the Kriging outputs at the model's ξ and ν
//!   ([`ErrorModel::refit`]), and a model without one is CV'd in closed
//!   form. What a fold holds has seen the held-out rows: on 50 to 400
//!   random poses of the UR10 series C, a CV holding the calibration and ξ
//!   was 6–59 % below the error on the poses not measured; on simulated
//!   UR10 campaigns of 60 poses it was 20–43 % below, and 9–35 % below with
//!   only ξ held.
//! - **Where the CV is measured.** The CV's error is the error at the
//!   campaign's own poses, each predicted from the other folds; the target
//!   is the error over the region. A planned campaign puts its poses where
//!   the model knew least, so its held-out poses are harder than the
//!   region's: the CV of a planned campaign was 1.27–1.58× the error on
//!   the pool's other poses on series B, 1.09–1.18× on series C. The model states both, in the units
//!   of the planner's IMSE: `MSE_cv`, its latent MSE at each held-out row —
//!   the Kriging outputs' from the row's fold complement (the diagonal of
//!   the closed-form `σ² B_II⁻¹` of the same folds, less the noise; it
//!   counts the trend coefficients' uncertainty, which the IMSE leaves
//!   out, so a model with many trend terms reads a little optimistic) plus, when the plan
//!   counts it, the calibration's share at the row (`tr(G Σ_f Gᵀ)`, the
//!   parameters' posterior without the row's fold, by a Woodbury downdate)
//!   — and `IMSE(m)` over the region.
//!
//! The forecast
//!
//! ```text
//! RMS(m + k) = √(a · IMSE(m + k) + ν²),   a = (RMS_cv² − ν²) / MSE_cv
//! ```
//!
//! scales the model's stated MSE by how far the CV's error exceeds it where
//! both are measured, carries that to the region, and falls with the
//! planned poses as the model's MSE does; the mean 3D error is that RMS
//! times the ratio mean/RMS of the CV residuals. A target below the floor
//! `√ν²·ratio` is unreachable by more poses.

use super::{HyperSource, Plan};
use crate::cancel::Cancel;
use crate::cv::cross_validate_folds;
use crate::dataset::Dataset;
use crate::kinematics::Robot;
use crate::kriging::HeldOut;
use crate::methods::default_params;
use crate::model::ErrorModel;
use crate::{Error, Result};

/// Folds of the CV that anchors the forecast.
pub const FORECAST_FOLDS: usize = 10;

/// Seed of the forecast's fold partition.
const FOLD_SEED: u64 = 1;

/// Up to this many measured rows the forecast's CV searches ξ and ν again
/// in every fold; above, it holds them (the cost of a fold's search grows
/// as m³, and the optimism of held hyperparameters shrinks with m).
pub const FULL_REFIT_ROWS: usize = 200;

/// A noise (3D RMS) at most this share of the CV's RMS error is one the
/// model did not measure: a laser tracker's repeatability is a visible
/// share of what a model leaves, and a nugget search that ends at the
/// bottom of its box says nothing of it (60 simulated UR10 poses: nuggets
/// 1e-8, 4e-7 and 1e-8, a floor of 0.0000 mm at a CV error of 0.12 mm,
/// against a simulated noise of 0.016 mm per axis).
pub const UNMEASURED_FLOOR: f64 = 0.01;

/// The forecast of the held-out mean 3D error with the number of poses.
#[derive(Debug, Clone, PartialEq)]
pub struct Forecast {
    /// Poses measured when the forecast was made.
    pub measured: usize,
    /// CV mean 3D error at `measured`, mm: the error at the campaign's
    /// own poses, each held out.
    pub cv_mean_3d: f64,
    /// `ρ = IMSE(m) / MSE_cv`: the model's MSE over the region over its
    /// held-out MSE at the campaign's poses, which carries the CV to the
    /// region (below 1 when the held-out poses are harder than the
    /// region's).
    pub region_ratio: f64,
    /// The repeatability floor: the mean 3D error with infinitely many
    /// poses (the model's noise), mm.
    pub floor_mean_3d: f64,
    /// Whether the model measured its noise: false when its noise is at
    /// most [`UNMEASURED_FLOOR`] of the CV's RMS error (the nuggets at the
    /// bottom of their search: the model interpolates its measurements),
    /// so that the floor reads about 0 without saying anything of the
    /// robot's repeatability.
    pub floor_identified: bool,
    /// Forecast mean 3D error after `k` more planned poses (`k` = 0, 1, …,
    /// the plan's length), mm.
    pub mean_3d: Vec<f64>,
}

/// What the forecast says of a target.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Verdict {
    /// Already met: the estimate over the region now is at or below it.
    Met,
    /// Met after this many more poses of the plan.
    After(usize),
    /// Not within the plan's poses, though above the floor: plan more.
    BeyondPlan,
    /// Below the repeatability floor: no number of poses reaches it.
    Unreachable,
}

impl Forecast {
    /// The forecast of `plan` for `robot`, whose hyperparameters were
    /// estimated on exactly the rows of `campaign`: its model and IMSE
    /// curve. The CV's fits stop at `cancel`.
    pub fn new(plan: &Plan, robot: &Robot, campaign: &Dataset, cancel: &Cancel) -> Result<Self> {
        let (Some(model), Some(&imse0)) = (&plan.model, plan.imse_curve.first()) else {
            return Err(Error::InvalidParameter(
                "a forecast needs the planner's IMSE curve (a plan by the model)".into(),
            ));
        };
        let fitted_on = model.outputs.first().map(|o| &o.data.x_train);
        if fitted_on != Some(&model.input_map().encode_dataset(campaign)?) {
            return Err(Error::InvalidParameter(format!(
                "a forecast needs the plan's model fitted on exactly the {} rows of the campaign",
                campaign.len()
            )));
        }
        // one partition for the CV and the model's held-out MSE
        let k = FORECAST_FOLDS.min(campaign.len());
        let fold = crate::stats::kfold_partition(campaign.len(), k, FOLD_SEED)?;
        let blocks = crate::stats::fold_blocks(&fold);
        // each output's closed-form held-out residuals and variances on
        // those folds, once: the MSE below, and the closed-form CV
        let held: Vec<HeldOut> = model
            .outputs
            .iter()
            .map(|o| o.held_out(&blocks))
            .collect::<Result<_>>()?;
        let (rms, ratio) = cv_error(model, robot, campaign, (&fold, &held), cancel)?;
        let noise2: f64 = model.noise_std().iter().map(|s| s * s).sum();
        let share = match model.calibration() {
            Some(c) if plan.imse_counts_calibration => {
                super::calibration::held_out_variance(c, &super::PoseSet::from(campaign), &blocks)?
            }
            _ => 0.0,
        };
        let held_mse = held_out_mse(model, &held) + share;
        // a model with no latent variance at its rows says nothing of where
        // they are: the CV then stands for the region as it is
        let mse_cv = if held_mse > 0.0 { held_mse } else { imse0 };
        let a = ((rms * rms - noise2) / mse_cv.max(f64::MIN_POSITIVE)).max(0.0);
        let mean_3d = plan
            .imse_curve
            .iter()
            .map(|i| (a * i + noise2).sqrt() * ratio)
            .collect();
        Ok(Forecast {
            measured: campaign.len(),
            cv_mean_3d: rms * ratio,
            region_ratio: if mse_cv > 0.0 { imse0 / mse_cv } else { 1.0 },
            floor_mean_3d: noise2.sqrt() * ratio,
            floor_identified: noise2.sqrt() > UNMEASURED_FLOOR * rms,
            mean_3d,
        })
    }

    /// The forecast of `plan` when its hyperparameters were re-estimated on
    /// `campaign` ([`Forecast::new`]); `None` otherwise. A forecast that
    /// fails (a fold whose calibration cannot be identified) leaves the
    /// plan as it is, with a note saying why there is no forecast; only an
    /// interruption is an error.
    pub fn of_plan(
        plan: &mut Plan,
        robot: &Robot,
        campaign: Option<&Dataset>,
        cancel: &Cancel,
    ) -> Result<Option<Self>> {
        let c = match (plan.source, campaign) {
            (HyperSource::Campaign, Some(c)) if plan.model.is_some() => c,
            _ => return Ok(None),
        };
        match Forecast::new(plan, robot, c, cancel) {
            Ok(f) => Ok(Some(f)),
            Err(e) if e.is_interrupted() => Err(e),
            Err(e) => {
                plan.notes.push(format!("no forecast: {e}"));
                Ok(None)
            }
        }
    }

    /// The forecast over the region with the campaign measured now
    /// (`mean_3d[0]`), mm.
    pub fn now_mean_3d(&self) -> f64 {
        self.mean_3d.first().copied().unwrap_or(self.cv_mean_3d)
    }

    /// When the target mean 3D error `target_mm` is met (over the region).
    pub fn verdict(&self, target_mm: f64) -> Verdict {
        if self.now_mean_3d() <= target_mm {
            return Verdict::Met;
        }
        if let Some(k) = self.mean_3d.iter().position(|e| *e <= target_mm) {
            return Verdict::After(k);
        }
        if self.floor_identified && target_mm <= self.floor_mean_3d {
            Verdict::Unreachable
        } else {
            Verdict::BeyondPlan
        }
    }
}

/// The 10-fold CV of `model` (fitted by [`default_params`] of `robot` on
/// `campaign`, as the planner fits it) that anchors the forecast: the RMS
/// 3D error and the ratio of the mean 3D error to it.
/// - Up to [`FULL_REFIT_ROWS`] rows every training fold is fitted as the
///   model was, ξ and ν searched anew. (Not warm-started from the model's
///   own: a search from there stops in the basin the held-out rows helped
///   shape, and on simulated UR10 campaigns of 60 poses that CV was 14–19 %
///   below the cold one.)
/// - Above, a calibrated model's folds re-identify the calibration and
///   refit the Kriging outputs at the model's ξ and ν
///   ([`ErrorModel::refit`]); a model without one is CV'd in closed form:
///   the outputs' `held` residuals on the same folds (ξ and ν held, β
///   re-estimated per fold, as [`crate::cv::cross_validate_closed_form`]).
///
/// `fold[i]` is row i's fold; `held[a]` output a's held-out residuals and
/// variances on those folds.
fn cv_error(
    model: &ErrorModel,
    robot: &Robot,
    campaign: &Dataset,
    (fold, held): (&[usize], &[HeldOut]),
    cancel: &Cancel,
) -> Result<(f64, f64)> {
    let s = if campaign.len() <= FULL_REFIT_ROWS {
        let params = default_params(robot, campaign)?
            .cancel(cancel.clone())
            .check()?;
        cross_validate_folds(campaign, fold, |train| params.fit(train))?.summary
    } else if model.calibration().is_some() {
        cross_validate_folds(campaign, fold, |train| {
            cancel.check()?;
            model.refit(train)
        })?
        .summary
    } else {
        let residuals: Vec<[f64; 3]> = (0..campaign.len())
            .map(|i| std::array::from_fn(|a| held.get(a).map_or(0.0, |h| h.residuals[i])))
            .collect();
        crate::stats::summarize(&residuals)
    };
    let rms = s.rms_mm.iter().map(|r| r * r).sum::<f64>().sqrt();
    Ok((rms, if rms > 0.0 { s.mean_3d_mm / rms } else { 1.0 }))
}

/// The Kriging outputs' share of `MSE_cv`: their latent MSE at the
/// campaign's rows, each predicted from the rows outside its block of the
/// forecast's CV (`held`: the diagonal of the closed-form `σ² B_II⁻¹` at
/// the model's hyperparameters, [`HeldOut::variances`], less the noise),
/// summed over the outputs and averaged over the rows, mm².
fn held_out_mse(model: &ErrorModel, held: &[HeldOut]) -> f64 {
    held.iter()
        .zip(model.noise_std())
        .map(|(h, s)| {
            let v = &h.variances;
            v.iter().map(|v| (v - s * s).max(0.0)).sum::<f64>() / v.len().max(1) as f64
        })
        .sum()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::cv::cross_validate_closed_form;
    use crate::params::ErrorModelParams;

    /// Above [`FULL_REFIT_ROWS`] a model without a calibration is CV'd from
    /// the held-out residuals the forecast computes anyway: the same
    /// figures as the closed-form CV on the same partition.
    #[test]
    fn the_closed_form_anchor_is_the_closed_form_cv() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
        let data = crate::dataset::read_csv(path.as_ref()).unwrap();
        assert!(data.len() > FULL_REFIT_ROWS);
        let robot = crate::kinematics::load_robot("comau-nj220").unwrap();
        let model = ErrorModelParams::new()
            .kriging(crate::kriging::KrigingOptions::default().starts(1))
            .check()
            .unwrap()
            .fit(&data)
            .unwrap();
        assert!(model.calibration().is_none());
        let fold = crate::stats::kfold_partition(data.len(), FORECAST_FOLDS, FOLD_SEED).unwrap();
        let blocks = crate::stats::fold_blocks(&fold);
        let held: Vec<HeldOut> = model
            .outputs
            .iter()
            .map(|o| o.held_out(&blocks).unwrap())
            .collect();
        let (rms, ratio) = cv_error(&model, &robot, &data, (&fold, &held), &Cancel::new()).unwrap();
        let s = cross_validate_closed_form(&data, &model, FORECAST_FOLDS, FOLD_SEED)
            .unwrap()
            .summary;
        let want = s.rms_mm.iter().map(|r| r * r).sum::<f64>().sqrt();
        assert!((rms - want).abs() <= 1e-12 * want, "{rms} vs {want}");
        assert!((rms * ratio - s.mean_3d_mm).abs() <= 1e-12 * want);
        // and the outputs' held-out MSE is their latent variance there
        assert!(held_out_mse(&model, &held) > 0.0);
    }

    /// Below a measured floor a target is unreachable; below a floor the
    /// model did not measure (about 0), it is only beyond the plan.
    #[test]
    fn only_a_measured_floor_makes_a_target_unreachable() {
        let f = |floor_identified| Forecast {
            measured: 100,
            cv_mean_3d: 0.2,
            region_ratio: 1.0,
            floor_mean_3d: 0.05,
            floor_identified,
            mean_3d: vec![0.2, 0.15, 0.12],
        };
        assert_eq!(f(true).verdict(0.25), Verdict::Met);
        assert_eq!(f(true).verdict(0.15), Verdict::After(1));
        assert_eq!(f(true).verdict(0.08), Verdict::BeyondPlan);
        assert_eq!(f(true).verdict(0.04), Verdict::Unreachable);
        assert_eq!(f(false).verdict(0.04), Verdict::BeyondPlan);
    }
}
