//! `Model`: a fitted `robokrige::model::ErrorModel`: fit, predict, files.

use crate::data::{Data, triplets_to_py};
use crate::params::FitParams;
use crate::progress::Progress;
use crate::{access, interrupt, to_py};
use numpy::PyArray2;
use pyo3::prelude::*;
use robokrige::Error;
use robokrige::cancel::Cancel;
use robokrige::dataset::Dataset;
use robokrige::kriging::OptimizerKind;
use robokrige::model::ErrorModel;
use std::path::PathBuf;

/// Predicted means and, if asked for, standard deviations (m × 3 each).
type MeanStd<'py> = (Bound<'py, PyArray2<f64>>, Option<Bound<'py, PyArray2<f64>>>);

/// A fitted TCP error model: one universal-Kriging model per axis.
#[pyclass(module = "robokrige._robokrige", name = "Model", frozen)]
pub struct Model {
    pub inner: ErrorModel,
}

/// A JSON value of the library as text (parsed by the Python layer).
pub fn json(value: &impl serde::Serialize, what: &str) -> PyResult<String> {
    serde_json::to_string(value).map_err(|e| {
        to_py(Error::Json {
            context: what.into(),
            source: e,
        })
    })
}

/// Refuse a fit of `rows` rows that would exceed the memory limit, with
/// the command line's rule ([`robokrige::model::check_fit_memory`]).
pub fn check_memory(rows: usize, optimizer: OptimizerKind) -> robokrige::Result<()> {
    robokrige::model::check_fit_memory(rows, optimizer, |n| {
        format!("e.g. the first {n} rows, q[:{n}]")
    })?;
    Ok(())
}

/// Fit `params` on `data` on a worker thread, interruptible by Ctrl-C
/// ([`interrupt::run`]); GA generations go to `progress` as
/// `(generation, 0, message)`.
pub fn fit_model(
    py: Python<'_>,
    data: &Dataset,
    params: &FitParams,
    progress: Option<Py<PyAny>>,
) -> PyResult<ErrorModel> {
    let cancel = Cancel::new();
    let p = Progress::new(progress, &cancel);
    let model = interrupt::run(py, &cancel, || {
        let valid = params.resolve(data, &cancel)?;
        check_memory(data.len(), access::optimizer(valid.params().get_kriging()))?;
        valid.fit_with_progress(data, &|axis: usize, generation: usize, best: f64| {
            p.call((
                generation,
                0usize,
                robokrige::report::fit::ga_progress(axis.min(2), generation, best),
            ))
        })
    })?;
    // the callback's exception first: it may have cancelled the fit
    p.finish()?;
    model.map_err(to_py)
}

impl Model {
    /// Error unless `data` has the model's joint count (the CLI's message).
    fn check_joints(&self, data: &Dataset) -> PyResult<()> {
        let n = access::n_joints(&self.inner);
        if data.n_joints() != n {
            return Err(to_py(Error::Input {
                source_name: data.source.clone(),
                message: format!(
                    "has {} joints but the model was fitted on {n}",
                    data.n_joints()
                ),
            }));
        }
        Ok(())
    }
}

#[pymethods]
impl Model {
    /// Fit on `data` with `params` (a dict of the estimator's parameters).
    #[staticmethod]
    #[pyo3(signature = (data, params, progress=None))]
    fn fit(
        py: Python<'_>,
        data: &Data,
        params: FitParams,
        progress: Option<Py<PyAny>>,
    ) -> PyResult<Model> {
        Ok(Model {
            inner: fit_model(py, &data.inner, &params, progress)?,
        })
    }

    /// Predicted errors (m × 3, mm) at the poses of `data`, and their
    /// standard deviations √MSE (m × 3) when `return_std`.
    #[pyo3(signature = (data, return_std=true))]
    fn predict<'py>(
        &self,
        py: Python<'py>,
        data: &Data,
        return_std: bool,
    ) -> PyResult<MeanStd<'py>> {
        self.check_joints(&data.inner)?;
        let d = &data.inner;
        let m = &self.inner;
        if !return_std && access::extras(m).is_empty() {
            // the fast path compensation uses: no m × m factor
            let mean = py.detach(|| m.predict_mean(&d.q, &d.dir)).map_err(to_py)?;
            return Ok((triplets_to_py(py, &mean), None));
        }
        let pred = py.detach(|| m.predict_dataset(d)).map_err(to_py)?;
        let std = return_std.then(|| triplets_to_py(py, &pred.std));
        Ok((triplets_to_py(py, &pred.mean), std))
    }

    /// The points of a prediction that leave what the training campaign
    /// covers, as (index, [issue, …]) in order (`std`: the prediction's
    /// standard deviations, if computed).
    #[pyo3(signature = (data, mean, std=None))]
    fn coverage(
        &self,
        py: Python<'_>,
        data: &Data,
        mean: numpy::PyReadonlyArray2<'_, f64>,
        std: Option<numpy::PyReadonlyArray2<'_, f64>>,
    ) -> PyResult<Vec<(usize, Vec<String>)>> {
        self.check_joints(&data.inner)?;
        let src = &data.inner.source;
        let mean = crate::data::triplets(&mean, "mean", src).map_err(to_py)?;
        let std = std
            .map(|s| crate::data::triplets(&s, "std", src))
            .transpose()
            .map_err(to_py)?;
        let d = &data.inner;
        if mean.len() != d.len() || std.as_ref().is_some_and(|s| s.len() != d.len()) {
            return Err(crate::invalid(
                "coverage: mean and std need one row per pose",
            ));
        }
        let w = py
            .detach(|| self.inner.coverage(&d.q, &d.dir, &mean, std.as_deref()))
            .map_err(to_py)?;
        Ok(w.into_iter()
            .map(|c| (c.index, c.issues.iter().map(ToString::to_string).collect()))
            .collect())
    }

    /// How far (mm, 3D) the prediction at joints `q` moves when every
    /// direction in `dir` is reversed (0 in joint space).
    fn direction_sensitivity(&self, q: Vec<f64>, dir: Vec<f64>) -> PyResult<f64> {
        let n = access::n_joints(&self.inner);
        if q.len() != n || dir.len() != n {
            return Err(to_py(Error::JointCount {
                expected: n,
                got: if q.len() != n { q.len() } else { dir.len() },
            }));
        }
        if dir.iter().any(|v| *v != 1.0 && *v != -1.0) || q.iter().any(|v| !v.is_finite()) {
            return Err(crate::invalid(
                "direction_sensitivity needs finite joints and directions of ±1",
            ));
        }
        self.inner.direction_sensitivity(&q, &dir).map_err(to_py)
    }

    /// Write the model file (the command line's JSON), atomically.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.save(&path)).map_err(to_py)
    }

    /// Read a model file written by `save` or by `robokrige fit`.
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Model> {
        let inner = py.detach(|| ErrorModel::load(&path)).map_err(to_py)?;
        Ok(Model { inner })
    }

    /// The model file's JSON text.
    fn to_json(&self) -> PyResult<String> {
        self.inner.to_json().map_err(to_py)
    }

    /// A model from model-file JSON text (`source_name` for messages).
    #[staticmethod]
    #[pyo3(signature = (text, source_name="<memory>"))]
    fn from_json(text: &str, source_name: &str) -> PyResult<Model> {
        let inner = ErrorModel::from_json(text, source_name).map_err(to_py)?;
        Ok(Model { inner })
    }

    /// "ejs" or "js".
    #[getter]
    fn space(&self) -> &'static str {
        match access::space(&self.inner) {
            robokrige::space::Space::Ejs => "ejs",
            robokrige::space::Space::Js => "js",
        }
    }

    /// Joints of the robot.
    #[getter]
    fn n_joints(&self) -> usize {
        access::n_joints(&self.inner)
    }

    /// Training rows.
    #[getter]
    fn n_rows(&self) -> usize {
        access::training_rows(&self.inner)
    }

    /// Name of every input column.
    #[getter]
    fn input_names(&self) -> Vec<String> {
        access::input_names(&self.inner).to_vec()
    }

    /// Correlation family of each output (ex, ey, ez).
    #[getter]
    fn families(&self) -> Vec<String> {
        access::families(&self.inner)
    }

    /// Whether a nugget was estimated.
    #[getter]
    fn nugget(&self) -> bool {
        access::nugget(access::options(&self.inner))
    }

    /// Whether each output's family was chosen by CV.
    #[getter]
    fn corr_auto(&self) -> bool {
        access::corr_auto(access::options(&self.inner))
    }

    /// Joints entered as (sin θ, cos θ), 0-based.
    #[getter]
    fn periodic(&self) -> Vec<usize> {
        access::periodic(&self.inner).to_vec()
    }

    /// Names of the extra inputs (effects added by `diagnose`).
    #[getter]
    fn extras(&self) -> Vec<String> {
        access::extras(&self.inner)
            .iter()
            .flat_map(|f| f.names())
            .collect()
    }

    /// The per-axis fit reports, as JSON text.
    fn reports_json(&self) -> PyResult<String> {
        json(&access::reports(&self.inner), "fit reports")
    }

    /// The fitting options, as JSON text.
    fn options_json(&self) -> PyResult<String> {
        json(access::options(&self.inner), "options")
    }

    /// The robot the model records (name, table digest, tool), as JSON text.
    fn robot_json(&self) -> PyResult<String> {
        json(&access::robot(&self.inner), "robot")
    }

    /// The measurement-noise standard deviation per axis (mm) the nugget
    /// attributes, times the model's interval scale (the predicted std is
    /// calibrated on the same leave-one-out residuals): add it in
    /// quadrature to a predicted std for a new measurement's.
    fn noise_std(&self) -> PyResult<[f64; 3]> {
        self.inner.predictive_noise_std().map_err(to_py)
    }

    /// The calibration under the model (identifiability report: directions
    /// seen, observability indices, parameters), as JSON text; "null"
    /// without one.
    fn calibration_json(&self) -> PyResult<String> {
        json(
            &self.inner.calibration().map(|c| c.identifiability()),
            "calibration",
        )
    }

    /// Warnings about the conditioning of the fit.
    fn conditioning_warnings(&self) -> Vec<String> {
        self.inner.conditioning_warnings()
    }

    fn __eq__(&self, other: &Bound<'_, PyAny>) -> bool {
        other
            .cast::<Model>()
            .is_ok_and(|o| o.get().inner == self.inner)
    }

    fn __reduce__<'py>(slf: &Bound<'py, Self>) -> PyResult<(Bound<'py, PyAny>, (String,))> {
        let from_json = slf.get_type().getattr("from_json")?;
        Ok((from_json, (slf.get().inner.to_json().map_err(to_py)?,)))
    }

    fn __repr__(&self) -> String {
        format!(
            "Model({} rows, {} joints, space {}, families {})",
            self.n_rows(),
            self.n_joints(),
            self.space(),
            self.families().join("/")
        )
    }
}
