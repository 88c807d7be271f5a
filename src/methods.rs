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
//!
//! A front end (the command line, Python) names a fit: a method, or the
//! model options one by one, plus the measured robot. [`params_with`] turns
//! those names into [`ErrorModelParams`] and holds every rule between them,
//! so that each front end only maps its flags or arguments to [`Overrides`]
//! and prints the one message a rule gives.
//!
//! ```
//! use robokrige::methods::{Method, Overrides, params_with};
//! use robokrige::kriging::OptimizerKind;
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
//! let data = robokrige::dataset::read_csv(path.as_ref())?;
//! let gps = params_with(Some(Method::from_name("ejs-gps")?), &Overrides::new(), &data)?;
//! assert_eq!(gps.get_kriging().get_optimizer(), OptimizerKind::Gps);
//! // a named method fixes its own options
//! let js = Overrides::new().space(robokrige::space::Space::Js);
//! let err = params_with(Some(Method::EjsGps), &js, &data).unwrap_err();
//! assert!(err.to_string().contains("leave space at the defaults"));
//! # Ok::<(), robokrige::Error>(())
//! ```

use crate::calibration::CalibrationOptions;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::kinematics::Robot;
use crate::kriging::{CorrChoice, KrigingOptions, OptimizerKind, TrendKind};
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
    /// Not a paper's method: the engine's recommendation for tracker data:
    /// EJS, constant trend, BFGS, a nugget estimated, and each
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

    /// The method called `name` ([`Method::name`]); `all` is handled by
    /// [`parse_methods`].
    pub fn from_name(name: &str) -> Result<Method> {
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
    s.split(',').map(|n| Method::from_name(n.trim())).collect()
}

/// What a front end sets on top of a method or of the defaults
/// ([`params_with`]). Each model option left unset keeps the default of
/// `robokrige fit` (EJS, constant trend, `auto` correlation, BFGS with its
/// default starts, a nugget, periodic joints `auto`); a named method fixes
/// them itself and refuses them. Builder setters named after the options.
#[derive(Debug, Clone, PartialEq)]
pub struct Overrides {
    space: Option<Space>,
    trend: Option<TrendKind>,
    corr: Option<CorrChoice>,
    optimizer: Option<OptimizerKind>,
    nugget: Option<bool>,
    starts: Option<usize>,
    periodic: Option<String>,
    seed: u64,
    robot: Option<Robot>,
    kinematic: bool,
    calibration: Option<CalibrationOptions>,
    covariates: Vec<String>,
}

impl Default for Overrides {
    fn default() -> Self {
        Self::new()
    }
}

impl Overrides {
    /// Nothing overridden: seed 1, no robot, a given robot calibrated with
    /// the default [`CalibrationOptions`].
    pub fn new() -> Self {
        Overrides {
            space: None,
            trend: None,
            corr: None,
            optimizer: None,
            nugget: None,
            starts: None,
            periodic: None,
            seed: 1,
            robot: None,
            kinematic: false,
            calibration: Some(CalibrationOptions::default()),
            covariates: Vec::new(),
        }
    }

    /// JS or EJS (default EJS).
    pub fn space(mut self, space: Space) -> Self {
        self.space = Some(space);
        self
    }

    /// The trend kind (default constant).
    pub fn trend(mut self, trend: TrendKind) -> Self {
        self.trend = Some(trend);
        self
    }

    /// The correlation family, or `auto` (the default: its choice by CV,
    /// [`CorrChoice::from_name`]).
    pub fn corr(mut self, corr: impl Into<CorrChoice>) -> Self {
        self.corr = Some(corr.into());
        self
    }

    /// The hyperparameter search (default BFGS).
    pub fn optimizer(mut self, optimizer: OptimizerKind) -> Self {
        self.optimizer = Some(optimizer);
        self
    }

    /// Estimate a nugget (default) or interpolate.
    pub fn nugget(mut self, nugget: bool) -> Self {
        self.nugget = Some(nugget);
        self
    }

    /// Starting points of a BFGS or GPS search (default
    /// [`OptimizerKind::default_starts`]).
    pub fn starts(mut self, starts: usize) -> Self {
        self.starts = Some(starts);
        self
    }

    /// Periodic joints by specification, resolved on the data
    /// ([`crate::space::parse_periodic`]: `auto`, the default, `none`, or
    /// 1-based joint numbers `1,4,6`).
    pub fn periodic(mut self, spec: impl Into<String>) -> Self {
        self.periodic = Some(spec.into());
        self
    }

    /// Seed of the starts (and of a method's search); allowed with a method.
    pub fn seed(mut self, seed: u64) -> Self {
        self.seed = seed;
        self
    }

    /// The measured robot: recorded in the model, calibrated first unless
    /// [`Overrides::calibrate`] says otherwise or the trend is kinematic.
    pub fn robot(mut self, robot: Robot) -> Self {
        self.robot = Some(robot);
        self
    }

    /// Add the robot's identification Jacobian to the trend (one fit
    /// calibrates and krigs); with a method, to its selection's candidates.
    pub fn kinematic(mut self, kinematic: bool) -> Self {
        self.kinematic = kinematic;
        self
    }

    /// How a given robot is calibrated before the Kriging fit; `None`:
    /// Kriging of the raw error. Ignored with the kinematic trend.
    pub fn calibrate(mut self, calibration: Option<CalibrationOptions>) -> Self {
        self.calibration = calibration;
        self
    }

    /// Covariate columns of the campaign (by name) that enter the model as
    /// inputs: each an input dimension with its own correlation length and
    /// a linear trend term ([`Feature::Covariate`], as `diagnose` adds a
    /// covariate), its first value the reference for predictions without
    /// the column. Empty by default: covariates are carried, not modelled.
    pub fn covariates(mut self, names: Vec<String>) -> Self {
        self.covariates = names;
        self
    }

    /// `set` with `value` when one is given (a front end's optional option),
    /// e.g. `.with(space, Overrides::space)`.
    pub fn with<T>(self, value: Option<T>, set: impl FnOnce(Self, T) -> Self) -> Self {
        match value {
            Some(v) => set(self, v),
            None => self,
        }
    }

    /// The rules between the names, before anything is built.
    fn check(&self, method: Option<Method>) -> Result<()> {
        let bad = |m: String| Err(Error::InvalidParameter(m));
        if let Some(m) = method {
            let given: Vec<&str> = [
                ("space", self.space.is_some()),
                ("trend", self.trend.is_some()),
                ("corr", self.corr.is_some()),
                ("optimizer", self.optimizer.is_some()),
                ("nugget", self.nugget.is_some()),
                ("starts", self.starts.is_some()),
                ("periodic", self.periodic.is_some()),
            ]
            .iter()
            .filter_map(|&(name, set)| set.then_some(name))
            .collect();
            if !given.is_empty() {
                return bad(format!(
                    "method '{}' fixes its own settings: leave {} at the defaults",
                    m.name(),
                    given.join(", ")
                ));
            }
        }
        if self.starts.is_some() && self.optimizer == Some(OptimizerKind::HookeJeeves) {
            return bad("starts is for optimizer 'bfgs' or 'gps' (Hooke–Jeeves runs once, from the centre of the box)".into());
        }
        if self.kinematic && self.robot.is_none() {
            return bad("kinematic needs robot (the robot whose Jacobian forms the trend)".into());
        }
        match method {
            Some(m) if self.kinematic && !m.selects_trend() => bad(format!(
                "kinematic with method '{}': it works for ejs-pca and ejs-ga (selection among polynomial and kinematic candidates); use kinematic without a method otherwise",
                m.name()
            )),
            _ => Ok(()),
        }
    }

    /// The model options one by one, defaults where unset, periodic joints
    /// resolved on `data`'s rows. The one place `KrigingOptions` is built
    /// from names.
    fn options_params(&self, data: &Dataset) -> Result<ErrorModelParams> {
        let optimizer = self.optimizer.unwrap_or(OptimizerKind::Bfgs);
        let opts = KrigingOptions::default()
            .trend(self.trend.unwrap_or(TrendKind::Constant))
            .corr(self.corr.unwrap_or(CorrChoice::AUTO))
            .optimizer(optimizer)
            .nugget(self.nugget.unwrap_or(true))
            .starts(self.starts.unwrap_or(optimizer.default_starts()))
            .seed(self.seed);
        let periodic =
            crate::space::parse_periodic(self.periodic.as_deref().unwrap_or("auto"), &data.q)?;
        Ok(ErrorModelParams::new()
            .space(self.space.unwrap_or(Space::Ejs))
            .periodic(periodic)
            .kriging(opts))
    }
}

/// The default error model for a campaign of `robot`: what `fit --robot R`
/// fits (the robot calibrated first, then Kriging of what it leaves, every
/// other choice at its default). `params_with(None, robot only, data)`.
pub fn default_params(robot: &Robot, data: &Dataset) -> Result<ErrorModelParams> {
    params_with(None, &Overrides::new().robot(robot.clone()), data)
}

/// The fit parameters a front end names: `method` (`None`: the model
/// options of `overrides`, defaults where unset) with the robot of
/// `overrides`, checked against `data` (its joint count; periodic joints
/// resolved on its rows). Every rule between the names is here, with one
/// message each:
/// - a named method fixes its own space, trend, correlation, optimiser,
///   nugget, starts and periodic joints, and refuses them;
/// - `starts` is for BFGS and GPS (Hooke–Jeeves runs once);
/// - `kinematic` needs the robot, and with a method only a selecting one
///   (`ejs-pca`, `ejs-ga`) takes it: its selection then runs among the
///   polynomial and kinematic candidates, on the default options;
/// - a robot is calibrated first unless the trend is kinematic or
///   [`Overrides::calibrate`] is `None`.
///
/// The result still goes through [`ErrorModelParams::check`].
pub fn params_with(
    method: Option<Method>,
    overrides: &Overrides,
    data: &Dataset,
) -> Result<ErrorModelParams> {
    let o = overrides;
    o.check(method)?;
    if let Some(r) = &o.robot {
        r.check_dataset(data)?;
    }
    let kinematic = o.robot.as_ref().filter(|_| o.kinematic);
    let params = match (method, kinematic) {
        (Some(m), None) => m.params(o.seed, false),
        (Some(m), Some(r)) => o.options_params(data)?.trend(m.trend(Some(r))),
        (None, Some(r)) => o
            .options_params(data)?
            .trend(TrendSpec::Kinematic(Box::new(r.clone()))),
        (None, None) => o.options_params(data)?,
    };
    let params = match &o.robot {
        Some(r) => params
            .robot(r.clone())
            .calibrate(o.calibration.clone().filter(|_| !o.kinematic)),
        None => params,
    };
    if o.covariates.is_empty() {
        return Ok(params);
    }
    Ok(params.extras(covariate_inputs(&o.covariates, data)?))
}

/// [`Overrides::covariates`] as features of `data`: each column present,
/// numeric and complete, named once.
fn covariate_inputs(names: &[String], data: &Dataset) -> Result<Vec<Feature>> {
    let mut out = Vec::with_capacity(names.len());
    for (k, name) in names.iter().enumerate() {
        if names[..k].contains(name) {
            return Err(Error::InvalidParameter(format!(
                "covariate '{name}' is named twice"
            )));
        }
        let f = Feature::Covariate {
            name: name.clone(),
            reference: None,
        };
        // the library's own messages: missing, read as text, or incomplete
        let values = f.columns(data)?.remove(0);
        out.push(Feature::Covariate {
            name: name.clone(),
            reference: values.first().copied(),
        });
    }
    Ok(out)
}
