//! ISO 9283 cube campaigns: poses clustered in a few cubes of the
//! workspace, as a performance test measures them, instead of spread over
//! the joint ranges.
//!
//! ISO 9283 §6.2 places a cube in the most used part of the workspace,
//! its edges parallel to the base frame, and measures five points: P1 at
//! the centre and P2–P5 on one diagonal plane (the plane through two
//! opposite edges), on the plane's diagonals at [`ISO_CORNER_INSET`] of
//! the diagonal's length from the corners. [`iso_cubes`] adds random
//! points in each cube with orientations tilted a little from the cube's,
//! and varies the branch from cube to cube (elbow and wrist flips, whole
//! turns of the joints whose limits allow them) as a real campaign that
//! moves the robot between cubes with joint moves does, so that several
//! joints span more than half a turn over the campaign.
//!
//! Cube centres come from joint configurations drawn in the spec's ranges
//! (so every cube is reachable on the branch it was drawn on): each cube
//! is kept only if all its poses are reached by the nominal inverse
//! kinematics, seeded from that configuration, without any joint moving
//! farther than [`IsoCubeSpec::max_branch_step_deg`] from it.
//! [`measure_cubes`] measures the poses on a [`TrueRobot`] in the order
//! visited. Everything is deterministic for a seed.

use super::{PoseContext, TrueRobot, gaussian, rng_for};
use crate::dataset::Dataset;
use crate::kinematics::{IkOptions, IkTarget, JointKind, Robot};
use crate::{Error, Result};
use nalgebra::{Isometry3, Translation3, UnitQuaternion, Vector3};
use rand::{Rng, RngExt};

/// Distance of ISO 9283's points P2–P5 from the corners of the cube's
/// diagonal plane, as a share of the plane's diagonal (ISO 9283 §6.2.3:
/// 10 % of the diagonal).
pub const ISO_CORNER_INSET: f64 = 0.1;

/// Number of ISO 9283 points per cube (P1 … P5).
pub const ISO_POINTS: usize = 5;

/// What [`iso_cubes`] draws.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoCubeSpec {
    /// Number of cubes.
    pub cubes: usize,
    /// Cube edge, mm.
    pub edge_mm: f64,
    /// Poses per cube: the [`ISO_POINTS`] ISO points, then random points
    /// inside the cube (at least [`ISO_POINTS`]).
    pub poses_per_cube: usize,
    /// Largest tilt of a random point's orientation from the cube's
    /// orientation (rotation about a random axis), degrees; the ISO points
    /// keep the cube's orientation.
    pub tilt_deg: f64,
    /// Joint ranges the cubes' configurations are drawn in (default: the
    /// robot's `work_ranges`).
    pub ranges: Option<Vec<(f64, f64)>>,
    /// Joints (0-based) whose drawn value is negated at random per cube
    /// (a branch flip, e.g. the elbow or the wrist), when the limits allow.
    pub flip_joints: Vec<usize>,
    /// Joints (0-based) given a random whole turn (−360°, 0 or +360°) per
    /// cube, among those that keep every pose of the cube inside the limits.
    pub turn_joints: Vec<usize>,
    /// Largest distance of any joint of a cube's pose from the cube's
    /// configuration, degrees: a cube whose poses need more (the branch
    /// changes inside it, or a singularity) is drawn again.
    pub max_branch_step_deg: f64,
    /// Cube draws tried per cube before giving up.
    pub max_attempts: usize,
    /// Visit the cube's poses in a random order (true) or in the order
    /// drawn (ISO points first).
    pub shuffle: bool,
}

impl IsoCubeSpec {
    /// `cubes` cubes of edge `edge_mm` with `poses_per_cube` poses each,
    /// tilts up to 10°, the robot's work ranges, no flips or turns.
    pub fn new(cubes: usize, edge_mm: f64, poses_per_cube: usize) -> Self {
        IsoCubeSpec {
            cubes,
            edge_mm,
            poses_per_cube,
            tilt_deg: 10.0,
            ranges: None,
            flip_joints: Vec::new(),
            turn_joints: Vec::new(),
            max_branch_step_deg: 90.0,
            max_attempts: 200,
            shuffle: true,
        }
    }

    /// Every revolute joint may turn, and the joints `flips` may flip.
    pub fn with_branches(mut self, robot: &Robot, flips: &[usize]) -> Self {
        self.flip_joints = flips.to_vec();
        self.turn_joints = (0..robot.dof())
            .filter(|&j| robot.links[j].kind == JointKind::Revolute)
            .collect();
        self
    }

    /// The spec's errors before any draw.
    pub fn validate(&self, robot: &Robot) -> Result<()> {
        let bad = |what: String| {
            Err(Error::InvalidParameter(format!(
                "ISO cube campaign: {what}"
            )))
        };
        if self.cubes == 0 {
            return bad("needs at least one cube".into());
        }
        if !(self.edge_mm.is_finite() && self.edge_mm > 0.0) {
            return bad(format!("cube edge {} mm must be positive", self.edge_mm));
        }
        if self.poses_per_cube < ISO_POINTS {
            return bad(format!(
                "{} poses per cube: at least the {ISO_POINTS} ISO points",
                self.poses_per_cube
            ));
        }
        if !(self.tilt_deg.is_finite() && (0.0..=180.0).contains(&self.tilt_deg)) {
            return bad(format!("tilt {}° must be in [0, 180]", self.tilt_deg));
        }
        if !(self.max_branch_step_deg.is_finite() && self.max_branch_step_deg > 0.0) {
            return bad("the branch step must be positive".into());
        }
        if self.max_attempts == 0 {
            return bad("needs at least one attempt per cube".into());
        }
        let n = robot.dof();
        if let Some(j) = self
            .flip_joints
            .iter()
            .chain(&self.turn_joints)
            .find(|&&j| j >= n)
        {
            return bad(format!("joint {} does not exist ({n} joints)", j + 1));
        }
        if let Some(r) = &self.ranges {
            if r.len() != n {
                return Err(Error::JointCount {
                    expected: n,
                    got: r.len(),
                });
            }
            for (j, ((lo, hi), (llo, lhi))) in r.iter().zip(&robot.limits).enumerate() {
                if !(lo.is_finite() && hi.is_finite() && lo <= hi && lo >= llo && hi <= lhi) {
                    return bad(format!(
                        "range of joint {} ({lo}, {hi}) must be ordered and inside the limits ({llo}, {lhi})",
                        j + 1
                    ));
                }
            }
        }
        Ok(())
    }
}

/// An ISO 9283 cube campaign's poses, in the order visited.
#[derive(Debug, Clone, PartialEq)]
pub struct IsoCubeCampaign {
    /// Commanded joints, one row per pose.
    pub q: Vec<Vec<f64>>,
    /// The cube (0-based) of each pose: the group label of a
    /// leave-one-cube-out validation.
    pub cube: Vec<usize>,
    /// Which ISO point (1–5) a pose is, `None` for a random point.
    pub iso_point: Vec<Option<usize>>,
    /// The cubes' centres (nominal TCP), mm.
    pub centres_mm: Vec<[f64; 3]>,
    /// The joint configuration each cube was drawn around (after its
    /// flips and turns).
    pub configurations: Vec<Vec<f64>>,
}

impl IsoCubeCampaign {
    /// Number of poses.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// Whether there is no pose.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Add poses out of the cubes, as a real campaign has: the robot's home
    /// pose first (with `home`), and `checks` poses drawn uniformly in the
    /// work ranges, inserted at seeded random places of the sequence. They
    /// form one more group (label `centres_mm.len()`) for
    /// leave-one-cube-out.
    pub fn add_out_of_cube_poses(&mut self, robot: &Robot, checks: usize, home: bool, seed: u64) {
        use rand::RngExt;
        let group = self.centres_mm.len();
        let mut rng = crate::stats::rng_for(seed, "out-of-cube poses");
        for _ in 0..checks {
            let q: Vec<f64> = robot
                .work_ranges
                .iter()
                .map(|(lo, hi)| lo + (hi - lo) * rng.random::<f64>())
                .collect();
            let at = rng.random_range(0..=self.q.len());
            self.q.insert(at, q);
            self.cube.insert(at, group);
            self.iso_point.insert(at, None);
        }
        if home {
            self.q.insert(0, robot.home.clone());
            self.cube.insert(0, group);
            self.iso_point.insert(0, None);
        }
    }

    /// The rows of cube `c`.
    pub fn rows_of(&self, c: usize) -> Vec<usize> {
        (0..self.len()).filter(|&i| self.cube[i] == c).collect()
    }

    /// The span (max − min) of each joint over the campaign, degrees.
    pub fn joint_spans(&self) -> Vec<f64> {
        let n = self.q.first().map_or(0, Vec::len);
        (0..n)
            .map(|j| {
                let (lo, hi) = self
                    .q
                    .iter()
                    .fold((f64::MAX, f64::MIN), |(l, h), r| (l.min(r[j]), h.max(r[j])));
                hi - lo
            })
            .collect()
    }
}

/// The offsets from a cube's centre of ISO 9283's points P1–P5 for a cube
/// of edge `edge_mm` (base-frame axes): P1 the centre; P2–P5 on the
/// diagonal plane through the edges `y = z = −e/2` and `y = z = +e/2`, at
/// [`ISO_CORNER_INSET`] of the plane's diagonal from its corners.
pub fn iso_points(edge_mm: f64) -> [Vector3<f64>; ISO_POINTS] {
    let h = 0.5 * edge_mm;
    // a corner is half a diagonal from the centre, so the inset point is
    // at (1 − 2·inset) of the corner's offset
    let s = 1.0 - 2.0 * ISO_CORNER_INSET;
    [
        Vector3::zeros(),
        Vector3::new(-h, -h, -h) * s,
        Vector3::new(h, -h, -h) * s,
        Vector3::new(h, h, h) * s,
        Vector3::new(-h, h, h) * s,
    ]
}

/// The eight corners of a cube of edge `edge_mm` around the origin.
fn corners(edge_mm: f64) -> Vec<Vector3<f64>> {
    let h = 0.5 * edge_mm;
    (0..8)
        .map(|k| {
            let sign = |b: usize| if k >> b & 1 == 1 { h } else { -h };
            Vector3::new(sign(0), sign(1), sign(2))
        })
        .collect()
}

/// A rotation by an angle uniform in [0, `max_deg`] about a random axis.
fn tilt(rng: &mut impl Rng, max_deg: f64) -> UnitQuaternion<f64> {
    let axis = loop {
        let v = Vector3::from_fn(|_, _| gaussian(rng, 1.0));
        if v.norm() > f64::EPSILON {
            break v.normalize();
        }
    };
    let angle = (max_deg * rng.random::<f64>()).to_radians();
    UnitQuaternion::from_scaled_axis(axis * angle)
}

/// One cube's poses, or `None` when a pose cannot be reached on the
/// branch of `config`.
fn cube_poses(
    robot: &Robot,
    spec: &IsoCubeSpec,
    config: &[f64],
    rng: &mut impl Rng,
) -> Option<(Vector3<f64>, Vec<Vec<f64>>)> {
    let centre = robot.fk(config).ok()?;
    let c = centre.translation.vector;
    let opts = IkOptions::default();
    let reach = |p: Vector3<f64>, r: UnitQuaternion<f64>| -> Option<Vec<f64>> {
        let target = IkTarget::pose(&Isometry3::from_parts(Translation3::from(c + p), r));
        let q = robot.ik(&target, config, &opts).ok()?;
        let near = q
            .iter()
            .zip(config)
            .all(|(a, b)| (a - b).abs() <= spec.max_branch_step_deg);
        (near && robot.within_limits(&q)).then_some(q)
    };
    // the whole cube must be reachable on this branch
    for k in corners(spec.edge_mm) {
        reach(k, centre.rotation)?;
    }
    let mut poses = Vec::with_capacity(spec.poses_per_cube);
    for p in iso_points(spec.edge_mm) {
        poses.push(reach(p, centre.rotation)?);
    }
    let h = 0.5 * spec.edge_mm;
    while poses.len() < spec.poses_per_cube {
        let p = Vector3::from_fn(|_, _| h * (2.0 * rng.random::<f64>() - 1.0));
        let r = centre.rotation * tilt(rng, spec.tilt_deg);
        // a tilted orientation the branch cannot reach is drawn again; the
        // corners were reached, so most draws succeed
        let mut q = reach(p, r);
        for _ in 1..spec.max_attempts {
            if q.is_some() {
                break;
            }
            let r = centre.rotation * tilt(rng, spec.tilt_deg);
            q = reach(p, r);
        }
        poses.push(q?);
    }
    Some((c, poses))
}

/// Apply a random whole turn to each of `spec.turn_joints` that keeps every
/// pose of the cube (and its configuration) inside the limits.
fn turn(
    robot: &Robot,
    spec: &IsoCubeSpec,
    config: &mut [f64],
    poses: &mut [Vec<f64>],
    rng: &mut impl Rng,
) {
    for &j in &spec.turn_joints {
        let (lo, hi) = robot.limits[j];
        let fits = |k: f64| {
            poses
                .iter()
                .map(|q| q[j])
                .chain([config[j]])
                .all(|v| (lo..=hi).contains(&(v + k)))
        };
        let options: Vec<f64> = [-360.0, 0.0, 360.0]
            .into_iter()
            .filter(|&k| fits(k))
            .collect();
        let k = options[rng.random_range(0..options.len())];
        config[j] += k;
        for q in poses.iter_mut() {
            q[j] += k;
        }
    }
}

/// Draw an ISO 9283 cube campaign for `robot` from `seed` (see the module
/// documentation). An error names the cube that could not be placed in
/// `spec.max_attempts` draws.
pub fn iso_cubes(robot: &Robot, spec: &IsoCubeSpec, seed: u64) -> Result<IsoCubeCampaign> {
    spec.validate(robot)?;
    let ranges = spec
        .ranges
        .clone()
        .unwrap_or_else(|| robot.work_ranges.clone());
    let mut rng = rng_for(seed, "iso-cubes");
    let mut out = IsoCubeCampaign {
        q: Vec::new(),
        cube: Vec::new(),
        iso_point: Vec::new(),
        centres_mm: Vec::new(),
        configurations: Vec::new(),
    };
    for c in 0..spec.cubes {
        let mut placed = None;
        for _ in 0..spec.max_attempts {
            let mut config: Vec<f64> = ranges
                .iter()
                .map(|(lo, hi)| lo + (hi - lo) * rng.random::<f64>())
                .collect();
            for &j in &spec.flip_joints {
                let (lo, hi) = robot.limits[j];
                if rng.random::<bool>() && (lo..=hi).contains(&-config[j]) {
                    config[j] = -config[j];
                }
            }
            if let Some((centre, poses)) = cube_poses(robot, spec, &config, &mut rng) {
                placed = Some((config, centre, poses));
                break;
            }
        }
        let Some((mut config, centre, mut poses)) = placed else {
            return Err(Error::InvalidParameter(format!(
                "ISO cube campaign: cube {} of edge {} mm could not be placed in {} draws",
                c + 1,
                spec.edge_mm,
                spec.max_attempts
            )));
        };
        turn(robot, spec, &mut config, &mut poses, &mut rng);
        let mut order: Vec<usize> = (0..poses.len()).collect();
        if spec.shuffle {
            for i in (1..order.len()).rev() {
                order.swap(i, rng.random_range(0..=i));
            }
        }
        for &k in &order {
            out.q.push(poses[k].clone());
            out.cube.push(c);
            out.iso_point.push((k < ISO_POINTS).then_some(k + 1));
        }
        out.centres_mm.push(centre.into());
        out.configurations.push(config);
    }
    Ok(out)
}

/// Measure the poses `q` on `truth`, in the order given (directions λ from
/// that order, the first from the nominal home pose): the true robot's
/// error (geometry, angular deviation with backlash, compliance) plus its
/// per-axis noise (repeatability and tracker), drawn from `seed`.
pub fn measure_cubes(truth: &TrueRobot, q: Vec<Vec<f64>>, seed: u64) -> Result<Dataset> {
    let measure = vec![true; q.len()];
    measure_sequence(truth, &q, &measure, "<ISO 9283 cubes>", seed)
}

/// Run the robot through the poses `q` in order from the nominal home pose
/// and measure those flagged in `measure` (a plan's measured poses between
/// its via-points): each measured row gets the directions λ the whole
/// sequence realises, the true robot's error and its per-axis noise drawn
/// from `seed`.
pub fn measure_sequence(
    truth: &TrueRobot,
    q: &[Vec<f64>],
    measure: &[bool],
    source: &str,
    seed: u64,
) -> Result<Dataset> {
    let home = truth.nominal.home.clone();
    let dir = crate::space::derive_directions(q, Some(&home));
    let rows: Vec<usize> = (0..q.len())
        .filter(|&i| measure.get(i) == Some(&true))
        .collect();
    let mut data = Dataset::from_poses(
        source,
        rows.iter().map(|&i| q[i].clone()).collect(),
        Some(rows.iter().map(|&i| dir[i].clone()).collect()),
    )?;
    truth.nominal.check_dataset(&data)?;
    let ctx = PoseContext::default();
    let mut rng = rng_for(seed, "iso-cubes-noise");
    let errors = data
        .q
        .iter()
        .zip(&data.dir)
        .map(|(q, d)| {
            let e = truth.error(q, d, &ctx);
            let s = truth.noise_sigma(q);
            std::array::from_fn(|a| e[a] + gaussian(&mut rng, s[a]))
        })
        .collect();
    data.errors = Some(errors);
    Ok(data)
}
