//! **PCC + PCA fusion** (seed 003 eqs 16–20), per output: rank the candidates
//! by |Pearson r| with the response (eq 16), keep those above a threshold T,
//! z-score them, eigen-decompose their covariance (eq 17), and keep the
//! leading principal components up to a cumulative variance share (eq 19):
//! the fused basis is `w_i = uᵀe_i` (eqs 18, 20), evaluable at new points
//! through the stored means, standard deviations and eigenvectors. A constant
//! term is kept in front (the components have zero training mean, and the
//! Kriging mean still needs one).

use super::screen::{CandidateSet, screen_candidates};
use super::selector::{BasisSelector, PccPcaReport, Selection, SelectionProblem};
use crate::kriging::{FusedBasis, Trend, trend_matrix};
use crate::{Error, Result};
use faer::{Mat, Side};

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

/// The PCC + PCA selector of seed 003 (EJS&PCA): per output,
/// [`pcc_pca`] of the candidates with at most m/2 terms, the fused basis as
/// the trend.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PccPca {
    /// |PCC| at or below which a candidate is dropped (eq 16; seed 003: 0.1).
    pub threshold: f64,
    /// Cumulative variance share the kept components explain (eq 19; 0.99).
    pub variance_share: f64,
}

impl BasisSelector for PccPca {
    fn select(&self, p: &SelectionProblem) -> Result<([Trend; 3], Selection)> {
        let mut trends = Vec::with_capacity(3);
        let mut reports = Vec::with_capacity(3);
        for a in 0..3 {
            let (basis, report) = pcc_pca(
                &p.candidates[a],
                p.x,
                &p.y[a],
                self.threshold,
                self.variance_share,
                p.x.len() / 2,
                p.names,
            )?;
            trends.push(Trend::Fused(basis));
            reports.push(report);
        }
        let trends: [Trend; 3] = trends.try_into().expect("three outputs");
        Ok((trends, Selection::PccPca { outputs: reports }))
    }
}
