//! KUKA KRL: a `.src` program of `PTP` axis moves in degrees.
//!
//! ```text
//! DEF robokrige_plan( )
//!   ; written by robokrige: 2 moves (1 measured, 1 via); joints in deg
//!   $VEL_AXIS[1] = 20.0
//!   …
//!   $ACC_AXIS[6] = 20.0
//!   ; via
//!   PTP {A1 0.0, A2 -90.0, A3 90.0, A4 0.0, A5 45.0, A6 0.0}
//!   ; measure 0
//!   PTP {A1 10.0, …}
//!   WAIT SEC 2.0
//! END
//! ```
//!
//! The `DEF` name must be the `.src` file's name. Each `PTP` carries every
//! axis (the first move of a KRL program must), and without `C_PTP` it
//! stops at its target; a prismatic axis's value is in mm, as KRL takes a
//! linear axis. The axis speeds are set once, at the top, as a percentage of
//! each axis's maximum ([`ProgramOptions::krl_percent`]).

use super::{DEG_DECIMALS, ProgramOptions, ProgramPose, deg_units, fixed, marks, summary};
use std::fmt::Write;

/// The KRL text of checked `poses` (six joints each).
pub(super) fn render(poses: &[ProgramPose], opts: &ProgramOptions) -> String {
    let mut s = String::new();
    let n = poses[0].q.len();
    let pct = fixed(opts.krl_percent, 3);
    let settle = fixed(opts.settle_s, 6);
    // writing to a String cannot fail
    let _ = writeln!(s, "DEF {}( )", opts.name);
    let _ = writeln!(s, "  ; {}", summary(poses, &deg_units(opts)));
    for var in ["$VEL_AXIS", "$ACC_AXIS"] {
        for k in 1..=n {
            let _ = writeln!(s, "  {var}[{k}] = {pct}");
        }
    }
    for (p, mark) in poses.iter().zip(marks(poses)) {
        let axes: Vec<String> =
            p.q.iter()
                .enumerate()
                .map(|(k, v)| format!("A{} {}", k + 1, fixed(*v, DEG_DECIMALS)))
                .collect();
        let _ = writeln!(s, "  ; {mark}");
        let _ = writeln!(s, "  PTP {{{}}}", axes.join(", "));
        if p.measure && opts.settle_s > 0.0 {
            let _ = writeln!(s, "  WAIT SEC {settle}");
        }
    }
    s.push_str("END\n");
    s
}
