//! Robotic probing of a straightedge, corrected by the physics model
//! (seed 002 §3, eqs 3–6, Table 2).
//!
//! A touch-trigger probe records the encoder angles `Θ(k)` at contact. The
//! stylus really is on the (straight) face; the nominal model places it at
//! `p_nominal(k) = f_nominal(Θ(k))` (eq 3), the identified model at
//! `p_proposed(k) = f_proposed(Θ(k))` (eq 6). The probing error shows as the
//! straightness of the probed profile: the displacement along the probing
//! direction from the least-squares line, max − min, and its standard
//! deviation.
//!
//! Simulation: for each point the probe approaches from `approach_mm` before
//! the face along the probing direction, so every joint's λ comes from that
//! approach move; the encoder reading at contact is the `q` at which the
//! true robot's TCP is on the face (solved by Newton steps with the nominal
//! Jacobian), minus the joint repeatability noise.

use super::PhysicsModel;
use crate::kinematics::{IkOptions, IkTarget, Robot};
use crate::sim::{TrueRobot, gaussian};
use crate::space::derive_directions;
use crate::{Error, Result};
use nalgebra::{Isometry3, Vector3};
use rand::Rng;
use serde::{Deserialize, Serialize};

/// One straightedge face to probe.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Straightedge {
    /// Name, e.g. "#1 side".
    pub name: String,
    /// Pose of the first contact point (orientation = the probe's).
    pub start: Isometry3<f64>,
    /// Unit direction along the edge (base frame).
    pub along: Vector3<f64>,
    /// Unit probing direction (towards the face, base frame).
    pub probe: Vector3<f64>,
    /// Length of the probed stretch along the edge, mm.
    pub length_mm: f64,
    /// Contact points, evenly spaced over `length_mm` (at least 3).
    pub points: usize,
    /// Distance before the face from which each touch starts, mm.
    pub approach_mm: f64,
}

/// Encoder readings of one probing run.
#[derive(Debug, Clone, PartialEq)]
pub struct ProbeRun {
    /// Encoder readings `Θ(k)` at each contact, with the joint repeatability
    /// noise (degrees or mm).
    pub joints: Vec<Vec<f64>>,
    /// Direction coefficients λ (±1) of each contact, from its approach move.
    pub dir: Vec<Vec<f64>>,
    /// The true contact points (on the straight face).
    pub contact: Vec<Vector3<f64>>,
}

/// Straightness of a probed profile, mm.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Straightness {
    /// max − min displacement from the least-squares line.
    pub straightness_mm: f64,
    /// Standard deviation of the displacement.
    pub std_mm: f64,
}

/// Probe `edge` on the true robot, starting from joints `start`.
pub fn probe(
    robot: &TrueRobot,
    edge: &Straightedge,
    start: &[f64],
    rng: &mut impl Rng,
) -> Result<ProbeRun> {
    let bad = |v: f64| v.is_nan() || v <= 0.0;
    if edge.points < 3 || bad(edge.length_mm) || bad(edge.approach_mm) {
        return Err(Error::InvalidParameter(
            "straightedge needs ≥ 3 points, a positive length and approach".into(),
        ));
    }
    let nominal = &robot.nominal;
    let ik = IkOptions::default();
    let step = edge.length_mm / (edge.points - 1) as f64;
    let mut seq = Vec::with_capacity(2 * edge.points);
    let mut contact = Vec::with_capacity(edge.points);
    let mut prev = start.to_vec();
    let ctx = Default::default();
    for k in 0..edge.points {
        let mut pose = edge.start;
        pose.translation.vector += edge.along * (k as f64 * step);
        let p = pose.translation.vector;
        let mut away = pose;
        away.translation.vector -= edge.probe * edge.approach_mm;
        let q0 = nominal.ik(&IkTarget::pose(&away), &prev, &ik)?;
        // the encoder reading at which the *true* TCP touches p: move the
        // nominal target until the true TCP (with the λ of the approach) is on p
        let mut target = pose;
        let mut q = nominal.ik(&IkTarget::pose(&target), &q0, &ik)?;
        for _ in 0..20 {
            let dir = derive_directions(&[q0.clone(), q.clone()], Some(&prev))[1].clone();
            let actual = robot.tcp(&robot.actual_joints(&q, &dir, &ctx), &ctx);
            let miss = p - actual;
            if miss.norm() < 1e-9 {
                break;
            }
            target.translation.vector += miss;
            q = nominal.ik(&IkTarget::pose(&target), &q, &ik)?;
        }
        let noisy: Vec<f64> = q
            .iter()
            .map(|v| v - gaussian(rng, robot.noise.repeatability_sigma_deg))
            .collect();
        seq.push(q0);
        seq.push(noisy);
        contact.push(p);
        prev = q;
    }
    let dirs = derive_directions(&seq, Some(start));
    Ok(ProbeRun {
        joints: seq.iter().skip(1).step_by(2).cloned().collect(),
        dir: dirs.iter().skip(1).step_by(2).cloned().collect(),
        contact,
    })
}

/// Straightness of `points` probed along `along` in direction `probe`.
pub fn straightness(
    points: &[Vector3<f64>],
    along: &Vector3<f64>,
    probe: &Vector3<f64>,
) -> Straightness {
    // displacement along the probing direction vs position along the edge
    let s: Vec<f64> = points.iter().map(|p| p.dot(along)).collect();
    let d: Vec<f64> = points.iter().map(|p| p.dot(probe)).collect();
    let n = s.len() as f64;
    let (ms, md) = (s.iter().sum::<f64>() / n, d.iter().sum::<f64>() / n);
    let sxx: f64 = s.iter().map(|v| (v - ms).powi(2)).sum();
    let sxy: f64 = s.iter().zip(&d).map(|(a, b)| (a - ms) * (b - md)).sum();
    let slope = if sxx > 0.0 { sxy / sxx } else { 0.0 };
    let r: Vec<f64> = s
        .iter()
        .zip(&d)
        .map(|(a, b)| b - md - slope * (a - ms))
        .collect();
    let (lo, hi) = r
        .iter()
        .fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
    Straightness {
        straightness_mm: hi - lo,
        std_mm: (r.iter().map(|v| v * v).sum::<f64>() / n).sqrt(),
    }
}

/// Probed points by a model: nominal (eq 3) when `model` is `None`, else
/// `f_proposed(Θ(k))` (eq 6).
pub fn probed_points(
    nominal: &Robot,
    model: Option<&PhysicsModel>,
    run: &ProbeRun,
) -> Vec<Vector3<f64>> {
    run.joints
        .iter()
        .zip(&run.dir)
        .map(|(q, d)| match model {
            None => nominal.fk_unchecked(q).translation.vector,
            Some(m) => m.tcp(q, d),
        })
        .collect()
}

/// The three straightedge locations of the example (seed 002 Fig. 4 in
/// spirit): a 1000 mm edge along the base Y axis through the TCP of the
/// probing pose, and 200 mm further out and lower / 150 mm closer and higher;
/// each probed on its side face (towards −X) and top face (towards −Z), 100
/// points. The probing pose is home with J5 bent by 60° (a straight wrist is
/// singular); it is returned as the start joints.
pub fn example_edges(robot: &Robot) -> Result<(Vec<Straightedge>, Vec<f64>)> {
    let mut q_ref = robot.home.clone();
    if q_ref.len() >= 5 {
        q_ref[4] += 60.0;
    }
    let home = robot.fk(&q_ref)?;
    let mut out = Vec::new();
    for (i, off) in [
        Vector3::new(0.0, 0.0, 0.0),
        Vector3::new(200.0, 0.0, -200.0),
        Vector3::new(-150.0, 0.0, 150.0),
    ]
    .iter()
    .enumerate()
    {
        for (face, probe) in [("side", -Vector3::x()), ("top", -Vector3::z())] {
            let mut start = home;
            start.translation.vector += off - Vector3::y() * 500.0;
            out.push(Straightedge {
                name: format!("#{} {face}", i + 1),
                start,
                along: Vector3::y(),
                probe,
                length_mm: 1000.0,
                points: 100,
                approach_mm: 5.0,
            });
        }
    }
    Ok((out, q_ref))
}

/// One row of the seed 002 Table 2 analogue.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ProbingRow {
    /// The straightedge's name.
    pub edge: String,
    /// With the nominal model (eq 3).
    pub nominal: Straightness,
    /// With the identified D-H model only.
    pub dh: Straightness,
    /// With the full physics model (D-H + APD tables, eq 6).
    pub full: Straightness,
}

impl ProbingRow {
    /// Reduction of the straightness error by the full model against the
    /// nominal one, `100 (1 − full/nominal)`, %.
    pub fn reduction_pct(&self) -> f64 {
        100.0 * (1.0 - self.full.straightness_mm / self.nominal.straightness_mm)
    }
}

/// Simulate robot `name` of `seed`, identify its physics models from its
/// indexing tests (each axis indexed over the range the probing uses, 5°
/// margin, and at least the campaign's range) and its Latin-hypercube
/// campaign (as [`super::compare`]), probe
/// the [`example_edges`] and report the straightness with each model.
///
/// With `noise == false` the tracker and the joint repeatability are switched
/// off everywhere (identification and probing), which shows the systematic
/// part of the probing error alone.
pub fn probing_example(name: &str, seed: u64, noise: bool) -> Result<(Vec<ProbingRow>, String)> {
    use crate::sim::{CampaignKind, CampaignSpec, ErrorProfile, campaign, rng_for};
    let nominal = crate::kinematics::load_robot(name)?;
    let mut robot = TrueRobot::draw(&nominal, &ErrorProfile::for_robot(&nominal), seed);
    if !noise {
        robot = robot.noise_free();
    }
    // index every axis over the range the probing uses (and the campaign's)
    let (edges, start) = example_edges(&nominal)?;
    let mut ranges = nominal.work_ranges.clone();
    let ik = IkOptions::default();
    for e in &edges {
        let mut q = start.clone();
        for k in 0..e.points {
            let mut pose = e.start;
            pose.translation.vector += e.along * (k as f64 * e.length_mm / (e.points - 1) as f64);
            q = nominal.ik(&IkTarget::pose(&pose), &q, &ik)?;
            for (j, r) in ranges.iter_mut().enumerate() {
                let (lo, hi) = nominal.limits[j];
                *r = ((r.0).min(q[j] - 5.0).max(lo), (r.1).max(q[j] + 5.0).min(hi));
            }
        }
    }
    let mut idx_spec = CampaignSpec::new(CampaignKind::Indexing, seed);
    idx_spec.ranges = Some(ranges);
    let indexing = campaign::measurements(&robot, &idx_spec)?;
    let id = super::identify_physics(
        &indexing,
        &campaign::measurements(&robot, &CampaignSpec::new(CampaignKind::Lhs, seed))?,
        &nominal,
    )?;
    let mut rng = rng_for(seed, "probing");
    let mut rows = Vec::new();
    for edge in edges {
        let run = probe(&robot, &edge, &start, &mut rng)?;
        let st = |m: Option<&PhysicsModel>| {
            straightness(&probed_points(&nominal, m, &run), &edge.along, &edge.probe)
        };
        rows.push(ProbingRow {
            edge: edge.name.clone(),
            nominal: st(None),
            dh: st(Some(&id.dh)),
            full: st(Some(&id.full)),
        });
    }
    Ok((rows, id.method))
}
