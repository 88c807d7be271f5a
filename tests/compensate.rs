//! Feed-forward compensation (seed 003 eq 22, seed 004 eqs 18–22), checked by
//! running the commands on the simulator's true robot.

mod common;

use nalgebra::{Translation3, Vector3};
use robokrige::compensate::{CompensationOptions, Stop, compensate, predict_along};
use robokrige::dataset::read_csv;
use robokrige::kinematics::{self, Robot};
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::ErrorModel;
use robokrige::sim::{Truth, execute, rng_for};
use robokrige::space::Space;
use robokrige::stats::position_error_table;
use robokrige::trajectory::Trajectory;
use robokrige::{Error, Result};
use std::path::{Path, PathBuf};
use std::sync::OnceLock;

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("datasets")
        .join(name)
}

fn robot() -> Robot {
    kinematics::preset("comau-nj220").unwrap()
}

/// EJS and JS models of the shipped COMAU campaign, fitted once (a quick
/// Hooke–Jeeves fit; the CLI's default GPS fit is better still).
fn models() -> &'static (ErrorModel, ErrorModel) {
    static M: OnceLock<(ErrorModel, ErrorModel)> = OnceLock::new();
    M.get_or_init(|| {
        let data = read_csv(&shipped("comau_lhs.csv")).unwrap();
        let opts = KrigingOptions::default()
            .optimizer(OptimizerKind::HookeJeeves)
            .max_evals(400)
            .starts(2);
        (
            ErrorModel::fit(&data, Space::Ejs, &opts).unwrap(),
            ErrorModel::fit(&data, Space::Js, &opts).unwrap(),
        )
    })
}

fn circle() -> Trajectory {
    Trajectory::read_csv(&shipped("comau_circle.csv")).unwrap()
}

fn truth() -> Truth {
    let text = std::fs::read_to_string(shipped("comau_circle.truth.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

/// Measured 3D errors (mean, max) of running `commands` aimed at `targets`.
fn run(truth: &Truth, commands: &Trajectory, targets: &Trajectory, seed: u64) -> (f64, f64) {
    let mut rng = rng_for(seed, "test");
    let ex = execute(
        &truth.robot,
        commands,
        &truth.robot.nominal.home,
        None,
        &truth.spec.effects,
        &mut rng,
    )
    .unwrap();
    let e: Vec<[f64; 3]> = ex
        .measured
        .iter()
        .zip(&targets.poses)
        .map(|(m, p)| {
            let d = Vector3::from(*m) - p.translation.vector;
            [d.x, d.y, d.z]
        })
        .collect();
    let t = position_error_table(&e);
    (t.mean_abs_mm, t.max_abs_mm)
}

fn comp(model: &ErrorModel, traj: &Trajectory, iterative: bool) -> Result<Trajectory> {
    let opts = CompensationOptions {
        iterative,
        ..CompensationOptions::default()
    };
    compensate(&robot(), model, traj, &opts).map(|c| c.commands)
}

#[test]
fn ejs_iterative_compensation_of_the_circle_meets_the_targets_and_beats_js() {
    let (ejs, js) = models();
    let (targets, truth) = (circle(), truth());
    let before = run(&truth, &targets, &targets, 1);
    let after_ejs = run(&truth, &comp(ejs, &targets, true).unwrap(), &targets, 2);
    let after_js = run(&truth, &comp(js, &targets, true).unwrap(), &targets, 2);
    let red = |a: (f64, f64)| (1.0 - a.0 / before.0, 1.0 - a.1 / before.1);
    let (mean_red, max_red) = red(after_ejs);
    eprintln!("before {before:?}, EJS {after_ejs:?}, JS {after_js:?}");
    assert!(mean_red >= 0.80, "mean reduction {mean_red:.3}");
    assert!(max_red >= 0.60, "max reduction {max_red:.3}");
    assert!(
        after_ejs.0 < 0.5 * after_js.0,
        "EJS {after_ejs:?} vs JS {after_js:?}"
    );
}

#[test]
fn single_step_is_eq_22_and_the_first_iteration() {
    let (ejs, _) = models();
    let targets = circle();
    let single = compensate(
        &robot(),
        ejs,
        &targets,
        &CompensationOptions {
            iterative: false,
            ..CompensationOptions::default()
        },
    )
    .unwrap();
    let one = compensate(
        &robot(),
        ejs,
        &targets,
        &CompensationOptions {
            max_iter: 1,
            ..CompensationOptions::default()
        },
    )
    .unwrap();
    assert_eq!(single.commands, one.commands);
    assert_eq!(single.history.len(), 1);
    // Pm = Pd − δ̂(s(Pd)): δ̂ at the nominal IK of the targets, λ from the order
    let r = robot();
    let mut seed = r.home.clone();
    let q: Vec<Vec<f64>> = targets
        .poses
        .iter()
        .map(|p| {
            seed = r
                .ik(&kinematics::IkTarget::pose(p), &seed, &Default::default())
                .unwrap();
            seed.clone()
        })
        .collect();
    let dir = robokrige::space::derive_directions(&q, Some(&r.home));
    let d = ejs.predict(&q, &dir).unwrap().mean;
    for ((pm, pd), di) in single.commands.poses.iter().zip(&targets.poses).zip(&d) {
        let want = pd.translation.vector - Vector3::from(*di);
        assert!((pm.translation.vector - want).norm() < 1e-9);
        assert_eq!(pm.rotation, pd.rotation);
    }
}

#[test]
fn iterative_compensation_converges_without_directions_and_settles_with_them() {
    let (ejs, js) = models();
    let targets = circle();
    let opts = CompensationOptions::default();
    // JS: a smooth map, a contraction — converges in a few iterations
    let c = compensate(&robot(), js, &targets, &opts).unwrap();
    assert_eq!(c.stop, Stop::Converged, "{:?}", c.history);
    assert!(c.converged && c.history.len() <= 3);
    assert!(c.history.last().unwrap().rmse_change_mm < opts.tol_mm);
    // EJS: λ switches at the reversals; the loop either converges or stalls
    // there, and then names the points
    let c = compensate(&robot(), ejs, &targets, &opts).unwrap();
    eprintln!("{:?} {:?} {:?}", c.stop, c.unsettled, c.history);
    match c.stop {
        Stop::Converged => assert!(c.history.last().unwrap().rmse_change_mm < opts.tol_mm),
        Stop::Stalled => assert!(!c.unsettled.is_empty()),
        other => panic!("unexpected stop {other:?}"),
    }
    assert!(c.history.len() >= 2 && c.history.len() <= opts.max_iter);
    // the model predicts the final commands to land on the targets: the
    // residual Pm + δ̂(s(Pm)) − Pd is small except at the few points where a
    // joint reverses (bisection at the λ switch leaves part of the backlash)
    let resid: Vec<f64> = c
        .commands
        .poses
        .iter()
        .zip(&targets.poses)
        .zip(&c.predicted)
        .map(|((pm, pd), d)| {
            (pm.translation.vector + Vector3::from(*d) - pd.translation.vector).norm()
        })
        .collect();
    let small = resid.iter().filter(|r| **r < 0.01).count();
    assert!(small >= resid.len() - 6, "{resid:?}");
}

#[test]
fn unreachable_points_are_reported_by_index_never_passed_through() {
    let (ejs, _) = models();
    let mut targets = circle();
    for i in [5, 40] {
        targets.poses[i].translation = Translation3::new(9000.0, 0.0, 0.0);
    }
    match compensate(&robot(), ejs, &targets, &CompensationOptions::default()) {
        Err(Error::Unreachable { indices, first }) => {
            assert_eq!(indices, vec![5, 40]);
            assert!(first.contains("did not converge"), "{first}");
        }
        other => panic!("expected Unreachable, got {other:?}"),
    }
}

#[test]
fn a_start_far_from_the_trajectory_does_not_make_it_unreachable() {
    // Seeded from this start alone, the inverse kinematics of the circle's
    // first eleven points did not converge; home is the last seed.
    let (ejs, _) = models();
    let opts = CompensationOptions {
        start: Some(vec![100.0, 0.0, -100.0, 170.0, -100.0, 170.0]),
        ..CompensationOptions::default()
    };
    let res = compensate(&robot(), ejs, &circle(), &opts).unwrap();
    assert_eq!(res.joints.len(), circle().len());
}

#[test]
fn a_start_outside_the_joint_limits_is_refused_by_name() {
    let e = robot()
        .start_or_home(Some(&[0.0, 200.0, -90.0, 0.0, 0.0, 0.0]))
        .unwrap_err()
        .to_string();
    assert!(e.contains("start pose") && e.contains("q2 = 200°"), "{e}");
    assert!(!e.contains("q3"), "{e}");
}

#[test]
fn bad_options_and_mismatched_robots_are_errors() {
    let (ejs, _) = models();
    let targets = circle();
    for opts in [
        CompensationOptions {
            tol_mm: 0.0,
            ..CompensationOptions::default()
        },
        CompensationOptions {
            max_iter: 0,
            ..CompensationOptions::default()
        },
        CompensationOptions {
            hints: Some(vec![vec![0.0; 6]; 3]),
            ..CompensationOptions::default()
        },
    ] {
        assert!(matches!(
            compensate(&robot(), ejs, &targets, &opts),
            Err(Error::InvalidParameter(_))
        ));
    }
    let scara = kinematics::preset("scara-rh3frh5515").unwrap();
    assert!(matches!(
        compensate(&scara, ejs, &targets, &CompensationOptions::default()),
        Err(Error::JointCount { .. })
    ));
    let empty = Trajectory::new(Vec::new());
    assert!(compensate(&robot(), ejs, &empty, &CompensationOptions::default()).is_err());
}

#[test]
fn mean_only_prediction_matches_the_full_prediction() {
    let (ejs, js) = models();
    let data = read_csv(&shipped("comau_verify.csv")).unwrap();
    for m in [ejs, js] {
        let full = m.predict_dataset(&data).unwrap().mean;
        let fast = m.predict_mean(&data.q, &data.dir).unwrap();
        for (a, b) in full.iter().flatten().zip(fast.iter().flatten()) {
            assert!((a - b).abs() < 1e-9 * (1.0 + a.abs()), "{a} vs {b}");
        }
    }
}

/// Servo lag: a model with the joint's moves as an input
/// compensates along a path, each point predicted from the move into it
/// (from the start pose for the first), and leaves less error on the
/// simulated robot than the same model without the lag input.
#[test]
fn a_lag_model_compensates_along_the_path_better_than_one_without_it() {
    use robokrige::features::Feature;
    use robokrige::params::ErrorModelParams;
    use robokrige::sim::{CampaignKind, CampaignSpec, Effect, SimOutput, simulate};
    use robokrige::study::{Targets, compensate_and_evaluate, compensate_and_evaluate_each};
    let nominal = robot();
    let lag = Effect::parse("lag:joint=2,gain=0.0005").unwrap();
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, 7);
    spec.poses = 200;
    spec.effects = vec![lag.clone()];
    let (SimOutput::Measurements(data), truth) = simulate(&nominal, &spec).unwrap() else {
        unreachable!()
    };
    // a path through 40 random poses of the same true robot
    let mut path = CampaignSpec::new(CampaignKind::Verify, 7);
    path.poses = 40;
    let SimOutput::Measurements(poses) = simulate(&nominal, &path).unwrap().0 else {
        unreachable!()
    };
    let targets = Targets::from_joints(&nominal, &poses.q).unwrap();
    let kriging = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(300)
        .starts(2);
    let fit = |extras: Vec<Feature>| {
        ErrorModelParams::new()
            .kriging(kriging.clone())
            .extras(extras)
            .check()
            .unwrap()
            .fit(&data)
            .unwrap()
    };
    let plain = fit(Vec::new());
    let with_lag = fit(vec![Feature::Moves {
        joint: 2,
        tau_poses: 0.0,
        clock: None,
    }]);
    let home = nominal.home.clone();
    // along the path: the first point is predicted with the move from the
    // start; a model without history inputs predicts every point alone
    let q = &poses.q[..5];
    let dir = robokrige::space::derive_directions(q, Some(&home));
    let mut path = vec![home.clone()];
    path.extend(q.iter().cloned());
    let mut dirs = vec![vec![1.0; home.len()]];
    dirs.extend(dir.iter().cloned());
    use robokrige::predictor::ErrorPredictor;
    let along = predict_along(&with_lag, &home, q, &dir).unwrap();
    assert_eq!(
        along[..],
        with_lag.predict_errors(&path, &dirs).unwrap()[1..]
    );
    assert_ne!(along[0], with_lag.predict_errors(q, &dir).unwrap()[0]);
    assert_eq!(
        predict_along(&plain, &home, q, &dir).unwrap(),
        plain.predict_errors(q, &dir).unwrap()
    );
    let run = |m: &ErrorModel| {
        compensate_and_evaluate(&nominal, m, Path::new("t"), &truth, &targets, &home, 3)
            .unwrap()
            .evaluation
    };
    let (a, b) = (run(&plain), run(&with_lag));
    assert_eq!(a.before, b.before, "the same nominal run");
    // both at once: the same runs, in order
    let each = compensate_and_evaluate_each(
        &nominal,
        &[&plain, &with_lag],
        Path::new("t"),
        &truth,
        &targets,
        &home,
        3,
    )
    .unwrap();
    assert_eq!([&each[0].evaluation, &each[1].evaluation], [&a, &b]);
    assert!(
        b.after.mean_abs_mm < 0.7 * a.after.mean_abs_mm,
        "lag model {:.4} mm vs plain {:.4} mm (nominal {:.4})",
        b.after.mean_abs_mm,
        a.after.mean_abs_mm,
        a.before.mean_abs_mm
    );
}

#[test]
fn an_unreachable_position_only_target_says_where_its_orientation_came_from() {
    // the library's compensate-and-evaluate (diagnose --traj) says what
    // `robokrige compensate` says: position-only targets took the start
    // pose's orientation, and the file's columns give another
    let (ejs, _) = models();
    let dir = common::Scratch::new("rk-orient");
    let traj = dir.path().join("far.csv");
    std::fs::write(&traj, "x,y,z\n1800,0,1000\n9000,0,1000\n").unwrap();
    let r = robot();
    let start = r.start_or_home(None).unwrap();
    let targets = robokrige::study::Targets::read(&traj, &r, None, &start).unwrap();
    let truth_path = shipped("comau_circle.truth.json");
    let truth = robokrige::study::load_truth(&truth_path).unwrap();
    let e = robokrige::study::compensate_and_evaluate(
        &r,
        ejs,
        &truth_path,
        &truth,
        &targets,
        &start,
        1,
    )
    .unwrap_err()
    .to_string();
    assert!(
        e.contains("unreachable")
            && e.contains("orientation of the start pose")
            && e.contains("roll_deg, pitch_deg, yaw_deg columns"),
        "{e}"
    );
}
