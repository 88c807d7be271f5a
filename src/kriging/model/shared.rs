//! Trend coefficients shared by several outputs. One kinematic parameter
//! error moves the TCP along x, y and z at once: it is one unknown, seen by
//! three outputs, not three (a β per axis lets each axis explain its own
//! data with its own parameter errors, which on a region of the joint space
//! no axis saw extrapolate three ways).
//!
//! Each output `a` keeps what its own universal-Kriging fit chose: ξ, ν,
//! the family, and σ_a² (the GLS one, as in Bayesian universal Kriging,
//! [`crate::kriging::KrigingProblem::solve`]). The coefficients are then the
//! posterior mean of the stacked generalised least squares
//!
//! ```text
//! min  Σ_a ‖ỹ_a − F̃_a β_a‖² / σ_a²  +  ‖P δ‖²
//! ```
//!
//! where `F̃_a = C_a⁻¹F_a`, `ỹ_a = C_a⁻¹y_a` (seed 003 eq 11 per output), a
//! coefficient of output `a` with key κ ([`TrendModel::shared_key`]) is
//! `δ_κ / y_std_a` (the outputs are z-scored separately; δ is in the
//! response's units) and the outputs' other coefficients (the constant) are
//! their own. With each output's QR `[F̃_a ỹ_a] = Q_a [G_a b_a; 0 ρ_a]` the
//! m rows of an output reduce to its p_a rows, so the stacked system is
//! small.
//!
//! **The prior** of δ_κ is over all outputs: `τ_κ = ‖Y‖ / max(‖F_κ‖, √k·n_κ)`
//! with `Y` the stacked centred responses, `F_κ` the stacked columns of κ,
//! `k` the outputs that see it and `n_κ` its [`CoefficientPrior::Norm`]: no
//! parameter alone explains more than the whole response (Helbert, Dupuy &
//! Carraro 2009; O'Hagan 1978). **The directions the campaign does not
//! see** are held at 0, as the calibration holds them at their nominal
//! value (its identifiability rule, see [`prior_rows`]).
//!
//! **Uncertainty.** The marginal posterior of output `a`'s coefficients is
//! read off a QR of the stacked system with β_a's columns last: its
//! trailing block `R₂₂` gives `Cov(β_a | Y) = (R₂₂ᵀR₂₂)⁻¹` (no inverse
//! formed). With `G := σ_a R₂₂` the output's MSE (eq 12), closed-form CV
//! and standard errors use it unchanged; for the closed-form CV what the
//! other outputs say of β_a acts as a prior (leaving a row of output `a`
//! out does not remove the same row of the other outputs).
//!
//! **Not least squares.** Weighting the rows by `R_a⁻¹` lets the correlated
//! process take part of what differs between regions of a campaign (its
//! ISO cubes, say), which spatial statistics calls the confounding of fixed
//! effects with a correlated random effect (Hodges & Reich 2010). Its
//! remedy, least squares for the coefficients and the process on the
//! residual (restricted spatial regression), was measured here: it brings
//! the one cube of the ABB stress campaign where GLS is 1.8× the D-H
//! calibration down to 1.06×, but puts the EJS models 1.75–1.83× off on
//! random folds of the harmonic UR10 campaigns and their 95 % intervals
//! over 0.98 (`docs/BENCHMARKS.md`, stress campaigns). GLS stays.

use super::KrigingModel;
use crate::kriging::problem::{PsiValue, Solution};
use crate::kriging::trend::{CoefficientPrior, Trend, TrendModel, trend_matrix};
use crate::{Error, Result};
use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::qr::no_pivoting::factor::{
    qr_in_place, qr_in_place_scratch, recommended_block_size,
};
use faer::linalg::triangular_solve::{
    solve_lower_triangular_in_place, solve_upper_triangular_in_place,
};
use faer::{Mat, Par};

/// One unknown of the stacked system: an output's own coefficient (output,
/// column) or a shared one (key).
#[derive(Debug, Clone, Copy, PartialEq)]
enum Unknown {
    Own(usize, usize),
    Shared(usize),
}

/// What the stacked system needs of one output: its GLS reduced to p rows.
struct Reduced {
    /// Upper-triangular G of `F̃ = QG` (no prior).
    g: Mat<f64>,
    /// `b = Qᵀỹ`.
    b: Vec<f64>,
    /// σ (GLS, normalised units).
    sigma: f64,
    /// Each column's key, if shared.
    keys: Vec<Option<usize>>,
    /// Each column's prior ([`TrendModel::prior`]).
    priors: Vec<CoefficientPrior>,
    /// ‖F_j‖ on the training rows.
    col_norm: Vec<f64>,
    /// ‖y‖ of the normalised response.
    y_norm: f64,
    /// The response's scale (original units per normalised unit).
    y_std: f64,
    /// `F̃ = C⁻¹F` (m × p), for the model's γ and kept factors.
    ftilde: Mat<f64>,
    /// `ỹ = C⁻¹y`, normalised.
    ytilde: Vec<f64>,
}

/// The outputs `models` (fitted on the same training inputs) with the
/// coefficients their trends share ([`TrendModel::shared_key`]) solved
/// jointly, `trends[a]` being output a's whole trend and `ys[a]` its
/// response in original units. A fit drops the trend columns that are
/// linearly dependent on its own output's rows; a shared column dropped on
/// one output is still a parameter the others identify, and it moves this
/// output too, so each output's model gets its whole trend back. ξ, ν, the
/// family, σ² and the factor C of every output are kept; β, γ and G change
/// (see the module doc). Models without a shared coefficient are returned
/// as they are.
pub fn share_coefficients(
    models: Vec<KrigingModel>,
    trends: &[&Trend],
    ys: &[&[f64]],
) -> Result<Vec<KrigingModel>> {
    if ys.len() != models.len() || trends.len() != models.len() {
        return Err(Error::InvalidParameter(format!(
            "{} trends and {} responses for {} outputs",
            trends.len(),
            ys.len(),
            models.len()
        )));
    }
    let any_shared = trends.iter().any(|t| t.has_shared());
    // a constant output (σ² = 0) has nothing to weigh its rows by
    if !any_shared || models.iter().any(|k| k.data.sigma2 <= 0.0) {
        return Ok(models);
    }
    let reduced: Vec<Reduced> = models
        .iter()
        .zip(trends)
        .zip(ys)
        .map(|((k, t), y)| k.reduced(t, y))
        .collect::<Result<_>>()?;
    let unknowns = unknowns(&reduced);
    let prior = prior_rows(&reduced, &unknowns, &priors(&reduced, &unknowns));
    let solved: Vec<(Vec<f64>, Mat<f64>)> = (0..reduced.len())
        .map(|a| marginal(&reduced, &unknowns, &prior, a))
        .collect::<Result<_>>()?;
    models
        .into_iter()
        .zip(reduced)
        .zip(solved)
        .zip(trends)
        .map(|(((k, r), (beta, g)), t)| k.with_coefficients(t, r, beta, g))
        .collect()
}

impl KrigingModel {
    /// The output's GLS with the trend `trend` reduced to its p rows: the
    /// QR of `[F̃ ỹ]`.
    fn reduced(&self, trend: &Trend, y: &[f64]) -> Result<Reduced> {
        let d = &self.data;
        let (m, p) = (d.x_train.len(), trend.len());
        if trend.dim() != d.trend.dim() {
            return Err(Error::InvalidParameter(format!(
                "a trend of {} inputs for a model of {}",
                trend.dim(),
                d.trend.dim()
            )));
        }
        if y.len() != m {
            return Err(Error::InvalidParameter(format!(
                "{} responses for {m} training rows",
                y.len()
            )));
        }
        let yn: Vec<f64> = y.iter().map(|v| (v - d.y_mean) / d.y_std).collect();
        let f = trend_matrix(trend, &d.x_train);
        // w = C⁻¹[F y]
        let w = self.with_factors(|c, _, _| {
            let mut w = Mat::<f64>::from_fn(m, p + 1, |i, j| if j < p { f[(i, j)] } else { yn[i] });
            solve_lower_triangular_in_place(c.as_ref(), w.as_mut(), Par::Seq);
            Ok(w)
        })?;
        // fewer rows than columns: zero rows below leave the least squares
        // as they are and give the QR its p + 1 rows
        let mut aug = Mat::<f64>::zeros(m.max(p + 1), p + 1);
        aug.as_mut().subrows_mut(0, m).copy_from(w.as_ref());
        qr(&mut aug);
        Ok(Reduced {
            g: Mat::from_fn(p, p, |i, j| if i <= j { aug[(i, j)] } else { 0.0 }),
            b: (0..p).map(|i| aug[(i, p)]).collect(),
            sigma: d.sigma2.sqrt(),
            keys: (0..p).map(|j| trend.shared_key(j)).collect(),
            priors: (0..p).map(|j| trend.prior(j)).collect(),
            col_norm: (0..p)
                .map(|j| f.col(j).iter().map(|v| v * v).sum::<f64>().sqrt())
                .collect(),
            y_norm: yn.iter().map(|v| v * v).sum::<f64>().sqrt(),
            y_std: d.y_std,
            ftilde: w.subcols(0, p).to_owned(),
            ytilde: (0..m).map(|i| w[(i, p)]).collect(),
        })
    }

    /// This output with the trend `trend` (reduced to `r`), its
    /// coefficients β and factor G (normalised units): `γ = C⁻ᵀ(ỹ − F̃β)`;
    /// ξ, ν, σ², ln ψ and C as they were.
    fn with_coefficients(
        self,
        trend: &Trend,
        r: Reduced,
        beta: Vec<f64>,
        g: Mat<f64>,
    ) -> Result<Self> {
        let d = &self.data;
        let m = d.x_train.len();
        let (ft, yt) = (&r.ftilde, &r.ytilde);
        let (c, gamma) = self.with_factors(|c, _, _| {
            let mut e = Mat::from_fn(m, 1, |i, _| {
                yt[i] - (0..beta.len()).map(|j| ft[(i, j)] * beta[j]).sum::<f64>()
            });
            solve_upper_triangular_in_place(c.transpose(), e.as_mut(), Par::Seq);
            Ok((c.clone(), (0..m).map(|i| e[(i, 0)]).collect::<Vec<_>>()))
        })?;
        let ln_det_r = 2.0 * (0..m).map(|i| c[(i, i)].ln()).sum::<f64>();
        let sol = Solution {
            value: PsiValue {
                ln_psi: d.ln_psi,
                sigma2: d.sigma2,
                ln_det_r,
                jitter: d.jitter,
            },
            c,
            g,
            beta,
            gamma,
            ftilde: Some(r.ftilde),
        };
        let d = self.data;
        KrigingModel::from_solution(
            sol,
            trend.clone(),
            d.corr,
            d.theta,
            d.nugget,
            d.x_train,
            d.y_mean,
            d.y_std,
        )
    }
}

/// Every output's own columns, then the shared keys (ascending).
fn unknowns(reduced: &[Reduced]) -> Vec<Unknown> {
    let mut out = Vec::new();
    let mut keys = Vec::new();
    for (a, r) in reduced.iter().enumerate() {
        for (j, key) in r.keys.iter().enumerate() {
            match key {
                Some(k) => keys.push(*k),
                None => out.push(Unknown::Own(a, j)),
            }
        }
    }
    keys.sort_unstable();
    keys.dedup();
    out.extend(keys.into_iter().map(Unknown::Shared));
    out
}

/// The prior precision `1/τ` of each unknown that has one, in the
/// unknown's own units (normalised for an own coefficient, the response's
/// units for a shared one): see the module doc.
fn priors(reduced: &[Reduced], unknowns: &[Unknown]) -> Vec<Option<f64>> {
    // ‖Y‖², the stacked centred responses in their units
    let y2: f64 = reduced.iter().map(|r| (r.y_norm * r.y_std).powi(2)).sum();
    unknowns
        .iter()
        .map(|u| match *u {
            Unknown::Own(a, j) => {
                let r = &reduced[a];
                let CoefficientPrior::Norm(n) = r.priors[j] else {
                    return None;
                };
                let fj = r.col_norm[j].max(n);
                (fj > 0.0 && r.y_norm > 0.0).then(|| fj / r.y_norm)
            }
            Unknown::Shared(key) => {
                let (mut f2, mut n, mut seen) = (0.0f64, 0.0f64, 0.0f64);
                for r in reduced {
                    if let Some(j) = r.column_of(key) {
                        f2 += r.col_norm[j].powi(2);
                        seen += 1.0;
                        if let CoefficientPrior::Norm(v) = r.priors[j] {
                            n = n.max(v);
                        }
                    }
                }
                let f = f2.sqrt().max(seen.sqrt() * n);
                (f > 0.0 && y2 > 0.0).then(|| f / y2.sqrt())
            }
        })
        .collect()
}

impl Reduced {
    fn column_of(&self, key: usize) -> Option<usize> {
        self.keys.iter().position(|k| *k == Some(key))
    }
}

/// Precision, relative to its prior, of the prior that holds a direction
/// of the shared coefficients that the data do not see at 0: the direction
/// is fixed (as the calibration fixes it at its nominal value), with G
/// still invertible.
const FIXED_PRECISION: f64 = 1e8;

/// The prior as rows over the unknowns (in their own units): `1/τ` on the
/// diagonal of each unknown that has one, and, on the shared unknowns, the
/// directions the data do not see held at 0.
///
/// The seen directions are those of the calibration's rule
/// ([`crate::calibration`]'s identifiability): in prior units `w = δ/τ`,
/// with the outputs' own coefficients eliminated (the trailing block
/// `R_ss` of the stacked data's QR, whose Gram matrix is the Schur
/// complement), a direction `v_i` of the SVD `R_ss diag(τ) = U Σ Vᵀ` is
/// seen when `σ_i > 1`: the data determine it better than the prior does
/// (the rows are whitened: unit noise). The others get the prior
/// precision `1 + FIXED_PRECISION` instead of 1, i.e. the rows
/// `(I + (√(1 + FIXED_PRECISION) − 1) V_u V_uᵀ) diag(1/τ)`.
fn prior_rows(reduced: &[Reduced], unknowns: &[Unknown], prior: &[Option<f64>]) -> Mat<f64> {
    let n = unknowns.len();
    let diag: Vec<(usize, f64)> = prior
        .iter()
        .enumerate()
        .filter_map(|(i, w)| w.map(|w| (i, w)))
        .collect();
    let mut rows = Mat::<f64>::zeros(diag.len(), n);
    for (r, &(i, w)) in diag.iter().enumerate() {
        rows[(r, i)] = w;
    }
    let shared: Vec<usize> = (0..n)
        .filter(|&i| matches!(unknowns[i], Unknown::Shared(_)))
        .collect();
    // every shared unknown needs a prior scale to be compared with
    if shared.is_empty() || shared.iter().any(|&i| prior[i].is_none()) {
        return rows;
    }
    let natural: Vec<(usize, f64)> = (0..n).map(|i| (i, 1.0)).collect();
    let mut s = stacked(reduced, unknowns, &natural, None);
    qr(&mut s);
    let (k, n0) = (shared.len(), shared[0]);
    // R_ss in prior units: column j times τ_j
    let rss = Mat::<f64>::from_fn(k, k, |i, j| {
        if i <= j {
            s[(n0 + i, n0 + j)] / prior[n0 + j].expect("a prior")
        } else {
            0.0
        }
    });
    let Ok(svd) = rss.thin_svd() else {
        return rows;
    };
    let (sv, v) = (svd.S(), svd.V());
    // (a NaN singular value counts as unseen)
    let unseen: Vec<usize> = (0..k).filter(|&i| sv[i].is_nan() || sv[i] <= 1.0).collect();
    if unseen.is_empty() {
        return rows;
    }
    let lift = (1.0 + FIXED_PRECISION).sqrt() - 1.0;
    // the shared rows are diag(1/τ) so far: add lift · V_u V_uᵀ diag(1/τ)
    for (r, &(i, _)) in diag.iter().enumerate() {
        let Some(a) = shared.iter().position(|&u| u == i) else {
            continue;
        };
        for (b, &j) in shared.iter().enumerate() {
            let vv: f64 = unseen.iter().map(|&c| v[(a, c)] * v[(b, c)]).sum();
            rows[(r, j)] += lift * vv * prior[j].expect("a prior");
        }
    }
    rows
}

/// The stacked system `[A | rhs]` with the unknowns in `order` (index into
/// `unknowns`, scale: the column's unknown is the natural one divided by
/// it): each output's rows `(G, b)/σ`, then the prior's rows if given.
fn stacked(
    reduced: &[Reduced],
    unknowns: &[Unknown],
    order: &[(usize, f64)],
    prior: Option<&Mat<f64>>,
) -> Mat<f64> {
    let n = unknowns.len();
    let data: usize = reduced.iter().map(|r| r.keys.len()).sum();
    let rows = data + prior.map_or(0, Mat::nrows);
    let mut s = Mat::<f64>::zeros(rows.max(n + 1), n + 1);
    let mut r0 = 0;
    for (b, r) in reduced.iter().enumerate() {
        let p = r.keys.len();
        for (c, &(u, scale)) in order.iter().enumerate() {
            let (j, unit) = match unknowns[u] {
                Unknown::Own(ob, j) if ob == b => (j, 1.0),
                Unknown::Shared(k) => match r.column_of(k) {
                    Some(j) => (j, 1.0 / r.y_std),
                    None => continue,
                },
                Unknown::Own(..) => continue,
            };
            for i in 0..p {
                s[(r0 + i, c)] = r.g[(i, j)] * unit * scale / r.sigma;
            }
        }
        for i in 0..p {
            s[(r0 + i, n)] = r.b[i] / r.sigma;
        }
        r0 += p;
    }
    if let Some(prior) = prior {
        for i in 0..prior.nrows() {
            for (c, &(u, scale)) in order.iter().enumerate() {
                s[(r0 + i, c)] = prior[(i, u)] * scale;
            }
        }
    }
    s
}

/// For each of output b's columns, its unknown and the factor from the
/// unknown's natural units to the column's coefficient (1 for its own,
/// `1/y_std_b` for a shared one).
fn selection(rb: &Reduced, b: usize, unknowns: &[Unknown]) -> Vec<(usize, f64)> {
    rb.keys
        .iter()
        .enumerate()
        .map(|(j, key)| {
            let u = match key {
                Some(k) => Unknown::Shared(*k),
                None => Unknown::Own(b, j),
            };
            let i = unknowns.iter().position(|v| *v == u).expect("an unknown");
            (i, if key.is_some() { 1.0 / rb.y_std } else { 1.0 })
        })
        .collect()
}

/// Output a's coefficients (normalised units) and G of their marginal
/// posterior: the QR of the stacked system with a's columns last.
fn marginal(
    reduced: &[Reduced],
    unknowns: &[Unknown],
    prior: &Mat<f64>,
    a: usize,
) -> Result<(Vec<f64>, Mat<f64>)> {
    let ra = &reduced[a];
    let mine = selection(ra, a, unknowns);
    let pa = mine.len();
    // the others, then a's columns in its trend's order, each in a's own
    // normalised units (the natural unknown is the coefficient / factor)
    let order: Vec<(usize, f64)> = (0..unknowns.len())
        .filter(|i| !mine.iter().any(|(u, _)| u == i))
        .map(|i| (i, 1.0))
        .chain(mine.iter().map(|&(u, f)| (u, 1.0 / f)))
        .collect();
    let n = unknowns.len();
    let mut s = stacked(reduced, unknowns, &order, Some(prior));
    qr(&mut s);
    let rr = Mat::<f64>::from_fn(n, n, |i, j| if i <= j { s[(i, j)] } else { 0.0 });
    if (0..n).any(|i| rr[(i, i)] == 0.0 || !rr[(i, i)].is_finite()) {
        return Err(Error::Numerical(
            "shared trend coefficients: a coefficient is neither seen nor given a prior".into(),
        ));
    }
    let mut z = Mat::from_fn(n, 1, |i, _| s[(i, n)]);
    solve_upper_triangular_in_place(rr.as_ref(), z.as_mut(), Par::Seq);
    let t = n - pa;
    let beta = (t..n).map(|i| z[(i, 0)]).collect();
    let g = Mat::from_fn(pa, pa, |i, j| {
        if i <= j {
            ra.sigma * rr[(t + i, t + j)]
        } else {
            0.0
        }
    });
    Ok((beta, g))
}

/// Householder QR of `a` in place (R on and above the diagonal).
fn qr(a: &mut Mat<f64>) {
    let (rows, cols) = (a.nrows(), a.ncols());
    let bs = recommended_block_size::<f64>(rows, cols);
    let mut qcoef = Mat::<f64>::zeros(bs, cols.min(rows));
    let mut mem = MemBuffer::new(qr_in_place_scratch::<f64>(
        rows,
        cols,
        bs,
        Par::Seq,
        Default::default(),
    ));
    qr_in_place(
        a.as_mut(),
        qcoef.as_mut(),
        Par::Seq,
        MemStack::new(&mut mem),
        Default::default(),
    );
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kriging::trend::{KinematicTrend, Monomials, Trend};
    use crate::kriging::{Hyperparameters, KrigingParams, Tuning};
    use nalgebra::{DMatrix, DVector};
    use rand::{RngExt, SeedableRng};

    /// Three outputs of the UR10's kinematic trend on `m` random poses:
    /// the error of a random parameter vector plus a smooth term per axis
    /// and noise; fitted per output at fixed ξ, ν.
    fn fitted(
        m: usize,
        shared: bool,
        narrow: bool,
    ) -> (Vec<KrigingModel>, Vec<Trend>, Vec<Vec<f64>>) {
        let robot = crate::kinematics::preset("ur10").unwrap();
        let n = robot.dof();
        let mut rng = rand::rngs::StdRng::seed_from_u64(7);
        let q: Vec<Vec<f64>> = (0..m)
            .map(|_| {
                (0..n)
                    .map(|_| {
                        if narrow {
                            rng.random_range(20.0..50.0)
                        } else {
                            rng.random_range(-120.0..120.0)
                        }
                    })
                    .collect()
            })
            .collect();
        let (mean, std) = (vec![0.0; n], vec![60.0; n]);
        let x: Vec<Vec<f64>> = q
            .iter()
            .map(|r| r.iter().map(|v| v / 60.0).collect())
            .collect();
        let np = crate::kinematics::calib_len(n);
        // a few parameters over the wide range; all of them over the narrow
        // one, which does not see every direction
        let params: Vec<usize> = if narrow {
            (0..np).collect()
        } else {
            (0..np).step_by(3).take(9).collect()
        };
        let delta: Vec<f64> = params
            .iter()
            .map(|_| rng.random_range(-0.01..0.01))
            .collect();
        let param_norm = vec![1.0; np];
        let trend = |axis: usize| {
            Trend::Kinematic(Box::new(KinematicTrend {
                robot: robot.clone(),
                axis,
                params: params.clone(),
                joint_mean: mean.clone(),
                joint_std: std.clone(),
                periodic: Vec::new(),
                poly: Monomials::constant(n),
                param_norm: param_norm.clone(),
                shared,
            }))
        };
        let ys: Vec<Vec<f64>> = (0..3)
            .map(|a| {
                q.iter()
                    .map(|r| {
                        let j = crate::kinematics::identification_jacobian_cols(&robot, r, &params);
                        let k: f64 = j[a].iter().zip(&delta).map(|(u, d)| u * d).sum();
                        k + 0.05 * (r[1] / 40.0 + a as f64).sin()
                            + 0.01 * rng.random_range(-1.0..1.0)
                    })
                    .collect()
            })
            .collect();
        let models = (0..3)
            .map(|a| {
                KrigingParams::new(trend(a))
                    .tuning(Tuning::Fixed(Hyperparameters::new(vec![0.3; n], 0.05)))
                    .check()
                    .unwrap()
                    .fit(&x, &ys[a])
                    .unwrap()
                    .0
            })
            .collect();
        (models, (0..3).map(trend).collect(), ys)
    }

    #[test]
    fn shared_coefficients_are_the_stacked_gls_and_its_marginal_posterior() {
        // wide: every direction seen; narrow: some held at 0
        assert_eq!(check_shared(false), 0);
        assert!(check_shared(true) > 0);
    }

    /// [`share_coefficients`] against the brute force on [`fitted`]; the
    /// number of directions held at 0.
    fn check_shared(narrow: bool) -> usize {
        let (models, trends, ys) = fitted(60, true, narrow);
        let refs: Vec<&[f64]> = ys.iter().map(Vec::as_slice).collect();
        let tr: Vec<&Trend> = trends.iter().collect();
        let shared = share_coefficients(models.clone(), &tr, &refs).unwrap();
        // the brute force: unknowns (own constants of x, y, z, then the
        // shared parameters in mm), explicit R⁻¹ and normal equations
        let p: Vec<usize> = trends.iter().map(|t| t.len()).collect();
        let keys: Vec<usize> = {
            let mut k: Vec<usize> = trends
                .iter()
                .flat_map(|t| (0..t.len()).filter_map(|j| t.shared_key(j)))
                .collect();
            k.sort_unstable();
            k.dedup();
            k
        };
        let nu = 3 + keys.len();
        let k_of = |t: &Trend, j: usize| keys.iter().position(|&v| Some(v) == t.shared_key(j));
        let mut normal = DMatrix::<f64>::zeros(nu, nu);
        let mut rhs = DVector::<f64>::zeros(nu);
        let mut maps = Vec::new();
        let (mut y2, mut f2) = (0.0, vec![0.0; keys.len()]);
        for (a, k) in models.iter().enumerate() {
            let d = &k.data;
            let trend = &trends[a];
            let m = d.x_train.len();
            assert!(trend.shared_key(0).is_none(), "the constant is own");
            // β_a = T_a z
            let mut t = DMatrix::<f64>::zeros(p[a], nu);
            t[(0, a)] = 1.0;
            for j in 1..p[a] {
                t[(j, 3 + k_of(trend, j).unwrap())] = 1.0 / d.y_std;
            }
            let f = trend_matrix(trend, &d.x_train);
            let f = DMatrix::from_fn(m, p[a], |i, j| f[(i, j)]);
            let (c, _, _) = k.factors().unwrap();
            let c = DMatrix::from_fn(m, m, |i, j| c[(i, j)]);
            let rinv = (&c * c.transpose()).try_inverse().unwrap() / d.sigma2;
            let yn = DVector::from_iterator(m, ys[a].iter().map(|v| (v - d.y_mean) / d.y_std));
            let ft = &f * &t;
            normal += ft.transpose() * &rinv * &ft;
            rhs += ft.transpose() * &rinv * &yn;
            y2 += (yn.norm() * d.y_std).powi(2);
            for j in 1..p[a] {
                f2[k_of(trend, j).unwrap()] += f.column(j).norm_squared();
            }
            maps.push(t);
        }
        // τ = ‖Y‖ / max(‖F_κ‖, √3 n_κ), n_κ = 1
        let tau: Vec<f64> = f2
            .iter()
            .map(|f2| y2.sqrt() / f2.sqrt().max(3f64.sqrt()))
            .collect();
        // the directions the data do not see (Schur complement of the
        // constants, in prior units, eigenvalue ≤ 1) are held at 0
        let ks = keys.len();
        let n_oo = normal.view((0, 0), (3, 3)).into_owned();
        let n_os = normal.view((0, 3), (3, ks)).into_owned();
        let schur = normal.view((3, 3), (ks, ks)).into_owned()
            - n_os.transpose() * n_oo.try_inverse().unwrap() * &n_os;
        let dt = DMatrix::from_diagonal(&DVector::from_vec(tau.clone()));
        let eig = (&dt * schur * &dt).symmetric_eigen();
        let mut prec = DMatrix::<f64>::identity(ks, ks);
        for i in 0..ks {
            if eig.eigenvalues[i] <= 1.0 {
                let v = eig.eigenvectors.column(i);
                prec += (v * v.transpose()) * FIXED_PRECISION;
            }
        }
        let held = (0..ks).filter(|&i| eig.eigenvalues[i] <= 1.0).count();
        let dinv = dt.try_inverse().unwrap();
        let pp = &dinv * prec * &dinv;
        let mut pfull = DMatrix::<f64>::zeros(nu, nu);
        pfull.view_mut((3, 3), (ks, ks)).copy_from(&pp);
        normal += &pfull;
        let ninv = normal.try_inverse().unwrap();
        let z = &ninv * &rhs;
        let cov = ninv;
        for (a, k) in shared.iter().enumerate() {
            let beta = &maps[a] * &z;
            let close = |u: f64, v: f64| (u - v).abs() <= 1e-7 * (1.0 + v.abs());
            for j in 0..p[a] {
                assert!(
                    close(k.data.beta[j], beta[j]),
                    "axis {a} β{j}: {} against {}",
                    k.data.beta[j],
                    beta[j]
                );
            }
            // σ²(GᵀG)⁻¹ is the marginal posterior covariance T_a N⁻¹ T_aᵀ
            let g = DMatrix::from_fn(p[a], p[a], |i, j| k.g[(i, j)]);
            let got = (g.transpose() * &g).try_inverse().unwrap() * k.data.sigma2;
            let want = &maps[a] * &cov * maps[a].transpose();
            for i in 0..p[a] {
                for j in 0..p[a] {
                    assert!(
                        (got[(i, j)] - want[(i, j)]).abs()
                            <= 1e-6 * want[(i, i)].abs().max(want[(j, j)].abs()),
                        "axis {a} cov ({i}, {j}): {} against {}",
                        got[(i, j)],
                        want[(i, j)]
                    );
                }
            }
        }
        held
    }

    #[test]
    fn models_without_shared_coefficients_are_returned_as_they_are() {
        let (models, trends, ys) = fitted(40, false, false);
        let refs: Vec<&[f64]> = ys.iter().map(Vec::as_slice).collect();
        let tr: Vec<&Trend> = trends.iter().collect();
        let out = share_coefficients(models.clone(), &tr, &refs).unwrap();
        assert_eq!(out, models);
        assert!(share_coefficients(models, &tr, &refs[..2]).is_err());
    }

    #[test]
    fn fewer_rows_than_parameters_are_solved_with_the_prior() {
        // 30 rows, 1 + 39 columns per output
        let (models, trends, ys) = fitted(30, true, true);
        assert!(trends[0].len() > 30);
        let refs: Vec<&[f64]> = ys.iter().map(Vec::as_slice).collect();
        let tr: Vec<&Trend> = trends.iter().collect();
        let out = share_coefficients(models, &tr, &refs).unwrap();
        for (k, t) in out.iter().zip(&trends) {
            assert_eq!(&k.data.trend, t);
            let p = k.predict(&k.data.x_train[..3]).unwrap();
            assert!(p.iter().all(|v| v.mean.is_finite() && v.mse.is_finite()));
        }
    }
}
