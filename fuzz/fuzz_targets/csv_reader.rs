//! The CSV readers on arbitrary bytes: no panic, and what reads back is
//! valid and round-trips through the writer.
#![no_main]

use libfuzzer_sys::fuzz_target;
use robokrige::dataset::{read_csv_from, write_csv_to};
use robokrige::trajectory::Trajectory;

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = read_csv_from(data, "fuzz.csv") {
        d.validate().expect("a dataset that reads is valid");
        let _ = d.warnings();
        let mut out = Vec::new();
        write_csv_to(&mut out, &d).expect("a valid dataset writes");
        let back = read_csv_from(out.as_slice(), "fuzz.csv").expect("what was written reads back");
        assert_eq!(back.q.len(), d.q.len());
        assert_eq!(back.errors, d.errors);
    }
    if let Ok(t) = Trajectory::read_csv_from(data, "fuzz.csv") {
        assert!(!t.is_empty());
        assert!(t.poses.iter().all(|p| p.translation.vector.iter().all(|v| v.is_finite())));
    }
});
