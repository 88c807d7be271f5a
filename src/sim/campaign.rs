//! A simulated campaign: what to simulate ([`CampaignSpec`]), its
//! measurement on a [`TrueRobot`] (the pose-dependent error, the
//! measurement effects and the noise, in the order the robot visits the
//! poses) and the truth file beside it ([`Truth`]). The poses of each
//! design are in [`super::designs`]:
//!
//! - `lhs`: Latin-hypercube poses in the joint ranges (default: the robot's
//!   `work_ranges`, seed 004 Table 2 for the COMAU), visited in the order drawn,
//!   so directions λ come from the sequence (seed 003 §IV.B).
//! - `verify`: independent uniformly random poses (seed 003 §IV.C: 30).
//! - `indexing`: single-axis indexing tests (seed 000 §2.3): each revolute joint
//!   in turn is indexed over a grid forward then backward, `cycles` times, the
//!   other joints at rest; every grid point is approached from both sides. A
//!   wrist axis that the TCP lies on at rest is tested with a later joint bent
//!   (seed 002 identifies every axis), so its circle is at least 50 mm.
//! - `circle`: a Ø100 mm circle of commanded TCP points at fixed orientation
//!   around the robot's home TCP (seed 004 §IV.B.3); not measured.

use super::designs::{Visit, circle, crosstalk, cubes, indexing, lhs, measured, uniform};
use super::{Effect, PoseContext, TrueRobot, gaussian, rng_for};
use crate::dataset::{Covariate, Dataset, DirSource, TextColumn};
use crate::kinematics::Robot;
use crate::space::derive_directions;
use crate::trajectory::Trajectory;
use crate::{Error, Result};
use nalgebra::Vector3;
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};

/// What to simulate (`simulate --kind`).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum CampaignKind {
    /// Latin-hypercube poses in the joint ranges, visited in order (the training campaign).
    Lhs,
    /// Independent random verification poses.
    Verify,
    /// Single-axis indexing tests, each grid point approached from both sides (seed 000 §2.3).
    Indexing,
    /// J1 indexed with J2 held at 0°, 20°, 40°, 60° (seed 000 §5.2, cross-talk).
    Crosstalk,
    /// A circle of commanded TCP points (a trajectory to compensate; not measured).
    Circle,
    /// ISO 9283 cubes: the poses clustered in a few cubes of the workspace, as a performance test measures them, each row labelled by its cube (`cube`: leave one cube out with `--groups cube`).
    Cubes,
}

impl CampaignKind {
    /// Default number of poses / trajectory points.
    pub fn default_poses(self) -> usize {
        match self {
            CampaignKind::Lhs => 300,
            CampaignKind::Verify => 30,
            CampaignKind::Indexing | CampaignKind::Crosstalk => 0,
            CampaignKind::Circle => 72,
            CampaignKind::Cubes => 600,
        }
    }
}

/// Campaign parameters; `CampaignSpec::new(kind, seed)` gives the defaults.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignSpec {
    /// Which design to simulate.
    pub kind: CampaignKind,
    /// Seed of the true robot *and* of the campaign's random draws. The same
    /// seed gives the same true robot for every kind.
    pub seed: u64,
    /// Poses (lhs, verify) or trajectory points (circle); ignored by indexing.
    pub poses: usize,
    /// Undeclared effects switched on for this campaign.
    pub effects: Vec<Effect>,
    /// Joint ranges overriding the robot's `work_ranges`.
    pub ranges: Option<Vec<(f64, f64)>>,
    /// Mean time per measured pose, s.
    pub seconds_per_pose: f64,
    /// Diameter of the `circle` trajectory, mm.
    pub circle_diameter_mm: f64,
    /// Forward-and-backward cycles of each indexing (and cross-talk) test.
    pub indexing_cycles: usize,
    /// Number of ISO 9283 cubes (`cubes`); the poses are shared equally.
    #[serde(default = "default_cubes")]
    pub cubes: usize,
    /// Edge of each cube, mm (`cubes`).
    #[serde(default = "default_cube_edge_mm")]
    pub cube_edge_mm: f64,
}

fn default_cubes() -> usize {
    4
}

fn default_cube_edge_mm() -> f64 {
    300.0
}

impl CampaignSpec {
    /// Defaults for `kind`.
    pub fn new(kind: CampaignKind, seed: u64) -> Self {
        CampaignSpec {
            kind,
            seed,
            poses: kind.default_poses(),
            effects: Vec::new(),
            ranges: None,
            seconds_per_pose: 12.0,
            circle_diameter_mm: 100.0,
            indexing_cycles: 3,
            cubes: default_cubes(),
            cube_edge_mm: default_cube_edge_mm(),
        }
    }

    /// The spec with the cube campaign's sizes given (`simulate`'s
    /// `--cubes`, `--edge`); each one not given keeps its value.
    pub fn cube_sizes(self, cubes: Option<usize>, edge_mm: Option<f64>) -> Self {
        CampaignSpec {
            cubes: cubes.unwrap_or(self.cubes),
            cube_edge_mm: edge_mm.unwrap_or(self.cube_edge_mm),
            ..self
        }
    }

    /// The spec with the sizes given (`simulate`'s `--poses`, `--diameter`,
    /// `--cycles`); each one not given keeps its value, the kind's default
    /// after [`new`](Self::new).
    pub fn sizes(
        self,
        poses: Option<usize>,
        circle_diameter_mm: Option<f64>,
        indexing_cycles: Option<usize>,
    ) -> Self {
        CampaignSpec {
            poses: poses.unwrap_or(self.poses),
            circle_diameter_mm: circle_diameter_mm.unwrap_or(self.circle_diameter_mm),
            indexing_cycles: indexing_cycles.unwrap_or(self.indexing_cycles),
            ..self
        }
    }

    /// Refuse a setting the kind does not use (it would be silently
    /// ignored): a field the kind ignores must keep the value [`new`](Self::new)
    /// gives it. `poses` is not used by an indexing or cross-talk campaign
    /// (their poses come from the joint grid and the cycles),
    /// `circle_diameter_mm` only by a circle, `indexing_cycles` only by
    /// indexing and cross-talk; a circle takes no `ranges` (it is drawn
    /// around the home TCP) and no effect of
    /// [`MEASUREMENT_EFFECTS`](super::MEASUREMENT_EFFECTS) (a circle is
    /// commanded, not measured). Messages name the `simulate` options.
    pub fn validate(&self) -> Result<()> {
        let defaults = CampaignSpec::new(self.kind, self.seed);
        let kind = format!("{:?}", self.kind).to_lowercase();
        let refuse = |what: &str| {
            Err(Error::InvalidParameter(format!(
                "{what} (here --kind {kind})"
            )))
        };
        let grid = matches!(self.kind, CampaignKind::Indexing | CampaignKind::Crosstalk);
        let circle = self.kind == CampaignKind::Circle;
        if grid && self.poses != defaults.poses {
            return refuse(
                "--poses is not used by an indexing or cross-talk campaign: its poses come from the joint grid and --cycles",
            );
        }
        if self.circle_diameter_mm != defaults.circle_diameter_mm && !circle {
            return refuse("--diameter is for --kind circle");
        }
        if self.indexing_cycles != defaults.indexing_cycles && !grid {
            return refuse("--cycles is for --kind indexing or crosstalk");
        }
        if self.kind == CampaignKind::Cubes {
            if self.cubes == 0 {
                return refuse("--cubes must be at least 1");
            }
            let per = self.poses / self.cubes;
            if per * self.cubes != self.poses || per < super::iso_cubes::ISO_POINTS {
                return refuse(&format!(
                    "--poses {} must be a multiple of --cubes {}, with at least the {} ISO points per cube",
                    self.poses,
                    self.cubes,
                    super::iso_cubes::ISO_POINTS
                ));
            }
            if !(self.cube_edge_mm.is_finite() && self.cube_edge_mm > 0.0) {
                return refuse(&format!(
                    "--edge {} must be a positive number of mm",
                    self.cube_edge_mm
                ));
            }
        } else if self.cubes != defaults.cubes || self.cube_edge_mm != defaults.cube_edge_mm {
            return refuse("--cubes and --edge are for --kind cubes");
        }
        if circle {
            if self.ranges.is_some() {
                return refuse(
                    "--ranges does not apply to a circle trajectory (it is drawn around the robot's home TCP)",
                );
            }
            for name in self.effects.iter().map(Effect::name) {
                if super::MEASUREMENT_EFFECTS.contains(&name) {
                    return refuse(&format!(
                        "--effect {name} acts on measurements, and a circle is a trajectory to compensate, not measured; evaluate runs it without that effect"
                    ));
                }
            }
        }
        Ok(())
    }
}

/// Joint ranges `LO:HI,LO:HI,…` (degrees; mm for a prismatic joint), one
/// pair per joint, for [`CampaignSpec::ranges`].
pub fn parse_ranges(s: &str) -> Result<Vec<(f64, f64)>> {
    s.split(',')
        .map(|part| {
            let (lo, hi) = part.split_once(':').ok_or_else(|| {
                Error::InvalidParameter(format!("--ranges: '{part}' is not LO:HI"))
            })?;
            let p = |x: &str| {
                x.trim().parse::<f64>().map_err(|_| {
                    Error::InvalidParameter(format!("--ranges: '{x}' is not a number"))
                })
            };
            Ok((p(lo)?, p(hi)?))
        })
        .collect()
}

/// The simulator's ground truth, written beside the data (never into it).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Truth {
    /// Format tag, [`TRUTH_FORMAT`].
    pub format: String,
    /// File format version, [`TRUTH_VERSION`].
    pub version: u32,
    /// The campaign that was simulated.
    pub spec: CampaignSpec,
    /// The true robot the campaign ran on.
    pub robot: TrueRobot,
    /// RMS over the measured rows of the per-axis noise σ (tracker +
    /// repeatability), mm: the best CV RMSE any model can reach.
    pub noise_floor_mm: Option<[f64; 3]>,
    /// Noise-free direction spread: mean over the poses of |δ(λ=+1) − δ(λ=−1)|
    /// per axis, mm (all joints approached from the same side).
    pub direction_spread_mm: Option<[f64; 3]>,
}

/// Format tag of a truth sidecar (its JSON `format` field).
pub const TRUTH_FORMAT: &str = "robokrige-sim-truth";
/// Version of the truth-sidecar format this crate writes.
pub const TRUTH_VERSION: u32 = 1;

/// A campaign's result.
#[derive(Debug, Clone, PartialEq)]
pub enum SimOutput {
    /// A measured campaign (every kind but `circle`).
    Measurements(Dataset),
    /// A commanded trajectory (`circle`).
    Trajectory(Trajectory),
}

/// Simulate `spec` on a true robot drawn around `nominal`.
pub fn simulate(nominal: &Robot, spec: &CampaignSpec) -> Result<(SimOutput, Truth)> {
    let profile = super::ErrorProfile::for_robot(nominal);
    let robot = TrueRobot::draw(nominal, &profile, spec.seed);
    simulate_on(&robot, spec)
}

/// The measurements of a measured campaign kind (all but `circle`) on `robot`.
pub fn measurements(robot: &TrueRobot, spec: &CampaignSpec) -> Result<Dataset> {
    match simulate_on(robot, spec)?.0 {
        SimOutput::Measurements(d) => Ok(d),
        SimOutput::Trajectory(_) => Err(Error::InvalidParameter(format!(
            "a {:?} campaign is a trajectory, not measurements",
            spec.kind
        ))),
    }
}

/// Simulate `spec` on a given true robot (e.g. one loaded from a truth file).
pub fn simulate_on(robot: &TrueRobot, spec: &CampaignSpec) -> Result<(SimOutput, Truth)> {
    let nominal = &robot.nominal;
    for e in &spec.effects {
        e.validate()?;
        e.check_joints(nominal.dof())?;
    }
    let ranges = spec
        .ranges
        .clone()
        .unwrap_or_else(|| nominal.work_ranges.clone());
    check_ranges(nominal, &ranges)?;
    let mut rng = rng_for(spec.seed, kind_stream(spec.kind));
    let mut truth = Truth {
        format: TRUTH_FORMAT.into(),
        version: TRUTH_VERSION,
        spec: spec.clone(),
        robot: robot.clone(),
        noise_floor_mm: None,
        direction_spread_mm: None,
    };
    let visits = match spec.kind {
        CampaignKind::Lhs => measured(lhs(&ranges, spec.poses, &mut rng)),
        CampaignKind::Verify => measured(uniform(&ranges, spec.poses, &mut rng)),
        CampaignKind::Indexing => indexing(nominal, &ranges, spec.indexing_cycles),
        CampaignKind::Crosstalk => crosstalk(nominal, &ranges, spec.indexing_cycles)?,
        CampaignKind::Circle => {
            let traj = circle(nominal, spec.circle_diameter_mm, spec.poses)?;
            return Ok((SimOutput::Trajectory(traj), truth));
        }
        CampaignKind::Cubes => cubes(nominal, spec, &ranges)?,
    };
    if visits.iter().all(|v| !v.measured) {
        return Err(Error::InvalidParameter(
            match spec.kind {
                CampaignKind::Indexing | CampaignKind::Crosstalk => {
                    "campaign has no poses (indexing needs --cycles > 0)"
                }
                _ => "campaign has no poses (use --poses > 0)",
            }
            .into(),
        ));
    }
    let data = measure(robot, spec, &visits, &mut rng)?;
    truth.noise_floor_mm = Some(noise_floor(robot, &data.q));
    truth.direction_spread_mm = Some(direction_spread(robot, &data.q));
    Ok((SimOutput::Measurements(data), truth))
}

fn kind_stream(kind: CampaignKind) -> &'static str {
    match kind {
        CampaignKind::Lhs => "campaign-lhs",
        CampaignKind::Verify => "campaign-verify",
        CampaignKind::Indexing => "campaign-indexing",
        CampaignKind::Crosstalk => "campaign-crosstalk",
        CampaignKind::Circle => "campaign-circle",
        CampaignKind::Cubes => "campaign-cubes",
    }
}

fn check_ranges(robot: &Robot, ranges: &[(f64, f64)]) -> Result<()> {
    if ranges.len() != robot.dof() {
        return Err(Error::JointCount {
            expected: robot.dof(),
            got: ranges.len(),
        });
    }
    for (i, ((lo, hi), (llo, lhi))) in ranges.iter().zip(&robot.limits).enumerate() {
        if lo.partial_cmp(hi) == Some(std::cmp::Ordering::Greater)
            || lo.is_nan()
            || hi.is_nan()
            || *lo < *llo
            || *hi > *lhi
        {
            return Err(Error::InvalidParameter(format!(
                "range of joint {} ({lo}, {hi}) must be ordered and inside the limits ({llo}, {lhi})",
                i + 1
            )));
        }
    }
    Ok(())
}

fn measure(
    robot: &TrueRobot,
    spec: &CampaignSpec,
    visits: &[Visit],
    rng: &mut impl Rng,
) -> Result<Dataset> {
    let all_q: Vec<Vec<f64>> = visits.iter().map(|v| v.q.clone()).collect();
    let all_dir = derive_directions(&all_q, Some(&robot.nominal.home));
    let travel = super::effects::travel_since_reversal(&all_q, &all_dir, Some(&robot.nominal.home));
    let lag = super::effects::lag_deviations(&spec.effects, &all_q, &robot.nominal.home);
    let rows: Vec<usize> = (0..visits.len()).filter(|&i| visits[i].measured).collect();
    let m = rows.len();
    let env = Environment::draw(spec, m, rng);
    let mut q = Vec::with_capacity(m);
    let mut dir = Vec::with_capacity(m);
    let mut errors = Vec::with_capacity(m);
    let mut positions = Vec::with_capacity(m);
    for (k, &i) in rows.iter().enumerate() {
        let (qk, dk) = (&all_q[i], &all_dir[i]);
        let ctx = env.context(k);
        let mut qa = robot.actual_joints(qk, dk, &ctx);
        let mut extra = lag[i].clone();
        for e in &spec.effects {
            e.joint_deviation(qk, &mut extra);
            e.history_deviation(dk, &travel[i], &mut extra);
        }
        for (a, x) in qa.iter_mut().zip(&extra) {
            *a += x + gaussian(rng, robot.noise.repeatability_sigma_deg);
        }
        let mut p = robot.tcp(&qa, &ctx);
        let sigma = robot.noise.tracker_sigma(&p);
        p += Vector3::from_fn(|_, _| gaussian(rng, sigma)) + env.tracker_offset(k);
        let nominal = robot.nominal.fk_unchecked(qk).translation.vector;
        errors.push((p - nominal).into());
        positions.push(p.into());
        q.push(qk.clone());
        dir.push(dk.clone());
    }
    let mut covariates = vec![
        covariate("time_s", env.time_s.clone()),
        covariate("temp_c", env.temp_sensor_c.clone()),
    ];
    if env.payload_column {
        covariates.push(covariate("payload_kg", env.payload_kg.clone()));
    }
    if matches!(spec.kind, CampaignKind::Indexing | CampaignKind::Crosstalk) {
        let tags: Vec<(usize, usize)> = rows
            .iter()
            .map(|&i| visits[i].tag.unwrap_or((0, 0)))
            .collect();
        covariates.push(covariate("axis", tags.iter().map(|t| t.0 as f64).collect()));
        covariates.push(covariate(
            "cycle",
            tags.iter().map(|t| t.1 as f64).collect(),
        ));
    }
    // a cube is a label, not a quantity: a text column ("c1", …)
    let text = if spec.kind == CampaignKind::Cubes {
        vec![TextColumn {
            name: "cube".into(),
            values: rows
                .iter()
                .map(|&i| format!("c{}", visits[i].tag.map_or(0, |t| t.0) + 1))
                .collect(),
            note: None,
        }]
    } else {
        Vec::new()
    };
    Ok(Dataset {
        source: "<simulated>".into(),
        q,
        dir,
        dir_source: DirSource::Given,
        errors: Some(errors),
        positions: Some(positions),
        ids: Some((0..m).map(|k| k.to_string()).collect()),
        covariates,
        text,
        lines: Default::default(),
    })
}

fn covariate(name: &str, values: Vec<f64>) -> Covariate {
    Covariate {
        name: name.into(),
        values,
        missing: 0,
    }
}

/// Time, temperature, payload and tracker set-up along a campaign.
struct Environment {
    time_s: Vec<f64>,
    temp_true_c: Vec<f64>,
    temp_sensor_c: Vec<f64>,
    temp_ref_c: f64,
    expansion_per_k: f64,
    payload_kg: Vec<f64>,
    payload_column: bool,
    step: Option<(std::ops::Range<usize>, [f64; 3])>,
}

impl Environment {
    fn draw(spec: &CampaignSpec, m: usize, rng: &mut impl Rng) -> Self {
        let mut time_s = Vec::with_capacity(m);
        let mut t = 0.0;
        for _ in 0..m {
            time_s.push((t * 10.0_f64).round() / 10.0);
            t += spec.seconds_per_pose * rng.random_range(0.8..1.2);
        }
        let temp_ref_c = 20.0 + rng.random_range(-1.0..2.0);
        let mut env = Environment {
            temp_true_c: Vec::with_capacity(m),
            temp_sensor_c: Vec::with_capacity(m),
            temp_ref_c,
            expansion_per_k: 0.0,
            payload_kg: vec![0.0; m],
            payload_column: false,
            step: None,
            time_s,
        };
        // ambient wander without influence unless the temperature effect is on
        let mut wander = 0.0_f64;
        let drift = spec.effects.iter().find_map(|e| match e {
            Effect::Temperature {
                delta_k,
                tau_s,
                expansion_per_k,
            } => Some((*delta_k, *tau_s, *expansion_per_k)),
            _ => None,
        });
        for k in 0..m {
            wander = (wander + gaussian(rng, 0.01)).clamp(-0.3, 0.3);
            let rise = drift.map_or(0.0, |(dk, tau, _)| {
                dk * (1.0 - (-env.time_s[k] / tau).exp())
            });
            let temp = temp_ref_c + wander + rise;
            env.temp_true_c.push(temp);
            let sensed = temp + gaussian(rng, 0.02);
            env.temp_sensor_c.push((sensed * 100.0).round() / 100.0);
        }
        env.expansion_per_k = drift.map_or(0.0, |d| d.2);
        for e in &spec.effects {
            match e {
                Effect::Payload { levels_kg } => {
                    env.payload_column = true;
                    let blocks = levels_kg.len();
                    for (k, p) in env.payload_kg.iter_mut().enumerate() {
                        *p = levels_kg[(k * blocks / m.max(1)).min(blocks - 1)];
                    }
                }
                Effect::TrackerStep {
                    row,
                    until,
                    offset_mm,
                } => env.step = Some((*row..until.unwrap_or(usize::MAX), *offset_mm)),
                _ => {}
            }
        }
        env
    }

    fn context(&self, k: usize) -> PoseContext {
        PoseContext {
            payload_kg: self.payload_kg[k],
            length_scale: 1.0 + self.expansion_per_k * (self.temp_true_c[k] - self.temp_ref_c),
        }
    }

    fn tracker_offset(&self, k: usize) -> Vector3<f64> {
        match self.step {
            Some((ref rows, off)) if rows.contains(&k) => Vector3::from(off),
            _ => Vector3::zeros(),
        }
    }
}

/// RMS over poses of the per-axis measurement noise σ (tracker + repeatability).
pub fn noise_floor(robot: &TrueRobot, q: &[Vec<f64>]) -> [f64; 3] {
    let mut acc = [0.0; 3];
    for qk in q {
        let s = robot.noise_sigma(qk);
        for a in 0..3 {
            acc[a] += s[a] * s[a];
        }
    }
    acc.map(|v| (v / q.len().max(1) as f64).sqrt())
}

/// Mean over poses of |δ(λ=+1) − δ(λ=−1)| per axis, noise-free, no effects.
pub fn direction_spread(robot: &TrueRobot, q: &[Vec<f64>]) -> [f64; 3] {
    let ctx = PoseContext::default();
    let mut acc = [0.0; 3];
    for qk in q {
        let plus = vec![1.0; qk.len()];
        let minus = vec![-1.0; qk.len()];
        let d = robot.error(qk, &plus, &ctx) - robot.error(qk, &minus, &ctx);
        for a in 0..3 {
            acc[a] += d[a].abs();
        }
    }
    acc.map(|v| v / q.len().max(1) as f64)
}
