//! The plants: one known effect drawn at a seeded random position,
//! direction and shape, added to the errors of a real campaign.
//!
//! Size: the planted TCP error's RMS over the rows it touches, pooled over
//! the three axes, is `k ×` the pooled CV RMSE of the base model on the
//! unplanted campaign (`k` = 1, 2, …). Directions are drawn per axis and
//! weighted by that axis's CV RMSE, so an axis with more noise gets a
//! proportionally larger share.
//!
//! Joint effects (servo lag, harmonic) reach the TCP through the robot's
//! position Jacobian at each pose ([`robokrige::sim::Effect`] gives the joint
//! deviation; the lag's is the simulator's `Effect::Lag` with τ = 0, the
//! joint stopping short of its last move by a share of it, written out here
//! because `sim` does not export it), so what is planted is what the
//! simulator would have measured.

use rand::RngExt;
use rand::rngs::StdRng;
use rand_distr::{Distribution, StandardNormal};
use robokrige::dataset::Dataset;
use robokrige::kinematics::Robot;
use robokrige::sim::Effect;

/// What a plant is, as drawn (before its size is applied).
#[derive(Debug, Clone)]
pub enum Shape {
    /// Offset from `row` (0-based) to the end, direction per axis.
    Step { row: usize, dir: [f64; 3] },
    /// Offset on rows `[from, to)`, direction per axis.
    Block {
        from: usize,
        to: usize,
        dir: [f64; 3],
    },
    /// `(temp_c − mean) × dir` mm per K.
    Drift { dir: [f64; 3] },
    /// Servo lag of 1-based `joint`: it stops short of its last move.
    Lag { joint: usize },
    /// `sin(2π q/period + phase)` degrees on 1-based `joint`.
    Harmonic {
        joint: usize,
        period_deg: f64,
        phase_rad: f64,
    },
}

/// Names of the kinds (the `--kinds` option).
pub const KINDS: [&str; 5] = ["step", "block", "drift", "lag", "harmonic"];

impl Shape {
    pub fn kind(&self) -> &'static str {
        match self {
            Shape::Step { .. } => "step",
            Shape::Block { .. } => "block",
            Shape::Drift { .. } => "drift",
            Shape::Lag { .. } => "lag",
            Shape::Harmonic { .. } => "harmonic",
        }
    }

    /// Where it is, for the per-plant lines.
    pub fn describe(&self) -> String {
        match self {
            Shape::Step { row, .. } => format!("step @{row}"),
            Shape::Block { from, to, .. } => format!("block {from}–{to}"),
            Shape::Drift { .. } => "drift ∝ temp_c".into(),
            Shape::Lag { joint } => format!("lag q{joint}"),
            Shape::Harmonic {
                joint, period_deg, ..
            } => format!("harmonic q{joint} P {period_deg:.2}°"),
        }
    }
}

/// A random direction (normal per axis), weighted by the axes' CV RMSE.
fn direction(rng: &mut StdRng, sigma: [f64; 3]) -> [f64; 3] {
    let mut d = [0.0; 3];
    for (a, s) in d.iter_mut().zip(sigma) {
        let z: f64 = StandardNormal.sample(rng);
        *a = z * s;
    }
    d
}

/// Draw one plant of `kind` on `data` (m rows): steps and blocks with their
/// edges anywhere in the middle 80 %, a block at least m/20 rows long (the
/// shortest block the diagnosis scans), a harmonic's period log-uniform
/// between 5° and a third of the joint's range (inside what the scan
/// covers, never on its grid on purpose), its phase uniform.
pub fn draw(kind: &str, data: &Dataset, sigma: [f64; 3], rng: &mut StdRng) -> Shape {
    let m = data.len();
    let (lo, hi) = ((m as f64 * 0.1) as usize, (m as f64 * 0.9) as usize);
    let n = data.n_joints();
    match kind {
        "step" => Shape::Step {
            row: rng.random_range(lo..hi),
            dir: direction(rng, sigma),
        },
        "block" => {
            let min_len = (m / 20).max(5);
            let from = rng.random_range(lo..hi - min_len);
            let to = rng.random_range(from + min_len..hi + 1);
            Shape::Block {
                from,
                to,
                dir: direction(rng, sigma),
            }
        }
        "drift" => Shape::Drift {
            dir: direction(rng, sigma),
        },
        "lag" => Shape::Lag {
            joint: rng.random_range(1..n + 1),
        },
        "harmonic" => {
            let joint = rng.random_range(1..n + 1);
            let (a, b) = data
                .q
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                    (a.min(r[joint - 1]), b.max(r[joint - 1]))
                });
            let top = ((b - a) / 3.0).max(5.5);
            let period_deg = (5f64.ln() + rng.random::<f64>() * (top.ln() - 5f64.ln())).exp();
            Shape::Harmonic {
                joint,
                period_deg,
                phase_rad: rng.random::<f64>() * std::f64::consts::TAU,
            }
        }
        other => panic!("unknown kind {other} (one of {KINDS:?})"),
    }
}

/// A plant at its size: the TCP error it adds to each row, and the planted
/// value of what the diagnosis estimates (a step's or a drift's
/// coefficients per axis, mm or mm/K; a lag's gain, deg/deg; a harmonic's
/// amplitude, degrees).
pub struct Planted {
    pub added: Vec<[f64; 3]>,
    pub value: [f64; 3],
}

/// TCP displacement of the joint deviation `dev_deg` at `q`.
fn through_jacobian(robot: &Robot, q: &[f64], dev_deg: &[f64]) -> [f64; 3] {
    let j = robot.position_jacobian(q).expect("joint count");
    let mut out = [0.0; 3];
    for (a, o) in out.iter_mut().enumerate() {
        *o = (0..dev_deg.len())
            .map(|i| j[(a, i)] * dev_deg[i].to_radians())
            .sum();
    }
    out
}

/// The unit-size shape on every row, and the rows it touches.
fn unit(shape: &Shape, data: &Dataset, robot: &Robot) -> (Vec<[f64; 3]>, std::ops::Range<usize>) {
    let m = data.len();
    let n = data.n_joints();
    match shape {
        Shape::Step { row, dir } => {
            let v = (0..m).map(|i| if i >= *row { *dir } else { [0.0; 3] });
            (v.collect(), *row..m)
        }
        Shape::Block { from, to, dir } => {
            let v = (0..m).map(|i| {
                if (*from..*to).contains(&i) {
                    *dir
                } else {
                    [0.0; 3]
                }
            });
            (v.collect(), *from..*to)
        }
        Shape::Drift { dir } => {
            let t = &data.covariate("temp_c").expect("checked").values;
            let mean = t.iter().sum::<f64>() / m as f64;
            (
                t.iter().map(|v| dir.map(|d| d * (v - mean))).collect(),
                0..m,
            )
        }
        Shape::Lag { joint } => {
            let j = joint - 1;
            let v = (0..m).map(|i| {
                let mut d = vec![0.0; n];
                d[j] = -(data.q[i][j] - data.q[i.saturating_sub(1)][j]);
                through_jacobian(robot, &data.q[i], &d)
            });
            (v.collect(), 0..m)
        }
        Shape::Harmonic {
            joint,
            period_deg,
            phase_rad,
        } => {
            let e = Effect::Harmonic {
                joint: *joint,
                period_deg: *period_deg,
                amp_deg: 1.0,
                phase_rad: *phase_rad,
            };
            let v = data.q.iter().map(|q| {
                let mut d = vec![0.0; n];
                e.joint_deviation(q, &mut d);
                through_jacobian(robot, q, &d)
            });
            (v.collect(), 0..m)
        }
    }
}

/// `shape` at `k ×` the pooled CV RMSE `sigma_pooled`.
pub fn at_size(shape: &Shape, data: &Dataset, robot: &Robot, k: f64, sigma_pooled: f64) -> Planted {
    let (u, touched) = unit(shape, data, robot);
    let ms: f64 = u[touched.clone()]
        .iter()
        .map(|r| r.iter().map(|v| v * v).sum::<f64>() / 3.0)
        .sum::<f64>()
        / touched.len() as f64;
    let s = k * sigma_pooled / ms.sqrt();
    let value = match shape {
        Shape::Step { dir, .. } | Shape::Block { dir, .. } | Shape::Drift { dir } => {
            dir.map(|d| d * s)
        }
        Shape::Lag { .. } | Shape::Harmonic { .. } => [s; 3],
    };
    Planted {
        added: u.iter().map(|r| r.map(|v| v * s)).collect(),
        value,
    }
}

/// `data` with `p` added to its errors.
pub fn apply(data: &Dataset, p: &Planted) -> Dataset {
    let mut out = data.clone();
    let e = out.errors.as_mut().expect("errors");
    for (r, a) in e.iter_mut().zip(&p.added) {
        for (v, d) in r.iter_mut().zip(a) {
            *v += d;
        }
    }
    out
}
