//! Bench binary: iterative compensation (seed 004 eqs 18–22) of a 10 000-point
//! trajectory (a Ø100 mm circle around the COMAU home pose, 0.036° per point)
//! with an EJS model of the shipped campaign; also the single step.
//! Prints the median of 5 runs. Run: `cargo bench --bench compensation`.

mod common;

use robokrige::compensate::{CompensationOptions, compensate};
use robokrige::kinematics;
use robokrige::kriging::KrigingOptions;
use robokrige::model::ErrorModel;
use robokrige::sim::designs::circle;
use robokrige::space::Space;
use std::time::Instant;

fn main() {
    let data = common::campaign();
    let model = ErrorModel::fit(&data, Space::Ejs, &KrigingOptions::default()).expect("fit");
    let robot = kinematics::preset("comau-nj220").expect("preset");
    let traj = circle(&robot, 100.0, 10_000).expect("circle");
    for iterative in [false, true] {
        let opts = CompensationOptions {
            iterative,
            max_iter: std::env::var("MAX_ITER")
                .ok()
                .and_then(|v| v.parse().ok())
                .unwrap_or(10),
            ..CompensationOptions::default()
        };
        let mut times = Vec::new();
        let mut last = None;
        for _ in 0..5 {
            let t0 = Instant::now();
            let c = compensate(&robot, &model, &traj, &opts).expect("compensate");
            times.push(t0.elapsed().as_secs_f64());
            last = Some(c);
        }
        times.sort_by(f64::total_cmp);
        let c = last.expect("ran");
        println!(
            "{} compensation of {} points: median {:.3} s (min {:.3}, max {:.3}); {} iterations, stop {:?}, final RMSE of the change {:.2e} mm, λ flips per iteration {:?}",
            if iterative {
                "iterative"
            } else {
                "single-step"
            },
            traj.len(),
            times[2],
            times[0],
            times[4],
            c.history.len(),
            c.stop,
            c.history.last().map_or(0.0, |h| h.rmse_change_mm),
            c.history
                .iter()
                .map(|h| h.direction_flips)
                .collect::<Vec<_>>()
        );
    }
}
