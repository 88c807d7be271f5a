//! The kinematic-error parameterisation used for calibration (seed 003 eq 4,
//! seed 004 eq 4): per link the MD-H errors `(Δθ_off, Δd, Δa, Δα, Δβ)`, then
//! the tool offset `(x, y, z)` and the base pose `(x, y, z, rx, ry, rz)` —
//! `5n + 9` parameters in degrees and mm — and the identification Jacobian
//! `∂P/∂p` of the TCP position, whose rows are the linearised error
//! `ΔP = Σ_j ∂P/∂p_j · Δp_j`.

use super::Robot;
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};

/// Number of calibration parameters of an `n`-joint robot.
pub fn calib_len(n: usize) -> usize {
    5 * n + 9
}

/// Names of the calibration parameters (`theta_off1`, `d1`, …, `base_rz`).
pub fn calib_names(n: usize) -> Vec<String> {
    let mut names = Vec::with_capacity(calib_len(n));
    for j in 1..=n {
        for p in ["theta_off", "d", "a", "alpha", "beta"] {
            names.push(format!("{p}{j}"));
        }
    }
    for p in [
        "tool_x", "tool_y", "tool_z", "base_x", "base_y", "base_z", "base_rx", "base_ry", "base_rz",
    ] {
        names.push(p.into());
    }
    names
}

/// The robot with the parameter errors `x` (degrees and mm) applied:
/// link values added, tool translated in the flange frame, base moved by a
/// translation and a small rotation (scaled axis, degrees) before it.
pub fn apply_errors(nominal: &Robot, x: &[f64]) -> Robot {
    let n = nominal.dof();
    let mut r = nominal.clone();
    for (j, l) in r.links.iter_mut().enumerate() {
        let e = &x[5 * j..5 * j + 5];
        l.theta_offset_deg += e[0];
        l.d_mm += e[1];
        l.a_mm += e[2];
        l.alpha_deg += e[3];
        l.beta_deg += e[4];
    }
    let t = &x[5 * n..5 * n + 9];
    r.tool = Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::identity(),
    ) * nominal.tool;
    let rot = UnitQuaternion::from_scaled_axis(Vector3::new(t[6], t[7], t[8]).map(f64::to_radians));
    r.base = Isometry3::from_parts(Translation3::new(t[3], t[4], t[5]), rot) * nominal.base;
    r
}

/// `∂P/∂p` at joints `q` (central differences, step 1e-4 deg / mm): three
/// rows (x, y, z) of [`calib_len`] columns, mm per degree or mm per mm.
pub fn identification_jacobian(robot: &Robot, q: &[f64]) -> [Vec<f64>; 3] {
    let all: Vec<usize> = (0..calib_len(robot.dof())).collect();
    identification_jacobian_cols(robot, q, &all)
}

/// The columns `cols` of [`identification_jacobian`].
pub fn identification_jacobian_cols(robot: &Robot, q: &[f64], cols: &[usize]) -> [Vec<f64>; 3] {
    let np = calib_len(robot.dof());
    let h = 1e-4;
    let mut out = [
        vec![0.0; cols.len()],
        vec![0.0; cols.len()],
        vec![0.0; cols.len()],
    ];
    let mut x = vec![0.0; np];
    for (c, &k) in cols.iter().enumerate() {
        x[k] = h;
        let p = apply_errors(robot, &x).fk_unchecked(q).translation.vector;
        x[k] = -h;
        let m = apply_errors(robot, &x).fk_unchecked(q).translation.vector;
        x[k] = 0.0;
        for a in 0..3 {
            out[a][c] = (p[a] - m[a]) / (2.0 * h);
        }
    }
    out
}
