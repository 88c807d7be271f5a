//! Correlation families defined outside the crate, registered by name.
//!
//! A model file names its family, so a family of one's own must be known by
//! name wherever a file is read. [`Correlation::register`] records a
//! [`CorrelationModel`] under a name for the life of the process and returns
//! the [`Correlation::Custom`] that fits, saves and predicts with it; reading
//! a file that names it then finds it, in the same process or in another one
//! that registered it too. Registering is idempotent for the same model and
//! refuses a name taken by another one.
//!
//! ```
//! use robokrige::kriging::{Correlation, CorrelationModel, TrainingInputs};
//!
//! /// `R = 1/(1 + h²)`, with `q = R′(h)/(2h) = −R²`.
//! struct RationalQuadratic;
//! impl CorrelationModel for RationalQuadratic {
//!     fn corr(&self, theta: &[f64], a: &[f64], b: &[f64]) -> f64 {
//!         let h2: f64 = (0..a.len()).map(|k| theta[k] * (a[k] - b[k]).powi(2)).sum();
//!         1.0 / (1.0 + h2)
//!     }
//!     fn gradient_weights(&self, _: &[f64], _: &TrainingInputs, _: usize, r: &[f64], w: &mut [f64]) {
//!         for (v, rv) in w.iter_mut().zip(r) {
//!             *v *= rv * rv;
//!         }
//!     }
//! }
//! static RQ: RationalQuadratic = RationalQuadratic;
//! let rq = Correlation::register("rational-quadratic", &RQ).unwrap();
//! assert_eq!(Correlation::parse("rational-quadratic"), Some(rq));
//! ```

use super::corr::{Correlation, CorrelationModel};
use crate::{Error, Result};
use std::sync::{Mutex, OnceLock};

/// A registered family: its name and its model.
pub struct CustomCorrelation {
    name: &'static str,
    model: &'static dyn CorrelationModel,
}

impl CustomCorrelation {
    /// The name in model files.
    pub fn name(&self) -> &'static str {
        self.name
    }

    /// The model.
    pub fn model(&self) -> &'static dyn CorrelationModel {
        self.model
    }
}

impl std::fmt::Debug for CustomCorrelation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("CustomCorrelation")
            .field("name", &self.name)
            .finish_non_exhaustive()
    }
}

/// The families registered in this process (a handful: a linear scan).
fn registry() -> &'static Mutex<Vec<&'static CustomCorrelation>> {
    static REGISTRY: OnceLock<Mutex<Vec<&'static CustomCorrelation>>> = OnceLock::new();
    REGISTRY.get_or_init(|| Mutex::new(Vec::new()))
}

/// The family registered as `name`, if any.
pub(super) fn find(name: &str) -> Option<&'static CustomCorrelation> {
    let families = registry().lock().unwrap_or_else(|e| e.into_inner());
    families.iter().copied().find(|c| c.name == name)
}

impl Correlation {
    /// Register `model` as the family `name` (lowercase letters, digits,
    /// `-` and `_`; not a built-in name nor `auto`) and return it. The
    /// same name with the same model returns the family registered before;
    /// with another model it is an error.
    pub fn register(name: &'static str, model: &'static dyn CorrelationModel) -> Result<Self> {
        let valid = !name.is_empty()
            && name
                .chars()
                .all(|c| c.is_ascii_lowercase() || c.is_ascii_digit() || c == '-' || c == '_');
        if !valid || name == "auto" || Correlation::ALL.iter().any(|c| c.name() == name) {
            return Err(Error::InvalidParameter(format!(
                "cannot register a correlation family as \"{name}\": use lowercase letters, \
                 digits, '-' and '_', and not a built-in name or \"auto\""
            )));
        }
        let mut families = registry().lock().unwrap_or_else(|e| e.into_inner());
        if let Some(c) = families.iter().find(|c| c.name == name) {
            if std::ptr::addr_eq(c.model, model) {
                return Ok(Correlation::Custom(c));
            }
            return Err(Error::InvalidParameter(format!(
                "the correlation family \"{name}\" is registered with another model"
            )));
        }
        // one small allocation per registered name, kept for the process's life
        let family: &'static CustomCorrelation =
            Box::leak(Box::new(CustomCorrelation { name, model }));
        families.push(family);
        Ok(Correlation::Custom(family))
    }
}
