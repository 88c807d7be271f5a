//! The method registry: names, parsing, and the GA method's selection.

use robokrige::dataset::Dataset;
use robokrige::kriging::TrendModel;
use robokrige::methods::{ALL_METHODS, Method, parse_methods};
use robokrige::selection::Selection;

mod common;

fn campaign(rows: usize) -> Dataset {
    common::comau_lhs(rows)
}

#[test]
fn names_parse_and_round_trip() {
    assert_eq!(parse_methods("all").unwrap(), ALL_METHODS.to_vec());
    assert_eq!(
        parse_methods("ejs-gps, js-hj").unwrap(),
        vec![Method::EjsGps, Method::JsHj]
    );
    for m in ALL_METHODS {
        assert_eq!(Method::from_name(m.name()).unwrap(), m);
    }
    let err = parse_methods("ejs-gps,ejs-magic").unwrap_err().to_string();
    assert!(err.contains("ejs-magic") && err.contains("ejs-ga"), "{err}");
}

#[test]
fn the_recommended_method_comes_first_with_a_nugget_and_the_family_by_cv() {
    assert_eq!(ALL_METHODS[0], Method::Recommended);
    assert_eq!(
        Method::from_name("recommended").unwrap(),
        Method::Recommended
    );
    let m = fit(Method::Recommended, &campaign(60), 1);
    assert!(m.options().get_nugget() && m.options().get_corr().is_by_cv());
    for (out, rep) in m.outputs().iter().zip(m.reports()) {
        assert!(rep.families.len() >= 2);
        assert!(rep.nugget > 0.0);
        assert!(rep.families.iter().any(|f| f.corr == out.corr()));
    }
    // the papers' methods keep interpolating
    let paper = fit(Method::EjsHj, &campaign(60), 1);
    assert!(!paper.options().get_nugget() && !paper.options().get_corr().is_by_cv());
}

#[test]
fn ga_method_selects_a_capped_deterministic_subset_with_the_constant() {
    let d = campaign(50);
    let a = fit(Method::EjsGa, &d, 3);
    let b = fit(Method::EjsGa, &d, 3);
    // same seed, same model (the reports differ only by their wall-clock seconds)
    assert_eq!(a.outputs(), b.outputs());
    for (out, report) in a.outputs().iter().zip(a.reports()) {
        let p = out.data().trend().len();
        assert!(
            (1..=44).contains(&p),
            "{p} terms for 50 rows, 10 folds (cap 45 − 1)"
        );
        assert_eq!(report.trend_terms[0], "1");
    }
    // the selection is recorded with the model: dependent candidates dropped
    // with a reason, the fitness history non-increasing (elitism), and the
    // selected names are the fitted trend's terms
    let Some(Selection::Ga { outputs }) = &a.selection() else {
        panic!("GA selection not recorded: {:?}", a.selection());
    };
    for (sel, report) in outputs.iter().zip(a.reports()) {
        assert_eq!(sel.candidates, 91);
        // 50 rows: at most 50 independent columns, and every λ² is affine in λ
        assert!(sel.dropped.len() >= 91 - 50, "{}", sel.dropped.len());
        for k in 1..=6 {
            let term = format!("dir{k}^2");
            let d = sel
                .dropped
                .iter()
                .find(|d| d.term == term)
                .expect("λ² dropped");
            assert!(
                d.reason.starts_with("linear combination of 1"),
                "{}",
                d.reason
            );
        }
        assert!(
            sel.selected
                .iter()
                .all(|t| !sel.dropped.iter().any(|d| &d.term == t))
        );
        assert_eq!(sel.selected, report.trend_terms);
        assert!(sel.history.windows(2).all(|w| w[1] <= w[0]));
        assert_eq!(sel.history.last().copied(), Some(sel.cv_rmse_mm));
    }
    let text = serde_json::to_string(&a).unwrap();
    assert!(text.contains("\"selection\":{\"kind\":\"ga\""));
}

fn fit(m: Method, data: &robokrige::dataset::Dataset, seed: u64) -> robokrige::model::ErrorModel {
    m.params(seed, false).check().unwrap().fit(data).unwrap()
}

/// `Overrides::covariates`: each named column becomes a model input (a
/// `Feature::Covariate` with its first value as the reference), as the
/// Python estimator's `covariates=[…]` asks; a missing column, or one
/// named twice, is refused with the library's message.
#[test]
fn covariates_by_name_become_model_inputs() {
    use robokrige::features::Feature;
    use robokrige::methods::{Overrides, params_with};
    let data = robokrige::dataset::read_csv(std::path::Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_temperature.csv"
    )))
    .unwrap()
    .select(&(0..80).collect::<Vec<_>>());
    let temp = data.covariate("temp_c").unwrap().values.clone();
    let o = Overrides::new().covariates(vec!["temp_c".into()]);
    let model = params_with(None, &o, &data)
        .unwrap()
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert_eq!(
        model.extras(),
        &[Feature::Covariate {
            name: "temp_c".into(),
            reference: Some(temp[0]),
        }]
    );
    assert!(model.input_names().iter().any(|n| n == "temp_c"));
    let plain = params_with(None, &Overrides::new(), &data)
        .unwrap()
        .check()
        .unwrap()
        .fit(&data)
        .unwrap();
    assert!(plain.extras().is_empty());
    let missing = params_with(
        None,
        &Overrides::new().covariates(vec!["humidity".into()]),
        &data,
    );
    assert!(
        missing
            .unwrap_err()
            .to_string()
            .contains("covariate column 'humidity', which is missing")
    );
    let twice = Overrides::new().covariates(vec!["temp_c".into(), "temp_c".into()]);
    assert!(
        params_with(None, &twice, &data)
            .unwrap_err()
            .to_string()
            .contains("named twice")
    );
}
