//! `Data`: a measurement campaign (`robokrige::dataset::Dataset`) made from
//! NumPy arrays or read from a measurement CSV, and the array conversions.

use crate::to_py;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray1, PyArray2, PyReadonlyArray1, PyReadonlyArray2};
use pyo3::prelude::*;
use pyo3::types::PyList;
use robokrige::dataset::{Covariate, Dataset, DirSource, TextColumn};
use robokrige::{Error, Result};
use std::path::PathBuf;

/// Rows of a 2-D array (read in place through a view, copied once into the
/// library's row format).
pub fn rows(a: &PyReadonlyArray2<'_, f64>) -> Vec<Vec<f64>> {
    a.as_array()
        .rows()
        .into_iter()
        .map(|r| r.to_vec())
        .collect()
}

/// An m × n array of rows that all have `n` entries (the caller's data).
pub fn rows_to_py<'py>(py: Python<'py>, rows: &[Vec<f64>], n: usize) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flat_map(|r| r.iter().copied()).collect();
    match Array2::from_shape_vec((rows.len(), n), flat) {
        Ok(a) => a.into_pyarray(py),
        // rows of unequal length: never made by the library
        Err(_) => PyArray2::zeros(py, (0, n), false),
    }
}

/// An m × 3 array of `[x, y, z]` rows; the buffer is handed to NumPy as is.
pub fn triplets_to_py<'py>(py: Python<'py>, rows: &[[f64; 3]]) -> Bound<'py, PyArray2<f64>> {
    let flat: Vec<f64> = rows.iter().flatten().copied().collect();
    Array2::from_shape_vec((rows.len(), 3), flat)
        .map(|a| a.into_pyarray(py))
        .unwrap_or_else(|_| PyArray2::zeros(py, (0, 3), false))
}

/// `[x, y, z]` rows of an m × 3 array, or an error naming `what`.
pub fn triplets(a: &PyReadonlyArray2<'_, f64>, what: &str, source: &str) -> Result<Vec<[f64; 3]>> {
    let v = a.as_array();
    if v.ncols() != 3 {
        return Err(Error::Input {
            source_name: source.into(),
            message: format!(
                "{what} has {} columns; expected 3 ({})",
                v.ncols(),
                if what == "errors" {
                    "ex, ey, ez in mm"
                } else {
                    "x, y, z in mm"
                }
            ),
        });
    }
    Ok(v.rows().into_iter().map(|r| [r[0], r[1], r[2]]).collect())
}

/// A measurement campaign: poses in visiting order, their directions λ,
/// the measured TCP errors and any covariates.
#[pyclass(module = "robokrige._robokrige", name = "Data", frozen)]
pub struct Data {
    pub inner: Dataset,
}

impl Data {
    /// Build and validate a campaign from its parts.
    #[allow(clippy::too_many_arguments)]
    fn build(
        q: Vec<Vec<f64>>,
        dirs: Option<Vec<Vec<f64>>>,
        errors: Option<Vec<[f64; 3]>>,
        positions: Option<Vec<[f64; 3]>>,
        covariates: Vec<(String, Vec<f64>)>,
        ids: Option<Vec<String>>,
        source: &str,
    ) -> Result<Dataset> {
        let m = q.len();
        let input = |message: String| Error::Input {
            source_name: source.into(),
            message,
        };
        if let Some(d) = &dirs
            && d.len() != m
        {
            return Err(input(format!("dirs has {} rows but q has {m}", d.len())));
        }
        let mut d = Dataset::from_poses(source, q, dirs)?;
        if let Some(e) = &errors
            && e.len() != m
        {
            return Err(input(format!("errors has {} rows but q has {m}", e.len())));
        }
        d.errors = errors;
        if let Some(p) = &positions
            && p.len() != m
        {
            return Err(input(format!(
                "positions has {} rows but q has {m}",
                p.len()
            )));
        }
        d.positions = positions;
        for (name, values) in covariates {
            if values.len() != m {
                return Err(input(format!(
                    "covariate '{name}' has {} values but q has {m} rows",
                    values.len()
                )));
            }
            d.covariates.push(Covariate {
                missing: values.iter().filter(|v| v.is_nan()).count(),
                name,
                values,
            });
        }
        if let Some(ids) = ids {
            if ids.len() != m {
                return Err(input(format!(
                    "ids has {} labels but q has {m} rows",
                    ids.len()
                )));
            }
            d.ids = Some(ids);
        }
        d.validate()?;
        Ok(d)
    }
}

#[pymethods]
impl Data {
    /// Campaign from arrays: `q` (m × n joints, degrees), `dirs` (m × n,
    /// ±1; derived from the row order when None), `errors` (m × 3, mm),
    /// `positions` (m × 3 measured TCP, mm), `covariates` (a list of
    /// (name, m values), NaN = missing), `ids`.
    #[new]
    #[allow(clippy::too_many_arguments)]
    #[pyo3(signature = (q, dirs=None, errors=None, positions=None, covariates=None, ids=None, source="<memory>"))]
    fn new(
        py: Python<'_>,
        q: PyReadonlyArray2<'_, f64>,
        dirs: Option<PyReadonlyArray2<'_, f64>>,
        errors: Option<PyReadonlyArray2<'_, f64>>,
        positions: Option<PyReadonlyArray2<'_, f64>>,
        covariates: Option<Vec<(String, PyReadonlyArray1<'_, f64>)>>,
        ids: Option<Vec<String>>,
        source: &str,
    ) -> PyResult<Self> {
        let q = rows(&q);
        let n = q.first().map_or(0, Vec::len);
        let dirs = match dirs {
            Some(d) => {
                let v = d.as_array();
                if v.ncols() != n {
                    return Err(to_py(Error::Input {
                        source_name: source.into(),
                        message: format!("dirs has {} columns but q has {n} joints", v.ncols()),
                    }));
                }
                Some(rows(&d))
            }
            None => None,
        };
        let errors = errors
            .map(|e| triplets(&e, "errors", source))
            .transpose()
            .map_err(to_py)?;
        let positions = positions
            .map(|e| triplets(&e, "positions", source))
            .transpose()
            .map_err(to_py)?;
        let covariates: Vec<(String, Vec<f64>)> = covariates
            .unwrap_or_default()
            .into_iter()
            .map(|(name, v)| (name, v.as_array().to_vec()))
            .collect();
        let inner = py
            .detach(|| Self::build(q, dirs, errors, positions, covariates, ids, source))
            .map_err(to_py)?;
        Ok(Data { inner })
    }

    /// Read a measurement CSV exactly as the command line does.
    #[staticmethod]
    fn read_csv(py: Python<'_>, path: PathBuf) -> PyResult<Self> {
        let inner = py
            .detach(|| robokrige::dataset::read_csv(&path))
            .map_err(to_py)?;
        Ok(Data { inner })
    }

    /// Number of poses m.
    #[getter]
    fn n_rows(&self) -> usize {
        self.inner.len()
    }

    /// Number of joints n.
    #[getter]
    fn n_joints(&self) -> usize {
        self.inner.n_joints()
    }

    /// The file name (or label) used in messages.
    #[getter]
    fn source(&self) -> &str {
        &self.inner.source
    }

    /// "given" (dir columns or arrays) or "derived" (from the row order).
    #[getter]
    fn dir_source(&self) -> &'static str {
        match self.inner.dir_source {
            DirSource::Given => "given",
            DirSource::Derived => "derived",
        }
    }

    /// Joint positions, m × n.
    #[getter]
    fn q<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows_to_py(py, &self.inner.q, self.inner.n_joints())
    }

    /// Directions λ = ±1, m × n.
    #[getter]
    fn dirs<'py>(&self, py: Python<'py>) -> Bound<'py, PyArray2<f64>> {
        rows_to_py(py, &self.inner.dir, self.inner.n_joints())
    }

    /// TCP errors, m × 3 (mm), or None.
    #[getter]
    fn errors<'py>(&self, py: Python<'py>) -> Option<Bound<'py, PyArray2<f64>>> {
        self.inner.errors.as_deref().map(|e| triplets_to_py(py, e))
    }

    /// Plausibility warnings (radians, repeated poses, text columns).
    fn warnings(&self) -> Vec<String> {
        self.inner.warnings()
    }

    /// Every column in the order the library writes them: id, q1..qN,
    /// dir1..dirN, ex,ey,ez, x,y,z, covariates, text columns; as
    /// (name, values) with a float64 array or a list of strings.
    fn columns<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyList>> {
        let d = &self.inner;
        let out = PyList::empty(py);
        let col = |v: Vec<f64>| PyArray1::from_vec(py, v);
        if let Some(ids) = &d.ids {
            out.append(("id", ids.clone()))?;
        }
        let n = d.n_joints();
        for j in 0..n {
            out.append((
                format!("q{}", j + 1),
                col(d.q.iter().map(|r| r[j]).collect()),
            ))?;
        }
        for j in 0..n {
            out.append((
                format!("dir{}", j + 1),
                col(d.dir.iter().map(|r| r[j]).collect()),
            ))?;
        }
        for (set, names) in [
            (&d.errors, ["ex", "ey", "ez"]),
            (&d.positions, ["x", "y", "z"]),
        ] {
            if let Some(v) = set {
                for (a, name) in names.iter().enumerate() {
                    out.append((*name, col(v.iter().map(|r| r[a]).collect())))?;
                }
            }
        }
        for c in &d.covariates {
            out.append((c.name.clone(), col(c.values.clone())))?;
        }
        for TextColumn { name, values, .. } in &d.text {
            out.append((name.clone(), values.clone()))?;
        }
        Ok(out)
    }

    fn __len__(&self) -> usize {
        self.inner.len()
    }

    fn __repr__(&self) -> String {
        format!(
            "Data({} rows, {} joints, directions {}, {}errors, {} covariates)",
            self.inner.len(),
            self.inner.n_joints(),
            self.dir_source(),
            if self.inner.errors.is_some() {
                ""
            } else {
                "no "
            },
            self.inner.covariates.len()
        )
    }
}
