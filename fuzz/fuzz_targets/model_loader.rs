//! Fuzz the model loader: any text must give a model that predicts finite
//! values at its own training inputs' scale, or an error — never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use robokrige::model::ErrorModel;

fuzz_target!(|data: &[u8]| {
    let Ok(text) = std::str::from_utf8(data) else {
        return;
    };
    if let Ok(m) = ErrorModel::from_json(text, "fuzz.json") {
        let q = vec![vec![0.0; m.n_joints]];
        let dir = vec![vec![1.0; m.n_joints]];
        let _ = m.predict(&q, &dir);
    }
});
