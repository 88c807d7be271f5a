//! A UR10 campaign whose tool keeps pointing down, shared by the tests of
//! the kinematic trend's conditioning and of the no-blow-up CV.

use robokrige::kinematics::{Robot, preset};
use robokrige::sim::{ErrorProfile, TrueRobot, rng_for};

/// The UR10 with the public data's TCP offset, a true robot drawn from
/// `seed`, and `m` poses (Latin hypercube from `rng_for(seed, stream)`):
/// joints 1, 2, 3, 6 over more than 180°, joint 4 = −90° − θ2 − θ3 (the
/// tool kept pointing down), joint 5 = −90° ± 3°.
pub fn ur10_tool_down(m: usize, seed: u64, stream: &str) -> (Robot, TrueRobot, Vec<Vec<f64>>) {
    let mut nominal = preset("ur10").unwrap();
    nominal.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
    let truth = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), seed);
    let ranges = [
        (-170.0, 170.0),
        (-185.0, 5.0),
        (-170.0, 170.0),
        (0.0, 0.0),
        (-93.0, -87.0),
        (-200.0, 200.0),
    ];
    let mut q = robokrige::sim::designs::lhs(&ranges, m, &mut rng_for(seed, stream));
    for r in &mut q {
        r[3] = -90.0 - r[1] - r[2];
    }
    (nominal, truth, q)
}
