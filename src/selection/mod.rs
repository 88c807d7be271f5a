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
mod selector;

pub use ga::{Ga, GaProgress};
pub use kinematic::{
    KINEMATIC_AXIS_TOL, KINEMATIC_MIN_SUPPORT, KINEMATIC_ZERO_TOL, kinematic_candidates,
    kinematic_trends,
};
pub(crate) use kinematic::{Terms, kinematic_trend_set_in, shared_kinematic_trends_in};
pub use pcc_pca::{PccPca, pcc_pca};
pub use screen::{CandidateScreen, CandidateSet, Dropped, screen_candidates};
pub use selector::{BasisSelector, GaSelection, PccPcaReport, Selection, SelectionProblem};

use crate::Result;
use crate::dataset::Dataset;
use crate::inputs::InputMap;
use crate::kinematics::Robot;
use crate::kriging::{Monomials, Trend, TrendKind};

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
                kinematic_trend_set_in(data, map, x, TrendKind::Quadratic, robot, Terms::Candidates)
            }
        }
    }
}
