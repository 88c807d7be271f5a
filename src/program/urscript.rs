//! Universal Robots URScript: one function, a `movej` per pose in radians.
//!
//! ```text
//! def robokrige_plan():
//!   # written by robokrige: 2 moves (1 measured, 1 via); joints in rad
//!   # via
//!   movej([0.0, -1.570796326795, 1.570796326795, 0.0, 0.785398163397, 0.0], a=0.5, v=0.25)
//!   # measure 0
//!   movej([…], a=0.5, v=0.25)
//!   sleep(2.0)
//! end
//! ```
//!
//! `movej` without a blend radius stops at its target; `sleep` then holds
//! the robot still for the tracker.

use super::{ProgramOptions, ProgramPose, RAD_DECIMALS, fixed, marks, summary};
use std::fmt::Write;

/// The URScript text of checked `poses` (six revolute joints each).
pub(super) fn render(poses: &[ProgramPose], opts: &ProgramOptions) -> String {
    let mut s = String::new();
    let a = fixed(opts.ur_acceleration, RAD_DECIMALS);
    let v = fixed(opts.ur_velocity, RAD_DECIMALS);
    let settle = fixed(opts.settle_s, 6);
    // writing to a String cannot fail
    let _ = writeln!(s, "def {}():", opts.name);
    let _ = writeln!(s, "  # {}", summary(poses, "rad"));
    for (p, mark) in poses.iter().zip(marks(poses)) {
        let q: Vec<String> =
            p.q.iter()
                .map(|d| fixed(d.to_radians(), RAD_DECIMALS))
                .collect();
        let _ = writeln!(s, "  # {mark}");
        let _ = writeln!(s, "  movej([{}], a={a}, v={v})", q.join(", "));
        if p.measure && opts.settle_s > 0.0 {
            let _ = writeln!(s, "  sleep({settle})");
        }
    }
    s.push_str("end\n");
    s
}
