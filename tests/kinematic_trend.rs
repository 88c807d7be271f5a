//! The kinematic-error trend basis and periodic joints.

mod common;

use robokrige::dataset::read_csv;
use robokrige::kinematics;
use robokrige::kriging::{KrigingOptions, OptimizerKind, TrendModel};
use robokrige::model::ErrorModel;
use robokrige::params::{ErrorModelParams, TrendSpec};
use robokrige::physics::identify_mdh;
use robokrige::sim::campaign::simulate_on;
use robokrige::sim::{CampaignKind, CampaignSpec, ErrorProfile, SimOutput, TrueRobot};
use robokrige::space::{Space, periodic_joints};
use std::path::Path;

/// The papers' set-up: Hooke–Jeeves, interpolating.
fn hj() -> KrigingOptions {
    KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .nugget(false)
}

fn rms3(a: &[[f64; 3]], b: &[[f64; 3]]) -> f64 {
    (a.iter()
        .zip(b)
        .map(|(u, v)| (0..3).map(|k| (u[k] - v[k]).powi(2)).sum::<f64>())
        .sum::<f64>()
        / a.len() as f64)
        .sqrt()
}

#[test]
fn periodic_encoding_layout_and_auto_choice() {
    let s = Space::Ejs.encode(&[1], &[10.0, 90.0], &[1.0, -1.0]);
    assert_eq!(s.len(), 5);
    assert_eq!(s[0], 10.0);
    assert!((s[1] - 1.0).abs() < 1e-15 && s[2].abs() < 1e-15);
    assert_eq!(&s[3..], &[1.0, -1.0]);
    assert_eq!(
        Space::Ejs.encoded_names(2, &[1]),
        vec!["q1", "sin q2", "cos q2", "dir1", "dir2"]
    );
    assert_eq!(Space::Js.encoded_dim(6, &[0, 3, 5]), 9);
    let q = vec![vec![-170.0, 0.0, 10.0], vec![20.0, 100.0, -30.0]];
    assert_eq!(periodic_joints(&q), vec![0]);
}

/// A joint entered as (sin, cos) makes θ and θ + 360° the same input.
#[test]
fn periodic_model_predicts_the_same_a_turn_later() {
    let nominal = kinematics::preset("ur10").unwrap();
    let robot = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), 4);
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, 4);
    spec.poses = 80;
    let (SimOutput::Measurements(d), _) = simulate_on(&robot, &spec).unwrap() else {
        panic!()
    };
    let m = ErrorModelParams::new()
        .space(Space::Ejs)
        .periodic(vec![0, 5])
        .kriging(hj())
        .check()
        .and_then(|p| p.fit(&d))
        .unwrap();
    assert_eq!(m.periodic(), &[0, 5]);
    let q = vec![vec![30.0, -80.0, 70.0, -90.0, 80.0, 10.0]];
    let mut q2 = q.clone();
    q2[0][0] += 360.0;
    q2[0][5] -= 360.0;
    let dir = vec![vec![1.0; 6]];
    let (a, b) = (
        m.predict_mean(&q, &dir).unwrap(),
        m.predict_mean(&q2, &dir).unwrap(),
    );
    assert!(rms3(&a, &b) < 1e-9, "{a:?} vs {b:?}");
    // without the encoding the two differ
    let plain = ErrorModel::fit(&d, Space::Ejs, &hj()).unwrap();
    let (c, e) = (
        plain.predict_mean(&q, &dir).unwrap(),
        plain.predict_mean(&q2, &dir).unwrap(),
    );
    assert!(rms3(&c, &e) > 1e-3);
    // the model round-trips with its encoding
    let path = std::env::temp_dir().join(format!("rk-periodic-{}.json", std::process::id()));
    m.save(&path).unwrap();
    let back = ErrorModel::load(&path).unwrap();
    assert_eq!(back.predict_mean(&q2, &dir).unwrap(), b);
    assert_eq!(back.input_map(), m.input_map());
    std::fs::remove_file(path).ok();
}

/// On a robot whose only error is geometric (no APD, compliance or noise),
/// the kinematic trend alone explains the error: universal Kriging with it
/// predicts new poses to the linearisation error, far better than the
/// constant trend from the same 150 poses.
#[test]
fn kinematic_trend_captures_geometric_errors() {
    let nominal = kinematics::preset("comau-nj220").unwrap();
    let mut robot = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), 5);
    for d in &mut robot.deviation {
        *d = robokrige::sim::JointDeviation::none();
    }
    robot
        .compliance
        .stiffness_nm_per_rad
        .iter_mut()
        .for_each(|k| *k = 0.0);
    robot = robot.noise_free();
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, 5);
    spec.poses = 150;
    let (SimOutput::Measurements(train), _) = simulate_on(&robot, &spec).unwrap() else {
        panic!()
    };
    let (SimOutput::Measurements(test), _) =
        simulate_on(&robot, &CampaignSpec::new(CampaignKind::Verify, 6)).unwrap()
    else {
        panic!()
    };
    let truth = test.errors.clone().unwrap();
    let kin = ErrorModelParams::new()
        .space(Space::Js)
        .kriging(hj())
        .trend(TrendSpec::Kinematic(Box::new(nominal.clone())))
        .check()
        .and_then(|p| p.fit(&train))
        .unwrap();
    let plain = ErrorModel::fit(&train, Space::Js, &hj()).unwrap();
    let e_kin = rms3(&truth, &kin.predict_mean(&test.q, &test.dir).unwrap());
    let e_plain = rms3(&truth, &plain.predict_mean(&test.q, &test.dir).unwrap());
    let e_none = rms3(&truth, &vec![[0.0; 3]; truth.len()]);
    eprintln!("rms: nominal {e_none:.4}, UK constant {e_plain:.4}, UK kinematic {e_kin:.5} mm");
    assert!(
        e_kin < 0.01 && e_kin < 0.1 * e_plain,
        "{e_kin} vs {e_plain}"
    );
    // the trend names say what they are
    let names = &kin.reports()[0].trend_terms;
    assert!(names.iter().any(|t| t.starts_with("dPx/d")), "{names:?}");
    // and the report lists the model's terms, every parameter the axes
    // share (each output's search saw a screened copy)
    for (r, o) in kin.reports().iter().zip(kin.outputs()) {
        assert_eq!(r.trend_terms.len(), o.data().trend().len());
        assert!(r.dropped_terms.is_empty());
    }
}

/// The public UR10 data, if present: 200 training rows, the next
/// 100 held out. Skips cleanly when ../shared/data is absent.
#[test]
fn ur10_real_data_small_split() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data/ipa-ur10/series_c_random_poses.csv");
    if !path.exists() {
        eprintln!("skipped: {} not found", path.display());
        return;
    }
    let data = read_csv(&path).unwrap();
    let mut robot = kinematics::preset("ur10").unwrap();
    robot.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    let train = data.select(&(0..200).collect::<Vec<_>>());
    let test = data.select(&(200..300).collect::<Vec<_>>());
    let truth = test.errors.clone().unwrap();
    let mean3 = |p: &[[f64; 3]]| {
        truth
            .iter()
            .zip(p)
            .map(|(t, q)| {
                ((t[0] - q[0]).powi(2) + (t[1] - q[1]).powi(2) + (t[2] - q[2]).powi(2)).sqrt()
            })
            .sum::<f64>()
            / truth.len() as f64
    };
    let nominal = mean3(&vec![[0.0; 3]; truth.len()]);
    let (cal, _) = identify_mdh(&train, &robot, &vec![None; 6]).unwrap();
    let dh = robokrige::physics::PhysicsModel::new(
        "t",
        robot.clone(),
        robokrige::physics::Geometry::Mdh { robot: cal },
    );
    let lm = mean3(&dh.predict(&test.q, &test.dir).unwrap());
    let uk = ErrorModelParams::new()
        .space(Space::Js)
        .periodic(periodic_joints(&train.q))
        .kriging(hj())
        .trend(TrendSpec::Kinematic(Box::new(robot.clone())))
        .check()
        .and_then(|p| p.fit(&train))
        .unwrap();
    let k = mean3(&uk.predict_mean(&test.q, &test.dir).unwrap());
    eprintln!(
        "UR10 held-out mean 3D: nominal {nominal:.3}, D-H {lm:.3}, UK kinematic JS {k:.3} mm"
    );
    assert!(lm < 0.7 * nominal && k < lm, "{nominal} {lm} {k}");
}

/// Refitting at a model's own hyperparameters on its own rows reproduces it,
/// for the polynomial and the kinematic trend; on more rows it still
/// predicts (the scaling path).
#[test]
fn refit_at_hyperparameters_reproduces_the_model() {
    let data =
        read_csv(&Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/comau_lhs.csv")).unwrap();
    let sub = data.select(&(0..120).collect::<Vec<_>>());
    let robot = kinematics::preset("comau-nj220").unwrap();
    let q = data.q[200..210].to_vec();
    let dir = data.dir[200..210].to_vec();
    for kin in [false, true] {
        let m = if kin {
            ErrorModelParams::new()
                .space(Space::Ejs)
                .kriging(hj())
                .trend(TrendSpec::Kinematic(Box::new(robot.clone())))
                .check()
                .and_then(|p| p.fit(&sub))
                .unwrap()
        } else {
            ErrorModel::fit(&sub, Space::Ejs, &hj()).unwrap()
        };
        let again = m.refit(&sub).unwrap();
        let (a, b) = (
            m.predict_mean(&q, &dir).unwrap(),
            again.predict_mean(&q, &dir).unwrap(),
        );
        assert!(rms3(&a, &b) < 1e-9, "kinematic {kin}: {a:?} vs {b:?}");
        let all = m.refit(&data).unwrap();
        let truth = &data.errors.as_ref().unwrap()[200..210];
        // rows 200..210 are now training rows: interpolated
        assert!(rms3(truth, &all.predict_mean(&q, &dir).unwrap()) < 1e-6);
    }
}

/// PCC + PCA over quadratic and kinematic candidates keeps kinematic rows
/// among the selected (fused) candidates of a geometric error, and the model
/// round-trips through its file.
#[test]
fn pcc_pca_can_fuse_kinematic_candidates() {
    let data =
        read_csv(&Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/comau_lhs.csv")).unwrap();
    let robot = kinematics::preset("comau-nj220").unwrap();
    let (m, reports) = common::fit_pcc_pca(&data, &hj(), Some(&robot));
    for r in &reports {
        let kin = r
            .ranking
            .iter()
            .filter(|(n, c)| n.starts_with("dP") && c.abs() > 0.1)
            .count();
        assert!(kin > 0, "{:?}", &r.ranking[..5]);
    }
    let path = std::env::temp_dir().join(format!("rk-pca-kin-{}.json", std::process::id()));
    m.save(&path).unwrap();
    let back = ErrorModel::load(&path).unwrap();
    let q = data.q[..5].to_vec();
    let dir = data.dir[..5].to_vec();
    assert_eq!(
        back.predict_mean(&q, &dir).unwrap(),
        m.predict_mean(&q, &dir).unwrap()
    );
    std::fs::remove_file(path).ok();
}
