//! Property tests (proptest) of kinematics round trips and Kriging
//! invariants, ill-conditioned inputs, and thread-count determinism.

mod common;

use proptest::prelude::*;
use robokrige::dataset::read_csv;
use robokrige::kinematics::{self, IkOptions, IkTarget};
use robokrige::kriging::{KrigingOptions, OptimizerKind, TrendKind};
use robokrige::model::ErrorModel;
use robokrige::space::Space;
use std::path::Path;

fn config() -> ProptestConfig {
    ProptestConfig {
        cases: 24,
        ..ProptestConfig::default()
    }
}

/// m points in [-1, 1]^d from a flat vector of draws.
fn points(flat: &[f64], d: usize) -> Vec<Vec<f64>> {
    flat.chunks(d).map(|c| c.to_vec()).collect()
}

fn fit(x: &[Vec<f64>], y: &[f64], theta: f64) -> robokrige::kriging::KrigingModel {
    let d = x[0].len();
    common::fit_at(
        x,
        y,
        &TrendKind::Constant.trend(d),
        &vec![theta; d],
        0.0,
        None,
    )
    .unwrap()
}

proptest! {
    #![proptest_config(config())]

    #[test]
    fn ik_recovers_every_pose_from_a_nearby_seed(
        u in prop::collection::vec(0.0f64..1.0, 6),
        nudge in prop::collection::vec(-3.0f64..3.0, 6),
    ) {
        let r = kinematics::preset("comau-nj220").unwrap();
        let q: Vec<f64> = r.work_ranges.iter().zip(&u).map(|((lo, hi), t)| lo + (hi - lo) * t).collect();
        let target = r.fk(&q).unwrap();
        let seed: Vec<f64> = q.iter().zip(&nudge).map(|(a, b)| a + b).collect();
        let sol = r.ik(&IkTarget::pose(&target), &seed, &IkOptions::default()).unwrap();
        let got = r.fk(&sol).unwrap();
        prop_assert!((got.translation.vector - target.translation.vector).norm() < 1e-6);
        prop_assert!(got.rotation.angle_to(&target.rotation) < 1e-9);
    }

    #[test]
    fn kriging_interpolates_its_training_points(
        flat in prop::collection::vec(-1.0f64..1.0, 60),
        y in prop::collection::vec(-2.0f64..2.0, 20),
        theta in 0.3f64..5.0,
    ) {
        let x = points(&flat, 3);
        let m = fit(&x, &y, theta);
        for (p, yi) in m.predict(&x).unwrap().iter().zip(&y) {
            prop_assert!((p.mean - yi).abs() < 1e-6, "{} vs {}", p.mean, yi);
            prop_assert!(p.mse >= 0.0 && p.mse < 1e-6);
        }
    }

    #[test]
    fn kriging_ignores_row_order_and_follows_affine_maps_of_y(
        flat in prop::collection::vec(-1.0f64..1.0, 60),
        y in prop::collection::vec(-2.0f64..2.0, 20),
        probe in prop::collection::vec(-1.0f64..1.0, 3),
        scale in 1e-6f64..1e3,
        shift in -5.0f64..5.0,
    ) {
        let x = points(&flat, 3);
        let base = fit(&x, &y, 1.0).predict(std::slice::from_ref(&probe)).unwrap()[0];
        let rev_x: Vec<Vec<f64>> = x.iter().rev().cloned().collect();
        let rev_y: Vec<f64> = y.iter().rev().copied().collect();
        let rev = fit(&rev_x, &rev_y, 1.0).predict(std::slice::from_ref(&probe)).unwrap()[0];
        prop_assert!((rev.mean - base.mean).abs() < 1e-8 * (1.0 + base.mean.abs()));
        let ay: Vec<f64> = y.iter().map(|v| scale * v + shift).collect();
        let aff = fit(&x, &ay, 1.0).predict(std::slice::from_ref(&probe)).unwrap()[0];
        let want = scale * base.mean + shift;
        prop_assert!((aff.mean - want).abs() < 1e-7 * (scale + shift.abs() + 1.0), "{} vs {want}", aff.mean);
        prop_assert!((aff.mse - scale * scale * base.mse).abs() <= 1e-6 * scale * scale * (base.mse + 1e-12));
    }
}

#[test]
fn nearly_coincident_points_and_extreme_correlation_lengths_stay_finite() {
    let mut x: Vec<Vec<f64>> = (0..15)
        .map(|i| vec![(i as f64 * 0.7).sin(), (i as f64 * 1.3).cos()])
        .collect();
    x.push(vec![x[3][0] + 1e-12, x[3][1]]); // a near-duplicate row
    let y: Vec<f64> = x.iter().map(|r| r[0] * r[0] - r[1]).collect();
    let probe = vec![vec![0.1, 0.2], vec![5.0, -5.0]];
    let dace = (10.0 + x.len() as f64) * f64::EPSILON;
    for theta in [1e-6, 1e-2, 1.0, 1e2] {
        let m = fit(&x, &y, theta);
        assert!(m.data().jitter() >= dace);

        for p in m.predict(&probe).unwrap() {
            assert!(
                p.mean.is_finite() && p.mse.is_finite() && p.mse >= 0.0,
                "θ {theta}: {p:?}"
            );
        }
    }
}

fn quick() -> KrigingOptions {
    KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(150)
        .starts(2)
}

#[test]
fn micrometre_scale_outputs_fit_like_millimetre_ones() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/comau_lhs.csv");
    let data = read_csv(&path)
        .unwrap()
        .select(&(0..120).collect::<Vec<_>>());
    let mut tiny = data.clone();
    for e in tiny.errors.as_mut().unwrap() {
        for v in e.iter_mut() {
            *v *= 1e-6;
        }
    }
    let a = ErrorModel::fit(&data, Space::Ejs, &quick()).unwrap();
    let b = ErrorModel::fit(&tiny, Space::Ejs, &quick()).unwrap();
    let (pa, pb) = (
        a.predict_dataset(&data).unwrap(),
        b.predict_dataset(&data).unwrap(),
    );
    for (u, v) in pa.mean.iter().flatten().zip(pb.mean.iter().flatten()) {
        assert!(
            (u * 1e-6 - v).abs() < 1e-9 * (u.abs() * 1e-6 + 1e-9),
            "{u} vs {v}"
        );
    }
}

#[test]
fn the_thread_count_does_not_change_a_fit() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets/comau_lhs.csv");
    let data = read_csv(&path)
        .unwrap()
        .select(&(0..120).collect::<Vec<_>>());
    let run = |threads: usize| {
        rayon::ThreadPoolBuilder::new()
            .num_threads(threads)
            .build()
            .unwrap()
            .install(|| ErrorModel::fit(&data, Space::Ejs, &quick()).unwrap())
    };
    let (one, two) = (run(1), run(2));
    assert_eq!(
        serde_json::to_string(one.outputs()).unwrap(),
        serde_json::to_string(two.outputs()).unwrap()
    );
    let p1 = one.predict_dataset(&data).unwrap();
    let p2 = rayon::ThreadPoolBuilder::new()
        .num_threads(2)
        .build()
        .unwrap()
        .install(|| two.predict_dataset(&data).unwrap());
    assert_eq!(p1, p2);
}

#[test]
fn an_unfactorisable_correlation_matrix_escalates_the_jitter() {
    // 40 points on a line with a very long correlation length: R is PSD in
    // exact arithmetic but far too ill-conditioned for a Cholesky with a
    // 1e-30 jitter; the ladder climbs (×10 per rung) until it factorises.
    let x: Vec<Vec<f64>> = (0..40).map(|i| vec![i as f64 / 39.0]).collect();
    let y: Vec<f64> = x.iter().map(|r| (3.0 * r[0]).sin()).collect();
    let m = common::fit_at(
        &x,
        &y,
        &TrendKind::Constant.trend(1),
        &[1e-3],
        0.0,
        Some(1e-30),
    )
    .unwrap();
    assert!(
        m.data().jitter() > 1e-29 && m.data().jitter() <= 1e-6,
        "jitter {:e}",
        m.data().jitter()
    );
    let p = m.predict(&[vec![0.5], vec![2.0]]).unwrap();
    assert!(p.iter().all(|v| v.mean.is_finite() && v.mse.is_finite()));
}
