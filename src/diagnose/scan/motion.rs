//! Motion-history candidates: how the robot moved into the pose.
//!
//! Joint j's moves `h_k = Δq_k + e^(−1/τ)·h_(k−1)` (`Δq_k = q_j(k) −
//! q_j(k−1)`) over a scanned memory τ ([`MOVE_TAUS`] in poses, and the
//! same multiples of the median interval in time when the campaign has a
//! time column), through the robot's Jacobian when it is given
//! ([`Feature::MovesJacobian`]: the TCP displacement a lag of joint j
//! causes) or else alone and times the joint angles ([`Feature::Moves`]);
//! the size of its last move ([`Feature::MoveSize`]); the TCP's last move
//! ([`Feature::TcpMove`]); and then the generic search (`generic.rs`).

use super::covariate::{constant_covariate, usable_covariates};
use super::generic::{generic_bases, generic_families};
use super::{EffectKind, Family, GridPoint, Sink, params, z_all, zscore};
use crate::dataset::{Covariate, Dataset};
use crate::features::{Clock, Feature};
use crate::kinematics::Robot;
use std::collections::BTreeMap;

/// Memories τ (poses) scanned for a joint's decaying sum of moves.
pub const MOVE_TAUS: [f64; 6] = [0.0, 0.5, 1.0, 2.0, 4.0, 8.0];

/// Names of a time column: the interval since the previous pose is a
/// candidate when one of these is present and never decreases.
const TIME_COLUMNS: [&str; 5] = ["time_s", "time", "t_s", "timestamp", "time_ms"];

/// Whether a column is named like a time column ([`TIME_COLUMNS`]): a
/// clock, the measurement order in seconds rather than a cause.
pub(crate) fn is_time_column(name: &str) -> bool {
    TIME_COLUMNS.contains(&name)
}

/// The time column of a campaign, when it has one that never decreases.
pub(super) fn time_column<'a>(data: &'a Dataset, exclude: &'a [String]) -> Option<&'a Covariate> {
    usable_covariates(data, exclude).find(|c| {
        TIME_COLUMNS.contains(&c.name.as_str())
            && c.values.windows(2).all(|w| w[1] >= w[0])
            && constant_covariate(c).is_none()
    })
}

/// The median interval between consecutive rows of a time column.
pub(super) fn median_interval(t: &Covariate) -> Option<f64> {
    let mut dt: Vec<f64> = t.values.windows(2).map(|w| w[1] - w[0]).collect();
    dt.sort_by(f64::total_cmp);
    dt.get(dt.len() / 2).copied()
}

/// How the robot moved into each pose, and the generic search:
/// - per joint j, its signed moves with a scanned memory τ (through the
///   robot's Jacobian when it is given, so that the candidate is the TCP
///   displacement a lag of joint j causes; else the moves and their product
///   with every joint angle) and the size of its last move;
/// - the TCP's last move (with the robot), the time since the previous pose
///   (with a time column);
/// - for each numeric column, the interval and each joint's last move: the
///   feature times one joint angle (θ, sin θ, cos θ; the joint scanned),
///   and the columns and the interval lagged by 1–3 rows.
///
/// The scans are grids of one family each, so a family's p-value pays for
/// its scan (the null takes the maximum over the same grid).
pub(super) fn motion_families(
    data: &Dataset,
    exclude: &[String],
    robot: Option<&Robot>,
    u: &[Vec<f64>],
    out: &mut Sink,
) {
    let memories = move_memories(data, exclude);
    for j in 1..=data.n_joints() {
        move_families(data, j, robot, u, &memories, out);
    }
    if let Some(r) = robot {
        tcp_move_family(data, r, out);
    }
    let (bases, lagged) = generic_bases(data, exclude, out);
    for (b, base) in bases.iter().enumerate() {
        generic_families(data, base, b < lagged, out);
    }
}

/// The memories a joint's moves are scanned over: `MOVE_TAUS` in poses
/// and, when the campaign has a time column, the same multiples of its
/// median interval in time.
fn move_memories(data: &Dataset, exclude: &[String]) -> Vec<(f64, Option<Clock>)> {
    let clocks: Vec<Clock> = time_column(data, exclude)
        .and_then(|t| {
            let median = median_interval(t)?;
            (median > 0.0).then(|| {
                MOVE_TAUS
                    .iter()
                    .filter(|&&k| k > 0.0)
                    .map(|&k| Clock {
                        column: t.name.clone(),
                        tau_s: k * median,
                        interval_s: Some(median),
                    })
                    .collect()
            })
        })
        .unwrap_or_default();
    MOVE_TAUS
        .iter()
        .map(|&tau| (tau, None))
        .chain(clocks.into_iter().map(|c| (0.0, Some(c))))
        .collect()
}

/// Joint `j`'s (1-based) moves into the pose over `memories` (through the
/// robot's Jacobian when given, else times the joint angles `u`), and the
/// size of its last move.
fn move_families(
    data: &Dataset,
    j: usize,
    robot: Option<&Robot>,
    u: &[Vec<f64>],
    memories: &[(f64, Option<Clock>)],
    out: &mut Sink,
) {
    let grid: Vec<GridPoint> = memories
        .iter()
        .filter_map(|(tau, clock)| move_point(data, j, *tau, clock, robot, u))
        .collect();
    if !grid.is_empty() {
        out.push(Family {
            kind: EffectKind::MotionHistory,
            source: vec![format!("move{j}")],
            label: format!("moves of q{j} into the pose (lag)"),
            grid,
            zoom: None,
        });
    }
    // the size alone: signed by λ it would be the signed move, which the
    // family above tests (and a candidate's columns must be what it adds)
    let size = Feature::MoveSize { joint: j };
    if let Ok(s) = size.columns_from_poses(&data.q, &data.dir) {
        out.push(Family {
            kind: EffectKind::MotionHistory,
            source: vec![format!("move{j}")],
            label: format!("size of q{j}'s last move"),
            grid: vec![GridPoint::new(
                BTreeMap::new(),
                vec![zscore(&s[0])],
                vec![size],
            )],
            zoom: None,
        });
    }
}

/// One memory (`tau` poses, or `clock`) of joint `j`'s moves: through the
/// robot's Jacobian when given, else the moves alone and times the joint
/// angles `u`. `None` when the columns cannot be computed.
fn move_point(
    data: &Dataset,
    j: usize,
    tau: f64,
    clock: &Option<Clock>,
    robot: Option<&Robot>,
    u: &[Vec<f64>],
) -> Option<GridPoint> {
    let (columns, add) = match robot {
        Some(r) => {
            let f = Feature::MovesJacobian {
                robot: Box::new(r.clone()),
                joint: j,
                tau_poses: tau,
                clock: clock.clone(),
            };
            (z_all(f.columns(data).ok()?), f)
        }
        None => {
            let plain = Feature::Moves {
                joint: j,
                tau_poses: tau,
                clock: clock.clone(),
            };
            let h = plain.columns(data).ok()?;
            let z = zscore(&h[0]);
            let mut cols = vec![z.clone()];
            cols.extend(
                u.iter()
                    .map(|uk| z.iter().zip(uk).map(|(a, b)| a * b).collect()),
            );
            (cols, plain)
        }
    };
    let params = match clock {
        Some(c) => params(&[("tau_s", c.tau_s)]),
        None => params(&[("tau_poses", tau)]),
    };
    // through the Jacobian the columns are the feature's (x, y, z rows);
    // without it, the moves and their products with the joint angles
    Some(if robot.is_some() {
        GridPoint::of_features(params, columns, vec![add])
    } else {
        GridPoint::new(params, columns, vec![add])
    })
}

/// The TCP's last move (needs the robot).
fn tcp_move_family(data: &Dataset, robot: &Robot, out: &mut Sink) {
    let f = Feature::TcpMove {
        robot: Box::new(robot.clone()),
    };
    if let Ok(c) = f.columns_from_poses(&data.q, &data.dir) {
        out.push(Family {
            kind: EffectKind::MotionHistory,
            source: vec!["tcp_move".into()],
            label: "the TCP's last move".into(),
            grid: vec![GridPoint::new(BTreeMap::new(), z_all(c), vec![f])],
            zoom: None,
        });
    }
}
