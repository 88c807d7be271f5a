//! Data shared by the bench targets: the shipped COMAU campaign (m = 300,
//! d = 12 in EJS) and 10 000 probe poses around it.

use robokrige::dataset::{Dataset, read_csv};
use std::path::Path;

/// `datasets/comau_lhs.csv`.
pub fn campaign() -> Dataset {
    read_csv(Path::new(concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/datasets/comau_lhs.csv"
    )))
    .expect("shipped dataset")
}

/// 10 000 poses: the campaign's poses shifted by 0.1° per repetition, with
/// their directions.
#[allow(dead_code)]
pub fn probe_10k(data: &Dataset) -> (Vec<Vec<f64>>, Vec<Vec<f64>>) {
    let m = data.len();
    let q = (0..10_000)
        .map(|k| {
            data.q[k % m]
                .iter()
                .map(|v| v + 0.1 * (k / m) as f64)
                .collect()
        })
        .collect();
    let dir = (0..10_000).map(|k| data.dir[k % m].clone()).collect();
    (q, dir)
}
