//! What a candidate would gain *inside* the model (step 3 of `diagnose`).
//!
//! A Gaussian process over the joint angles absorbs part of any effect that
//! depends on them, and what it leaves in its out-of-fold residuals is not
//! shaped like the effect (a cross-talk of 0.05° left residuals no regressor
//! explained). So a candidate is judged by what it brings to the model:
//! its regressor columns X are added to the trend of every output at the
//! current ξ and nugget (held fixed), and the drop of the cross-validation
//! error is computed in closed form.
//!
//! For one output with `R = CCᵀ` (nugget included), `Z = C⁻¹`, trend `F`,
//! `F̃ = ZF = Q_F G` and `P = I − Q_F Q_Fᵀ`, the held-out residuals of
//! universal Kriging at fixed ξ use the residual precision (Dubrule 1983;
//! [`crate::kriging::KrigingModel::held_out_residuals`])
//!
//! `A = R⁻¹ − R⁻¹F(FᵀR⁻¹F)⁻¹FᵀR⁻¹ = MᵀM`,  `M = PZ`,  `γ = Ay`,
//!
//! leave-one-out `e_i = γ_i / A_ii` and leave-block-out `e_b = A_bb⁻¹ γ_b`.
//! Adding columns X to `F` is the rank-k update, with `Q_X` an orthonormal
//! basis of `MX` and the whitened residual `r̃ = My = Cᵀγ`,
//!
//! `A' = A − UUᵀ`,  `U = ZᵀQ_X`,  `A'y = γ − U(Q_Xᵀ r̃)`,
//!
//! so a grid point costs two products with the m × m matrices `M` and `Zᵀ`
//! (batched over a family's grid) and O(mk) for its leave-one-out errors.
//!
//! The test statistic of a family is the largest leave-one-out gain over its
//! grid, `Σ_axes y_std² (SSE_before − SSE_after)` in mm². Its null
//! distribution comes from pseudo-campaigns of the fitted model itself: the
//! whitened residual of every row multiplied by a random sign (the same on
//! the three axes) gives `γ* = Mᵀ(s ∘ r̃)`, data the model explains as well
//! as the real data but in which no candidate has a real effect. Signs, not
//! a permutation of the rows (Freedman & Lane 1983), because the noise is
//! not the same everywhere (joint repeatability reaches the TCP through the
//! Jacobian, tracker noise grows with the distance): a sign flip keeps every
//! row's size, a permutation does not (the wild bootstrap). Only `γ` and `r̃`
//! change, so one resample costs one m × m product per axis.

use crate::kriging::{Hyperparameters, KrigingModel, KrigingOptions, KrigingParams, Trend, Tuning};
use crate::model::ErrorModel;
use crate::{Error, Result};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par};
use rayon::prelude::*;
use std::ops::Range;

/// One output of the current model, prepared for trend updates at one K-fold
/// partition.
pub struct AxisSystem {
    /// The Cholesky factor `C` of `R`: `Z = C⁻¹` is applied by triangular
    /// solves (m² flops per column, half a product with a dense m × m
    /// matrix), and `M`, `A = MᵀM` are never kept.
    c: Mat<f64>,
    /// `Q_Fᵀ` (p × m): `P = I − Q_F Q_Fᵀ`.
    qt: Mat<f64>,
    a_diag: Vec<f64>,
    /// The partition the blocks are of (fold of every row).
    fold: Vec<usize>,
    /// `A_bb = M_bᵀ M_b` of every block of `fold`
    /// ([`crate::stats::fold_blocks`] order).
    blocks: Vec<Mat<f64>>,
    gamma: Vec<f64>,
    rt: Vec<f64>,
    /// `y_std²`: normalised units → mm².
    scale2: f64,
    /// Process variance σ² (normalised units).
    sigma2: f64,
}

impl AxisSystem {
    /// From a fitted output, for the K-fold partition `fold` (O(m³), once
    /// per round: `Z = C⁻¹`, m³/3 flops, then `M = PZ`, its column norms
    /// `A_ii` and the blocks `A_bb`, 2m³/K flops).
    pub fn new(model: &KrigingModel, fold: &[usize]) -> Result<Self> {
        let (c, ft, g) = model.factors()?;
        let m = c.nrows();
        if fold.len() != m {
            return Err(Error::InvalidParameter(format!(
                "a fold partition of {} rows for a model of {m}",
                fold.len()
            )));
        }
        let mut mw = Mat::<f64>::identity(m, m);
        solve_lower_triangular_in_place(c.as_ref(), mw.as_mut(), faer::get_global_parallelism());
        // Q_Fᵀ = G⁻ᵀ F̃ᵀ
        let mut qt = ft.transpose().to_owned();
        solve_lower_triangular_in_place(g.transpose(), qt.as_mut(), Par::Seq);
        // M = Z − Q_F (Q_Fᵀ Z)
        let b = &qt * &mw;
        mw -= qt.transpose() * &b;
        let blocks = crate::stats::fold_blocks(fold)
            .iter()
            .map(|idx| {
                let mb = Mat::<f64>::from_fn(m, idx.len(), |i, c| mw[(i, idx[c])]);
                mb.transpose() * &mb
            })
            .collect();
        let gamma = model.data.gamma.clone();
        let gcol = Mat::<f64>::from_fn(m, 1, |i, _| gamma[i]);
        let rtm = c.transpose() * &gcol;
        Ok(AxisSystem {
            // A_ii = ‖M e_i‖²
            a_diag: (0..m)
                .map(|i| mw.col(i).iter().map(|v| v * v).sum())
                .collect(),
            rt: (0..m).map(|i| rtm[(i, 0)]).collect(),
            c: c.clone(),
            qt,
            fold: fold.to_vec(),
            blocks,
            gamma,
            scale2: model.data.y_std * model.data.y_std,
            sigma2: model.data.sigma2,
        })
    }

    /// `(MX, Q_FᵀZX)` by one triangular solve: `ZX = C⁻¹X`, then the
    /// projection.
    fn whiten(&self, x: Mat<f64>) -> (Mat<f64>, Mat<f64>) {
        let mut zx = x;
        solve_lower_triangular_in_place(
            self.c.as_ref(),
            zx.as_mut(),
            faer::get_global_parallelism(),
        );
        let bx = &self.qt * &zx;
        zx -= self.qt.transpose() * &bx;
        (zx, bx)
    }

    /// `MᵀY = C⁻ᵀ(PY)` by one triangular solve.
    fn m_transpose_times(&self, y: Mat<f64>) -> Mat<f64> {
        let mut py = y;
        let proj = &self.qt * &py;
        py -= self.qt.transpose() * &proj;
        solve_upper_triangular_in_place(
            self.c.transpose(),
            py.as_mut(),
            faer::get_global_parallelism(),
        );
        py
    }

    /// The model's own expectation of its leave-one-out RMSE (mm): with
    /// `Var(y) = σ²R`, `Var(γ) = σ²A`, so a held-out residual
    /// `e_i = γ_i / A_ii` has variance `σ² / A_ii` — the nugget's noise plus
    /// the interpolation error at that row — averaged over the rows.
    pub fn expected_loo_rmse(&self) -> f64 {
        let m = self.rows() as f64;
        (self.scale2 * self.sigma2 * self.a_diag.iter().map(|a| 1.0 / a).sum::<f64>() / m).sqrt()
    }

    /// Number of training rows m.
    pub fn rows(&self) -> usize {
        self.gamma.len()
    }

    /// `γ* = Mᵀr̃*` for a pseudo whitened residual `r̃*`.
    fn gamma_of(&self, rt: &[f64]) -> Vec<f64> {
        let m = self.rows();
        let g = self.m_transpose_times(Mat::<f64>::from_fn(m, 1, |i, _| rt[i]));
        (0..m).map(|i| g[(i, 0)]).collect()
    }

    /// Leave-one-out SSE without any added column (normalised units).
    fn loo_sse0(&self, gamma: &[f64]) -> f64 {
        gamma
            .iter()
            .zip(&self.a_diag)
            .map(|(g, a)| (g / a).powi(2))
            .sum()
    }
}

/// A family's grid prepared on one axis: an orthonormal basis `Q_X` of the
/// whitened, projected columns of every grid point and `U = ZᵀQ_X`.
struct Prepared {
    q: Mat<f64>,
    u: Mat<f64>,
    /// Columns of `q`/`u` of each grid point (empty: nothing new).
    spans: Vec<Range<usize>>,
    /// `1 / A'_ii` of each grid point, which does not depend on the response
    /// (`A'_ii = A_ii − Σ_c U_ic²`); `None` where the point leaves a row
    /// unpredictable (`A'_ii` vanishes).
    inv_den: Vec<Option<Vec<f64>>>,
    /// For batches of pseudo-campaigns ([`FamilyTest::best_of_batch`]):
    /// `W²` (m × grid points), column g the squared `1 / A'_ii` of point g
    /// (zero for an unusable point)…
    w2: Mat<f64>,
    /// …`V = U` with each column scaled by its point's `W²`…
    v: Mat<f64>,
    /// …and `S_g = U_gᵀ diag(W²_g) U_g` of every point g.
    s: Vec<Mat<f64>>,
}

/// Relative size below which a whitened column counts as already in the
/// span of the trend (or of the point's earlier columns).
const DEPENDENT: f64 = 1e-7;

fn prepare(sys: &AxisSystem, grid: &[&[&[f64]]]) -> Prepared {
    let m = sys.rows();
    let k: usize = grid.iter().map(|p| p.len()).sum();
    let x = Mat::<f64>::from_fn(m, k, {
        let cols: Vec<&[f64]> = grid.iter().flat_map(|p| p.iter().copied()).collect();
        move |i, j| cols[j][i]
    });
    let (xt, xb) = sys.whiten(x);
    let mut q = Mat::<f64>::zeros(m, k);
    let mut spans = Vec::with_capacity(grid.len());
    let (mut src, mut dst) = (0, 0);
    for point in grid {
        let start = dst;
        for _ in point.iter() {
            let full2: f64 = (0..m).map(|i| xt[(i, src)].powi(2)).sum::<f64>()
                + (0..xb.nrows()).map(|i| xb[(i, src)].powi(2)).sum::<f64>();
            let mut v: Vec<f64> = (0..m).map(|i| xt[(i, src)]).collect();
            for _ in 0..2 {
                for c in start..dst {
                    let d: f64 = (0..m).map(|i| v[i] * q[(i, c)]).sum();
                    v.iter_mut()
                        .enumerate()
                        .for_each(|(i, x)| *x -= d * q[(i, c)]);
                }
            }
            let nv = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            if full2 > 0.0 && nv > DEPENDENT * full2.sqrt() {
                for (i, x) in v.iter().enumerate() {
                    q[(i, dst)] = x / nv;
                }
                dst += 1;
            }
            src += 1;
        }
        spans.push(start..dst);
    }
    let q = q.subcols(0, dst).to_owned();
    // U = ZᵀQ_X = MᵀQ_X (Q_X lies in the range of P)
    let u = sys.m_transpose_times(q.clone());
    let inv_den = spans
        .iter()
        .map(|span| {
            (0..m)
                .map(|i| {
                    let den = sys.a_diag[i] - span.clone().map(|c| u[(i, c)].powi(2)).sum::<f64>();
                    (den > 1e-10 * sys.a_diag[i]).then(|| 1.0 / den)
                })
                .collect()
        })
        .collect::<Vec<Option<Vec<f64>>>>();
    let w2 = Mat::<f64>::from_fn(m, spans.len(), |i, g| {
        inv_den[g].as_ref().map_or(0.0, |w| w[i] * w[i])
    });
    let mut v = Mat::<f64>::zeros(m, u.ncols());
    let mut s = Vec::with_capacity(spans.len());
    for (g, span) in spans.iter().enumerate() {
        for c in span.clone() {
            for i in 0..m {
                v[(i, c)] = u[(i, c)] * w2[(i, g)];
            }
        }
        let n = span.len();
        s.push(Mat::<f64>::from_fn(n, n, |x, y| {
            let (cx, cy) = (span.start + x, span.start + y);
            (0..m).map(|i| v[(i, cx)] * u[(i, cy)]).sum()
        }));
    }
    Prepared {
        q,
        u,
        spans,
        inv_den,
        w2,
        v,
        s,
    }
}

/// Leave-one-out SSE (normalised units) of every grid point for the
/// response with `gamma`, `rt`; `NaN` where a point leaves a row
/// unpredictable (its A'_ii vanishes).
fn loo_sse(sys: &AxisSystem, prep: &Prepared, gamma: &[f64], rt: &[f64]) -> Vec<f64> {
    let m = sys.rows();
    // Q_Xᵀ r̃ for every column at once
    let r = faer::ColRef::from_slice(rt);
    let coef = prep.q.transpose() * r;
    let mut num = vec![0.0; m];
    prep.spans
        .iter()
        .zip(&prep.inv_den)
        .map(|(span, inv_den)| {
            let Some(inv_den) = inv_den else {
                return f64::NAN;
            };
            num.copy_from_slice(gamma);
            for c in span.clone() {
                let uc = prep.u.col(c);
                let k = coef[c];
                for (n, u) in num.iter_mut().zip(uc.iter()) {
                    *n -= u * k;
                }
            }
            num.iter().zip(inv_den).map(|(n, w)| (n * w).powi(2)).sum()
        })
        .collect()
}

/// The regressor columns of one grid point on each output axis (a column
/// of every axis is in all three).
pub type AxisColumns<'a> = [Vec<&'a [f64]>; 3];

/// Columns that are regressors of every axis, as [`AxisColumns`].
pub fn on_every_axis(columns: &[Vec<f64>]) -> AxisColumns<'_> {
    std::array::from_fn(|_| columns.iter().map(Vec::as_slice).collect())
}

/// One candidate family prepared on the three outputs.
pub struct FamilyTest {
    axes: Vec<Prepared>,
}

impl FamilyTest {
    /// `grid[g][a]` holds the regressor columns of grid point g on output
    /// axis a.
    pub fn new(systems: &[AxisSystem], grid: &[AxisColumns<'_>]) -> Self {
        FamilyTest {
            axes: systems
                .iter()
                .enumerate()
                .map(|(a, s)| {
                    let on_axis: Vec<&[&[f64]]> = grid.iter().map(|p| &p[a][..]).collect();
                    prepare(s, &on_axis)
                })
                .collect(),
        }
    }

    /// Pooled leave-one-out gain (mm²) of every grid point; `responses`
    /// holds `(γ, r̃, SSE₀)` per axis (the real data or a pseudo-campaign).
    fn gains(&self, systems: &[AxisSystem], responses: &[Response]) -> Vec<f64> {
        let mut total = vec![0.0; self.axes[0].spans.len()];
        for ((sys, prep), r) in systems.iter().zip(&self.axes).zip(responses) {
            for (t, sse) in total.iter_mut().zip(loo_sse(sys, prep, &r.gamma, &r.rt)) {
                *t += sys.scale2 * (r.sse0 - sse);
            }
        }
        total
    }

    /// Grid points whose pooled leave-one-out gain on the data is within
    /// `within` (mm²) of the best: a likelihood-ratio style support set of
    /// the scanned parameter.
    pub fn near_best(
        &self,
        systems: &[AxisSystem],
        responses: &[Response],
        within: f64,
    ) -> Vec<usize> {
        let gains = self.gains(systems, responses);
        let best = gains
            .iter()
            .copied()
            .filter(|g| g.is_finite())
            .fold(f64::NEG_INFINITY, f64::max);
        gains
            .iter()
            .enumerate()
            .filter(|(_, g)| g.is_finite() && **g >= best - within)
            .map(|(i, _)| i)
            .collect()
    }

    /// The best pooled leave-one-out gain (mm²) over the grid in every
    /// pseudo-campaign of `batch` (`−∞` where no point is usable): what
    /// [`FamilyTest::best`] gives for each, from three matrix products per
    /// axis instead of a pass over the grid per campaign. With `k = Q_Xᵀr̃*`
    /// and `w = 1/A'_ii`, a point's leave-one-out SSE expands as
    ///
    /// `Σ_i w_i²(γ*_i − (Uk)_i)² = (W²)ᵀ(γ*∘γ*) − 2 kᵀ(Vᵀγ*) + kᵀ S k`,
    ///
    /// so the batch costs the products `Q_XᵀR̃*`, `VᵀΓ*` and `(W²)ᵀ(Γ*∘Γ*)`.
    pub fn best_of_batch(&self, systems: &[AxisSystem], batch: &Batch) -> Vec<f64> {
        let nb = batch.len();
        let ng = self.axes[0].spans.len();
        let mut total = vec![0.0; ng * nb];
        for ((sys, prep), r) in systems.iter().zip(&self.axes).zip(&batch.axes) {
            let k = prep.q.transpose() * &r.rt;
            let d = prep.v.transpose() * &r.gamma;
            let e = prep.w2.transpose() * &r.gamma2;
            for (g, span) in prep.spans.iter().enumerate() {
                let row = &mut total[g * nb..(g + 1) * nb];
                if prep.inv_den[g].is_none() {
                    row.fill(f64::NAN);
                    continue;
                }
                let sg = &prep.s[g];
                for (b, t) in row.iter_mut().enumerate() {
                    let mut sse = e[(g, b)];
                    for (x, cx) in span.clone().enumerate() {
                        sse -= 2.0 * k[(cx, b)] * d[(cx, b)];
                        for (y, cy) in span.clone().enumerate() {
                            sse += k[(cx, b)] * k[(cy, b)] * sg[(x, y)];
                        }
                    }
                    *t += sys.scale2 * (r.sse0[b] - sse);
                }
            }
        }
        (0..nb)
            .map(|b| {
                (0..ng)
                    .map(|g| total[g * nb + b])
                    .filter(|v| v.is_finite())
                    .fold(f64::NEG_INFINITY, f64::max)
            })
            .collect()
    }

    /// Best grid point and its pooled leave-one-out gain (mm²) on the data;
    /// `(0, −∞)` when no point is usable.
    pub fn best(&self, systems: &[AxisSystem], responses: &[Response]) -> (usize, f64) {
        self.gains(systems, responses)
            .into_iter()
            .enumerate()
            .filter(|(_, g)| g.is_finite())
            .fold((0, f64::NEG_INFINITY), |a, b| if b.1 > a.1 { b } else { a })
    }

    /// Closed-form K-fold CV SSE (mm², pooled over the axes) with grid point
    /// `g` added, at the partition the systems were built for.
    pub fn kfold_sse(&self, systems: &[AxisSystem], g: usize) -> f64 {
        systems
            .iter()
            .zip(&self.axes)
            .map(|(sys, prep)| {
                let span = prep.spans[g].clone();
                let coef: Vec<f64> = span
                    .clone()
                    .map(|c| (0..sys.rows()).map(|i| prep.q[(i, c)] * sys.rt[i]).sum())
                    .collect();
                crate::stats::fold_blocks(&sys.fold)
                    .iter()
                    .zip(&sys.blocks)
                    .map(|(idx, a_bb)| {
                        let n = idx.len();
                        let mut a = a_bb.clone();
                        let mut gam = Mat::<f64>::from_fn(n, 1, |r, _| sys.gamma[idx[r]]);
                        for (k, c) in span.clone().enumerate() {
                            for r in 0..n {
                                let ur = prep.u[(idx[r], c)];
                                gam[(r, 0)] -= ur * coef[k];
                                for s in 0..n {
                                    a[(r, s)] -= ur * prep.u[(idx[s], c)];
                                }
                            }
                        }
                        sys.scale2 * block_sse(a, gam)
                    })
                    .sum::<f64>()
            })
            .sum()
    }
}

/// `‖A_bb⁻¹ γ_b‖²`.
fn block_sse(a: Mat<f64>, gamma: Mat<f64>) -> f64 {
    let e = faer::linalg::solvers::Solve::solve(&a.partial_piv_lu(), &gamma);
    (0..e.nrows()).map(|r| e[(r, 0)].powi(2)).sum()
}

/// Closed-form K-fold CV SSE (mm², pooled) of the model as it is, at the
/// partition the systems were built for.
pub fn kfold_sse_before(systems: &[AxisSystem]) -> f64 {
    systems
        .iter()
        .map(|sys| {
            crate::stats::fold_blocks(&sys.fold)
                .iter()
                .zip(&sys.blocks)
                .map(|(idx, a)| {
                    let n = idx.len();
                    let a = a.clone();
                    let g = Mat::<f64>::from_fn(n, 1, |r, _| sys.gamma[idx[r]]);
                    sys.scale2 * block_sse(a, g)
                })
                .sum::<f64>()
        })
        .sum()
}

/// The response of one axis: `γ = Ay`, the whitened residual `r̃` and the
/// leave-one-out SSE without additions.
pub struct Response {
    gamma: Vec<f64>,
    rt: Vec<f64>,
    sse0: f64,
}

/// The responses of the data itself.
pub fn observed(systems: &[AxisSystem]) -> Vec<Response> {
    systems
        .iter()
        .map(|s| Response {
            sse0: s.loo_sse0(&s.gamma),
            gamma: s.gamma.clone(),
            rt: s.rt.clone(),
        })
        .collect()
}

/// A pseudo-campaign of the fitted model: the whitened residual of every
/// row multiplied by `signs[i] = ±1` (the same sign on every axis).
pub fn flipped(systems: &[AxisSystem], signs: &[f64]) -> Vec<Response> {
    systems
        .iter()
        .map(|s| {
            let rt: Vec<f64> = s.rt.iter().zip(signs).map(|(r, f)| r * f).collect();
            let gamma = s.gamma_of(&rt);
            Response {
                sse0: s.loo_sse0(&gamma),
                rt,
                gamma,
            }
        })
        .collect()
}

/// Pseudo-campaigns of one axis in a batch, a column each.
struct BatchAxis {
    gamma: Mat<f64>,
    gamma2: Mat<f64>,
    rt: Mat<f64>,
    sse0: Vec<f64>,
}

/// A batch of sign-flipped pseudo-campaigns ([`flipped`] for several sign
/// vectors at once: one m × m × batch product per axis).
pub struct Batch {
    axes: Vec<BatchAxis>,
}

impl Batch {
    /// Number of pseudo-campaigns.
    pub fn len(&self) -> usize {
        self.axes.first().map_or(0, |a| a.sse0.len())
    }

    /// `true` when the batch holds no campaign.
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }
}

/// The pseudo-campaigns of `signs` (each one `±1` per row), as [`flipped`].
pub fn flipped_batch(systems: &[AxisSystem], signs: &[Vec<f64>]) -> Batch {
    Batch {
        axes: systems
            .iter()
            .map(|s| {
                let m = s.rows();
                let rt = Mat::<f64>::from_fn(m, signs.len(), |i, b| s.rt[i] * signs[b][i]);
                let gamma = s.m_transpose_times(rt.clone());
                let gamma2 = Mat::<f64>::from_fn(m, signs.len(), |i, b| gamma[(i, b)].powi(2));
                let sse0 = (0..signs.len())
                    .map(|b| (0..m).map(|i| gamma2[(i, b)] / s.a_diag[i].powi(2)).sum())
                    .collect();
                BatchAxis {
                    gamma,
                    gamma2,
                    rt,
                    sse0,
                }
            })
            .collect(),
    }
}

/// Leave-one-out SSE (mm², pooled) of the model as it is.
pub fn loo_sse_before(systems: &[AxisSystem]) -> f64 {
    systems
        .iter()
        .map(|s| s.scale2 * s.loo_sse0(&s.gamma))
        .sum()
}

/// The systems of `model` at the ξ and nugget it would choose with
/// `columns` in its trend. A GP that has bent its correlation lengths to
/// absorb part of an effect (a short length over q2 for a q2 harmonic)
/// hides it from a test at its own ξ; here every output is refitted (ξ, ν
/// by a local search from the model's own, so an irrelevant column leaves
/// them where they were) with the columns as trend-only inputs, and then
/// factorised at that ξ with its own trend, so the candidate is tested
/// where the model would stand with it; `axes` is the output axis of each
/// column (`None`: every axis). `errors` are the campaign's
/// measured errors (mm). On a campaign larger than `opts.converge_rows`,
/// ξ and ν are re-estimated on the subset a fit with `opts` converges on
/// ([`crate::kriging::converge_subset`]: a likelihood step costs m³/3) and
/// the systems are still factorised on all rows.
pub fn refit_systems(
    model: &ErrorModel,
    errors: &[[f64; 3]],
    opts: &KrigingOptions,
    columns: &[Vec<f64>],
    axes: &[Option<usize>],
    fold: &[usize],
) -> Result<Vec<AxisSystem>> {
    let corr = model.correlation_dims();
    let rows = crate::kriging::converge_subset(errors.len(), opts);
    let x = &model.outputs[0].data.x_train;
    // the rows the search sees, the columns appended as trend-only inputs
    let search_rows: Vec<usize> = rows.unwrap_or_else(|| (0..errors.len()).collect());
    let x_fit: Vec<Vec<f64>> = search_rows
        .iter()
        .map(|&i| {
            x[i].iter()
                .copied()
                .chain(columns.iter().map(|c| c[i]))
                .collect()
        })
        .collect();
    let searched: Vec<Result<Hyperparameters>> = model
        .outputs
        .par_iter()
        .enumerate()
        .map(|(a, km)| {
            let Trend::Monomials(base) = &km.data.trend else {
                return Err(Error::InvalidParameter(
                    "diagnose refits need a polynomial trend".into(),
                ));
            };
            let terms = crate::model::with_linear_columns(base, axes, a);
            let y_fit: Vec<f64> = search_rows.iter().map(|&i| errors[i][a]).collect();
            let start = Hyperparameters::of(&model.reports[a], corr);
            // the refit continues the model's own family (with the family
            // chosen by CV it may differ from the options')
            let (_, report) = KrigingParams::new(Trend::Monomials(terms))
                .options(opts.clone())
                .corr(km.corr())
                .tuning(Tuning::Warm(start))
                .correlation_inputs(corr)
                .check()?
                .fit(&x_fit, &y_fit)?;
            Ok(Hyperparameters::new(
                report.theta[..corr].to_vec(),
                report.nugget,
            ))
        })
        .collect();
    let searched: Vec<Hyperparameters> = searched.into_iter().collect::<Result<_>>()?;
    let o = &model.outputs;
    let systems = crate::model::solve_outputs(
        x,
        corr,
        |a| errors.iter().map(|e| e[a]).collect(),
        &[&o[0].data.trend, &o[1].data.trend, &o[2].data.trend],
        std::array::from_fn(|a| o[a].corr()),
        std::array::from_fn(|a| searched[a].clone()),
        opts,
    )?;
    systems.iter().map(|at| AxisSystem::new(at, fold)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kriging::Monomials;

    /// A small GP problem: 2 correlated inputs, one trend-only column.
    fn problem() -> (Vec<Vec<f64>>, Vec<f64>, Vec<f64>) {
        let m = 60;
        let x: Vec<Vec<f64>> = (0..m)
            .map(|i| {
                let t = i as f64;
                vec![
                    (t * 0.618).fract() * 2.0 - 1.0,
                    (t * 0.414).fract() * 2.0 - 1.0,
                ]
            })
            .collect();
        let extra: Vec<f64> = (0..m).map(|i| ((i * 7) % 5) as f64 - 2.0).collect();
        let y: Vec<f64> = x
            .iter()
            .zip(&extra)
            .enumerate()
            .map(|(i, (r, e))| {
                (2.0 * r[0]).sin() + r[1] * r[1] + 0.3 * e + 0.01 * ((i * 13) % 7) as f64
            })
            .collect();
        (x, extra, y)
    }

    #[test]
    fn closed_form_gain_equals_refactorising_with_the_column_in_the_trend() {
        let (x, extra, y) = problem();
        let opts = KrigingOptions {
            nugget: true,
            optimizer: crate::kriging::OptimizerKind::HookeJeeves,
            ..KrigingOptions::default()
        };
        let names = vec!["a".to_string(), "b".to_string()];
        let base = Trend::Monomials(Monomials::constant(2));
        let (model, rep) = KrigingParams::new(base)
            .options(opts)
            .names(names)
            .check()
            .and_then(|p| p.fit(&x, &y))
            .unwrap();
        let m = x.len();
        let fold: Vec<usize> = (0..m).map(|i| (i * 7) % 6).collect();
        let sys = vec![AxisSystem::new(&model, &fold).unwrap()];
        let test = FamilyTest::new(&sys, &[on_every_axis(std::slice::from_ref(&extra))]);
        // the same column in the trend, factorised at the same ξ and nugget
        let x_aug: Vec<Vec<f64>> = x
            .iter()
            .zip(&extra)
            .map(|(r, e)| vec![r[0], r[1], *e])
            .collect();
        let mut terms = Monomials::constant(3);
        terms.exponents.push(vec![0, 0, 1]);
        let aug = KrigingParams::new(Trend::Monomials(terms))
            .tuning(Tuning::Fixed(Hyperparameters::of(&rep, 2)))
            .correlation_inputs(2)
            .check()
            .and_then(|p| p.fit(&x_aug, &y))
            .unwrap()
            .0;
        assert_eq!(aug.data.theta, vec![rep.theta[0], rep.theta[1], 0.0]);
        let folds: Vec<Vec<usize>> = (0..6)
            .map(|f| (0..m).filter(|&i| fold[i] == f).collect())
            .collect();
        let sse = |e: Vec<f64>| e.iter().map(|v| v * v).sum::<f64>();
        let singles: Vec<Vec<usize>> = (0..m).map(|i| vec![i]).collect();
        let loo_before = sse(model.held_out_residuals(&singles).unwrap());
        let loo_after = sse(aug.held_out_residuals(&singles).unwrap());
        let gain = test.best(&sys, &observed(&sys)).1;
        assert!(loo_before > 2.0 * loo_after, "{loo_before} {loo_after}");
        assert!(
            ((loo_before - loo_after) - gain).abs() < 1e-8 * loo_before,
            "{gain}"
        );
        assert!((loo_sse_before(&sys) - loo_before).abs() < 1e-9 * loo_before);
        // the model's own leave-one-out expectation: from M = PZ here, from
        // the held-out blocks' diagonals in the closed-form CV
        let own = sys[0].expected_loo_rmse();
        for blocks in [&singles, &folds] {
            let h = model.held_out(blocks).unwrap();
            assert!(
                (h.expected_loo_rmse - own).abs() < 1e-9 * own,
                "{h:?} {own}"
            );
        }
        let kf_before = sse(model.held_out_residuals(&folds).unwrap());
        let kf_after = sse(aug.held_out_residuals(&folds).unwrap());
        assert!((kfold_sse_before(&sys) - kf_before).abs() < 1e-8 * kf_before);
        assert!((test.kfold_sse(&sys, 0) - kf_after).abs() < 1e-8 * kf_before);
        // a column already in the trend (a constant) adds nothing
        let constant = vec![vec![3.0; m]];
        let none = FamilyTest::new(&sys, &[on_every_axis(&constant)]);
        assert!(none.best(&sys, &observed(&sys)).1.abs() < 1e-12);
        // sign-flipped pseudo-campaigns keep the model's own fit
        let signs: Vec<f64> = (0..m)
            .map(|i| if i % 3 == 0 { -1.0 } else { 1.0 })
            .collect();
        let pseudo = flipped(&sys, &signs);
        assert!(pseudo[0].sse0 > 0.0 && test.best(&sys, &pseudo).1.is_finite());
        // a batch of them gives what each gives alone
        let points = [
            vec![extra.clone()],
            vec![extra.clone(), x.iter().map(|r| r[0] * r[1]).collect()],
        ];
        let grid: Vec<AxisColumns<'_>> = points.iter().map(|g| on_every_axis(g)).collect();
        let two = FamilyTest::new(&sys, &grid);
        let signs2: Vec<f64> = (0..m).map(|i| if i % 5 < 2 { -1.0 } else { 1.0 }).collect();
        let batch = flipped_batch(&sys, &[signs.clone(), signs2.clone()]);
        let together = two.best_of_batch(&sys, &batch);
        for (s, t) in [signs, signs2].iter().zip(together) {
            let alone = two.best(&sys, &flipped(&sys, s)).1;
            assert!(
                (alone - t).abs() <= 1e-9 * alone.abs().max(1e-12),
                "{alone} {t}"
            );
        }
    }
}
