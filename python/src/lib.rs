//! `robokrige._robokrige`: the extension module under the `robokrige` Python
//! package. It binds the library's one fit API (`ErrorModelParams` →
//! `check` → `fit`), prediction, model files, cross-validation,
//! compensation and diagnosis. The pure-Python layer (`robokrige/*.py`)
//! turns NumPy arrays and pandas frames into the calls made here.
//!
//! Rules kept here:
//! - every input is checked before it reaches code that could panic (shapes
//!   here, values by `Dataset::validate` and the options' `validate`);
//! - every `robokrige::Error` becomes `robokrige.RobokrigeError` with the
//!   library's message, word for word;
//! - every long call runs with the interpreter released (`Python::detach`);
//!   progress callbacks attach again to call into Python;
//! - fits, CV, diagnoses and plans run on a worker thread while the calling
//!   thread runs Python's signal handlers every 50 ms: Ctrl-C sets the
//!   work's cancellation token, and the call raises KeyboardInterrupt once
//!   the library has stopped (`interrupt`).

mod access;
mod data;
mod interrupt;
mod model;
mod params;
mod physics;
mod plan;
mod progress;
mod studies;

use pyo3::create_exception;
use pyo3::exceptions::PyValueError;
use pyo3::prelude::*;

create_exception!(
    robokrige,
    RobokrigeError,
    PyValueError,
    "A robokrige failure: bad data, a bad parameter, a numerical failure. The message is the library's (and the command line's) own."
);

/// The library's error as a Python exception, with the same message.
pub fn to_py(e: robokrige::Error) -> PyErr {
    RobokrigeError::new_err(e.to_string())
}

/// A `RobokrigeError` with a message of this crate (argument checks).
pub fn invalid(message: impl Into<String>) -> PyErr {
    to_py(robokrige::Error::InvalidParameter(message.into()))
}

/// The robokrige library version these bindings were built with.
#[pyfunction]
fn library_version() -> &'static str {
    robokrige::model::SOFTWARE
}

/// Which build of the extension this is: "x86-64-v3" when it was compiled
/// with AVX2 and FMA enabled (runs only on such CPUs), "x86-64" for the
/// portable baseline (faer still dispatches its kernels at run time), or
/// the target architecture elsewhere.
#[pyfunction]
fn build_target_cpu() -> &'static str {
    if cfg!(all(
        target_arch = "x86_64",
        target_feature = "avx2",
        target_feature = "fma"
    )) {
        "x86-64-v3"
    } else if cfg!(target_arch = "x86_64") {
        "x86-64"
    } else {
        std::env::consts::ARCH
    }
}

#[pymodule]
fn _robokrige(m: &Bound<'_, PyModule>) -> PyResult<()> {
    m.add("RobokrigeError", m.py().get_type::<RobokrigeError>())?;
    m.add_class::<data::Data>()?;
    m.add_class::<model::Model>()?;
    m.add_class::<physics::PhysicsModel>()?;
    m.add_function(wrap_pyfunction!(library_version, m)?)?;
    m.add_function(wrap_pyfunction!(build_target_cpu, m)?)?;
    m.add_function(wrap_pyfunction!(studies::cross_validate, m)?)?;
    m.add_function(wrap_pyfunction!(studies::compensate, m)?)?;
    m.add_function(wrap_pyfunction!(studies::diagnose, m)?)?;
    m.add_function(wrap_pyfunction!(plan::plan, m)?)?;
    Ok(())
}
