//! ABB RAPID: a module whose `main` makes a `MoveAbsJ` per pose in degrees.
//!
//! ```text
//! MODULE robokrige_plan
//!   ! written by robokrige: 2 moves (1 measured, 1 via); joints in deg
//!   PROC main()
//!     ! via
//!     MoveAbsJ [[0.0,-90.0,90.0,0.0,45.0,0.0],[9E9,9E9,9E9,9E9,9E9,9E9]], v100, fine, tool0;
//!     ! measure 0
//!     MoveAbsJ [[10.0,…],[9E9,…]], v100, fine, tool0;
//!     WaitTime 2.0;
//!   ENDPROC
//! ENDMODULE
//! ```
//!
//! The joint target's robot axes are the six joints (a linear axis in mm);
//! its external axes are 9E9, "not connected". `fine` stops at the target,
//! and the speed is one of RAPID's predefined `speeddata`
//! ([`ProgramOptions::rapid_speed`]). The moves use `tool0` (the flange):
//! a joint target does not depend on the tool.

use super::{DEG_DECIMALS, ProgramOptions, ProgramPose, deg_units, fixed, marks, summary};
use std::fmt::Write;

/// The external axes of every joint target: none connected.
const NO_EXTERNAL_AXES: &str = "[9E9,9E9,9E9,9E9,9E9,9E9]";

/// The RAPID text of checked `poses` (six joints each).
pub(super) fn render(poses: &[ProgramPose], opts: &ProgramOptions) -> String {
    let mut s = String::new();
    let settle = fixed(opts.settle_s, 6);
    // writing to a String cannot fail
    let _ = writeln!(s, "MODULE {}", opts.name);
    let _ = writeln!(s, "  ! {}", summary(poses, &deg_units(opts)));
    s.push_str("  PROC main()\n");
    for (p, mark) in poses.iter().zip(marks(poses)) {
        let q: Vec<String> = p.q.iter().map(|v| fixed(*v, DEG_DECIMALS)).collect();
        let _ = writeln!(s, "    ! {mark}");
        let _ = writeln!(
            s,
            "    MoveAbsJ [[{}],{NO_EXTERNAL_AXES}], {}, fine, tool0;",
            q.join(","),
            opts.rapid_speed
        );
        if p.measure && opts.settle_s > 0.0 {
            let _ = writeln!(s, "    WaitTime {settle};");
        }
    }
    s.push_str("  ENDPROC\nENDMODULE\n");
    s
}
