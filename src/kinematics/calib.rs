//! The kinematic-error parameterisation used for calibration (seed 003 eq 4,
//! seed 004 eq 4): per link the MD-H errors `(Δθ_off, Δd, Δa, Δα, Δβ)`, then
//! the tool offset `(x, y, z)` and the base pose `(x, y, z, rx, ry, rz)` —
//! `5n + 9` parameters in degrees and mm — and the identification Jacobian
//! `∂P/∂p` of the TCP position, whose rows are the linearised error
//! `ΔP = Σ_j ∂P/∂p_j · Δp_j`.

use super::{MdhLink, Robot};
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
        *l = link_with_errors(l, &x[5 * j..5 * j + 5]);
    }
    let t = &x[5 * n..5 * n + 9];
    r.tool = tool_with_errors(nominal, t);
    r.base = base_with_errors(nominal, t);
    r
}

/// A link with its errors `(Δθ_off, Δd, Δa, Δα, Δβ)` added.
fn link_with_errors(link: &MdhLink, e: &[f64]) -> MdhLink {
    let mut l = *link;
    l.theta_offset_deg += e[0];
    l.d_mm += e[1];
    l.a_mm += e[2];
    l.alpha_deg += e[3];
    l.beta_deg += e[4];
    l
}

/// The tool with the offset `t[0..3]` applied in the flange frame.
fn tool_with_errors(nominal: &Robot, t: &[f64]) -> Isometry3<f64> {
    Isometry3::from_parts(
        Translation3::new(t[0], t[1], t[2]),
        UnitQuaternion::identity(),
    ) * nominal.tool
}

/// The base moved by the translation `t[3..6]` and the rotation `t[6..9]`.
fn base_with_errors(nominal: &Robot, t: &[f64]) -> Isometry3<f64> {
    let rot = UnitQuaternion::from_scaled_axis(Vector3::new(t[6], t[7], t[8]).map(f64::to_radians));
    Isometry3::from_parts(Translation3::new(t[3], t[4], t[5]), rot) * nominal.base
}

/// The forward kinematics of `apply_errors(nominal, x)` at one pose, kept
/// link by link: `F_i = base·T_1⋯T_i` for i = 0…n, and the tool.
///
/// The TCP of the same robot with **one** error parameter moved
/// ([`ErrorChain::moved`]) then costs that parameter's link (or the tool,
/// or the base) and the products after it, instead of a whole forward
/// kinematics: the central differences of an identification Jacobian need
/// 2P of them per pose. Every position it returns equals
/// `apply_errors(nominal, x′).fk_unchecked(q)` bit for bit, because it
/// forms the same products in the same order.
pub struct ErrorChain<'a> {
    nominal: &'a Robot,
    x: &'a [f64],
    q: &'a [f64],
    /// `T_i(q_i)`, base to flange.
    links: Vec<Isometry3<f64>>,
    /// `F_i = base·T_1⋯T_i`, i = 0…n.
    prefix: Vec<Isometry3<f64>>,
    tool: Isometry3<f64>,
}

impl<'a> ErrorChain<'a> {
    /// The chain of `apply_errors(nominal, x)` at joints `q` (one value per
    /// joint; `x` of [`calib_len`]).
    pub fn new(nominal: &'a Robot, x: &'a [f64], q: &'a [f64]) -> Self {
        let n = nominal.dof();
        let t = &x[5 * n..5 * n + 9];
        let links: Vec<Isometry3<f64>> = nominal
            .links
            .iter()
            .enumerate()
            .map(|(i, l)| link_with_errors(l, &x[5 * i..5 * i + 5]).transform(q[i]))
            .collect();
        let mut prefix = Vec::with_capacity(n + 1);
        let mut f = base_with_errors(nominal, t);
        prefix.push(f);
        for l in &links {
            f *= *l;
            prefix.push(f);
        }
        ErrorChain {
            nominal,
            x,
            q,
            links,
            prefix,
            tool: tool_with_errors(nominal, t),
        }
    }

    /// The TCP position of `apply_errors(nominal, x′)`, where `x′` is `x`
    /// with parameter `k` set to `value`.
    pub fn moved(&self, k: usize, value: f64) -> Vector3<f64> {
        let n = self.links.len();
        let (nominal, x) = (self.nominal, self.x);
        if k < 5 * n {
            let i = k / 5;
            let mut e = [0.0; 5];
            e.copy_from_slice(&x[5 * i..5 * i + 5]);
            e[k - 5 * i] = value;
            let mut f = self.prefix[i];
            f *= link_with_errors(&nominal.links[i], &e).transform(self.q[i]);
            for l in &self.links[i + 1..] {
                f *= *l;
            }
            return (f * self.tool).translation.vector;
        }
        let mut t = [0.0; 9];
        t.copy_from_slice(&x[5 * n..5 * n + 9]);
        t[k - 5 * n] = value;
        if k < 5 * n + 3 {
            return (self.prefix[n] * tool_with_errors(nominal, &t))
                .translation
                .vector;
        }
        let mut f = base_with_errors(nominal, &t);
        for l in &self.links {
            f *= *l;
        }
        (f * self.tool).translation.vector
    }
}

/// The step of the identification Jacobian's central differences, degrees
/// or mm: [`identification_jacobian`] and the calibration's residual
/// Jacobian.
pub const IDENTIFICATION_STEP: f64 = 1e-4;

/// `∂P/∂p` at joints `q` (central differences, step [`IDENTIFICATION_STEP`]): three
/// rows (x, y, z) of [`calib_len`] columns, mm per degree or mm per mm.
pub fn identification_jacobian(robot: &Robot, q: &[f64]) -> [Vec<f64>; 3] {
    let all: Vec<usize> = (0..calib_len(robot.dof())).collect();
    identification_jacobian_cols(robot, q, &all)
}

/// The columns `cols` of [`identification_jacobian`].
pub fn identification_jacobian_cols(robot: &Robot, q: &[f64], cols: &[usize]) -> [Vec<f64>; 3] {
    let h = IDENTIFICATION_STEP;
    let x = vec![0.0; calib_len(robot.dof())];
    let chain = ErrorChain::new(robot, &x, q);
    let mut out = [
        vec![0.0; cols.len()],
        vec![0.0; cols.len()],
        vec![0.0; cols.len()],
    ];
    for (c, &k) in cols.iter().enumerate() {
        let p = chain.moved(k, h);
        let m = chain.moved(k, -h);
        for a in 0..3 {
            out[a][c] = (p[a] - m[a]) / (2.0 * h);
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::kinematics::preset;
    use rand::{RngExt, SeedableRng, rngs::StdRng};

    /// The chain's positions are the whole forward kinematics' bit for bit,
    /// for every parameter, on robots with a base and a tool.
    #[test]
    fn a_moved_parameter_gives_the_whole_forward_kinematics_bit_for_bit() {
        let mut rng = StdRng::seed_from_u64(7);
        for name in crate::kinematics::PRESET_NAMES {
            let mut robot = preset(name).unwrap();
            robot.base = Isometry3::from_parts(
                Translation3::new(120.0, -35.0, 410.0),
                UnitQuaternion::from_euler_angles(0.1, -0.2, 0.7),
            );
            robot.tool = Isometry3::from_parts(
                Translation3::new(-14.0, 30.0, 92.8),
                UnitQuaternion::from_euler_angles(0.3, 0.0, -0.4),
            );
            let np = calib_len(robot.dof());
            for _ in 0..5 {
                let x: Vec<f64> = (0..np).map(|_| rng.random_range(-0.5..0.5)).collect();
                let q: Vec<f64> = robot
                    .limits
                    .iter()
                    .map(|&(lo, hi)| rng.random_range(lo..hi))
                    .collect();
                let chain = ErrorChain::new(&robot, &x, &q);
                let whole = |x: &[f64]| apply_errors(&robot, x).fk_unchecked(&q).translation.vector;
                // every parameter at its own value: the unmoved robot
                for (k, &v) in x.iter().enumerate() {
                    assert_eq!(
                        chain.moved(k, v),
                        whole(&x),
                        "{name}, parameter {k} unmoved"
                    );
                }
                for k in 0..np {
                    let v = x[k] + rng.random_range(-1e-3..1e-3);
                    let mut moved = x.clone();
                    moved[k] = v;
                    assert_eq!(chain.moved(k, v), whole(&moved), "{name}, parameter {k}");
                }
            }
        }
    }
}
