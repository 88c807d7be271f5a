//! The one thing every error model can do: predict the TCP error of
//! commanded poses.
//!
//! A Kriging `ErrorModel`, a physics `PhysicsModel` (seed 000 eq 3, seed 002
//! eq 1) and their `HybridModel` implement it next to their own types (this
//! module depends on nothing above it); the compensator and the studies take
//! any of them.

use crate::Result;

/// Anything that predicts the TCP error `δ̂(θ, λ)` (mm, measurement frame) of
/// commanded poses.
pub trait ErrorPredictor: Sync {
    /// Joint count the model was built for.
    fn n_joints(&self) -> usize;
    /// Predicted errors `[ex, ey, ez]` at commanded joints `q` approached in
    /// directions `dir` (one row per pose).
    fn predict_errors(&self, q: &[Vec<f64>], dir: &[Vec<f64>]) -> Result<Vec<[f64; 3]>>;
}
