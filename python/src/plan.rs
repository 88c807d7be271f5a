//! `plan`: which poses to measure next, in which order (`robokrige plan`):
//! the library's planner (`PlanParams` → `check` → `plan`) with the
//! command line's defaults, interruptible by Ctrl-C.

use crate::data::{Data, rows_to_py};
use crate::model::{Model, json};
use crate::params::robot_with_tool;
use crate::{interrupt, to_py};
use numpy::{PyArray1, PyArray2};
use pyo3::prelude::*;
use robokrige::cancel::Cancel;
use robokrige::plan::stop::Forecast;
use robokrige::plan::{PlanInputs, PlanParams, PoseSet, Region, TrackerView};
use robokrige::program::{ProgramFormat, ProgramOptions};
use robokrige::{Error, Result};
use std::path::PathBuf;

/// The region a plan lowers the error over: a task file (joint poses or a
/// TCP path, as `--region`) or the poses of a campaign.
#[derive(FromPyObject)]
pub enum RegionArg<'py> {
    Poses(Bound<'py, Data>),
    File(PathBuf),
}

/// The tracker's view (`--tracker`, `--max-range`, `--max-incidence`).
fn tracker(
    at: Option<[f64; 3]>,
    max_range: Option<f64>,
    max_incidence: Option<f64>,
) -> Result<Option<TrackerView>> {
    let Some(at) = at else {
        if max_range.is_some() || max_incidence.is_some() {
            return Err(Error::InvalidParameter(
                "max_range and max_incidence need the tracker's position (tracker=(x, y, z))"
                    .into(),
            ));
        }
        return Ok(None);
    };
    let mut view = TrackerView::new(at)?;
    if let Some(r) = max_range {
        view = view.max_range(r)?;
    }
    if let Some(i) = max_incidence {
        view = view.max_incidence(i)?;
    }
    Ok(Some(view))
}

/// The plan's moves (joints k × n, directions k × n, measure flags, the
/// pool row or candidate of each measured pose, −1 for a via-point), its
/// summary as JSON (the command line's `--json`, with its text report
/// under `text`), and the model it used.
type PlanOut<'py> = (
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray2<f64>>,
    Bound<'py, PyArray1<bool>>,
    Bound<'py, PyArray1<i64>>,
    String,
    Option<Model>,
);

/// Plan `budget` poses for `robot` (preset or robot file, with `tool`),
/// as `robokrige plan`: continuing `campaign` (its hyperparameters
/// re-estimated on it), else from a `prior` model, else a space-filling
/// first batch; among the poses of `pool` only, when given; lowering the
/// integrated MSE over `region` (default: the pool's poses, else the
/// robot's working ranges). With `output`, the plan is also written as the
/// command line writes it (`format`: csv, urscript, krl or rapid).
#[pyfunction]
#[pyo3(signature = (robot, budget, *, tool=None, campaign=None, prior=None, pool=None,
    region=None, first_batch=50, candidates=5000, region_points=1000, via_step=5.0,
    passes=1, tracker_at=None, max_range=None, max_incidence=None, target_mm=None, seed=1,
    output=None, format="csv"))]
#[allow(clippy::too_many_arguments)]
pub fn plan<'py>(
    py: Python<'py>,
    robot: &str,
    budget: usize,
    tool: Option<(f64, f64, f64)>,
    campaign: Option<Bound<'py, Data>>,
    prior: Option<Bound<'py, Model>>,
    pool: Option<Bound<'py, Data>>,
    region: Option<RegionArg<'py>>,
    first_batch: usize,
    candidates: usize,
    region_points: usize,
    via_step: f64,
    passes: usize,
    tracker_at: Option<[f64; 3]>,
    max_range: Option<f64>,
    max_incidence: Option<f64>,
    target_mm: Option<f64>,
    seed: u64,
    output: Option<PathBuf>,
    format: &str,
) -> PyResult<PlanOut<'py>> {
    let robot = robot_with_tool(robot, tool).map_err(to_py)?;
    let format = ProgramFormat::from_name(format).map_err(to_py)?;
    if let Some(out) = &output {
        let inputs: Vec<&std::path::Path> = match &region {
            Some(RegionArg::File(p)) => vec![p.as_path()],
            _ => Vec::new(),
        };
        robokrige::output::check_outputs(&inputs, &[out.as_path()]).map_err(to_py)?;
        if format != ProgramFormat::Csv {
            // a program the controller cannot take is refused before planning
            ProgramOptions::for_file(out, format, robot.prismatic_joints()).map_err(to_py)?;
        }
    }
    let campaign = campaign.as_ref().map(|d| &d.get().inner);
    let pool = pool.as_ref().map(|d| &d.get().inner);
    let prior = prior.as_ref().map(|m| &m.get().inner);
    let region = match (&region, pool) {
        (Some(RegionArg::File(path)), _) => Region::from_file(path, &robot).map_err(to_py)?,
        (Some(RegionArg::Poses(d)), _) => Region::Poses(PoseSet::from(&d.get().inner)),
        (None, Some(p)) => Region::Poses(p.into()),
        (None, None) => Region::WorkRange,
    };
    let mut params = PlanParams::new(budget)
        .first_batch(first_batch)
        .candidates(candidates)
        .region_points(region_points)
        .via_step(via_step)
        .passes(passes)
        .seed(seed);
    if let Some(view) = tracker(tracker_at, max_range, max_incidence).map_err(to_py)? {
        params = params.tracker(view);
    }
    let cancel = Cancel::new();
    let params = params.cancel(cancel.clone());
    let out = interrupt::run(py, &cancel, || {
        let mut plan = params.check()?.plan(&PlanInputs {
            robot: &robot,
            campaign,
            prior,
            pool,
            region: &region,
        })?;
        let forecast = Forecast::of_plan(&mut plan, &robot, campaign, &cancel)?;
        if let Some(path) = &output {
            plan.write(path, format, &robot)?;
        }
        let mut summary = robokrige::report::plan::json(&plan, forecast.as_ref());
        summary["text"] = robokrige::report::plan::text(&plan, forecast.as_ref(), target_mm).into();
        Ok((plan, summary))
    })?;
    let (plan, summary) = out.map_err(to_py)?;
    let n = robot.dof();
    let q: Vec<Vec<f64>> = plan.moves.iter().map(|m| m.q.clone()).collect();
    let dir: Vec<Vec<f64>> = plan.moves.iter().map(|m| m.dir.clone()).collect();
    let measure: Vec<bool> = plan.moves.iter().map(|m| m.measure).collect();
    let source: Vec<i64> = plan
        .moves
        .iter()
        .map(|m| match m.pose {
            Some(i) if m.measure => i64::try_from(plan.chosen[i]).unwrap_or(i64::MAX),
            _ => -1,
        })
        .collect();
    Ok((
        rows_to_py(py, &q, n),
        rows_to_py(py, &dir, n),
        PyArray1::from_vec(py, measure),
        PyArray1::from_vec(py, source),
        json(&summary, "plan")?,
        plan.model.map(|inner| Model { inner }),
    ))
}
