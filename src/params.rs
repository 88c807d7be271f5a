//! One way to fit: parameters → checked parameters → `fit` (the shape of
//! linfa's `Params → ValidParams → Fit`).
//!
//! ```
//! use robokrige::params::{ErrorModelParams, TrendSpec};
//! use robokrige::{dataset::read_csv, space::Space};
//! let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
//! let data = read_csv(path.as_ref())?.select(&(0..60).collect::<Vec<_>>());
//! let model = ErrorModelParams::new()
//!     .space(Space::Js)
//!     .trend(TrendSpec::PccPca { threshold: 0.1, variance_share: 0.99, kinematic: None })
//!     .check()?
//!     .fit(&data)?;
//! assert_eq!(model.space(), Space::Js);
//! # Ok::<(), robokrige::Error>(())
//! ```
//!
//! Every combination of space, trend and hyperparameters is reachable,
//! including the GA selection in JS. The papers' methods are
//! `methods::Method::params`, which holds their constants in one
//! place.

use crate::calibration::{CalibrationOptions, calibrate};
use crate::cancel::Cancel;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::inputs::InputMap;
use crate::kinematics::Robot;
use crate::kriging::{Hyperparameters, KrigingOptions, OptimizerKind, TrainingInputs, Trend};
use crate::model::{ErrorModel, fit_outputs};
use crate::selection::{
    BasisSelector, Candidates, Ga, GaProgress, PccPca, Selection, SelectionProblem,
    shared_kinematic_trends_in,
};
use crate::space::Space;
use crate::{Error, Result};

/// How each output's trend is chosen.
#[derive(Debug, Clone, PartialEq)]
pub enum TrendSpec {
    /// The options' trend kind (constant, linear, quadratic) on every output.
    Options,
    /// A given trend per output, in x, y, z order.
    PerAxis(Box<[Trend; 3]>),
    /// Constant plus the rows of the robot's identification Jacobian (seed
    /// 003 eq 4): one fit calibrates and krigs.
    Kinematic(Box<Robot>),
    /// PCC + PCA fusion of the quadratic monomials (seed 003 eqs 15–20), and
    /// of the robot's Jacobian rows when `kinematic` is given.
    PccPca {
        /// |PCC| below which a candidate is dropped (seed 003: 0.1).
        threshold: f64,
        /// Share of the candidates' variance the kept components explain (0.99).
        variance_share: f64,
        /// Robot whose Jacobian rows join the candidates.
        kinematic: Option<Box<Robot>>,
    },
    /// The genetic algorithm of seed 004 over the quadratic monomials (and
    /// the Jacobian rows), fitness the closed-form `folds`-fold CV RMSE.
    Ga {
        /// CV folds of the fitness (seed 004: 10).
        folds: usize,
        /// Robot whose Jacobian rows join the candidates.
        kinematic: Option<Box<Robot>>,
    },
}

/// Where the correlation hyperparameters come from. (A refit at a fitted
/// model's own hyperparameters, with no search, is [`ErrorModel::refit`].)
#[derive(Debug, Clone, PartialEq)]
#[non_exhaustive]
pub enum HyperSpec {
    /// Searched on the data with the options' optimiser.
    Search,
    /// A local search per output from these, one per output in x, y, z
    /// order ([`crate::kriging::Tuning::Warm`]; e.g.
    /// [`ErrorModel::warm_starts`] of a model fitted on similar data: a CV
    /// fold, one more trend term).
    Warm(Vec<Hyperparameters>),
}

/// The parameters of an error-model fit, set by builder methods.
#[derive(Debug, Clone, PartialEq)]
pub struct ErrorModelParams {
    space: Space,
    periodic: Vec<usize>,
    kriging: KrigingOptions,
    trend: TrendSpec,
    hyper: HyperSpec,
    extras: Vec<Feature>,
    robot: Option<Robot>,
    calibration: Option<CalibrationOptions>,
}

/// Parameters that passed [`ErrorModelParams::check`]: only these fit.
#[derive(Debug, Clone, PartialEq)]
pub struct ValidErrorModelParams(ErrorModelParams);

impl Default for ErrorModelParams {
    fn default() -> Self {
        Self::new()
    }
}

impl ErrorModelParams {
    /// EJS, no periodic joint, [`KrigingOptions::recommended`] (nugget,
    /// family by CV, BFGS), the options' trend, hyperparameters searched, no
    /// extras.
    pub fn new() -> Self {
        ErrorModelParams {
            space: Space::Ejs,
            periodic: Vec::new(),
            kriging: KrigingOptions::recommended(),
            trend: TrendSpec::Options,
            hyper: HyperSpec::Search,
            extras: Vec::new(),
            robot: None,
            calibration: None,
        }
    }

    /// Calibrate the robot ([`ErrorModelParams::robot`]) first: identify
    /// its MD-H, tool and base errors on the campaign
    /// ([`crate::calibration::calibrate`]), then fit the Kriging outputs to
    /// what the calibration leaves. The model holds both and predicts their
    /// sum. `None`: Kriging of the raw error (the default).
    pub fn calibrate(mut self, calibration: Option<CalibrationOptions>) -> Self {
        self.calibration = calibration;
        self
    }

    /// The calibration options, when the fit calibrates first.
    pub fn get_calibration(&self) -> Option<&CalibrationOptions> {
        self.calibration.as_ref()
    }

    /// JS or EJS.
    pub fn space(mut self, space: Space) -> Self {
        self.space = space;
        self
    }

    /// Joints (0-based) entered as `(sin θ, cos θ)` instead of θ, so that θ
    /// and θ ± 360° are the same input ([`crate::space::Space::encode`];
    /// [`crate::space::periodic_joints`] chooses those that turn over half a
    /// turn). Empty (the default): none. Part of the model's input map
    /// ([`InputMap::periodic`]); a joint the data does not have is refused
    /// by the fit.
    pub fn periodic(mut self, joints: Vec<usize>) -> Self {
        self.periodic = joints;
        self
    }

    /// The Kriging options: trend kind, correlation, optimiser, nugget,
    /// seed (and their cancellation token: set [`cancel`](Self::cancel)
    /// after this).
    pub fn kriging(mut self, options: KrigingOptions) -> Self {
        self.kriging = options;
        self
    }

    /// The token that stops the fit ([`crate::cancel`]): the calibration,
    /// a trend selection and every output's search check it, and a
    /// cancelled fit returns [`Error::Interrupted`]. It is the Kriging
    /// options' token ([`KrigingOptions::cancel`]); [`Cancel::never`] by
    /// default.
    pub fn cancel(mut self, token: Cancel) -> Self {
        self.kriging.cancel = token;
        self
    }

    /// The cancellation token.
    pub fn get_cancel(&self) -> &Cancel {
        &self.kriging.cancel
    }

    /// How the trend is chosen.
    pub fn trend(mut self, trend: TrendSpec) -> Self {
        self.trend = trend;
        self
    }

    /// Where the hyperparameters come from.
    pub fn hyper(mut self, hyper: HyperSpec) -> Self {
        self.hyper = hyper;
        self
    }

    /// Extra inputs after `[θ, λ]` (effects `diagnose` adds).
    pub fn extras(mut self, extras: Vec<Feature>) -> Self {
        self.extras = extras;
        self
    }

    /// The robot the campaign was measured on, recorded in the model
    /// ([`ErrorModel::record_robot`]).
    pub fn robot(mut self, robot: Robot) -> Self {
        self.robot = Some(robot);
        self
    }

    /// The input space.
    pub fn get_space(&self) -> Space {
        self.space
    }

    /// The joints entered as `(sin θ, cos θ)`.
    pub fn get_periodic(&self) -> &[usize] {
        &self.periodic
    }

    /// The Kriging options.
    pub fn get_kriging(&self) -> &KrigingOptions {
        &self.kriging
    }

    /// How the trend is chosen.
    pub fn get_trend(&self) -> &TrendSpec {
        &self.trend
    }

    /// The robot recorded in the model, if any.
    pub fn get_robot(&self) -> Option<&Robot> {
        self.robot.as_ref()
    }

    /// The memory check of a fit of `rows` rows with these parameters'
    /// optimiser, as a command makes it before it starts
    /// ([`crate::model::check_fit_rows`]: `option` is the command's option
    /// that takes fewer rows, if it has one).
    pub fn check_fit_rows(
        &self,
        rows: usize,
        option: Option<&str>,
    ) -> Result<Option<crate::kriging::FitPlan>> {
        crate::model::check_fit_rows(rows, self.kriging.get_optimizer(), option)
    }

    /// The robot whose identification Jacobian enters the trend (the
    /// kinematic trend, or the kinematic candidates of a selection), if any.
    pub fn kinematic_robot(&self) -> Option<&Robot> {
        match &self.trend {
            TrendSpec::Kinematic(r) => Some(r),
            TrendSpec::PccPca { kinematic, .. } | TrendSpec::Ga { kinematic, .. } => {
                kinematic.as_deref()
            }
            TrendSpec::Options | TrendSpec::PerAxis(_) => None,
        }
    }

    /// The settings for reports, as `(name, value)` pairs in the command
    /// line's words: `space` (`ejs`), `trend` (the options' kind, `+
    /// kinematic` when [`kinematic_robot`](Self::kinematic_robot) is set),
    /// `corr` (`auto` or the family), `optimizer` (`bfgs`, `gps`, `hj`),
    /// `nugget` (`estimated` or `none (interpolating)`), and `periodic`
    /// (`q4,q6`) when there are periodic joints.
    pub fn settings(&self) -> Vec<(&'static str, String)> {
        let opts = &self.kriging;
        let mut v = vec![
            ("space", format!("{:?}", self.space).to_lowercase()),
            (
                "trend",
                format!("{:?}", opts.get_trend()).to_lowercase()
                    + if self.kinematic_robot().is_some() {
                        " + kinematic"
                    } else {
                        ""
                    },
            ),
            ("corr", opts.get_corr().to_string()),
            (
                "optimizer",
                match opts.get_optimizer() {
                    OptimizerKind::Bfgs => "bfgs",
                    OptimizerKind::Gps => "gps",
                    OptimizerKind::HookeJeeves => "hj",
                }
                .to_string(),
            ),
            (
                "nugget",
                if opts.get_nugget() {
                    "estimated"
                } else {
                    "none (interpolating)"
                }
                .to_string(),
            ),
        ];
        if self.calibration.is_some() {
            v.push((
                "calibration",
                "MD-H, tool and base by Levenberg–Marquardt on the directions the campaign sees"
                    .to_string(),
            ));
        }
        if !self.periodic.is_empty() {
            let p: Vec<String> = self
                .periodic
                .iter()
                .map(|j| format!("q{}", j + 1))
                .collect();
            v.push(("periodic", p.join(",")));
        }
        v
    }

    /// [`settings`](Self::settings) as one line: `space ejs, trend
    /// constant, …`.
    pub fn settings_line(&self) -> String {
        self.settings()
            .iter()
            .map(|(k, v)| format!("{k} {v}"))
            .collect::<Vec<_>>()
            .join(", ")
    }

    /// Check the combination and every value.
    pub fn check(self) -> Result<ValidErrorModelParams> {
        self.kriging.validate()?;
        let bad = |m: &str| Err(Error::InvalidParameter(m.into()));
        if !self.extras.is_empty() && self.trend != TrendSpec::Options {
            return bad("extra inputs take the options' trend (each adds a linear term to it)");
        }
        if let Some(c) = &self.calibration {
            c.validate()?;
            if self.robot.is_none() {
                return bad("a calibration needs the robot the campaign was measured on");
            }
            if matches!(self.trend, TrendSpec::Kinematic(_)) {
                return bad(
                    "the kinematic trend calibrates inside the Kriging fit: fit it without a calibration",
                );
            }
        }
        if let HyperSpec::Warm(starts) = &self.hyper
            && starts.len() != 3
        {
            return Err(Error::InvalidParameter(format!(
                "warm starts must be one per output (3), not {}",
                starts.len()
            )));
        }
        match &self.trend {
            TrendSpec::PccPca {
                threshold,
                variance_share,
                ..
            } if !(*threshold >= 0.0
                && *threshold < 1.0
                && *variance_share > 0.0
                && *variance_share <= 1.0) =>
            {
                return bad("PCC + PCA needs 0 ≤ threshold < 1 and 0 < variance share ≤ 1");
            }
            TrendSpec::Ga { folds, .. } if *folds < 2 => {
                return bad("the GA's CV fitness needs at least 2 folds");
            }
            _ => {}
        }
        Ok(ValidErrorModelParams(self))
    }
}

impl ValidErrorModelParams {
    /// The parameters.
    pub fn params(&self) -> &ErrorModelParams {
        &self.0
    }

    /// Fit on `data`.
    pub fn fit(&self, data: &Dataset) -> Result<ErrorModel> {
        self.fit_with_progress(data, &|_, _, _| {})
    }

    /// [`ValidErrorModelParams::fit`], reporting GA generations to `progress`.
    pub fn fit_with_progress(&self, data: &Dataset, progress: GaProgress) -> Result<ErrorModel> {
        let p = &self.0;
        let calibration = match (&p.calibration, &p.robot) {
            (Some(opts), Some(robot)) => Some(calibrate(data, robot, opts)?),
            _ => None,
        };
        p.kriging.cancel.check()?;
        let residual;
        let data = match &calibration {
            Some(c) => {
                residual = c.residual(data)?;
                &residual
            }
            None => data,
        };
        let (space, periodic, opts) = (p.space, &p.periodic, &p.kriging);
        let starts = match &p.hyper {
            HyperSpec::Search => None,
            HyperSpec::Warm(s) => Some(&s[..]),
        };
        let mut model = if p.extras.is_empty() {
            let (map, x) = InputMap::fit(data, space, periodic, &[])?;
            let (trends, selection) = self.trends(data, &map, &x, progress)?;
            let mut model = fit_outputs(data, &map, &x, opts, &trends, starts)?;
            model.selection = selection;
            model
        } else {
            ErrorModel::fit_with_extras(data, space, periodic, opts, &p.extras, starts)?
        };
        if let Some(r) = p.robot.as_ref().or(match &p.trend {
            TrendSpec::Kinematic(r) => Some(r),
            _ => None,
        }) {
            model.record_robot(r)?;
        }
        Ok(match calibration {
            Some(c) => model.with_calibration(c),
            None => model,
        })
    }

    /// Each output's trend (and the selection's report) on `data`, whose
    /// space map is `map` and normalised inputs `x`.
    fn trends(
        &self,
        data: &Dataset,
        map: &InputMap,
        x: &[Vec<f64>],
        progress: GaProgress,
    ) -> Result<([Trend; 3], Option<Selection>)> {
        let p = &self.0;
        let opts = &p.kriging;
        let select = |selector: &dyn BasisSelector, robot: &Option<Box<Robot>>| {
            let candidates = match robot {
                Some(r) => Candidates::Kinematic(r),
                None => Candidates::Quadratic,
            }
            .build(data, map, x)?;
            let errors = data.errors_or_err()?;
            let y: [Vec<f64>; 3] = std::array::from_fn(|a| errors.iter().map(|e| e[a]).collect());
            let problem = SelectionProblem {
                x,
                inputs: &TrainingInputs::new(x),
                names: map.names(),
                y: &y,
                candidates: &candidates,
                options: opts,
            };
            let (trends, report) = selector.select(&problem)?;
            Ok((trends, Some(report)))
        };
        match &p.trend {
            TrendSpec::Options => {
                let t = opts.trend.trend(map.dim());
                Ok(([t.clone(), t.clone(), t], None))
            }
            TrendSpec::PerAxis(t) => Ok(((**t).clone(), None)),
            TrendSpec::Kinematic(r) => Ok((
                shared_kinematic_trends_in(data, map, x, opts.trend, r)?,
                None,
            )),
            TrendSpec::PccPca {
                threshold,
                variance_share,
                kinematic,
            } => select(
                &PccPca {
                    threshold: *threshold,
                    variance_share: *variance_share,
                },
                kinematic,
            ),
            TrendSpec::Ga { folds, kinematic } => select(
                &Ga {
                    folds: *folds,
                    seed: opts.seed,
                    progress,
                },
                kinematic,
            ),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kriging::{Correlation, TrendKind};

    #[test]
    fn settings_name_every_choice_in_the_command_lines_words() {
        let p = ErrorModelParams::new();
        assert_eq!(
            p.settings_line(),
            "space ejs, trend constant, corr auto, optimizer bfgs, nugget estimated"
        );
        let opts = KrigingOptions::default()
            .trend(TrendKind::Linear)
            .corr(Correlation::Matern52)
            .optimizer(OptimizerKind::HookeJeeves)
            .nugget(false);
        let robot = crate::kinematics::load_robot("comau-nj220").unwrap();
        let p = ErrorModelParams::new()
            .space(Space::Js)
            .periodic(vec![3, 5])
            .kriging(opts)
            .trend(TrendSpec::Ga {
                folds: 10,
                kinematic: Some(Box::new(robot.clone())),
            });
        assert_eq!(p.kinematic_robot(), Some(&robot));
        let s = p.settings();
        assert_eq!(s[1], ("trend", "linear + kinematic".to_string()));
        assert_eq!(s[2].1, Correlation::Matern52.to_string());
        assert_eq!(s[3], ("optimizer", "hj".to_string()));
        assert_eq!(s[4], ("nugget", "none (interpolating)".to_string()));
        assert_eq!(s[5], ("periodic", "q4,q6".to_string()));
        assert_eq!(p.get_robot(), None);
    }
}
