//! Closed-form leave-block-out cross-validation of a fitted model
//! (Dubrule 1983): residuals and their variances at fixed ξ, from the
//! fit's factors, without a refit.

use super::KrigingModel;
use crate::kriging::trend::TrendModel;
use crate::{Error, Result};
use faer::linalg::matmul::matmul;
use faer::linalg::triangular_solve::solve_lower_triangular_in_place;
use faer::{Accum, Mat, MatRef, Par};

/// Held-out rows of one row each solved together ([`KrigingModel::held_out`]):
/// each chunk, in increasing row order, is solved on the trailing block of
/// the factor from its first row, and holds an m × `UNIT_CHUNK` matrix.
const UNIT_CHUNK: usize = 128;
impl KrigingModel {
    /// Closed-form leave-block-out residuals at fixed ξ (Dubrule 1983): for
    /// each block I of training rows, `e_I = y_I − ŷ_I` where ŷ_I is the
    /// universal-Kriging prediction from the other rows with ξ, the input
    /// normalisation and the nugget held fixed and β re-estimated by GLS.
    ///
    /// With `B = R⁻¹ − R⁻¹F(FᵀR⁻¹F)⁻¹FᵀR⁻¹` the held-out prediction is
    /// `ŷ_I = −B_II⁻¹ B_I,rest y_rest`, so `e_I = B_II⁻¹ (B y)_I` and
    /// `B y = R⁻¹(y − Fβ) = γ`. With `Z_I = C⁻¹ E_I` and thin `Q = F̃ G⁻¹`,
    /// `B_II = Z_Iᵀ Z_I − (Qᵀ Z_I)ᵀ (Qᵀ Z_I)`: one triangular solve per block
    /// instead of a refit. Residuals in original units, training-row order.
    pub fn held_out_residuals(&self, blocks: &[Vec<usize>]) -> Result<Vec<f64>> {
        self.held_out(blocks).map(|h| h.residuals)
    }

    /// [`KrigingModel::held_out_residuals`] and, from the same blocks
    /// `B_II` (their diagonals are `B_ii`), the model's own expectation of
    /// its leave-one-out RMSE ([`HeldOut::expected_loo_rmse`]).
    pub fn held_out(&self, blocks: &[Vec<usize>]) -> Result<HeldOut> {
        self.with_factors(|c, ftilde, g| self.held_out_with(blocks, c, ftilde, g))
    }

    /// [`KrigingModel::held_out`] with the factors `(C, F̃, G)`.
    fn held_out_with(
        &self,
        blocks: &[Vec<usize>],
        c: &Mat<f64>,
        ftilde: &Mat<f64>,
        g: &Mat<f64>,
    ) -> Result<HeldOut> {
        let d = &self.data;
        let m = d.x_train.len();
        let p = d.trend.len();
        if blocks.len() > 1 && blocks.iter().all(|b| b.len() == 1) {
            let rows: Vec<usize> = blocks.iter().map(|b| b[0]).collect();
            return self.held_out_rows(&rows, c, ftilde, g);
        }
        let mut out = vec![f64::NAN; m];
        let mut variances = vec![f64::NAN; m];
        // Σ 1/B_ii over the held-out rows, and their number
        let (mut inv_b, mut rows) = (0.0, 0usize);
        for block in blocks {
            let k = block.len();
            if k == 0 {
                continue;
            }
            if block.iter().any(|&i| i >= m) || k + p > m {
                return Err(Error::InvalidParameter(format!(
                    "held-out block of {k} rows does not fit {m} training rows and {p} trend terms"
                )));
            }
            let (z, qz) = unit_columns(block, c.as_ref(), ftilde.as_ref(), g, Par::Seq);
            let mut b = Mat::<f64>::zeros(k, k);
            matmul(
                b.as_mut(),
                Accum::Replace,
                z.transpose(),
                z.as_ref(),
                1.0,
                Par::Seq,
            );
            matmul(
                b.as_mut(),
                Accum::Add,
                qz.transpose(),
                qz.as_ref(),
                -1.0,
                Par::Seq,
            );
            inv_b += (0..k).map(|j| 1.0 / b[(j, j)]).sum::<f64>();
            rows += k;
            let rhs = Mat::<f64>::from_fn(k, 1, |j, _| d.gamma[block[j]]);
            let lu = b.partial_piv_lu();
            let e = faer::linalg::solvers::Solve::solve(&lu, &rhs);
            // Var(e_I) = σ² B_II⁻¹: its diagonal, one column at a time
            let cov = faer::linalg::solvers::Solve::solve(&lu, Mat::<f64>::identity(k, k));
            for (j, &i) in block.iter().enumerate() {
                out[i] = e[(j, 0)] * d.y_std;
                variances[i] = d.sigma2 * cov[(j, j)] * d.y_std * d.y_std;
            }
        }
        if out.iter().any(|v| !v.is_finite() && !v.is_nan()) {
            return Err(Error::Numerical(
                "closed-form CV produced non-finite residuals".into(),
            ));
        }
        Ok(HeldOut {
            residuals: out,
            variances,
            expected_loo_rmse: d.y_std * (d.sigma2 * inv_b / rows.max(1) as f64).sqrt(),
        })
    }
}

impl KrigingModel {
    /// [`KrigingModel::held_out_with`] for blocks of one row each, `rows`:
    /// `Z = C⁻¹ E` for them in multi-column solves, then per row
    /// `B_ii = ‖z_i‖² − ‖G⁻ᵀ F̃ᵀ z_i‖²` and `e_i = γ_i / B_ii`. Since `C` is
    /// lower triangular, `C⁻¹ e_i` is 0 above row `i`: the rows go in
    /// increasing order in chunks of [`UNIT_CHUNK`], each solved on the
    /// trailing block `C[i₀.., i₀..]` from its first row `i₀` (with `F̃`'s rows
    /// from `i₀`), about 40 % of the solve on the whole factor for rows
    /// spread over the campaign.
    fn held_out_rows(
        &self,
        rows: &[usize],
        c: &Mat<f64>,
        ftilde: &Mat<f64>,
        g: &Mat<f64>,
    ) -> Result<HeldOut> {
        let d = &self.data;
        let (m, p, n) = (d.x_train.len(), d.trend.len(), rows.len());
        if rows.iter().any(|&i| i >= m) || 1 + p > m {
            return Err(Error::InvalidParameter(format!(
                "held-out rows do not fit {m} training rows and {p} trend terms"
            )));
        }
        let mut sorted = rows.to_vec();
        sorted.sort_unstable();
        let mut out = vec![f64::NAN; m];
        let mut variances = vec![f64::NAN; m];
        let mut inv_b = 0.0;
        for chunk in sorted.chunks(UNIT_CHUNK) {
            let i0 = chunk[0];
            let k = m - i0;
            let local: Vec<usize> = chunk.iter().map(|&i| i - i0).collect();
            let (z, qz) = unit_columns(
                &local,
                c.as_ref().submatrix(i0, i0, k, k),
                ftilde.as_ref().subrows(i0, k),
                g,
                Par::rayon(0),
            );
            for (j, &i) in chunk.iter().enumerate() {
                let zz: f64 = z.col(j).iter().map(|v| v * v).sum();
                let qq: f64 = qz.col(j).iter().map(|v| v * v).sum();
                let b = zz - qq;
                inv_b += 1.0 / b;
                out[i] = d.gamma[i] / b * d.y_std;
                variances[i] = d.sigma2 / b * d.y_std * d.y_std;
            }
        }
        if out.iter().any(|v| v.is_infinite()) {
            return Err(Error::Numerical(
                "closed-form CV produced non-finite residuals".into(),
            ));
        }
        Ok(HeldOut {
            residuals: out,
            variances,
            expected_loo_rmse: d.y_std * (d.sigma2 * inv_b / n.max(1) as f64).sqrt(),
        })
    }
}

/// `Z = C⁻¹ E_rows` (m × k, `E_rows` the unit columns of `rows`, m the
/// order of `c`) and `Qᵀ Z = G⁻ᵀ F̃ᵀ Z` (p × k): what
/// `B_II = ZᵀZ − (QᵀZ)ᵀ(QᵀZ)` is made of.
fn unit_columns(
    rows: &[usize],
    c: MatRef<'_, f64>,
    ftilde: MatRef<'_, f64>,
    g: &Mat<f64>,
    par: Par,
) -> (Mat<f64>, Mat<f64>) {
    let mut z = Mat::<f64>::zeros(c.nrows(), rows.len());
    for (j, &i) in rows.iter().enumerate() {
        z[(i, j)] = 1.0;
    }
    solve_lower_triangular_in_place(c, z.as_mut(), par);
    let mut qz = Mat::<f64>::zeros(g.nrows(), rows.len());
    matmul(
        qz.as_mut(),
        Accum::Replace,
        ftilde.transpose(),
        z.as_ref(),
        1.0,
        Par::Seq,
    );
    faer::linalg::triangular_solve::solve_lower_triangular_in_place(
        g.transpose(),
        qz.as_mut(),
        Par::Seq,
    );
    (z, qz)
}

/// Closed-form held-out residuals of a model ([`KrigingModel::held_out`]).
#[derive(Debug, Clone, PartialEq)]
pub struct HeldOut {
    /// Residuals `y_I − ŷ_I`, original units, training-row order (NaN for a
    /// row in no block).
    pub residuals: Vec<f64>,
    /// The model's own variance of each held-out residual, the diagonal of
    /// `σ² B_II⁻¹` (`σ² / B_ii` for a block of one row; original units²,
    /// training-row order, NaN for a row in no block): the variance of a
    /// new measurement at that row predicted from the rows outside its
    /// block.
    pub variances: Vec<f64>,
    /// The model's own expectation of its leave-one-out RMSE over the rows
    /// of the blocks, original units: with `Var(y) = σ²R`, `Var(γ) = σ²B`,
    /// so a held-out residual `γ_i / B_ii` has variance `σ² / B_ii` — the
    /// nugget's noise plus the interpolation error at that row —, and this
    /// is `y_std·√(σ² · mean 1/B_ii)`.
    pub expected_loo_rmse: f64,
}

#[cfg(test)]
mod tests {
    use crate::kriging::{
        Hyperparameters, KrigingOptions, KrigingParams, Monomials, Trend, Tuning,
    };

    /// One multi-column solve for many one-row blocks gives what one block
    /// at a time gives: residuals, variances, and σ²/B_ii's mean.
    #[test]
    fn one_row_blocks_at_once_equal_one_at_a_time() {
        let m = 60;
        let x: Vec<Vec<f64>> = (0..m)
            .map(|i| vec![(i as f64 * 0.618).fract(), (i as f64 * 0.377).fract()])
            .collect();
        let y: Vec<f64> = x
            .iter()
            .enumerate()
            .map(|(i, r)| (3.0 * r[0]).sin() * r[1] + 0.02 * ((i * 7919 % 97) as f64 / 97.0 - 0.5))
            .collect();
        let (model, _) = KrigingParams::new(Trend::Monomials(Monomials::linear(2)))
            .options(KrigingOptions::default())
            .tuning(Tuning::Fixed(Hyperparameters::new(vec![3.0, 5.0], 1e-3)))
            .correlation_inputs(2)
            .check()
            .unwrap()
            .fit(&x, &y)
            .unwrap();
        let rows = [0, 7, 13, 59];
        let blocks: Vec<Vec<usize>> = rows.iter().map(|&i| vec![i]).collect();
        let together = model.held_out(&blocks).unwrap();
        for &i in &rows {
            let alone = model.held_out(&[vec![i]]).unwrap();
            let close = |a: f64, b: f64| (a - b).abs() <= 1e-9 * b.abs().max(1e-12);
            assert!(close(together.residuals[i], alone.residuals[i]), "row {i}");
            assert!(close(together.variances[i], alone.variances[i]), "row {i}");
            assert!(alone.residuals[i].is_finite() && alone.variances[i] > 0.0);
        }
        assert!(together.residuals[1].is_nan() && together.variances[1].is_nan());
        // expected_loo_rmse² is the mean of σ²/B_ii = mean of the variances
        let mean_var: f64 = rows.iter().map(|&i| together.variances[i]).sum::<f64>() / 4.0;
        assert!((together.expected_loo_rmse.powi(2) - mean_var).abs() < 1e-12 * mean_var);
    }
}
