//! The fused trend basis of PCC + PCA (seed 003 §III.B): the selected
//! candidate terms, standardised and projected on their principal
//! directions. The selection itself is the `basis` module's `pcc_pca`;
//! this is the trend a model carries and evaluates.

use super::trend::{KinematicTrend, Monomials, Trend, TrendModel};
use serde::{Deserialize, Serialize};

/// A fused trend basis `[1, w_1, …, w_k]`, `w_i = ((u(s) − μ)/σ)ᵀ e_i`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FusedBasis {
    /// The selected candidates u (PCC above threshold) when they are all
    /// monomials (otherwise unused and empty).
    pub candidates: Monomials,
    /// The selected candidates when some are kinematic-error rows.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub kinematic: Option<Box<KinematicTrend>>,
    /// Training mean μ of each selected candidate.
    pub mean: Vec<f64>,
    /// Training standard deviation σ of each selected candidate (divisor m − 1).
    pub std: Vec<f64>,
    /// Principal directions e_i (each of length `candidates.len()`), by
    /// decreasing variance.
    pub components: Vec<Vec<f64>>,
}

impl TrendModel for FusedBasis {
    fn len(&self) -> usize {
        1 + self.components.len()
    }

    fn dim(&self) -> usize {
        self.selected().dim()
    }

    fn eval_into(&self, s: &[f64], out: &mut [f64]) {
        let sel = self.selected();
        let mut u = vec![0.0; sel.len()];
        sel.eval_into(s, &mut u);
        for ((v, m), sd) in u.iter_mut().zip(&self.mean).zip(&self.std) {
            *v = (*v - m) / sd;
        }
        out[0] = 1.0;
        for (o, e) in out[1..].iter_mut().zip(&self.components) {
            *o = u.iter().zip(e).map(|(a, b)| a * b).sum();
        }
    }

    fn term_name(&self, j: usize, _inputs: &[String]) -> String {
        if j == 0 { "1".into() } else { format!("pc{j}") }
    }
}

impl FusedBasis {
    /// The selected candidates u: the kinematic-error rows, or the monomials.
    fn selected(&self) -> &dyn TrendModel {
        match &self.kinematic {
            Some(k) => k.as_ref(),
            None => &self.candidates,
        }
    }

    /// Shapes consistent with its candidates (for trends read from files).
    pub fn validate(&self) -> std::result::Result<(), String> {
        let c = match &self.kinematic {
            Some(k) => {
                k.validate()?;
                k.len()
            }
            None => {
                self.candidates.validate()?;
                self.candidates.len()
            }
        };
        if self.mean.len() != c
            || self.std.len() != c
            || self.components.iter().any(|e| e.len() != c)
        {
            return Err(format!(
                "fused basis: means, scales or components do not match its {c} candidates"
            ));
        }
        Ok(())
    }

    pub(crate) fn new(
        selected: Trend,
        mean: Vec<f64>,
        std: Vec<f64>,
        components: Vec<Vec<f64>>,
    ) -> Self {
        let (candidates, kinematic) = match selected {
            Trend::Kinematic(k) => (
                Monomials {
                    dim: k.poly.dim,
                    exponents: Vec::new(),
                },
                Some(k),
            ),
            Trend::Monomials(m) => (m, None),
            Trend::Fused(_) => unreachable!("candidate sets are monomials or kinematic"),
        };
        FusedBasis {
            candidates,
            kinematic,
            mean,
            std,
            components,
        }
    }

    /// The same basis with only the terms at `keep` (index 0 = the constant).
    pub fn subset(&self, keep: &[usize]) -> Self {
        let mut out = self.clone();
        out.components = keep
            .iter()
            .filter(|&&j| j > 0)
            .map(|&j| self.components[j - 1].clone())
            .collect();
        out
    }
}
