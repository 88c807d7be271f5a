//! A diagnosis as `robokrige diagnose` runs it, around
//! [`diagnose`](crate::diagnose::diagnose): optionally on the residual of a
//! D-H calibration first, then the models before and after the added
//! effects (each holding that calibration), and their compensation of a
//! trajectory compared on the simulated robot. With a robot, the residual
//! of its calibration is what is diagnosed unless the caller says not to.
//!
//! With a calibration `c`, the diagnosed data are the residuals
//! `e − ĉ(q)` of the campaign's errors `e` after the calibration's
//! prediction `ĉ`, and a model is `ĉ + k̂`: the Kriging `k̂` of that
//! residual ([`ErrorModel::with_calibration`]), as `fit --robot` makes.

use super::{Targets, compensate_and_evaluate_each};
use crate::calibration::{Calibration, CalibrationOptions};
use crate::dataset::Dataset;
use crate::diagnose::{DiagnoseOptions, fit_with_effects};
use crate::features::Feature;
use crate::kinematics::Robot;
use crate::model::ErrorModel;
use crate::sim::Truth;
use crate::stats::PositionErrorTable;
use crate::{Error, Result};
use serde::Serialize;
use std::path::Path;

/// What a diagnosis runs on: the campaign, or the residual of its D-H
/// calibration.
#[derive(Debug, Clone)]
pub struct DiagnosisBase {
    /// The calibration whose residual is diagnosed, if any.
    pub calibration: Option<Calibration>,
    /// The rows diagnosed: the campaign's, or their calibration residuals.
    pub data: Dataset,
}

impl DiagnosisBase {
    /// `data` as it is, or the residual of a D-H calibration (default
    /// options, Levenberg–Marquardt on all rows) of the robot of `opts`.
    ///
    /// `calibrate`: `None` calibrates exactly when `opts` has a robot —
    /// the model an engineer deploys with a robot is the calibrated one
    /// (`fit --robot`), so that is what is diagnosed; `Some(false)` never
    /// calibrates; `Some(true)` calibrates, and needs the robot.
    pub fn new(data: Dataset, opts: &DiagnoseOptions, calibrate: Option<bool>) -> Result<Self> {
        if !calibrate.unwrap_or(opts.get_robot().is_some()) {
            return Ok(DiagnosisBase {
                calibration: None,
                data,
            });
        }
        let robot = opts.get_robot().ok_or_else(|| {
            Error::InvalidParameter(
                "calibrating before the diagnosis needs the robot (--robot)".into(),
            )
        })?;
        // geometric: the joint harmonics stay candidates of the diagnosis,
        // found with their evidence and intervals
        let cal = crate::calibration::calibrate(&data, robot, &CalibrationOptions::geometric())?;
        let data = cal.residual(&data)?;
        Ok(DiagnosisBase {
            calibration: Some(cal),
            data,
        })
    }

    /// The diagnosis of the rows ([`crate::diagnose::diagnose_residual`]:
    /// with a calibration, its directions are refitted beside each added
    /// effect for the coefficient intervals).
    pub fn diagnose(
        &self,
        opts: &DiagnoseOptions,
        progress: &dyn Fn(&str),
    ) -> Result<crate::diagnose::Diagnosis> {
        crate::diagnose::diagnose_residual(&self.data, self.calibration.as_ref(), opts, progress)
    }

    /// The models before the diagnosis ([`DiagnosisBase::model`] without
    /// extras) and `after` it compared on `targets`
    /// ([`compare_compensation`]) on the simulator truth file `truth_path`.
    pub fn compare_compensation(
        &self,
        opts: &DiagnoseOptions,
        after: &ErrorModel,
        (robot, targets): (&Robot, &Targets),
        truth_path: &Path,
        seed: u64,
    ) -> Result<CompensationComparison> {
        let truth = super::load_truth(truth_path)?;
        let before = self.model(opts, &[])?;
        compare_compensation(robot, targets, (truth_path, &truth), [&before, after], seed)
    }

    /// The model of the diagnosed rows with `extras` as inputs
    /// ([`fit_with_effects`]: none gives the model before the diagnosis,
    /// [`Diagnosis::extras`](crate::diagnose::Diagnosis::extras) the one
    /// after), holding the calibration if there is one.
    pub fn model(&self, opts: &DiagnoseOptions, extras: &[Feature]) -> Result<ErrorModel> {
        let m = fit_with_effects(&self.data, opts, extras)?;
        Ok(match &self.calibration {
            Some(c) => m.with_calibration(c.clone()),
            None => m,
        })
    }
}

/// The error tables (nominal commands, compensated commands) of one model's
/// iterative compensation, run on the simulated robot.
pub type ErrorTables = (PositionErrorTable, PositionErrorTable);

/// The models before and after a diagnosis, compensating the same
/// trajectory on the same simulated runs.
#[derive(Debug, Clone, Serialize)]
pub struct CompensationComparison {
    /// With the model before the added effects.
    pub before_model: ErrorTables,
    /// With the model after them.
    pub after_model: ErrorTables,
}

/// Iterative compensation of `targets` with the models `before` and
/// `after`, each run on the truth's simulated robot from `robot`'s home
/// with the noise stream `seed` ([`compensate_and_evaluate_each`]).
pub fn compare_compensation(
    robot: &Robot,
    targets: &Targets,
    (truth_path, truth): (&Path, &Truth),
    [before, after]: [&ErrorModel; 2],
    seed: u64,
) -> Result<CompensationComparison> {
    let runs = compensate_and_evaluate_each(
        robot,
        &[before, after],
        truth_path,
        truth,
        targets,
        &robot.home,
        seed,
    )?;
    let [b, a] = [&runs[0], &runs[1]].map(|r| (r.evaluation.before, r.evaluation.after));
    Ok(CompensationComparison {
        before_model: b,
        after_model: a,
    })
}
