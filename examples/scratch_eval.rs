use faer::Mat;
use robokrige::kriging::*;
fn main() {
    let m: usize = std::env::args().nth(1).unwrap().parse().unwrap();
    let d = 12;
    let rows: Vec<Vec<f64>> = (0..m)
        .map(|i| {
            (0..d)
                .map(|k| ((i * (k + 3)) as f64 * 0.618).sin())
                .collect()
        })
        .collect();
    let inputs = TrainingInputs::new(&rows);
    let f = Mat::<f64>::from_fn(m, 1, |_, _| 1.0);
    let y: Vec<f64> = (0..m).map(|i| (i as f64 * 0.1).sin()).collect();
    let prob = KrigingProblem {
        min_jitter: None,
        corr: &Gaussian,
        inputs: &inputs,
        f: &f,
        y: &y,
    };
    let mut ws = Workspace::new(m, 1);
    let theta = vec![0.3; d];
    let t = std::time::Instant::now();
    for _ in 0..3 {
        prob.psi(&theta, 1e-3, &mut ws).unwrap();
    }
    println!("psi {:.3} s", t.elapsed().as_secs_f64() / 3.0);
    let mut g = vec![0.0; d + 1];
    let t = std::time::Instant::now();
    for _ in 0..3 {
        prob.psi_grad(&theta, 1e-3, &mut ws, &mut g).unwrap();
    }
    println!("psi_grad {:.3} s", t.elapsed().as_secs_f64() / 3.0);
}
