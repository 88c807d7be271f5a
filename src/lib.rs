//! # robokrige
//!
//! Universal-Kriging surrogate models of an industrial robot's TCP error over the
//! **extended joint space** `s = [θ1..θn, λ1..λn]` (λ = ±1, the direction each
//! joint last moved), and everything around them: kinematics, a measurement
//! simulator, dataset I/O.
//!
//! Module map (see `DESIGN.md` of the project):
//!
//! | module | owns |
//! |---|---|
//! | [`kinematics`] | MD-H chain (seed 003 eq 1), forward kinematics, Jacobian, IK, presets |
//! | [`space`] | direction coefficients λ (seed 003 eq 5) |
//! | [`dataset`] | the measurement CSV: read, validate, write |
//! | [`sim`] | a "true robot" with geometric errors, angular positioning deviation, backlash, compliance, noise and undeclared effects; campaigns |
//! | [`stats`] | summaries of error sets |
//! | [`memory`] | memory estimates and the limit checked before large allocations |
//! | [`kriging`] | universal Kriging: trend, correlation, fit, predict |
//! | [`basis`], [`methods`], [`cv`] | trend selection, the papers' model variants, K-fold CV |
//! | [`plot`] | SVG charts (box plots, x–y plots) |

pub mod basis;
pub mod compensate;
pub mod cv;
pub mod dataset;
pub mod diagnose;
pub mod error;
pub mod features;
pub mod frames;
pub mod holdout;
pub mod kinematics;
pub mod kriging;
pub mod memory;
pub mod methods;
pub mod model;
pub mod optim;
pub mod output;
pub mod physics;
pub mod plot;
pub mod predictor;
pub mod sim;
pub mod space;
pub mod stats;
pub mod trajectory;

pub use error::{Error, Result};
