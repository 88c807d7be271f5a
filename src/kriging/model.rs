//! A fitted single-output universal-Kriging model: the predictor (seed 003
//! eq 10) and its mean squared error (eq 12).
//!
//! `ŷ(s) = f(s)ᵀβ + r(s)ᵀγ`, `γ = R⁻¹(y − Fβ)`;
//! `φ(s) = σ²[1 − r̃ᵀr̃ + vᵀv]` with `r̃ = C⁻¹r`, `u = F̃ᵀr̃ − f(s)`, `v = G⁻ᵀu`
//! (DACE's form of eq 12), all in normalised units and scaled back by the
//! output's mean and standard deviation.

use super::corr::{Correlation, CorrelationModel, TrainingInputs};
use super::problem::{Solution, storable_ln_psi};
use super::trend::{Trend, TrendModel, trend_matrix};
use crate::{Error, Result};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Accum, Mat, Par};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

mod held_out;
mod shared;
pub use held_out::HeldOut;
pub use shared::share_coefficients;

/// Points per block in batched prediction.
const BLOCK: usize = 128;

/// What is saved of a model: enough to predict bit-identically.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KrigingModelData {
    /// Trend `f(s)` of the normalised inputs.
    pub(crate) trend: Trend,
    /// Correlation family, by name (files without one are Gaussian).
    #[serde(default)]
    pub(crate) corr: Correlation,
    /// Correlation parameters ξ, one per input dimension (normalised inputs).
    pub(crate) theta: Vec<f64>,
    /// Nugget ν added to R's diagonal (0: interpolation).
    pub(crate) nugget: f64,
    /// Numerical jitter ε added to R's diagonal.
    pub(crate) jitter: f64,
    /// Normalised training inputs, m rows.
    pub(crate) x_train: Vec<Vec<f64>>,
    /// Training mean of the response, original units (mm for an error model).
    pub(crate) y_mean: f64,
    /// Training standard deviation of the response: a normalised value v is
    /// `y_mean + y_std·v` in original units.
    pub(crate) y_std: f64,
    /// GLS trend coefficients β (eq 11), normalised units.
    pub(crate) beta: Vec<f64>,
    /// `γ = R⁻¹(y − Fβ)` (eq 10) on the normalised response, one per training row.
    pub(crate) gamma: Vec<f64>,
    /// Process variance σ² (normalised units, eq 13).
    pub(crate) sigma2: f64,
    /// ln ψ at ξ (eq 14); `f64::MIN` stands for −∞ (σ² = 0).
    pub(crate) ln_psi: f64,
    /// Lower Cholesky factor of R, packed by rows (`i ≥ j`): written by
    /// model files of version 1 only (O(m²)); now empty, and the factor is
    /// recomputed from ξ, ν, ε and the inputs when first needed.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub(crate) chol_lower: Vec<f64>,
    /// QR factor G of F̃, packed by rows (`i ≤ j`).
    pub(crate) g_upper: Vec<f64>,
}

/// Read access to the saved part of a model (the factors' packed forms
/// stay internal).
impl KrigingModelData {
    /// Trend `f(s)` of the normalised inputs.
    pub fn trend(&self) -> &Trend {
        &self.trend
    }

    /// Correlation family.
    pub fn corr(&self) -> Correlation {
        self.corr
    }

    /// Correlation parameters ξ, one per input dimension (0 for trend-only
    /// inputs).
    pub fn theta(&self) -> &[f64] {
        &self.theta
    }

    /// Nugget ν (0: interpolation).
    pub fn nugget(&self) -> f64 {
        self.nugget
    }

    /// Numerical jitter ε added to R's diagonal.
    pub fn jitter(&self) -> f64 {
        self.jitter
    }

    /// Normalised training inputs, m rows.
    pub fn x_train(&self) -> &[Vec<f64>] {
        &self.x_train
    }

    /// Training mean of the response, original units.
    pub fn y_mean(&self) -> f64 {
        self.y_mean
    }

    /// Training standard deviation of the response.
    pub fn y_std(&self) -> f64 {
        self.y_std
    }

    /// GLS trend coefficients β (eq 11), normalised units.
    pub fn beta(&self) -> &[f64] {
        &self.beta
    }

    /// `γ = R⁻¹(y − Fβ)` (eq 10), one per training row.
    pub fn gamma(&self) -> &[f64] {
        &self.gamma
    }

    /// Process variance σ² (normalised units, eq 13).
    pub fn sigma2(&self) -> f64 {
        self.sigma2
    }

    /// ln ψ at ξ (eq 14); `f64::MIN` stands for −∞.
    pub fn ln_psi(&self) -> f64 {
        self.ln_psi
    }
}

/// The m × m part of a fit, needed for the MSE and closed-form CV but not
/// for the mean: C (lower Cholesky factor of R + νI) and `F̃ = C⁻¹F`.
#[derive(Debug, Clone)]
struct Factors {
    c: Mat<f64>,
    ftilde: Mat<f64>,
}

/// Largest m whose factor a freshly fitted model keeps in memory (128 MB);
/// beyond it the factor is recomputed on the first MSE request.
pub const KEEP_FACTOR_MAX_M: usize = 4096;

/// A fitted model ready for prediction. The mean needs only β and γ; the
/// Cholesky factor is computed on the first MSE request (or kept from the
/// fit), so a loaded model costs O(m·d) until then.
#[derive(Debug, Clone, Serialize, Deserialize)]
#[serde(try_from = "KrigingModelData", into = "KrigingModelData")]
pub struct KrigingModel {
    /// The saved part: trend, ξ, ν, training inputs, β, γ.
    pub(crate) data: KrigingModelData,
    g: Mat<f64>,
    /// Training inputs, dimension-major (vectorised correlation vectors).
    xt: TrainingInputs,
    factors: std::sync::OnceLock<std::result::Result<Factors, String>>,
}

impl PartialEq for KrigingModel {
    fn eq(&self, other: &Self) -> bool {
        self.data == other.data
    }
}

impl From<KrigingModel> for KrigingModelData {
    fn from(m: KrigingModel) -> Self {
        m.data
    }
}

impl TryFrom<KrigingModelData> for KrigingModel {
    type Error = Error;

    /// Data read from a file: every check, the trend's too.
    fn try_from(data: KrigingModelData) -> Result<Self> {
        KrigingModel::checked(data, true)
    }
}

impl KrigingModel {
    /// The saved part: trend, ξ, ν, training inputs, β, γ (read-only: the
    /// cached factors are derived from it).
    pub fn data(&self) -> &KrigingModelData {
        &self.data
    }

    /// Assemble a model after checking sizes, ranges and finiteness; with
    /// `trend_from_file` also the trend's structure and its values at the
    /// training inputs (a fit builds its trend itself and has just
    /// evaluated it, so its models skip that O(m·p) pass — one per GA
    /// fitness evaluation).
    fn checked(mut data: KrigingModelData, trend_from_file: bool) -> Result<Self> {
        let m = data.x_train.len();
        let p = data.trend.len();
        let d = data.theta.len();
        let bad = |what: &str| Err(Error::InvalidParameter(format!("Kriging model: {what}")));
        let old_factor = !data.chol_lower.is_empty();
        if data.gamma.len() != m || (old_factor && data.chol_lower.len() != m * (m + 1) / 2) {
            return bad("training size and factors disagree");
        }
        if data.beta.len() != p || data.g_upper.len() != p * (p + 1) / 2 || data.trend.dim() != d {
            return bad("trend size and coefficients disagree");
        }
        if data.x_train.iter().any(|r| r.len() != d) {
            return bad("training rows have the wrong dimension");
        }
        let finite = data
            .theta
            .iter()
            .chain(&data.beta)
            .chain(&data.gamma)
            .chain(&data.chol_lower)
            .chain(&data.g_upper)
            .all(|v| v.is_finite());
        if !finite
            || !data.sigma2.is_finite()
            || data.y_std.is_nan()
            || data.y_std <= 0.0
            || !data.y_mean.is_finite()
        {
            return bad("non-finite or invalid values");
        }
        if data.theta.iter().any(|t| *t < 0.0) {
            return bad("a correlation parameter ξ is negative");
        }
        // σ² = (y − Fβ)ᵀγ / m vanishes only with γ
        if data.sigma2 == 0.0 && data.gamma.iter().any(|g| *g != 0.0) {
            return bad("σ² is 0 but γ is not");
        }
        let jitter_ok =
            data.jitter.is_finite() && (0.0..=super::problem::MAX_JITTER).contains(&data.jitter);
        if !data.nugget.is_finite() || data.nugget < 0.0 || !jitter_ok {
            return bad("the nugget or the jitter is negative, non-finite or out of range");
        }
        // the MSE is σ²·y_std²: it must stay finite
        if data.sigma2 < 0.0 || !(data.y_std * data.y_std * data.sigma2.max(1.0)).is_finite() {
            return bad(&format!(
                "σ² = {:e} is negative or the output scale y_std = {:e} overflows",
                data.sigma2, data.y_std
            ));
        }
        if data.x_train.iter().flatten().any(|v| !v.is_finite()) {
            return bad("non-finite training inputs");
        }
        if trend_from_file {
            if let Err(why) = data.trend.validate() {
                return bad(&why);
            }
            // a trend whose parameters divide by zero (e.g. a fused basis's
            // std of 0, found by fuzzing) shows at the training inputs
            let f = trend_matrix(&data.trend, &data.x_train);
            if (0..f.ncols()).any(|j| f.col(j).iter().any(|v| !v.is_finite())) {
                return bad("the trend is not finite at the training inputs");
            }
        }
        let g = unpack_upper(&data.g_upper, p);
        let xt = TrainingInputs::new(&data.x_train);
        let factors = std::sync::OnceLock::new();
        if old_factor {
            // a version-1 file: use its factor, and save the compact form
            let c = unpack_lower(&data.chol_lower, m);
            let ftilde = ftilde(&c, &data.trend, &data.x_train);
            let _ = factors.set(Ok(Factors { c, ftilde }));
            data.chol_lower = Vec::new();
        }
        Ok(KrigingModel {
            data,
            g,
            xt,
            factors,
        })
    }
}

/// `F̃ = C⁻¹ F`.
fn ftilde(c: &Mat<f64>, trend: &Trend, x: &[Vec<f64>]) -> Mat<f64> {
    let mut f = trend_matrix(trend, x);
    solve_lower_triangular_in_place(c.as_ref(), f.as_mut(), Par::Seq);
    f
}

fn unpack_lower(v: &[f64], n: usize) -> Mat<f64> {
    let mut m = Mat::zeros(n, n);
    let mut k = 0;
    for i in 0..n {
        for j in 0..=i {
            m[(i, j)] = v[k];
            k += 1;
        }
    }
    m
}

fn unpack_upper(v: &[f64], n: usize) -> Mat<f64> {
    let mut m = Mat::zeros(n, n);
    let mut k = 0;
    for i in 0..n {
        for j in i..n {
            m[(i, j)] = v[k];
            k += 1;
        }
    }
    m
}

/// Mean and MSE of one predicted output, original units.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Pred {
    /// Predicted mean, original units (mm for an error model).
    pub mean: f64,
    /// Mean squared error φ (eq 12), units².
    pub mse: f64,
}

impl KrigingModel {
    /// Assemble from a solution at ξ of the family `corr` (the family the
    /// solution was computed with).
    #[allow(clippy::too_many_arguments)]
    pub fn from_solution(
        sol: Solution,
        trend: Trend,
        corr: Correlation,
        theta: Vec<f64>,
        nugget: f64,
        x_train: Vec<Vec<f64>>,
        y_mean: f64,
        y_std: f64,
    ) -> Result<Self> {
        let m = x_train.len();
        let p = trend.len();
        let mut g_upper = Vec::with_capacity(p * (p + 1) / 2);
        for i in 0..p {
            for j in i..p {
                g_upper.push(sol.g[(i, j)]);
            }
        }
        KrigingModel::checked(
            KrigingModelData {
                trend,
                corr,
                theta,
                nugget,
                jitter: sol.value.jitter,
                x_train,
                y_mean,
                y_std,
                beta: sol.beta,
                gamma: sol.gamma,
                sigma2: sol.value.sigma2,
                ln_psi: storable_ln_psi(sol.value.ln_psi),
                chol_lower: Vec::new(),
                g_upper,
            },
            false,
        )
        .inspect(|model| {
            if m <= KEEP_FACTOR_MAX_M {
                let ftilde = sol
                    .ftilde
                    .unwrap_or_else(|| ftilde(&sol.c, &model.data.trend, &model.data.x_train));
                let _ = model.factors.set(Ok(Factors { c: sol.c, ftilde }));
            }
        })
    }

    /// The correlation family.
    pub fn corr(&self) -> Correlation {
        self.data.corr
    }

    /// The factors of the fit in normalised units: `C` (lower Cholesky
    /// factor of R + νI), `F̃ = C⁻¹F` and `G` (upper, `F̃ = QG`). C is
    /// recomputed from ξ, ν, ε and the training inputs on the first call
    /// (O(m³), bit-identical to the fit's) unless the fit kept it.
    pub fn factors(&self) -> Result<(&Mat<f64>, &Mat<f64>, &Mat<f64>)> {
        let f = self.factors.get_or_init(|| {
            let d = &self.data;
            super::problem::factor_at(&d.corr, &self.xt, &d.theta, d.nugget, d.jitter)
                .map(|c| {
                    let ftilde = ftilde(&c, &d.trend, &d.x_train);
                    Factors { c, ftilde }
                })
                .map_err(|e| e.to_string())
        });
        match f {
            Ok(f) => Ok((&f.c, &f.ftilde, &self.g)),
            Err(e) => Err(Error::Numerical(e.clone())),
        }
    }

    /// `f` of the factors `(C, F̃, G)` for one computation: the kept ones;
    /// else, up to [`KEEP_FACTOR_MAX_M`] rows, computed and kept; above it
    /// computed for `f` alone and dropped afterwards, so that a closed-form
    /// CV of a campaign of thousands of rows does not leave m² numbers per
    /// output behind (three outputs of 12 000 rows: 3.5 GB).
    fn with_factors<R>(
        &self,
        f: impl FnOnce(&Mat<f64>, &Mat<f64>, &Mat<f64>) -> Result<R>,
    ) -> Result<R> {
        if self.factors.get().is_some() || self.data.x_train.len() <= KEEP_FACTOR_MAX_M {
            let (c, ft, g) = self.factors()?;
            return f(c, ft, g);
        }
        let d = &self.data;
        let c = super::problem::factor_at(&d.corr, &self.xt, &d.theta, d.nugget, d.jitter)?;
        let ft = ftilde(&c, &d.trend, &d.x_train);
        f(&c, &ft, &self.g)
    }

    /// Drop the factors kept in memory (m² numbers; recomputed when next
    /// needed).
    pub(crate) fn release_factors(&mut self) {
        self.factors = std::sync::OnceLock::new();
    }

    /// Whether the factors are in memory (kept from the fit, or computed by
    /// an earlier [`KrigingModel::factors`] call).
    pub fn has_factors(&self) -> bool {
        self.factors.get().is_some()
    }

    /// Input dimension.
    pub fn dim(&self) -> usize {
        self.data.theta.len()
    }

    /// The mean only, `ŷ(s) = f(s)ᵀβ + r(s)ᵀγ` (seed 003 eq 9), original
    /// units: no triangular solves, so several times cheaper than
    /// [`KrigingModel::predict`] (compensation needs only the mean). The
    /// correlation vector is accumulated dimension by dimension over the
    /// contiguous training values, then one vectorised `exp`.
    pub fn predict_mean(&self, s: &[Vec<f64>]) -> Vec<f64> {
        let d = &self.data;
        let m = d.x_train.len();
        s.par_chunks(BLOCK)
            .flat_map_iter(|blk| {
                let mut acc = vec![0.0; m];
                let mut fs = vec![0.0; d.trend.len()];
                blk.iter()
                    .map(|x| {
                        d.corr.fill_row(&d.theta, &self.xt, x, &mut acc);
                        d.trend.eval_into(x, &mut fs);
                        d.y_mean + d.y_std * (dot(&fs, &d.beta) + dot(&acc, &d.gamma))
                    })
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// For each point (normalised inputs), the training row the model
    /// correlates it with most, `argmax_i R(s, s_i)`, and that correlation
    /// (the process's, without the nugget): the measurement its prediction
    /// leans on most.
    pub fn nearest_training(&self, s: &[Vec<f64>]) -> Vec<(usize, f64)> {
        let d = &self.data;
        let m = d.x_train.len();
        s.par_chunks(BLOCK)
            .flat_map_iter(|blk| {
                let mut acc = vec![0.0; m];
                blk.iter()
                    .map(|x| {
                        d.corr.fill_row(&d.theta, &self.xt, x, &mut acc);
                        acc.iter()
                            .copied()
                            .enumerate()
                            .fold(
                                (0, f64::NEG_INFINITY),
                                |b, (i, r)| if r > b.1 { (i, r) } else { b },
                            )
                    })
                    .collect::<Vec<_>>()
            })
            .collect()
    }

    /// The trend-only prediction `f(s)ᵀβ` at normalised inputs, original
    /// units (what the model says without its Kriging correction).
    pub fn predict_trend(&self, s: &[Vec<f64>]) -> Vec<f64> {
        let d = &self.data;
        let mut fs = vec![0.0; d.trend.len()];
        s.iter()
            .map(|x| {
                d.trend.eval_into(x, &mut fs);
                d.y_mean + d.y_std * dot(&fs, &d.beta)
            })
            .collect()
    }

    /// The output's mean and standard deviation `(y_mean, y_std)` that
    /// normalise it, original units.
    pub fn output_scale(&self) -> (f64, f64) {
        (self.data.y_mean, self.data.y_std)
    }

    /// The process (prior) standard deviation `σ·y_std`, original units:
    /// what the Kriging std tends to far from every training point.
    pub fn process_std(&self) -> f64 {
        self.data.sigma2.sqrt() * self.data.y_std
    }

    /// The noise standard deviation `√(ν·σ²)·y_std` (original units): the
    /// part of the process the nugget ν attributes to measurement noise
    /// (0 for an interpolating model).
    pub fn noise_std(&self) -> f64 {
        (self.data.sigma2 * self.data.nugget).sqrt() * self.data.y_std
    }

    /// Standard errors of the GLS trend coefficients β (normalised units):
    /// `Cov(β) = σ²(FᵀR⁻¹F)⁻¹` (seed 003 eq 11), and with `C⁻¹F = QG` this is
    /// `σ²(GᵀG)⁻¹ = σ²G⁻¹G⁻ᵀ`, whose diagonal is the squared row norms of
    /// `G⁻¹` (a p × p triangular solve, no m × m work).
    pub fn beta_std_errors(&self) -> Vec<f64> {
        let p = self.g.nrows();
        let mut ginv = Mat::<f64>::identity(p, p);
        faer::linalg::triangular_solve::solve_upper_triangular_in_place(
            self.g.as_ref(),
            ginv.as_mut(),
            Par::Seq,
        );
        let s = self.data.sigma2.sqrt();
        (0..p)
            .map(|k| s * (0..p).map(|j| ginv[(k, j)].powi(2)).sum::<f64>().sqrt())
            .collect()
    }

    /// Predict at normalised inputs (mean and MSE in original units).
    /// Blocks of points run in parallel; each point's result does not depend
    /// on the others. An error only when the factor cannot be recomputed
    /// (see [`KrigingModel::factors`]).
    pub fn predict(&self, s: &[Vec<f64>]) -> Result<Vec<Pred>> {
        let (c, ftilde, _) = self.factors()?;
        Ok(s.par_chunks(BLOCK)
            .flat_map_iter(|blk| self.predict_block(blk, c, ftilde))
            .collect())
    }

    fn predict_block(&self, s: &[Vec<f64>], c: &Mat<f64>, ftilde: &Mat<f64>) -> Vec<Pred> {
        let d = &self.data;
        let (m, p, b) = (d.x_train.len(), d.trend.len(), s.len());
        let mut r = Mat::<f64>::zeros(m, b);
        let mut fs = vec![0.0; p];
        let mut col = vec![0.0; m];
        let mut means = Vec::with_capacity(b);
        for (k, x) in s.iter().enumerate() {
            d.corr.fill_row(&d.theta, &self.xt, x, &mut col);
            d.trend.eval_into(x, &mut fs);
            let mean = dot(&fs, &d.beta) + dot(&col, &d.gamma);
            means.push(mean);
            for (i, v) in col.iter().enumerate() {
                r[(i, k)] = *v;
            }
        }
        // r̃ = C⁻¹ r and U = F̃ᵀ r̃ for all points of the block at once
        solve_lower_triangular_in_place(c.as_ref(), r.as_mut(), Par::Seq);
        let mut uu = Mat::<f64>::zeros(p, b);
        matmul(
            uu.as_mut(),
            Accum::Replace,
            ftilde.transpose(),
            r.as_ref(),
            1.0,
            Par::Seq,
        );
        let mut u = vec![0.0; p];
        (0..b)
            .map(|k| {
                d.trend.eval_into(&s[k], &mut fs);
                let rr: f64 = r.col(k).iter().map(|v| v * v).sum();
                for (j, uj) in u.iter_mut().enumerate() {
                    *uj = uu[(j, k)] - fs[j];
                }
                let vv = solve_gt(&self.g, &mut u);
                let mse = (d.sigma2 * (1.0 - rr + vv)).max(0.0);
                Pred {
                    mean: d.y_mean + d.y_std * means[k],
                    mse: mse * d.y_std * d.y_std,
                }
            })
            .collect()
    }
}

/// Solve `Gᵀ v = u` in place (forward substitution, G upper) and return `vᵀv`.
fn solve_gt(g: &Mat<f64>, u: &mut [f64]) -> f64 {
    let p = u.len();
    for i in 0..p {
        let mut s = u[i];
        for k in 0..i {
            s -= g[(k, i)] * u[k];
        }
        u[i] = s / g[(i, i)];
    }
    u.iter().map(|v| v * v).sum()
}

fn dot(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}
