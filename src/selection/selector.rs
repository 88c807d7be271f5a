//! What every trend selection shares: the problem it is given
//! ([`SelectionProblem`]), the trait of a selector ([`BasisSelector`]),
//! and the report saved with the model ([`Selection`]).

use super::screen::Dropped;
use crate::Result;
use crate::kriging::{KrigingOptions, TrainingInputs, Trend};
use serde::{Deserialize, Serialize};

/// A selection problem: the training rows of one campaign, encoded, with
/// one candidate trend per output axis.
#[derive(Debug, Clone, Copy)]
pub struct SelectionProblem<'a> {
    /// Normalised training inputs, one row per pose.
    pub x: &'a [Vec<f64>],
    /// The same rows as correlation inputs.
    pub inputs: &'a TrainingInputs,
    /// Input names (for the terms' names in reports).
    pub names: &'a [String],
    /// The responses (errors, mm) of each output axis x, y, z.
    pub y: &'a [Vec<f64>; 3],
    /// The candidates of each output axis.
    pub candidates: &'a [Trend; 3],
    /// Options of any fit a selector makes (correlation, optimiser, nugget).
    pub options: &'a KrigingOptions,
}

/// A way of choosing each output's trend from its candidates.
pub trait BasisSelector {
    /// The chosen trend per output axis (x, y, z), and the report saved with
    /// the model.
    fn select(&self, problem: &SelectionProblem) -> Result<([Trend; 3], Selection)>;
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
