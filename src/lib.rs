//! # robokrige
//!
//! Universal-Kriging surrogate models of an industrial robot's TCP (tool
//! centre point) error over the **extended joint space** (EJS)
//! `s = [θ1..θn, λ1..λn]` (λ = ±1, the direction each joint last moved) or
//! the joint space (JS) `[θ1..θn]` alone, and everything around them:
//! kinematics, calibration, a measurement simulator, dataset I/O.
//!
//! # Quick start: the calibrated model
//!
//! A campaign (joints, approach directions, measured errors) and the
//! robot it was measured on give the model an engineer deploys: the
//! robot's kinematic errors (its MD-H, modified Denavit–Hartenberg,
//! parameters, tool and base) identified on the directions the campaign
//! sees, then Kriging of what that calibration leaves, in one file.
//!
//! ```no_run
//! use robokrige::calibration::CalibrationOptions;
//! use robokrige::compensate::{CompensationOptions, compensate};
//! use robokrige::cv::cross_validate_closed_form;
//! use robokrige::dataset::read_csv;
//! use robokrige::kinematics::load_robot;
//! use robokrige::params::ErrorModelParams;
//! use robokrige::trajectory::Trajectory;
//!
//! let data = read_csv("datasets/comau_lhs.csv".as_ref())?;
//! let robot = load_robot("comau-nj220")?; // a preset or a robot file
//! let model = ErrorModelParams::new()
//!     .robot(robot.clone())
//!     .calibrate(Some(CalibrationOptions::default()))
//!     .check()?
//!     .fit(&data)?;
//! // how well it predicts poses it was not fitted on (10 folds, seed 1)
//! let cv = cross_validate_closed_form(&data, &model, 10, 1)?;
//! println!("CV mean 3D error {:.3} mm", cv.summary.mean_3d_mm);
//! // the error at new poses, with its standard deviation, mm
//! let p = model.predict(&[vec![0.0, -10.0, -120.0, 0.0, -30.0, 0.0]], &[vec![1.0; 6]])?;
//! println!("{:?} ± {:?}", p.mean[0], p.std[0]);
//! // the commands that put the TCP on a path, and the model file
//! let path = Trajectory::read_csv("datasets/comau_circle.csv".as_ref())?;
//! let out = compensate(&robot, &model, &path, &CompensationOptions::default())?;
//! println!("{} joint commands to send", out.commands.poses.len());
//! model.save("model.json".as_ref())?;
//! # Ok::<(), robokrige::Error>(())
//! ```
//!
//! Module map, bottom layer first (the layers and their rules:
//! `docs/ARCHITECTURE.md`; the papers cited as "seed 00N": `REFERENCES.md`):
//!
//! | layer | module | owns |
//! |---|---|---|
//! | data | [`error`] | the crate's one error type |
//! | data | [`cancel`] | `Cancel`: a token that stops long work (fits, CV, diagnosis, planning) between its steps |
//! | data | [`dataset`] | the measurement CSV: read, validate, write |
//! | data | [`trajectory`] | commanded TCP paths (CSV) |
//! | data | [`program`] | joint moves as a robot program: joint CSV, URScript, KUKA KRL, ABB RAPID |
//! | data | [`space`] | direction coefficients λ (seed 003 eq 5), JS/EJS encoding, input normalisation |
//! | data | [`stats`] | summaries of error sets, seeded RNG streams, fold partitions |
//! | data | [`memory`], [`output`] | memory estimates before large allocations; checked, atomic output files |
//! | data | [`vec3`] | TCP error vectors `[x, y, z]` (mm): norm, residuals |
//! | data | [`predictor`] | the `ErrorPredictor` trait every error model implements |
//! | geometry and numerics | [`kinematics`] | MD-H chain (seed 003 eq 1), forward kinematics, Jacobian, IK (also along a path), presets |
//! | geometry and numerics | [`frames`] | best-fit plane, circle, axis line; SVD registration (seed 004 eqs 29–35) |
//! | geometry and numerics | [`calibration`] | MD-H, tool and base errors by Levenberg–Marquardt on the directions a campaign sees; the joints' harmonics and backlash; identifiability; the calibration's prediction and variance |
//! | geometry and numerics | [`optim`] | box-constrained minimisers (BFGS, GPS, Hooke–Jeeves, GA, Levenberg–Marquardt) |
//! | engine | [`kriging`] | universal Kriging: trend, correlation families, likelihood, fit, predict |
//! | engine | [`features`] | extra inputs beyond `[θ, λ]` that `diagnose` can add |
//! | engine | [`inputs`] | `InputMap`: encoding, extras and normalisation of a model's inputs, in one place |
//! | engine | [`selection`] | trend selection: candidates, PCC + PCA (partial correlation and principal components, seed 003 eqs 15–20), a genetic algorithm (GA, seed 004), the kinematic trend |
//! | model | [`model`] | `ErrorModel`: three Kriging outputs over JS or EJS, save/load |
//! | model | [`params`] | `ErrorModelParams` → checked → `fit`: every space × trend × hyperparameter choice |
//! | model | [`methods`] | the papers' model variants by name (`Method::params`), and `recommended`; a fit by names and its rules (`params_with`) |
//! | studies | [`cv`] | K-fold cross-validation (seed 003 eq 21), refit or closed form |
//! | studies | [`compensate`] | single-step and iterative feed-forward compensation (seed 003 eq 22, seed 004 eqs 18–22) |
//! | studies | [`diagnose`] | closing the loop: what the model still misses |
//! | studies | [`sim`] | a "true robot" and its campaigns (checks the engine; never used inside it) |
//! | studies | [`physics`] | the lookup-table models of seeds 000 and 002, D-H calibration, physics + Kriging, comparisons |
//! | studies | [`study`] | compensation targets, simulator truth files, before/after evaluation on the simulated robot |
//! | studies | [`holdout`] | Kriging beside the D-H calibration on held-out real rows |
//! | studies | [`plan`] | which poses to measure next: the integrated-MSE design, its order with via-points, when to stop |
//! | studies | [`batch`] | a fleet: every campaign of a folder fitted and cross-validated, in parallel |
//! | studies | [`demo`] | the demo's job on the simulated COMAU: methods by CV, compensation, a diagnosis |
//! | presentation | `plot` | SVG charts (box plots, x–y plots) and the studies' charts; Cargo feature `plot` (default) |
//! | presentation | [`report`] | the studies' text reports: the tables the CLI prints, its Markdown reports |
//! | presentation | `config` | config files (`robokrige run`): steps as command lines, run in order; Cargo feature `cli` |
//!
//! Cargo features: `cli` (the `robokrige` binary: clap, indicatif) and
//! `plot` (plotters), both on by default; `default-features = false` gives
//! the library alone.

#![warn(missing_docs)]

pub mod batch;
pub mod calibration;
pub mod cancel;
pub mod compensate;
#[cfg(feature = "cli")]
pub mod config;
pub mod cv;
pub mod dataset;
pub mod demo;
pub mod diagnose;
pub mod error;
pub mod features;
pub mod frames;
pub mod holdout;
pub mod inputs;
pub mod kinematics;
pub mod kriging;
pub mod memory;
pub mod methods;
pub mod model;
pub mod optim;
pub mod output;
pub mod params;
pub mod physics;
pub mod plan;
#[cfg(feature = "plot")]
pub mod plot;
pub mod predictor;
pub mod program;
pub mod report;
pub mod selection;
pub mod sim;
pub mod space;
pub mod stats;
pub mod study;
pub mod trajectory;
pub mod vec3;

pub use error::{Error, Result};
