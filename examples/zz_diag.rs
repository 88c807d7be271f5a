use robokrige::diagnose::{DiagnoseOptions, diagnose};
fn main() {
    let files: Vec<String> = std::env::args().skip(1).collect();
    for f in files {
        let data = robokrige::dataset::read_csv(std::path::Path::new(&f)).unwrap();
        let t0 = std::time::Instant::now();
        let d = diagnose(&data, &DiagnoseOptions::default(), &|s| eprintln!("  .. {s}")).unwrap();
        println!("== {f}: {:.1} s; before {:?} after {:?} extras {:?}", t0.elapsed().as_secs_f64(), d.before.cv_rmse_mm, d.after.cv_rmse_mm, d.after.extras);
        for e in d.effects.iter().filter(|e| e.round == 1).take(6) {
            println!("   r{} {:<45} score {:.3} expl {:.3} p {:.4} q {:.4} {:?} acc {} {:?}", e.round, e.label, e.score, e.explained, e.p_value, e.q_value, e.params, e.accepted, e.note);
        }
        for e in d.effects.iter().filter(|e| e.round > 1).take(3) {
            println!("   r{} {:<45} score {:.3} expl {:.3} p {:.4} q {:.4} {:?} acc {} {:?}", e.round, e.label, e.score, e.explained, e.p_value, e.q_value, e.params, e.accepted, e.note);
        }
    }
}
