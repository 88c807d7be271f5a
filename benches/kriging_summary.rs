//! Bench binary that prints what criterion does not: ψ evaluations spent and
//! ln ψ reached by a full fit, next to the timings of one ψ evaluation, a full
//! fit and 10 000 predictions at m = 300, d = 12 (the default COMAU campaign
//! in EJS), for the constant, linear and quadratic trends.
//! Run: `cargo bench --bench kriging_summary` (add `-- quick` to skip the fits).
//! The statistically careful timings are `cargo bench --bench kriging` (criterion).

use robokrige::dataset::read_csv;
use robokrige::kriging::{
    Gaussian, KrigingOptions, KrigingProblem, Monomials, TrainingInputs, TrendKind, Workspace,
    independent_columns, trend_matrix,
};
use robokrige::model::ErrorModel;
use robokrige::space::{Normalizer, Space};
use std::hint::black_box;
use std::path::Path;
use std::time::Instant;

fn main() {
    let quick = std::env::args().any(|a| a == "quick");
    let data = read_csv(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .expect("shipped dataset");
    let rows = Space::Ejs.rows(&data.q, &data.dir);
    let x = Normalizer::fit(&rows).apply_rows(&rows);
    let inputs = TrainingInputs::new(&x);
    let y: Vec<f64> = data.errors.as_ref().unwrap().iter().map(|e| e[0]).collect();
    let yn = Normalizer::fit_column(&y);
    let y: Vec<f64> = y.iter().map(|v| (v - yn.mean[0]) / yn.std[0]).collect();
    let theta = vec![0.05; 12];
    println!("m = {}, d = {}", x.len(), x[0].len());
    let mut r = faer::Mat::<f64>::zeros(x.len(), x.len());
    let t0 = Instant::now();
    for _ in 0..300 {
        inputs.fill_lower(&Gaussian, black_box(&theta), 0.0, r.as_mut());
    }
    println!(
        "fill R (lower):            {:8.3} ms",
        t0.elapsed().as_secs_f64() / 300.0 * 1e3
    );
    for kind in [TrendKind::Constant, TrendKind::Linear, TrendKind::Quadratic] {
        let cand = kind.monomials(12);
        let (kept, _) = independent_columns(&trend_matrix(&cand, &x), 1e-9);
        let trend: Monomials = cand.subset(&kept);
        let f = trend_matrix(&trend, &x);
        let prob = KrigingProblem {
            min_jitter: None,
            corr: &Gaussian,
            inputs: &inputs,
            f: &f,
            y: &y,
        };
        let mut ws = Workspace::new(x.len(), f.ncols());
        let reps = 300;
        let t0 = Instant::now();
        for _ in 0..reps {
            black_box(prob.psi(black_box(&theta), 0.0, &mut ws).unwrap());
        }
        println!(
            "psi eval   {kind:?} (p = {:>2}): {:8.3} ms",
            f.ncols(),
            t0.elapsed().as_secs_f64() / reps as f64 * 1e3
        );
    }
    let q: Vec<Vec<f64>> = (0..10_000)
        .map(|k| {
            data.q[k % data.len()]
                .iter()
                .map(|v| v + 0.1 * (k / data.len()) as f64)
                .collect()
        })
        .collect();
    let dir: Vec<Vec<f64>> = (0..10_000)
        .map(|k| data.dir[k % data.len()].clone())
        .collect();
    for kind in [TrendKind::Constant, TrendKind::Linear, TrendKind::Quadratic] {
        let opts = KrigingOptions {
            trend: kind,
            ..KrigingOptions::default()
        };
        if quick {
            continue;
        }
        let t0 = Instant::now();
        let model = ErrorModel::fit(&data, Space::Ejs, &opts).unwrap();
        let fit_s = t0.elapsed().as_secs_f64();
        let evals: usize = model.reports.iter().map(|r| r.evals).sum();
        let lp: Vec<String> = model
            .reports
            .iter()
            .map(|r| format!("{:.4}", r.ln_psi))
            .collect();
        let t0 = Instant::now();
        let p = model.predict(&q, &dir).unwrap();
        black_box(p);
        println!(
            "full fit   {kind:?}: 3 outputs {fit_s:7.2} s ({evals} ψ evals, ln ψ = [{}]); predict 10 000 points x 3 outputs {:.3} s",
            lp.join(", "),
            t0.elapsed().as_secs_f64()
        );
    }
}
