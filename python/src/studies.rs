//! Cross-validation, compensation and diagnosis, as the command line runs
//! them (`robokrige cv`, `compensate`, `diagnose`), with the same defaults.
//! Results go to Python as JSON text (parsed there into dicts and arrays).

use crate::data::{Data, rows};
use crate::model::{Model, check_memory, json};
use crate::params::{FitParams, parse_periodic, robot_with_tool};
use crate::physics::PhysicsModel;
use crate::progress::Progress;
use crate::{interrupt, invalid, to_py};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use numpy::{PyReadonlyArray2, PyUntypedArrayMethods};
use pyo3::prelude::*;
use robokrige::cancel::Cancel;
use robokrige::compensate::{CompensationOptions, Stop};
use robokrige::cv::{CvMode, CvPlan, Folds};
use robokrige::diagnose::DiagnoseOptions;
use robokrige::kinematics::Robot;
use robokrige::physics::AnyModel;
use robokrige::study::{GivenOrientation, Targets, check_truth_robot, evaluate, load_truth};
use robokrige::trajectory::Trajectory;
use robokrige::{Error, Result};
use serde_json::json as j;
use std::path::PathBuf;
use std::sync::atomic::{AtomicUsize, Ordering};

/// K-fold CV of a model choice: "refit" (hyperparameters re-optimised on
/// every training fold, as `robokrige cv`) or "closed-form" (one fit's ξ,
/// residuals from the bordered system): the library's [`CvPlan`], as the
/// command line runs it, interruptible by Ctrl-C. Returns the `CvResult`
/// as JSON.
#[pyfunction]
#[pyo3(signature = (data, params, folds=10, cv_seed=1, mode="refit", progress=None))]
pub fn cross_validate(
    py: Python<'_>,
    data: &Data,
    params: FitParams,
    folds: usize,
    cv_seed: u64,
    mode: &str,
    progress: Option<Py<PyAny>>,
) -> PyResult<String> {
    let plan = CvPlan {
        mode: CvMode::from_name(mode).map_err(to_py)?,
        folds: Folds::Random {
            k: folds,
            seed: cv_seed,
        },
        hyper_rows: None,
    };
    let d = &data.inner;
    let cancel = Cancel::new();
    let p = Progress::new(progress, &cancel);
    let res = interrupt::run(py, &cancel, || {
        let valid = params.resolve(d, &cancel)?;
        check_memory(
            d.len(),
            crate::access::optimizer(valid.params().get_kriging()),
        )?;
        let report = |done: usize, k: usize| {
            if done > 0 {
                p.call((done, k, format!("fold {done} of {k}")));
            }
        };
        Ok(plan.run(d, &valid, &report)?.0)
    })?;
    p.finish()?;
    json(&res.map_err(to_py)?, "cv result")
}

/// The robot's targets: a file (trajectory or pose list, as the command
/// line reads it), joint poses, or TCP positions with optional roll, pitch,
/// yaw (degrees).
struct TargetSpec<'a, 'py> {
    path: Option<PathBuf>,
    xyz: Option<PyReadonlyArray2<'py, f64>>,
    rpy: Option<PyReadonlyArray2<'py, f64>>,
    joints: Option<PyReadonlyArray2<'py, f64>>,
    orientation: Option<&'a [f64]>,
}

fn finite_rows(what: &str, rows: &[Vec<f64>], limit: f64) -> Result<()> {
    for (i, r) in rows.iter().enumerate() {
        if let Some(v) = r.iter().find(|v| !(v.is_finite() && v.abs() <= limit)) {
            return Err(Error::InvalidParameter(format!(
                "{what} row {i} (0-based): {v} is not a finite value within ±{limit:e}"
            )));
        }
    }
    Ok(())
}

impl TargetSpec<'_, '_> {
    fn resolve(self, robot: &Robot, start: &[f64]) -> Result<Targets> {
        let given = [
            self.path.is_some(),
            self.xyz.is_some(),
            self.joints.is_some(),
        ];
        if given.iter().filter(|g| **g).count() != 1 {
            return Err(Error::InvalidParameter(
                "give the targets one way: a file, joint poses or TCP positions".into(),
            ));
        }
        let orientation = self.orientation.map(|rpy_deg| GivenOrientation {
            rpy_deg,
            named: "orientation=",
        });
        if let Some(path) = &self.path {
            return Targets::read(path, robot, orientation, start);
        }
        if let Some(q) = &self.joints {
            let q = rows(q);
            finite_rows("joints", &q, robokrige::dataset::MAX_ABS_JOINT)?;
            for r in &q {
                robot.check_len(r)?;
            }
            return Targets::from_joints(robot, &q)?.orient(robot, orientation, start);
        }
        let Some(xyz) = &self.xyz else {
            unreachable!("one of the three was given")
        };
        let xyz = rows(xyz);
        if xyz.first().is_some_and(|r| r.len() != 3) {
            return Err(Error::InvalidParameter(
                "TCP targets need 3 columns: x, y, z (mm)".into(),
            ));
        }
        finite_rows("xyz", &xyz, robokrige::dataset::MAX_ABS_POSITION_MM)?;
        let rpy = self.rpy.as_ref().map(rows);
        if let Some(r) = &rpy {
            if r.len() != xyz.len() || r.first().is_some_and(|r| r.len() != 3) {
                return Err(Error::InvalidParameter(
                    "roll, pitch, yaw need one row of 3 angles (degrees) per target".into(),
                ));
            }
            finite_rows("rpy", r, 1e6)?;
        }
        if xyz.is_empty() {
            return Err(Error::InvalidParameter(
                "the trajectory has no points".into(),
            ));
        }
        let poses = xyz
            .iter()
            .enumerate()
            .map(|(i, p)| {
                let rot = rpy.as_ref().map_or(UnitQuaternion::identity(), |r| {
                    UnitQuaternion::from_euler_angles(
                        r[i][0].to_radians(),
                        r[i][1].to_radians(),
                        r[i][2].to_radians(),
                    )
                });
                Isometry3::from_parts(Translation3::from(Vector3::new(p[0], p[1], p[2])), rot)
            })
            .collect();
        Targets::from_trajectory(Trajectory {
            poses,
            has_orientation: rpy.is_some(),
        })
        .orient(robot, orientation, start)
    }
}

fn stop_name(s: Stop) -> &'static str {
    match s {
        Stop::SingleStep => "single-step",
        Stop::Converged => "converged",
        Stop::Stalled => "stalled",
        Stop::MaxIterations => "max-iterations",
    }
}

/// How Python's `compensate` gives its targets' orientation, for an
/// unreachable position-only target ([`Targets::explain`]).
const ORIENTATION: &str = "the task's orientation with orientation=(roll, pitch, yaw), or a start= pose whose tool points as the task needs";

/// A model `compensate` takes: a Kriging model, a physics model, or a
/// model file of either kind (read as the command line's `--model`).
#[derive(FromPyObject)]
pub enum AnyModelArg<'py> {
    Kriging(Bound<'py, Model>),
    Physics(Bound<'py, PhysicsModel>),
    File(PathBuf),
}

/// The model of `arg`, borrowed, or read from its file into `file`.
fn any_model<'a>(
    arg: &'a AnyModelArg<'_>,
    file: &'a mut Option<AnyModel>,
) -> PyResult<Predictor<'a>> {
    Ok(match arg {
        AnyModelArg::Kriging(m) => Predictor::Kriging(&m.get().inner),
        AnyModelArg::Physics(m) => Predictor::Physics(&m.get().inner),
        AnyModelArg::File(path) => {
            let m = file.insert(AnyModel::load(path).map_err(to_py)?);
            match m {
                AnyModel::Kriging(k) => Predictor::Kriging(k),
                AnyModel::Physics(p) => Predictor::Physics(p),
            }
        }
    })
}

/// A model to compensate with, by kind (the checks and the coverage differ).
#[derive(Clone, Copy)]
enum Predictor<'a> {
    Kriging(&'a robokrige::model::ErrorModel),
    Physics(&'a robokrige::physics::PhysicsModel),
}

/// Pre-compensate targets for `robot` with `model` (a Kriging or physics
/// model; feed-forward, single step or iterative), as `robokrige
/// compensate`; with `truth` (a simulator truth file) also run the nominal
/// and compensated commands on the simulated robot. Returns JSON.
#[pyfunction]
#[pyo3(signature = (model, robot, *, path=None, xyz=None, rpy=None, joints=None, tool=None,
    iterative=true, tol=1e-3, max_iter=10, start=None, orientation=None, truth=None, truth_seed=1))]
#[allow(clippy::too_many_arguments)]
pub fn compensate(
    py: Python<'_>,
    model: AnyModelArg<'_>,
    robot: &str,
    path: Option<PathBuf>,
    xyz: Option<PyReadonlyArray2<'_, f64>>,
    rpy: Option<PyReadonlyArray2<'_, f64>>,
    joints: Option<PyReadonlyArray2<'_, f64>>,
    tool: Option<(f64, f64, f64)>,
    iterative: bool,
    tol: f64,
    max_iter: usize,
    start: Option<Vec<f64>>,
    orientation: Option<Vec<f64>>,
    truth: Option<PathBuf>,
    truth_seed: u64,
) -> PyResult<String> {
    if let (Some(x), Some(r)) = (&xyz, &rpy)
        && x.shape()[0] != r.shape()[0]
    {
        return Err(invalid("xyz and rpy need the same number of rows"));
    }
    let spec = TargetSpec {
        path,
        xyz,
        rpy,
        joints,
        orientation: orientation.as_deref(),
    };
    let robot = robot_with_tool(robot, tool).map_err(to_py)?;
    let mut file = None;
    let m = any_model(&model, &mut file)?;
    match m {
        Predictor::Kriging(k) => k.check_robot(&robot, "model"),
        Predictor::Physics(p) => p.check_robot(&robot, "model"),
    }
    .map_err(to_py)?;
    let start = robot.start_or_home(start.as_deref()).map_err(to_py)?;
    let targets = spec.resolve(&robot, &start).map_err(to_py)?;
    let opts = CompensationOptions {
        iterative,
        tol_mm: tol,
        max_iter,
        start: Some(start.clone()),
        hints: targets.hints.clone(),
        ..CompensationOptions::default()
    };
    let out = py
        .detach(|| {
            let t0 = std::time::Instant::now();
            let (res, coverage) = match m {
                Predictor::Kriging(k) => {
                    let res = robokrige::compensate::compensate(&robot, k, &targets.traj, &opts)
                        .map_err(|e| targets.explain(e, ORIENTATION))?;
                    // the means the compensation used; no standard deviations
                    let coverage = k.coverage(&res.joints, &res.dir, &res.predicted, None)?;
                    (res, coverage)
                }
                Predictor::Physics(p) => (
                    robokrige::compensate::compensate(&robot, p, &targets.traj, &opts)
                        .map_err(|e| targets.explain(e, ORIENTATION))?,
                    Vec::new(),
                ),
            };
            let seconds = t0.elapsed().as_secs_f64();
            let evaluation = match &truth {
                Some(tp) => {
                    let t = load_truth(tp)?;
                    check_truth_robot(&t, &robot, tp)?;
                    let (ev, (before, after)) =
                        evaluate(tp, &t, &targets, &res.commands, &start, truth_seed)?;
                    Some(j!({"summary": ev, "before": before, "after": after}))
                }
                None => None,
            };
            Ok::<_, Error>((res, seconds, coverage, evaluation))
        })
        .map_err(to_py)?;
    let (res, seconds, coverage, evaluation) = out;
    let xyz: Vec<[f64; 3]> = res
        .commands
        .poses
        .iter()
        .map(|p| {
            let t = p.translation.vector;
            [t.x, t.y, t.z]
        })
        .collect();
    let rpy: Option<Vec<[f64; 3]>> = res.commands.has_orientation.then(|| {
        res.commands
            .poses
            .iter()
            .map(|p| {
                let (r, pi, y) = p.rotation.euler_angles();
                [r.to_degrees(), pi.to_degrees(), y.to_degrees()]
            })
            .collect()
    });
    let coverage: Vec<_> = coverage
        .iter()
        .map(|c| {
            let issues: Vec<String> = c.issues.iter().map(ToString::to_string).collect();
            j!({"index": c.index, "issues": issues})
        })
        .collect();
    let model_kind = match m {
        Predictor::Kriging(_) => "kriging",
        Predictor::Physics(_) => "physics",
    };
    let v = j!({
        "model": model_kind,
        "xyz": xyz, "rpy": rpy, "joints": res.joints, "dir": res.dir,
        "predicted": res.predicted, "history": res.history, "converged": res.converged,
        "stop": stop_name(res.stop), "unsettled": res.unsettled, "seconds": seconds,
        "coverage": coverage, "evaluation": evaluation,
    });
    json(&v, "compensation")
}

/// Find what the model misses, trace it to an effect, add it, re-validate
/// (`robokrige diagnose`, same defaults). Returns the diagnosis as JSON and
/// the final model (with the effects added, refitted on all rows).
#[pyfunction]
#[pyo3(signature = (data, method="ejs", nugget=true, folds=10, seed=1, permutations=1999,
    fdr=0.05, max_effects=3, periodic="none", robot=None, progress=None,
    refit_rows=None, scan_rows=None, calibrate=None))]
#[allow(clippy::too_many_arguments)]
pub fn diagnose(
    py: Python<'_>,
    data: &Data,
    method: &str,
    nugget: bool,
    folds: usize,
    seed: u64,
    permutations: usize,
    fdr: f64,
    max_effects: usize,
    periodic: &str,
    robot: Option<String>,
    progress: Option<Py<PyAny>>,
    refit_rows: Option<usize>,
    scan_rows: Option<usize>,
    calibrate: Option<bool>,
) -> PyResult<(String, Model)> {
    let d = &data.inner;
    let cancel = Cancel::new();
    let p = Progress::new(progress, &cancel);
    let step = AtomicUsize::new(0);
    let out = interrupt::run(py, &cancel, || {
        let o = DiagnoseOptions::of_method(method, seed, nugget)?
            .periodic(parse_periodic(periodic, &d.q)?)
            .folds(folds)
            .permutations(permutations)
            .fdr(fdr)
            .max_effects(max_effects)
            .refit_rows(refit_rows.unwrap_or(robokrige::diagnose::DEFAULT_REFIT_ROWS))
            .scan_rows(scan_rows.unwrap_or(robokrige::diagnose::DEFAULT_SCAN_ROWS))
            .robot(
                robot
                    .as_deref()
                    .map(robokrige::kinematics::load_robot)
                    .transpose()?,
            )
            .cancel(cancel.clone());
        let optimizer = crate::access::optimizer(o.get_kriging());
        robokrige::model::check_fit_memory(d.len(), optimizer, |n| {
            format!("e.g. the first {n} rows")
        })?;
        // with a robot (unless `calibrate` is false), the residual of a
        // D-H calibration is diagnosed and the model holds that
        // calibration, as the CLI's `diagnose --robot`
        let base = robokrige::study::diagnosis::DiagnosisBase::new(d.clone(), &o, calibrate)?;
        let diag = base.diagnose(&o, &|msg: &str| {
            let k = step.fetch_add(1, Ordering::SeqCst) + 1;
            p.call((k, 0usize, msg.to_string()));
        })?;
        let model = base.model(&o, &diag.extras)?;
        let mut v = serde_json::to_value(&diag).map_err(|e| Error::Json {
            context: "diagnosis".into(),
            source: e,
        })?;
        v["before_residuals"] = j!(diag.before.residuals);
        v["after_residuals"] = j!(diag.after.residuals);
        v["method"] = j!(method);
        Ok::<_, Error>((v, model))
    })?;
    p.finish()?;
    let (v, model) = out.map_err(to_py)?;
    Ok((json(&v, "diagnosis")?, Model { inner: model }))
}
