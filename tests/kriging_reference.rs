//! Universal Kriging against SMT 2.15 KRG and a long-double evaluation of the
//! DACE formulas (`tests/fixtures/kriging_smt.json`, made by
//! `tests/fixtures/gen_kriging_fixtures.py`; see `tests/fixtures/README.md`).
//!
//! 1. At the same fixed ξ: predictions and MSE at the 30 verification poses
//!    agree with the reference to 1e-8 relative, ψ to 1e-10.
//! 2. At SMT's optimum ξ our ψ equals SMT's, and our own optimiser finds a ψ
//!    as good (to 2e-8 relative) or better for every output.

mod common;

use robokrige::dataset::{Dataset, read_csv};
use robokrige::kriging::{KrigingOptions, TrendKind};
use robokrige::space::{Normalizer, Space};
use serde_json::Value;
use std::path::Path;

fn root(p: &str) -> String {
    format!("{}/{p}", env!("CARGO_MANIFEST_DIR"))
}

fn fixture() -> Value {
    let text = std::fs::read_to_string(root("tests/fixtures/kriging_smt.json")).unwrap();
    serde_json::from_str(&text).unwrap()
}

fn f64s(v: &Value) -> Vec<f64> {
    v.as_array()
        .unwrap()
        .iter()
        .map(|x| x.as_f64().unwrap())
        .collect()
}

struct Setup {
    x: Vec<Vec<f64>>,
    xv: Vec<Vec<f64>>,
    train: Dataset,
}

fn setup(space: Space, fx: &Value) -> Setup {
    let train = read_csv(Path::new(&root("datasets/comau_lhs.csv"))).unwrap();
    let verify = read_csv(Path::new(&root("datasets/comau_verify.csv"))).unwrap();
    let rows = space.rows(&train.q, &train.dir);
    let norm = Normalizer::fit(&rows);
    let key = if space == Space::Ejs { "ejs" } else { "js" };
    let (m_ref, s_ref) = (
        f64s(&fx["normalisation"][key]["x_mean"]),
        f64s(&fx["normalisation"][key]["x_std"]),
    );
    for k in 0..m_ref.len() {
        assert!(
            (norm.mean[k] - m_ref[k]).abs() <= 1e-12 * (1.0 + m_ref[k].abs()),
            "x mean {k}"
        );
        assert!(
            (norm.std[k] - s_ref[k]).abs() <= 1e-12 * s_ref[k],
            "x std {k}"
        );
    }
    Setup {
        x: norm.apply_rows(&rows),
        xv: norm.apply_rows(&space.rows(&verify.q, &verify.dir)),
        train,
    }
}

impl Setup {
    /// Training response of output `axis` (mm).
    fn axis(&self, axis: usize) -> Vec<f64> {
        self.train
            .errors
            .as_ref()
            .unwrap()
            .iter()
            .map(|e| e[axis])
            .collect()
    }
}

fn parse_case(c: &Value) -> (Space, TrendKind, usize) {
    let space = if c["space"] == "ejs" {
        Space::Ejs
    } else {
        Space::Js
    };
    let trend = match c["trend"].as_str().unwrap() {
        "constant" => TrendKind::Constant,
        "linear" => TrendKind::Linear,
        _ => TrendKind::Quadratic,
    };
    let axis = ["ex", "ey", "ez"]
        .iter()
        .position(|a| c["output"] == *a)
        .unwrap();
    (space, trend, axis)
}

fn rel(a: f64, b: f64, floor: f64) -> f64 {
    (a - b).abs() / b.abs().max(floor)
}

#[test]
fn same_fixed_theta_same_predictions_mse_and_psi() {
    let fx = fixture();
    let cases = fx["fixed_theta"]["cases"].as_array().unwrap();
    assert_eq!(cases.len(), 15);
    let mut worst = std::collections::BTreeMap::<String, (f64, f64, f64)>::new();
    for c in cases {
        let (space, trend, axis) = parse_case(c);
        let s = setup(space, &fx);
        let y = s.axis(axis);
        let theta = f64s(&c["theta"]);
        let d = space.dim(6);
        // the same R as the reference: its diagonal is 1 + SMT's nugget (100·eps)
        let model = common::fit_at(
            &s.x,
            &y,
            &trend.trend(d),
            &theta,
            0.0,
            Some(ref_nugget(&fx)),
        )
        .unwrap();
        let pred = model.predict(&s.xv).unwrap();
        let (mean_ref, mse_ref) = (f64s(&c["verify"]["mean"]), f64s(&c["verify"]["mse"]));
        // 1e-8, or where R is so ill-conditioned that no float64 code gets
        // there (js: cond(R) = 2.8e8; SMT and numpy are off by 2–4e-8) the
        // generator's float64-vs-long-double spread ×10
        let tol = |key: &str| c["suggested_tolerance"][key].as_f64().unwrap().max(1e-8);
        let (tm, ts) = (tol("mean_rel"), tol("mse_rel"));
        let w = worst
            .entry(c["space"].as_str().unwrap().to_string())
            .or_insert((0.0, 0.0, 0.0));
        for (k, p) in pred.iter().enumerate() {
            let (em, es) = (rel(p.mean, mean_ref[k], 1e-3), rel(p.mse, mse_ref[k], 0.0));
            w.0 = w.0.max(em);
            w.1 = w.1.max(es);
            assert!(
                em < tm,
                "{c_id}: mean at verify {k}: {} vs {} ({em:e} > {tm:e})",
                p.mean,
                mean_ref[k],
                c_id = id(c)
            );
            assert!(
                es < ts,
                "{c_id}: mse at verify {k}: {} vs {} ({es:e} > {ts:e})",
                p.mse,
                mse_ref[k],
                c_id = id(c)
            );
        }
        // ψ: 1e-10, or the generator's float64-vs-long-double spread ×10 where
        // R is worse conditioned (js: cond(R) ≈ 3e8)
        let ep = rel(model.data().ln_psi().exp(), c["psi"].as_f64().unwrap(), 0.0);
        let tol = c["suggested_tolerance"]["psi_rel"]
            .as_f64()
            .unwrap()
            .max(1e-10);
        w.2 = w.2.max(ep);
        assert!(
            ep < tol,
            "{}: psi {} vs {} (tol {tol:e})",
            id(c),
            model.data().ln_psi().exp(),
            c["psi"]
        );
    }
    for (space, w) in &worst {
        eprintln!(
            "{space}: worst relative disagreement with the long-double reference: mean {:.1e}, mse {:.1e}, psi {:.1e}",
            w.0, w.1, w.2
        );
    }
    // the well-conditioned space meets 1e-8 outright
    assert!(worst["ejs"].0 < 1e-8 && worst["ejs"].1 < 1e-8);
}

/// Largest accepted ψ_ours/ψ_SMT − 1, the default optimiser without a
/// nugget (SMT's model). Measured 2026-11-25 with the BFGS default:
/// +8e-11…+1.0e-9 on the six EJS cases (the same optimum to the line
/// search's tolerance), −0.5…−1.7 % on js-quadratic (a better optimum:
/// SMT's box caps ξ at 20). With the GPS + BFGS polish default before it:
/// −3e-12…+1.3e-8 on EJS (one ξ on the 1e-6 bound, where the polish
/// freezes it). With the nugget the default estimates, ψ is lower by
/// 25–54 % on EJS: a larger model, not a better search.
const PSI_GAP: f64 = 2e-8;

fn ref_nugget(fx: &Value) -> f64 {
    fx["conventions"]["nugget"].as_f64().unwrap()
}

fn id(c: &Value) -> String {
    format!("{}/{}/{}", c["space"], c["trend"], c["output"])
}

#[test]
fn our_optimiser_finds_psi_at_least_as_good_as_smt() {
    let fx = fixture();
    let mut worst = f64::NEG_INFINITY;
    for c in fx["optimum"]["cases"].as_array().unwrap() {
        let (space, trend, axis) = parse_case(c);
        let s = setup(space, &fx);
        let y = s.axis(axis);
        let monos = trend.trend(space.dim(6));
        let psi_smt = c["psi"].as_f64().unwrap();
        // our ψ at SMT's ξ is SMT's ψ
        let at_smt = common::fit_at(
            &s.x,
            &y,
            &monos,
            &f64s(&c["theta"]),
            0.0,
            Some(ref_nugget(&fx)),
        )
        .unwrap();
        assert!(
            rel(at_smt.data().ln_psi().exp(), psi_smt, 0.0) < 1e-9,
            "{}: ψ at SMT's ξ",
            id(c)
        );
        // our optimiser does at least as well
        // the same diagonal as SMT (its nugget 100·eps) so ψ values compare exactly
        // and SMT's model class: interpolating (the default estimates a
        // nugget, a larger model whose ψ is lower by construction)
        let opts = KrigingOptions::default()
            .trend(trend)
            .nugget(false)
            .min_jitter(Some(ref_nugget(&fx)));
        let (_, report) = common::fit_searched(&s.x, &y, &monos, &opts).unwrap();
        let ours = report.ln_psi.exp();
        let gap = ours / psi_smt - 1.0;
        eprintln!(
            "{}: ψ ours {ours:.10} SMT {psi_smt:.10} (ours/SMT − 1 = {gap:+.1e}; {} evals)",
            id(c),
            report.evals
        );
        worst = worst.max(gap);
    }
    assert!(
        worst <= PSI_GAP,
        "ψ worse than SMT's by {worst:e} (relative)"
    );
}
