//! Model files across versions. Version 3 stores the input map
//! (space, periodic joints, extras, names, normalisation) as one field,
//! `inputs`. A version-2 file written by the code before that
//! (`tests/fixtures/model_v2.json`: periodic joints, two extras) loads and
//! predicts what it predicted then, and so does its version-1 form (with the
//! Cholesky factors); a refit with today's code writes the same model in the
//! version-3 layout. "The same" is to [`REL`] relative: the correlation fill
//! uses fused multiply-adds since 2026-11-25, which moves the last
//! bits; everything else (structure, names, integers, strings) is exact.

mod common;

use robokrige::dataset::{Dataset, read_csv};
use robokrige::features::Feature;
use robokrige::kriging::{KrigingOptions, OptimizerKind};
use robokrige::model::{ErrorModel, MODEL_VERSION_UNCALIBRATED, Prediction};
use robokrige::params::ErrorModelParams;
use robokrige::space::Space;
use serde_json::{Value, json};
use std::path::Path;

fn repo(path: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(path)
}

fn fixture(name: &str) -> String {
    std::fs::read_to_string(repo("tests/fixtures").join(name)).unwrap()
}

fn verify() -> Dataset {
    read_csv(&repo("datasets/comau_verify.csv")).unwrap()
}

/// Relative agreement of numbers across code versions (a few ulp of
/// rounding, amplified by the solves).
const REL: f64 = 1e-11;

fn close(w: f64, g: f64) -> bool {
    (w - g).abs() <= REL * w.abs().max(g.abs()).max(1e-300)
}

/// Every mean and standard deviation of `model`'s prediction `p` as
/// `expected` to [`REL`] (`{"mean": [[x, y, z], …], "std": …}`). The
/// fixture's std is the √MSE of the code that wrote it; today's is that
/// MSE calibrated on the model's leave-one-out residuals
/// ([`robokrige::model::LooCheck::mean_std`]).
fn assert_close_predictions(model: &ErrorModel, p: &Prediction, expected: &Value) {
    let check = model.loo_check().unwrap();
    for (key, got) in [("mean", &p.mean), ("std", &p.std)] {
        let want: Vec<[f64; 3]> = serde_json::from_value(expected[key].clone()).unwrap();
        assert_eq!(want.len(), got.len(), "{key}");
        for (w, g) in want.iter().zip(got) {
            for a in 0..3 {
                let w = if key == "std" {
                    check.mean_std(a, w[a] * w[a])
                } else {
                    w[a]
                };
                assert!(close(w, g[a]), "{key}: {w} vs {}", g[a]);
            }
        }
    }
}

/// Two JSON documents equal in structure and every non-number, numbers to
/// [`REL`] (integers exactly).
fn assert_same_json(a: &Value, b: &Value, at: &str) {
    match (a, b) {
        (Value::Number(x), Value::Number(y)) if x.is_f64() || y.is_f64() => {
            let (x, y) = (x.as_f64().unwrap(), y.as_f64().unwrap());
            assert!(close(x, y), "{at}: {x} vs {y}");
        }
        (Value::Array(x), Value::Array(y)) => {
            assert_eq!(x.len(), y.len(), "{at}: length");
            for (i, (u, v)) in x.iter().zip(y).enumerate() {
                assert_same_json(u, v, &format!("{at}[{i}]"));
            }
        }
        (Value::Object(x), Value::Object(y)) => {
            let keys = |o: &serde_json::Map<String, Value>| o.keys().cloned().collect::<Vec<_>>();
            assert_eq!(keys(x), keys(y), "{at}: keys");
            for (k, u) in x {
                assert_same_json(u, &y[k], &format!("{at}.{k}"));
            }
        }
        _ => assert_eq!(a, b, "{at}"),
    }
}

fn expected_predictions() -> Value {
    serde_json::from_str(&fixture("model_v2.predictions.json")).unwrap()
}

#[test]
fn a_version_2_file_loads_and_predicts_as_it_did() {
    let text = fixture("model_v2.json");
    let v2: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v2["version"], 2);
    assert_eq!(v2["options"]["periodic"], json!([0, 5]));
    let model = ErrorModel::from_json(&text, "model_v2.json").unwrap();
    assert_eq!(model.version(), MODEL_VERSION_UNCALIBRATED);
    assert_eq!(model.space(), Space::Ejs);
    assert_eq!(model.periodic(), &[0, 5]);
    assert_eq!(model.input_map().periodic(), &[0, 5]);
    assert_eq!(model.extras().len(), 2);
    let names: Vec<String> = serde_json::from_value(v2["input_names"].clone()).unwrap();
    assert_eq!(model.input_names(), &names[..]);
    assert_eq!(model.input_norm().mean.len(), names.len());
    let v = verify();
    let p = model.predict(&v.q, &v.dir).unwrap();
    assert_close_predictions(&model, &p, &expected_predictions());

    // saved again: version 3, the map as one field, no periodic joints in
    // the options
    let v3_text = model.to_json().unwrap();
    let v3: Value = serde_json::from_str(&v3_text).unwrap();
    assert_eq!(v3["version"], 3);
    assert_eq!(v3["inputs"]["periodic"], json!([0, 5]));
    assert_eq!(v3["inputs"]["names"], v2["input_names"]);
    assert_eq!(v3["inputs"]["norm"], v2["input_norm"]);
    assert_eq!(v3["inputs"]["extras"], v2["extras"]);
    assert!(v3["options"].get("periodic").is_none());
    for old in ["space", "n_joints", "input_names", "input_norm", "extras"] {
        assert!(v3.get(old).is_none(), "{old} at the top level");
    }
    let back = ErrorModel::from_json(&v3_text, "model_v3.json").unwrap();
    assert_eq!(back, model);
    assert_close_predictions(
        &back,
        &back.predict(&v.q, &v.dir).unwrap(),
        &expected_predictions(),
    );
}

#[test]
fn a_version_1_file_loads_and_predicts_as_it_did() {
    // version 1 = version 2 with each output's packed lower Cholesky factor
    let text = fixture("model_v2.json");
    let model = ErrorModel::from_json(&text, "model_v2.json").unwrap();
    let v = verify();
    model.predict(&v.q, &v.dir).unwrap(); // computes the factors
    let mut v1: Value = serde_json::from_str(&text).unwrap();
    v1["version"] = 1.into();
    for (a, out) in model.outputs().iter().enumerate() {
        let (c, _, _) = out.factors().unwrap();
        let packed: Vec<f64> = (0..c.nrows())
            .flat_map(|i| (0..=i).map(move |j| (i, j)))
            .map(|(i, j)| c[(i, j)])
            .collect();
        v1["outputs"][a]["chol_lower"] = serde_json::to_value(packed).unwrap();
    }
    let v1_text = v1.to_string();
    assert!(v1_text.len() > text.len(), "v1 stores the factors");
    let old = ErrorModel::from_json(&v1_text, "model_v1.json").unwrap();
    assert_eq!(old.version(), MODEL_VERSION_UNCALIBRATED);
    assert_eq!(old.periodic(), &[0, 5]);
    assert_close_predictions(
        &old,
        &old.predict(&v.q, &v.dir).unwrap(),
        &expected_predictions(),
    );
}

#[test]
fn a_refit_with_todays_code_writes_the_same_model() {
    // the fit of the fixture (tests/fixtures/README.md), through today's API
    let data = read_csv(&repo("datasets/comau_lhs.csv")).unwrap();
    let data = data.select(&(0..40).collect::<Vec<_>>());
    let opts = KrigingOptions::default()
        .optimizer(OptimizerKind::HookeJeeves)
        .starts(4)
        .max_evals(80)
        .nugget(true);
    let refit = ErrorModelParams::new()
        .space(Space::Ejs)
        .periodic(vec![0, 5])
        .kriging(opts)
        .extras(vec![
            Feature::Harmonic {
                joint: 2,
                period_deg: 30.0,
                centre_deg: 0.0,
            },
            Feature::PreviousDirection { joint: 1 },
        ])
        .check()
        .and_then(|p| p.fit(&data))
        .unwrap();
    let loaded = ErrorModel::from_json(&fixture("model_v2.json"), "model_v2.json").unwrap();
    // the same file: only the version and the layout changed (numbers to REL)
    let as_value = |m: &ErrorModel| serde_json::from_str::<Value>(&m.to_json().unwrap()).unwrap();
    assert_same_json(&as_value(&refit), &as_value(&loaded), "model");
    let v = verify();
    assert_close_predictions(
        &refit,
        &refit.predict(&v.q, &v.dir).unwrap(),
        &expected_predictions(),
    );
}

#[test]
fn a_version_2_file_with_impossible_inputs_is_refused() {
    let text = fixture("model_v2.json");
    for (what, edit) in [
        (
            "periodic joint 9",
            Box::new(|v: &mut Value| v["options"]["periodic"] = json!([0, 8]))
                as Box<dyn Fn(&mut Value)>,
        ),
        (
            "a repeated periodic joint",
            Box::new(|v: &mut Value| v["options"]["periodic"] = json!([0, 0])),
        ),
        (
            "one name short",
            Box::new(|v: &mut Value| {
                v["input_names"].as_array_mut().unwrap().pop();
            }),
        ),
        (
            "no space",
            Box::new(|v: &mut Value| {
                v.as_object_mut().unwrap().remove("space");
            }),
        ),
    ] {
        let mut v: Value = serde_json::from_str(&text).unwrap();
        edit(&mut v);
        let e = ErrorModel::from_json(&v.to_string(), "bad_v2.json").unwrap_err();
        assert!(e.to_string().contains("bad_v2.json"), "{what}: {e}");
    }
    // in version 3 too
    let model = ErrorModel::from_json(&text, "model_v2.json").unwrap();
    let mut v: Value = serde_json::from_str(&model.to_json().unwrap()).unwrap();
    v["inputs"]["periodic"] = json!([6]);
    let e = ErrorModel::from_json(&v.to_string(), "bad_v3.json").unwrap_err();
    assert!(e.to_string().contains("periodic joint 7"), "{e}");
}

/// A closed-form CV of a model above `KEEP_FACTOR_MAX_M` rows computes its
/// factors for the CV alone (three outputs of 12 000 rows would otherwise
/// keep 3.5 GB): the same residuals as with the factors kept, and none
/// left in memory afterwards.
#[test]
fn a_large_model_does_not_keep_the_factors_of_a_closed_form_cv() {
    use robokrige::kriging::{Trend, model::KEEP_FACTOR_MAX_M};
    let m = KEEP_FACTOR_MAX_M + 1;
    let x: Vec<Vec<f64>> = (0..m).map(|i| vec![i as f64 / m as f64]).collect();
    let y: Vec<f64> = x
        .iter()
        .enumerate()
        .map(|(i, r)| (6.0 * r[0]).sin() + 0.01 * ((i * 7919 % 101) as f64 / 101.0 - 0.5))
        .collect();
    let trend = Trend::Monomials(robokrige::kriging::Monomials::constant(1));
    let model = common::fit_at(&x, &y, &trend, &[4.0], 1e-3, None).unwrap();
    assert!(!model.has_factors());
    let blocks = vec![vec![3, 1000, 4000], vec![17]];
    let transient = model.held_out(&blocks).unwrap();
    assert!(!model.has_factors());
    model.factors().unwrap();
    let kept = model.held_out(&blocks).unwrap();
    // the rows of no block stay NaN; the others agree bit for bit
    for i in [0, 3, 17, 1000, 4000] {
        let (t, k) = (transient.residuals[i], kept.residuals[i]);
        assert!(
            t.to_bits() == k.to_bits() && (i == 0) == t.is_nan(),
            "row {i}: {t} {k}"
        );
    }
    assert_eq!(transient.expected_loo_rmse, kept.expected_loo_rmse);
}

/// A harmonic whose phase is counted from a joint value other than 0 (what
/// `diagnose` adds) makes a version-5 file, which a build before that field
/// refuses instead of reading its columns from θ = 0; it loads back and
/// predicts the same. Without one, the file stays version 3.
#[test]
fn a_phase_referenced_harmonic_is_a_version_5_file() {
    let data = read_csv(&repo("datasets/comau_harmonic.csv"))
        .unwrap()
        .head(60);
    let fit = |centre_deg: f64| {
        ErrorModelParams::new()
            .space(Space::Js)
            .kriging(
                KrigingOptions::default()
                    .optimizer(OptimizerKind::HookeJeeves)
                    .max_evals(40),
            )
            .extras(vec![Feature::Harmonic {
                joint: 2,
                period_deg: 20.0,
                centre_deg,
            }])
            .check()
            .and_then(|p| p.fit(&data))
            .unwrap()
    };
    let plain = fit(0.0);
    assert_eq!(plain.version(), MODEL_VERSION_UNCALIBRATED);
    assert!(!plain.to_json().unwrap().contains("centre_deg"));
    let centred = fit(-31.25);
    assert_eq!(centred.version(), robokrige::model::MODEL_VERSION_PHASE);
    let text = centred.to_json().unwrap();
    let head: Value = serde_json::from_str(&text).unwrap();
    assert_eq!(head["version"], 5);
    assert_eq!(head["inputs"]["extras"][0]["centre_deg"], -31.25);
    let back = ErrorModel::from_json(&text, "centred.json").unwrap();
    assert_eq!(back.extras(), centred.extras());
    assert_eq!(
        back.predict(&data.q, &data.dir).unwrap().mean,
        centred.predict(&data.q, &data.dir).unwrap().mean
    );
    // a reference that is not a number is refused
    let bad = ErrorModelParams::new()
        .extras(vec![Feature::Harmonic {
            joint: 2,
            period_deg: 20.0,
            centre_deg: f64::NAN,
        }])
        .check()
        .and_then(|p| p.fit(&data));
    assert!(
        bad.as_ref()
            .is_err_and(|e| e.to_string().contains("phase reference")),
        "{:?}",
        bad.map(|_| ())
    );
    // the column names say where the phase is counted from
    assert!(
        centred
            .input_names()
            .iter()
            .any(|n| n == "sin(2π·(q2+31.25°)/20.0000°)"),
        "{:?}",
        centred.input_names()
    );
}
