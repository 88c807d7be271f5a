//! Warm starts (`HyperSpec::Warm`): a refit on 90 % of the rows,
//! started from the full fit's ξ, ν and curvature, reaches the ln ψ of a
//! cold multistart at a fraction of the evaluations; and the support screen
//! of the kinematic trend (`supported_columns`).

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
    let w = warm.fit(&fold).unwrap();
    let c = ErrorModel::fit(&fold, Space::Ejs, &o).unwrap();
    for a in 0..3 {
        let (rw, rc) = (&w.reports()[a], &c.reports()[a]);
        eprintln!(
            "axis {a}: warm ln ψ {:.5} ({} evals), cold {:.5} ({} evals)",
            rw.ln_psi, rw.evals, rc.ln_psi, rc.evals
        );
        assert!(rw.ln_psi <= rc.ln_psi + 1e-3, "axis {a}");
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
