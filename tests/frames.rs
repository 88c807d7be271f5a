//! Tests of `robokrige::frames` against known truth: points are generated on a
//! known plane / circle / rigid motion, the fit must recover it (exactly without
//! noise, within linearised standard errors with noise), and every bad input
//! must return an error, never panic.

use nalgebra::{DMatrix, Matrix3, Rotation3, Unit, UnitQuaternion, Vector3};
use rand::rngs::StdRng;
use rand::{RngExt, SeedableRng};
use rand_distr::{Distribution, Normal};
use robokrige::Error;
use robokrige::frames::{
    Circle3, angle_2d, fit_circle_2d, fit_circle_3d, fit_plane, register, wrap_pi,
};
use std::f64::consts::{FRAC_PI_2, PI};

// ---------- helpers ----------

fn random_unit(rng: &mut StdRng) -> Vector3<f64> {
    loop {
        let v = Vector3::new(
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
            rng.random_range(-1.0..1.0),
        );
        let n = v.norm();
        if n > 0.1 && n < 1.0 {
            return v / n;
        }
    }
}

fn random_rotation(rng: &mut StdRng) -> UnitQuaternion<f64> {
    let axis = Unit::new_normalize(random_unit(rng));
    UnitQuaternion::from_axis_angle(&axis, rng.random_range(-PI..PI))
}

/// Orthonormal (e1, e2) with e1 × e2 = n.
fn basis(n: &Vector3<f64>) -> (Vector3<f64>, Vector3<f64>) {
    let a = if n.x.abs() < 0.9 {
        Vector3::x()
    } else {
        Vector3::y()
    };
    let e1 = (a - n * n.dot(&a)).normalize();
    (e1, n.cross(&e1))
}

fn tilted_axis() -> Vector3<f64> {
    Vector3::new(0.3, -0.5, 0.8).normalize()
}

fn assert_invalid<T: std::fmt::Debug>(r: robokrige::Result<T>, needles: &[&str]) {
    match r {
        Err(Error::InvalidParameter(msg)) => {
            for n in needles {
                assert!(msg.contains(n), "message {msg:?} lacks {n:?}");
            }
        }
        other => panic!("expected InvalidParameter containing {needles:?}, got {other:?}"),
    }
}

/// Linearised standard errors of (Qx, Qy, R) for i.i.d. radial noise σ:
/// Cov = σ² (JᵀJ)⁻¹ with J the geometric-fit Jacobian at the truth.
fn circle_std_errors(angles: &[f64], sigma: f64) -> [f64; 3] {
    let j = DMatrix::from_fn(angles.len(), 3, |r, c| match c {
        0 => -angles[r].cos(),
        1 => -angles[r].sin(),
        _ => -1.0,
    });
    let cov = (j.transpose() * &j).try_inverse().unwrap() * sigma * sigma;
    [cov[(0, 0)].sqrt(), cov[(1, 1)].sqrt(), cov[(2, 2)].sqrt()]
}

// ---------- angles ----------

#[test]
fn wrap_pi_and_angle_2d_values() {
    assert_eq!(wrap_pi(PI), PI);
    assert_eq!(wrap_pi(-PI), PI);
    assert!((wrap_pi(1.5 * PI) + FRAC_PI_2).abs() < 1e-15);
    assert!((wrap_pi(-1.5 * PI) - FRAC_PI_2).abs() < 1e-15);
    assert!((wrap_pi(7.0 * PI) - PI).abs() < 1e-12);
    assert!((wrap_pi(0.25 + 10.0 * PI) - 0.25).abs() < 1e-12);
    assert_eq!(wrap_pi(0.0), 0.0);
    assert!(wrap_pi(f64::NAN).is_nan());
    assert!(wrap_pi(f64::INFINITY).is_nan());
    for k in -50..50 {
        let w = wrap_pi(k as f64 * 0.37);
        assert!(w > -PI && w <= PI);
    }
    assert!((angle_2d([0.0, 2.0]) - FRAC_PI_2).abs() < 1e-15);
    assert!((angle_2d([-1.0, 0.0]) - PI).abs() < 1e-15);
    assert!((angle_2d([1.0, -1.0]) + PI / 4.0).abs() < 1e-15);
}

// ---------- plane ----------

#[test]
fn plane_exact_recovery_tilted() {
    let mut rng = StdRng::seed_from_u64(1);
    let n_true = tilted_axis();
    let c_true = Vector3::new(812.0, -301.5, 455.25);
    let (e1, e2) = basis(&n_true);
    let pts: Vec<Vector3<f64>> = (0..40)
        .map(|_| c_true + e1 * rng.random_range(-400.0..400.0) + e2 * rng.random_range(-50.0..50.0))
        .collect();
    let plane = fit_plane(&pts).unwrap();
    assert!((plane.normal - n_true).norm() < 1e-12, "{:?}", plane.normal);
    assert!(n_true.dot(&(plane.point - c_true)).abs() < 1e-9);
    assert!(plane.rms < 1e-9);
    assert!((plane.normal.norm() - 1.0).abs() < 1e-14);
}

#[test]
fn plane_normal_sign_convention() {
    // Downward-pointing true normal: the fit must report the upward one.
    let n_true = -tilted_axis();
    let (e1, e2) = basis(&n_true);
    let grid: Vec<Vector3<f64>> = (0..5)
        .flat_map(|i| (0..5).map(move |j| (i as f64, j as f64)))
        .map(|(i, j)| e1 * (10.0 * i) + e2 * (7.0 * j))
        .collect();
    let plane = fit_plane(&grid).unwrap();
    assert!((plane.normal + n_true).norm() < 1e-12);
    assert!(plane.normal.z > 0.0);
    // Vertical planes (normal ⟂ z, so the computed z is round-off): then x > 0.
    for k in 0..12 {
        let a = 0.1 + k as f64 * 0.5;
        let n = Vector3::new(a.cos(), a.sin(), 0.0);
        let along = Vector3::new(-a.sin(), a.cos(), 0.0);
        let vert: Vec<Vector3<f64>> = (0..4)
            .flat_map(|i| (0..4).map(move |j| (i as f64, j as f64)))
            .map(|(i, j)| n * 2.5 + along * (13.7 * i) + Vector3::z() * (9.1 * j))
            .collect();
        let plane = fit_plane(&vert).unwrap();
        let expect = if n.x > 0.0 { n } else { -n };
        assert!(
            (plane.normal - expect).norm() < 1e-12,
            "a={a}: {:?}",
            plane.normal
        );
    }
    // Plane y = 3 (normal = ±y): then y > 0.
    let yplane: Vec<Vector3<f64>> = (0..4)
        .flat_map(|i| (0..4).map(move |k| Vector3::new(i as f64, 3.0, k as f64)))
        .collect();
    let plane = fit_plane(&yplane).unwrap();
    assert!((plane.normal - Vector3::y()).norm() < 1e-12);
}

#[test]
fn plane_with_noise_within_bounds() {
    let mut rng = StdRng::seed_from_u64(2);
    let normal = Normal::new(0.0, 0.01).unwrap();
    let n_true = tilted_axis();
    let (e1, e2) = basis(&n_true);
    let pts: Vec<Vector3<f64>> = (0..400)
        .map(|_| {
            e1 * rng.random_range(-500.0..500.0)
                + e2 * rng.random_range(-500.0..500.0)
                + n_true * normal.sample(&mut rng)
        })
        .collect();
    let plane = fit_plane(&pts).unwrap();
    // Tilt standard error ≈ σ / (√N · 289 mm) ≈ 1.7e-6 rad.
    assert!((plane.normal - n_true).norm() < 1e-5, "{:?}", plane.normal);
    assert!((plane.rms - 0.01).abs() < 0.001, "rms {}", plane.rms);
}

// ---------- circle 2D ----------

#[test]
fn circle2_exact_full_circle() {
    let (cx, cy, r) = (120.0, -45.0, 37.5);
    let pts: Vec<[f64; 2]> = (0..12)
        .map(|k| {
            let a = k as f64 * PI / 6.0 + 0.1;
            [cx + r * a.cos(), cy + r * a.sin()]
        })
        .collect();
    let c = fit_circle_2d(&pts).unwrap();
    assert!((c.center[0] - cx).abs() < 1e-10 && (c.center[1] - cy).abs() < 1e-10);
    assert!((c.radius - r).abs() < 1e-10);
    assert!(c.rms < 1e-10);
}

#[test]
fn circle2_three_points_circumcircle() {
    // Right triangle: the circumcentre is the hypotenuse midpoint.
    let c = fit_circle_2d(&[[0.0, 0.0], [6.0, 0.0], [0.0, 8.0]]).unwrap();
    assert!((c.center[0] - 3.0).abs() < 1e-12 && (c.center[1] - 4.0).abs() < 1e-12);
    assert!((c.radius - 5.0).abs() < 1e-12);
}

#[test]
fn circle2_exact_short_arc_30deg() {
    let (cx, cy, r) = (1500.0, -2200.0, 500.0);
    let pts: Vec<[f64; 2]> = (0..31)
        .map(|k| {
            let a = 1.0 + (k as f64).to_radians();
            [cx + r * a.cos(), cy + r * a.sin()]
        })
        .collect();
    let c = fit_circle_2d(&pts).unwrap();
    assert!((c.center[0] - cx).abs() < 1e-8, "{:?}", c.center);
    assert!((c.center[1] - cy).abs() < 1e-8, "{:?}", c.center);
    assert!((c.radius - r).abs() < 1e-8, "{}", c.radius);
    assert!(c.rms < 1e-9);
}

#[test]
fn circle2_short_arc_1um_noise_within_standard_errors() {
    let (cx, cy, r, sigma) = (1500.0, -2200.0, 500.0, 0.001);
    let angles: Vec<f64> = (0..31).map(|k| 1.0 + (k as f64).to_radians()).collect();
    let se = circle_std_errors(&angles, sigma);
    // Short arc: centre and radius are ~10³× less certain than one point.
    assert!(se[2] > 10.0 * sigma);
    let noise = Normal::new(0.0, sigma).unwrap();
    for seed in 0..20 {
        let mut rng = StdRng::seed_from_u64(100 + seed);
        let pts: Vec<[f64; 2]> = angles
            .iter()
            .map(|a| {
                let rr = r + noise.sample(&mut rng);
                [cx + rr * a.cos(), cy + rr * a.sin()]
            })
            .collect();
        let c = fit_circle_2d(&pts).unwrap();
        let err = [c.center[0] - cx, c.center[1] - cy, c.radius - r];
        for k in 0..3 {
            assert!(
                err[k].abs() < 5.0 * se[k],
                "seed {seed}: err {err:?} vs se {se:?}"
            );
        }
        assert!(c.rms < 2.0 * sigma && c.rms > 0.3 * sigma, "rms {}", c.rms);
    }
}

#[test]
fn circle2_is_the_geometric_minimiser() {
    // Eq 10's optimality conditions, checked from the definition: at the
    // minimiser of Σ (d_k − R)², d_k = ‖p_k − Q‖, the gradient vanishes:
    // Σ r_k = 0 and Σ r_k (p_k − Q)/d_k = 0, and no nearby (Q, R) is better.
    // The algebraic (Kåsa) fit alone violates these on a noisy short arc.
    let (cx, cy, r, sigma) = (40.0, 60.0, 500.0, 0.2);
    let noise = Normal::new(0.0, sigma).unwrap();
    let mut rng = StdRng::seed_from_u64(9);
    let pts: Vec<[f64; 2]> = (0..31)
        .map(|k| {
            let a = (k as f64).to_radians();
            let rr = r + noise.sample(&mut rng);
            [cx + rr * a.cos(), cy + rr * a.sin()]
        })
        .collect();
    let c = fit_circle_2d(&pts).unwrap();
    let cost = |q: [f64; 2], rad: f64| -> f64 {
        pts.iter()
            .map(|p| ((p[0] - q[0]).hypot(p[1] - q[1]) - rad).powi(2))
            .sum()
    };
    let (mut g0, mut gx, mut gy) = (0.0, 0.0, 0.0);
    for p in &pts {
        let (dx, dy) = (p[0] - c.center[0], p[1] - c.center[1]);
        let d = dx.hypot(dy);
        let res = d - c.radius;
        g0 += res;
        gx += res * dx / d;
        gy += res * dy / d;
    }
    for g in [g0, gx, gy] {
        assert!(g.abs() < 1e-7, "gradient component {g}");
    }
    let best = cost(c.center, c.radius);
    assert!(best <= cost([cx, cy], r));
    assert!((c.rms - (best / 31.0).sqrt()).abs() < 1e-12);
    for h in [1e-3, -1e-3] {
        assert!(best <= cost([c.center[0] + h, c.center[1]], c.radius));
        assert!(best <= cost([c.center[0], c.center[1] + h], c.radius));
        assert!(best <= cost(c.center, c.radius + h));
    }
}

#[test]
fn circle2_bidirectional_indexing() {
    // Each angle visited twice (up, then down), with a direction-dependent
    // angular deviation (moves points along the circle) and radial noise.
    let (cx, cy, r, sigma) = (-350.0, 720.0, 640.0, 0.005);
    let mut angles = Vec::new();
    let mut rng = StdRng::seed_from_u64(3);
    let noise = Normal::new(0.0, sigma).unwrap();
    let mut pts = Vec::new();
    for (dir, ks) in [
        (1.0, (0..=24).collect::<Vec<i32>>()),
        (-1.0, (0..=24).rev().collect()),
    ] {
        for k in ks {
            let a = (-60.0 + 10.0 * k as f64).to_radians() + dir * 2e-4;
            let rr = r + noise.sample(&mut rng);
            angles.push(a);
            pts.push([cx + rr * a.cos(), cy + rr * a.sin()]);
        }
    }
    let se = circle_std_errors(&angles, sigma);
    let c = fit_circle_2d(&pts).unwrap();
    let err = [c.center[0] - cx, c.center[1] - cy, c.radius - r];
    for k in 0..3 {
        assert!(err[k].abs() < 5.0 * se[k], "err {err:?} vs se {se:?}");
    }
}

// ---------- circle 3D ----------

fn circle3_points(c: Vector3<f64>, n: Vector3<f64>, r: f64, phis: &[f64]) -> Vec<Vector3<f64>> {
    let (e1, e2) = basis(&n);
    phis.iter()
        .map(|p| c + (e1 * p.cos() + e2 * p.sin()) * r)
        .collect()
}

#[test]
fn circle3_tilted_exact_signed_normal_and_angles() {
    let n_true = tilted_axis();
    let c_true = Vector3::new(400.0, -250.0, 900.0);
    let r = 321.0;
    let (e1, _) = basis(&n_true);
    let phis: Vec<f64> = (0..25)
        .map(|k| (-40.0 + 10.0 * k as f64).to_radians())
        .collect();
    let pts = circle3_points(c_true, n_true, r, &phis);

    let c = fit_circle_3d(&pts).unwrap();
    assert!((c.normal - n_true).norm() < 1e-12, "{:?}", c.normal);
    assert!((c.center - c_true).norm() < 1e-9);
    assert!((c.radius - r).abs() < 1e-9);
    assert!(c.rms < 1e-9 && c.plane_rms < 1e-9);
    // x_ref off the plane: only its projection (e1) counts.
    let x_ref = e1 * 2.0 + n_true * 5.0;
    // (Angles compared modulo 2π: φ = 180° may come out as ±π.)
    for (p, phi) in pts.iter().zip(&phis) {
        let a = c.angle_of(p, &x_ref);
        assert!(a > -PI && a <= PI);
        assert!(wrap_pi(a - phi).abs() < 1e-12);
    }

    // Same points in reverse order: the axis flips, angles change sign.
    let rev: Vec<Vector3<f64>> = pts.iter().rev().copied().collect();
    let c = fit_circle_3d(&rev).unwrap();
    assert!((c.normal + n_true).norm() < 1e-12, "{:?}", c.normal);
    assert!((c.center - c_true).norm() < 1e-9);
    for (p, phi) in pts.iter().zip(&phis) {
        assert!(wrap_pi(c.angle_of(p, &x_ref) + phi).abs() < 1e-12);
    }
}

#[test]
fn circle3_bidirectional_sign_is_first_pass() {
    let n_true = Vector3::new(-0.1, 0.2, -0.97).normalize();
    let c_true = Vector3::new(10.0, 20.0, 30.0);
    let noise = Normal::new(0.0, 0.01).unwrap();
    let up: Vec<f64> = (0..=18).map(|k| (10.0 * k as f64).to_radians()).collect();
    let there_back: Vec<f64> = up.iter().chain(up.iter().rev()).copied().collect();
    let back_there: Vec<f64> = up.iter().rev().chain(up.iter()).copied().collect();
    for (seed, (phis, sign)) in [(there_back, 1.0), (back_there, -1.0)]
        .iter()
        .cycle()
        .take(16)
        .enumerate()
    {
        let mut rng = StdRng::seed_from_u64(40 + seed as u64);
        let pts: Vec<Vector3<f64>> = circle3_points(c_true, n_true, 250.0, phis)
            .into_iter()
            .map(|p| {
                p + Vector3::new(
                    noise.sample(&mut rng),
                    noise.sample(&mut rng),
                    noise.sample(&mut rng),
                )
            })
            .collect();
        let c = fit_circle_3d(&pts).unwrap();
        assert!((c.normal - n_true * *sign).norm() < 1e-3, "{:?}", c.normal);
        assert!((c.center - c_true).norm() < 0.05, "{:?}", c.center);
        assert!((c.radius - 250.0).abs() < 0.02, "{}", c.radius);
    }
}

#[test]
fn circle3_full_turn_with_noise() {
    let n_true = tilted_axis();
    let c_true = Vector3::new(-700.0, 150.0, 1200.0);
    let (r, sigma) = (180.0, 0.005);
    let mut rng = StdRng::seed_from_u64(5);
    let noise = Normal::new(0.0, sigma).unwrap();
    let phis: Vec<f64> = (0..72).map(|k| (5.0 * k as f64).to_radians()).collect();
    let pts: Vec<Vector3<f64>> = circle3_points(c_true, n_true, r, &phis)
        .into_iter()
        .map(|p| {
            p + Vector3::new(
                noise.sample(&mut rng),
                noise.sample(&mut rng),
                noise.sample(&mut rng),
            )
        })
        .collect();
    let c = fit_circle_3d(&pts).unwrap();
    // Standard errors: centre ≈ σ√(2/N) ≈ 8e-4, tilt ≈ σ/(R√(N/2)) ≈ 5e-6.
    assert!((c.center - c_true).norm() < 5e-3, "{:?}", c.center - c_true);
    assert!((c.radius - r).abs() < 3e-3, "{}", c.radius);
    assert!((c.normal - n_true).norm() < 3e-5, "{:?}", c.normal);
    assert!((c.rms - sigma).abs() < 0.3 * sigma, "{}", c.rms);
    assert!((c.plane_rms - sigma).abs() < 0.3 * sigma, "{}", c.plane_rms);
}

#[test]
fn circle3_angle_of_degenerate_reference_is_nan() {
    let c = Circle3 {
        center: Vector3::zeros(),
        normal: Vector3::z(),
        radius: 1.0,
        rms: 0.0,
        plane_rms: 0.0,
    };
    assert!(
        c.angle_of(&Vector3::new(1.0, 0.0, 0.0), &Vector3::new(0.0, 0.0, 3.0))
            .is_nan()
    );
    assert!(
        c.angle_of(&Vector3::new(f64::NAN, 0.0, 0.0), &Vector3::x())
            .is_nan()
    );
    assert!((c.angle_of(&Vector3::new(0.0, 2.0, 7.0), &Vector3::x()) - FRAC_PI_2).abs() < 1e-15);
    assert!((c.angle_of(&Vector3::new(-1.0, 0.0, 0.0), &Vector3::x()) - PI).abs() < 1e-15);
}

// ---------- registration ----------

#[test]
fn register_exact_random_transforms() {
    let mut rng = StdRng::seed_from_u64(6);
    for _ in 0..20 {
        let rot = random_rotation(&mut rng);
        let t = Vector3::new(
            rng.random_range(-2000.0..2000.0),
            rng.random_range(-2000.0..2000.0),
            rng.random_range(-2000.0..2000.0),
        );
        let from: Vec<Vector3<f64>> = (0..10)
            .map(|_| {
                Vector3::new(
                    rng.random_range(-1000.0..1000.0),
                    rng.random_range(-1000.0..1000.0),
                    rng.random_range(-1000.0..1000.0),
                )
            })
            .collect();
        let to: Vec<Vector3<f64>> = from.iter().map(|p| rot * p + t).collect();
        let reg = register(&from, &to).unwrap();
        assert!(reg.transform.rotation.angle_to(&rot) < 1e-12);
        assert!((reg.transform.translation.vector - t).norm() < 1e-9);
        assert!(reg.rms < 1e-9 && reg.max < 1e-9);
        assert!(!reg.reflection_guarded);
    }
}

#[test]
fn register_with_noise_within_bounds() {
    let mut rng = StdRng::seed_from_u64(7);
    let sigma = 0.02;
    let noise = Normal::new(0.0, sigma).unwrap();
    let rot = random_rotation(&mut rng);
    let t = Vector3::new(1200.0, -300.0, 450.0);
    let from: Vec<Vector3<f64>> = (0..60)
        .map(|_| {
            Vector3::new(
                rng.random_range(-800.0..800.0),
                rng.random_range(-800.0..800.0),
                rng.random_range(0.0..1200.0),
            )
        })
        .collect();
    let to: Vec<Vector3<f64>> = from
        .iter()
        .map(|p| {
            rot * p
                + t
                + Vector3::new(
                    noise.sample(&mut rng),
                    noise.sample(&mut rng),
                    noise.sample(&mut rng),
                )
        })
        .collect();
    let reg = register(&from, &to).unwrap();
    // Rotation s.e. ≈ σ/(√N · ~500 mm) ≈ 5e-6 rad; translation ≈ σ/√N + lever arm.
    assert!(reg.transform.rotation.angle_to(&rot) < 5e-5);
    assert!((reg.transform.translation.vector - t).norm() < 0.1);
    // Residual distances: rms ≈ σ√3 · √((3N − 6)/(3N)).
    let expect = sigma * 3f64.sqrt() * ((3.0 * 60.0 - 6.0) / 180.0f64).sqrt();
    assert!(
        (reg.rms - expect).abs() < 0.2 * expect,
        "rms {} vs {expect}",
        reg.rms
    );
    assert!(reg.max >= reg.rms && reg.max < 6.0 * sigma);
}

#[test]
fn register_coplanar_points_always_proper_rotation() {
    // Coplanar sets: σ₃ = 0, the unguarded R = VUᵀ is a reflection for about
    // half of the random cases; the guard must always give the true rotation.
    let mut rng = StdRng::seed_from_u64(8);
    let mut guarded = 0;
    for _ in 0..60 {
        let rot = random_rotation(&mut rng);
        let t = Vector3::new(5.0, -7.0, 11.0);
        let from: Vec<Vector3<f64>> = (0..8)
            .map(|_| {
                Vector3::new(
                    rng.random_range(-500.0..500.0),
                    rng.random_range(-500.0..500.0),
                    0.0,
                )
            })
            .collect();
        let to: Vec<Vector3<f64>> = from.iter().map(|p| rot * p + t).collect();
        let reg = register(&from, &to).unwrap();
        let r = reg.transform.rotation.to_rotation_matrix().into_inner();
        assert!((r.determinant() - 1.0).abs() < 1e-12);
        assert!(reg.transform.rotation.angle_to(&rot) < 1e-9);
        assert!((reg.transform.translation.vector - t).norm() < 1e-9);
        assert!(reg.max < 1e-9);
        guarded += reg.reflection_guarded as usize;
    }
    assert!(
        guarded > 0,
        "no coplanar case exercised the reflection guard"
    );
}

#[test]
fn register_mirrored_set_gives_best_proper_rotation() {
    // from: ±a x̂, ±b ŷ, ±c ẑ (covariance diag(a², b², c²), a > b > c);
    // to: mirrored x → −x. H = diag(−2a², 2b², 2c²); the best proper rotation
    // flips the smallest axis: R = diag(−1, 1, −1), t = 0, with residual 2c on
    // the two ±c points.
    let (a, b, c) = (300.0, 200.0, 50.0);
    let from = vec![
        Vector3::new(a, 0.0, 0.0),
        Vector3::new(-a, 0.0, 0.0),
        Vector3::new(0.0, b, 0.0),
        Vector3::new(0.0, -b, 0.0),
        Vector3::new(0.0, 0.0, c),
        Vector3::new(0.0, 0.0, -c),
    ];
    let to: Vec<Vector3<f64>> = from.iter().map(|p| Vector3::new(-p.x, p.y, p.z)).collect();
    let reg = register(&from, &to).unwrap();
    assert!(reg.reflection_guarded);
    let r = reg.transform.rotation.to_rotation_matrix().into_inner();
    assert!((r.determinant() - 1.0).abs() < 1e-12);
    let expect = Matrix3::from_diagonal(&Vector3::new(-1.0, 1.0, -1.0));
    assert!((r - expect).norm() < 1e-12, "{r}");
    assert!(reg.transform.translation.vector.norm() < 1e-12);
    assert!((reg.max - 2.0 * c).abs() < 1e-9);
    assert!((reg.rms - 2.0 * c / 3f64.sqrt()).abs() < 1e-9);
    // And mirrored after a rotation: still a proper rotation, still guarded.
    let rot = Rotation3::from_euler_angles(0.3, -0.2, 1.1);
    let to2: Vec<Vector3<f64>> = to.iter().map(|p| rot * p).collect();
    let reg = register(&from, &to2).unwrap();
    assert!(reg.reflection_guarded);
    let r2 = reg.transform.rotation.to_rotation_matrix().into_inner();
    assert!((r2 - rot.matrix() * expect).norm() < 1e-12);
}

// ---------- bad input ----------

#[test]
fn too_few_points_are_rejected() {
    let p2 = [Vector3::new(0.0, 0.0, 0.0), Vector3::new(1.0, 0.0, 0.0)];
    assert_invalid(
        fit_plane(&p2),
        &["fit_plane", "needs at least 3 points, got 2"],
    );
    assert_invalid(fit_plane(&[]), &["fit_plane", "got 0"]);
    assert_invalid(
        fit_circle_3d(&p2),
        &["fit_circle_3d", "needs at least 3 points, got 2"],
    );
    assert_invalid(
        fit_circle_2d(&[[0.0, 0.0], [1.0, 1.0]]),
        &["fit_circle_2d", "needs at least 3 points, got 2"],
    );
    assert_invalid(fit_circle_2d(&[]), &["fit_circle_2d", "got 0"]);
    assert_invalid(
        register(&p2, &p2),
        &["register", "needs at least 3 points, got 2"],
    );
    assert_invalid(register(&[], &[]), &["register", "got 0"]);
}

#[test]
fn non_finite_values_are_rejected() {
    let good = [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(1.0, 1.0, 0.2),
    ];
    for bad_val in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut bad = good;
        bad[2].y = bad_val;
        assert_invalid(fit_plane(&bad), &["fit_plane", "point 2", "non-finite"]);
        assert_invalid(
            fit_circle_3d(&bad),
            &["fit_circle_3d", "point 2", "non-finite"],
        );
        assert_invalid(
            register(&bad, &good),
            &["register", "`from` point 2", "non-finite"],
        );
        assert_invalid(
            register(&good, &bad),
            &["register", "`to` point 2", "non-finite"],
        );
        let mut bad2 = [[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]];
        bad2[1][0] = bad_val;
        assert_invalid(
            fit_circle_2d(&bad2),
            &["fit_circle_2d", "point 1", "non-finite"],
        );
    }
}

#[test]
fn collinear_and_coincident_points_are_rejected() {
    let d = Vector3::new(0.3, -0.4, 0.5);
    let line: Vec<Vector3<f64>> = (0..6)
        .map(|k| Vector3::new(10.0, 20.0, 30.0) + d * (k as f64 * 17.0))
        .collect();
    assert_invalid(fit_plane(&line), &["fit_plane", "collinear"]);
    assert_invalid(fit_circle_3d(&line), &["fit_circle_3d", "collinear"]);
    let same = vec![Vector3::new(1.0, 2.0, 3.0); 5];
    assert_invalid(fit_plane(&same), &["fit_plane", "collinear or coincident"]);
    let line2: Vec<[f64; 2]> = (0..5)
        .map(|k| [1.0 + 2.0 * k as f64, -3.0 + 0.5 * k as f64])
        .collect();
    assert_invalid(fit_circle_2d(&line2), &["fit_circle_2d", "collinear"]);
    assert_invalid(
        fit_circle_2d(&[[1.0, 1.0], [1.0, 1.0], [1.0, 1.0]]),
        &["fit_circle_2d", "coincident"],
    );
    // Two distinct points, one repeated: collinear.
    assert_invalid(
        fit_circle_2d(&[[0.0, 0.0], [1.0, 0.0], [1.0, 0.0]]),
        &["fit_circle_2d", "collinear"],
    );

    let tri = vec![
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(1.0, 0.0, 0.0),
        Vector3::new(0.0, 1.0, 0.0),
        Vector3::new(0.0, 0.0, 1.0),
        Vector3::new(1.0, 1.0, 1.0),
        Vector3::new(2.0, 0.5, 0.0),
    ];
    assert_invalid(
        register(&line, &tri),
        &["register", "`from` points are collinear"],
    );
    assert_invalid(
        register(&tri, &line),
        &["register", "`to` points are collinear"],
    );
}

#[test]
fn mismatched_lengths_are_rejected() {
    let a: Vec<Vector3<f64>> = (0..4)
        .map(|k| Vector3::new(k as f64, (k * k) as f64, 1.0))
        .collect();
    assert_invalid(register(&a, &a[..3]), &["register", "4", "3", "length"]);
    assert_invalid(register(&a[..2], &a), &["register", "length"]);
}
