//! `PhysicsModel`: a physics-based error model file (`robokrige physics
//! identify -o`: D-H calibration and lookup tables), to compensate with as
//! the command line's `compensate --model` does.

use crate::data::{Data, triplets_to_py};
use crate::model::json;
use crate::to_py;
use numpy::PyArray2;
use pyo3::prelude::*;
use robokrige::physics::{AnyModel, PhysicsModel as Inner};
use std::path::PathBuf;

/// A physics-based TCP error model (seed 000 / 002: the identified
/// geometry and the joints' lookup tables).
#[pyclass(module = "robokrige._robokrige", name = "PhysicsModel", frozen)]
pub struct PhysicsModel {
    pub inner: Inner,
}

#[pymethods]
impl PhysicsModel {
    /// Read a physics model file (`robokrige physics identify -o`).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<PhysicsModel> {
        let inner = py.detach(|| Inner::load(&path)).map_err(to_py)?;
        Ok(PhysicsModel { inner })
    }

    /// Write the model file (pretty JSON), atomically.
    fn save(&self, py: Python<'_>, path: PathBuf) -> PyResult<()> {
        py.detach(|| self.inner.save(&path)).map_err(to_py)
    }

    /// Predicted TCP errors (m × 3, mm) at the poses of `data` (joints and
    /// directions).
    fn predict<'py>(&self, py: Python<'py>, data: &Data) -> PyResult<Bound<'py, PyArray2<f64>>> {
        let d = &data.inner;
        self.inner.nominal.check_dataset(d).map_err(to_py)?;
        let mean = py
            .detach(|| self.inner.predict(&d.q, &d.dir))
            .map_err(to_py)?;
        Ok(triplets_to_py(py, &mean))
    }

    /// One line on how it was identified.
    #[getter]
    fn description(&self) -> &str {
        &self.inner.description
    }

    /// Whether it has lookup tables (else the D-H model alone).
    #[getter]
    fn has_tables(&self) -> bool {
        self.inner.has_tables()
    }

    /// Joints of the robot.
    #[getter]
    fn n_joints(&self) -> usize {
        self.inner.nominal.dof()
    }

    /// The nominal robot (the controller's kinematics), as JSON text.
    fn robot_json(&self) -> PyResult<String> {
        json(&self.inner.nominal, "robot")
    }

    fn __repr__(&self) -> String {
        format!(
            "PhysicsModel({}: {})",
            self.inner.nominal.name,
            AnyModel::Physics(Box::new(self.inner.clone())).describe()
        )
    }
}
