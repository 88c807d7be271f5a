//! The model variants compared in seeds 003 (Table 2, Fig 9) and 004 (Fig 8),
//! by the papers' names. Every method's `fit` does all of its selection on
//! the rows it is given, so inside each training fold of a refit CV.
//!
//! | name | space | trend | hyperparameters |
//! |---|---|---|---|
//! | `js-hj` | JS | constant | Hooke–Jeeves |
//! | `ejs-hj` | EJS | constant | Hooke–Jeeves |
//! | `ejs-gps` | EJS | constant | GPS |
//! | `ejs-pca` | EJS | PCC + PCA fusion of the quadratic candidates (T = 0.1, 99 %) | GPS |
//! | `ejs-ga` | EJS | GA subset of the quadratic candidates, fitness = closed-form K-fold CV RMSE at the constant-trend ξ | GPS |

use crate::kinematics::Robot;
use crate::kriging::{KrigingOptions, OptimizerKind};
use crate::params::{ErrorModelParams, TrendSpec};
use crate::space::Space;
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// GPS starts of the papers' set-ups (box centre + 3 LHS points).
pub const PAPER_GPS_STARTS: usize = OptimizerKind::Gps.default_starts();

/// A named model variant.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "kebab-case")]
pub enum Method {
    /// Not a paper's method: the engine's recommendation for tracker data
    /// (issue 17): EJS, constant trend, BFGS, a nugget estimated, and each
    /// output's correlation family chosen by closed-form CV
    /// ([`crate::kriging::CorrChoice::ByCv`]).
    Recommended,
    /// Seed 003's JS model: joint space `[θ]`, constant trend, Gaussian
    /// correlation, Hooke–Jeeves on ln ψ, interpolating.
    JsHj,
    /// Seed 003's EJS model: `[θ, λ]` (eq 5), otherwise as [`Method::JsHj`].
    EjsHj,
    /// EJS with the hyperparameters by generalised pattern search (seed 004).
    EjsGps,
    /// EJS with each output's trend chosen by PCC + PCA fusion of the
    /// quadratic monomials (seed 003 eqs 15–20; PCC threshold 0.1, 99 % of the
    /// variance).
    EjsPca,
    /// EJS with each output's trend chosen by the genetic algorithm of seed
    /// 004 (fitness: 10-fold CV RMSE).
    EjsGa,
}

/// All methods: the recommended one first, then the papers' in their order.
pub const ALL_METHODS: [Method; 6] = [
    Method::Recommended,
    Method::JsHj,
    Method::EjsHj,
    Method::EjsGps,
    Method::EjsPca,
    Method::EjsGa,
];

impl Method {
    /// The paper-style name (`ejs-gps`, …).
    pub fn name(self) -> &'static str {
        match self {
            Method::Recommended => "recommended",
            Method::JsHj => "js-hj",
            Method::EjsHj => "ejs-hj",
            Method::EjsGps => "ejs-gps",
            Method::EjsPca => "ejs-pca",
            Method::EjsGa => "ejs-ga",
        }
    }

    /// Parse a name; `all` is handled by [`parse_methods`].
    pub fn parse(name: &str) -> Result<Method> {
        ALL_METHODS
            .iter()
            .copied()
            .find(|m| m.name() == name)
            .ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "unknown method '{name}' (known: {}, all)",
                    ALL_METHODS.map(Method::name).join(", ")
                ))
            })
    }

    /// The method's fit parameters: every paper constant is here (GPS with
    /// [`PAPER_GPS_STARTS`] starts, PCC threshold 0.1 and 99 % variance share,
    /// 10 GA folds). `nugget` switches the papers' methods to estimating one;
    /// [`Method::Recommended`] always does.
    pub fn params(self, seed: u64, nugget: bool) -> ErrorModelParams {
        let gps = KrigingOptions {
            seed,
            nugget,
            optimizer: OptimizerKind::Gps,
            starts: PAPER_GPS_STARTS,
            ..KrigingOptions::default()
        };
        let hj = KrigingOptions {
            optimizer: OptimizerKind::HookeJeeves,
            ..gps.clone()
        };
        let p = ErrorModelParams::new();
        match self {
            Method::Recommended => p.kriging(KrigingOptions {
                seed,
                ..KrigingOptions::recommended()
            }),
            Method::JsHj => p.space(Space::Js).kriging(hj),
            Method::EjsHj => p.kriging(hj),
            Method::EjsGps => p.kriging(gps),
            Method::EjsPca | Method::EjsGa => p.kriging(gps).trend(self.trend(None)),
        }
    }

    /// Whether the method selects its trend (PCC + PCA or GA), so that the
    /// rows of a robot's identification Jacobian can join its candidates
    /// ([`Method::trend`]).
    pub fn selects_trend(self) -> bool {
        matches!(self, Method::EjsPca | Method::EjsGa)
    }

    /// The method's trend: the PCC + PCA or GA selection with the papers'
    /// constants (the rows of `kinematic`'s identification Jacobian among
    /// the candidates when given), the options' trend for the others.
    pub fn trend(self, kinematic: Option<&Robot>) -> TrendSpec {
        let kinematic = kinematic.map(|r| Box::new(r.clone()));
        match self {
            Method::EjsPca => TrendSpec::PccPca {
                threshold: PAPER_PCC_THRESHOLD,
                variance_share: PAPER_VARIANCE_SHARE,
                kinematic,
            },
            Method::EjsGa => TrendSpec::Ga {
                folds: PAPER_GA_FOLDS,
                kinematic,
            },
            _ => TrendSpec::Options,
        }
    }
}

/// Seed 003's PCC threshold: candidates with |PCC| below it are dropped.
pub const PAPER_PCC_THRESHOLD: f64 = 0.1;
/// Seed 003's share of the candidates' variance the PCA components keep.
pub const PAPER_VARIANCE_SHARE: f64 = 0.99;
/// Seed 004's CV folds of the GA fitness.
pub const PAPER_GA_FOLDS: usize = 10;

/// `all` or a comma-separated list of method names.
pub fn parse_methods(s: &str) -> Result<Vec<Method>> {
    if s.trim() == "all" {
        return Ok(ALL_METHODS.to_vec());
    }
    s.split(',').map(|n| Method::parse(n.trim())).collect()
}
