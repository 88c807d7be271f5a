//! Trend (basis) selection for universal Kriging: which regression terms
//! each output's trend keeps.
//!
//! - **What can be chosen** ([`Candidates`]): the monomials of degree ≤ 2 in
//!   the normalised inputs (seed 003 eq 15), and with a robot also the rows
//!   of its identification Jacobian (seed 003 eq 4, [`kinematic_candidates`]).
//!   [`screen_candidates`] removes the linearly dependent ones, each with
//!   its reason.
//! - **How it is chosen** ([`BasisSelector`]), per output: [`PccPca`], the
//!   PCC + PCA fusion of seed 003 (eqs 16–20, no fit), and [`Ga`], the
//!   genetic algorithm of seed 004 (§III.B, closed-form CV fitness at a fixed
//!   ξ).
//! - The kinematic trend itself, without a selection: [`kinematic_trends`],
//!   screened per axis.
//!
//! A selector returns one trend per output axis and a [`Selection`] report,
//! which the model saves; the model layer (`params`) then fits with them.

mod ga;
mod kinematic;
mod pcc_pca;
mod screen;

pub use ga::{Ga, GaProgress, GaSelection};
pub(crate) use kinematic::kinematic_trend_set_in;
pub use kinematic::{
    KINEMATIC_AXIS_TOL, KINEMATIC_MIN_SUPPORT, KINEMATIC_ZERO_TOL, kinematic_candidates,
    kinematic_trends,
};
pub use pcc_pca::{PccPca, PccPcaReport, pcc_pca};
pub use screen::{CandidateScreen, CandidateSet, Dropped, screen_candidates};

use crate::Result;
use crate::dataset::Dataset;
use crate::inputs::InputMap;
use crate::kinematics::Robot;
use crate::kriging::{KrigingOptions, Monomials, TrainingInputs, Trend, TrendKind};
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

/// The candidate terms of a selection.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Candidates<'a> {
    /// All monomials of degree ≤ 2 in the normalised inputs (seed 003 eq 15).
    Quadratic,
    /// The quadratic monomials and the rows of the robot's identification
    /// Jacobian ([`kinematic_candidates`]).
    Kinematic(&'a Robot),
}

impl Candidates<'_> {
    /// The candidates of each output axis on `data`, whose space map (no
    /// extras) is `map` and whose normalised inputs are `x`.
    pub fn build(&self, data: &Dataset, map: &InputMap, x: &[Vec<f64>]) -> Result<[Trend; 3]> {
        match self {
            Candidates::Quadratic => Ok(std::array::from_fn(|_| {
                Trend::from(Monomials::quadratic(map.dim()))
            })),
            Candidates::Kinematic(robot) => {
                kinematic_trend_set_in(data, map, x, TrendKind::Quadratic, robot, None)
            }
        }
    }
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
