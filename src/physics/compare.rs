//! Physics vs Kriging on one simulated robot: prediction error on
//! an independent path (seed 000 §4.1) and compensation error (§4.2).
//!
//! Everything is simulated in-process from one seed: the true robot, its
//! indexing tests (for the physics model), a Latin-hypercube training
//! campaign (for Kriging and the hybrid), a bidirectional Ø`path_mm` circle
//! path and independent random poses. Each model then
//! - **predicts** the error of the executed path and poses: the score is
//!   the measured error minus the prediction;
//! - **compensates** them (iterative feed-forward, seed 004 eqs 18–22; for
//!   the physics model this is seed 000 eq 17 iterated): the commands run on
//!   the true robot and the score is measured − target.
//!
//! Scores are 3D and, as in seed 000 (a 2D model), XY only.

use super::{HybridModel, identify_physics};
use crate::compensate::{CompensationOptions, compensate};
use crate::dataset::Dataset;
use crate::kinematics::{self, Robot};
use crate::methods::Method;
use crate::predictor::ErrorPredictor;
use crate::sim::{
    CampaignKind, CampaignSpec, ErrorProfile, Execution, TrueRobot, campaign, designs, execute,
    rng_for,
};
use crate::stats::spread;
use crate::trajectory::Trajectory;
use crate::vec3::{Vec3, norms, residuals};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};

/// Options of [`compare`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompareOptions {
    /// Preset robot name.
    pub robot: String,
    /// Seed of the true robot and of every campaign.
    pub seed: u64,
    /// Poses of the Kriging training campaign.
    pub train_poses: usize,
    /// Points of the circle path (run forward, then backward).
    pub path_points: usize,
    /// Diameter of the circle path, mm.
    pub path_mm: f64,
    /// Independent random poses.
    pub verify_poses: usize,
    /// Kriging method of the JS row.
    pub js: Method,
    /// Kriging method of the EJS row and of the hybrid's residual model.
    pub ejs: Method,
    /// Estimate a nugget in every Kriging fit (the papers interpolate: no nugget).
    pub nugget: bool,
}

impl CompareOptions {
    /// Refuse `nugget` when it changes nothing: both methods are
    /// `recommended`, which always estimates a nugget.
    pub fn validate(&self) -> Result<()> {
        if self.nugget && self.js == Method::Recommended && self.ejs == Method::Recommended {
            return Err(Error::InvalidParameter(
                "--nugget changes the papers' methods only; --js and --ejs are both `recommended`, which always estimates one".into(),
            ));
        }
        Ok(())
    }
}

impl Default for CompareOptions {
    fn default() -> Self {
        CompareOptions {
            robot: "scara-rh3frh5515".into(),
            seed: 1,
            train_poses: 300,
            path_points: 72,
            path_mm: 100.0,
            verify_poses: 50,
            js: Method::JsHj,
            ejs: Method::EjsGps,
            nugget: false,
        }
    }
}

/// Mean and max of the 3D and the XY error, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Score {
    /// Mean of the 3D error |e|, mm.
    pub mean_3d_mm: f64,
    /// Largest 3D error |e|, mm.
    pub max_3d_mm: f64,
    /// Mean of the XY error `√(e_x² + e_y²)`, mm.
    pub mean_xy_mm: f64,
    /// Largest XY error, mm.
    pub max_xy_mm: f64,
}

impl Score {
    /// Scores of a set of error vectors.
    pub fn of(errors: &[[f64; 3]]) -> Self {
        let d3 = norms(errors);
        let dxy: Vec<f64> = errors.iter().map(Vec3::norm_xy).collect();
        let (a, b) = (spread(&d3), spread(&dxy));
        Score {
            mean_3d_mm: a.mean,
            max_3d_mm: a.max,
            mean_xy_mm: b.mean,
            max_xy_mm: b.max,
        }
    }
}

/// One model's row.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CompareRow {
    /// The model's name, e.g. "nominal", "D-H + APD (physics)", "Kriging EJS".
    pub model: String,
    /// Measured − predicted error on the circle path.
    pub predict_path: Score,
    /// Measured − predicted error on the independent random poses.
    pub predict_poses: Score,
    /// Measured − target on the path after compensation.
    pub compensate_path: Score,
    /// Measured − target on the random poses after compensation.
    pub compensate_poses: Score,
    /// Compensation iterations on the path.
    pub iterations: usize,
    /// Predicted error at every path point, mm (for the plots).
    pub path_predicted: Vec<[f64; 3]>,
}

/// Result of [`compare`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Comparison {
    /// The options it ran with.
    pub options: CompareOptions,
    /// How the physics model was identified.
    pub physics: String,
    /// Rows: nominal, D-H only, D-H + APD, Kriging JS, Kriging EJS, hybrid.
    pub rows: Vec<CompareRow>,
    /// What measurement noise alone gives (simulator truth, for reading the
    /// table): mean |n| of the tracker + repeatability noise σ per axis,
    /// `E‖n‖ ≈ 1.596 σ` in 3D, `1.253 σ` in XY, over the path and the poses.
    ///
    /// This one is over the path (means only; the maxima are NaN).
    pub noise_path: Score,
    /// The same over the random poses (means only; the maxima are NaN).
    pub noise_poses: Score,
    /// The path's nominal TCP points, mm (for the plots).
    pub path_nominal: Vec<[f64; 3]>,
    /// Measured − nominal error at every executed path point (uncompensated), mm
    /// (for the plots).
    pub path_errors: Vec<[f64; 3]>,
    /// Campaign sizes: indexing rows, training rows, path points, poses.
    pub sizes: [usize; 4],
    /// Remarks on the set-up (identification notes, pose draw, Kriging methods).
    pub notes: Vec<String>,
}

/// The bidirectional circle path: forward around, then back. Centred on the
/// home TCP, or — if part of that circle is out of reach (a SCARA's home is
/// near full stretch) — moved toward the base axis in steps of the radius
/// until every point is reachable.
fn path(nominal: &Robot, opts: &CompareOptions) -> Result<Trajectory> {
    let home = nominal.fk(&nominal.home)?;
    let c = home.translation.vector;
    let toward = -nalgebra::Vector3::new(c.x, c.y, 0.0).normalize() * (0.5 * opts.path_mm);
    let mut fwd = Err(Error::InvalidParameter("no circle tried".into()));
    for k in 0..8 {
        let mut center = home;
        center.translation.vector += toward * k as f64;
        fwd = designs::circle_around(
            nominal,
            &center,
            &nominal.home,
            opts.path_mm,
            opts.path_points,
        );
        if fwd.is_ok() {
            break;
        }
    }
    let fwd = fwd?;
    let mut poses = fwd.poses.clone();
    poses.extend(fwd.poses.iter().rev().skip(1).cloned());
    Ok(Trajectory::new(poses))
}

/// Run the whole comparison ([`CompareOptions::validate`] first);
/// `progress(step, total, what)` after each step.
pub fn compare(opts: &CompareOptions, progress: &dyn Fn(usize, usize, &str)) -> Result<Comparison> {
    opts.validate()?;
    let nominal = kinematics::load_robot(&opts.robot)?;
    let robot = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), opts.seed);
    // 6 set-up steps, then one per model row (6)
    let total = 12;
    let step = |k: usize, what: &str| progress(k, total, what);

    step(0, "indexing tests and training campaign");
    let c = Campaigns::simulate(&robot, &nominal, opts)?;

    step(1, "physics identification");
    let id = identify_physics(&c.indexing, &c.train, &nominal)?;
    let (phys, dh, how, mut notes) = (id.full, id.dh, id.method, id.notes);

    step(2, "Kriging JS");
    let quiet = &|_: usize, _: usize, _: f64| {};
    let fit = |m: Method, d: &Dataset| {
        m.params(opts.seed, opts.nugget)
            .check()?
            .fit_with_progress(d, quiet)
    };
    let js = fit(opts.js, &c.train)?;
    step(3, "Kriging EJS");
    let ejs = fit(opts.ejs, &c.train)?;
    step(4, "hybrid");
    let mut resid = c.train.clone();
    let pred = phys.predict(&c.train.q, &c.train.dir)?;
    resid.errors = Some(residuals(c.train.errors_or_err()?, &pred));
    let hybrid = HybridModel {
        physics: phys.clone(),
        residual: fit(opts.ejs, &resid)?,
    };

    step(5, "executing the path and the poses");
    let scene = Scene::run(&robot, &nominal, &c.poses, opts)?;
    let models: Vec<(&str, Option<&dyn ErrorPredictor>)> = vec![
        ("nominal", None),
        ("D-H only", Some(&dh)),
        ("D-H + APD (physics)", Some(&phys)),
        ("Kriging JS", Some(&js)),
        ("Kriging EJS", Some(&ejs)),
        ("hybrid: physics + Kriging EJS", Some(&hybrid)),
    ];
    let mut rows = Vec::new();
    for (k, (name, model)) in models.iter().enumerate() {
        step(6 + k, &format!("predicting and compensating: {name}"));
        rows.push(scene.row(name, *model)?);
    }
    if c.scara {
        notes.push("random poses: the first of a uniform draw with the elbow bent by at least 15° (|q2| ≥ 15°; a stretched SCARA is singular)".into());
    }
    notes.push(kriging_note(opts, c.train.len()));
    step(total, "done");
    Ok(Comparison {
        options: opts.clone(),
        physics: how,
        noise_path: noise_score(&robot, &scene.run.joints),
        path_nominal: scene
            .run
            .joints
            .iter()
            .map(|q| nominal.fk_unchecked(q).translation.vector.into())
            .collect(),
        path_errors: scene.path_err.clone(),
        noise_poses: noise_score(&robot, &c.poses.q),
        rows,
        sizes: [
            c.indexing.len(),
            c.train.len(),
            scene.traj.len(),
            c.poses.len(),
        ],
        notes,
    })
}

/// The simulated campaigns of a comparison.
struct Campaigns {
    /// The indexing tests (for the physics model).
    indexing: Dataset,
    /// The Latin-hypercube training campaign (Kriging, the hybrid).
    train: Dataset,
    /// The independent random poses.
    poses: Dataset,
    /// Whether the robot is a SCARA (its poses keep the elbow bent).
    scara: bool,
}

impl Campaigns {
    fn simulate(robot: &TrueRobot, nominal: &Robot, opts: &CompareOptions) -> Result<Self> {
        let indexing =
            campaign::measurements(robot, &CampaignSpec::new(CampaignKind::Indexing, opts.seed))?;
        let mut lhs = CampaignSpec::new(CampaignKind::Lhs, opts.seed);
        lhs.poses = opts.train_poses;
        let train = campaign::measurements(robot, &lhs)?;
        let mut ver = CampaignSpec::new(CampaignKind::Verify, opts.seed + 1000);
        // a SCARA with a stretched elbow is singular: a compensated target there
        // can lie out of reach, so its random poses keep |q2| ≥ 15°
        let scara = super::is_scara(nominal);
        ver.poses = if scara {
            2 * opts.verify_poses
        } else {
            opts.verify_poses
        };
        let all = campaign::measurements(robot, &ver)?;
        let keep: Vec<usize> = (0..all.len())
            .filter(|&k| !scara || all.q[k][1].abs() >= 15.0)
            .take(opts.verify_poses)
            .collect();
        Ok(Campaigns {
            indexing,
            train,
            poses: all.select(&keep),
            scara,
        })
    }
}

/// The path and the poses every model is scored on: the path executed
/// uncompensated, and the measured − nominal errors of both.
struct Scene<'a> {
    robot: &'a TrueRobot,
    nominal: &'a Robot,
    poses: &'a Dataset,
    seed: u64,
    traj: Trajectory,
    start: Vec<f64>,
    run: Execution,
    path_err: Vec<[f64; 3]>,
    pose_err: Vec<[f64; 3]>,
    pose_targets: Trajectory,
}

impl<'a> Scene<'a> {
    fn run(
        robot: &'a TrueRobot,
        nominal: &'a Robot,
        poses: &'a Dataset,
        opts: &CompareOptions,
    ) -> Result<Self> {
        let traj = path(nominal, opts)?;
        let start = nominal.home.clone();
        let run = execute(
            robot,
            &traj,
            &start,
            None,
            &[],
            &mut exec_rng(opts.seed, "path"),
        )?;
        let path_err: Vec<[f64; 3]> = run
            .joints
            .iter()
            .zip(&run.measured)
            .map(|(qk, m)| {
                let p = nominal.fk_unchecked(qk).translation.vector;
                [m[0] - p.x, m[1] - p.y, m[2] - p.z]
            })
            .collect();
        let pose_err = poses.errors_or_err()?.to_vec();
        let pose_targets =
            Trajectory::new(poses.q.iter().map(|q| nominal.fk_unchecked(q)).collect());
        Ok(Scene {
            robot,
            nominal,
            poses,
            seed: opts.seed,
            traj,
            start,
            run,
            path_err,
            pose_err,
            pose_targets,
        })
    }

    /// One model's row: it predicts the path's and the poses' errors, and
    /// compensates both (the commands run on the true robot). `None`: the
    /// nominal row (predicts zero, compensates nothing).
    fn row(&self, name: &str, model: Option<&dyn ErrorPredictor>) -> Result<CompareRow> {
        let (run, poses) = (&self.run, self.poses);
        let (pp, pq) = match model {
            Some(m) => (
                m.predict_errors(&run.joints, &run.dir)?,
                m.predict_errors(&poses.q, &poses.dir)?,
            ),
            None => (
                vec![[0.0; 3]; self.path_err.len()],
                vec![[0.0; 3]; self.pose_err.len()],
            ),
        };
        let (comp_path, iterations) = match model {
            Some(m) => {
                let c = compensate(self.nominal, m, &self.traj, &CompensationOptions::default())?;
                (c.commands.clone(), c.history.len())
            }
            None => (self.traj.clone(), 0),
        };
        let comp_poses = match model {
            Some(m) => {
                let o = CompensationOptions {
                    hints: Some(poses.q.clone()),
                    ..CompensationOptions::default()
                };
                compensate(self.nominal, m, &self.pose_targets, &o)?.commands
            }
            None => self.pose_targets.clone(),
        };
        let after_path = execute(
            self.robot,
            &comp_path,
            &self.start,
            None,
            &[],
            &mut exec_rng(self.seed, "cpath"),
        )?;
        let after_poses = execute(
            self.robot,
            &comp_poses,
            &self.start,
            Some(&poses.q),
            &[],
            &mut exec_rng(self.seed, "cposes"),
        )?;
        Ok(CompareRow {
            model: name.to_string(),
            predict_path: Score::of(&residuals(&self.path_err, &pp)),
            predict_poses: Score::of(&residuals(&self.pose_err, &pq)),
            compensate_path: Score::of(&vs_target(&after_path.measured, &self.traj)),
            compensate_poses: Score::of(&vs_target(&after_poses.measured, &self.pose_targets)),
            iterations,
            path_predicted: pp.clone(),
        })
    }
}

/// The seeded noise stream of one execution (`tag`: path, cpath, cposes).
fn exec_rng(seed: u64, tag: &str) -> rand::rngs::StdRng {
    rng_for(seed, &format!("compare-{tag}"))
}

/// Measured − target at every point of `tr`.
fn vs_target(meas: &[[f64; 3]], tr: &Trajectory) -> Vec<[f64; 3]> {
    meas.iter()
        .zip(&tr.poses)
        .map(|(m, t)| {
            let p = t.translation.vector;
            [m[0] - p.x, m[1] - p.y, m[2] - p.z]
        })
        .collect()
}

/// The note that names the Kriging methods and whether they estimate a
/// nugget (`recommended` always does; the papers' methods only when asked).
fn kriging_note(opts: &CompareOptions, train_rows: usize) -> String {
    let nugget = |m: Method| {
        if opts.nugget || m == Method::Recommended {
            "with a nugget"
        } else {
            "interpolating, as in the papers"
        }
    };
    format!(
        "Kriging: JS {} ({}) and EJS {} ({}) fitted on the {}-pose Latin-hypercube campaign; the hybrid's residual model is {} on the same poses",
        opts.js.name(),
        nugget(opts.js),
        opts.ejs.name(),
        nugget(opts.ejs),
        train_rows,
        opts.ejs.name(),
    )
}

/// What measurement noise alone gives at the joints `q`: the mean of
/// `E‖n‖` for `n ~ N(0, σ² I)` with the simulator's σ per axis —
/// `2σ√(2/π)` in 3D (σ the RMS of the three), `σ√(π/2)` in XY (of the two);
/// maxima NaN.
fn noise_score(robot: &TrueRobot, q: &[Vec<f64>]) -> Score {
    let s: Vec<[f64; 3]> = q.iter().map(|qk| robot.noise_sigma(qk)).collect();
    let m3: Vec<f64> = s
        .iter()
        .map(|v| {
            2.0 * (2.0 / std::f64::consts::PI).sqrt()
                * ((v[0].powi(2) + v[1].powi(2) + v[2].powi(2)) / 3.0).sqrt()
        })
        .collect();
    let m2: Vec<f64> = s
        .iter()
        .map(|v| (std::f64::consts::PI / 2.0).sqrt() * ((v[0].powi(2) + v[1].powi(2)) / 2.0).sqrt())
        .collect();
    Score {
        mean_3d_mm: spread(&m3).mean,
        max_3d_mm: f64::NAN,
        mean_xy_mm: spread(&m2).mean,
        max_xy_mm: f64::NAN,
    }
}
