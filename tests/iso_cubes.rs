//! The ISO 9283 cube campaign generator (`sim::iso_cubes`): poses inside
//! their cubes, the ISO points where the standard puts them, the branch
//! varied so that joints span more than half a turn, deterministic for a
//! seed, and bad specs refused as values.

use robokrige::kinematics::{Robot, load_robot};
use robokrige::sim::iso_cubes::{ISO_POINTS, IsoCubeSpec, iso_cubes, iso_points, measure_cubes};
use robokrige::sim::{ErrorProfile, TrueRobot};

fn ur10() -> Robot {
    let mut r = load_robot("ur10").unwrap();
    r.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    r
}

#[test]
fn iso_points_sit_on_the_diagonal_plane_inset_from_its_corners() {
    let e = 300.0;
    let p = iso_points(e);
    assert_eq!(p[0].norm(), 0.0);
    // the plane through the edges y = z = ∓e/2: y = z for every point
    let diagonal = (e * e + 2.0 * e * e).sqrt();
    let corner = nalgebra::Vector3::new(-0.5 * e, -0.5 * e, -0.5 * e);
    assert!(((p[1] - corner).norm() - 0.1 * diagonal).abs() < 1e-9);
    for q in &p[1..] {
        assert!((q.y - q.z).abs() < 1e-12);
        assert!((q.norm() - 0.4 * diagonal).abs() < 1e-9);
    }
}

#[test]
fn ur10_cubes_hold_their_poses_and_vary_the_branch() {
    let robot = ur10();
    let spec = IsoCubeSpec::new(4, 300.0, 20).with_branches(&robot, &[2, 4]);
    let c = iso_cubes(&robot, &spec, 5).unwrap();
    assert_eq!(c.len(), 80);
    assert_eq!(c, iso_cubes(&robot, &spec, 5).unwrap(), "deterministic");
    assert_ne!(c.q, iso_cubes(&robot, &spec, 6).unwrap().q);
    for (i, q) in c.q.iter().enumerate() {
        let p = robot.position(q).unwrap();
        let centre = nalgebra::Vector3::from(c.centres_mm[c.cube[i]]);
        let d = p - centre;
        // inside the cube (IK tolerance aside)
        assert!(d.amax() <= 150.0 + 1e-4, "pose {i}: {d:?}");
        if c.iso_point[i] == Some(1) {
            assert!(d.norm() < 1e-4);
        }
    }
    for k in 0..4 {
        assert_eq!(c.rows_of(k).len(), 20);
        let iso = c
            .rows_of(k)
            .iter()
            .filter(|&&i| c.iso_point[i].is_some())
            .count();
        assert_eq!(iso, ISO_POINTS);
    }
    let wide = c.joint_spans().iter().filter(|&&s| s > 180.0).count();
    assert!(wide >= 3, "spans {:?}", c.joint_spans());
    let truth = TrueRobot::draw(&robot, &ErrorProfile::for_robot(&robot), 5);
    let data = measure_cubes(&truth, c.q.clone(), 5).unwrap();
    assert_eq!(data.len(), 80);
    let e = data.errors.as_ref().unwrap();
    assert!(
        e.iter()
            .all(|v| v.iter().all(|x| x.is_finite() && x.abs() < 20.0))
    );
}

#[test]
fn other_robots_get_cubes_too() {
    let comau = load_robot("comau-nj220").unwrap();
    let spec = IsoCubeSpec {
        ranges: Some(vec![
            (-90.0, 90.0),
            (-40.0, 20.0),
            (-150.0, -90.0),
            (-90.0, 90.0),
            (-60.0, 60.0),
            (-90.0, 90.0),
        ]),
        ..IsoCubeSpec::new(3, 400.0, 10).with_branches(&comau, &[4])
    };
    assert_eq!(iso_cubes(&comau, &spec, 1).unwrap().len(), 30);
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/examples/robots/abb-irb2600.toml"
    );
    let abb = load_robot(path).unwrap();
    let c = iso_cubes(&abb, &IsoCubeSpec::new(3, 200.0, 8), 2).unwrap();
    assert_eq!(c.len(), 24);
}

#[test]
fn bad_specs_are_errors() {
    let robot = ur10();
    let bad = [
        IsoCubeSpec::new(0, 300.0, 10),
        IsoCubeSpec::new(3, f64::NAN, 10),
        IsoCubeSpec::new(3, 300.0, 4),
        IsoCubeSpec {
            flip_joints: vec![6],
            ..IsoCubeSpec::new(3, 300.0, 10)
        },
        IsoCubeSpec {
            ranges: Some(vec![(0.0, 1.0)]),
            ..IsoCubeSpec::new(3, 300.0, 10)
        },
        // a cube far larger than the robot's reach cannot be placed
        IsoCubeSpec {
            max_attempts: 3,
            ..IsoCubeSpec::new(1, 5000.0, 10)
        },
    ];
    for spec in bad {
        assert!(iso_cubes(&robot, &spec, 1).is_err(), "{spec:?}");
    }
    let truth = TrueRobot::draw(&robot, &ErrorProfile::for_robot(&robot), 1);
    assert!(measure_cubes(&truth, vec![vec![0.0; 5]], 1).is_err());
}
