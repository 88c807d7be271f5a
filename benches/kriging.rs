//! Criterion benchmarks of the Kriging engine at m = 300, d = 12 (the default
//! COMAU campaign in EJS): one ψ evaluation, a full fit of the three outputs
//! (GPS, 4 starts), and prediction of 10 000 points, for the constant, linear
//! and quadratic trends. Run: `cargo bench --bench kriging`.

mod common;

use common::{campaign, probe_10k};
use criterion::{Criterion, criterion_group, criterion_main};
use robokrige::kriging::{
    Gaussian, KrigingOptions, KrigingProblem, TrainingInputs, TrendKind, Workspace,
    independent_columns, trend_matrix,
};
use robokrige::model::ErrorModel;
use robokrige::space::{Normalizer, Space};
use std::hint::black_box;
use std::time::Duration;

const TRENDS: [TrendKind; 3] = [TrendKind::Constant, TrendKind::Linear, TrendKind::Quadratic];

fn psi_eval(c: &mut Criterion) {
    let data = campaign();
    let rows = Space::Ejs.rows(&data.q, &data.dir);
    let x = Normalizer::fit(&rows).apply_rows(&rows);
    let inputs = TrainingInputs::new(&x);
    let y: Vec<f64> = data.errors.as_ref().unwrap().iter().map(|e| e[0]).collect();
    let yn = Normalizer::fit_column(&y);
    let y: Vec<f64> = y.iter().map(|v| (v - yn.mean[0]) / yn.std[0]).collect();
    let theta = vec![0.05; 12];
    let mut g = c.benchmark_group("psi_eval_m300_d12");
    for kind in TRENDS {
        let cand = kind.monomials(12);
        let (kept, _) = independent_columns(&trend_matrix(&cand, &x), 1e-9);
        let f = trend_matrix(&cand.subset(&kept), &x);
        let prob = KrigingProblem {
            min_jitter: None,
            corr: &Gaussian,
            inputs: &inputs,
            f: &f,
            y: &y,
            prior: &[],
        };
        let mut ws = Workspace::new(x.len(), f.ncols());
        g.bench_function(format!("{kind:?}").to_lowercase(), |b| {
            b.iter(|| prob.psi(black_box(&theta), 0.0, &mut ws).unwrap())
        });
    }
    g.finish();
}

fn full_fit(c: &mut Criterion) {
    let data = campaign();
    let mut g = c.benchmark_group("fit_3_outputs_gps");
    g.sample_size(10).measurement_time(Duration::from_secs(40));
    for kind in TRENDS {
        let opts = KrigingOptions::default().trend(kind);
        g.bench_function(format!("{kind:?}").to_lowercase(), |b| {
            b.iter(|| ErrorModel::fit(black_box(&data), Space::Ejs, &opts).unwrap())
        });
    }
    g.finish();
}

fn predict_10k(c: &mut Criterion) {
    let data = campaign();
    let (q, dir) = probe_10k(&data);
    let mut g = c.benchmark_group("predict_10000_points_3_outputs");
    g.sample_size(20);
    for kind in TRENDS {
        let opts = KrigingOptions::default().trend(kind);
        let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
        g.bench_function(format!("{kind:?}").to_lowercase(), |b| {
            b.iter(|| model.predict(black_box(&q), &dir).unwrap())
        });
    }
    g.finish();
}

criterion_group!(benches, psi_eval, full_fit, predict_10k);
criterion_main!(benches);
