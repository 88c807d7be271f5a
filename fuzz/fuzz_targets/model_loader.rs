//! The model loader on arbitrary text: no panic, and a model that loads
//! predicts finite values (or says why not) at a few poses.
#![no_main]

use libfuzzer_sys::fuzz_target;
use robokrige::model::ErrorModel;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    let Ok(model) = ErrorModel::from_json(text, "fuzz.json") else {
        return;
    };
    let n = model.n_joints;
    let q: Vec<Vec<f64>> = (0..3)
        .map(|k| (0..n).map(|j| 10.0 * (k as f64 - 1.0) + j as f64).collect())
        .collect();
    let dir: Vec<Vec<f64>> = (0..3).map(|k| vec![if k % 2 == 0 { 1.0 } else { -1.0 }; n]).collect();
    let Ok(data) = robokrige::dataset::Dataset::from_poses("fuzz", q, Some(dir)) else {
        return;
    };
    if let Ok(p) = model.predict_dataset(&data) {
        assert!(
            p.mean.iter().flatten().all(|v| v.is_finite()),
            "a loaded model predicted a non-finite mean"
        );
    }
    // what loads saves and loads again
    let again = model.to_json().expect("a loaded model serialises");
    ErrorModel::from_json(&again, "again.json").expect("a loaded model loads again");
});
