//! The order of a plan's poses, and the pre-position moves that make every
//! joint arrive from its planned side.
//!
//! A joint's direction of approach is the sign of its last move
//! ([`crate::space::derive_directions`]): λ is realised by the order of the
//! poses. The tour is greedy: from the robot's current pose, the next pose
//! is the nearest remaining one (joints scaled by their ranges), where a
//! pose the direct move would reach from the wrong side on some joint costs
//! the detour of a pre-position move as well. Such a pose gets one: a
//! via-point `q − λ·step` (every joint `step` back on its planned side,
//! within the limits), which is not measured, so the move from it realises
//! λ on every joint — the hysteresis test design of seed 004 Table 1 (each
//! pose approached from a chosen side), generalised to every joint at once.

use super::candidates::PoseSet;
use crate::space::MOVE_EPS;

/// One move of a plan: a pose measured, or a pre-position move (via-point)
/// that is not.
#[derive(Debug, Clone, PartialEq)]
pub struct PlannedMove {
    /// Joint values, degrees (mm for prismatic joints).
    pub q: Vec<f64>,
    /// The direction each joint arrives from, ±1 (realised by the order).
    pub dir: Vec<f64>,
    /// Measure here (a planned pose), or only pass (a via-point).
    pub measure: bool,
    /// For a measured pose: its index among the poses ordered (the pool
    /// row or candidate it came from is the caller's).
    pub pose: Option<usize>,
}

/// A tour of a plan's poses: its moves, and what it could not do.
#[derive(Debug, Clone, PartialEq)]
pub struct Tour {
    /// The moves in order: the poses measured and the via-points.
    pub moves: Vec<PlannedMove>,
    /// Poses that arrive from another side than planned on some joint.
    pub unrealised: usize,
    /// Per joint, the via-points stopped at a hard limit.
    pub at_limit: Vec<usize>,
    /// The passes toured: at least 1, at most one per pose.
    pub passes: usize,
}

/// The realised directions of a move from `(from, from_dir)` to `to`.
fn arrival(from: &[f64], from_dir: &[f64], to: &[f64]) -> Vec<f64> {
    from.iter()
        .zip(to)
        .zip(from_dir)
        .map(|((a, b), d)| {
            if b - a > MOVE_EPS {
                1.0
            } else if a - b > MOVE_EPS {
                -1.0
            } else {
                *d
            }
        })
        .collect()
}

/// Order `poses` (each with its planned λ) from the start pose
/// `(start, start_dir)`, with a via-point `step` back before every pose the
/// direct move would reach from a wrong side, in one pass. `ranges` scale
/// the joints for distances; `limits` bound the via-points (a joint whose
/// via-point would leave them arrives as it can: its λ is then counted in
/// [`Tour::unrealised`]). A via-point whose joint `step` back would leave
/// the limits stops at the limit; [`Tour::at_limit`] counts those
/// via-points per joint, for the caller to warn about (a move to a hard
/// limit).
pub fn order(
    poses: &PoseSet,
    start: &[f64],
    start_dir: &[f64],
    ranges: &[(f64, f64)],
    limits: &[(f64, f64)],
    step: &[f64],
) -> Tour {
    let scale: Vec<f64> = ranges.iter().map(|(lo, hi)| (hi - lo).max(1e-12)).collect();
    let dist = |a: &[f64], b: &[f64]| -> f64 {
        a.iter()
            .zip(b)
            .zip(&scale)
            .map(|((x, y), s)| ((x - y) / s).powi(2))
            .sum::<f64>()
            .sqrt()
    };
    let detour: f64 = 2.0
        * step
            .iter()
            .zip(&scale)
            .map(|(d, s)| (d / s).powi(2))
            .sum::<f64>()
            .sqrt();
    let (mut cur, mut cur_dir) = (start.to_vec(), start_dir.to_vec());
    let mut left: Vec<usize> = (0..poses.len()).collect();
    let mut moves = Vec::with_capacity(2 * poses.len());
    let mut unrealised = 0;
    let mut at_limit = vec![0; start.len()];
    while !left.is_empty() {
        let cost = |i: usize| -> (f64, bool) {
            let direct = arrival(&cur, &cur_dir, &poses.q[i]) == poses.dir[i];
            let d = dist(&cur, &poses.q[i]);
            (if direct { d } else { d + detour }, direct)
        };
        let (k, direct) = left
            .iter()
            .enumerate()
            .map(|(k, &i)| (k, cost(i)))
            .min_by(|a, b| a.1.0.total_cmp(&b.1.0))
            .map(|(k, (_, direct))| (k, direct))
            .expect("a pose left");
        let i = left.swap_remove(k);
        let (q, want) = (&poses.q[i], &poses.dir[i]);
        if !direct {
            let via: Vec<f64> = q
                .iter()
                .zip(want)
                .zip(step.iter().zip(limits))
                .map(|((v, l), (s, (lo, hi)))| (v - l * s).clamp(*lo, *hi))
                .collect();
            for (j, (lo, hi)) in limits.iter().enumerate() {
                let stepped = q[j] - want[j] * step[j];
                if stepped < *lo || stepped > *hi {
                    at_limit[j] += 1;
                }
            }
            let via_dir = arrival(&cur, &cur_dir, &via);
            moves.push(PlannedMove {
                q: via.clone(),
                dir: via_dir.clone(),
                measure: false,
                pose: None,
            });
            cur = via;
            cur_dir = via_dir;
        }
        let got = arrival(&cur, &cur_dir, q);
        if got != *want {
            unrealised += 1;
        }
        moves.push(PlannedMove {
            q: q.clone(),
            dir: got.clone(),
            measure: true,
            pose: Some(i),
        });
        cur = q.clone();
        cur_dir = got;
    }
    Tour {
        moves,
        unrealised,
        at_limit,
        passes: 1,
    }
}

/// [`order`] in `passes` passes over the region (at least 1, at most one
/// per pose; [`Tour::passes`] says how many): the poses, in the order
/// they were chosen, cut into runs of consecutive ones (sizes differing by
/// at most one), each run toured in turn from where the last one ended. The poses are chosen one by one, each where the model is
/// least sure given those before it, so each run spreads over the region
/// and a campaign stopped after a pass is the design chosen for its size.
///
/// One tour of all the poses measures the workspace region by region, and
/// ties the measurement order to the pose: an order effect (a tracker
/// step, a warm-up drift) is then a region of the joint space, which
/// `diagnose` cannot tell from an effect of the pose
/// ([`crate::diagnose::OrderInJointSpace`]). In passes, every stretch of
/// the order covers the region, at the price of a longer path: on
/// space-filling plans of 300 poses, six passes took the correlation of
/// the row index with its nearest poses' from 0.36 to 0.21 on the COMAU
/// NJ220 and from 0.44 to 0.09 on the UR10, and the motion (the largest
/// joint move of each move, summed) up by 9 % and 32 %.
pub fn in_passes(
    poses: &PoseSet,
    passes: usize,
    (start, start_dir): (&[f64], &[f64]),
    ranges: &[(f64, f64)],
    limits: &[(f64, f64)],
    step: &[f64],
) -> Tour {
    let n = poses.len();
    let passes = passes.clamp(1, n.max(1));
    let (mut cur, mut cur_dir) = (start.to_vec(), start_dir.to_vec());
    let mut moves = Vec::with_capacity(2 * n);
    let mut unrealised = 0;
    let mut at_limit = vec![0; start.len()];
    for k in 0..passes {
        let rows: Vec<usize> = (k * n / passes..(k + 1) * n / passes).collect();
        let run = order(&poses.select(&rows), &cur, &cur_dir, ranges, limits, step);
        if let Some(last) = run.moves.last() {
            cur.clone_from(&last.q);
            cur_dir.clone_from(&last.dir);
        }
        moves.extend(run.moves.into_iter().map(|mut m| {
            m.pose = m.pose.map(|i| rows[i]);
            m
        }));
        unrealised += run.unrealised;
        for (a, b) in at_limit.iter_mut().zip(run.at_limit) {
            *a += b;
        }
    }
    Tour {
        moves,
        unrealised,
        at_limit,
        passes,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// In passes, each pass tours its own run of the poses in the order
    /// chosen, every pose once, and starts where the last pass ended.
    #[test]
    fn passes_tour_consecutive_runs_of_the_poses_in_turn() {
        let n = 11;
        let poses = PoseSet {
            q: (0..n)
                .map(|i| vec![((i * 37) % 23) as f64, ((i * 11) % 7) as f64])
                .collect(),
            dir: vec![vec![1.0, 1.0]; n],
        };
        let r = [(-50.0, 50.0), (-50.0, 50.0)];
        let tour = in_passes(&poses, 3, (&[0.0, 0.0], &[1.0, 1.0]), &r, &r, &[5.0, 5.0]);
        assert_eq!((tour.unrealised, tour.passes), (0, 3));
        let measured: Vec<usize> = tour.moves.iter().filter_map(|m| m.pose).collect();
        let mut all = measured.clone();
        all.sort_unstable();
        assert_eq!(all, (0..n).collect::<Vec<_>>());
        // runs of 3, 4 and 4 poses: 0..3, 3..7, 7..11, one after the other
        let pass = |i: usize| (0..3).find(|&k| i < (k + 1) * n / 3).unwrap();
        let passes: Vec<usize> = measured.iter().map(|&i| pass(i)).collect();
        assert!(passes.windows(2).all(|w| w[0] <= w[1]), "{passes:?}");
        assert_eq!(passes.iter().filter(|&&k| k == 0).count(), 3);
        // one pass is the tour of `order`
        let one = in_passes(&poses, 1, (&[0.0, 0.0], &[1.0, 1.0]), &r, &r, &[5.0, 5.0]);
        let tour = order(&poses, &[0.0, 0.0], &[1.0, 1.0], &r, &r, &[5.0, 5.0]);
        assert_eq!(one, tour);
        // more passes than poses: one per pose
        let most = in_passes(&poses, 99, (&[0.0, 0.0], &[1.0, 1.0]), &r, &r, &[5.0, 5.0]);
        assert_eq!(most.passes, n);
    }

    #[test]
    fn every_pose_arrives_from_its_planned_side() {
        let poses = PoseSet {
            q: vec![
                vec![10.0, 0.0],
                vec![20.0, 5.0],
                vec![15.0, -5.0],
                vec![15.0, -5.0],
            ],
            dir: vec![
                vec![1.0, -1.0],
                vec![-1.0, 1.0],
                vec![1.0, 1.0],
                vec![-1.0, -1.0],
            ],
        };
        let ranges = [(-90.0, 90.0), (-90.0, 90.0)];
        let Tour {
            moves,
            unrealised,
            at_limit,
            ..
        } = order(
            &poses,
            &[0.0, 0.0],
            &[1.0, 1.0],
            &ranges,
            &ranges,
            &[5.0, 5.0],
        );
        assert_eq!(unrealised, 0);
        assert_eq!(at_limit, [0, 0]);
        assert_eq!(moves.iter().filter(|m| m.measure).count(), 4);
        // replaying the moves gives each measured pose its planned λ
        let q: Vec<Vec<f64>> = moves.iter().map(|m| m.q.clone()).collect();
        let dirs = crate::space::derive_directions(&q, Some(&[0.0, 0.0]));
        for (m, d) in moves.iter().zip(&dirs) {
            if let Some(i) = m.pose {
                assert_eq!(d, &poses.dir[i], "pose {i}");
            }
        }
        // the same pose planned from both sides is measured twice
        assert!(moves.iter().filter(|m| !m.measure).count() >= 1);
    }

    #[test]
    fn a_side_beyond_the_limit_is_reported() {
        let poses = PoseSet {
            q: vec![vec![-90.0]],
            dir: vec![vec![1.0]],
        };
        let r = [(-90.0, 90.0)];
        let tour = order(&poses, &[0.0], &[1.0], &r, &r, &[5.0]);
        assert_eq!(tour.unrealised, 1);
    }

    #[test]
    fn a_via_point_stopped_at_a_limit_is_counted_per_joint() {
        // q1 at 60° approached from below, 50° back would be 10° (inside);
        // 100° back would be −40°, beyond the lower limit −30°.
        let poses = PoseSet {
            q: vec![vec![60.0, 0.0]],
            dir: vec![vec![1.0, -1.0]],
        };
        let r = [(-30.0, 90.0), (-90.0, 90.0)];
        for (step, want) in [(50.0, [0, 0]), (100.0, [1, 0])] {
            let tour = order(&poses, &[70.0, -10.0], &[1.0, 1.0], &r, &r, &[step, 5.0]);
            assert_eq!(
                (tour.unrealised, tour.at_limit.as_slice()),
                (0, &want[..]),
                "step {step}"
            );
            assert_eq!(tour.moves.len(), 2, "one via-point, then the pose");
        }
    }
}
