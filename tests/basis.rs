//! PCC + PCA basis fusion (seed 003 eqs 16–20).

mod common;

use robokrige::dataset::read_csv;
use robokrige::kriging::{KrigingOptions, Monomials, OptimizerKind, TrendModel, trend_matrix};
use robokrige::model::ErrorModel;
use robokrige::selection::{pcc_pca, screen_candidates};
use robokrige::space::Normalizer;
use std::path::Path;

fn inputs(m: usize) -> Vec<Vec<f64>> {
    let rows: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            let t = i as f64;
            vec![
                (t * 0.37).sin(),
                (t * 0.91).cos(),
                ((t * 1.7).sin() * 3.0).tanh(),
                if i % 3 == 0 { 1.0 } else { -1.0 },
            ]
        })
        .collect();
    Normalizer::fit(&rows).apply_rows(&rows)
}

#[test]
fn ranks_by_correlation_and_keeps_orthogonal_components_with_the_eigenvalues() {
    let x = inputs(200);
    let y: Vec<f64> = x
        .iter()
        .map(|s| 3.0 * s[0] + s[1] * s[2] + 0.5 * s[3])
        .collect();
    let names: Vec<String> = ["a", "b", "c", "d"].map(String::from).to_vec();
    let cand = Monomials::quadratic(4);
    let (basis, report) = pcc_pca(&cand, &x, &y, 0.1, 0.99, 100, &names).unwrap();
    assert_eq!(report.ranking[0].0, "a", "{:?}", &report.ranking[..3]);
    assert!(
        report
            .ranking
            .windows(2)
            .all(|w| w[0].1.abs() >= w[1].1.abs())
    );
    assert_eq!(
        report.selected,
        report.ranking.iter().filter(|r| r.1.abs() > 0.1).count()
    );
    assert!(report.explained >= 0.99 && report.components <= report.selected);
    // eqs 17–19: the fused columns are uncorrelated on the training data, with
    // variances equal to the kept eigenvalues; the first column is the constant
    let w = trend_matrix(&basis, &x);
    let m = x.len() as f64;
    for a in 1..basis.len() {
        assert!(w.col(0).iter().all(|v| *v == 1.0));
        for b in 1..basis.len() {
            let c: f64 = (0..x.len()).map(|i| w[(i, a)] * w[(i, b)]).sum::<f64>() / (m - 1.0);
            let want = if a == b {
                report.eigenvalues[a - 1]
            } else {
                0.0
            };
            assert!(
                (c - want).abs() < 1e-9 * (1.0 + want),
                "cov({a},{b}) = {c}, want {want}"
            );
        }
    }
}

#[test]
fn pca_models_round_trip_and_bad_parameters_are_errors() {
    let d = read_csv(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .unwrap();
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .max_evals(60);
    let (model, reports) = common::fit_pcc_pca(&d, &opts, None);
    for (r, out) in reports.iter().zip(model.outputs()) {
        eprintln!(
            "PCC+PCA: {} candidates, {} above T, {} components ({:.4} of the variance)",
            r.ranking.len(),
            r.selected,
            r.components,
            r.explained
        );
        assert!(r.components >= 1 && r.selected >= r.components);
        // the constant plus the components (none is dependent on the others)
        assert_eq!(out.data().trend().len(), 1 + r.components);
    }
    let text = serde_json::to_string(&model).unwrap();
    let back = ErrorModel::from_json(&text, "pca.json").unwrap();
    let (a, b) = (
        model.predict_dataset(&d).unwrap(),
        back.predict_dataset(&d).unwrap(),
    );
    assert!(
        a.mean
            .iter()
            .flatten()
            .zip(b.mean.iter().flatten())
            .all(|(x, y)| x.to_bits() == y.to_bits())
    );
    let x = inputs(20);
    let y = vec![0.0; 20];
    assert!(pcc_pca(&Monomials::linear(4), &x, &y, 1.5, 0.99, 10, &[]).is_err());
    // a constant response correlates with nothing: only the constant term remains
    let (basis, report) = pcc_pca(&Monomials::linear(4), &x, &y, 0.1, 0.99, 10, &[]).unwrap();
    assert_eq!((basis.len(), report.selected), (1, 0));
}

#[test]
fn screening_drops_dependent_candidates_and_says_why() {
    // inputs a, b, d (d binary, like λ) and a column c = a exactly
    let x: Vec<Vec<f64>> = inputs(60)
        .into_iter()
        .map(|r| vec![r[0], r[1], r[0], r[3]])
        .collect();
    let names: Vec<String> = ["a", "b", "c", "d"].map(String::from).to_vec();
    let s = screen_candidates(&Monomials::quadratic(4), &x, &names);
    assert_eq!(s.total, 15);
    let reason = |t: &str| {
        s.dropped
            .iter()
            .find(|d| d.term == t)
            .map(|d| d.reason.clone())
            .unwrap_or_else(|| panic!("{t} not dropped: {:?}", s.dropped))
    };
    assert_eq!(reason("c"), "exact duplicate of a");
    assert_eq!(reason("a*c"), "exact duplicate of a^2");
    // d² is affine in d because d takes two values
    assert_eq!(
        reason("d^2"),
        "linear combination of 1, d on the training rows"
    );
    assert_eq!(s.kept.len() + s.dropped.len(), 15);
    assert!(!s.kept.contains(&3));
}
