//! Warm starts (`HyperSpec::Warm`): a refit on 90 % of the rows,
//! started from the full fit's ξ, ν and curvature, predicts the held-out
//! rows as a cold multistart does, at a fraction of the evaluations; and
//! the support screen of the kinematic trend (`supported_columns`).

use robokrige::dataset::read_csv;
use robokrige::kriging::{Hyperparameters, KrigingOptions, support, supported_columns};
use robokrige::model::ErrorModel;
use robokrige::params::{ErrorModelParams, HyperSpec};
use robokrige::space::Space;

#[test]
fn a_warm_fold_refit_matches_the_cold_one_at_a_fraction_of_the_cost() {
    let data = read_csv(std::path::Path::new("datasets/comau_lhs.csv")).unwrap();
    let data = data.select(&(0..200).collect::<Vec<_>>());
    let o = KrigingOptions::default().nugget(true);
    let full = ErrorModel::fit(&data, Space::Ejs, &o).unwrap();
    let warm = ErrorModelParams::new()
        .kriging(o.clone())
        .hyper(HyperSpec::Warm(full.warm_starts()))
        .check()
        .unwrap();
    let fold = data.select(&(0..200).filter(|i| i % 10 != 3).collect::<Vec<_>>());
    let held = data.select(&(0..200).filter(|i| i % 10 == 3).collect::<Vec<_>>());
    let w = warm.fit(&fold).unwrap();
    let c = ErrorModel::fit(&fold, Space::Ejs, &o).unwrap();
    let (pw, pc) = (
        w.predict(&held.q, &held.dir).unwrap(),
        c.predict(&held.q, &held.dir).unwrap(),
    );
    let errors = held.errors.as_ref().unwrap();
    let rms = |d: &dyn Fn(usize) -> f64| {
        ((0..held.len()).map(|i| d(i).powi(2)).sum::<f64>() / held.len() as f64).sqrt()
    };
    for (a, (rw, rc)) in w.reports().iter().zip(c.reports()).enumerate() {
        // the search stops once an iteration gains < 0.01 nats: within a
        // fraction of a nat of the cold optimum (m/2 · Δln ψ)
        let nats = (rw.ln_psi - rc.ln_psi) * fold.len() as f64 / 2.0;
        let apart = rms(&|i| pw.mean[i][a] - pc.mean[i][a]);
        let held_out = rms(&|i| errors[i][a] - pc.mean[i][a]);
        eprintln!(
            "axis {a}: warm ln ψ {:.5} ({} evals), cold {:.5} ({} evals), {nats:.3} nats \
             apart; predictions {apart:.5} apart, held-out RMS {held_out:.5}",
            rw.ln_psi, rw.evals, rc.ln_psi, rc.evals
        );
        assert!(nats < 0.25, "axis {a}");
        assert!(apart < 0.1 * held_out, "axis {a}");
        assert!(3 * rw.evals < rc.evals, "axis {a}");
        assert_eq!(rw.starts, 1);
    }
    // the start is how the fit began, not part of the model
    assert_eq!(w.options(), &o);
}

#[test]
fn warm_starts_of_the_wrong_size_are_refused() {
    let data = read_csv(std::path::Path::new("datasets/comau_lhs.csv")).unwrap();
    let data = data.select(&(0..60).collect::<Vec<_>>());
    let one = Hyperparameters::new(vec![0.1; 3], 0.0);
    let fit = |starts: Vec<Hyperparameters>| {
        ErrorModelParams::new()
            .kriging(KrigingOptions::default())
            .hyper(HyperSpec::Warm(starts))
            .check()
            .and_then(|p| p.fit(&data))
    };
    // one start, or three of the wrong length
    assert!(fit(vec![one.clone()]).is_err());
    assert!(fit(vec![one.clone(), one.clone(), one]).is_err());
    // negative ξ
    assert!(fit(vec![Hyperparameters::new(vec![-1.0; 12], 0.0); 3]).is_err());
}

#[test]
fn a_column_seen_by_one_row_is_not_supported() {
    assert!((support(&[0.0, 2.0, 0.0, 0.0]) - 1.0).abs() < 1e-12);
    assert!((support(&[1.0; 40]) - 40.0).abs() < 1e-9);
    assert_eq!(support(&[0.0; 5]), 0.0);
    let m = 50;
    // constant, a ramp, and a column that is zero except on one row
    let f = faer::Mat::from_fn(m, 3, |i, j| match j {
        0 => 1.0,
        1 => i as f64,
        _ => f64::from(u8::from(i == 7)),
    });
    assert_eq!(supported_columns(&f, 1e-3, 0.0).0, vec![0, 1, 2]);
    assert_eq!(supported_columns(&f, 1e-3, 10.0).0, vec![0, 1]);
}
