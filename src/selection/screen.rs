//! Screening of trend candidates: the linearly dependent ones are removed
//! before any selection, each with the reason (seed 003 eq 15 discussion).

use crate::kriging::{Monomials, Trend, TrendModel, independent_columns, trend_matrix};
use faer::Mat;
use faer::linalg::solvers::SolveLstsq;
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
