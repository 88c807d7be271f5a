//! Bench binary: `diagnose` on real UR10 campaigns (IPA series B and C,
//! read from `../shared/data/ipa-ur10/`, never copied into the repository)
//! with known effects planted at seeded random rows, directions, joints,
//! periods and sizes ([`plant`]), each scored against the diagnosis of the
//! same campaign without it ([`score`]).
//!
//! Run: `cargo bench --bench plant_real -- [--series b|c|b,c] [--rows N]
//! [--plants N] [--seed S] [--sizes 1,2] [--kinds step,block,drift,lag,harmonic]
//! [--minutes M] [--no-calibrate] [--json DIR] [--max-effects N]`. Defaults: both series, all rows, 20
//! plants (the kinds in turn), seed 1, sizes 1 and 2, every kind, no time
//! limit (`--minutes`: no plant starts after M minutes; the table has what
//! ran; `--json DIR`: each diagnosis's JSON written there, as
//! `<series>-control.json` and `<series>-<plant>-<size>x.json`, `-raw`
//! before `.json` with `--no-calibrate`).
//!
//! `diagnose` runs as `robokrige diagnose FILE --robot ur10 --tool
//! -0.14,0.30,92.82` would: the library entry point with the CLI's
//! defaults, so on the residual of the campaign's D-H calibration
//! (`--no-calibrate`: on the raw error). Plants go into the measured
//! errors, before the calibration.
//! The size unit is the pooled CV RMSE of that default model on the
//! unplanted campaign (the control's "before"), computed once per series.

mod plant;
mod score;

use plant::KINDS;
use robokrige::dataset::{Dataset, read_csv};
use robokrige::diagnose::{DiagnoseOptions, Diagnosis, base_params, fit_with_effects};
use robokrige::study::diagnosis::DiagnosisBase;
use score::Outcome;
use std::path::PathBuf;
use std::time::Instant;

const DATA: &str = concat!(env!("CARGO_MANIFEST_DIR"), "/../shared/data/ipa-ur10");
const TOOL: &str = "-0.14,0.30,92.82";

struct Args {
    series: Vec<char>,
    rows: Option<usize>,
    plants: usize,
    seed: u64,
    sizes: Vec<f64>,
    kinds: Vec<String>,
    minutes: Option<f64>,
    /// `Some(false)` with `--no-calibrate`, else the CLI's default.
    calibrate: Option<bool>,
    /// Where each diagnosis's JSON is written (`--json DIR`).
    json: Option<PathBuf>,
    /// `--max-effects N` (else the CLI's default).
    max_effects: Option<usize>,
}

fn list<T: std::str::FromStr>(s: &str) -> Vec<T> {
    s.split(',')
        .map(|v| {
            v.trim()
                .parse()
                .unwrap_or_else(|_| panic!("bad list item {v}"))
        })
        .collect()
}

fn args() -> Args {
    let mut a = Args {
        series: vec!['b', 'c'],
        rows: None,
        plants: 20,
        seed: 1,
        sizes: vec![1.0, 2.0],
        kinds: KINDS.iter().map(|k| k.to_string()).collect(),
        minutes: None,
        calibrate: None,
        json: None,
        max_effects: None,
    };
    let argv: Vec<String> = std::env::args().skip(1).collect();
    let mut it = argv.iter();
    while let Some(k) = it.next() {
        if k == "--bench" {
            continue;
        }
        let mut v = || {
            it.next()
                .unwrap_or_else(|| panic!("{k} needs a value"))
                .clone()
        };
        match k.as_str() {
            "--series" => {
                a.series = v()
                    .split(',')
                    .filter_map(|s| s.trim().chars().next())
                    .collect()
            }
            "--rows" => a.rows = Some(v().parse().expect("--rows N")),
            "--plants" => a.plants = v().parse().expect("--plants N"),
            "--seed" => a.seed = v().parse().expect("--seed S"),
            "--sizes" => a.sizes = list(&v()),
            "--kinds" => a.kinds = list(&v()),
            "--minutes" => a.minutes = Some(v().parse().expect("--minutes M")),
            "--no-calibrate" => a.calibrate = Some(false),
            "--json" => a.json = Some(PathBuf::from(v())),
            "--max-effects" => a.max_effects = Some(v().parse().expect("--max-effects N")),
            other => panic!("unknown option {other}"),
        }
    }
    for k in &a.kinds {
        assert!(
            KINDS.contains(&k.as_str()),
            "unknown kind {k} (one of {KINDS:?})"
        );
    }
    a
}

/// Write `d` as `<name>.json` in the `--json` directory, if any.
fn save(a: &Args, name: &str, d: &Diagnosis) {
    if let Some(dir) = &a.json {
        std::fs::create_dir_all(dir).expect("--json directory");
        let text = serde_json::to_string_pretty(d).expect("diagnosis JSON");
        let raw = if a.calibrate == Some(false) {
            "-raw"
        } else {
            ""
        };
        std::fs::write(dir.join(format!("{name}{raw}.json")), text).expect("writing the JSON");
    }
}

fn file(series: char) -> PathBuf {
    let name = match series {
        'b' => "series_b_joint_configurations.csv",
        'c' => "series_c_random_poses.csv",
        s => panic!("unknown series {s} (b or c)"),
    };
    PathBuf::from(DATA).join(name)
}

/// What `robokrige diagnose FILE --robot ur10 --tool …` runs with.
fn options(data: &Dataset, max_effects: Option<usize>) -> DiagnoseOptions {
    let robot = robokrige::kinematics::load_robot_with_tool("ur10", Some(TOOL)).expect("ur10");
    let o = DiagnoseOptions::default()
        .base(&base_params("ejs", 1, true).expect("ejs"))
        .periodic(robokrige::space::parse_periodic("none", &data.q).expect("none"))
        .robot(Some(robot));
    match max_effects {
        Some(n) => o.max_effects(n),
        None => o,
    }
}

/// The diagnosis of `data` as the CLI runs it: on the residual of its
/// calibration unless `calibrate` is `Some(false)`. Returns the rows
/// diagnosed too.
fn run(data: &Dataset, o: &DiagnoseOptions, calibrate: Option<bool>) -> (Diagnosis, Dataset) {
    let base = DiagnosisBase::new(data.clone(), o, calibrate).expect("calibration");
    let d = base.diagnose(o, &|_| {}).expect("diagnose");
    (d, base.data)
}

fn added(d: &Diagnosis) -> String {
    let a: Vec<String> = d
        .effects
        .iter()
        .filter(|e| e.accepted)
        .map(score::with_params)
        .collect();
    if a.is_empty() {
        "nothing".into()
    } else {
        a.join("; ")
    }
}

/// One scored plant.
struct Row {
    kind: &'static str,
    size: f64,
    score: score::Score,
    seconds: f64,
}

fn main() {
    let a = args();
    let t0 = Instant::now();
    for &s in &a.series {
        let path = file(s);
        if !path.exists() {
            println!("series {s}: {} not found, skipped", path.display());
            continue;
        }
        let data = read_csv(&path)
            .expect("csv")
            .head(a.rows.unwrap_or(usize::MAX));
        let m = data.len();
        let o = options(&data, a.max_effects);
        let robot = o.get_robot().expect("robot").clone();
        let (control, control_rows) = run(&data, &o, a.calibrate);
        save(&a, &format!("{s}-control"), &control);
        let sigma = control.before.cv_rmse_mm;
        let pooled = control.before.pooled_rmse_mm;
        println!(
            "\n## series {s}, {m} rows, seed {}, {}: control {:.0} s, CV RMSE {:.4}/{:.4}/{:.4} mm (pooled {pooled:.4}); control added: {}",
            a.seed,
            if a.calibrate == Some(false) {
                "raw error"
            } else {
                "calibrated base"
            },
            control.seconds,
            sigma[0],
            sigma[1],
            sigma[2],
            added(&control)
        );
        if let Some(text) = control.order_in_joint_space.as_ref().and_then(|o| o.text()) {
            println!("control's note on the order: {text}");
        }
        let temp_varies = data.covariate("temp_c").is_some_and(|c| {
            let (lo, hi) = c
                .values
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), v| {
                    (l.min(*v), h.max(*v))
                });
            hi - lo > 0.05
        });
        let kinds: Vec<&str> = a
            .kinds
            .iter()
            .map(String::as_str)
            .filter(|k| {
                let keep = *k != "drift" || temp_varies;
                if !keep {
                    println!("drift skipped: temp_c does not vary on these rows");
                }
                keep
            })
            .collect();
        let mut rng = robokrige::stats::rng_for(a.seed, &format!("plant-real-{s}"));
        let mut rows: Vec<Row> = Vec::new();
        'plants: for i in 0..a.plants {
            let shape = plant::draw(kinds[i % kinds.len()], &data, sigma, &mut rng);
            for &k in &a.sizes {
                if a.minutes
                    .is_some_and(|mm| t0.elapsed().as_secs_f64() > 60.0 * mm)
                {
                    println!("time limit reached after {i} plants");
                    break 'plants;
                }
                let p = plant::at_size(&shape, &data, &robot, k, pooled);
                let (d, _) = run(&plant::apply(&data, &p), &o, a.calibrate);
                let own = |t: &[score::Target]| own_coefficients(&control_rows, &o, &d, t);
                let sc = score::score(&d, &control, (&shape, &p), m, &own);
                println!(
                    "plant {i:>2} {k}× {:<26} {:<10}{}{}{}{} row cov {:<5} coef cov {:<5} (+own {:<5}) {:>4.0} s  new: {}",
                    shape.describe(),
                    format!("{:?}", sc.outcome),
                    if sc.left_by_cap {
                        " (left by the cap)"
                    } else {
                        ""
                    },
                    if sc.outcome == Outcome::Proxy && !sc.seen {
                        " (never significant)"
                    } else {
                        ""
                    },
                    if sc.own_only { " (own only)" } else { "" },
                    if sc.by_order_note {
                        " (by the order note)"
                    } else {
                        ""
                    },
                    opt(sc.row_covered),
                    opt(sc.coef_covered.as_ref().map(|v| v.iter().all(|b| *b))),
                    opt(sc.own_covered.as_ref().map(|v| v.iter().all(|b| *b))),
                    d.seconds,
                    if sc.added.is_empty() {
                        "nothing".into()
                    } else {
                        sc.added.join("; ")
                    }
                );
                save(&a, &format!("{s}-{i}-{k}x"), &d);
                println!("           all added: {}", added(&d));
                println!("           planted family: {}", score::trace(&d, &shape, m));
                if !sc.detail.is_empty() {
                    println!("           found: {}", sc.detail);
                }
                rows.push(Row {
                    kind: shape.kind(),
                    size: k,
                    score: sc,
                    seconds: d.seconds,
                });
            }
        }
        table(s, m, &a.sizes, &rows);
    }
}

/// The unplanted campaign's coefficients of `targets` (`data`: its rows as
/// diagnosed, the calibration residual by default) when it is fitted
/// with the planted diagnosis's final effects.
fn own_coefficients(
    data: &Dataset,
    o: &DiagnoseOptions,
    d: &Diagnosis,
    targets: &[score::Target],
) -> Option<Vec<f64>> {
    let model = fit_with_effects(data, &o.for_rows(data.len()), &d.extras).ok()?;
    targets
        .iter()
        .map(|(column, a, _)| model.trend_coefficient(column).map(|c| c[*a].0))
        .collect()
}

fn opt(b: Option<bool>) -> &'static str {
    match b {
        Some(true) => "yes",
        Some(false) => "no",
        None => "–",
    }
}

fn frac(x: usize, n: usize) -> String {
    if n == 0 {
        "–".into()
    } else {
        format!("{x}/{n}")
    }
}

/// Per size: one line per kind and the total, counts and rates.
fn table(s: char, m: usize, sizes: &[f64], rows: &[Row]) {
    for &k in sizes {
        println!(
            "\nseries {s}, {m} rows, size {k}× the CV noise (row tolerance {} rows)\n",
            score::tolerance(m)
        );
        println!(
            "| kind | plants | right | proxy, named | (of which by the order note alone) | proxy, not named | (of which the planted family never significant) | (proxies, named or not, that added only effects the control found significant) | missed | not right, listed as left by the cap | row / period / τ interval covers | coefficient intervals cover (plant: all axes) | (per axis) | (per axis, planted + campaign's own) | s / diagnose |"
        );
        println!("|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|");
        let mut kinds: Vec<&str> = rows.iter().map(|r| r.kind).collect();
        kinds.dedup();
        kinds.sort();
        kinds.dedup();
        kinds.push("all");
        for kind in kinds {
            let sel: Vec<&Row> = rows
                .iter()
                .filter(|r| r.size == k && (kind == "all" || r.kind == kind))
                .collect();
            let n = sel.len();
            let count = |o: Outcome| sel.iter().filter(|r| r.score.outcome == o).count();
            let cov = |f: fn(&score::Score) -> Option<bool>| {
                let v: Vec<bool> = sel.iter().filter_map(|r| f(&r.score)).collect();
                frac(v.iter().filter(|b| **b).count(), v.len())
            };
            let pct = |x: usize| {
                if n == 0 {
                    "–".into()
                } else {
                    format!("{x} ({:.0} %)", 100.0 * x as f64 / n as f64)
                }
            };
            let secs = sel.iter().map(|r| r.seconds).sum::<f64>() / n.max(1) as f64;
            println!(
                "| {kind} | {n} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {secs:.0} |",
                pct(count(Outcome::Right)),
                pct(count(Outcome::ProxyNamed)),
                sel.iter().filter(|r| r.score.by_order_note).count(),
                pct(count(Outcome::Proxy)),
                sel.iter()
                    .filter(|r| r.score.outcome == Outcome::Proxy && !r.score.seen)
                    .count(),
                sel.iter().filter(|r| r.score.own_only).count(),
                pct(count(Outcome::Missed)),
                pct(sel.iter().filter(|r| r.score.left_by_cap).count()),
                cov(|s| s.row_covered),
                cov(|s| s.coef_covered.as_ref().map(|v| v.iter().all(|b| *b))),
                frac(
                    sel.iter()
                        .flat_map(|r| r.score.coef_covered.iter().flatten())
                        .filter(|b| **b)
                        .count(),
                    sel.iter()
                        .flat_map(|r| r.score.coef_covered.iter().flatten())
                        .count(),
                ),
                frac(
                    sel.iter()
                        .flat_map(|r| r.score.own_covered.iter().flatten())
                        .filter(|b| **b)
                        .count(),
                    sel.iter()
                        .flat_map(|r| r.score.own_covered.iter().flatten())
                        .count(),
                ),
            );
        }
    }
}
