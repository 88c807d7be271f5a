//! Bench binary for the likelihood core: for simulated COMAU
//! campaigns of m training poses (held-out: 200 uniform poses of the same
//! true robot) and the shipped campaign, the 3-output fit with the previous
//! default (GPS from 4 starts + finite-difference BFGS polish) against the
//! new default (projected BFGS on the analytic gradient), with and without a
//! nugget: wall time, peak-free evaluation counts, ln ψ per output and the
//! held-out RMS 3D error as a multiple of the noise floor
//! (`√(σx² + σy² + σz²)`, the simulator's per-axis noise RMS).
//!
//! Run: `cargo bench --bench likelihood_core -- [sizes] [--new-only]`,
//! sizes comma-separated (default `300,600,1200`).
//!
//! `-- --scale [sizes] [--old-max M]` prints the scale table instead (sizes
//! default `300,600,1200,2773,12000`): per size, fit wall time, peak
//! resident memory of the fit (`VmHWM`, reset before each fit), ψ
//! evaluations, held-out RMS 3D / floor, model file size, load time and the
//! time of the first prediction with standard deviations (the factor is
//! recomputed then); the previous GPS default beside it up to `--old-max`
//! rows (default 1200). The train/test CSVs are written to
//! `target/bench-data/` for `benches/reference_scale.py`.
//!
//! `-- --user-family [sizes]` adds, after each default fit, the same fit
//! with a user's family ([`Correlation::register`]) that forwards every call
//! to the built-in [`robokrige::kriging::Gaussian`]: what the trait-object
//! path of a family of one's own costs (same evaluations, same ln ψ; the
//! time is the measure).
//!
//! `-- --families` prints the correlation-family table instead:
//! simulated campaigns of 300 poses (robot seeds 931–932, not used
//! elsewhere; three robots) and the shipped campaign (`comau_lhs.csv`, its
//! 30 verification poses held out), each family and the family chosen by CV, with and without
//! a nugget: fit wall time and held-out RMS 3D / floor. The splits are
//! written to `target/bench-data/fam_*` for
//! `benches/reference_scale.py --families`.

use robokrige::dataset::{Dataset, read_csv};
use robokrige::kinematics;
use robokrige::kriging::{Correlation, KrigingOptions, OptimizerKind};
use robokrige::model::ErrorModel;
use robokrige::sim::campaign::{measurements, noise_floor};
use robokrige::sim::{CampaignKind, CampaignSpec, ErrorProfile, TrueRobot};
use robokrige::space::Space;
use std::path::Path;
use std::time::Instant;

/// Seed of the bench's true robot (not used by any shipped dataset).
const SEED: u64 = 901;

struct Case {
    name: String,
    train: Dataset,
    test: Option<(Dataset, f64)>,
}

fn simulated(robot_name: &str, seed: u64, m: usize) -> Case {
    let nominal = kinematics::preset(robot_name).unwrap();
    let robot = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), seed);
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, seed);
    spec.poses = m;
    let train = measurements(&robot, &spec).unwrap();
    let mut vspec = CampaignSpec::new(CampaignKind::Verify, seed);
    vspec.poses = 200;
    let test = measurements(&robot, &vspec).unwrap();
    let f = noise_floor(&robot, &test.q);
    let floor = (f[0] * f[0] + f[1] * f[1] + f[2] * f[2]).sqrt();
    Case {
        name: format!("sim {robot_name} seed {seed}, m={m}"),
        train,
        test: Some((test, floor)),
    }
}

/// The shipped campaign: `comau_lhs.csv` (300 poses) to train, the 30
/// verification poses of `comau_verify.csv` held out, the floor from its
/// truth file (the simulator's per-axis noise RMS).
fn shipped() -> Case {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("datasets");
    let train = read_csv(&root.join("comau_lhs.csv")).unwrap();
    let test = read_csv(&root.join("comau_verify.csv")).unwrap();
    let truth: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(root.join("comau_verify.truth.json")).unwrap(),
    )
    .unwrap();
    let floor = truth["noise_floor_mm"]
        .as_array()
        .unwrap()
        .iter()
        .map(|v| v.as_f64().unwrap().powi(2))
        .sum::<f64>()
        .sqrt();
    Case {
        name: "shipped comau_lhs.csv → comau_verify.csv (30)".into(),
        train,
        test: Some((test, floor)),
    }
}

fn held_out(model: &ErrorModel, test: &Dataset) -> f64 {
    let p = model.predict_dataset(test).unwrap();
    let e = test.errors.as_ref().unwrap();
    let ss: f64 = p
        .mean
        .iter()
        .zip(e)
        .map(|(a, b)| (0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>())
        .sum();
    (ss / e.len() as f64).sqrt()
}

fn run(case: &Case, label: &str, opts: &KrigingOptions) {
    let t0 = Instant::now();
    let model = ErrorModel::fit(&case.train, Space::Ejs, opts).expect("fit");
    let secs = t0.elapsed().as_secs_f64();
    let evals: usize = model.reports().iter().map(|r| r.evals).sum();
    let lp: Vec<String> = model
        .reports()
        .iter()
        .map(|r| format!("{:.4}", r.ln_psi))
        .collect();
    let ho = case.test.as_ref().map_or(String::from("-"), |(t, floor)| {
        format!("{:.2}×", held_out(&model, t) / floor)
    });
    println!(
        "| {} | {label} | {secs:.2} | {evals} | {} | {ho} |",
        case.name,
        lp.join(" / ")
    );
}

/// The Gaussian as a user's registered family: every call forwarded,
/// through a trait object, to the built-in vectorised one.
fn users_gaussian() -> Correlation {
    use robokrige::kriging::{CorrelationModel, Gaussian, TrainingInputs};
    struct Forward;
    impl CorrelationModel for Forward {
        fn corr(&self, theta: &[f64], a: &[f64], b: &[f64]) -> f64 {
            Gaussian.corr(theta, a, b)
        }
        fn fill_column(&self, theta: &[f64], x: &TrainingInputs, i: usize, out: &mut [f64]) {
            Gaussian.fill_column(theta, x, i, out)
        }
        fn gradient_weights(
            &self,
            theta: &[f64],
            x: &TrainingInputs,
            i: usize,
            r: &[f64],
            w: &mut [f64],
        ) {
            Gaussian.gradient_weights(theta, x, i, r, w)
        }
        fn fill_row(&self, theta: &[f64], x: &TrainingInputs, s: &[f64], out: &mut [f64]) {
            Gaussian.fill_row(theta, x, s, out)
        }
    }
    static FORWARD: Forward = Forward;
    Correlation::register("users-gaussian", &FORWARD).unwrap()
}

/// Peak resident memory since the last reset, bytes (Linux).
fn peak_rss() -> Option<u64> {
    let s = std::fs::read_to_string("/proc/self/status").ok()?;
    let l = s.lines().find(|l| l.starts_with("VmHWM:"))?;
    l.split_whitespace()
        .nth(1)?
        .parse::<u64>()
        .ok()
        .map(|kb| kb * 1024)
}

/// Reset the peak resident memory (Linux `clear_refs` 5).
fn reset_peak() {
    let _ = std::fs::write("/proc/self/clear_refs", "5");
}

fn scale_row(case: &Case, label: &str, opts: &KrigingOptions) {
    reset_peak();
    let t0 = Instant::now();
    let model = ErrorModel::fit(&case.train, Space::Ejs, opts).expect("fit");
    let secs = t0.elapsed().as_secs_f64();
    let peak = peak_rss().map_or("-".into(), robokrige::memory::human);
    let evals: usize = model.reports().iter().map(|r| r.evals).sum();
    let (test, floor) = case.test.as_ref().expect("simulated");
    let ho = held_out(&model, test) / floor;
    let path = std::env::temp_dir().join(format!("robokrige-scale-{}.json", std::process::id()));
    model.save(&path).unwrap();
    let size = std::fs::metadata(&path).unwrap().len();
    let t1 = Instant::now();
    let back = ErrorModel::load(&path).unwrap();
    let load = t1.elapsed().as_secs_f64();
    let t2 = Instant::now();
    back.predict(&test.q, &test.dir).unwrap();
    let first = t2.elapsed().as_secs_f64();
    std::fs::remove_file(&path).ok();
    println!(
        "| {} | {label} | {secs:.1} | {peak} | {evals} | {ho:.2}× | {} | {load:.2} | {first:.2} |",
        case.train.len(),
        robokrige::memory::human(size)
    );
}

fn scale(args: &[String]) {
    let sizes: Vec<usize> = args
        .iter()
        .find(|a| a.chars().next().is_some_and(|c| c.is_ascii_digit()))
        .map_or(vec![300, 600, 1200, 2773, 12000], |s| {
            s.split(',').map(|v| v.parse().expect("size")).collect()
        });
    let old_max: usize = args
        .iter()
        .position(|a| a == "--old-max")
        .and_then(|i| args.get(i + 1))
        .map_or(1200, |v| v.parse().expect("--old-max"));
    let dir = Path::new(concat!(env!("CARGO_MANIFEST_DIR"), "/target/bench-data"));
    std::fs::create_dir_all(dir).unwrap();
    println!(
        "| m | optimiser | fit s | peak memory | ψ evaluations | held-out RMS 3D / floor | model file | load s | first predict with std, s |"
    );
    println!("|---|---|---|---|---|---|---|---|---|");
    for m in sizes {
        let case = simulated("comau-nj220", SEED, m);
        let (test, floor) = case.test.as_ref().unwrap();
        robokrige::dataset::write_csv(&dir.join(format!("train_{m}.csv")), &case.train).unwrap();
        robokrige::dataset::write_csv(&dir.join(format!("test_{m}.csv")), test).unwrap();
        std::fs::write(dir.join(format!("floor_{m}.txt")), format!("{floor}")).unwrap();
        for nugget in [false, true] {
            let n = if nugget { " + nugget" } else { "" };
            if m <= old_max {
                let old = KrigingOptions::default()
                    .optimizer(OptimizerKind::Gps)
                    .starts(4)
                    .nugget(nugget);
                scale_row(&case, &format!("GPS + polish (previous default){n}"), &old);
            }
            let new = KrigingOptions::default().nugget(nugget);
            scale_row(&case, &format!("BFGS (new default){n}"), &new);
        }
    }
}

/// The correlation-family table (see the module docs).
fn families() {
    let dir = Path::new("target/bench-data");
    std::fs::create_dir_all(dir).unwrap();
    println!("| campaign | family | nugget | fit s | held-out RMS 3D / floor | chosen (x/y/z) |");
    println!("|---|---|---|---|---|---|");
    let cases: Vec<Case> = [
        ("comau-nj220", 931),
        ("comau-nj220", 932),
        ("kuka-kr30ha", 931),
        ("ur10", 931),
    ]
    .into_iter()
    .map(|(robot, seed)| simulated(robot, seed, 300))
    .chain(std::iter::once(shipped()))
    .collect();
    for (i, case) in cases.iter().enumerate() {
        let (test, floor) = case.test.as_ref().unwrap();
        robokrige::dataset::write_csv(&dir.join(format!("fam_{i}_train.csv")), &case.train)
            .unwrap();
        robokrige::dataset::write_csv(&dir.join(format!("fam_{i}_test.csv")), test).unwrap();
        std::fs::write(
            dir.join(format!("fam_{i}_floor.txt")),
            format!("{floor} {}", case.name),
        )
        .unwrap();
        let choices: Vec<Option<Correlation>> = Correlation::ALL
            .into_iter()
            .map(Some)
            .chain(std::iter::once(None))
            .collect();
        for nugget in [false, true] {
            for corr in &choices {
                let opts = KrigingOptions::default()
                    .corr(corr.map_or(KrigingOptions::recommended().get_corr(), Into::into))
                    .nugget(nugget);
                let t0 = Instant::now();
                let model = ErrorModel::fit(&case.train, Space::Ejs, &opts).expect("fit");
                let secs = t0.elapsed().as_secs_f64();
                let ho = held_out(&model, test) / floor;
                let chosen: Vec<String> = model
                    .outputs()
                    .iter()
                    .map(|o| o.corr().to_string())
                    .collect();
                println!(
                    "| {} | {} | {} | {secs:.2} | {ho:.2}× | {} |",
                    case.name,
                    corr.map_or("auto".to_string(), |c| c.to_string()),
                    if nugget { "yes" } else { "no" },
                    if corr.is_none() {
                        chosen.join(" / ")
                    } else {
                        String::new()
                    }
                );
            }
        }
    }
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.iter().any(|a| a == "--families") {
        families();
        return;
    }
    if args.iter().any(|a| a == "--scale") {
        scale(&args);
        return;
    }
    let user_family = args.iter().any(|a| a == "--user-family");
    let new_only = user_family || args.iter().any(|a| a == "--new-only");
    let sizes: Vec<usize> = args
        .iter()
        .find(|a| a.chars().next().is_some_and(|c| c.is_ascii_digit()))
        .map_or(vec![300, 600, 1200], |s| {
            s.split(',').map(|v| v.parse().expect("size")).collect()
        });
    let mut cases = vec![Case {
        name: "comau_lhs.csv (300)".into(),
        train: read_csv(Path::new(concat!(
            env!("CARGO_MANIFEST_DIR"),
            "/datasets/comau_lhs.csv"
        )))
        .unwrap(),
        test: None,
    }];
    if !args.iter().any(|a| a == "--sizes-only") {
        for (robot, seed) in [
            ("comau-nj220", SEED + 1),
            ("comau-nj220", SEED + 2),
            ("kuka-kr30ha", SEED),
            ("ur10", SEED),
        ] {
            cases.push(simulated(robot, seed, 300));
        }
    }
    cases.extend(sizes.iter().map(|&m| simulated("comau-nj220", SEED, m)));
    println!(
        "| campaign | optimiser | fit s | evaluations | ln ψ x / y / z | held-out RMS 3D / floor |"
    );
    println!("|---|---|---|---|---|---|");
    for case in &cases {
        for nugget in [false, true] {
            let n = if nugget { " + nugget" } else { "" };
            if !new_only {
                let old = KrigingOptions::default()
                    .optimizer(OptimizerKind::Gps)
                    .starts(4)
                    .nugget(nugget);
                run(case, &format!("GPS + polish{n}"), &old);
            }
            let new = KrigingOptions::default().nugget(nugget);
            run(case, &format!("BFGS (gradient){n}"), &new);
            if user_family {
                run(
                    case,
                    &format!("BFGS, user's Gaussian{n}"),
                    &new.corr(users_gaussian()),
                );
            }
        }
    }
}
