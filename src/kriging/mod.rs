//! Universal Kriging (seed 003 eqs 6–14; seed 004 eqs 6–14; DACE).
//!
//! - [`trend`]: trend models `f(s)` ([`TrendModel`], [`Monomials`]).
//! - [`corr`]: correlation models ([`CorrelationModel`], [`Gaussian`], eq 8);
//!   `registry`: families of one's own, by name ([`Correlation::register`]).
//! - [`problem`]: ψ(ξ) and the solve at fixed ξ — the whole algorithm on a page.
//! - [`model`]: the fitted predictor and its MSE (eqs 10, 12).
//! - `options`: what a fit is asked ([`KrigingOptions`]) and reports
//!   ([`FitReport`]).
//! - `params`: one output's fit, [`KrigingParams`] → `check` →
//!   [`ValidKrigingParams::fit`], with its [`Tuning`].
//! - `fit`: the steps of that fit; `family`: the family fixed or chosen by
//!   CV ([`CorrChoice`]).
//! - `search`: the hyperparameter search sized to the campaign ([`FitPlan`]).
//!
//! A fit drops linearly dependent trend columns, minimises ln ψ over
//! `log10 ξ` (and `log10 ν` with an estimated nugget) with projected BFGS on
//! the analytic gradient (default), Hooke–Jeeves or multistart GPS — or
//! takes ξ, ν as given — then solves at the optimum.

pub mod corr;
mod dense;
mod family;
mod fastexp;
mod fit;
mod fma;
mod fused;
pub mod model;
mod options;
mod params;
pub mod problem;
mod registry;
mod search;
pub mod trend;

pub use corr::{Correlation, CorrelationModel, Gaussian, TrainingInputs};
pub use family::{CorrChoice, FAMILY_FOLDS, FamilyScore};
pub use fit::{SHARED_SCREEN_SUPPORT, SHARED_SCREEN_TOL, fit_columns};
pub use fused::FusedBasis;
pub use model::{HeldOut, KrigingModel, KrigingModelData, Pred, share_coefficients};
pub use options::{FitReport, KrigingOptions, MIN_CONVERGE_ROWS, OptimizerKind, TrendKind};
pub use params::{Hyperparameters, KrigingParams, Tuning, ValidKrigingParams};
pub use problem::{KrigingProblem, PsiValue, Solution, Workspace, storable_ln_psi};
pub use registry::CustomCorrelation;
pub use search::{FitPlan, REFINE_ROWS, SEARCH_ROWS, converge_subset};
use search::{Search, converge_bfgs, ln_psi_objective, optimise, row_subset};
pub use trend::{
    CoefficientPrior, KinematicTrend, Monomials, Trend, TrendModel, independent_columns, support,
    supported_columns, trend_matrix,
};
