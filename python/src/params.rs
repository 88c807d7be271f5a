//! The Python estimator's parameters → the library's checked fit parameters
//! (`ErrorModelParams` → `check`), with the command line's defaults and
//! rules (`robokrige fit`'s `ModelArgs`), so that the same data and the
//! same settings give the same model file.

use pyo3::prelude::*;
use robokrige::calibration::CalibrationOptions;
use robokrige::cancel::Cancel;
use robokrige::dataset::Dataset;
use robokrige::kinematics::Robot;
use robokrige::kriging::CorrChoice;
use robokrige::kriging::{OptimizerKind, TrendKind};
use robokrige::methods::{Method, Overrides, params_with};
use robokrige::params::ValidErrorModelParams;
use robokrige::space::Space;
use robokrige::{Error, Result};

/// `ErrorModel.get_params()` of the Python layer, read item by item. A
/// model option is `None` when left at its default (the library's default
/// then applies, and a named method does not count it as given).
#[derive(Debug, Clone, FromPyObject)]
pub struct FitParams {
    #[pyo3(item)]
    pub space: Option<String>,
    #[pyo3(item)]
    pub trend: Option<String>,
    #[pyo3(item)]
    pub nugget: Option<bool>,
    #[pyo3(item)]
    pub corr: Option<String>,
    #[pyo3(item)]
    pub optimizer: Option<String>,
    #[pyo3(item)]
    pub starts: Option<usize>,
    #[pyo3(item)]
    pub seed: u64,
    #[pyo3(item)]
    pub periodic: Option<String>,
    #[pyo3(item)]
    pub robot: Option<String>,
    #[pyo3(item)]
    pub tool: Option<(f64, f64, f64)>,
    #[pyo3(item)]
    pub kinematic: bool,
    #[pyo3(item)]
    pub calibrate: bool,
    #[pyo3(item)]
    pub joint_harmonics: bool,
    #[pyo3(item)]
    pub backlash: bool,
    #[pyo3(item)]
    pub method: Option<String>,
    /// Covariate columns that enter the model as inputs
    /// ([`Overrides::covariates`]); none in the campaign form of `fit`.
    #[pyo3(item)]
    pub covariate_inputs: Option<Vec<String>>,
}

fn bad(message: String) -> Error {
    Error::InvalidParameter(message)
}

/// `"ejs"` or `"js"`.
pub fn parse_space(s: &str) -> Result<Space> {
    match s {
        "ejs" => Ok(Space::Ejs),
        "js" => Ok(Space::Js),
        _ => Err(bad(format!("space '{s}': expected 'ejs' or 'js'"))),
    }
}

fn parse_trend(s: &str) -> Result<TrendKind> {
    match s {
        "constant" => Ok(TrendKind::Constant),
        "linear" => Ok(TrendKind::Linear),
        "quadratic" => Ok(TrendKind::Quadratic),
        _ => Err(bad(format!(
            "trend '{s}': expected 'constant', 'linear' or 'quadratic'"
        ))),
    }
}

/// `"bfgs"`, `"gps"` or `"hj"`.
pub fn parse_optimizer(s: &str) -> Result<OptimizerKind> {
    match s {
        "bfgs" => Ok(OptimizerKind::Bfgs),
        "gps" => Ok(OptimizerKind::Gps),
        "hj" => Ok(OptimizerKind::HookeJeeves),
        _ => Err(bad(format!(
            "optimizer '{s}': expected 'bfgs', 'gps' or 'hj'"
        ))),
    }
}

/// Periodic joints as `--periodic`: "auto" (range over 180° in `q`),
/// "none", or 1-based joint numbers "1,4,6" (the library's rule).
pub fn parse_periodic(spec: &str, q: &[Vec<f64>]) -> Result<Vec<usize>> {
    robokrige::space::parse_periodic(spec, q)
}

/// A preset name or robot file, with its tool translation replaced (mm):
/// the library's [`Robot::with_tool_translation`].
pub fn robot_with_tool(spec: &str, tool: Option<(f64, f64, f64)>) -> Result<Robot> {
    let robot = robokrige::kinematics::load_robot(spec)?;
    match tool {
        Some((x, y, z)) => robot.with_tool_translation([x, y, z]),
        None => Ok(robot),
    }
}

impl FitParams {
    /// The parameters given, as the library's overrides (the rules and
    /// defaults are the library's: [`params_with`]).
    fn overrides(&self) -> Result<Overrides> {
        let robot = self
            .robot
            .as_deref()
            .map(|r| robot_with_tool(r, self.tool))
            .transpose()?;
        if self.tool.is_some() && robot.is_none() {
            return Err(bad("tool needs robot (the robot the tool is on)".into()));
        }
        let mut o = Overrides::new()
            .seed(self.seed)
            .kinematic(self.kinematic)
            .calibrate(self.calibrate.then(|| {
                CalibrationOptions {
                    joint_harmonics: self.joint_harmonics,
                    ..CalibrationOptions::default()
                }
                .with_backlash(self.backlash)
            }));
        if let Some(v) = &self.space {
            o = o.space(parse_space(v)?);
        }
        if let Some(v) = &self.trend {
            o = o.trend(parse_trend(v)?);
        }
        if let Some(v) = &self.corr {
            o = o.corr(CorrChoice::from_name(v)?);
        }
        if let Some(v) = &self.optimizer {
            o = o.optimizer(parse_optimizer(v)?);
        }
        if let Some(v) = self.nugget {
            o = o.nugget(v);
        }
        if let Some(v) = self.starts {
            o = o.starts(v);
        }
        if let Some(v) = &self.periodic {
            o = o.periodic(v.as_str());
        }
        if let Some(r) = robot {
            o = o.robot(r);
        }
        if let Some(c) = &self.covariate_inputs {
            o = o.covariates(c.clone());
        }
        Ok(o)
    }

    /// The checked fit parameters for `data` (periodic joints resolved on
    /// its rows, the robot checked against its joint count), stopped by
    /// `cancel`: what `robokrige fit` fits with the same flags.
    pub fn resolve(&self, data: &Dataset, cancel: &Cancel) -> Result<ValidErrorModelParams> {
        let method = self.method.as_deref().map(Method::from_name).transpose()?;
        params_with(method, &self.overrides()?, data)?
            .cancel(cancel.clone())
            .check()
    }
}
