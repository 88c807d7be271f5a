//! The method registry: names, parsing, and the GA method's selection.

use robokrige::dataset::{Dataset, read_csv};
use robokrige::kriging::TrendModel;
use robokrige::methods::{ALL_METHODS, Method, parse_methods};
use std::path::Path;

fn campaign(rows: usize) -> Dataset {
    let d = read_csv(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .unwrap();
    d.select(&(0..rows).collect::<Vec<_>>())
}

#[test]
fn names_parse_and_round_trip() {
    assert_eq!(parse_methods("all").unwrap(), ALL_METHODS.to_vec());
    assert_eq!(
        parse_methods("ejs-gps, js-hj").unwrap(),
        vec![Method::EjsGps, Method::JsHj]
    );
    for m in ALL_METHODS {
        assert_eq!(Method::parse(m.name()).unwrap(), m);
    }
    let err = parse_methods("ejs-gps,ejs-magic").unwrap_err().to_string();
    assert!(err.contains("ejs-magic") && err.contains("ejs-ga"), "{err}");
}

#[test]
fn ga_method_selects_a_capped_deterministic_subset_with_the_constant() {
    let d = campaign(50);
    let a = Method::EjsGa.fit(&d, 3).unwrap();
    let b = Method::EjsGa.fit(&d, 3).unwrap();
    // same seed, same model (the reports differ only by their wall-clock seconds)
    assert_eq!(a.outputs, b.outputs);
    for (out, report) in a.outputs.iter().zip(&a.reports) {
        let p = out.data.trend.len();
        assert!(
            (1..=44).contains(&p),
            "{p} terms for 50 rows, 10 folds (cap 45 − 1)"
        );
        assert_eq!(report.trend_terms[0], "1");
    }
}
