//! Independent-reference tests of `robokrige::kinematics`.
//!
//! * FK against fixtures computed with Peter Corke's Robotics Toolbox for Python
//!   (and spatialmath for the β chain), see `tests/fixtures/README.md`.
//! * IK round trips, error cases.
//! * The geometric Jacobian against central finite differences.
//! * Closed forms: seed 000 eq 1 (SCARA) and the COMAU home-pose wrist centre.

use nalgebra::{Isometry3, Matrix3, Rotation3, Translation3, UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use robokrige::Error;
use robokrige::kinematics::{IkOptions, IkTarget, JointKind, MdhLink, PRESET_NAMES, Robot, preset};
use serde::Deserialize;

const FIXTURES: &str = include_str!("fixtures/fk_fixtures.json");

#[derive(Deserialize)]
struct Fixtures {
    cases: Vec<Case>,
}

#[derive(Deserialize)]
struct Case {
    name: String,
    /// Only for cases that are not presets (`mdh-beta`).
    links: Option<Vec<MdhLink>>,
    limits: Option<Vec<(f64, f64)>>,
    base: Option<[[f64; 4]; 4]>,
    tool: Option<[[f64; 4]; 4]>,
    samples: Vec<Sample>,
}

#[derive(Deserialize)]
struct Sample {
    q: Vec<f64>,
    /// Row-major 4×4 homogeneous TCP pose, mm.
    pose: [[f64; 4]; 4],
}

fn fixtures() -> Fixtures {
    serde_json::from_str(FIXTURES).expect("tests/fixtures/fk_fixtures.json parses")
}

fn rotation_of(m: &[[f64; 4]; 4]) -> Matrix3<f64> {
    Matrix3::from_fn(|r, c| m[r][c])
}

fn translation_of(m: &[[f64; 4]; 4]) -> Vector3<f64> {
    Vector3::new(m[0][3], m[1][3], m[2][3])
}

fn isometry_of(m: &[[f64; 4]; 4]) -> Isometry3<f64> {
    let rot = Rotation3::from_matrix_unchecked(rotation_of(m));
    Isometry3::from_parts(
        Translation3::from(translation_of(m)),
        UnitQuaternion::from_rotation_matrix(&rot),
    )
}

/// The robot of a fixture case: a preset, or (for `mdh-beta`) a preset clone
/// whose links, base, tool and limits are replaced by the stored ones.
fn robot_of(case: &Case) -> Robot {
    match &case.links {
        None => preset(&case.name).expect("fixture case names a preset"),
        Some(links) => {
            let mut r = preset("comau-nj220").unwrap();
            r.name = case.name.clone();
            r.links = links.clone();
            r.limits = case.limits.clone().expect("custom case stores limits");
            r.work_ranges = r.limits.clone();
            r.home = vec![0.0; links.len()];
            r.base = isometry_of(case.base.as_ref().expect("custom case stores base"));
            r.tool = isometry_of(case.tool.as_ref().expect("custom case stores tool"));
            r
        }
    }
}

fn mdh_beta_robot() -> Robot {
    let fx = fixtures();
    let case = fx.cases.iter().find(|c| c.name == "mdh-beta").unwrap();
    robot_of(case)
}

fn random_q(rng: &mut StdRng, ranges: &[(f64, f64)]) -> Vec<f64> {
    ranges
        .iter()
        .map(|&(lo, hi)| rng.random_range(lo..hi))
        .collect()
}

#[test]
fn fk_matches_independent_fixtures() {
    let fx = fixtures();
    let names: Vec<&str> = fx.cases.iter().map(|c| c.name.as_str()).collect();
    for p in PRESET_NAMES {
        assert!(names.contains(&p), "no fixture for preset {p}");
    }
    assert!(names.contains(&"mdh-beta"));

    for case in &fx.cases {
        let robot = robot_of(case);
        if case.links.is_some() {
            // The β chain really has β ≠ 0 (otherwise the case proves nothing).
            assert!(robot.links.iter().filter(|l| l.beta_deg != 0.0).count() >= 2);
            assert!(robot.tool.translation.vector.norm() > 1.0);
        }
        assert!(case.samples.len() >= 25, "{}", case.name);
        for (k, s) in case.samples.iter().enumerate() {
            let pose = robot.fk(&s.q).unwrap();
            let dp = (pose.translation.vector - translation_of(&s.pose)).amax();
            let dr =
                (pose.rotation.to_rotation_matrix().into_inner() - rotation_of(&s.pose)).amax();
            assert!(
                dp < 1e-6,
                "{} sample {k}: position differs by {dp:e} mm at q = {:?}",
                case.name,
                s.q
            );
            assert!(
                dr < 1e-9,
                "{} sample {k}: rotation differs by {dr:e} at q = {:?}",
                case.name,
                s.q
            );
            // The fixture poses are proper rigid transforms.
            assert_eq!(s.pose[3], [0.0, 0.0, 0.0, 1.0]);
        }
    }
}

/// Whether `q` is too close to a kinematic singularity for a joint-space round
/// trip to be well posed with the default tolerances.
///
/// * Several solutions within the ±3° seed perturbation (or q4/q6 only
///   determined as a sum): wrist θ5 ≈ 0 for the 6-axis arms, elbow θ3 ≈ 0 for
///   the UR10, θ2 ≈ 0 for the SCARA — margin 8°.
/// * Ill conditioning: IK stops once the weighted task residual is below
///   ~1.4e-7 mm (position 1e-7 mm, orientation 1e-10 rad × 1000 mm/rad), so the
///   joint error can reach ~1.4e-7 / σ_min, where σ_min is the smallest
///   singular value of the IK's weighted Jacobian (orientation rows ×
///   `orientation_weight_mm`) with columns per API unit (degree or mm).
///   σ_min ≥ 0.35 mm/unit (20 mm/rad) keeps that below 1e-6° / 1e-6 mm.
///   (Example that would fail otherwise: UR10 q = (92.58, −115.80, 41.20,
///   −23.17, 68.75, 16.39)°, near the shoulder singularity, σ_min = 0.149
///   mm/rad: IK meets its tolerance with a 1.2e-8 mm residual but
///   |Δq6| = 2.7e-6°.)
fn near_singular(robot: &Robot, q: &[f64], opts: &IkOptions) -> bool {
    let margin = 8.0;
    let near = |v: f64| {
        let w = v.rem_euclid(180.0);
        w < margin || w > 180.0 - margin
    };
    let by_geometry = match robot.name.as_str() {
        "comau-nj220" | "kuka-kr30ha" => near(q[4]),
        "ur10" => near(q[2]) || near(q[4]),
        "scara-rh3frh5515" => near(q[1]),
        _ => false,
    };
    let mut jw = robot.jacobian(q).unwrap();
    for c in 0..robot.dof() {
        for r in 3..6 {
            jw[(r, c)] *= opts.orientation_weight_mm;
        }
        let scale = robot.unit_scale(c);
        jw.column_mut(c).scale_mut(scale);
    }
    let sigma_min = jw.singular_values().min();
    by_geometry || sigma_min < 0.35
}

#[test]
fn ik_round_trip() {
    let mut rng = StdRng::seed_from_u64(0x1c_0ffee);
    let opts = IkOptions::default();
    for name in PRESET_NAMES {
        let robot = preset(name).unwrap();
        let (mut done, mut skipped) = (0, 0);
        while done < 50 {
            assert!(skipped < 50, "{name}: {skipped} near-singular draws");
            let q = random_q(&mut rng, &robot.work_ranges);
            let target_pose = robot.fk(&q).unwrap();
            let seed: Vec<f64> = q.iter().map(|v| v + rng.random_range(-3.0..3.0)).collect();
            let sol = robot
                .ik(&IkTarget::pose(&target_pose), &seed, &opts)
                .unwrap_or_else(|e| {
                    panic!("{name}: IK failed for q = {q:?}, seed = {seed:?}: {e}")
                });
            assert_eq!(sol.len(), q.len());
            // The pose is always reached, singular or not.
            let reached = robot.fk(&sol).unwrap();
            let dp = (reached.translation.vector - target_pose.translation.vector).norm();
            let dr = reached.rotation.angle_to(&target_pose.rotation);
            assert!(
                dp < 1e-6,
                "{name}: position residual {dp:e} mm at q = {q:?}"
            );
            assert!(
                dr < 1e-9,
                "{name}: orientation residual {dr:e} rad at q = {q:?}"
            );
            assert!(robot.within_limits(&sol));
            if near_singular(&robot, &q, &opts) {
                skipped += 1;
                continue;
            }
            let err = sol
                .iter()
                .zip(&q)
                .map(|(a, b)| (a - b).abs())
                .fold(0.0, f64::max);
            assert!(
                err < 1e-6,
                "{name}: |q_ik − q| = {err:e} for q = {q:?}, seed = {seed:?}, q_ik = {sol:?}"
            );
            done += 1;
        }
    }
}

#[test]
fn ik_errors() {
    let opts = IkOptions::default();
    for name in PRESET_NAMES {
        let robot = preset(name).unwrap();
        let home_pose = robot.fk(&robot.home).unwrap();

        // 10 m beyond the home TCP: out of reach for every preset.
        let far =
            IkTarget::position(home_pose.translation.vector + Vector3::new(10_000.0, 0.0, 0.0));
        match robot.ik(&far, &robot.home, &opts) {
            Err(Error::IkNotConverged { position_mm, .. }) => {
                assert!(position_mm > 5_000.0, "{name}: residual {position_mm}")
            }
            other => panic!("{name}: expected IkNotConverged, got {other:?}"),
        }
        let far_pose = Isometry3::from_parts(
            Translation3::from(home_pose.translation.vector + Vector3::new(0.0, 0.0, 10_000.0)),
            home_pose.rotation,
        );
        assert!(matches!(
            robot.ik(&IkTarget::pose(&far_pose), &robot.home, &opts),
            Err(Error::IkNotConverged { .. })
        ));

        // Wrong-length seed / joint vector.
        let short = &robot.home[..robot.dof() - 1];
        match robot.ik(&IkTarget::pose(&home_pose), short, &opts) {
            Err(Error::JointCount { expected, got }) => {
                assert_eq!((expected, got), (robot.dof(), robot.dof() - 1))
            }
            other => panic!("{name}: expected JointCount, got {other:?}"),
        }
        let long: Vec<f64> = robot.home.iter().copied().chain([0.0]).collect();
        assert!(matches!(
            robot.fk(&long),
            Err(Error::JointCount { expected, got }) if expected == robot.dof() && got == robot.dof() + 1
        ));
        assert!(matches!(
            robot.jacobian(short),
            Err(Error::JointCount { .. })
        ));
    }
    assert!(matches!(
        preset("no-such-robot"),
        Err(Error::UnknownRobot { .. })
    ));
}

#[test]
fn jacobian_matches_finite_differences() {
    let mut rng = StdRng::seed_from_u64(7);
    let mut robots: Vec<Robot> = PRESET_NAMES.iter().map(|n| preset(n).unwrap()).collect();
    robots.push(mdh_beta_robot());
    for robot in &robots {
        for _ in 0..8 {
            let q = random_q(&mut rng, &robot.work_ranges);
            let j = robot.jacobian(&q).unwrap();
            let jp = robot.position_jacobian(&q).unwrap();
            assert_eq!((j.nrows(), j.ncols()), (6, robot.dof()));
            assert_eq!(jp, j.fixed_rows::<3>(0).into_owned());
            for i in 0..robot.dof() {
                // Step in API units (degrees or mm), then convert the difference
                // quotient to the Jacobian's units (per radian or per mm).
                let h = 1e-3;
                let mut qp = q.clone();
                let mut qm = q.clone();
                qp[i] += h;
                qm[i] -= h;
                let tp = robot.fk(&qp).unwrap();
                let tm = robot.fk(&qm).unwrap();
                let step = 2.0 * h * robot.unit_scale(i);
                let lin = (tp.translation.vector - tm.translation.vector) / step;
                let ang = (tp.rotation * tm.rotation.inverse()).scaled_axis() / step;
                let j_lin = j.fixed_view::<3, 1>(0, i).into_owned();
                let j_ang = j.fixed_view::<3, 1>(3, i).into_owned();
                let tol_lin = 1e-6 * j_lin.norm().max(1.0);
                let tol_ang = 1e-6 * j_ang.norm().max(1.0);
                assert!(
                    (lin - j_lin).norm() < tol_lin,
                    "{} joint {i} linear: fd {lin:?} vs J {j_lin:?} at q = {q:?}",
                    robot.name
                );
                assert!(
                    (ang - j_ang).norm() < tol_ang,
                    "{} joint {i} angular: fd {ang:?} vs J {j_ang:?} at q = {q:?}",
                    robot.name
                );
                if robot.links[i].kind == JointKind::Prismatic {
                    assert_eq!(j_ang, Vector3::zeros());
                }
            }
        }
    }
}

#[test]
fn scara_matches_seed000_eq1() {
    let robot = preset("scara-rh3frh5515").unwrap();
    assert_eq!(robot.links[2].kind, JointKind::Prismatic);
    let (l1, l2) = (325.0, 225.0);
    let mut rng = StdRng::seed_from_u64(0);
    let mut qs = vec![vec![0.0; 4], robot.home.clone()];
    qs.extend((0..50).map(|_| random_q(&mut rng, &robot.limits)));
    for q in qs {
        let (t1, t2) = (q[0].to_radians(), q[1].to_radians());
        let expected = Vector3::new(
            l1 * t1.cos() + l2 * (t1 + t2).cos(),
            l1 * t1.sin() + l2 * (t1 + t2).sin(),
            q[2],
        );
        let p = robot.position(&q).unwrap();
        assert!(
            (p - expected).amax() < 1e-9,
            "q = {q:?}: {p:?} vs {expected:?}"
        );
        // Tool roll: the TCP orientation is a rotation of θ1+θ2+θ4 about z.
        let yaw =
            UnitQuaternion::from_axis_angle(&Vector3::z_axis(), (q[0] + q[1] + q[3]).to_radians());
        assert!(robot.fk(&q).unwrap().rotation.angle_to(&yaw) < 1e-12);
    }
}

#[test]
fn comau_home_wrist_centre() {
    // q = (0, 0, −90°, 0, 0, 0): upper arm vertical, forearm horizontal forward,
    // so the wrist centre (origin of frame 4) is at
    // (a1 + d4, 0, d1 + a2 + a3) = (400 + 1125.33, 0, 830 + 1175 + 250) mm.
    let robot = preset("comau-nj220").unwrap();
    let q = [0.0, 0.0, -90.0, 0.0, 0.0, 0.0];
    let frames = robot.frames(&q);
    assert_eq!(frames.len(), robot.dof() + 2);
    let wc = frames[4].translation.vector;
    let expected = Vector3::new(400.0 + 1125.33, 0.0, 830.0 + 1175.0 + 250.0);
    assert!((wc - expected).amax() < 1e-9, "wrist centre {wc:?}");
    // Elbow (frame 2 origin) straight above the shoulder, TCP d6 further along x.
    let elbow = frames[2].translation.vector;
    assert!((elbow - Vector3::new(400.0, 0.0, 830.0 + 1175.0)).amax() < 1e-9);
    let tcp = robot.position(&q).unwrap();
    assert!((tcp - expected - Vector3::new(230.0, 0.0, 0.0)).amax() < 1e-9);
    // Negative q2 leans the arm forward (+x), q3 below −90° tilts the forearm down.
    let lean = robot.frames(&[0.0, -10.0, -90.0, 0.0, 0.0, 0.0])[2]
        .translation
        .vector;
    assert!(lean.x > 400.0 + 100.0);
    let tilt = robot.frames(&[0.0, 0.0, -100.0, 0.0, 0.0, 0.0])[4]
        .translation
        .vector;
    assert!(tilt.z < expected.z - 100.0);
}

/// `Robot::with_tool_translation`: the one place a TCP offset replaces a
/// robot's tool (`--tool`, Python's `tool=`): the translation set, the
/// rotation kept, non-finite offsets refused; `load_robot_with_tool` parses
/// `--tool` into it and keeps its own message.
#[test]
fn a_tool_translation_replaces_the_offset_and_keeps_the_rotation() {
    use robokrige::kinematics::{load_robot, load_robot_with_tool};
    let robot = load_robot("ur10").unwrap();
    let moved = robot
        .clone()
        .with_tool_translation([1.5, -2.0, 250.0])
        .unwrap();
    assert_eq!(
        moved.tool.translation.vector.as_slice(),
        &[1.5, -2.0, 250.0]
    );
    assert_eq!(moved.tool.rotation, robot.tool.rotation);
    assert_eq!(
        load_robot_with_tool("ur10", Some("1.5, -2, 250")).unwrap(),
        moved
    );
    let bad = robot
        .with_tool_translation([f64::NAN, 0.0, 1.0])
        .unwrap_err();
    assert_eq!(
        bad.to_string(),
        "invalid parameter: tool (NaN, 0, 1): expected finite x, y, z in mm"
    );
    for t in ["1,2", "1,2,x", "1,2,inf"] {
        let e = load_robot_with_tool("ur10", Some(t))
            .unwrap_err()
            .to_string();
        assert_eq!(
            e,
            format!("invalid parameter: --tool '{t}': expected x,y,z in mm")
        );
    }
}

/// Joints outside the robot's limits are named, with how many rows and
/// the furthest value; a campaign inside them gives none.
#[test]
fn a_campaign_beyond_the_joint_limits_is_named_per_joint() {
    let robot = robokrige::kinematics::preset("comau-nj220").unwrap();
    let path = format!("{}/datasets/comau_lhs.csv", env!("CARGO_MANIFEST_DIR"));
    let mut data = robokrige::dataset::read_csv(path.as_ref())
        .unwrap()
        .head(10);
    assert!(robot.limit_warnings(&data).is_empty());
    let hi = robot.limits[1].1;
    data.q[3][1] = hi + 7.0;
    data.q[5][1] = hi + 30.0;
    let w = robot.limit_warnings(&data);
    assert_eq!(w.len(), 1, "{w:?}");
    assert!(
        w[0].contains("q2 of 2 row(s)") && w[0].contains(&format!("(up to {:.2}°)", hi + 30.0)),
        "{w:?}"
    );
}
