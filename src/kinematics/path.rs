//! Inverse kinematics along a path: one joint solution per pose, in order.
//!
//! The first pass follows the paper's rule (seed 004, below eq 18): each pose
//! is seeded from the previous pose's solution, so the robot stays on one
//! branch of its IK along the path. Failures are collected by index, never
//! skipped.

use super::{IkOptions, IkTarget, Robot};
use crate::{Error, Result};
use nalgebra::Isometry3;

/// The IK target of a commanded pose: the whole pose when the path carries
/// orientations, its position otherwise.
pub fn path_target(has_orientation: bool, pose: &Isometry3<f64>) -> IkTarget {
    if has_orientation {
        IkTarget::pose(pose)
    } else {
        IkTarget::position(pose.translation.vector)
    }
}

/// The joints of every point, or [`Error::Unreachable`] listing the points
/// whose IK failed (with the first failure's message).
pub fn all_reached(results: Vec<Result<Vec<f64>>>) -> Result<Vec<Vec<f64>>> {
    let mut joints = Vec::with_capacity(results.len());
    let mut failed = Vec::new();
    let mut first = String::new();
    for (i, r) in results.into_iter().enumerate() {
        match r {
            Ok(q) => joints.push(q),
            Err(e) => {
                if failed.is_empty() {
                    first = e.to_string();
                }
                failed.push(i);
            }
        }
    }
    if failed.is_empty() {
        Ok(joints)
    } else {
        Err(Error::Unreachable {
            indices: failed,
            first,
        })
    }
}

/// Sequential IK along `poses`: each point seeded from its hint (if given),
/// then from the previous point's solution (the paper's rule), then from the
/// start pose, then from the robot's home pose (a start far from the
/// trajectory must not make its points unreachable). One result per pose, in order.
pub fn first_pass_joints(
    robot: &Robot,
    has_orientation: bool,
    poses: &[Isometry3<f64>],
    start: &[f64],
    hints: Option<&[Vec<f64>]>,
    opts: &IkOptions,
) -> Vec<Result<Vec<f64>>> {
    let mut prev = start.to_vec();
    poses
        .iter()
        .enumerate()
        .map(|(i, p)| {
            let mut seeds: Vec<&[f64]> = Vec::with_capacity(4);
            if let Some(h) = hints.and_then(|h| h.get(i)) {
                seeds.push(h);
            }
            seeds.push(&prev);
            seeds.push(start);
            if robot.home.as_slice() != start {
                seeds.push(&robot.home);
            }
            let r = robot.ik_from_any(&path_target(has_orientation, p), &seeds, opts);
            if let Ok(q) = &r {
                prev.clone_from(q);
            }
            r
        })
        .collect()
}
