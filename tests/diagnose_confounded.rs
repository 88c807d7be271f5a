//! `diagnose` where a real-like order drift confounds a tracker step:
//! the report either adds the step with a row interval that
//! covers it, or names step and drift as not separable on this campaign.
//! The step's row, its direction and size, and the drift's are seeded
//! random draws (no round fraction of the campaign a grid could favour).

mod common;

use rand::RngExt;
use robokrige::dataset::Dataset;
use robokrige::diagnose::{DiagnoseOptions, Diagnosis, EffectReport, diagnose};
use robokrige::features::Feature;
use robokrige::kinematics;
use robokrige::sim::{CampaignKind, CampaignSpec, SimOutput, simulate};
use robokrige::stats::rng_for;

const STEP: &str = "step in the measurement order";
const DRIFT: &str = "drift over the measurement order";

/// A direction of norm `size` (mm), normal per axis.
fn direction(rng: &mut rand::rngs::StdRng, size: f64) -> [f64; 3] {
    let v: [f64; 3] = std::array::from_fn(|_| rng.random_range(-1.0..1.0));
    let n = v.iter().map(|x| x * x).sum::<f64>().sqrt().max(1e-9);
    v.map(|x| size * x / n)
}

/// A simulated campaign of `m` rows with a warm-up-like drift over the
/// order (saturating, as a robot's slow changes) and a step at a random
/// row of the middle 80 %; returns it and the step's row.
fn planted(m: usize, seed: u64) -> (Dataset, usize) {
    let robot = kinematics::preset("comau-nj220").unwrap();
    let mut spec = CampaignSpec::new(CampaignKind::Lhs, seed);
    spec.poses = m;
    let SimOutput::Measurements(mut data) = simulate(&robot, &spec).unwrap().0 else {
        unreachable!()
    };
    let mut rng = rng_for(seed, "diagnose-confounded");
    let row = rng.random_range(m / 10..m - m / 10);
    let (step_mm, drift_mm) = (rng.random_range(0.10..0.16), rng.random_range(0.12..0.25));
    let step = direction(&mut rng, step_mm);
    let drift = direction(&mut rng, drift_mm);
    let tau = rng.random_range(0.2..0.6) * m as f64;
    let errors = data
        .errors
        .as_mut()
        .expect("a simulated campaign has errors");
    for (i, e) in errors.iter_mut().enumerate() {
        let warm = 1.0 - (-(i as f64) / tau).exp();
        for a in 0..3 {
            e[a] += drift[a] * warm + if i >= row { step[a] } else { 0.0 };
        }
    }
    (data, row)
}

fn options() -> DiagnoseOptions {
    common::quick_diagnose()
}

fn names(e: &EffectReport, family: &str) -> bool {
    e.confounded_with.iter().any(|c| c.starts_with(family))
}

/// The step added with a row interval that covers `row`, or step and drift
/// named together as not separable.
fn step_or_not_separable(d: &Diagnosis, row: usize) -> Result<String, String> {
    let added: Vec<&EffectReport> = d.effects.iter().filter(|e| e.accepted).collect();
    for e in &added {
        // a step, or a block of rows (two steps) with the step as the edge
        // nearest to it
        let steps = e.add.iter().any(|f| matches!(f, Feature::Step { .. }));
        let nearest = ["row", "from_row", "to_row"]
            .into_iter()
            .filter_map(|k| Some((k, e.params.get(k)?, e.params_ci.get(k)?)))
            .min_by(|a, b| {
                (a.1 - row as f64)
                    .abs()
                    .total_cmp(&(b.1 - row as f64).abs())
            });
        if let Some((key, _, ci)) = nearest.filter(|_| steps)
            && ci[0] <= row as f64
            && row as f64 <= ci[1]
        {
            return Ok(format!("{} added, 95 % {key} {ci:?} covers {row}", e.label));
        }
        if steps && names(e, DRIFT) {
            return Ok(format!("{} named not separable from the drift", e.label));
        }
        if e.label == DRIFT && names(e, STEP) {
            return Ok("drift added, named not separable from the step".into());
        }
    }
    Err(format!(
        "planted step at row {row}; added: {:?}",
        added
            .iter()
            .map(|e| (&e.label, &e.params, &e.params_ci, &e.confounded_with))
            .collect::<Vec<_>>()
    ))
}

#[test]
fn a_step_confounded_by_an_order_drift_is_added_with_its_row_or_named_not_separable() {
    for seed in [3, 8] {
        let (data, row) = planted(300, seed);
        let d = diagnose(&data, &options(), &|_| {}).unwrap();
        let names = robokrige::report::diagnose::Names {
            data: std::path::Path::new("planted"),
            method: "ejs",
        };
        eprintln!("{}", robokrige::report::diagnose::summary(&d, names));
        match step_or_not_separable(&d, row) {
            Ok(how) => eprintln!("seed {seed}: {how}"),
            Err(why) => panic!("seed {seed}: {why}"),
        }
    }
}
