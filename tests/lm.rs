//! Levenberg–Marquardt: convergence on classic problems, scaling, rank
//! deficiency (frozen parameters), non-finite trial points, the numerical
//! Jacobian and the error cases.

use nalgebra::{DMatrix, DVector};
use robokrige::Error;
use robokrige::optim::{LmOptions, LmStop, levenberg_marquardt, numerical_jacobian};

type Rj = robokrige::Result<(DVector<f64>, DMatrix<f64>)>;

fn assert_invalid<T: std::fmt::Debug>(r: robokrige::Result<T>, prefix: &str) {
    match r {
        Err(Error::InvalidParameter(msg)) => {
            assert!(msg.starts_with(prefix), "message {msg:?}")
        }
        other => panic!("expected InvalidParameter, got {other:?}"),
    }
}

fn rosenbrock(x: &[f64]) -> Rj {
    let r = DVector::from_vec(vec![10.0 * (x[1] - x[0] * x[0]), 1.0 - x[0]]);
    let j = DMatrix::from_row_slice(2, 2, &[-20.0 * x[0], 10.0, -1.0, 0.0]);
    Ok((r, j))
}

#[test]
fn rosenbrock_converges_from_the_classic_start() {
    let res = levenberg_marquardt(rosenbrock, &[-1.2, 1.0], &LmOptions::default()).unwrap();
    assert!(
        (res.x[0] - 1.0).abs() < 1e-10 && (res.x[1] - 1.0).abs() < 1e-10,
        "{res:?}"
    );
    assert!(res.cost < 1e-20, "{res:?}");
    assert_ne!(res.stop, LmStop::MaxIterations, "{res:?}");
    assert_eq!(res.evaluations, res.iterations + 1);
    assert_eq!(res.rank, 2);
    assert!(res.unidentifiable.is_empty());
    // zero residual → zero standard errors
    assert!(res.std_errors.iter().all(|s| s.is_finite() && *s < 1e-9));
}

/// y = a·exp(−b t) + c, noise-free.
fn exp_data() -> (Vec<f64>, Vec<f64>, [f64; 3]) {
    let truth = [5.0, 0.3, 1.0];
    let t: Vec<f64> = (0..40).map(|i| i as f64 * 0.25).collect();
    let y = t
        .iter()
        .map(|t| truth[0] * (-truth[1] * t).exp() + truth[2])
        .collect();
    (t, y, truth)
}

#[test]
fn exponential_fit_recovers_the_parameters() {
    let (t, y, truth) = exp_data();
    let f = |p: &[f64]| -> Rj {
        let m = t.len();
        let r = DVector::from_fn(m, |i, _| p[0] * (-p[1] * t[i]).exp() + p[2] - y[i]);
        let j = DMatrix::from_fn(m, 3, |i, c| {
            let e = (-p[1] * t[i]).exp();
            match c {
                0 => e,
                1 => -p[0] * t[i] * e,
                _ => 1.0,
            }
        });
        Ok((r, j))
    };
    let res = levenberg_marquardt(f, &[1.0, 1.0, 0.0], &LmOptions::default()).unwrap();
    for (a, b) in res.x.iter().zip(&truth) {
        assert!((a - b).abs() < 1e-8, "{res:?}");
    }
    assert!(res.rms < 1e-10, "{res:?}");
    assert_ne!(res.stop, LmStop::MaxIterations);
    assert_eq!(res.rank, 3);
}

#[test]
fn exponential_fit_with_noise_gives_sensible_standard_errors() {
    let (t, mut y, truth) = exp_data();
    // deterministic ±0.01 "noise"
    for (i, v) in y.iter_mut().enumerate() {
        *v += 0.01 * if (i * 7 + 3) % 5 < 2 { 1.0 } else { -1.0 };
    }
    let f = |p: &[f64]| -> Rj {
        let m = t.len();
        let r = DVector::from_fn(m, |i, _| p[0] * (-p[1] * t[i]).exp() + p[2] - y[i]);
        let j = numerical_jacobian(
            |q: &[f64]| {
                Ok(DVector::from_fn(m, |i, _| {
                    q[0] * (-q[1] * t[i]).exp() + q[2]
                }))
            },
            p,
            &[1e-6; 3],
        )?;
        Ok((r, j))
    };
    let res = levenberg_marquardt(f, &[1.0, 1.0, 0.0], &LmOptions::default()).unwrap();
    assert!((res.rms - 0.01).abs() < 0.002, "{res:?}");
    for ((a, b), s) in res.x.iter().zip(&truth).zip(&res.std_errors) {
        assert!(s.is_finite() && *s > 0.0 && *s < 0.05, "{res:?}");
        assert!((a - b).abs() < 6.0 * s, "{res:?}");
    }
    // at the optimum the gradient Jᵀr vanishes: a perturbation raises the cost
    let cost_at = |p: &[f64]| {
        0.5 * t
            .iter()
            .zip(&y)
            .map(|(t, y)| (p[0] * (-p[1] * t).exp() + p[2] - y).powi(2))
            .sum::<f64>()
    };
    for k in 0..3 {
        for s in [-1e-4, 1e-4] {
            let mut p = res.x.clone();
            p[k] += s;
            assert!(cost_at(&p) > res.cost, "param {k} step {s}");
        }
    }
}

/// Linear residual r = A x − b where columns 0 and 1 of A are identical.
#[test]
fn duplicate_columns_freeze_one_parameter_and_give_the_other_the_full_effect() {
    let m = 30;
    let a = DMatrix::from_fn(m, 3, |i, c| {
        let t = i as f64 / m as f64;
        match c {
            0 | 1 => 1.0 + t,
            _ => (3.0 * t).sin(),
        }
    });
    // b = A·(s, 0, w) + a component orthogonal to nothing in particular
    let (s_true, w_true) = (3.0, -1.5);
    let b = DVector::from_fn(m, |i, _| {
        let t = i as f64 / m as f64;
        s_true * (1.0 + t) + w_true * (3.0 * t).sin() + 0.05 * (17.0 * t).cos()
    });
    let a2 = a.clone();
    let b2 = b.clone();
    let f = move |x: &[f64]| -> Rj { Ok((&a2 * DVector::from_column_slice(x) - &b2, a2.clone())) };
    let x0 = [0.5, 0.25, 0.0];
    let res = levenberg_marquardt(f, &x0, &LmOptions::default()).unwrap();
    assert_eq!(res.unidentifiable.len(), 1, "{res:?}");
    let frozen = res.unidentifiable[0];
    assert!(frozen == 0 || frozen == 1);
    // documented rule: of identical columns the later one is frozen
    assert_eq!(frozen, 1);
    let kept = 1 - frozen;
    assert_eq!(res.x[frozen], x0[frozen], "frozen parameter must not move");
    // reference least-squares solution with the two columns merged
    let a_red = DMatrix::from_fn(m, 2, |i, c| a[(i, if c == 0 { 0 } else { 2 })]);
    let sol = a_red.clone().svd(true, true).solve(&b, 1e-14).unwrap();
    assert!(
        (res.x[kept] + res.x[frozen] - sol[0]).abs() < 1e-9,
        "{res:?} vs {sol}"
    );
    assert!((res.x[2] - sol[1]).abs() < 1e-9, "{res:?} vs {sol}");
    let best_cost = 0.5 * (&a_red * &sol - &b).norm_squared();
    assert!((res.cost - best_cost).abs() <= 1e-12 * best_cost.max(1.0));
    assert!(
        res.cost > 1e-4,
        "the problem has a non-zero optimal residual"
    );
    assert_eq!(res.rank, 2);
    assert_eq!(res.std_errors[frozen], f64::INFINITY);
    assert!(res.std_errors[kept].is_finite() && res.std_errors[2].is_finite());
}

/// Planar two-link arm with a base pose (bx, by, base angle) and per-joint
/// offset and length: the base angle and the first joint offset are the same
/// rotation, so one is frozen; the rest are recovered exactly.
#[test]
fn calibration_like_problem_with_a_redundant_offset() {
    // parameters: [bx, by, base_angle, off1, l1, off2, l2]
    let truth = [2.0, -1.0, 0.01, 0.02, 400.0, -0.015, 300.5];
    let nominal = [0.0, 0.0, 0.0, 0.0, 400.2, 0.0, 300.0];
    let poses: Vec<(f64, f64)> = (0..25)
        .map(|i| {
            let i = i as f64;
            (-1.5 + 0.12 * i, 2.0 * (0.7 * i).sin())
        })
        .collect();
    let fk = |p: &[f64], q: (f64, f64)| {
        let a1 = p[2] + q.0 + p[3];
        let a2 = a1 + q.1 + p[5];
        [
            p[0] + p[4] * a1.cos() + p[6] * a2.cos(),
            p[1] + p[4] * a1.sin() + p[6] * a2.sin(),
        ]
    };
    let measured: Vec<[f64; 2]> = poses.iter().map(|&q| fk(&truth, q)).collect();
    let resid = |p: &[f64]| -> robokrige::Result<DVector<f64>> {
        let mut r = Vec::with_capacity(2 * poses.len());
        for (q, m) in poses.iter().zip(&measured) {
            let e = fk(p, *q);
            r.push(e[0] - m[0]);
            r.push(e[1] - m[1]);
        }
        Ok(DVector::from_vec(r))
    };
    let f = |p: &[f64]| -> Rj { Ok((resid(p)?, numerical_jacobian(resid, p, &[1e-6; 7])?)) };
    let res = levenberg_marquardt(f, &nominal, &LmOptions::default()).unwrap();
    assert_eq!(res.unidentifiable, vec![3], "{res:?}");
    assert_eq!(res.rank, 6);
    assert_eq!(res.x[3], nominal[3]);
    // the frozen offset's effect goes to the base angle
    assert!((res.x[2] - (truth[2] + truth[3])).abs() < 1e-9, "{res:?}");
    for k in [0, 1, 4, 5, 6] {
        assert!((res.x[k] - truth[k]).abs() < 1e-7, "param {k}: {res:?}");
    }
    assert!(res.rms < 1e-8, "{res:?}");
}

#[test]
fn badly_scaled_parameters_converge() {
    // y = A·exp(−k t) + c with A ~ 1e3, k ~ 1e-3, t up to 2000
    let truth = [2000.0, 0.002, 0.5];
    let t: Vec<f64> = (0..50).map(|i| i as f64 * 40.0).collect();
    let y: Vec<f64> = t
        .iter()
        .map(|t| truth[0] * (-truth[1] * t).exp() + truth[2])
        .collect();
    let f = |p: &[f64]| -> Rj {
        let m = t.len();
        let r = DVector::from_fn(m, |i, _| p[0] * (-p[1] * t[i]).exp() + p[2] - y[i]);
        let j = DMatrix::from_fn(m, 3, |i, c| {
            let e = (-p[1] * t[i]).exp();
            match c {
                0 => e,
                1 => -p[0] * t[i] * e,
                _ => 1.0,
            }
        });
        Ok((r, j))
    };
    let res = levenberg_marquardt(f, &[1000.0, 0.001, 0.0], &LmOptions::default()).unwrap();
    for (a, b) in res.x.iter().zip(&truth) {
        assert!((a - b).abs() <= 1e-9 * b.abs().max(1.0), "{res:?}");
    }
    assert!(res.iterations < 50, "{res:?}");
    assert_ne!(res.stop, LmStop::MaxIterations);
}

#[test]
fn non_finite_trial_points_are_rejected_steps() {
    // r = sqrt(x) − 3: the Gauss–Newton step from x = 100 lands at x = −40,
    // where the residual is NaN
    let mut nan_points = 0;
    let f = |x: &[f64]| -> Rj {
        if x[0] < 0.0 {
            nan_points += 1;
        }
        Ok((
            DVector::from_element(1, x[0].sqrt() - 3.0),
            DMatrix::from_element(1, 1, 0.5 / x[0].sqrt()),
        ))
    };
    let res = levenberg_marquardt(f, &[100.0], &LmOptions::default()).unwrap();
    assert!((res.x[0] - 9.0).abs() < 1e-9, "{res:?}");
    assert!(
        nan_points >= 1,
        "the first trial should have been infeasible"
    );
}

#[test]
fn max_iterations_is_reported() {
    let opts = LmOptions {
        max_iter: 3,
        ..LmOptions::default()
    };
    let res = levenberg_marquardt(rosenbrock, &[-1.2, 1.0], &opts).unwrap();
    assert_eq!(res.stop, LmStop::MaxIterations);
    assert_eq!(res.iterations, 3);
    assert_eq!(res.evaluations, 4);
    // a starting point that is already optimal stops on the gradient at once
    let res = levenberg_marquardt(rosenbrock, &[1.0, 1.0], &LmOptions::default()).unwrap();
    assert_eq!(res.stop, LmStop::SmallGradient);
    assert_eq!((res.iterations, res.evaluations), (0, 1));
}

#[test]
fn numerical_jacobian_matches_analytic() {
    let f = |x: &[f64]| -> robokrige::Result<DVector<f64>> {
        Ok(DVector::from_vec(vec![
            x[0].sin() * x[1],
            (x[0] * x[2]).exp(),
            x[1] * x[1] * x[2] + 1000.0 * x[0],
            (1e-3 * x[2]).cos(),
        ]))
    };
    let x: [f64; 3] = [0.3, -1.2, 0.7];
    let analytic = DMatrix::from_row_slice(
        4,
        3,
        &[
            x[0].cos() * x[1],
            x[0].sin(),
            0.0,
            x[2] * (x[0] * x[2]).exp(),
            0.0,
            x[0] * (x[0] * x[2]).exp(),
            1000.0,
            2.0 * x[1] * x[2],
            x[1] * x[1],
            0.0,
            0.0,
            -1e-3 * (1e-3 * x[2]).sin(),
        ],
    );
    let num = numerical_jacobian(f, &x, &[1e-5, 1e-5, 1e-4]).unwrap();
    assert_eq!(num.shape(), (4, 3));
    let err = (&num - &analytic).amax();
    assert!(err < 1e-6, "max error {err}\n{num}\n{analytic}");
    // and it is usable as the Jacobian for LM (Rosenbrock)
    let rosen_r = |x: &[f64]| -> robokrige::Result<DVector<f64>> {
        Ok(DVector::from_vec(vec![
            10.0 * (x[1] - x[0] * x[0]),
            1.0 - x[0],
        ]))
    };
    let g = |x: &[f64]| -> Rj { Ok((rosen_r(x)?, numerical_jacobian(rosen_r, x, &[1e-7; 2])?)) };
    let res = levenberg_marquardt(g, &[-1.2, 1.0], &LmOptions::default()).unwrap();
    assert!((res.x[0] - 1.0).abs() < 1e-8 && (res.x[1] - 1.0).abs() < 1e-8);
}

#[test]
fn numerical_jacobian_errors() {
    let f = |x: &[f64]| -> robokrige::Result<DVector<f64>> { Ok(DVector::from_row_slice(x)) };
    assert_invalid(
        numerical_jacobian(f, &[1.0, 2.0], &[1e-6]),
        "numerical_jacobian:",
    );
    assert_invalid(
        numerical_jacobian(f, &[1.0, 2.0], &[1e-6, 0.0]),
        "numerical_jacobian:",
    );
    assert_invalid(
        numerical_jacobian(f, &[1.0], &[f64::NAN]),
        "numerical_jacobian:",
    );
    let mut calls = 0;
    let varying = |_: &[f64]| -> robokrige::Result<DVector<f64>> {
        calls += 1;
        Ok(DVector::zeros(calls))
    };
    assert_invalid(
        numerical_jacobian(varying, &[1.0, 2.0], &[1e-6, 1e-6]),
        "numerical_jacobian:",
    );
    // errors of f are passed on
    let failing =
        |_: &[f64]| -> robokrige::Result<DVector<f64>> { Err(Error::Numerical("boom".into())) };
    assert!(matches!(
        numerical_jacobian(failing, &[1.0], &[1e-6]),
        Err(Error::Numerical(_))
    ));
}

#[test]
fn levenberg_marquardt_errors() {
    const P: &str = "levenberg_marquardt:";
    let o = LmOptions::default();
    // empty x0
    assert_invalid(levenberg_marquardt(rosenbrock, &[], &o), P);
    // non-finite residual at x0
    let nan_at_start = |x: &[f64]| -> Rj {
        Ok((
            DVector::from_element(2, (x[0] - 1.0).sqrt()),
            DMatrix::from_element(2, 1, 1.0),
        ))
    };
    assert_invalid(levenberg_marquardt(nan_at_start, &[0.0], &o), P);
    // Jacobian with the wrong number of rows
    let bad_rows = |x: &[f64]| -> Rj {
        Ok((
            DVector::from_element(3, x[0]),
            DMatrix::from_element(2, 1, 1.0),
        ))
    };
    assert_invalid(levenberg_marquardt(bad_rows, &[1.0], &o), P);
    // Jacobian with the wrong number of columns
    let bad_cols = |x: &[f64]| -> Rj {
        Ok((
            DVector::from_element(3, x[0]),
            DMatrix::from_element(3, 2, 1.0),
        ))
    };
    assert_invalid(levenberg_marquardt(bad_cols, &[1.0], &o), P);
    // residual length changing at a trial point
    let mut calls = 0;
    let changing = |x: &[f64]| -> Rj {
        calls += 1;
        let m = if calls == 1 { 2 } else { 3 };
        Ok((
            DVector::from_element(m, x[0] - 5.0),
            DMatrix::from_element(m, 1, 1.0),
        ))
    };
    assert_invalid(levenberg_marquardt(changing, &[1.0], &o), P);
    // empty residual
    let empty = |_: &[f64]| -> Rj { Ok((DVector::zeros(0), DMatrix::zeros(0, 1))) };
    assert_invalid(levenberg_marquardt(empty, &[1.0], &o), P);
    // invalid options
    for bad in [
        LmOptions { lambda0: 0.0, ..o },
        LmOptions {
            tol_step: f64::NAN,
            ..o
        },
        LmOptions { rank_tol: 1.0, ..o },
    ] {
        assert_invalid(levenberg_marquardt(rosenbrock, &[-1.2, 1.0], &bad), P);
    }
    // errors of the closure are passed on
    let failing = |_: &[f64]| -> Rj { Err(Error::Numerical("boom".into())) };
    assert!(matches!(
        levenberg_marquardt(failing, &[1.0], &o),
        Err(Error::Numerical(_))
    ));
}

/// Rosenbrock as a `LeastSquares` problem that counts its Jacobians.
struct CountedRosenbrock {
    jacobians: usize,
}

impl robokrige::optim::LeastSquares for CountedRosenbrock {
    fn residual(&mut self, x: &[f64]) -> robokrige::Result<DVector<f64>> {
        Ok(rosenbrock(x)?.0)
    }

    fn jacobian(&mut self, x: &[f64]) -> robokrige::Result<DMatrix<f64>> {
        self.jacobians += 1;
        Ok(rosenbrock(x)?.1)
    }
}

#[test]
fn a_least_squares_problem_takes_the_same_steps_with_jacobians_only_where_accepted() {
    // a start far away and little damping, so that some trials are rejected
    let opts = LmOptions {
        lambda0: 1e-6,
        ..LmOptions::default()
    };
    let x0 = [-3.0, -4.0];
    let together = levenberg_marquardt(rosenbrock, &x0, &opts).unwrap();
    let mut problem = CountedRosenbrock { jacobians: 0 };
    let apart = robokrige::optim::levenberg_marquardt_on(&mut problem, &x0, &opts).unwrap();
    assert_eq!(apart.x, together.x);
    assert_eq!(apart.cost.to_bits(), together.cost.to_bits());
    assert_eq!(apart.evaluations, together.evaluations);
    assert_eq!(apart.stop, together.stop);
    assert!(
        problem.jacobians < together.evaluations,
        "{} Jacobians for {} evaluations",
        problem.jacobians,
        together.evaluations
    );
}
