//! The integrated-MSE design of one batch: which candidates, measured next,
//! lower the prediction variance over the region the most.
//!
//! For one output with correlation `r` (the fitted family at its ξ), nugget
//! ν, process variance σ² (output units²) and measured inputs D, the
//! posterior covariance of the latent error between two points is
//! `σ²·c_D(x, x′)` with
//!
//! ```text
//! c_D(x, x′) = r(x, x′) − v(x)ᵀ v(x′),   v(x) = C⁻¹ r(D, x),   C Cᵀ = R_D + νI
//! ```
//!
//! (the simple-Kriging part of eq 12: the uncertainty of the trend
//! coefficients, which shrinks as 1/m wherever the poses are, is left out).
//! The integrated MSE over the region's points Z is
//! `IMSE = σ² · mean_z c(z, z)`, and measuring x (with noise ν) lowers it by
//!
//! ```text
//! ΔIMSE(x) = σ² · mean_z c(z, x)² / (c(x, x) + ν)
//! ```
//!
//! Unlike the variance `c(x, x)` alone, which is largest on the boundary of
//! the data and piles the points up there, ΔIMSE counts how much of the
//! *region* a measurement informs. A batch is chosen greedily: the
//! candidate of largest ΔIMSE summed over the outputs, then every
//! covariance conditioned on it (a rank-one update:
//! `c ← c − c(·, x)c(x, ·)/(c(x, x) + ν)`), then the next — the
//! hyperparameters held at their fitted values, since nothing new is
//! measured inside a batch.
//!
//! Cost per output, m measured, n candidates, z region points: the
//! correlations `m·(n + z) + n·z`, the solves `m²(n + z)`, the product
//! `m·n·z`, then `n·z` per chosen pose.

use crate::kriging::{CorrelationModel, KrigingModel, TrainingInputs};
use crate::{Error, Result};
use faer::{Mat, Par};
use rayon::prelude::*;

/// One output's state during the choice of a batch.
pub(super) struct AxisDesign {
    /// σ², output units².
    scale: f64,
    /// ν (relative to σ²).
    nugget: f64,
    /// `c(z, x_c)`: candidate c's values over the region at
    /// `c·z .. (c + 1)·z`.
    kzc: Vec<f64>,
    /// Region points z.
    nz: usize,
    /// `c(x_c, x_c)`.
    var_c: Vec<f64>,
    /// `c(z, z)`.
    var_z: Vec<f64>,
    /// `v(x_c)` for every candidate, one row per conditioning point (the
    /// measured rows, then the poses chosen so far in the batch).
    v: Vec<Vec<f64>>,
    /// The candidates' inputs (for `r(x_c, x)` of a chosen x).
    cand: TrainingInputs,
    corr: crate::kriging::Correlation,
    theta: Vec<f64>,
}

/// `r(a, b)` for every `a` in `rows` (columns) and `b` in `against`
/// (rows of the result): `against.m × rows.len()`.
fn cross(
    corr: &dyn CorrelationModel,
    theta: &[f64],
    against: &TrainingInputs,
    rows: &[Vec<f64>],
) -> Mat<f64> {
    let m = against.m;
    let cols: Vec<Vec<f64>> = rows
        .par_iter()
        .map(|s| {
            let mut col = vec![0.0; m];
            corr.fill_row(theta, against, s, &mut col);
            col
        })
        .collect();
    Mat::from_fn(m, rows.len(), |i, j| cols[j][i])
}

impl AxisDesign {
    /// The state for `model` (one output of an error model, its inputs
    /// normalised as `cand` and `region` are), before any pose of the batch.
    pub(super) fn new(
        model: &KrigingModel,
        cand: &[Vec<f64>],
        region: &[Vec<f64>],
    ) -> Result<Self> {
        let data = model.data();
        let d = model.dim();
        let theta = data.theta().to_vec();
        let corr = data.corr();
        if cand.iter().chain(region).any(|r| r.len() != d) {
            return Err(Error::InvalidParameter(format!(
                "candidates and region need the model's {d} inputs"
            )));
        }
        let train = TrainingInputs::new(data.x_train());
        let (c, _, _) = model.factors()?;
        let mut vc = cross(&corr, &theta, &train, cand);
        let mut vz = cross(&corr, &theta, &train, region);
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            c.as_ref(),
            vc.as_mut(),
            Par::rayon(0),
        );
        faer::linalg::triangular_solve::solve_lower_triangular_in_place(
            c.as_ref(),
            vz.as_mut(),
            Par::rayon(0),
        );
        let region_in = TrainingInputs::new(region);
        let mut kzc = cross(&corr, &theta, &region_in, cand);
        faer::linalg::matmul::matmul(
            kzc.as_mut(),
            faer::Accum::Add,
            vz.transpose(),
            vc.as_ref(),
            -1.0,
            Par::rayon(0),
        );
        let nz = region.len();
        let kzc: Vec<f64> = (0..cand.len())
            .flat_map(|c| (0..nz).map(move |k| (k, c)))
            .map(|(k, c)| kzc[(k, c)])
            .collect();
        let col_sq =
            |v: &Mat<f64>, j: usize| (0..v.nrows()).map(|i| v[(i, j)].powi(2)).sum::<f64>();
        let var_c = (0..cand.len())
            .map(|j| (1.0 - col_sq(&vc, j)).max(0.0))
            .collect();
        let var_z = (0..region.len())
            .map(|j| (1.0 - col_sq(&vz, j)).max(0.0))
            .collect();
        let (_, sd) = model.output_scale();
        Ok(AxisDesign {
            scale: data.sigma2() * sd * sd,
            nugget: data.nugget() + data.jitter(),
            kzc,
            nz,
            var_c,
            var_z,
            v: (0..vc.nrows())
                .map(|i| (0..vc.ncols()).map(|j| vc[(i, j)]).collect())
                .collect(),
            cand: TrainingInputs::new(cand),
            corr,
            theta,
        })
    }

    /// The region's integrated MSE now, output units².
    pub(super) fn imse(&self) -> f64 {
        self.scale * self.var_z.iter().sum::<f64>() / self.var_z.len().max(1) as f64
    }

    /// `ΔIMSE` of every candidate (output units²).
    pub(super) fn gains(&self, out: &mut [f64]) {
        let nz = self.nz.max(1);
        out.par_iter_mut()
            .zip(self.kzc.par_chunks(nz))
            .enumerate()
            .for_each(|(c, (g, col))| {
                let s: f64 = col.iter().map(|v| v * v).sum();
                *g += self.scale * s / nz as f64 / (self.var_c[c] + self.nugget);
            });
    }

    /// Condition on candidate `x` being measured.
    pub(super) fn choose(&mut self, x: usize) {
        let n = self.var_c.len();
        // c(x_c, x) = r(x_c, x) − Σ_rows v[c]·v[x]
        let mut cx = vec![0.0; n];
        let sx: Vec<f64> = self.cand.row(x);
        self.corr.fill_row(&self.theta, &self.cand, &sx, &mut cx);
        for row in &self.v {
            let vx = row[x];
            for (o, vc) in cx.iter_mut().zip(row) {
                *o -= vc * vx;
            }
        }
        let denom = cx[x].max(0.0) + self.nugget;
        let nz = self.nz;
        let kxz: Vec<f64> = self.kzc[x * nz..(x + 1) * nz].to_vec();
        self.kzc
            .par_chunks_mut(nz.max(1))
            .zip(self.var_c.par_iter_mut())
            .zip(&cx)
            .for_each(|((col, vc), cxc)| {
                let f = cxc / denom;
                for (k, kz) in col.iter_mut().zip(&kxz) {
                    *k -= f * kz;
                }
                *vc = (*vc - cxc * f).max(0.0);
            });
        for (vz, kz) in self.var_z.iter_mut().zip(&kxz) {
            *vz = (*vz - kz * kz / denom).max(0.0);
        }
        let norm = denom.sqrt();
        self.v.push(cx.iter().map(|v| v / norm).collect());
    }
}
