//! Universal Kriging invariants: interpolation, MSE ≥ 0 and ≈ 0 at training
//! points, row-order independence, dependent trend terms dropped, save/load
//! bit-identical, optimiser ≤ fixed starting points.

mod common;

use robokrige::dataset::{Dataset, read_csv};
use robokrige::kriging::{KrigingOptions, Monomials, OptimizerKind, Trend, TrendKind};
use robokrige::model::ErrorModel;
use robokrige::space::{Normalizer, Space};
use std::path::Path;

fn campaign(rows: usize) -> Dataset {
    let mut d = read_csv(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .unwrap();
    d.q.truncate(rows);
    d.dir.truncate(rows);
    d.errors.as_mut().unwrap().truncate(rows);
    d.positions = None;
    d.ids = None;
    d.covariates.clear();
    d
}

fn normalised(d: &Dataset, space: Space) -> Vec<Vec<f64>> {
    let rows = space.rows(&d.q, &d.dir);
    Normalizer::fit(&rows).apply_rows(&rows)
}

fn axis(d: &Dataset, a: usize) -> Vec<f64> {
    d.errors.as_ref().unwrap().iter().map(|e| e[a]).collect()
}

const THETA: [f64; 12] = [0.3, 0.5, 0.4, 0.2, 0.3, 0.1, 0.5, 0.3, 0.2, 0.1, 0.1, 0.1];

#[test]
fn interpolates_training_points_with_zero_mse_and_nonnegative_mse_elsewhere() {
    let d = campaign(120);
    let x = normalised(&d, Space::Ejs);
    for trend in [
        Trend::from(Monomials::constant(12)),
        Trend::from(Monomials::linear(12)),
        Trend::from(Monomials::quadratic(12)),
    ] {
        let y = axis(&d, 1);
        let m = common::fit_at(&x, &y, &trend, &THETA, 0.0, None).unwrap();
        let p = m.predict(&x).unwrap();
        for (pi, yi) in p.iter().zip(&y) {
            assert!((pi.mean - yi).abs() < 1e-7, "{} vs {}", pi.mean, yi);
            assert!(
                pi.mse >= 0.0 && pi.mse < 1e-9,
                "mse at a training point {}",
                pi.mse
            );
        }
        // elsewhere: between training points
        let mid: Vec<Vec<f64>> = x
            .windows(2)
            .map(|w| w[0].iter().zip(&w[1]).map(|(a, b)| 0.5 * (a + b)).collect())
            .collect();
        assert!(
            m.predict(&mid)
                .unwrap()
                .iter()
                .all(|p| p.mse >= 0.0 && p.mse.is_finite() && p.mean.is_finite())
        );
    }
}

#[test]
fn with_a_nugget_the_model_smooths_instead_of_interpolating() {
    let d = campaign(80);
    let x = normalised(&d, Space::Ejs);
    let y = axis(&d, 0);
    let m = common::fit_at(
        &x,
        &y,
        &Trend::from(Monomials::constant(12)),
        &THETA,
        0.05,
        None,
    )
    .unwrap();
    let worst = m
        .predict(&x)
        .unwrap()
        .iter()
        .zip(&y)
        .map(|(p, v)| (p.mean - v).abs())
        .fold(0.0, f64::max);
    assert!(
        worst > 1e-4,
        "a nugget of 0.05 should not interpolate (worst residual {worst})"
    );
}

#[test]
fn row_order_does_not_change_predictions() {
    let d = campaign(90);
    let x = normalised(&d, Space::Ejs);
    let y = axis(&d, 2);
    let perm: Vec<usize> = (0..90).map(|i| (i * 37) % 90).collect();
    let xp: Vec<Vec<f64>> = perm.iter().map(|&i| x[i].clone()).collect();
    let yp: Vec<f64> = perm.iter().map(|&i| y[i]).collect();
    let trend = Trend::from(Monomials::linear(12));
    let a = common::fit_at(&x, &y, &trend, &THETA, 0.0, None).unwrap();
    let b = common::fit_at(&xp, &yp, &trend, &THETA, 0.0, None).unwrap();
    let probe: Vec<Vec<f64>> = x
        .iter()
        .map(|r| r.iter().map(|v| v + 0.05).collect())
        .collect();
    for (pa, pb) in a
        .predict(&probe)
        .unwrap()
        .iter()
        .zip(b.predict(&probe).unwrap())
    {
        assert!((pa.mean - pb.mean).abs() < 1e-9 * (1.0 + pa.mean.abs()));
        assert!((pa.mse - pb.mse).abs() < 1e-9 * (1e-6 + pa.mse));
    }
    assert!((a.data().ln_psi() - b.data().ln_psi()).abs() < 1e-10);
}

#[test]
fn quadratic_trend_over_ejs_drops_the_direction_squares() {
    let d = campaign(150);
    let opts = KrigingOptions::default()
        .trend(TrendKind::Quadratic)
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(60);
    let model = ErrorModel::fit(&d, Space::Ejs, &opts).unwrap();
    for r in model.reports() {
        assert_eq!(r.trend_terms.len() + r.dropped_terms.len(), 91);
        // dir_k² is affine in dir_k: the six squares go (nothing else in this design)
        assert_eq!(
            r.dropped_terms,
            (1..=6).map(|k| format!("dir{k}^2")).collect::<Vec<_>>()
        );
    }
}

#[test]
fn save_load_predicts_bit_identically_and_rejects_other_formats() {
    let d = campaign(60);
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(80);
    let model = ErrorModel::fit(&d, Space::Ejs, &opts).unwrap();
    let path = std::env::temp_dir().join(format!("robokrige-model-{}.json", std::process::id()));
    model.save(&path).unwrap();
    let back = ErrorModel::load(&path).unwrap();
    assert_eq!(back, model);
    let probe_q: Vec<Vec<f64>> =
        d.q.iter()
            .map(|q| q.iter().map(|v| v + 0.7).collect())
            .collect();
    let (a, b) = (
        model.predict(&probe_q, &d.dir).unwrap(),
        back.predict(&probe_q, &d.dir).unwrap(),
    );
    for (x, y) in a
        .mean
        .iter()
        .flatten()
        .chain(a.std.iter().flatten())
        .zip(b.mean.iter().flatten().chain(b.std.iter().flatten()))
    {
        assert_eq!(x.to_bits(), y.to_bits());
    }
    let text =
        std::fs::read_to_string(&path)
            .unwrap()
            .replacen("\"version\":3", "\"version\":99", 1);
    let err = ErrorModel::from_json(&text, "old.json")
        .unwrap_err()
        .to_string();
    assert!(err.contains("version"), "{err}");
    // wrong joint count at prediction
    assert!(model.predict(&[vec![0.0; 5]], &[vec![1.0; 5]]).is_err());
    std::fs::remove_file(path).ok();
}

/// Model files are O(m·d): no Cholesky factor is written, and the MSE after
/// loading (factor recomputed) is bit-identical. (Files of versions 1 and 2
/// still load: `tests/model_file.rs`.)
#[test]
fn model_files_store_no_factor_and_load_bit_identically() {
    let d = campaign(80);
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(60)
        .nugget(true);
    let model = ErrorModel::fit(&d, Space::Ejs, &opts).unwrap();
    let text = serde_json::to_string(&model).unwrap();
    assert!(!text.contains("chol_lower"));
    let back = ErrorModel::from_json(&text, "v3.json").unwrap();
    let probe_q: Vec<Vec<f64>> =
        d.q.iter()
            .map(|q| q.iter().map(|v| v - 0.4).collect())
            .collect();
    let p0 = model.predict(&probe_q, &d.dir).unwrap();
    let p = back.predict(&probe_q, &d.dir).unwrap();
    for (x, y) in p0
        .mean
        .iter()
        .chain(&p0.std)
        .flatten()
        .zip(p.mean.iter().chain(&p.std).flatten())
    {
        assert_eq!(x.to_bits(), y.to_bits());
    }
    // an impossible ξ or scale is refused on load, with one clear error
    for (field, value) in [("theta", "[-1.0]"), ("y_std", "1e300"), ("nugget", "-0.5")] {
        let mut bad: serde_json::Value = serde_json::from_str(&text).unwrap();
        let v: serde_json::Value = serde_json::from_str(value).unwrap();
        if field == "theta" {
            let mut t = bad["outputs"][0]["theta"].clone();
            t[0] = v[0].clone();
            bad["outputs"][0]["theta"] = t;
        } else {
            bad["outputs"][0][field] = v;
        }
        assert!(
            ErrorModel::from_json(&bad.to_string(), "bad.json").is_err(),
            "{field} = {value} accepted"
        );
    }
}

#[test]
fn optimisers_improve_on_their_start_and_gps_reaches_at_least_hj() {
    let d = campaign(100);
    let hj = ErrorModel::fit(
        &d,
        Space::Ejs,
        &KrigingOptions::default().optimizer(OptimizerKind::HookeJeeves),
    )
    .unwrap();
    let gps = ErrorModel::fit(&d, Space::Ejs, &KrigingOptions::default().starts(3)).unwrap();
    let x = normalised(&d, Space::Ejs);
    for a in 0..3 {
        // the box centre (HJ's start) is worse than what both methods found
        let centre = vec![10f64.powf(-2.0); 12];
        let at_centre = common::fit_at(
            &x,
            &axis(&d, a),
            &Trend::from(Monomials::constant(12)),
            &centre,
            0.0,
            None,
        )
        .unwrap();
        assert!(hj.reports()[a].ln_psi < at_centre.data().ln_psi());
        // GPS starts from the centre too, and more places
        assert!(
            gps.reports()[a].ln_psi <= hj.reports()[a].ln_psi + 1e-3,
            "axis {a}: gps {} hj {}",
            gps.reports()[a].ln_psi,
            hj.reports()[a].ln_psi
        );
    }
}

#[test]
fn constant_response_fits_and_predicts_the_constant() {
    let mut d = campaign(40);
    for e in d.errors.as_mut().unwrap() {
        e[1] = 0.25;
    }
    let model = ErrorModel::fit(
        &d,
        Space::Ejs,
        &KrigingOptions::default()
            .optimizer(OptimizerKind::HookeJeeves)
            .max_evals(50),
    )
    .unwrap();
    let p = model.predict(&d.q, &d.dir).unwrap();
    assert!(p.mean.iter().all(|m| (m[1] - 0.25).abs() < 1e-12));
    assert!(p.std.iter().all(|s| s[1] == 0.0));
}

#[test]
fn estimated_nugget_is_positive_on_noisy_data_and_small_on_clean_data() {
    // a smooth function of the inputs, with and without 5 % noise
    let d = campaign(120);
    let x = normalised(&d, Space::Js);
    let clean: Vec<f64> = x
        .iter()
        .map(|r| (r[0] + 0.5 * r[1]).sin() + 0.3 * r[2] * r[3])
        .collect();
    let mut rng = 12345u64;
    let mut noise = || {
        rng = rng
            .wrapping_mul(6364136223846793005)
            .wrapping_add(1442695040888963407);
        ((rng >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 0.35
    };
    let noisy: Vec<f64> = clean.iter().map(|v| v + noise()).collect();
    let opts = KrigingOptions::default().nugget(true).starts(2);
    let (_, r_noisy) =
        common::fit_searched(&x, &noisy, &Trend::from(Monomials::constant(6)), &opts).unwrap();
    let (_, r_clean) =
        common::fit_searched(&x, &clean, &Trend::from(Monomials::constant(6)), &opts).unwrap();
    assert!(
        r_noisy.nugget > 1e-3,
        "noisy data: nugget {}",
        r_noisy.nugget
    );
    assert!(
        r_clean.nugget < r_noisy.nugget / 100.0,
        "clean {} vs noisy {}",
        r_clean.nugget,
        r_noisy.nugget
    );
}

#[test]
fn cross_validation_predicts_every_row_once_out_of_fold() {
    let d = campaign(60);
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(60);
    let cv = robokrige::cv::cross_validate_refit(&d, 5, 3, |train| {
        assert_eq!(train.len(), 48);
        ErrorModel::fit(train, Space::Ejs, &opts)
    })
    .unwrap();
    assert_eq!(cv.residuals.len(), 60);
    assert_eq!(cv.fold, robokrige::cv::kfold_partition(60, 5, 3).unwrap());
    // out-of-fold residuals are much smaller than the errors themselves, but not zero
    let raw = robokrige::stats::summarize(d.errors.as_ref().unwrap());
    assert!(cv.summary.mean_3d_mm < 0.5 * raw.mean_3d_mm && cv.summary.mean_3d_mm > 0.0);
}

#[test]
fn closed_form_cv_equals_refit_at_fixed_theta() {
    let d = campaign(120);
    let x = normalised(&d, Space::Ejs);
    let fold = robokrige::cv::kfold_partition(120, 10, 7).unwrap();
    let blocks: Vec<Vec<usize>> = (0..10)
        .map(|f| (0..120).filter(|&i| fold[i] == f).collect())
        .collect();
    let mut worst: f64 = 0.0;
    for (trend, nugget, a) in [
        (Trend::from(Monomials::constant(12)), 0.0, 0),
        (Trend::from(Monomials::linear(12)), 0.0, 1),
        (Trend::from(Monomials::linear(12)), 0.01, 2),
    ] {
        let y = axis(&d, a);
        let full = common::fit_at(&x, &y, &trend, &THETA, nugget, None).unwrap();
        let closed = full.held_out_residuals(&blocks).unwrap();
        for block in &blocks {
            let train: Vec<usize> = (0..120).filter(|i| !block.contains(i)).collect();
            let xt: Vec<Vec<f64>> = train.iter().map(|&i| x[i].clone()).collect();
            let yt: Vec<f64> = train.iter().map(|&i| y[i]).collect();
            let refit = common::fit_at(&xt, &yt, &trend, &THETA, nugget, None).unwrap();
            let xh: Vec<Vec<f64>> = block.iter().map(|&i| x[i].clone()).collect();
            for (p, &i) in refit.predict(&xh).unwrap().iter().zip(block) {
                let e = y[i] - p.mean;
                let diff = (closed[i] - e).abs() / e.abs().max(1e-3);
                worst = worst.max(diff);
                assert!(
                    diff < 1e-8,
                    "row {i}: closed form {} vs refit {e}",
                    closed[i]
                );
            }
        }
    }
    eprintln!("closed-form vs refit at fixed ξ: worst relative difference {worst:.1e}");
}

#[test]
fn closed_form_cv_of_an_error_model_matches_its_outputs_and_rejects_other_data() {
    let d = campaign(80);
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(60);
    let model = ErrorModel::fit(&d, Space::Ejs, &opts).unwrap();
    let cv = robokrige::cv::cross_validate_closed_form(&d, &model, 8, 2).unwrap();
    assert_eq!(cv.mode, robokrige::cv::CvMode::ClosedForm);
    assert_eq!(cv.residuals.len(), 80);
    assert!(cv.residuals.iter().flatten().all(|v| v.is_finite()));
    let other = campaign(81);
    assert!(robokrige::cv::cross_validate_closed_form(&other, &model, 8, 2).is_err());
}

/// `converge_rows` below m: ξ converges on the seeded subset
/// `converge_subset` names, and the model still holds and predicts every
/// row.
#[test]
fn xi_converges_on_a_subset_and_the_model_solves_on_all_rows() {
    let d = campaign(240);
    let x = normalised(&d, Space::Js);
    let y = axis(&d, 0);
    let trend = Trend::Monomials(Monomials::constant(6));
    let opts = KrigingOptions::default().starts(2).converge_rows(100);
    let (model, rep) = common::fit_searched(&x, &y, &trend, &opts).unwrap();
    assert_eq!(rep.search_rows, 100);
    assert_eq!(model.data().x_train().len(), 240);
    let rows = robokrige::kriging::converge_subset(240, &opts).unwrap();
    assert_eq!(rows.len(), 100);
    assert!(rows.windows(2).all(|w| w[0] < w[1]));
    assert_eq!(robokrige::kriging::converge_subset(100, &opts), None);
    // the whole campaign's residual at its own rows is the nugget's smoothing only
    let fit = model.predict_mean(&x);
    let rms = (fit
        .iter()
        .zip(&y)
        .map(|(p, t)| (p - t).powi(2))
        .sum::<f64>()
        / 240.0)
        .sqrt();
    let spread = (y.iter().map(|v| v * v).sum::<f64>() / 240.0).sqrt();
    assert!(rms < 0.5 * spread, "{rms} {spread}");
    // too few rows to converge on is refused
    let bad = opts.converge_rows(10);
    assert!(common::fit_searched(&x, &y, &trend, &bad).is_err());
}

/// `KrigingOptions`' fields are private: each builder setter sets what its
/// getter reads, and the rest stays as it was.
#[test]
fn options_setters_set_what_the_getters_read() {
    use robokrige::kriging::{CorrChoice, Correlation, Hyperparameters};
    let d = KrigingOptions::default();
    let o = d
        .clone()
        .trend(TrendKind::Linear)
        .corr(CorrChoice::ByCv { folds: 5 })
        .optimizer(OptimizerKind::Gps)
        .nugget(false)
        .log10_theta((-4.0, 1.0))
        .log10_nugget((-7.0, -1.0))
        .starts(3)
        .seed(9)
        .max_evals(123)
        .tol(0.05)
        .min_jitter(Some(1e-9))
        .polish(false)
        .converge_rows(200);
    assert_eq!(o.get_trend(), TrendKind::Linear);
    assert_eq!(o.get_corr(), CorrChoice::ByCv { folds: 5 });
    assert!(o.get_corr().is_by_cv() && !o.get_nugget() && !o.get_polish());
    assert_eq!(
        o.clone().corr(Correlation::Matern32).get_corr().fixed(),
        Some(Correlation::Matern32)
    );
    assert_eq!(o.get_optimizer(), OptimizerKind::Gps);
    assert_eq!(o.get_log10_theta(), (-4.0, 1.0));
    assert_eq!(o.get_log10_nugget(), (-7.0, -1.0));
    assert_eq!(
        (o.get_starts(), o.get_seed(), o.get_max_evals()),
        (3, 9, 123)
    );
    assert_eq!(o.get_tol(), 0.05);
    assert_eq!(o.get_min_jitter(), Some(1e-9));
    assert_eq!(o.get_converge_rows(), 200);
    assert!(o.validate().is_ok());
    // the defaults: a nugget, BFGS from its 8 starts, the family not chosen
    assert!(d.get_nugget() && !d.get_corr().is_by_cv());
    assert_eq!(d.get_optimizer(), OptimizerKind::Bfgs);
    assert_eq!(d.get_starts(), OptimizerKind::Bfgs.default_starts());
    assert!(KrigingOptions::recommended().get_corr().is_by_cv());
    let w = Hyperparameters::new(vec![0.1, 0.2], 0.3);
    assert_eq!((w.theta(), w.nugget()), (&[0.1, 0.2][..], 0.3));
    assert!(w.inverse_hessian().is_none());
    // ranges are still checked by validate
    assert!(d.clone().log10_theta((1.0, -1.0)).validate().is_err());
    assert!(d.clone().converge_rows(10).validate().is_err());
    assert!(
        d.clone()
            .corr(CorrChoice::ByCv { folds: 1 })
            .validate()
            .is_err()
    );
    assert!(d.starts(0).validate().is_err());
}

/// `KrigingParams` refuses what cannot fit, with a message, before or at
/// the data: fixed hyperparameters with the family chosen by CV, negative
/// ξ, names or correlation inputs that do not match the columns.
#[test]
fn kriging_params_refuse_impossible_fits() {
    use robokrige::kriging::{CorrChoice, Hyperparameters, KrigingParams, Tuning};
    let x: Vec<Vec<f64>> = (0..20)
        .map(|i| vec![(i as f64 * 0.3).sin(), (i as f64 * 0.7).cos()])
        .collect();
    let y: Vec<f64> = x.iter().map(|r| r[0] + 0.5 * r[1]).collect();
    let trend = Trend::from(Monomials::constant(2));
    let fixed = Tuning::Fixed(Hyperparameters::new(vec![1.0, 1.0], 1e-3));
    let by_cv = KrigingParams::new(trend.clone())
        .corr(CorrChoice::ByCv { folds: 5 })
        .tuning(fixed.clone())
        .check()
        .unwrap_err();
    assert!(
        by_cv.to_string().contains("fixed correlation family"),
        "{by_cv}"
    );
    let negative = KrigingParams::new(trend.clone())
        .tuning(Tuning::Warm(Hyperparameters::new(vec![-1.0, 1.0], 0.0)))
        .check()
        .unwrap_err();
    assert!(negative.to_string().contains("ξ ≥ 0"), "{negative}");
    let names = KrigingParams::new(trend.clone())
        .names(vec!["a".into()])
        .check()
        .and_then(|p| p.fit(&x, &y))
        .unwrap_err();
    assert!(names.to_string().contains("1 input names for 2"), "{names}");
    let dims = KrigingParams::new(trend.clone())
        .correlation_inputs(3)
        .check()
        .and_then(|p| p.fit(&x, &y))
        .unwrap_err();
    assert!(dims.to_string().contains("3 correlation inputs"), "{dims}");
    let short = KrigingParams::new(trend.clone())
        .tuning(Tuning::Fixed(Hyperparameters::new(vec![1.0], 1e-3)))
        .check()
        .and_then(|p| p.fit(&x, &y))
        .unwrap_err();
    assert!(
        short.to_string().contains("1 correlation parameters for 2"),
        "{short}"
    );
    // and what can fit does: fixed, warm and searched
    for tuning in [
        fixed,
        Tuning::Warm(Hyperparameters::new(vec![1.0, 1.0], 1e-3)),
        Tuning::Search,
    ] {
        let (model, report) = KrigingParams::new(trend.clone())
            .tuning(tuning)
            .check()
            .and_then(|p| p.fit(&x, &y))
            .unwrap();
        assert_eq!(model.corr(), robokrige::kriging::Correlation::Gaussian);
        assert_eq!(report.theta.len(), 2);
    }
}
