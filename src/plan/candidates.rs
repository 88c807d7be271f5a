//! Where a pose may be planned: candidates drawn in the robot's working
//! ranges (or a pool of given poses), the region whose prediction error
//! matters, the tracker's line of sight, and the space-filling choice used
//! before any hyperparameter is known.

use crate::kinematics::Robot;
use crate::stats::rng_for;
use crate::{Error, Result};
use nalgebra::Vector3;
use rand::RngExt;

/// Poses with their planned approach directions λ (±1 per joint).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct PoseSet {
    /// Joint values, degrees (mm for prismatic joints).
    pub q: Vec<Vec<f64>>,
    /// Direction of approach of every joint, ±1.
    pub dir: Vec<Vec<f64>>,
}

impl From<&crate::dataset::Dataset> for PoseSet {
    /// A campaign's poses and directions (its errors, if any, left out).
    fn from(d: &crate::dataset::Dataset) -> Self {
        PoseSet {
            q: d.q.clone(),
            dir: d.dir.clone(),
        }
    }
}

impl PoseSet {
    /// The number of poses.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// Whether there is none.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// The poses at `rows`, in that order.
    pub fn select(&self, rows: &[usize]) -> PoseSet {
        PoseSet {
            q: rows.iter().map(|&i| self.q[i].clone()).collect(),
            dir: rows.iter().map(|&i| self.dir[i].clone()).collect(),
        }
    }

    /// At most `n` poses spread evenly over the set (all of them when there
    /// are fewer), in order.
    pub fn thinned(&self, n: usize) -> PoseSet {
        if self.len() <= n || n == 0 {
            return self.clone();
        }
        let rows: Vec<usize> = (0..n).map(|k| k * self.len() / n).collect();
        self.select(&rows)
    }
}

/// Draw `n` candidate poses in `ranges`: a Latin hypercube of the joints,
/// each joint's λ drawn ±1 with equal odds where both are realisable. A
/// direction is realisable when the joint can come from `step` away on
/// that side without leaving `limits` (a pre-position move): a pose within
/// `step` of its lower limit can only be approached moving down (λ = −1).
pub fn draw(
    ranges: &[(f64, f64)],
    limits: &[(f64, f64)],
    step: &[f64],
    n: usize,
    seed: u64,
) -> PoseSet {
    let mut rng = rng_for(seed, "plan-candidates");
    let q = crate::sim::designs::lhs(ranges, n, &mut rng);
    let dir = q
        .iter()
        .map(|row| directions(row, limits, step, &mut rng))
        .collect();
    PoseSet { q, dir }
}

/// λ for the joints of pose `q`: ±1 with equal odds where a pre-position
/// move `step` back on either side stays within `limits`, else the one
/// side that does (−1 within `step` of the lower limit).
fn directions(
    q: &[f64],
    limits: &[(f64, f64)],
    step: &[f64],
    rng: &mut impl rand::Rng,
) -> Vec<f64> {
    q.iter()
        .zip(limits.iter().zip(step))
        .map(|(v, ((lo, hi), s))| match (v - s >= *lo, v + s <= *hi) {
            (true, true) if rng.random::<bool>() => 1.0,
            (true, true) | (false, _) => -1.0,
            (true, false) => 1.0,
        })
        .collect()
}

/// The index of the largest `score` among the entries not `taken`
/// (the greedy step of every choice here).
pub(super) fn best_untaken(score: &[f64], taken: &[bool]) -> Option<usize> {
    (0..score.len())
        .filter(|&i| !taken[i])
        .max_by(|&a, &b| score[a].total_cmp(&score[b]))
}

/// A laser tracker's line of sight: its position (robot base frame, mm),
/// and optionally the largest distance to the reflector and the largest
/// angle between the reflector's axis (the tool's z axis) and the line to
/// the tracker.
#[derive(Debug, Clone, PartialEq)]
pub struct TrackerView {
    position: Vector3<f64>,
    max_range_mm: Option<f64>,
    max_incidence_deg: Option<f64>,
}

impl TrackerView {
    /// A tracker at `position` (mm, robot base frame), no range or angle limit.
    pub fn new(position: [f64; 3]) -> Result<Self> {
        if position.iter().any(|v| !v.is_finite()) {
            return Err(Error::InvalidParameter(
                "the tracker position needs three finite numbers (mm)".into(),
            ));
        }
        Ok(TrackerView {
            position: Vector3::from(position),
            max_range_mm: None,
            max_incidence_deg: None,
        })
    }

    /// The tracker of a plan's options: at `position` (x, y, z, mm), with
    /// the largest range and incidence if given; `None` without a position.
    pub fn from_options(
        position: Option<&[f64]>,
        max_range: Option<f64>,
        max_incidence: Option<f64>,
    ) -> Result<Option<Self>> {
        let Some(p) = position else {
            return Ok(None);
        };
        let pos: [f64; 3] = p.try_into().map_err(|_| {
            Error::InvalidParameter(format!(
                "--tracker needs x,y,z (three numbers, mm), got {} values",
                p.len()
            ))
        })?;
        if max_range.is_none() && max_incidence.is_none() {
            return Err(Error::InvalidParameter(
                "--tracker alone leaves out no pose: give --max-range and/or --max-incidence"
                    .into(),
            ));
        }
        let mut view = TrackerView::new(pos)?;
        if let Some(r) = max_range {
            view = view.max_range(r)?;
        }
        if let Some(i) = max_incidence {
            view = view.max_incidence(i)?;
        }
        Ok(Some(view))
    }

    /// The largest tracker–reflector distance, mm (> 0).
    pub fn max_range(mut self, mm: f64) -> Result<Self> {
        if !(mm.is_finite() && mm > 0.0) {
            return Err(Error::InvalidParameter(format!(
                "the tracker's maximum range must be a positive distance in mm, not {mm}"
            )));
        }
        self.max_range_mm = Some(mm);
        Ok(self)
    }

    /// The largest incidence angle of the reflector, degrees (0–180).
    pub fn max_incidence(mut self, deg: f64) -> Result<Self> {
        if !(deg.is_finite() && deg > 0.0 && deg <= 180.0) {
            return Err(Error::InvalidParameter(format!(
                "the reflector's maximum incidence must be an angle in (0, 180] degrees, not {deg}"
            )));
        }
        self.max_incidence_deg = Some(deg);
        Ok(self)
    }

    /// Whether the tracker sees the reflector at the robot's pose `q`
    /// (nominal kinematics).
    pub fn sees(&self, robot: &Robot, q: &[f64]) -> bool {
        let Ok(pose) = robot.fk(q) else {
            return false;
        };
        let to_tracker = self.position - pose.translation.vector;
        let dist = to_tracker.norm();
        if self.max_range_mm.is_some_and(|r| dist > r) {
            return false;
        }
        if let Some(max) = self.max_incidence_deg {
            if dist == 0.0 {
                return false;
            }
            let axis = pose.rotation * Vector3::z();
            let cos = (axis.dot(&to_tracker) / dist).clamp(-1.0, 1.0);
            if cos.acos().to_degrees() > max {
                return false;
            }
        }
        true
    }
}

/// Scaled coordinates of a pose for distances: each joint over its range,
/// λ as ±0.5 (a flipped direction counts as far as a whole range).
fn scaled(q: &[f64], dir: &[f64], ranges: &[(f64, f64)]) -> Vec<f64> {
    q.iter()
        .zip(ranges)
        .map(|(v, (lo, hi))| (v - lo) / (hi - lo).max(1e-12))
        .chain(dir.iter().map(|l| 0.5 * l))
        .collect()
}

fn dist2(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum()
}

/// A space-filling choice of `k` poses of `cand` (greedy maximin: each the
/// candidate farthest from the measured poses `measured` and those chosen
/// before it, in joints scaled by `ranges` and λ), the first the farthest
/// from `measured` or, without any, the one nearest the candidates' centre.
pub fn maximin(cand: &PoseSet, measured: &PoseSet, ranges: &[(f64, f64)], k: usize) -> Vec<usize> {
    let pts: Vec<Vec<f64>> = (0..cand.len())
        .map(|i| scaled(&cand.q[i], &cand.dir[i], ranges))
        .collect();
    let mut nearest = vec![f64::INFINITY; pts.len()];
    for (q, d) in measured.q.iter().zip(&measured.dir) {
        let p = scaled(q, d, ranges);
        for (n, c) in nearest.iter_mut().zip(&pts) {
            *n = n.min(dist2(c, &p));
        }
    }
    if measured.is_empty() && !pts.is_empty() {
        let dim = pts[0].len();
        let centre: Vec<f64> = (0..dim)
            .map(|j| pts.iter().map(|p| p[j]).sum::<f64>() / pts.len() as f64)
            .collect();
        for (n, c) in nearest.iter_mut().zip(&pts) {
            *n = -dist2(c, &centre);
        }
    }
    let mut chosen = Vec::with_capacity(k);
    let mut taken = vec![false; pts.len()];
    let mut from_centre = measured.is_empty();
    for _ in 0..k.min(pts.len()) {
        let best = best_untaken(&nearest, &taken).expect("a candidate left");
        chosen.push(best);
        taken[best] = true;
        if from_centre {
            nearest.fill(f64::INFINITY);
            from_centre = false;
        }
        let p = pts[best].clone();
        for (n, c) in nearest.iter_mut().zip(&pts) {
            *n = n.min(dist2(c, &p));
        }
    }
    chosen
}

/// A first batch that covers the region as it is distributed: `k`
/// candidates chosen greedily to lower the region points' mean distance to
/// their nearest chosen-or-measured pose the most (a greedy k-medoids, in
/// joints scaled by `ranges` and λ). Unlike [`maximin`], which reaches for
/// the boundary first, it puts the poses where the region's poses are.
pub fn covering(
    cand: &PoseSet,
    region: &PoseSet,
    measured: &PoseSet,
    ranges: &[(f64, f64)],
    k: usize,
) -> Vec<usize> {
    use rayon::prelude::*;
    let pts: Vec<Vec<f64>> = (0..cand.len())
        .map(|i| scaled(&cand.q[i], &cand.dir[i], ranges))
        .collect();
    let zs: Vec<Vec<f64>> = (0..region.len())
        .map(|i| scaled(&region.q[i], &region.dir[i], ranges))
        .collect();
    let mut nearest: Vec<f64> = zs
        .iter()
        .map(|z| {
            measured
                .q
                .iter()
                .zip(&measured.dir)
                .map(|(q, d)| dist2(z, &scaled(q, d, ranges)).sqrt())
                .fold(f64::INFINITY, f64::min)
        })
        .collect();
    // the distance of a region point with nothing near it counts as the
    // largest scaled distance there is
    let cap = (ranges.len() as f64 * 2.0).sqrt();
    nearest.iter_mut().for_each(|n| *n = n.min(cap));
    let mut chosen = Vec::with_capacity(k);
    let mut taken = vec![false; pts.len()];
    for _ in 0..k.min(pts.len()) {
        let gain: Vec<f64> = pts
            .par_iter()
            .map(|c| {
                zs.iter()
                    .zip(&nearest)
                    .map(|(z, n)| (n - dist2(c, z).sqrt()).max(0.0))
                    .sum()
            })
            .collect();
        let best = best_untaken(&gain, &taken).expect("a candidate left");
        taken[best] = true;
        chosen.push(best);
        for (n, z) in nearest.iter_mut().zip(&zs) {
            *n = n.min(dist2(&pts[best], z).sqrt());
        }
    }
    chosen
}

/// `n` candidates around the region's poses: a region pose (cycled, in
/// order) moved by a uniform offset of at most `spread` of each joint's
/// range, clamped into `ranges`, with λ drawn as in [`draw`]. Poses drawn
/// in the whole working range rarely come near a task, a curve in joint
/// space; these do.
pub fn around(
    region: &PoseSet,
    ranges: &[(f64, f64)],
    limits: &[(f64, f64)],
    step: &[f64],
    spread: f64,
    n: usize,
    seed: u64,
) -> PoseSet {
    if region.is_empty() {
        return PoseSet::default();
    }
    let mut rng = rng_for(seed, "plan-candidates-around");
    let mut out = PoseSet::default();
    for k in 0..n {
        let base = &region.q[k % region.len()];
        let q: Vec<f64> = base
            .iter()
            .zip(ranges)
            .map(|(v, (lo, hi))| {
                let w = spread * (hi - lo);
                (v + w * (2.0 * rng.random::<f64>() - 1.0)).clamp(*lo, *hi)
            })
            .collect();
        let dir = directions(&q, limits, step, &mut rng);
        out.q.push(q);
        out.dir.push(dir);
    }
    out
}
