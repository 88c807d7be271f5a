//! The demo's job (`robokrige demo`) on the simulated COMAU SMART5 NJ 220 of
//! seed 1: simulate the campaigns of `datasets/generate.sh`, fit JS and EJS,
//! compare the papers' methods by K-fold CV, compensate the Ø100 mm circle
//! and the verification poses on the simulated robot, and diagnose a
//! campaign with an undeclared tracker bump. [`run_demo`] computes it all
//! and returns a [`Demo`]; the CLI writes its files, plots and report.

use crate::cv::{CvResult, cross_validate_closed_form, cross_validate_method};
use crate::dataset::{Dataset, write_csv};
use crate::diagnose::{DiagnoseOptions, Diagnosis, diagnose};
use crate::kinematics::{self, Robot};
use crate::methods::Method;
use crate::model::{AXES, ErrorModel};
use crate::sim::{CampaignKind, CampaignSpec, Effect, SimOutput, Truth, simulate};
use crate::stats::PositionErrorTable;
use crate::study::{Targets, compensate_and_evaluate_each};
use crate::trajectory::Trajectory;
use crate::{Error, Result};
use std::path::Path;

/// The demo's robot (a preset).
pub const ROBOT: &str = "comau-nj220";
/// Seed of the true robot, of the campaigns, the fits, the CV folds and the
/// measurement noise.
const SEED: u64 = 1;
/// Verification poses.
const VERIFY_POSES: usize = 30;
/// Points of the Ø100 mm circle.
const CIRCLE_POINTS: usize = 72;
/// Steps [`run_demo`] reports to its progress callback.
pub const STEPS: usize = 7;

/// Sizes of the demo. `Default` is the shipped demo: 300 poses, 10-fold CV.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct DemoOptions {
    /// Poses of the Latin-hypercube campaign (and of its copy with the
    /// tracker bump).
    pub poses: usize,
    /// Folds K of the cross-validation of the methods.
    pub folds: usize,
}

impl Default for DemoOptions {
    fn default() -> Self {
        DemoOptions {
            poses: 300,
            folds: 10,
        }
    }
}

impl DemoOptions {
    /// Error unless there are at least 20 poses (the diagnosis' 10-fold CV)
    /// and `2 ≤ folds ≤ poses`.
    pub fn validate(&self) -> Result<()> {
        if self.poses < 20 || self.folds < 2 || self.folds > self.poses {
            return Err(Error::InvalidParameter(format!(
                "the demo needs ≥ 20 poses and 2 ≤ folds ≤ poses, got {} poses and {} folds",
                self.poses, self.folds
            )));
        }
        Ok(())
    }

    /// The row (0-based) before which the tracker is bumped: half-way.
    pub fn step_row(&self) -> usize {
        self.poses / 2
    }

    /// The undeclared effect of the diagnosed campaign: the tracker knocked
    /// by (0.15, −0.1, 0.1) mm before [`step_row`](Self::step_row).
    pub fn step_effect(&self) -> String {
        format!(
            "tracker-step:row={},dx=0.15,dy=-0.1,dz=0.1",
            self.step_row()
        )
    }
}

/// One method's cross-validation.
#[derive(Debug, Clone)]
pub struct MethodCv {
    /// The method.
    pub method: Method,
    /// Its K-fold CV: refit in every fold (`recommended`, `js-hj`,
    /// `ejs-hj`) or closed form at the full-data fit (the others).
    pub cv: CvResult,
}

/// One model's compensation of one target set, measured on the simulated
/// robot.
#[derive(Debug, Clone, PartialEq)]
pub struct CompensationRow {
    /// `"circle"` or `"verification poses"`.
    pub target: &'static str,
    /// `"JS"` or `"EJS"`.
    pub model: &'static str,
    /// Errors of the nominal commands.
    pub nominal: PositionErrorTable,
    /// Errors of the compensated commands.
    pub after: PositionErrorTable,
    /// Iterations of the feed-forward compensation.
    pub iterations: usize,
}

impl CompensationRow {
    /// Reduction of the mean and of the max 3D error, %.
    pub fn reduction_pct(&self) -> (f64, f64) {
        (
            100.0 * (1.0 - self.after.mean_abs_mm / self.nominal.mean_abs_mm),
            100.0 * (1.0 - self.after.max_abs_mm / self.nominal.max_abs_mm),
        )
    }
}

/// Everything the demo computed.
#[derive(Debug, Clone)]
pub struct Demo {
    /// Its sizes.
    pub options: DemoOptions,
    /// The nominal robot ([`ROBOT`]).
    pub robot: Robot,
    /// The Latin-hypercube campaign (`comau_lhs.csv`).
    pub lhs: Dataset,
    /// The verification poses (`comau_verify.csv`).
    pub verify: Dataset,
    /// The Ø100 mm circle (`comau_circle.csv`).
    pub circle: Trajectory,
    /// The campaign with the tracker bump (`comau_tracker_step.csv`).
    pub tracker_step: Dataset,
    /// `js-hj` fitted on [`lhs`](Self::lhs).
    pub js: ErrorModel,
    /// `ejs-gps` fitted on [`lhs`](Self::lhs).
    pub ejs: ErrorModel,
    /// `ejs-ga` fitted on [`lhs`](Self::lhs).
    pub ejs_ga: ErrorModel,
    /// The methods' cross-validations: `recommended`, `js-hj`, `ejs-hj`
    /// (refit), `ejs-gps`, `ejs-pca`, `ejs-ga` (closed form).
    pub methods: Vec<MethodCv>,
    /// JS and EJS on the circle, then on the verification poses.
    pub compensation: Vec<CompensationRow>,
    /// Measured errors along the circle: `nominal`, `JS compensated`, `EJS
    /// compensated`.
    pub circle_runs: Vec<(String, Vec<[f64; 3]>)>,
    /// The diagnosis of [`tracker_step`](Self::tracker_step).
    pub diagnosis: Diagnosis,
}

impl Demo {
    /// The folders of a demo written to `out`: `data`, `models`, `plots`
    /// (created).
    pub fn create_folders(out: &Path) -> Result<()> {
        for sub in ["data", "models", "plots"] {
            let d = out.join(sub);
            std::fs::create_dir_all(&d).map_err(|e| Error::io(&d, e))?;
        }
        Ok(())
    }

    /// Write the campaigns to `out/data` (as `datasets/generate.sh` names
    /// them) and the models to `out/models` (`js.json`, `ejs.json`,
    /// `ejs_ga.json`).
    pub fn write_files(&self, out: &Path) -> Result<()> {
        write_csv(&out.join("data/comau_lhs.csv"), &self.lhs)?;
        write_csv(&out.join("data/comau_verify.csv"), &self.verify)?;
        self.circle.write_csv(&out.join("data/comau_circle.csv"))?;
        write_csv(&out.join("data/comau_tracker_step.csv"), &self.tracker_step)?;
        self.js.save(&out.join("models/js.json"))?;
        self.ejs.save(&out.join("models/ejs.json"))?;
        self.ejs_ga.save(&out.join("models/ejs_ga.json"))
    }
}

/// One campaign of the demo's robot with `effect`, if any.
fn campaign(
    robot: &Robot,
    kind: CampaignKind,
    poses: usize,
    effect: Option<&str>,
) -> Result<(SimOutput, Truth)> {
    let mut spec = CampaignSpec::new(kind, SEED);
    spec.poses = poses;
    if let Some(e) = effect {
        spec.effects = vec![Effect::parse(e)?];
    }
    simulate(robot, &spec)
}

fn measurements(o: SimOutput) -> Dataset {
    match o {
        SimOutput::Measurements(d) => d,
        SimOutput::Trajectory(_) => unreachable!("a pose campaign"),
    }
}

/// Run the demo. `progress(done, what)` is told the steps done (of
/// [`STEPS`]) and what runs now.
pub fn run_demo(options: &DemoOptions, progress: &(dyn Fn(usize, &str) + Sync)) -> Result<Demo> {
    options.validate()?;
    let robot = kinematics::load_robot(ROBOT)?;
    progress(0, "simulating the COMAU campaigns");
    let c = Campaigns::simulate(&robot, options)?;

    // 1. models
    progress(
        1,
        &format!(
            "fitting JS (js-hj) and EJS (ejs-gps) models on {} poses",
            options.poses
        ),
    );
    let fit = |m: Method, data: &Dataset| m.params(SEED, false).check()?.fit(data);
    let js = fit(Method::JsHj, &c.lhs)?;
    let ejs = fit(Method::EjsGps, &c.lhs)?;

    // 2. method comparison
    let (methods, ejs_ga) = compare_methods(&c.lhs, &ejs, options.folds, progress)?;

    // 3. compensation
    let (compensation, circle_runs) = compensate_with_both(&robot, &c, [&js, &ejs], progress)?;

    // 4. diagnose
    progress(
        6,
        "diagnosing comau_tracker_step.csv (an undeclared tracker bump)",
    );
    let diagnosis = diagnose(&c.tracker_step, &DiagnoseOptions::default(), &|m| {
        progress(6, &format!("diagnose: {m}"))
    })?;
    progress(STEPS, "done");
    Ok(Demo {
        options: *options,
        robot,
        lhs: c.lhs,
        verify: c.verify,
        circle: c.circle,
        tracker_step: c.tracker_step,
        js,
        ejs,
        ejs_ga,
        methods,
        compensation,
        circle_runs,
        diagnosis,
    })
}

/// The demo's simulated campaigns (those of `datasets/generate.sh`).
struct Campaigns {
    lhs: Dataset,
    verify: Dataset,
    verify_truth: Truth,
    circle: Trajectory,
    circle_truth: Truth,
    tracker_step: Dataset,
}

impl Campaigns {
    fn simulate(robot: &Robot, options: &DemoOptions) -> Result<Self> {
        let (lhs, _) = campaign(robot, CampaignKind::Lhs, options.poses, None)?;
        let (verify, verify_truth) = campaign(robot, CampaignKind::Verify, VERIFY_POSES, None)?;
        let (circle, circle_truth) = campaign(robot, CampaignKind::Circle, CIRCLE_POINTS, None)?;
        let SimOutput::Trajectory(circle) = circle else {
            unreachable!("a trajectory campaign")
        };
        let step = options.step_effect();
        let (bumped, _) = campaign(robot, CampaignKind::Lhs, options.poses, Some(&step))?;
        Ok(Campaigns {
            lhs: measurements(lhs),
            verify: measurements(verify),
            verify_truth,
            circle,
            circle_truth,
            tracker_step: measurements(bumped),
        })
    }
}

/// K-fold CV of the methods on `lhs`: `recommended`, `js-hj`, `ejs-hj`
/// refitted in every fold; `ejs-gps` (the fitted `ejs`), `ejs-pca`,
/// `ejs-ga` in closed form at the full-data fit. Returns the `ejs-ga`
/// model too.
fn compare_methods(
    lhs: &Dataset,
    ejs: &ErrorModel,
    k: usize,
    progress: &(dyn Fn(usize, &str) + Sync),
) -> Result<(Vec<MethodCv>, ErrorModel)> {
    let mut methods = Vec::new();
    for m in [Method::Recommended, Method::JsHj, Method::EjsHj] {
        progress(
            2,
            &format!("{k}-fold CV of {} (refit in every fold)", m.name()),
        );
        let cv = cross_validate_method(lhs, m, k, SEED, &|| {}, &|_, _, _| {})?;
        methods.push(MethodCv { method: m, cv });
    }
    let mut ejs_ga = None;
    for m in [Method::EjsGps, Method::EjsPca, Method::EjsGa] {
        progress(
            3,
            &format!(
                "{k}-fold CV of {} (closed form at the full-data fit)",
                m.name()
            ),
        );
        let model = if m == Method::EjsGps {
            ejs.clone()
        } else {
            m.params(SEED, false)
                .check()?
                .fit_with_progress(lhs, &|axis, g, best| {
                    progress(
                        3,
                        &format!(
                            "GA selection for {}: generation {g}, best CV RMSE {best:.4} mm",
                            AXES[axis]
                        ),
                    )
                })?
        };
        let cv = cross_validate_closed_form(lhs, &model, k, SEED)?;
        methods.push(MethodCv { method: m, cv });
        if m == Method::EjsGa {
            ejs_ga = Some(model);
        }
    }
    Ok((methods, ejs_ga.expect("ejs-ga is among the methods")))
}

/// The measured errors along a path: (label, error per point).
type Runs = Vec<(String, Vec<[f64; 3]>)>;

/// JS and EJS compensate the circle, then the verification poses, each run
/// on the simulated robot: the table rows, and the circle's measured errors
/// (nominal, JS compensated, EJS compensated).
fn compensate_with_both(
    robot: &Robot,
    c: &Campaigns,
    [js, ejs]: [&ErrorModel; 2],
    progress: &(dyn Fn(usize, &str) + Sync),
) -> Result<(Vec<CompensationRow>, Runs)> {
    let mut compensation = Vec::new();
    let verify_targets = Targets::from_joints(robot, &c.verify.q)?;
    let circle_targets = Targets::from_trajectory(c.circle.clone());
    let mut circle_runs: Runs = Vec::new();
    let sets = [
        (
            "circle",
            "Ø100 mm circle (72 points)",
            &circle_targets,
            &c.circle_truth,
            "comau_circle.truth.json",
        ),
        (
            "verification poses",
            "30 verification poses",
            &verify_targets,
            &c.verify_truth,
            "comau_verify.truth.json",
        ),
    ];
    for (done, (target, name, targets, truth, truth_file)) in (4..).zip(sets) {
        progress(
            done,
            &format!("compensating the {name} with JS and EJS, run on the simulated robot"),
        );
        let runs = compensate_and_evaluate_each(
            robot,
            &[js, ejs],
            Path::new(truth_file),
            truth,
            targets,
            &robot.home,
            SEED,
        )?;
        for (label, run) in ["JS", "EJS"].into_iter().zip(runs) {
            let (ev, (before, after)) = (run.evaluation, run.runs);
            if target == "circle" {
                if circle_runs.is_empty() {
                    circle_runs.push(("nominal".into(), before));
                }
                circle_runs.push((format!("{label} compensated"), after));
            }
            compensation.push(CompensationRow {
                target,
                model: label,
                nominal: ev.before,
                after: ev.after,
                iterations: run.compensation.history.len(),
            });
        }
    }
    Ok((compensation, circle_runs))
}
