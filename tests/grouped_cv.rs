//! Grouped cross-validation on a small ISO 9283 cube campaign (joints over
//! 180°, home and check poses out of the cubes): leave-one-cube-out of
//! every model `holdout` compares, and `cv --groups` on a column.

mod common;

use common::rk;
use robokrige::cv::{cross_validate_folds, group_partition, kfold_partition};
use robokrige::dataset::{Dataset, TextColumn, read_csv};
use robokrige::holdout::{CV_MODELS, HyperRows, holdout_cv};
use robokrige::kinematics::{JointKind, Robot, load_robot};
use robokrige::kriging::KrigingOptions;
use robokrige::params::ErrorModelParams;
use robokrige::sim::iso_cubes::{IsoCubeSpec, iso_cubes, measure_cubes};
use robokrige::sim::{ErrorProfile, TrueRobot};
use robokrige::space::periodic_joints;

fn ur10() -> Robot {
    let mut r = load_robot("ur10").unwrap();
    r.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    r
}

/// 3 cubes of 40 poses, the home pose and 3 check poses out of them.
fn campaign(robot: &Robot, seed: u64) -> (Dataset, Vec<usize>) {
    let mut spec = IsoCubeSpec::new(3, 250.0, 40);
    spec.flip_joints = vec![2, 4];
    spec.turn_joints = (0..robot.dof())
        .filter(|&j| robot.links[j].kind == JointKind::Revolute)
        .collect();
    let mut c = iso_cubes(robot, &spec, seed).unwrap();
    c.add_out_of_cube_poses(robot, 3, true, seed);
    let truth = TrueRobot::draw(robot, &ErrorProfile::for_robot(robot), seed);
    (measure_cubes(&truth, c.q.clone(), seed).unwrap(), c.cube)
}

#[test]
fn leave_one_cube_out_never_blows_up_and_flags_the_new_cube() {
    let robot = ur10();
    let (data, cube) = campaign(&robot, 7);
    let periodic = periodic_joints(&data.q);
    assert!(periodic.len() >= 4, "{periodic:?}");
    let base = ErrorModelParams::new()
        .periodic(periodic)
        .kriging(KrigingOptions::default().nugget(true).starts(4));
    // the hyperparameters chosen on each fold's training rows, as
    // `holdout --groups` does by default
    let cv = holdout_cv(&data, &robot, &base, &cube, HyperRows::EachFold, &|_, _| {}).unwrap();
    assert_eq!(cv.folds, 4);
    assert_eq!(cv.hyper, HyperRows::EachFold);
    for (f, w) in cv.fold_max_mm.iter().enumerate() {
        eprintln!("group {f}: {}", w.map(|v| format!("{v:.3}")).join(" / "));
    }
    for (f, w) in cv.fold_max_mm.iter().enumerate() {
        // no Kriging model blows up on a cube it never saw: the calibrated
        // models (what `fit --robot` deploys), and the kinematic-trend
        // models, whose parameter errors are one vector for the three axes,
        // every parameter a term and the unseen directions held at 0.
        // Measured 0.70–1.58× the D-H calibration's max with ξ chosen on
        // the 80-odd rows of the other cubes (0.30–1.29× on this build with
        // ξ chosen on all rows, the held-out cube's included); with a β per
        // axis and the first of nearly dependent parameters kept, 2.3–5.3×.
        // The stress bench holds the full-size campaigns to 1.5× (the
        // largest there, 1.47×).
        for k in 1..CV_MODELS.len() {
            assert!(
                w[k] <= 1.75 * w[0],
                "group {f}: {} max {:.3} mm against the D-H calibration's {:.3}",
                CV_MODELS[k],
                w[k],
                w[0]
            );
        }
    }
    // a whole cube held out is outside every Kriging model's coverage
    for (name, s) in CV_MODELS.iter().zip(&cv.scores).skip(1) {
        assert!(s.flag_rate > 0.9, "{name}: {s:?}");
    }
    // and random folds are not: the flag is the exception there
    let random = kfold_partition(data.len(), 5, 1).unwrap();
    let all = HyperRows::First(data.len());
    let cv = holdout_cv(&data, &robot, &base, &random, all, &|_, _| {}).unwrap();
    for (name, s) in CV_MODELS.iter().zip(&cv.scores).skip(1) {
        eprintln!("{name}: {s:?}");
        // measured 0.14–0.15 on this small campaign (its 4 out-of-cube
        // poses alone are 3 %), against more than 0.9 for a held-out cube
        assert!(s.flag_rate < 0.2, "{name}: {s:?}");
        for c in s.coverage_95 {
            assert!(c > 0.85, "{name}: {s:?}");
        }
    }
}

/// With the hyperparameters chosen per fold, a held-out cube is predicted
/// by models that saw nothing of it: the same errors as choosing them once
/// on the other cubes' rows, put first, and holding the cube out.
#[test]
fn each_fold_chooses_the_hyperparameters_without_the_held_out_group() {
    let robot = ur10();
    let (data, cube) = campaign(&robot, 5);
    let base = ErrorModelParams::new()
        .periodic(periodic_joints(&data.q))
        .kriging(KrigingOptions::default().nugget(true).starts(2));
    let each = holdout_cv(&data, &robot, &base, &cube, HyperRows::EachFold, &|_, _| {}).unwrap();
    let held = 1;
    let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| cube[i] == held);
    let order: Vec<usize> = train.iter().chain(&test).copied().collect();
    let reordered = data.select(&order);
    let fold: Vec<usize> = order
        .iter()
        .map(|&i| usize::from(cube[i] == held))
        .collect();
    let first = HyperRows::First(train.len());
    let once = holdout_cv(&reordered, &robot, &base, &fold, first, &|_, _| {}).unwrap();
    assert_eq!(once.hyper, first);
    for (k, name) in CV_MODELS.iter().enumerate() {
        let (a, b) = (each.fold_max_mm[held][k], once.fold_max_mm[1][k]);
        assert!(
            (a - b).abs() <= 1e-9 * b.max(1.0),
            "{name}: {a} against {b}"
        );
    }
    // and the first rows need to be enough to choose them on
    let err = holdout_cv(&data, &robot, &base, &cube, HyperRows::First(5), &|_, _| {})
        .unwrap_err()
        .to_string();
    assert!(err.contains("at least 10 rows"), "{err}");
    // as does every fold's training rows: a group of all rows but 6
    let lopsided: Vec<usize> = (0..data.len()).map(|i| usize::from(i >= 6)).collect();
    let err = holdout_cv(
        &data,
        &robot,
        &base,
        &lopsided,
        HyperRows::EachFold,
        &|_, _| {},
    )
    .unwrap_err()
    .to_string();
    assert!(
        err.contains("fold 2 of 2") && err.contains("leaves 6 to train on"),
        "{err}"
    );
    // and it does not suggest choosing them once on the first rows: such a
    // fold cannot be fitted at all
    assert!(
        err.contains("split that group") && !err.contains("--train"),
        "{err}"
    );
}

#[test]
fn groups_come_from_a_column_and_every_group_is_one_fold() {
    let robot = ur10();
    let (mut data, cube) = campaign(&robot, 3);
    let labels: Vec<String> = cube.iter().map(|c| format!("cube-{c}")).collect();
    data.text.push(TextColumn {
        name: "cube".into(),
        values: labels.clone(),
        note: None,
    });
    let fold = group_partition(&data.group_labels("cube").unwrap()).unwrap();
    // the same grouping (folds numbered by first appearance)
    for i in 0..fold.len() {
        for j in 0..fold.len() {
            assert_eq!(fold[i] == fold[j], cube[i] == cube[j]);
        }
    }
    let params = ErrorModelParams::new()
        .robot(robot)
        .calibrate(Some(Default::default()))
        .kriging(KrigingOptions::default().starts(2))
        .check()
        .unwrap();
    let cv = cross_validate_folds(&data, &fold, |t| params.fit(t)).unwrap();
    assert_eq!(cv.folds, 4);
    assert!(cv.scores.is_some());
    // unknown columns and a single group are errors that say so
    let err = data.group_labels("cell").unwrap_err().to_string();
    assert!(
        err.contains("no column 'cell'") && err.contains("cube"),
        "{err}"
    );
    assert!(group_partition(&vec!["a".to_string(); 5]).is_err());
}

/// `cv FILE --groups COLUMN` with a quick fit (Hooke–Jeeves, Gaussian).
fn cv_groups(csv: &std::path::Path, column: &str) -> (i32, String, String) {
    rk(&[
        "cv",
        csv.to_str().unwrap(),
        "--groups",
        column,
        "--optimizer",
        "hj",
        "--corr",
        "gaussian",
    ])
}

#[test]
fn cv_groups_on_the_command_line() {
    let dir = std::env::temp_dir().join(format!("robokrige-groups-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    // the shipped campaign, grouped by thirds of its rows in a text column
    let src = format!("{}/datasets/comau_lhs.csv", env!("CARGO_MANIFEST_DIR"));
    let text = std::fs::read_to_string(&src).unwrap();
    let mut out = String::new();
    for (i, line) in text.lines().enumerate() {
        let cell = if i == 0 {
            "cell".to_string()
        } else {
            format!("c{}", (i - 1) * 3 / 300)
        };
        out += &format!("{line},{cell}\n");
    }
    let csv = dir.join("grouped.csv");
    std::fs::write(&csv, out).unwrap();
    let (c, stdout, err) = cv_groups(&csv, "cell");
    assert_eq!(c, 0, "{err}");
    assert!(
        stdout.contains("leave-one-group-out CV over the 3 groups of 'cell'"),
        "{stdout}"
    );
    assert!(stdout.contains("95 % interval coverage"), "{stdout}");
    let (c, _, err) = rk(&["cv", csv.to_str().unwrap(), "--groups", "nope"]);
    assert_eq!(c, 1, "{err}");
    assert!(err.contains("no column 'nope'"), "{err}");
    std::fs::remove_dir_all(dir).ok();
}

/// Two 100 mm cubes of 300 poses with the gear harmonics ten times the
/// usual (the stress bench's narrowest campaign), the home pose and three
/// check poses far from them.
#[test]
fn harmonics_found_in_two_small_cubes_do_not_move_the_poses_far_from_them() {
    use robokrige::calibration::{CalibrationOptions, calibrate_both};
    use robokrige::vec3::{norms, residuals};
    let robot = ur10();
    let mut spec = IsoCubeSpec::new(2, 100.0, 300);
    spec.flip_joints = vec![2, 4];
    spec.turn_joints = (0..robot.dof()).collect();
    spec.tilt_deg = 0.0;
    let seed = 5;
    let mut c = iso_cubes(&robot, &spec, seed).unwrap();
    c.add_out_of_cube_poses(&robot, 3, true, seed);
    let mut profile = ErrorProfile::for_robot(&robot);
    profile.harmonic_deg *= 10.0;
    let truth = TrueRobot::draw(&robot, &profile, seed);
    let data = measure_cubes(&truth, c.q.clone(), seed).unwrap();
    let (inside, far): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| c.cube[i] < 2);
    let (train, held) = (data.select(&inside), data.select(&far));
    let (geometric, full) = calibrate_both(&train, &robot, &CalibrationOptions::default()).unwrap();
    // the search finds periods in the cubes (aliases of the longer errors)
    assert!(!full.harmonics().is_empty(), "{}", full.summary_line());
    let worst = |cal: &robokrige::calibration::Calibration| {
        let pred = cal.predict(&held.q, &held.dir).unwrap();
        norms(&residuals(held.errors.as_ref().unwrap(), &pred))
            .into_iter()
            .fold(0.0f64, f64::max)
    };
    let (g, h) = (worst(&geometric), worst(&full));
    // refitting the geometry beside them gains nothing significant on the
    // cubes and moved these poses from 2.01 to 2.71 mm; it is not done
    assert!(
        h <= 1.05 * g,
        "with harmonics {h:.3} mm, geometric {g:.3} mm ({})",
        full.summary_line()
    );
}

/// `simulate --kind cubes` writes a cube campaign whose `cube` column is a
/// label `cv --groups cube` holds out cube by cube; with an effect it is
/// measured like any campaign, and a bad size is refused.
#[test]
fn simulated_cubes_on_the_command_line_are_held_out_cube_by_cube() {
    let dir = tempfile::tempdir().unwrap();
    let csv = dir.path().join("cubes.csv");
    let (c, _, err) = rk(&[
        "simulate",
        "--kind",
        "cubes",
        "--cubes",
        "3",
        "--edge",
        "200",
        "--poses",
        "90",
        "--seed",
        "4",
        "-o",
        csv.to_str().unwrap(),
    ]);
    assert_eq!(c, 0, "{err}");
    let data = read_csv(&csv).unwrap();
    assert_eq!(data.len(), 90);
    let labels = data.group_labels("cube").unwrap();
    for g in ["c1", "c2", "c3"] {
        assert_eq!(labels.iter().filter(|l| *l == g).count(), 30, "{g}");
    }
    // a label, not a covariate a model or a diagnosis would take up
    assert!(data.covariate("cube").is_none());
    // each cube is a cluster: its poses within the cube's reach of each other
    let robot = load_robot("comau-nj220").unwrap();
    for g in ["c1", "c2", "c3"] {
        let p: Vec<_> = (0..data.len())
            .filter(|&i| labels[i] == g)
            .map(|i| robot.position(&data.q[i]).unwrap())
            .collect();
        let far = p
            .iter()
            .flat_map(|a| p.iter().map(move |b| (a - b).norm()))
            .fold(0.0f64, f64::max);
        assert!(far <= 200.0 * 3f64.sqrt() + 1e-6, "{g}: {far} mm");
    }
    let (c, stdout, err) = cv_groups(&csv, "cube");
    assert_eq!(c, 0, "{err}");
    assert!(
        stdout.contains("leave-one-group-out CV over the 3 groups of 'cube'"),
        "{stdout}"
    );
    let (c, _, err) = rk(&[
        "simulate",
        "--kind",
        "cubes",
        "--cubes",
        "4",
        "--poses",
        "90",
        "-o",
        dir.path().join("x.csv").to_str().unwrap(),
    ]);
    assert_eq!(c, 1);
    assert!(err.contains("multiple of --cubes 4"), "{err}");
}

/// A fold that cannot be fitted (a group so large that the rest cannot
/// carry the kinematic trend) names itself and its sizes.
#[test]
fn a_fold_that_fails_names_itself_and_its_sizes() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("g.csv");
    let text = std::fs::read_to_string(format!(
        "{}/datasets/comau_lhs.csv",
        env!("CARGO_MANIFEST_DIR")
    ))
    .unwrap();
    let mut lines = text.lines();
    let mut out = format!("{},g\n", lines.next().unwrap());
    for (i, l) in lines.take(60).enumerate() {
        let g = match i {
            0..30 => "a",
            30..59 => "b",
            _ => "c",
        };
        out += &format!("{l},{g}\n");
    }
    std::fs::write(&path, out).unwrap();
    let (c, _, err) = rk(&[
        "holdout",
        path.to_str().unwrap(),
        "--robot",
        "comau-nj220",
        "--groups",
        "g",
    ]);
    assert_eq!(c, 1, "{err}");
    assert!(
        err.contains("fold 1 of 3 (30 rows held out, 30 to train on)"),
        "{err}"
    );
}
