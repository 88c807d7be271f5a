//! Cooperative cancellation of long work: a [`Cancel`] token that the caller
//! keeps and sets from another thread (a Ctrl-C handler, a GUI button, the
//! Python bindings' signal check), and that long loops read.
//!
//! The work carries the token in its parameters (`cancel` builder setters
//! of `KrigingOptions`, `ErrorModelParams`, `DiagnoseOptions` and
//! `PlanParams`; this module, at the bottom layer, knows none of them) and
//! reads it between units of work: likelihood evaluations, GA generations,
//! CV folds, the rounds and resample batches of a diagnosis, the poses a
//! planner chooses. A requested cancellation ends the work with
//! [`Error::Interrupted`] within one such unit.
//!
//! A token that is never set changes nothing: reading it is one relaxed
//! atomic load, and every result is bit for bit what it is without one.
//! The default token ([`Cancel::never`]) cannot be set at all.
//!
//! ```
//! use robokrige::cancel::Cancel;
//! let token = Cancel::new();
//! let handle = token.clone(); // e.g. moved into a signal handler
//! assert!(token.check().is_ok());
//! handle.cancel();
//! assert!(token.is_cancelled());
//! assert!(matches!(token.check(), Err(robokrige::Error::Interrupted)));
//! ```

use crate::{Error, Result};
use std::sync::Arc;
use std::sync::atomic::{AtomicBool, Ordering};

/// A cancellation token: clones share one flag. [`Cancel::never`] (the
/// default) holds none and is never cancelled.
///
/// Equality ignores the token: two options that differ only by their token
/// ask for the same computation (and give the same result unless one is
/// cancelled), so `KrigingOptions` and the params that hold one compare by
/// what they compute.
#[derive(Clone, Default)]
pub struct Cancel(Option<Arc<AtomicBool>>);

impl Cancel {
    /// A fresh token, not cancelled.
    pub fn new() -> Self {
        Cancel(Some(Arc::new(AtomicBool::new(false))))
    }

    /// A token that is never cancelled (the default; nothing is shared).
    pub const fn never() -> Self {
        Cancel(None)
    }

    /// Ask the work that holds this token (or a clone of it) to stop. No
    /// effect on [`Cancel::never`].
    pub fn cancel(&self) {
        if let Some(flag) = &self.0 {
            flag.store(true, Ordering::Relaxed);
        }
    }

    /// Whether a cancellation was requested.
    pub fn is_cancelled(&self) -> bool {
        self.0.as_ref().is_some_and(|f| f.load(Ordering::Relaxed))
    }

    /// `Err(`[`Error::Interrupted`]`)` once a cancellation was requested.
    pub fn check(&self) -> Result<()> {
        if self.is_cancelled() {
            Err(Error::Interrupted)
        } else {
            Ok(())
        }
    }
}

impl PartialEq for Cancel {
    /// Always true: a token is not part of what is computed.
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

impl std::fmt::Debug for Cancel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.0 {
            None => f.write_str("Cancel::never()"),
            Some(_) => write!(f, "Cancel {{ cancelled: {} }}", self.is_cancelled()),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clones_share_the_flag_and_never_stays_clear() {
        let a = Cancel::new();
        let b = a.clone();
        assert!(!b.is_cancelled() && b.check().is_ok());
        a.cancel();
        assert!(b.is_cancelled());
        assert!(matches!(b.check(), Err(Error::Interrupted)));
        let n = Cancel::never();
        n.cancel();
        assert!(!n.is_cancelled() && n.check().is_ok());
        assert_eq!(a, n, "tokens do not take part in equality");
        assert_eq!(format!("{a:?}"), "Cancel { cancelled: true }");
        assert_eq!(format!("{n:?}"), "Cancel::never()");
    }
}
