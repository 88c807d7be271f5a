//! The poses of each campaign design, in the order the robot visits them
//! ([`super::campaign`] measures them on a [`super::TrueRobot`]):
//!
//! - [`lhs`]: a Latin hypercube in the joint ranges (seed 004 Table 2),
//!   visited in the order drawn, so that the directions λ come from the
//!   sequence (seed 003 §IV.B);
//! - [`uniform`]: independent uniformly random poses (seed 003 §IV.C);
//! - single-axis indexing tests on the [`indexing_grid`] (seed 000 §2.3),
//!   every grid point approached from both sides; a wrist axis that the TCP
//!   lies on at rest is tested with a later joint bent, so that its circle
//!   is at least [`INDEXING_MIN_RADIUS_MM`];
//! - the cross-talk test: indexing with joint 2 at each of
//!   [`CROSSTALK_J2_DEG`];
//! - ISO 9283 cubes ([`super::iso_cubes`]);
//! - [`circle`] / [`circle_around`]: a circle of commanded TCP poses at
//!   fixed orientation (seed 004 §IV.B.3), a trajectory, not measured.

use super::campaign::CampaignSpec;
use crate::kinematics::{IkOptions, IkTarget, JointKind, Robot};
use crate::space::MOVE_EPS;
use crate::trajectory::Trajectory;
use crate::{Error, Result};
use nalgebra::{Isometry3, Translation3, Vector3};
use rand::{Rng, RngExt};

/// One pose the robot goes to; only `measured` ones become rows.
#[derive(Debug, Clone, PartialEq)]
pub(super) struct Visit {
    pub(super) q: Vec<f64>,
    pub(super) measured: bool,
    /// (indexed joint, cycle) for indexing tests; (cube, 0) for a cube
    /// campaign (its `cube` column).
    pub(super) tag: Option<(usize, usize)>,
}

pub(super) fn measured(poses: Vec<Vec<f64>>) -> Vec<Visit> {
    poses
        .into_iter()
        .map(|q| Visit {
            q,
            measured: true,
            tag: None,
        })
        .collect()
}

/// The poses of an ISO 9283 cube campaign ([`super::iso_cubes`]): the
/// spec's cubes in its ranges, the poses shared equally, every revolute
/// joint allowed a whole turn per cube where its limits let it; each
/// visit tagged with its cube.
pub(super) fn cubes(
    robot: &Robot,
    spec: &CampaignSpec,
    ranges: &[(f64, f64)],
) -> Result<Vec<Visit>> {
    if robot.dof() < 6 {
        return Err(Error::InvalidParameter(format!(
            "--kind cubes needs a robot of six joints or more (its poses hold a cube's orientation), not {} with {}",
            robot.name,
            robot.dof()
        )));
    }
    let mut iso = super::iso_cubes::IsoCubeSpec::new(
        spec.cubes,
        spec.cube_edge_mm,
        spec.poses / spec.cubes.max(1),
    )
    .with_branches(robot, &[]);
    iso.ranges = Some(ranges.to_vec());
    let c = super::iso_cubes::iso_cubes(robot, &iso, spec.seed)?;
    Ok(c.q
        .into_iter()
        .zip(c.cube)
        .map(|(q, cube)| Visit {
            q,
            measured: true,
            tag: Some((cube, 0)),
        })
        .collect())
}

/// Latin-hypercube sample of `m` points: each joint's range cut into `m`
/// strata, one point per stratum, strata paired by independent permutations.
pub fn lhs(ranges: &[(f64, f64)], m: usize, rng: &mut impl Rng) -> Vec<Vec<f64>> {
    let mut cols: Vec<Vec<f64>> = Vec::with_capacity(ranges.len());
    for (lo, hi) in ranges {
        let mut perm: Vec<usize> = (0..m).collect();
        for i in (1..m).rev() {
            let j = rng.random_range(0..=i);
            perm.swap(i, j);
        }
        cols.push(
            perm.iter()
                .map(|&s| lo + (hi - lo) * (s as f64 + rng.random::<f64>()) / m as f64)
                .collect(),
        );
    }
    (0..m)
        .map(|k| cols.iter().map(|c| c[k]).collect())
        .collect()
}

/// `m` independent uniform points in the ranges.
pub fn uniform(ranges: &[(f64, f64)], m: usize, rng: &mut impl Rng) -> Vec<Vec<f64>> {
    (0..m)
        .map(|_| {
            ranges
                .iter()
                .map(|(lo, hi)| lo + (hi - lo) * rng.random::<f64>())
                .collect()
        })
        .collect()
}

/// Indexing grid of seed 000 eqs 15–16: the range ends plus every multiple of
/// the step inside (10° for ranges ≥ 100°, else a tenth of the range).
pub fn indexing_grid(lo: f64, hi: f64) -> Vec<f64> {
    let span = hi - lo;
    let step = if span >= 100.0 { 10.0 } else { span / 10.0 };
    let mut g = vec![lo];
    let mut v = (lo / step).floor() * step + step;
    while v < hi - 1e-9 {
        if v > lo + 1e-9 {
            g.push(v);
        }
        v += step;
    }
    g.push(hi);
    g
}

fn rest_pose(ranges: &[(f64, f64)]) -> Vec<f64> {
    ranges
        .iter()
        .map(|(lo, hi)| {
            if *lo <= 0.0 && 0.0 <= *hi {
                0.0
            } else {
                0.5 * (lo + hi)
            }
        })
        .collect()
}

/// Smallest TCP distance from a joint axis at which its indexing test can
/// resolve the angle (seed 002 identifies every axis's APD from the circle).
pub const INDEXING_MIN_RADIUS_MM: f64 = 50.0;

/// Distance of the TCP from the axis line of joint `j` (0-based) at `q`.
fn tcp_axis_distance(robot: &Robot, q: &[f64], j: usize) -> f64 {
    let f = robot.frames(q);
    let z = f[j].rotation * Vector3::z();
    let v = f[robot.dof() + 1].translation.vector - f[j].translation.vector;
    (v - z * v.dot(&z)).norm()
}

/// The rest pose for joint `j`'s test: the common rest, unless the TCP lies
/// within [`INDEXING_MIN_RADIUS_MM`] of the axis (a wrist axis with the wrist
/// straight); then the first later revolute joint that moves the TCP off the
/// axis is bent to half of its range's larger end.
fn axis_rest(robot: &Robot, rest: &[f64], ranges: &[(f64, f64)], j: usize) -> Vec<f64> {
    if tcp_axis_distance(robot, rest, j) >= INDEXING_MIN_RADIUS_MM {
        return rest.to_vec();
    }
    for k in j + 1..robot.dof() {
        if robot.links[k].kind != JointKind::Revolute {
            continue;
        }
        let (lo, hi) = ranges[k];
        let mut q = rest.to_vec();
        q[k] = if hi.abs() >= lo.abs() {
            0.5 * hi
        } else {
            0.5 * lo
        };
        if tcp_axis_distance(robot, &q, j) >= INDEXING_MIN_RADIUS_MM {
            return q;
        }
    }
    rest.to_vec()
}

pub(super) fn indexing(robot: &Robot, ranges: &[(f64, f64)], cycles: usize) -> Vec<Visit> {
    let common = rest_pose(ranges);
    let mut visits = Vec::new();
    for (j, link) in robot.links.iter().enumerate() {
        let (lo, hi) = ranges[j];
        if link.kind != JointKind::Revolute || hi - lo < 1e-6 {
            continue;
        }
        let rest = axis_rest(robot, &common, ranges, j);
        let grid = indexing_grid(lo, hi);
        let step = grid[1] - grid[0];
        let over_lo = (0.5 * step).min(lo - robot.limits[j].0);
        let over_hi = (0.5 * step).min(robot.limits[j].1 - hi);
        let mut go = |v: f64, measured: bool, cycle: usize| {
            let mut q = rest.clone();
            q[j] = v;
            visits.push(Visit {
                q,
                measured,
                tag: Some((j + 1, cycle + 1)),
            });
        };
        for c in 0..cycles {
            if over_lo > MOVE_EPS {
                go(lo - over_lo, false, c);
            }
            for &v in &grid {
                go(v, true, c);
            }
            if over_hi > MOVE_EPS {
                go(hi + over_hi, false, c);
            }
            for &v in grid.iter().rev() {
                go(v, true, c);
            }
        }
    }
    visits
}

/// J2 angles of seed 000 §5.2 at which the J1 test is repeated.
pub const CROSSTALK_J2_DEG: [f64; 4] = [0.0, 20.0, 40.0, 60.0];

/// Seed 000 §5.2 (eq 21): J1 indexed at −100°, −80°, …, 100° bidirectionally
/// with J2 held at each of [`CROSSTALK_J2_DEG`] (clamped into J2's range),
/// `cycles` times; all rows are tagged axis 1.
pub(super) fn crosstalk(robot: &Robot, ranges: &[(f64, f64)], cycles: usize) -> Result<Vec<Visit>> {
    if robot.dof() < 2 {
        return Err(Error::InvalidParameter(
            "the cross-talk test needs at least two joints".into(),
        ));
    }
    let rest = rest_pose(ranges);
    let (lo, hi) = (ranges[0].0.max(-100.0), ranges[0].1.min(100.0));
    let grid: Vec<f64> = (0..=10)
        .map(|i| -100.0 + 20.0 * i as f64)
        .filter(|v| *v >= lo - 1e-9 && *v <= hi + 1e-9)
        .collect();
    if grid.len() < 3 {
        return Err(Error::InvalidParameter(
            "the cross-talk test needs J1's range to cover at least 3 of −100°, −80°, …, 100°"
                .into(),
        ));
    }
    let over = 10.0_f64;
    let mut visits = Vec::new();
    for (h, &held) in CROSSTALK_J2_DEG.iter().enumerate() {
        let held = held.clamp(ranges[1].0, ranges[1].1);
        let mut go = |v: f64, measured: bool, cycle: usize| {
            let mut q = rest.clone();
            q[0] = v;
            q[1] = held;
            visits.push(Visit {
                q,
                measured,
                tag: Some((1, h * cycles + cycle + 1)),
            });
        };
        for c in 0..cycles {
            go((grid[0] - over).max(robot.limits[0].0), false, c);
            for &v in &grid {
                go(v, true, c);
            }
            go(
                (grid[grid.len() - 1] + over).min(robot.limits[0].1),
                false,
                c,
            );
            for &v in grid.iter().rev() {
                go(v, true, c);
            }
        }
    }
    Ok(visits)
}

/// Ø`diameter` circle of `points` commanded TCP poses in the base XY plane
/// around the home TCP, orientation fixed at home's; every point checked
/// reachable by IK along the path.
pub fn circle(robot: &Robot, diameter: f64, points: usize) -> Result<Trajectory> {
    if points < 3 || diameter.is_nan() || diameter <= 0.0 {
        return Err(Error::InvalidParameter(
            "circle needs at least 3 points and a positive diameter".into(),
        ));
    }
    let home = robot.fk(&robot.home)?;
    circle_around(robot, &home, &robot.home, diameter, points)
}

/// Ø`diameter` circle of `points` poses in the base XY plane around `center`
/// (orientation fixed at `center`'s), each checked reachable by IK seeded
/// from the previous point (the first from `seed`).
pub fn circle_around(
    robot: &Robot,
    center: &Isometry3<f64>,
    seed: &[f64],
    diameter: f64,
    points: usize,
) -> Result<Trajectory> {
    if points < 3 || diameter.is_nan() || diameter <= 0.0 {
        return Err(Error::InvalidParameter(
            "circle needs at least 3 points and a positive diameter".into(),
        ));
    }
    let home = center;
    let c = home.translation.vector;
    let r = 0.5 * diameter;
    let mut q = seed.to_vec();
    let mut poses = Vec::with_capacity(points);
    for k in 0..points {
        let phi = std::f64::consts::TAU * k as f64 / points as f64;
        let p = c + Vector3::new(r * phi.cos(), r * phi.sin(), 0.0);
        let pose = Isometry3::from_parts(Translation3::from(p), home.rotation);
        q = robot.ik(&IkTarget::pose(&pose), &q, &IkOptions::default())?;
        poses.push(pose);
    }
    Ok(Trajectory::new(poses))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::rng_for;

    #[test]
    fn lhs_has_one_point_per_stratum() {
        let ranges = [(-20.0, 20.0), (0.0, 1.0)];
        let pts = lhs(&ranges, 50, &mut rng_for(3, "t"));
        for (j, (lo, hi)) in ranges.iter().enumerate() {
            let mut strata: Vec<usize> = pts
                .iter()
                .map(|p| ((p[j] - lo) / (hi - lo) * 50.0).floor() as usize)
                .collect();
            strata.sort_unstable();
            assert_eq!(strata, (0..50).collect::<Vec<_>>());
        }
    }

    #[test]
    fn paper_grids() {
        let g2 = indexing_grid(-143.0, 143.0);
        assert_eq!(g2.len(), 31);
        assert_eq!(&g2[..3], &[-143.0, -140.0, -130.0]);
        assert_eq!(indexing_grid(-165.0, 165.0).len(), 35);
    }
}
