//! Basis (trend) selection for universal Kriging.
//!
//! Candidates: all monomials of degree ≤ η in the 2n normalised EJS variables
//! (seed 003 eq 15; [`Monomials::full`]), linearly dependent ones removed
//! ([`independent_columns`]).
//!
//! **PCC + PCA fusion** (seed 003 eqs 16–20), per output: rank the candidates
//! by |Pearson r| with the response (eq 16), keep those above a threshold T,
//! z-score them, eigen-decompose their covariance (eq 17), and keep the
//! leading principal components up to a cumulative variance share (eq 19):
//! the fused basis is `w_i = uᵀe_i` (eqs 18, 20), evaluable at new points
//! through the stored means, standard deviations and eigenvectors. A constant
//! term is kept in front (the components have zero training mean, and the
//! Kriging mean still needs one).

pub use crate::kriging::FusedBasis;
use crate::kriging::{Monomials, Trend, TrendModel, independent_columns, trend_matrix};
use crate::{Error, Result};
use faer::linalg::solvers::SolveLstsq;
use faer::{Mat, Side};
use serde::{Deserialize, Serialize};

/// A candidate removed before selection, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Dropped {
    /// The candidate term's name, e.g. a monomial of the input names.
    pub term: String,
    /// Why it was dropped: an exact duplicate, zero on every training row, or a
    /// linear combination of the kept terms it names.
    pub reason: String,
}

/// The candidates that survive screening on the training inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CandidateScreen {
    /// Number of candidates before screening (91 for 12 inputs, η = 2).
    pub total: usize,
    /// Indices (into the candidate list) of the linearly independent ones.
    #[serde(skip)]
    pub kept: Vec<usize>,
    /// Candidates removed as linearly dependent, with reasons, in candidate order.
    pub dropped: Vec<Dropped>,
}

/// Screen `candidates` at the training inputs `x`: in candidate order, a term
/// is dropped when its column is an exact duplicate of a kept one, or lies
/// (to relative tolerance 1e-9) in the span of the kept columns — e.g. `λ²`,
/// which is affine in `λ` because λ = ±1 (seed 003 eq 15 discussion). The
/// reason names the terms it depends on.
pub fn screen_candidates(
    candidates: &dyn TrendModel,
    x: &[Vec<f64>],
    names: &[String],
) -> CandidateScreen {
    let f = trend_matrix(candidates, x);
    let (kept, dropped_idx) = independent_columns(&f, 1e-9);
    let m = f.nrows();
    let col = |j: usize| (0..m).map(|i| f[(i, j)]).collect::<Vec<f64>>();
    let name = |j: usize| candidates.term_name(j, names);
    let basis = Mat::<f64>::from_fn(m, kept.len(), |i, k| f[(i, kept[k])]);
    let qr = (!kept.is_empty()).then(|| basis.qr());
    let dropped = dropped_idx
        .into_iter()
        .map(|j| {
            let cj = col(j);
            let reason = if let Some(&k) = kept.iter().find(|&&k| col(k) == cj) {
                format!("exact duplicate of {}", name(k))
            } else if cj.iter().all(|v| *v == 0.0) {
                "zero on every training row".to_string()
            } else if let Some(qr) = &qr {
                let rhs = Mat::<f64>::from_fn(m, 1, |i, _| cj[i]);
                let coef = qr.solve_lstsq(&rhs);
                let big = (0..kept.len())
                    .map(|k| coef[(k, 0)].abs())
                    .fold(0.0, f64::max);
                let support: Vec<String> = (0..kept.len())
                    .filter(|&k| coef[(k, 0)].abs() > 1e-6 * big)
                    .map(|k| name(kept[k]))
                    .collect();
                let shown = support
                    .iter()
                    .take(4)
                    .cloned()
                    .collect::<Vec<_>>()
                    .join(", ");
                let more = if support.len() > 4 { ", …" } else { "" };
                format!("linear combination of {shown}{more} on the training rows")
            } else {
                "no independent terms to compare with".to_string()
            };
            Dropped {
                term: name(j),
                reason,
            }
        })
        .collect();
    CandidateScreen {
        total: candidates.len(),
        kept,
        dropped,
    }
}

/// GA basis selection for one output (seed 004 §III.B).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct GaSelection {
    /// Candidates before screening, and those removed as dependent.
    pub candidates: usize,
    /// Candidates removed as linearly dependent before the GA ran, with reasons.
    pub dropped: Vec<Dropped>,
    /// Size cap C ≤ (K−1)m/K on the selected terms.
    pub size_cap: usize,
    /// Selected terms (the constant always first).
    pub selected: Vec<String>,
    /// Best fitness: closed-form K-fold CV RMSE (mm, seed 004 eq 17).
    pub cv_rmse_mm: f64,
    /// Best fitness after each generation (seed 004 Fig 10).
    pub history: Vec<f64>,
    /// Generations run (the GA stops on stall or at its generation cap).
    pub generations: usize,
    /// Distinct chromosomes (term subsets) whose fitness was evaluated.
    pub evaluations: usize,
}

/// What a method's basis selection did, per output axis; saved with the model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "kebab-case")]
pub enum Selection {
    /// PCC + PCA fusion (seed 003 eqs 16–20).
    PccPca {
        /// One report per output axis (x, y, z).
        outputs: Vec<PccPcaReport>,
    },
    /// GA subset selection (seed 004 §III.B).
    Ga {
        /// One selection per output axis (x, y, z).
        outputs: Vec<GaSelection>,
    },
}

/// A candidate set PCC + PCA can draw from: monomials, or monomials plus the
/// kinematic-error rows ([`crate::kriging::KinematicTrend`]).
pub trait CandidateSet: TrendModel {
    /// The candidates at `keep`, as a trend.
    fn pick(&self, keep: &[usize]) -> Trend;
}

impl CandidateSet for Monomials {
    fn pick(&self, keep: &[usize]) -> Trend {
        Trend::Monomials(self.subset(keep))
    }
}

impl CandidateSet for Trend {
    fn pick(&self, keep: &[usize]) -> Trend {
        self.subset(keep)
    }
}

/// What PCC + PCA did, for the report.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PccPcaReport {
    /// Candidates removed before ranking (linear dependence), with reasons.
    pub dropped: Vec<Dropped>,
    /// Candidates with zero variance on the training rows (the constant).
    pub no_variance: Vec<String>,
    /// (candidate name, Pearson r) of every candidate with non-zero variance,
    /// by decreasing |r|.
    pub ranking: Vec<(String, f64)>,
    /// Threshold T on |r| (eq 16; paper: 0.1): a candidate is kept when |r| > T.
    pub threshold: f64,
    /// Candidates kept (|r| > threshold), n2.
    pub selected: usize,
    /// Eigenvalues of the z-scored selection's covariance, decreasing.
    pub eigenvalues: Vec<f64>,
    /// Components kept, n3, and their cumulative variance share (eq 19).
    pub components: usize,
    /// Cumulative share of variance of the kept components, in [0, 1] (eq 19).
    pub explained: f64,
}

/// PCC + PCA fusion of `candidates` (evaluated at normalised inputs `x`) for
/// response `y`: threshold `t` on |r| (paper: 0.1), cumulative variance share
/// `cum` (paper: 0.99). At most `max_terms` − 1 components are kept (the
/// basis must leave room in the training folds).
pub fn pcc_pca(
    candidates: &dyn CandidateSet,
    x: &[Vec<f64>],
    y: &[f64],
    t: f64,
    cum: f64,
    max_terms: usize,
    names: &[String],
) -> Result<(FusedBasis, PccPcaReport)> {
    let valid = (0.0..1.0).contains(&t) && cum > 0.0 && cum <= 1.0 && max_terms >= 1;
    if !valid {
        return Err(Error::InvalidParameter(
            "PCC threshold must be in [0, 1), variance share in (0, 1], max_terms ≥ 1".into(),
        ));
    }
    let m = x.len();
    let f = trend_matrix(candidates, x);
    let screen = screen_candidates(candidates, x, names);
    let independent = screen.kept;
    let mut no_variance = Vec::new();
    let ym = y.iter().sum::<f64>() / m as f64;
    let yv: f64 = y.iter().map(|v| (v - ym) * (v - ym)).sum();
    // eq 16 for every candidate with variance
    let mut scored: Vec<(usize, f64, f64, f64)> = Vec::new(); // (column, r, mean, std)
    for &j in &independent {
        let col: Vec<f64> = (0..m).map(|i| f[(i, j)]).collect();
        let mu = col.iter().sum::<f64>() / m as f64;
        let var: f64 = col.iter().map(|v| (v - mu) * (v - mu)).sum();
        if var <= 1e-20 * m as f64 {
            no_variance.push(candidates.term_name(j, names));
            continue;
        }
        if yv <= 0.0 {
            continue; // constant response: no candidate correlates
        }
        let cov: f64 = col.iter().zip(y).map(|(a, b)| (a - mu) * (b - ym)).sum();
        scored.push((
            j,
            cov / (var * yv).sqrt(),
            mu,
            (var / (m as f64 - 1.0)).sqrt(),
        ));
    }
    scored.sort_by(|a, b| b.1.abs().total_cmp(&a.1.abs()).then(a.0.cmp(&b.0)));
    let ranking = scored
        .iter()
        .map(|s| (candidates.term_name(s.0, names), s.1))
        .collect();
    let sel: Vec<&(usize, f64, f64, f64)> = scored.iter().filter(|s| s.1.abs() > t).collect();
    let n2 = sel.len();
    let selected = candidates.pick(&sel.iter().map(|s| s.0).collect::<Vec<_>>());
    let (mean, std): (Vec<f64>, Vec<f64>) = sel.iter().map(|s| (s.2, s.3)).unzip();
    if n2 == 0 {
        let basis = FusedBasis::new(selected, mean, std, Vec::new());
        return Ok((
            basis,
            PccPcaReport {
                dropped: screen.dropped,
                no_variance,
                ranking,
                threshold: t,
                selected: 0,
                eigenvalues: Vec::new(),
                components: 0,
                explained: 0.0,
            },
        ));
    }
    // eq 17: covariance of the z-scored selection
    let z = Mat::<f64>::from_fn(m, n2, |i, k| (f[(i, sel[k].0)] - mean[k]) / std[k]);
    let cov = Mat::<f64>::from_fn(n2, n2, |a, b| {
        (0..m).map(|i| z[(i, a)] * z[(i, b)]).sum::<f64>() / (m as f64 - 1.0)
    });
    let evd = cov
        .self_adjoint_eigen(Side::Lower)
        .map_err(|e| Error::Numerical(format!("PCA eigen-decomposition: {e:?}")))?;
    // faer sorts ascending; eqs 18–19 want descending
    let eigenvalues: Vec<f64> = (0..n2).rev().map(|k| evd.S()[k].max(0.0)).collect();
    let total: f64 = eigenvalues.iter().sum();
    let mut n3 = 0;
    let mut acc = 0.0;
    while n3 < n2 && n3 + 1 < max_terms && (n3 == 0 || acc < cum * total) {
        acc += eigenvalues[n3];
        n3 += 1;
    }
    let components = (0..n3)
        .map(|c| (0..n2).map(|k| evd.U()[(k, n2 - 1 - c)]).collect())
        .collect();
    let basis = FusedBasis::new(selected, mean, std, components);
    let report = PccPcaReport {
        dropped: screen.dropped,
        no_variance,
        ranking,
        threshold: t,
        selected: n2,
        explained: if total > 0.0 { acc / total } else { 0.0 },
        eigenvalues,
        components: n3,
    };
    Ok((basis, report))
}
