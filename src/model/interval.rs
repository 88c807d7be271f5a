//! Predictive intervals calibrated on the model's own leave-one-out
//! residuals.
//!
//! A Gaussian process fitted by maximum likelihood states its uncertainty
//! through σ², and σ² is only as right as the Gaussian assumption: on a
//! real campaign a few gross residuals inflate it, and the intervals of
//! every other pose become too wide (series B of the UR10: 0.97–0.985 of
//! held-out rows inside a "95 %" interval). Bachoc (2013, "Cross
//! validation and maximum likelihood estimations of hyper-parameters of
//! Gaussian processes with model misspecification", CSDA 66) estimates σ²
//! from the leave-one-out residuals instead; the same idea with the
//! quantile in place of the mean square is the jackknife interval of
//! conformal prediction (Barber, Candès, Ramdas & Tibshirani 2021,
//! "Predictive inference with the jackknife+", Ann. Statist. 49).
//!
//! Per output, with the closed-form LOO residual `e_i` and its variance
//! `v_i = σ²/B_ii` ([`crate::kriging::HeldOut`]) at [`LOO_SAMPLE`]
//! training rows spread over the campaign:
//!
//! ```text
//! c = q_0.95(|e_i| / √v_i) / 1.96
//! ```
//!
//! and every standard deviation the model states for its Kriging part (the
//! √MSE of the mean and the noise of a new measurement) is multiplied by
//! `c`: 95 % of the leave-one-out residuals fall inside the model's 95 %
//! interval. `c` is a function of the fitted model alone (no file field);
//! it is computed on the first request and kept.

use super::{ErrorModel, LOO_SAMPLE, Z95};
use crate::Result;
use std::sync::OnceLock;

/// What the leave-one-out residuals of a fitted model say about its
/// stated uncertainty, per output axis.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LooCheck {
    /// The factor `c` on the model's standard deviations (module docs).
    pub interval_scale: [f64; 3],
    /// The RMS of the leave-one-out residuals, mm.
    pub loo_rmse: [f64; 3],
    /// The model's own expectation of it before the scale,
    /// [`crate::kriging::HeldOut::expected_loo_rmse`], mm.
    pub expected_loo_rmse: [f64; 3],
    /// Training rows the residuals were taken at.
    pub rows: usize,
}

/// The [`LooCheck`] of a model, computed once (it is a function of the
/// fitted model, not a saved field): equal for any two models, as the
/// models' own fields decide.
#[derive(Debug, Clone, Default)]
pub(crate) struct LooCache(OnceLock<std::result::Result<LooCheck, String>>);

impl PartialEq for LooCache {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// The training rows of the leave-one-out sample: up to [`LOO_SAMPLE`] of
/// `m`, evenly over the campaign.
fn sample(m: usize) -> Vec<Vec<usize>> {
    let n = m.min(LOO_SAMPLE);
    (0..n).map(|i| vec![i * m / n]).collect()
}

/// `c` of one output from its residuals and their variances (NaN where not
/// held out): the 95 % quantile of the standardised residuals over
/// [`Z95`]; 1 when there are none or they are degenerate.
fn scale_of(residuals: &[f64], variances: &[f64]) -> f64 {
    let mut z: Vec<f64> = residuals
        .iter()
        .zip(variances)
        .filter(|(r, v)| r.is_finite() && **v > 0.0)
        .map(|(r, v)| r.abs() / v.sqrt())
        .collect();
    if z.is_empty() {
        return 1.0;
    }
    z.sort_by(f64::total_cmp);
    // the smallest value with at least 95 % of the sample at or below it
    let k = ((0.95 * z.len() as f64).ceil() as usize).clamp(1, z.len()) - 1;
    let c = z[k] / Z95;
    if c.is_finite() && c > 0.0 { c } else { 1.0 }
}

impl ErrorModel {
    /// The leave-one-out check of this model's intervals ([`LooCheck`]),
    /// computed on the first call and kept.
    pub fn loo_check(&self) -> Result<LooCheck> {
        let got = self.loo.0.get_or_init(|| {
            let blocks = sample(self.n_train());
            let mut out = LooCheck {
                interval_scale: [1.0; 3],
                loo_rmse: [0.0; 3],
                expected_loo_rmse: [0.0; 3],
                rows: blocks.len(),
            };
            for (a, k) in self.outputs.iter().enumerate() {
                let h = k.held_out(&blocks).map_err(|e| e.to_string())?;
                let held: Vec<f64> = h
                    .residuals
                    .iter()
                    .copied()
                    .filter(|r| r.is_finite())
                    .collect();
                out.loo_rmse[a] =
                    (held.iter().map(|r| r * r).sum::<f64>() / held.len().max(1) as f64).sqrt();
                out.expected_loo_rmse[a] = h.expected_loo_rmse;
                out.interval_scale[a] = scale_of(&h.residuals, &h.variances);
            }
            Ok(out)
        });
        got.clone().map_err(crate::Error::Numerical)
    }

    /// The factor on each output's stated standard deviations
    /// ([`LooCheck::interval_scale`]).
    pub fn interval_scale(&self) -> Result<[f64; 3]> {
        self.loo_check().map(|c| c.interval_scale)
    }

    /// The standard deviation of the measurement noise per axis that a
    /// predicted standard deviation is combined with, in quadrature, for
    /// a new measurement's: [`ErrorModel::noise_std`] (the nugget's) times
    /// the [`interval_scale`](Self::interval_scale), mm.
    pub fn predictive_noise_std(&self) -> Result<[f64; 3]> {
        let c = self.interval_scale()?;
        let n = self.noise_std();
        Ok(std::array::from_fn(|a| n[a] * c[a]))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn scale_puts_95_percent_of_the_standardised_residuals_inside() {
        // 100 residuals with unit variance: |z| = 0.02, 0.04, …, 2.0
        let r: Vec<f64> = (1..=100).map(|i| 0.02 * i as f64).collect();
        let v = vec![1.0; 100];
        let c = scale_of(&r, &v);
        assert!((c * Z95 - 1.9).abs() < 1e-12, "{c}");
        // variance 4 halves the standardised residuals
        let c4 = scale_of(&r, &[4.0; 100]);
        assert!((c4 - c / 2.0).abs() < 1e-12);
        // NaN rows (not held out) are skipped, none at all gives 1
        let mut rn = r.clone();
        rn.push(f64::NAN);
        assert_eq!(scale_of(&rn, &[1.0; 101]), c);
        assert_eq!(scale_of(&[f64::NAN], &[1.0]), 1.0);
    }

    #[test]
    fn sample_spreads_over_the_campaign() {
        assert_eq!(sample(3), vec![vec![0], vec![1], vec![2]]);
        let s = sample(1000);
        assert_eq!(s.len(), LOO_SAMPLE);
        assert_eq!(
            s[LOO_SAMPLE - 1],
            vec![(LOO_SAMPLE - 1) * 1000 / LOO_SAMPLE]
        );
    }
}
