//! Fuzz the measurement CSV reader: any bytes must give a dataset that
//! validates and writes back, or an error — never a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;
use robokrige::dataset::{read_csv_from, write_csv_to};

fuzz_target!(|data: &[u8]| {
    if let Ok(d) = read_csv_from(data, "fuzz.csv") {
        d.validate().expect("a dataset the reader accepts is valid");
        let mut out = Vec::new();
        write_csv_to(&mut out, &d).expect("a valid dataset writes");
        let back = read_csv_from(out.as_slice(), "back.csv").expect("what we write reads back");
        assert_eq!(back.len(), d.len());
    }
});
