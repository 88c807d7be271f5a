//! Correlation families: the vectorised fills agree with
//! the scalar definition, every family is saved by name and loads back to
//! the same predictions, files without a family load as Gaussian, and
//! `corr_auto` keeps the family with the lowest closed-form CV error.

use robokrige::dataset::Dataset;
use robokrige::kriging::{Correlation, CorrelationModel, KrigingOptions, TrainingInputs};
use robokrige::model::ErrorModel;
use robokrige::space::Space;

mod common;

fn campaign(rows: usize) -> Dataset {
    common::comau_lhs(rows)
}

#[test]
fn vectorised_fills_match_the_scalar_definition() {
    let rows: Vec<Vec<f64>> = (0..23)
        .map(|i| {
            let t = i as f64;
            vec![
                (t * 0.37).sin(),
                (t * 1.3).cos(),
                if i % 2 == 0 { 1.0 } else { -1.0 },
            ]
        })
        .collect();
    let x = TrainingInputs::new(&rows);
    let theta = [0.7, 0.05, 2.0];
    let point = [0.1, -0.4, 1.0];
    for corr in Correlation::ALL {
        let mut r = faer::Mat::<f64>::zeros(23, 23);
        x.fill_lower(&corr, &theta, 0.0, r.as_mut());
        let mut row = vec![0.0; 23];
        corr.fill_row(&theta, &x, &point, &mut row);
        for i in 0..23 {
            let want = corr.corr(&theta, &point, &rows[i]);
            assert!(
                (row[i] - want).abs() <= 1e-15 + 4e-16 * want,
                "{corr} row {i}"
            );
            for j in i + 1..23 {
                let want = corr.corr(&theta, &rows[i], &rows[j]);
                assert!(
                    (r[(j, i)] - want).abs() <= 1e-15 + 4e-16 * want,
                    "{corr} ({j},{i})"
                );
                assert!(want > 0.0 && want < 1.0, "{corr}: a correlation in (0, 1)");
            }
        }
        // R(h) decreases with distance, and is 1 at distance 0
        assert_eq!(corr.corr(&theta, &point, &point), 1.0);
    }
}

#[test]
fn every_family_saves_by_name_and_predicts_the_same_after_loading() {
    let data = campaign(60);
    let test = campaign(80).select(&(60..80).collect::<Vec<_>>());
    let scratch = common::Scratch::new("robokrige-families");
    let dir = scratch.path();
    let mut means = Vec::new();
    for corr in Correlation::ALL {
        let opts = KrigingOptions::default().corr(corr).nugget(false);
        let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
        let path = dir.join(format!("{corr}.json"));
        model.save(&path).unwrap();
        let text = std::fs::read_to_string(&path).unwrap();
        assert!(text.contains(&format!("\"corr\":\"{}\"", corr.name())));
        let back = ErrorModel::load(&path).unwrap();
        assert!(back.outputs().iter().all(|o| o.corr() == corr));
        let a = model.predict_dataset(&test).unwrap();
        let b = back.predict_dataset(&test).unwrap();
        assert_eq!(a.mean, b.mean, "{corr}");
        // an interpolator passes through its training data
        let fit = model.predict_dataset(&data).unwrap();
        let e = data.errors.as_ref().unwrap();
        for (p, m) in fit.mean.iter().zip(e) {
            for k in 0..3 {
                assert!((p[k] - m[k]).abs() < 1e-5, "{corr}: {p:?} vs {m:?}");
            }
        }
        means.push(a.mean);
    }
    // the families are different models
    assert_ne!(means[0], means[1]);
    assert_ne!(means[1], means[3]);
}

#[test]
fn files_without_a_family_load_as_gaussian() {
    let data = campaign(40);
    let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default()).unwrap();
    let text = model.to_json().unwrap();
    let old = text.replace("\"corr\":\"gaussian\",", "");
    assert!(!old.contains("\"corr\""));
    let back = ErrorModel::from_json(&old, "old.json").unwrap();
    assert!(
        back.outputs()
            .iter()
            .all(|o| o.corr() == Correlation::Gaussian)
    );
    assert_eq!(back.outputs(), model.outputs());
}

#[test]
fn auto_keeps_the_family_with_the_lowest_cv_error() {
    let data = campaign(80);
    let opts = KrigingOptions::recommended().nugget(true);
    let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
    for (out, rep) in model.outputs().iter().zip(model.reports()) {
        // tried from the smoothest, stopping after the first rougher family
        // that scored worse than the best so far
        let tried: Vec<Correlation> = rep.families.iter().map(|f| f.corr).collect();
        assert!(tried.len() >= 2, "{tried:?}");
        assert_eq!(tried, Correlation::ALL[..tried.len()]);
        let best_before_last = rep.families[..tried.len() - 1]
            .iter()
            .map(|f| f.cv_rmse)
            .fold(f64::INFINITY, f64::min);
        for (i, f) in rep.families.iter().enumerate().skip(1) {
            let best_before = rep.families[..i]
                .iter()
                .map(|f| f.cv_rmse)
                .fold(f64::INFINITY, f64::min);
            if i + 1 < tried.len() {
                assert!(f.cv_rmse <= best_before, "went on after a worse family");
            }
        }
        if tried.len() < Correlation::ALL.len() {
            assert!(rep.families.last().unwrap().cv_rmse > best_before_last);
        }
        assert!(rep.families.iter().all(|f| f.rows == data.len()));
        let best = rep
            .families
            .iter()
            .min_by(|a, b| a.cv_rmse.total_cmp(&b.cv_rmse))
            .unwrap();
        assert!(best.cv_rmse.is_finite());
        assert_eq!(out.corr(), best.corr);
    }
    // deterministic, and the table is saved with the model
    let again = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
    assert_eq!(again.reports(), model.reports());
    let back = ErrorModel::from_json(&model.to_json().unwrap(), "auto.json").unwrap();
    assert_eq!(back.reports()[0].families, model.reports()[0].families);
}

/// Over `SEARCH_ROWS` rows the family is chosen on the search subset and
/// only the chosen family converges on all rows (a rough 2-input response
/// with noise, 1 100 rows).
#[test]
fn auto_on_a_large_campaign_chooses_on_the_search_subset() {
    use rand::{RngExt, SeedableRng};
    use robokrige::kriging::{KrigingParams, Monomials, SEARCH_ROWS, Trend};
    let m = SEARCH_ROWS + 100;
    let mut rng = rand::rngs::StdRng::seed_from_u64(7);
    let x: Vec<Vec<f64>> = (0..m)
        .map(|_| vec![rng.random_range(-1.0..1.0), rng.random_range(-1.0..1.0)])
        .collect();
    // a kink (|x|) is rough: a Gaussian is not the obvious choice
    let y: Vec<f64> = x
        .iter()
        .map(|r: &Vec<f64>| (3.0 * r[0]).abs() + 0.5 * r[1] + 0.02 * rng.random_range(-1.0..1.0))
        .collect();
    // two starts keep the test fast; the path is the same
    let opts = KrigingOptions::recommended().starts(2);
    let trend = Trend::Monomials(Monomials::constant(2));
    let (model, rep) = KrigingParams::new(trend)
        .options(opts)
        .check()
        .and_then(|p| p.fit(&x, &y))
        .unwrap();
    assert!(rep.families.len() >= 2);
    assert!(rep.families.iter().all(|f| f.rows == SEARCH_ROWS));
    let best = rep
        .families
        .iter()
        .min_by(|a, b| a.cv_rmse.total_cmp(&b.cv_rmse))
        .unwrap();
    assert_eq!(model.corr(), best.corr);
    // ξ converged on all rows, and the model holds all of them
    assert_eq!(rep.search_rows, m);
    let fit = model.predict_mean(&x[..50]);
    let rms = (fit
        .iter()
        .zip(&y)
        .map(|(p, t)| (p - t).powi(2))
        .sum::<f64>()
        / 50.0)
        .sqrt();
    assert!(rms < 0.05, "in-sample RMS {rms}");
}
