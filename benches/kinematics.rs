//! Bench binary (no external harness): forward kinematics, Jacobian and
//! inverse kinematics throughput on the COMAU preset.
//! Run: `cargo bench --bench kinematics`.

use robokrige::kinematics::{IkOptions, IkTarget, preset};
use std::hint::black_box;
use std::time::Instant;

fn time<F: FnMut() -> usize>(name: &str, reps: usize, mut f: F) {
    let t0 = Instant::now();
    let mut sink = 0usize;
    for _ in 0..reps {
        sink = sink.wrapping_add(f());
    }
    let dt = t0.elapsed().as_secs_f64();
    println!(
        "{name:<32} {:>10.3} µs/op  ({reps} ops, {sink})",
        dt / reps as f64 * 1e6
    );
}

fn main() {
    let r = preset("comau-nj220").unwrap();
    let q = r.home.clone();
    time("fk (6 joints)", 200_000, || {
        black_box(r.fk_unchecked(black_box(&q))).translation.x as usize
    });
    time("jacobian (6x6)", 100_000, || {
        black_box(r.jacobian(black_box(&q)).unwrap()).ncols()
    });
    let target = IkTarget::pose(&r.fk(&[2.0, -22.0, -123.0, 1.0, -18.0, 2.0]).unwrap());
    let opts = IkOptions::default();
    time("ik from a 3° neighbour", 20_000, || {
        black_box(r.ik(&target, black_box(&q), &opts).unwrap()).len()
    });
}
