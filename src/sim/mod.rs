//! Measurement simulator: a believable "true robot" and the campaigns an
//! engineer would run on it with a laser tracker.
//!
//! - [`TrueRobot`]: geometric errors on every MD-H parameter, bidirectional
//!   angular positioning deviation (harmonics + angle-dependent backlash, seed
//!   000 eqs 3–6, seed 003 eq 5), gravity compliance, repeatability and tracker
//!   noise (seed 000 Table 2).
//! - [`Effect`]: undeclared effects (temperature drift, payload, gear harmonic,
//!   tracker step, cross-talk).
//! - [`campaign`]: Latin-hypercube, verification, axis-indexing (seed 000 §2.3)
//!   and circle-trajectory (seed 004 §IV.B.3) designs, and their measurement.
//!
//! - [`iso_cubes`]: ISO 9283 cube campaigns (poses clustered in a few cubes,
//!   the branch varied from cube to cube) and their measurement.
//!
//! Everything is reproducible from a seed; the simulator's truth goes to a
//! sidecar JSON ([`Truth`]), never into the measurement CSV. The truth may be
//! used to *check* the engine, never inside it.

pub mod campaign;
pub mod designs;
mod effects;
pub mod execute;
pub mod iso_cubes;
mod scara_truth;
mod true_robot;

pub use campaign::{CampaignKind, CampaignSpec, SimOutput, Truth, parse_ranges, simulate};
pub use effects::{EFFECT_NAMES, Effect, MEASUREMENT_EFFECTS};
pub use execute::{Execution, execute};
pub use scara_truth::ScaraTruth;
pub use true_robot::{
    Compliance, ErrorProfile, Harmonic, JointDeviation, NoiseModel, PoseContext, TrueRobot,
};

use rand_distr::{Distribution, Normal};
use std::path::{Path, PathBuf};

pub use crate::stats::rng_for;

/// One draw of `N(0, σ²)` (0 when σ ≤ 0).
pub fn gaussian(rng: &mut impl rand::Rng, sigma: f64) -> f64 {
    if sigma > 0.0 && sigma.is_finite() {
        Normal::new(0.0, sigma).map_or(0.0, |d| d.sample(rng))
    } else {
        0.0
    }
}

impl SimOutput {
    /// Write it: a measurement CSV ([`crate::dataset::write_csv`]) or a
    /// trajectory CSV.
    pub fn write_csv(&self, path: &Path) -> crate::Result<()> {
        match self {
            SimOutput::Measurements(d) => crate::dataset::write_csv(path, d),
            SimOutput::Trajectory(t) => t.write_csv(path),
        }
    }
}

/// Where a campaign written to `output` keeps its simulator truth by
/// default: `a.csv` → `a.truth.json`.
pub fn truth_path_for(output: &Path) -> PathBuf {
    output.with_extension("truth.json")
}
