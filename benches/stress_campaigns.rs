//! Stress campaigns at full size: ISO 9283 cube campaigns of three robots
//! (the UR10 with five or six joints wider than 180°, the COMAU NJ220, and
//! the ABB IRB 2600 from its robot file), some with home and check poses
//! out of the cubes, cross-validated by `holdout_cv` with random 10-fold
//! (hyperparameters chosen once on all rows) and leave-one-cube-out folds
//! (chosen on each fold's training cubes, as `holdout --groups` does).
//!
//! Per campaign and fold kind, per model: mean and max 3D error, the worst
//! fold's max over the D-H calibration's max in that fold, the 95 %
//! interval coverage per axis, and the flag rate and recall of gross
//! errors.
//!
//! Run: `cargo bench --bench stress_campaigns` (about 5 minutes on 2
//! cores); `-- NAME` runs the campaigns whose name contains NAME;
//! `-- --backlash` gives the calibrated models a calibration with the
//! joints' backlash (`holdout --backlash`).

use robokrige::calibration::CalibrationOptions;
use robokrige::cv::kfold_partition;
use robokrige::holdout::{CV_MODELS, HoldoutCv, HyperRows, holdout_cv};
use robokrige::kinematics::{JointKind, Robot, load_robot};
use robokrige::kriging::KrigingOptions;
use robokrige::params::ErrorModelParams;
use robokrige::sim::iso_cubes::{IsoCubeSpec, iso_cubes, measure_cubes};
use robokrige::sim::{ErrorProfile, TrueRobot};
use robokrige::space::periodic_joints;

struct Campaign {
    name: &'static str,
    robot: Robot,
    spec: IsoCubeSpec,
    seed: u64,
    /// Home pose and check poses out of the cubes.
    out_of_cube: Option<usize>,
    /// Gear harmonics scaled by this (a robot with more than geometry).
    harmonics: f64,
}

fn ur10() -> Robot {
    let mut r = load_robot("ur10").unwrap();
    r.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    r
}

fn spec(robot: &Robot, cubes: usize, edge: f64, per: usize, flips: &[usize]) -> IsoCubeSpec {
    let mut s = IsoCubeSpec::new(cubes, edge, per);
    s.flip_joints = flips.to_vec();
    s.turn_joints = (0..robot.dof())
        .filter(|&j| robot.links[j].kind == JointKind::Revolute)
        .collect();
    s
}

fn campaigns() -> Vec<Campaign> {
    let ur10 = ur10();
    let comau = load_robot("comau-nj220").unwrap();
    let abb = load_robot(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/robots/abb-irb2600.toml"
    ))
    .unwrap();
    let mut comau_spec = spec(&comau, 4, 400.0, 150, &[4]);
    comau_spec.ranges = Some(vec![
        (-90.0, 90.0),
        (-40.0, 20.0),
        (-150.0, -90.0),
        (-90.0, 90.0),
        (-60.0, 60.0),
        (-90.0, 90.0),
    ]);
    let mut abb_spec = spec(&abb, 4, 300.0, 150, &[4]);
    abb_spec.ranges = Some(vec![
        (-90.0, 90.0),
        (-20.0, 60.0),
        (-60.0, 20.0),
        (-90.0, 90.0),
        (-90.0, 90.0),
        (-90.0, 90.0),
    ]);
    let mut narrow = spec(&ur10, 2, 100.0, 300, &[2, 4]);
    narrow.tilt_deg = 0.0;
    vec![
        Campaign {
            name: "ur10 4 cubes 300 mm",
            spec: spec(&ur10, 4, 300.0, 158, &[2, 4]),
            robot: ur10.clone(),
            seed: 2,
            out_of_cube: None,
            harmonics: 1.0,
        },
        Campaign {
            name: "ur10 5 cubes 400 mm",
            spec: spec(&ur10, 5, 400.0, 126, &[2, 4]),
            robot: ur10.clone(),
            seed: 4,
            out_of_cube: None,
            harmonics: 1.0,
        },
        Campaign {
            name: "ur10 3 cubes 200 mm + home + 6 checks, harmonics x10",
            spec: spec(&ur10, 3, 200.0, 208, &[2, 4]),
            robot: ur10.clone(),
            seed: 3,
            out_of_cube: Some(6),
            harmonics: 10.0,
        },
        Campaign {
            name: "ur10 2 cubes 100 mm + home + 3 checks, harmonics x10",
            spec: narrow,
            robot: ur10,
            seed: 5,
            out_of_cube: Some(3),
            harmonics: 10.0,
        },
        Campaign {
            name: "comau-nj220 4 cubes 400 mm",
            spec: comau_spec,
            robot: comau,
            seed: 1,
            out_of_cube: None,
            harmonics: 1.0,
        },
        Campaign {
            name: "abb-irb2600 (robot file) 4 cubes 300 mm",
            spec: abb_spec,
            robot: abb,
            seed: 1,
            out_of_cube: None,
            harmonics: 1.0,
        },
    ]
}

fn print(label: &str, cv: &HoldoutCv) {
    let ratio = |k: usize| {
        cv.fold_max_mm
            .iter()
            .map(|f| f[k] / f[0])
            .fold(0.0f64, f64::max)
    };
    println!(
        "  {label} ({} folds; hyperparameters {:.1} s, calibrated model fits {:.1} s, kinematic {:.1} s):",
        cv.folds,
        cv.hyper_seconds,
        cv.rows[2].seconds + cv.rows[3].seconds,
        cv.rows[4].seconds + cv.rows[5].seconds
    );
    println!(
        "  | model | mean 3D | max 3D | worst fold max / D-H | coverage x / y / z | flagged | gross flagged |"
    );
    for (k, name) in CV_MODELS.iter().enumerate() {
        let (r, s) = (&cv.rows[k + 1], &cv.scores[k]);
        println!(
            "  | {name} | {:.3} | {:.3} | {:.2} | {:.3} / {:.3} / {:.3} | {:.1} % | {} |",
            r.mean_mm,
            r.max_mm,
            ratio(k),
            s.coverage_95[0],
            s.coverage_95[1],
            s.coverage_95[2],
            100.0 * s.flag_rate,
            s.flag_recall.map_or("-".into(), |v| format!(
                "{:.0} % of {}",
                100.0 * v,
                s.gross_rows
            ))
        );
    }
}

fn main() -> robokrige::Result<()> {
    let filter: Option<String> = std::env::args().skip(1).find(|a| !a.starts_with('-'));
    let backlash = std::env::args().any(|a| a == "--backlash");
    for c in campaigns() {
        if filter
            .as_ref()
            .is_some_and(|f| !c.name.contains(f.as_str()))
        {
            continue;
        }
        let t = std::time::Instant::now();
        let mut camp = iso_cubes(&c.robot, &c.spec, c.seed)?;
        if let Some(checks) = c.out_of_cube {
            camp.add_out_of_cube_poses(&c.robot, checks, true, c.seed);
        }
        let mut profile = ErrorProfile::for_robot(&c.robot);
        profile.harmonic_deg *= c.harmonics;
        let truth = TrueRobot::draw(&c.robot, &profile, c.seed);
        let data = measure_cubes(&truth, camp.q.clone(), c.seed)?;
        let periodic = periodic_joints(&data.q);
        println!(
            "{} (seed {}): {} poses, joint spans [{}] deg, periodic {:?}",
            c.name,
            c.seed,
            data.len(),
            camp.joint_spans()
                .iter()
                .map(|v| format!("{v:.0}"))
                .collect::<Vec<_>>()
                .join(", "),
            periodic.iter().map(|j| j + 1).collect::<Vec<_>>()
        );
        let base = ErrorModelParams::new()
            .periodic(periodic)
            .kriging(KrigingOptions::default().nugget(true))
            .calibrate(backlash.then(|| CalibrationOptions::default().with_backlash(true)));
        let random = kfold_partition(data.len(), 10, c.seed)?;
        let t_cv = std::time::Instant::now();
        let cv = holdout_cv(
            &data,
            &c.robot,
            &base,
            &random,
            HyperRows::First(data.len()),
            &|_, _| {},
        )?;
        let label = format!("random 10-fold, {:.1} s", t_cv.elapsed().as_secs_f64());
        print(&label, &cv);
        let cv = holdout_cv(
            &data,
            &c.robot,
            &base,
            &camp.cube,
            HyperRows::EachFold,
            &|_, _| {},
        )?;
        print("leave one cube out", &cv);
        println!("  ({:.0} s)", t.elapsed().as_secs_f64());
    }
    Ok(())
}
