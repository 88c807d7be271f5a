//! One universal-Kriging problem at fixed data: evaluating the concentrated
//! objective ψ(ξ) and solving for β, σ², γ (seed 003 eqs 10–14; DACE).
//!
//! With `R = C Cᵀ` (Cholesky), `F̃ = C⁻¹F`, `ỹ = C⁻¹y` and the thin QR
//! `[F̃ ỹ] = Q [[G, b], [0, ρ]]`:
//!
//! - `β = G⁻¹ b` (GLS estimate, eq 11, by QR — never normal equations),
//! - `σ² = ρ²/m` (eq 13: `ρ = ‖ỹ − F̃β‖`),
//! - `ln ψ = (2/m) Σ ln C_ii + ln σ²` (eq 14: `ψ = |R|^(1/m) σ²`),
//! - `γ = C⁻ᵀ(ỹ − F̃β) = R⁻¹(y − Fβ)` for the predictor (eq 10).
//!
//! `R` gets `1 + ν + ε` on its diagonal: ν the nugget (noise-to-signal ratio,
//! 0 for interpolation) and ε a jitter: the smallest of the ladder
//! `ε_k = (10 + m)·eps·10^k` (k = 0 is DACE's choice) for which the Cholesky
//! succeeds, up to [`MAX_JITTER`]. The Gaussian correlation is numerically
//! singular for small ξ, so the search starts one rung below the rung that
//! worked last time (found by walking down/up): two factorisations in the
//! common case instead of up to nine, and ε still a function of ξ alone.

use super::corr::{CorrelationModel, TrainingInputs};
use super::trend::CoefficientPrior;
use crate::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{
    qr_in_place, qr_in_place_scratch, recommended_block_size,
};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par};

/// Largest jitter tried before a Cholesky failure is reported.
pub const MAX_JITTER: f64 = 1e-6;

/// Training data of one output, normalised, with its trend matrix.
pub struct KrigingProblem<'a> {
    /// First rung of the jitter ladder; `None` = DACE's `(10 + m)·eps`.
    pub min_jitter: Option<f64>,
    /// Correlation family `R(s, s')`.
    pub corr: &'a dyn CorrelationModel,
    /// Normalised training inputs, dimension-major.
    pub inputs: &'a TrainingInputs,
    /// m × p trend matrix with linearly independent columns.
    pub f: &'a Mat<f64>,
    /// Normalised response, length m.
    pub y: &'a [f64],
    /// The prior of each trend coefficient in Bayesian universal Kriging
    /// (one per column of `f`, or empty for none): `β_j ~ N(0, τ_j²)` with
    /// `τ_j = ‖y‖ / max(‖F_j‖, n_j)` for [`CoefficientPrior::Norm`]`(n_j)`
    /// — no single term may explain more than the whole response a priori —
    /// and no prior for [`CoefficientPrior::Flat`]. See
    /// [`KrigingProblem::solve`].
    pub prior: &'a [CoefficientPrior],
}

/// Reusable buffers for ψ evaluations (one per thread).
pub struct Workspace {
    /// R without jitter (lower triangle), kept across jitter attempts.
    base: Mat<f64>,
    r: Mat<f64>,
    /// Jitter rung that worked last.
    rung: usize,
    aug: Mat<f64>,
    qcoef: Mat<f64>,
    mem: MemBuffer,
    /// C⁻¹ for the gradient; allocated by the first [`KrigingProblem::psi_grad`].
    cinv: Mat<f64>,
    /// Products of the blocked inverse (below [`PAR_MIN_ROWS`] rows, at
    /// most m²/4 values); allocated by the first [`KrigingProblem::psi_grad`].
    scratch: Mat<f64>,
    /// Parallelism of the m × m work ([`par_for`]): from [`PAR_MIN_ROWS`]
    /// rows every evaluation uses all threads, so that three outputs on
    /// two cores never leave one idle.
    par: Par,
}

impl Workspace {
    /// Start the next evaluation's jitter ladder from the bottom, as a new
    /// workspace would (its buffers are overwritten before they are read).
    pub(super) fn forget_rung(&mut self) {
        self.rung = 0;
    }

    /// Buffers for `m` rows and `p` trend terms.
    pub fn new(m: usize, p: usize) -> Self {
        let bs = recommended_block_size::<f64>(m, p + 1);
        let par = par_for(m);
        let req = qr_in_place_scratch::<f64>(m, p + 1, bs, Par::Seq, Default::default());
        Workspace {
            base: Mat::zeros(m, m),
            r: Mat::zeros(m, m),
            rung: 0,
            aug: Mat::zeros(m, p + 1),
            qcoef: Mat::zeros(bs, (p + 1).min(m)),
            mem: MemBuffer::new(req),
            cinv: Mat::zeros(0, 0),
            scratch: Mat::zeros(0, 0),
            par,
        }
    }
}

/// Value of the concentrated objective at one ξ.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PsiValue {
    /// ln ψ (what the optimisers minimise).
    pub ln_psi: f64,
    /// `σ² = ρ²/m` (eq 13), normalised units.
    pub sigma2: f64,
    /// ln |R|.
    pub ln_det_r: f64,
    /// Jitter ε that made R factorisable.
    pub jitter: f64,
}

/// Everything prediction needs, at one ξ.
#[derive(Debug, Clone)]
pub struct Solution {
    /// The objective's value and its by-products at this ξ.
    pub value: PsiValue,
    /// Lower Cholesky factor C of R (upper triangle zero).
    pub c: Mat<f64>,
    /// Upper-triangular QR factor G of F̃ (p × p).
    pub g: Mat<f64>,
    /// `β = G⁻¹ b`, GLS trend coefficients (eq 11).
    pub beta: Vec<f64>,
    /// `γ = R⁻¹(y − Fβ)` for the predictor (eq 10), length m.
    pub gamma: Vec<f64>,
    /// `F̃ = C⁻¹F` when the solver kept it (the model computes it from C
    /// otherwise).
    pub ftilde: Option<Mat<f64>>,
}

impl KrigingProblem<'_> {
    /// Number of training rows.
    pub fn m(&self) -> usize {
        self.y.len()
    }

    /// Fill R and factorise it in `ws.r` with the smallest working jitter rung.
    fn factor_r(&self, theta: &[f64], nugget: f64, ws: &mut Workspace) -> Result<f64> {
        let m = self.m();
        let eps0 = self.min_jitter.unwrap_or((10.0 + m as f64) * f64::EPSILON);
        let jitter = |k: usize| eps0 * 10f64.powi(k as i32);
        let max_rung = (MAX_JITTER / eps0).log10().floor() as usize;
        self.inputs
            .fill_lower(self.corr, theta, nugget, ws.base.as_mut());
        let try_rung = |ws: &mut Workspace, k: usize| {
            // the lower triangle is all the factorisation reads
            ws.r.as_mut().copy_from_triangular_lower(ws.base.as_ref());
            for i in 0..m {
                ws.r[(i, i)] += jitter(k);
            }
            super::dense::cholesky_lower(ws.r.as_mut(), ws.par)
        };
        let mut k = ws.rung.saturating_sub(1);
        if try_rung(ws, k) {
            while k > 0 {
                if try_rung(ws, k - 1) {
                    k -= 1;
                } else {
                    // the failed attempt overwrote the factor: redo rung k
                    if !try_rung(ws, k) {
                        break;
                    }
                    ws.rung = k;
                    return Ok(jitter(k));
                }
            }
            if k == 0 {
                ws.rung = 0;
                return Ok(jitter(0));
            }
        }
        loop {
            k += 1;
            if k > max_rung {
                return Err(Error::Numerical(format!(
                    "correlation matrix not positive definite even with jitter {MAX_JITTER:e} (duplicate poses? try a nugget)"
                )));
            }
            if try_rung(ws, k) {
                ws.rung = k;
                return Ok(jitter(k));
            }
        }
    }

    /// ln ψ(ξ) and σ² (eq 14): one Cholesky, one triangular solve with p + 1
    /// right-hand sides, one QR of [F̃ ỹ]. No allocation. An error when R
    /// cannot be factorised or the likelihood is degenerate (σ² = 0).
    pub fn psi(&self, theta: &[f64], nugget: f64, ws: &mut Workspace) -> Result<PsiValue> {
        let v = self.evaluate(theta, nugget, ws)?;
        if v.sigma2 > 0.0 && v.ln_psi.is_finite() {
            Ok(v)
        } else {
            Err(Error::Numerical(format!(
                "degenerate likelihood (σ² = {:e}, ln|R| = {:e})",
                v.sigma2, v.ln_det_r
            )))
        }
    }

    fn evaluate(&self, theta: &[f64], nugget: f64, ws: &mut Workspace) -> Result<PsiValue> {
        let jitter = self.factor_r(theta, nugget, ws)?;
        let (ln_det_r, sigma2) = self.trend_qr(
            ws.r.as_ref(),
            &mut ws.aug,
            &mut ws.qcoef,
            &mut ws.mem,
            ws.par,
        );
        Ok(PsiValue {
            ln_psi: ln_det_r / self.m() as f64 + sigma2.ln(),
            sigma2,
            ln_det_r,
            jitter,
        })
    }

    /// Given the factor C: `ln|R| = 2Σ ln C_ii`, then `[F̃ ỹ] = C⁻¹[F y]` and
    /// its QR in `aug` (G and b on top, ρ at (p, p)); returns (ln|R|, σ²).
    fn trend_qr(
        &self,
        c: faer::MatRef<'_, f64>,
        aug: &mut Mat<f64>,
        qcoef: &mut Mat<f64>,
        mem: &mut MemBuffer,
        par: Par,
    ) -> (f64, f64) {
        let m = self.m();
        let p = self.f.ncols();
        let ln_det_r = 2.0 * (0..m).map(|i| c[(i, i)].ln()).sum::<f64>();
        aug.as_mut().subcols_mut(0, p).copy_from(self.f.as_ref());
        for (i, v) in self.y.iter().enumerate() {
            aug[(i, p)] = *v;
        }
        solve_lower_triangular_in_place(c, aug.as_mut(), par);
        qr_in_place(
            aug.as_mut(),
            qcoef.as_mut(),
            Par::Seq,
            MemStack::new(mem),
            Default::default(),
        );
        let rho = aug[(p, p)];
        (ln_det_r, rho * rho / m as f64)
    }

    /// `y − Fβ`.
    fn residual(&self, beta: &[f64]) -> Vec<f64> {
        (0..self.m())
            .map(|i| {
                self.y[i]
                    - (0..beta.len())
                        .map(|j| self.f[(i, j)] * beta[j])
                        .sum::<f64>()
            })
            .collect()
    }

    /// ln ψ and its gradient in the optimisers' coordinates `z = (log10 ξ,
    /// log10 ν)`; `grad` has `d` entries, plus one for ν when it has `d + 1`.
    ///
    /// With ψ profiled over β and σ² (envelope theorem: β and σ² are optimal
    /// at every ξ, so their own derivatives drop out),
    ///
    /// `∂ ln ψ / ∂t = (1/m) [tr(R⁻¹ ∂R/∂t) − γᵀ (∂R/∂t) γ / σ²]
    ///              = (1/m) Σ_ij W_ij (∂R/∂t)_ij`,  `W = R⁻¹ − γγᵀ/σ²`,
    ///
    /// with `γ = R⁻¹(y − Fβ)`. The trace needs R⁻¹ itself (no solve gives
    /// it), formed from the Cholesky factor as `C⁻ᵀC⁻¹` (lower triangle, one
    /// extra m × m buffer, m³/3 + m³/3 flops next to the factorisation's
    /// m³/3). The d derivative matrices are never formed: with
    /// `∂R/∂ln ξ_k = q ∘ ξ_k D_k` (`D_k` the squared differences of input k;
    /// the correlation model gives `−q`,
    /// [`CorrelationModel::gradient_weights`]), `P = W ∘ (−q)` is written
    /// over R⁻¹'s strict lower triangle and `Σ_{i>j} P_ij D_k,ij` for every
    /// k comes from one product `Pᵀ[X², X, 1]` (`super::dense::pair_sq_diff_sums`).
    /// For the nugget, `∂R/∂ln ν = νI`. The jitter ε is held constant.
    /// Allocates O(m·d).
    pub fn psi_grad(
        &self,
        theta: &[f64],
        nugget: f64,
        ws: &mut Workspace,
        grad: &mut [f64],
    ) -> Result<PsiValue> {
        let m = self.m();
        let p = self.f.ncols();
        let d = theta.len();
        assert!(grad.len() == d || grad.len() == d + 1, "gradient length");
        let v = self.psi(theta, nugget, ws)?;
        let (_, beta) = gls_beta(&ws.aug, p);
        let e = self.residual(&beta);
        // R⁻¹ (lower) = C⁻ᵀ C⁻¹, written over the factor in ws.r
        super::dense::inverse_from_cholesky(&mut ws.r, &mut ws.cinv, &mut ws.scratch, ws.par);
        let rinv = &ws.r;
        // γ = R⁻¹ e from the lower triangle
        let mut gamma = vec![0.0; m];
        for j in 0..m {
            let col = &rinv
                .col(j)
                .try_as_col_major()
                .expect("contiguous")
                .as_slice()[j + 1..];
            let ej = e[j];
            super::dense::axpy(&mut gamma[j + 1..], ej, col);
            gamma[j] += rinv[(j, j)] * ej + super::dense::dot(col, &e[j + 1..]);
        }
        let inv_s2 = 1.0 / v.sigma2;
        let tr: f64 = (0..m).map(|i| rinv[(i, i)]).sum();
        // P = (R⁻¹ − γγᵀ/σ²) ∘ (−q) over R⁻¹'s strict lower triangle
        for j in 0..m {
            let rc = &ws
                .base
                .col(j)
                .try_as_col_major()
                .expect("contiguous")
                .as_slice()[j + 1..];
            let p = &mut ws
                .r
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous")
                .as_slice_mut()[j + 1..];
            super::dense::axpy(p, -gamma[j] * inv_s2, &gamma[j + 1..]);
            self.corr.gradient_weights(theta, self.inputs, j, rc, p);
        }
        super::dense::pair_sq_diff_sums(ws.r.as_mut(), self.inputs, &mut grad[..d]);
        // ∂/∂ln ξ_k = −ξ_k Σ_{i>j} P D_k; symmetric: Σ_ij = 2 Σ_{i>j};
        // d/dlog10 = ln 10 · d/dln
        let scale = -2.0 * std::f64::consts::LN_10 / m as f64;
        for (g, t) in grad[..d].iter_mut().zip(theta) {
            *g *= scale * t;
        }
        if grad.len() == d + 1 {
            let gg: f64 = gamma.iter().map(|g| g * g).sum();
            grad[d] = std::f64::consts::LN_10 * nugget * (tr - gg * inv_s2) / m as f64;
        }
        Ok(v)
    }

    /// Full solution at ξ: C, G, β, γ (eqs 10–13). Unlike [`Self::psi`] it
    /// accepts σ² = 0 (a response the trend reproduces exactly).
    ///
    /// Holds one m × m matrix (the factor, filled in place and refilled for
    /// the next jitter rung if the Cholesky fails: the same ladder as
    /// [`Self::psi`]'s, and below [`PAR_MIN_ROWS`] rows the same bits), so
    /// that campaigns of ten thousand rows fit in memory; from
    /// [`PAR_MIN_ROWS`] rows the factorisation uses all threads.
    pub fn solve(&self, theta: &[f64], nugget: f64) -> Result<Solution> {
        let m = self.m();
        let p = self.f.ncols();
        let par = par_for(m);
        let eps0 = self.min_jitter.unwrap_or((10.0 + m as f64) * f64::EPSILON);
        let max_rung = (MAX_JITTER / eps0).log10().floor() as usize;
        let mut factored = None;
        for k in 0..=max_rung {
            let jitter = eps0 * 10f64.powi(k as i32);
            if let Ok(c) = factor_at(self.corr, self.inputs, theta, nugget, jitter) {
                factored = Some((c, jitter));
                break;
            }
        }
        let Some((c, jitter)) = factored else {
            return Err(Error::Numerical(format!(
                "correlation matrix not positive definite even with jitter {MAX_JITTER:e} (duplicate poses? try a nugget)"
            )));
        };
        let mut aug = Mat::zeros(m, p + 1);
        let (mut qcoef, mut mem) = qr_buffers(m, p + 1);
        let (ln_det_r, sigma2) = self.trend_qr(c.as_ref(), &mut aug, &mut qcoef, &mut mem, par);
        let value = PsiValue {
            ln_psi: ln_det_r / m as f64 + sigma2.ln(),
            sigma2,
            ln_det_r,
            jitter,
        };
        let (g, beta) = if self.prior.iter().any(|b| *b != CoefficientPrior::Flat) {
            self.posterior_beta(&aug, sigma2)
        } else {
            gls_beta(&aug, p)
        };
        // γ = C⁻ᵀ C⁻¹ (y − Fβ)
        let e = self.residual(&beta);
        let mut resid = faer::Col::from_fn(m, |i| e[i]);
        solve_lower_triangular_in_place(c.as_ref(), resid.as_mat_mut(), par);
        solve_upper_triangular_in_place(c.transpose(), resid.as_mat_mut(), par);
        Ok(Solution {
            value,
            c,
            g,
            beta,
            gamma: resid.iter().copied().collect(),
            ftilde: None,
        })
    }
}

impl KrigingProblem<'_> {
    /// Bayesian universal Kriging's trend at this ξ: with the prior
    /// `β_j ~ N(0, τ_j²)` on the columns with one (`τ_j = ‖y‖/max(‖F_j‖, n_j)`,
    /// precision `Λ = diag(1/τ_j²)`, 0 elsewhere), the posterior mean and
    /// covariance of β are
    ///
    /// ```text
    /// β = (F̃ᵀF̃ + σ²Λ)⁻¹ F̃ᵀỹ,     Cov(β | y) = σ² (F̃ᵀF̃ + σ²Λ)⁻¹,
    /// ```
    ///
    /// i.e. the GLS (seed 003 eq 11) of `[F̃; σΛ^{1/2}] β ≈ [ỹ; 0]`, and the
    /// same as adding `F Σβ Fᵀ` to the covariance of y (O'Hagan 1978;
    /// Helbert, Dupuy & Carraro 2009, "Assessment of uncertainty in computer
    /// experiments from Universal to Bayesian Kriging"). Since `[F̃ ỹ]` is
    /// already `Q [G b; 0 ρ]`, the augmented QR is that of the small
    /// `[G b; σΛ^{1/2} 0]`. Returns the augmented G (so that the MSE, eq 12,
    /// the closed-form CV and the β standard errors use the posterior
    /// covariance) and β. σ² is the GLS one (ψ and the search are those of
    /// universal Kriging; the prior acts on the solution at the chosen ξ).
    /// Unflagged columns (the constant) keep a flat prior: no direction of
    /// the kinematic coefficients is unbounded, the mean is free.
    fn posterior_beta(&self, aug: &Mat<f64>, sigma2: f64) -> (Mat<f64>, Vec<f64>) {
        let p = self.f.ncols();
        let y_norm = self.y.iter().map(|v| v * v).sum::<f64>().sqrt();
        let sigma = sigma2.sqrt();
        let rows: Vec<(usize, f64)> = (0..p)
            .filter_map(|j| match self.prior.get(j) {
                Some(CoefficientPrior::Norm(n)) => Some((j, *n)),
                _ => None,
            })
            .filter_map(|(j, n)| {
                let fj = self
                    .f
                    .col(j)
                    .iter()
                    .map(|v| v * v)
                    .sum::<f64>()
                    .sqrt()
                    .max(n);
                (fj > 0.0 && y_norm > 0.0).then(|| (j, sigma * fj / y_norm))
            })
            .collect();
        let n = p + rows.len();
        let mut small = Mat::<f64>::zeros(n, p + 1);
        for i in 0..p {
            for j in i..=p {
                small[(i, j)] = aug[(i, j)];
            }
        }
        for (k, (j, w)) in rows.iter().enumerate() {
            small[(p + k, *j)] = *w;
        }
        let (mut qcoef, mut mem) = qr_buffers(n, p + 1);
        qr_in_place(
            small.as_mut(),
            qcoef.as_mut(),
            Par::Seq,
            MemStack::new(&mut mem),
            Default::default(),
        );
        gls_beta(&small, p)
    }
}

/// The Householder coefficients and the scratch of a sequential QR of a
/// `rows × cols` matrix ([`qr_in_place`]).
fn qr_buffers(rows: usize, cols: usize) -> (Mat<f64>, MemBuffer) {
    let bs = recommended_block_size::<f64>(rows, cols);
    let qcoef = Mat::zeros(bs, cols.min(rows));
    let mem = MemBuffer::new(qr_in_place_scratch::<f64>(
        rows,
        cols,
        bs,
        Par::Seq,
        Default::default(),
    ));
    (qcoef, mem)
}

/// G and `β = G⁻¹ b` (eq 11) from the QR of `[F̃ ỹ]` held in `aug`
/// ([`KrigingProblem::trend_qr`]).
fn gls_beta(aug: &Mat<f64>, p: usize) -> (Mat<f64>, Vec<f64>) {
    let g = Mat::<f64>::from_fn(p, p, |i, j| if i <= j { aug[(i, j)] } else { 0.0 });
    let mut b = faer::Col::from_fn(p, |i| aug[(i, p)]);
    solve_upper_triangular_in_place(g.as_ref(), b.as_mat_mut(), Par::Seq);
    (g, b.iter().copied().collect())
}

/// From this many rows a single factorisation ([`KrigingProblem::solve`],
/// [`factor_at`]) uses all threads; below, one (the callers run outputs and
/// starts in parallel). The choice depends on m alone, so a factor
/// recomputed after loading a model is the fit's, bit for bit.
pub const PAR_MIN_ROWS: usize = 2048;

fn par_for(m: usize) -> Par {
    if m >= PAR_MIN_ROWS {
        Par::rayon(0)
    } else {
        Par::Seq
    }
}

/// The lower Cholesky factor C of `R + (ν + ε)I` at a known jitter ε, filled
/// and factorised exactly as during the fit, so the factor is bit-identical
/// to the fit's (saved models keep ξ, ν, ε and the inputs, not C: O(m·d)
/// instead of O(m²)). Upper triangle zero. One m × m allocation.
pub fn factor_at(
    corr: &dyn CorrelationModel,
    inputs: &TrainingInputs,
    theta: &[f64],
    nugget: f64,
    jitter: f64,
) -> Result<Mat<f64>> {
    let m = inputs.m;
    let par = par_for(m);
    let mut c = Mat::<f64>::zeros(m, m);
    inputs.fill_lower(corr, theta, nugget, c.as_mut());
    for i in 0..m {
        c[(i, i)] += jitter;
    }
    if !super::dense::cholesky_lower(c.as_mut(), par) {
        return Err(Error::Numerical(format!(
            "correlation matrix not positive definite at the saved ξ, ν = {nugget:e} and jitter {jitter:e}"
        )));
    }
    for j in 0..m {
        for i in 0..j {
            c[(i, j)] = 0.0;
        }
    }
    Ok(c)
}

/// ln ψ as stored in reports and model files: −∞ (a response the trend
/// reproduces exactly, σ² = 0) becomes `f64::MIN`, since JSON has no
/// infinities and a saved model must load back.
pub fn storable_ln_psi(v: f64) -> f64 {
    if v.is_finite() { v } else { f64::MIN }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kriging::corr::Correlation;

    /// The posterior β of one column of `f` under each prior, at fixed ξ and
    /// a nugget: y = 0.5·f₁ + a smooth bump, with `f₁` small on these rows.
    fn beta_1(prior: &[CoefficientPrior]) -> f64 {
        let m = 40;
        let x: Vec<Vec<f64>> = (0..m).map(|i| vec![i as f64 / m as f64]).collect();
        let f = Mat::<f64>::from_fn(m, 2, |i, j| if j == 0 { 1.0 } else { 0.01 * x[i][0] });
        let y: Vec<f64> = (0..m)
            .map(|i| 0.5 * f[(i, 1)] + (6.0 * x[i][0]).sin())
            .collect();
        let inputs = TrainingInputs::new(&x);
        let corr = Correlation::Gaussian;
        let prob = KrigingProblem {
            min_jitter: None,
            corr: &corr,
            inputs: &inputs,
            f: &f,
            y: &y,
            prior,
        };
        prob.solve(&[3.0], 0.05).unwrap().beta[1]
    }

    /// A coefficient's prior is no wider than the whole response over the
    /// larger of its column's norm and the given one: a term this axis
    /// sees weakly (a small column) but that moves the TCP on the others
    /// (a large given norm) is held near 0; the flat prior leaves it free.
    #[test]
    fn a_larger_given_norm_tightens_the_prior() {
        use CoefficientPrior::{Flat, Norm};
        let free = beta_1(&[Flat, Flat]);
        let own = beta_1(&[Flat, Norm(0.0)]);
        let wide_axis = beta_1(&[Flat, Norm(1e-6)]);
        let tight = beta_1(&[Flat, Norm(10.0)]);
        // a norm below the column's own changes nothing
        assert_eq!(own, wide_axis);
        assert!(
            free.abs() > own.abs() && own.abs() > 10.0 * tight.abs(),
            "{free} {own} {tight}"
        );
    }
}
