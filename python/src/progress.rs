//! Progress callbacks: called from the library's worker threads while the
//! interpreter is released, each call attaching to it again. A callback that
//! raises stops the computation (its call's [`Cancel`] token is set, and the
//! library stops at its next check); its first exception is raised when the
//! call returns.

use pyo3::prelude::*;
use robokrige::cancel::Cancel;
use std::sync::Mutex;

/// An optional Python callable, the token of its call, and the first
/// exception the callable raised.
pub struct Progress {
    callback: Option<Py<PyAny>>,
    cancel: Cancel,
    error: Mutex<Option<PyErr>>,
}

impl Progress {
    pub fn new(callback: Option<Py<PyAny>>, cancel: &Cancel) -> Self {
        Progress {
            callback,
            cancel: cancel.clone(),
            error: Mutex::new(None),
        }
    }

    /// Call the callback with `args` (attaching to the interpreter); keep
    /// its first exception and cancel the call. After one exception it is
    /// not called again.
    pub fn call<A>(&self, args: A)
    where
        A: for<'py> pyo3::call::PyCallArgs<'py>,
    {
        let Some(cb) = &self.callback else { return };
        let Ok(mut err) = self.error.lock() else {
            return;
        };
        if err.is_some() {
            return;
        }
        Python::attach(|py| {
            if let Err(e) = cb.call1(py, args) {
                *err = Some(e);
                self.cancel.cancel();
            }
        });
    }

    /// The callback's first exception, if it raised.
    pub fn finish(self) -> PyResult<()> {
        match self.error.into_inner() {
            Ok(Some(e)) => Err(e),
            _ => Ok(()),
        }
    }
}
