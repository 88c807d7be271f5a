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
//! **Where the data are sparse the error grows faster than the stated
//! variance.** The Gaussian process's MSE rises away from the data, but on
//! a real campaign the error rises faster: on the 2 773 poses of UR10
//! series C, the leave-one-out residuals standardised by their stated
//! standard deviation have an RMS of 0.94 over the half of the rows with
//! the smallest, and 1.32 over the 5 % with the largest, where 9 of the 10
//! gross residuals are. One factor for all poses then makes the intervals
//! too wide near the data and too narrow away from it. So the calibration
//! has two parameters: a power of the stated MSE as well as the scale.
//!
//! Per output `a`, at [`LOO_SAMPLE`] training rows spread over the
//! campaign, with the closed-form LOO residual `e_i`, its variance
//! `v_i = σ²/B_ii` ([`crate::kriging::HeldOut`]), the nugget's noise
//! variance `τ²` and the Kriging MSE of the held-out mean
//! `s_i = max(v_i − τ², 0)`:
//!
//! ```text
//! t_i² = τ² + s_i (s_i / μ)^κ          μ = median of s_i
//! κ    = argmax_κ Σ_a [ −½ Σ_i ln t_i² − (n/2) ln( (1/n) Σ_i e_i²/t_i² ) ]
//! c    = q_0.95(|e_i| / t_i) / 1.96
//! ```
//!
//! `κ`, one for the three outputs, maximises the Gaussian likelihood of the
//! residuals with the scale profiled out, on a grid over `[0, `[`POWER_MAX`]`]`
//! (0 is the plain scale; a negative power, intervals that narrow away
//! from the data, is not searched); `c`, per output, then puts 95 % of the
//! standardised residuals inside the 95 % interval, as the jackknife does.
//! The model's standard deviations are then `c √(s (s/μ)^κ)` for a mean
//! of MSE `s` ([`LooCheck::mean_std`]), with `s` held to the range of the
//! `s_i` inside the power (the power law is not extrapolated: far from the
//! data the standard deviation grows as `√s` again), and `c τ` for the
//! noise of a new measurement. They are functions of the fitted model alone (no file
//! field), computed on the first request and kept.

use super::{ErrorModel, LOO_SAMPLE, Z95};
use crate::Result;
use std::sync::OnceLock;

/// What the leave-one-out residuals of a fitted model say about its
/// stated uncertainty, per output axis.
#[derive(Debug, Clone, PartialEq)]
pub struct LooCheck {
    /// The factor `c` on the model's standard deviations (module docs).
    pub interval_scale: [f64; 3],
    /// The power `κ` of the stated MSE (module docs), one for the outputs.
    pub interval_power: f64,
    /// The reference `μ` of the power per output: the median Kriging MSE
    /// of the held-out means, mm² (0 when there is none).
    pub reference_mse: [f64; 3],
    /// The smallest and largest Kriging MSE of the held-out means per
    /// output, mm²: the range the power was fitted on, to which a stated
    /// MSE is held for its growth (the power is not extrapolated).
    pub mse_range: [[f64; 2]; 3],
    /// The RMS of the leave-one-out residuals, mm.
    pub loo_rmse: [f64; 3],
    /// The model's own expectation of it before the scale,
    /// [`crate::kriging::HeldOut::expected_loo_rmse`], mm.
    pub expected_loo_rmse: [f64; 3],
    /// Training rows the residuals were taken at.
    pub rows: usize,
    /// The leave-one-out residual per output at every training row, mm
    /// (NaN at a row outside the sample): what a check of one training row
    /// reads instead of solving for it again.
    pub residuals: [Vec<f64>; 3],
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

/// The largest power `κ` of the stated MSE searched (module docs).
pub const POWER_MAX: f64 = 3.0;
/// The step of the grid `κ` is searched on.
const POWER_STEP: f64 = 0.05;

/// One output's held-out rows as the calibration sees them: residual
/// `e_i`, Kriging MSE of the held-out mean `s_i`, the noise variance `τ²`
/// and the median `μ` of the `s_i`.
struct AxisSample {
    e: Vec<f64>,
    s: Vec<f64>,
    tau2: f64,
    mu: f64,
    /// The smallest and largest `s_i`.
    range: [f64; 2],
}

impl AxisSample {
    /// From the held-out residuals and their variances (NaN where not held
    /// out) and the noise variance `tau2`; rows whose variance is not
    /// positive are skipped.
    fn new(residuals: &[f64], variances: &[f64], tau2: f64) -> Self {
        let (e, s): (Vec<f64>, Vec<f64>) = residuals
            .iter()
            .zip(variances)
            .filter(|(r, v)| r.is_finite() && v.is_finite() && **v > 0.0)
            .map(|(r, v)| (*r, (v - tau2).max(0.0)))
            .unzip();
        let mut sorted = s.clone();
        sorted.sort_by(f64::total_cmp);
        let mu = sorted.get(sorted.len() / 2).copied().unwrap_or(0.0);
        let range = [
            sorted.first().copied().unwrap_or(0.0),
            sorted.last().copied().unwrap_or(0.0),
        ];
        AxisSample {
            e,
            s,
            tau2,
            mu,
            range,
        }
    }

    /// The variance `t_i²` of row `i` at power `kappa` (module docs).
    fn t2(&self, i: usize, kappa: f64) -> f64 {
        self.tau2 + self.s[i] * growth(self.s[i], self.mu, self.range, kappa)
    }

    /// The profile log-likelihood of the residuals at power `kappa`, the
    /// scale at its maximum (module docs); `None` when some `t_i² = 0`.
    fn profile(&self, kappa: f64) -> Option<f64> {
        let n = self.e.len() as f64;
        let (mut log_t2, mut z2) = (0.0, 0.0);
        for (i, e) in self.e.iter().enumerate() {
            let t2 = self.t2(i, kappa);
            if t2 <= 0.0 {
                return None;
            }
            log_t2 += t2.ln();
            z2 += e * e / t2;
        }
        (z2 > 0.0).then(|| -0.5 * log_t2 - 0.5 * n * (z2 / n).ln())
    }

    /// `c` at power `kappa`: [`scale_of`] with the variances `t_i²`.
    fn scale(&self, kappa: f64) -> f64 {
        let t2: Vec<f64> = (0..self.e.len()).map(|i| self.t2(i, kappa)).collect();
        scale_of(&self.e, &t2)
    }
}

/// `(s/μ)^κ` with `s` held to `range`, the MSEs the power was fitted on
/// (module docs); 1 when `μ` or `κ` is 0.
fn growth(s: f64, mu: f64, range: [f64; 2], kappa: f64) -> f64 {
    if mu > 0.0 && kappa > 0.0 && range[0] <= range[1] {
        (s.clamp(range[0], range[1]) / mu).powf(kappa)
    } else {
        1.0
    }
}

/// The power `κ` on the grid `0, POWER_STEP, …, POWER_MAX` that maximises
/// the pooled profile likelihood of the outputs (module docs); an output
/// without one (no held-out row, every residual 0) is left out, and 0 when
/// none has one or no power gives every other a likelihood.
fn power_of(axes: &[AxisSample]) -> f64 {
    let steps = (POWER_MAX / POWER_STEP).round() as usize;
    let usable: Vec<&AxisSample> = axes.iter().filter(|a| a.profile(0.0).is_some()).collect();
    if usable.is_empty() {
        return 0.0;
    }
    (0..=steps)
        .map(|k| k as f64 * POWER_STEP)
        .filter_map(|kappa| {
            usable
                .iter()
                .map(|a| a.profile(kappa))
                .sum::<Option<f64>>()
                .map(|l| (kappa, l))
        })
        .fold(None, |best: Option<(f64, f64)>, (kappa, l)| match best {
            Some((_, b)) if b >= l => best,
            _ => Some((kappa, l)),
        })
        .map_or(0.0, |(kappa, _)| kappa)
}

impl LooCheck {
    /// The calibrated standard deviation of a Kriging mean whose stated MSE
    /// on output `axis` is `mse` (mm²): `c √(s (s/μ)^κ)`, with `s/μ` held
    /// to the range the power was fitted on (module docs), mm.
    pub fn mean_std(&self, axis: usize, mse: f64) -> f64 {
        let s = mse.max(0.0);
        let g = growth(
            s,
            self.reference_mse[axis],
            self.mse_range[axis],
            self.interval_power,
        );
        self.interval_scale[axis] * (s * g).sqrt()
    }
}

impl ErrorModel {
    /// The leave-one-out check of this model's intervals ([`LooCheck`]),
    /// computed on the first call and kept.
    pub fn loo_check(&self) -> Result<LooCheck> {
        let got = self.loo.0.get_or_init(|| {
            let blocks = sample(self.n_train());
            let noise = self.noise_std();
            let mut out = LooCheck {
                interval_scale: [1.0; 3],
                interval_power: 0.0,
                reference_mse: [0.0; 3],
                mse_range: [[0.0; 2]; 3],
                loo_rmse: [0.0; 3],
                expected_loo_rmse: [0.0; 3],
                rows: blocks.len(),
                residuals: Default::default(),
            };
            let mut axes = Vec::with_capacity(self.outputs.len());
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
                out.residuals[a] = h.residuals.clone();
                axes.push(AxisSample::new(
                    &h.residuals,
                    &h.variances,
                    noise[a] * noise[a],
                ));
            }
            out.interval_power = power_of(&axes);
            for (a, x) in axes.iter().enumerate() {
                out.interval_scale[a] = x.scale(out.interval_power);
                out.reference_mse[a] = x.mu;
                out.mse_range[a] = x.range;
            }
            Ok(out)
        });
        got.clone().map_err(crate::Error::Numerical)
    }

    /// The factor on each output's stated standard deviations
    /// ([`LooCheck::interval_scale`]); the Kriging mean's is also raised
    /// to a power ([`LooCheck::mean_std`]).
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

    /// Residuals drawn with variance `τ² + s (s/μ)^κ₀` at seeded random
    /// MSEs `s` over two decades: the power found is near κ₀, and the scale
    /// then puts 95 % inside; with κ₀ = 0 the power stays near 0.
    #[test]
    fn the_power_of_the_stated_mse_is_found_from_the_residuals() {
        use rand::RngExt;
        use rand_distr::{Distribution, StandardNormal};
        for (kappa0, seed) in [(1.0, 3), (0.0, 4), (2.0, 5)] {
            let mut rng = crate::stats::rng_for(seed, "interval power");
            let (tau2, n) = (0.25, 1024);
            let s: Vec<f64> = (0..n)
                .map(|_| 10f64.powf(rng.random_range(-1.0..1.0)))
                .collect();
            let mut sorted = s.clone();
            sorted.sort_by(f64::total_cmp);
            let mu = sorted[n / 2];
            let e: Vec<f64> = s
                .iter()
                .map(|&si| {
                    let z: f64 = StandardNormal.sample(&mut rng);
                    z * (tau2 + si * (si / mu).powf(kappa0)).sqrt()
                })
                .collect();
            let v: Vec<f64> = s.iter().map(|si| si + tau2).collect();
            let axis = AxisSample::new(&e, &v, tau2);
            let kappa = power_of(std::slice::from_ref(&axis));
            assert!((kappa - kappa0).abs() <= 0.25, "κ₀ {kappa0}: found {kappa}");
            let c = axis.scale(kappa);
            let inside = (0..n)
                .filter(|&i| e[i].abs() <= Z95 * c * axis.t2(i, kappa).sqrt())
                .count();
            assert!((inside as f64 / n as f64 - 0.95).abs() < 0.002, "{inside}");
        }
    }

    /// The power is not extrapolated: a stated MSE outside the range it
    /// was fitted on grows (or shrinks) as `√s` again beyond it.
    #[test]
    fn the_power_holds_the_mse_to_the_range_it_was_fitted_on() {
        let check = LooCheck {
            interval_scale: [2.0; 3],
            interval_power: 1.0,
            reference_mse: [2.0; 3],
            mse_range: [[1.0, 4.0]; 3],
            loo_rmse: [1.0; 3],
            expected_loo_rmse: [1.0; 3],
            rows: 10,
            residuals: Default::default(),
        };
        let want = |s: f64, g: f64| 2.0 * (s * g).sqrt();
        assert_eq!(check.mean_std(0, 3.0), want(3.0, 1.5));
        assert_eq!(check.mean_std(1, 16.0), want(16.0, 2.0));
        assert_eq!(check.mean_std(2, 0.25), want(0.25, 0.5));
        assert_eq!(check.mean_std(0, 0.0), 0.0);
        let plain = LooCheck {
            interval_power: 0.0,
            ..check.clone()
        };
        assert_eq!(plain.mean_std(0, 16.0), 8.0);
    }

    #[test]
    fn sample_spreads_over_the_campaign() {
        assert_eq!(sample(3), vec![vec![0], vec![1], vec![2]]);
        let s = sample(3000);
        assert_eq!(s.len(), LOO_SAMPLE);
        assert_eq!(
            s[LOO_SAMPLE - 1],
            vec![(LOO_SAMPLE - 1) * 3000 / LOO_SAMPLE]
        );
    }
}
