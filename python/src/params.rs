//! The Python estimator's parameters → the library's checked fit parameters
//! (`ErrorModelParams` → `check`), with the command line's defaults and
//! rules (`robokrige fit`'s `ModelArgs`), so that the same data and the
//! same settings give the same model file.

use pyo3::prelude::*;
use robokrige::dataset::Dataset;
use robokrige::calibration::CalibrationOptions;
use robokrige::kinematics::Robot;
use robokrige::kriging::{CorrChoice, KrigingOptions, OptimizerKind, TrendKind};
use robokrige::methods::Method;
use robokrige::params::{ErrorModelParams, TrendSpec, ValidErrorModelParams};
use robokrige::space::Space;
use robokrige::{Error, Result};

/// `ErrorModel.get_params()` of the Python layer, read item by item.
#[derive(Debug, Clone, FromPyObject)]
pub struct FitParams {
    #[pyo3(item)]
    pub space: String,
    #[pyo3(item)]
    pub trend: String,
    #[pyo3(item)]
    pub nugget: bool,
    #[pyo3(item)]
    pub corr: String,
    #[pyo3(item)]
    pub optimizer: String,
    #[pyo3(item)]
    pub starts: Option<usize>,
    #[pyo3(item)]
    pub seed: u64,
    #[pyo3(item)]
    pub periodic: String,
    #[pyo3(item)]
    pub robot: Option<String>,
    #[pyo3(item)]
    pub tool: Option<(f64, f64, f64)>,
    #[pyo3(item)]
    pub kinematic: bool,
    #[pyo3(item)]
    pub calibrate: bool,
    #[pyo3(item)]
    pub method: Option<String>,
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

/// The options' correlation choice, as `--corr`.
fn parse_corr(s: &str) -> Result<CorrChoice> {
    CorrChoice::from_name(s).ok_or_else(|| {
        bad(format!(
            "corr '{s}': expected 'auto', 'gaussian', 'matern52', 'matern32' or 'exponential'"
        ))
    })
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

/// A preset name or robot file, with its tool translation replaced (mm).
pub fn robot_with_tool(spec: &str, tool: Option<(f64, f64, f64)>) -> Result<Robot> {
    let mut robot = robokrige::kinematics::load_robot(spec)?;
    if let Some((x, y, z)) = tool {
        if ![x, y, z].iter().all(|v| v.is_finite()) {
            return Err(bad(format!(
                "tool ({x}, {y}, {z}): expected finite x, y, z in mm"
            )));
        }
        robot.tool = nalgebra::Isometry3::from_parts(
            nalgebra::Translation3::new(x, y, z),
            robot.tool.rotation,
        );
    }
    Ok(robot)
}

impl FitParams {
    /// Space, periodic joints (resolved on `data`) and options as
    /// `robokrige fit` makes them from its flags.
    fn options(&self, data: &Dataset) -> Result<(Space, Vec<usize>, KrigingOptions)> {
        let optimizer = parse_optimizer(&self.optimizer)?;
        if self.starts.is_some() && optimizer == OptimizerKind::HookeJeeves {
            return Err(bad(
                "starts is for optimizer 'bfgs' or 'gps' (Hooke–Jeeves runs once, from the centre of the box)".into(),
            ));
        }
        let opts = crate::access::fit_options(
            parse_trend(&self.trend)?,
            parse_corr(&self.corr)?,
            optimizer,
            self.nugget,
            self.starts.unwrap_or(optimizer.default_starts()),
            self.seed,
        );
        let periodic = parse_periodic(&self.periodic, &data.q)?;
        Ok((parse_space(&self.space)?, periodic, opts))
    }

    /// The checked fit parameters for `data` (periodic joints resolved on
    /// its rows, the robot checked against its joint count): what
    /// `robokrige fit` fits with the same flags.
    pub fn resolve(&self, data: &Dataset) -> Result<ValidErrorModelParams> {
        if self.kinematic && self.robot.is_none() {
            return Err(bad(
                "kinematic=True needs robot (the robot whose Jacobian forms the trend)".into(),
            ));
        }
        let robot = self
            .robot
            .as_deref()
            .map(|r| robot_with_tool(r, self.tool))
            .transpose()?;
        if self.tool.is_some() && robot.is_none() {
            return Err(bad("tool needs robot (the robot the tool is on)".into()));
        }
        if let Some(r) = &robot {
            r.check_dataset(data)?;
        }
        let kinematic = robot.as_ref().filter(|_| self.kinematic);
        let params = match &self.method {
            Some(name) => {
                let method = Method::parse(name)?;
                match (kinematic, method) {
                    (Some(r), Method::EjsGa | Method::EjsPca) => {
                        // as `fit --method … --kinematic`: the flags' options
                        let (_, periodic, opts) = self.options(data)?;
                        ErrorModelParams::new()
                            .periodic(periodic)
                            .kriging(opts)
                            .trend(method.trend(Some(r)))
                    }
                    (Some(_), _) => {
                        return Err(bad(
                            "kinematic=True with a method works for 'ejs-pca' and 'ejs-ga' (selection among polynomial and kinematic candidates); use kinematic=True without a method otherwise".into(),
                        ));
                    }
                    (None, m) => m.params(self.seed, false),
                }
            }
            None => {
                let (space, periodic, opts) = self.options(data)?;
                let p = ErrorModelParams::new()
                    .space(space)
                    .periodic(periodic)
                    .kriging(opts);
                match kinematic {
                    Some(r) => p.trend(TrendSpec::Kinematic(Box::new(r.clone()))),
                    None => p,
                }
            }
        };
        match robot {
            // as `robokrige fit --robot`: calibrated unless the kinematic
            // trend does it or the caller said no
            Some(r) => {
                let calibrate = self.calibrate && !self.kinematic;
                params
                    .robot(r)
                    .calibrate(calibrate.then(CalibrationOptions::default))
            }
            None => params,
        }
        .check()
    }
}
