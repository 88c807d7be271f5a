//! Interruptible calls: Ctrl-C stops a long fit, CV, diagnosis or plan.
//!
//! Python runs its signal handlers only on the main thread, and only when
//! that thread runs Python code, so a call that sat inside the library for
//! minutes with the interpreter released could not be interrupted. Here
//! the work runs on a worker thread with the interpreter released, while
//! the calling thread waits for it in slices of [`POLL`] and, between
//! slices, lets Python run its signal handlers (`py.check_signals()`). When
//! one raises (KeyboardInterrupt for Ctrl-C), the work's
//! [`Cancel`] token is set; the library reads it between likelihood
//! evaluations, CV folds, diagnose rounds and the planner's choices, and
//! returns `Error::Interrupted`; the worker is joined and the handler's
//! exception is raised. Without a signal nothing changes: the result is
//! the library's, bit for bit, and the calling thread wakes up as soon as
//! the work is done (not at the next slice).

use pyo3::prelude::*;
use robokrige::cancel::Cancel;
use std::sync::{Condvar, Mutex};
use std::time::Duration;

/// How often the calling thread runs Python's signal handlers while it
/// waits.
pub const POLL: Duration = Duration::from_millis(50);

/// Stack of the worker thread: the command line's main thread has 8 MB,
/// and the work is the same.
const WORKER_STACK: usize = 8 << 20;

/// Set by the worker when it is done; the caller waits on it in slices.
struct Done {
    flag: Mutex<bool>,
    cv: Condvar,
}

impl Done {
    fn set(&self) {
        if let Ok(mut f) = self.flag.lock() {
            *f = true;
        }
        self.cv.notify_all();
    }

    /// Wait at most `slice`; whether the work is done.
    fn wait(&self, slice: Duration) -> bool {
        match self.flag.lock() {
            Ok(f) => self
                .cv
                .wait_timeout_while(f, slice, |done| !*done)
                .map_or(true, |(f, _)| *f),
            // a poisoned lock: the worker panicked, join reports it
            Err(_) => true,
        }
    }
}

/// Run `work` on a worker thread with the interpreter released; between
/// slices of [`POLL`] run Python's signal handlers. The outer error is a
/// handler's exception (the work was cancelled through `cancel` and has
/// stopped); the inner result is the work's.
pub fn run<T, F>(py: Python<'_>, cancel: &Cancel, work: F) -> PyResult<robokrige::Result<T>>
where
    T: Send,
    F: FnOnce() -> robokrige::Result<T> + Send,
{
    let done = Done {
        flag: Mutex::new(false),
        cv: Condvar::new(),
    };
    std::thread::scope(|s| {
        let worker = std::thread::Builder::new()
            .name("robokrige-work".into())
            .stack_size(WORKER_STACK)
            .spawn_scoped(s, || {
                // set on the way out, also when the work panics
                struct SetOnDrop<'a>(&'a Done);
                impl Drop for SetOnDrop<'_> {
                    fn drop(&mut self) {
                        self.0.set();
                    }
                }
                let _guard = SetOnDrop(&done);
                work()
            })
            .map_err(|e| pyo3::exceptions::PyRuntimeError::new_err(e.to_string()))?;
        let mut signal = None;
        while !py.detach(|| done.wait(POLL)) {
            if let Err(e) = py.check_signals() {
                cancel.cancel();
                signal = Some(e);
                break;
            }
        }
        let result = match py.detach(|| worker.join()) {
            Ok(r) => r,
            // a panic in the library: re-raised here, PyO3 turns it into
            // a PanicException at the call's boundary
            Err(panic) => std::panic::resume_unwind(panic),
        };
        match signal {
            Some(e) => Err(e),
            None => Ok(result),
        }
    })
}
