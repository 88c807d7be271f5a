//! `rust_timing TRAIN.csv PREDICT.csv REPEATS`: fit the command line's
//! default model (the `recommended` settings, periodic joints "auto") on
//! TRAIN through `ErrorModelParams` and predict PREDICT with standard
//! deviations, REPEATS times; print one JSON line per repeat with the fit
//! and predict wall times (the data already in memory, as in the Python
//! timing) and a digest of the model file, to check both sides fitted the
//! same model.

use robokrige::dataset::read_csv;
use robokrige::kriging::KrigingOptions;
use robokrige::params::ErrorModelParams;
use robokrige::space::{Space, periodic_joints};
use std::time::Instant;

fn main() -> robokrige::Result<()> {
    let args: Vec<String> = std::env::args().collect();
    if args.len() != 4 {
        eprintln!("usage: rust_timing TRAIN.csv PREDICT.csv REPEATS");
        std::process::exit(2);
    }
    let train = read_csv(args[1].as_ref())?;
    let poses = read_csv(args[2].as_ref())?;
    let repeats: usize = args[3].parse().unwrap_or(1);
    for _ in 0..repeats {
        let t0 = Instant::now();
        let opts = KrigingOptions {
            corr_auto: true,
            periodic: periodic_joints(&train.q),
            ..KrigingOptions::default()
        };
        let model = ErrorModelParams::new()
            .space(Space::Ejs)
            .kriging(opts)
            .check()?
            .fit(&train)?;
        let fit = t0.elapsed().as_secs_f64();
        let t1 = Instant::now();
        let pred = model.predict_dataset(&poses)?;
        let predict = t1.elapsed().as_secs_f64();
        let json = model.to_json()?;
        // FNV-1a of the model file: equal on both sides = the same model
        let digest = json.bytes().fold(0xcbf29ce484222325u64, |h, b| {
            (h ^ u64::from(b)).wrapping_mul(0x100000001b3)
        });
        println!(
            "{{\"fit\": {fit}, \"predict\": {predict}, \"rows\": {}, \"poses\": {}, \"model_fnv\": \"{digest:016x}\", \"mean0\": {}}}",
            train.len(),
            pred.mean.len(),
            pred.mean[0][0]
        );
    }
    Ok(())
}
