//! The simulator's "true robot": what the real machine does when commanded `q*`.
//!
//! Actual joint value (seed 000 eq 4, seed 003 eq 5, plus compliance and noise):
//!
//! `q = q* + Δq_apd(q*, λ) + Δq_grav(q*, payload) + ε_rep`,
//!
//! then the TCP is the forward kinematics of the *true* MD-H chain (every
//! parameter perturbed, seed 003 eq 2), and the tracker reads it with noise.

use super::{gaussian, rng_for};
use crate::kinematics::{JointKind, MdhLink, Robot};
use nalgebra::{Isometry3, Translation3, Vector3};
use rand::{Rng, RngExt};
use serde::{Deserialize, Serialize};
use std::f64::consts::TAU;

/// One sinusoid `A·sin(2π·θ*/P + φ)` of a joint's angular positioning deviation.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Harmonic {
    /// Amplitude A, degrees (mm for a prismatic joint).
    pub amplitude_deg: f64,
    /// Period P in the commanded angle θ*, degrees.
    pub period_deg: f64,
    /// Phase φ, radians.
    pub phase_rad: f64,
}

impl Harmonic {
    /// Value at commanded angle `q` (degrees).
    pub fn at(&self, q: f64) -> f64 {
        self.amplitude_deg * (TAU * q / self.period_deg + self.phase_rad).sin()
    }
}

/// Bidirectional angular positioning deviation of one joint (seed 000 eqs 3–6;
/// seed 003 eq 5):
///
/// `Δθ(θ*, λ) = Σ_h A_h sin(2πθ*/P_h + φ_h) + λ·b(θ*)`, with the angle-dependent
/// backlash half-width `b(θ*) = b0 + b1·sin(2πθ*/P_b + φ_b)`, `b0 > |b1|`.
/// Units: degrees (mm for a prismatic joint).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointDeviation {
    /// Gear-pitch harmonics of the commanded angle (direction independent).
    pub harmonics: Vec<Harmonic>,
    /// Mean backlash half-width `b0`.
    pub backlash_deg: f64,
    /// Angle-dependent part `b1 sin(2πθ*/P_b + φ_b)` of the half-width.
    pub backlash_variation: Harmonic,
}

impl JointDeviation {
    /// No deviation at all.
    pub fn none() -> Self {
        JointDeviation {
            harmonics: Vec::new(),
            backlash_deg: 0.0,
            backlash_variation: Harmonic {
                amplitude_deg: 0.0,
                period_deg: 360.0,
                phase_rad: 0.0,
            },
        }
    }

    /// `Δθ(θ*, λ)`.
    pub fn at(&self, q: f64, dir: f64) -> f64 {
        let periodic: f64 = self.harmonics.iter().map(|h| h.at(q)).sum();
        periodic + dir * (self.backlash_deg + self.backlash_variation.at(q))
    }
}

/// Gravity compliance: lumped masses at frame origins and torsional joint
/// stiffness. Deflection of joint i: `Δθ_i = τ_i / K_i` with
/// `τ_i = Σ_{k ≥ i} (z_{i−1} × (c_k − o_{i−1})) · m_k g`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Compliance {
    /// Mass at the origin of frame k (k = 1..n), kg.
    pub link_masses_kg: Vec<f64>,
    /// Joint stiffness, N·m/rad; 0 means rigid.
    pub stiffness_nm_per_rad: Vec<f64>,
}

/// Noise of one measured pose.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct NoiseModel {
    /// Unidirectional repeatability: per-joint Gaussian σ (deg or mm).
    pub repeatability_sigma_deg: f64,
    /// Tracker maximum permissible error `U = a + b·L` (seed 000 Table 2:
    /// 15 µm + 6 µm/m), taken as 2σ per axis; this field is the constant
    /// part `a`, mm.
    pub tracker_mpe_const_mm: f64,
    /// Distance-proportional part `b` of the tracker MPE, mm per metre of
    /// tracker-to-point distance L (seed 000: 0.006).
    pub tracker_mpe_per_m_mm: f64,
    /// Tracker position in the robot base frame, mm.
    pub tracker_position_mm: [f64; 3],
}

impl NoiseModel {
    /// Per-axis tracker σ (mm) at a point.
    pub fn tracker_sigma(&self, p: &Vector3<f64>) -> f64 {
        let l_m = (p - Vector3::from(self.tracker_position_mm)).norm() / 1000.0;
        (self.tracker_mpe_const_mm + self.tracker_mpe_per_m_mm * l_m) / 2.0
    }
}

/// Magnitudes used to draw a true robot (1σ unless stated).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorProfile {
    /// σ of the perturbation of every MD-H length (d, a), mm.
    pub length_sigma_mm: f64,
    /// σ of the perturbation of every MD-H angle (θ offset, α, β), degrees.
    pub angle_sigma_deg: f64,
    /// σ of the tool offset perturbation per axis, mm.
    pub tool_sigma_mm: f64,
    /// Mean backlash half-width is drawn uniformly in `[0.5, 1.5]×` this.
    pub backlash_deg: f64,
    /// Amplitude scale of the gear-pitch harmonics.
    pub harmonic_deg: f64,
    /// Mass scale: total arm mass, kg (0 disables compliance).
    pub arm_mass_kg: f64,
    /// Stiffness of the shoulder and elbow, N·m/rad.
    pub stiffness_nm_per_rad: f64,
    /// Unidirectional repeatability σ per joint, degrees (mm for a prismatic joint).
    pub repeatability_sigma_deg: f64,
}

impl ErrorProfile {
    /// Defaults scaled to the robot: a large industrial arm gets the
    /// sub-millimetre errors of seeds 003/004, the SCARA the tens of
    /// micrometres of seed 000.
    pub fn for_robot(robot: &Robot) -> Self {
        let reach: f64 = robot
            .links
            .iter()
            .map(|l| l.a_mm.abs() + l.d_mm.abs())
            .sum();
        if reach < 1000.0 {
            ErrorProfile {
                length_sigma_mm: 0.03,
                angle_sigma_deg: 0.005,
                tool_sigma_mm: 0.01,
                backlash_deg: 0.003,
                harmonic_deg: 0.002,
                arm_mass_kg: 0.0,
                stiffness_nm_per_rad: 0.0,
                repeatability_sigma_deg: 0.0004,
            }
        } else {
            let s = (reach / 4000.0).powi(3);
            ErrorProfile {
                length_sigma_mm: 0.2,
                angle_sigma_deg: 0.008,
                tool_sigma_mm: 0.08,
                backlash_deg: 0.004,
                harmonic_deg: 0.002,
                arm_mass_kg: 600.0 * s,
                stiffness_nm_per_rad: 4.0e7 * s,
                repeatability_sigma_deg: 0.0004,
            }
        }
    }
}

/// A simulated robot: the nominal model it is sold as and what it really is.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TrueRobot {
    /// The model the controller believes (nominal parameters).
    pub nominal: Robot,
    /// The real geometry: every MD-H parameter and the tool perturbed.
    pub actual: Robot,
    /// Per-joint bidirectional angular positioning deviation.
    pub deviation: Vec<JointDeviation>,
    /// Gravity compliance of the arm (masses and joint stiffnesses).
    pub compliance: Compliance,
    /// Noise of the joints and of the tracker.
    pub noise: NoiseModel,
}

/// Everything that acts on one commanded pose besides geometry.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PoseContext {
    /// Payload at the TCP, kg.
    pub payload_kg: f64,
    /// Link lengths scale `1 + κ·ΔT` (thermal expansion), 1 = none.
    pub length_scale: f64,
}

impl Default for PoseContext {
    fn default() -> Self {
        PoseContext {
            payload_kg: 0.0,
            length_scale: 1.0,
        }
    }
}

impl TrueRobot {
    /// Draw a true robot around `nominal`, reproducibly from `seed`.
    pub fn draw(nominal: &Robot, profile: &ErrorProfile, seed: u64) -> Self {
        let mut rng = rng_for(seed, "true-robot");
        let mut actual = nominal.clone();
        for link in &mut actual.links {
            perturb_link(link, profile, &mut rng);
        }
        let dt = Vector3::from_fn(|_, _| gaussian(&mut rng, profile.tool_sigma_mm));
        actual.tool =
            Isometry3::from_parts(Translation3::from(dt), nominal.tool.rotation) * nominal.tool;
        let deviation = nominal
            .links
            .iter()
            .map(|_| draw_deviation(profile, &mut rng))
            .collect();
        let n = nominal.dof();
        let mut link_masses_kg = vec![0.0; n];
        // upper arm + elbow, forearm, wrist, flange: shares of the arm mass
        for (k, share) in [(1usize, 0.35), (2, 0.25), (3, 0.3), (5, 0.1)] {
            if k < n {
                link_masses_kg[k] = share * profile.arm_mass_kg;
            }
        }
        let mut stiffness = vec![0.0; n];
        for j in [1usize, 2] {
            if j < n {
                let spread = rng.random_range(0.8..1.25);
                stiffness[j] = profile.stiffness_nm_per_rad * spread;
            }
        }
        let reach: f64 = nominal
            .links
            .iter()
            .map(|l| l.a_mm.abs() + l.d_mm.abs())
            .sum();
        TrueRobot {
            nominal: nominal.clone(),
            actual,
            deviation,
            compliance: Compliance {
                link_masses_kg,
                stiffness_nm_per_rad: stiffness,
            },
            noise: NoiseModel {
                repeatability_sigma_deg: profile.repeatability_sigma_deg,
                tracker_mpe_const_mm: 0.015,
                tracker_mpe_per_m_mm: 0.006,
                tracker_position_mm: [1.2 * reach, -0.6 * reach, 0.0],
            },
        }
    }

    /// Number of joints.
    pub fn dof(&self) -> usize {
        self.nominal.dof()
    }

    /// The same robot measured without noise: no joint repeatability, a
    /// perfect tracker (to see the systematic errors alone).
    pub fn noise_free(mut self) -> Self {
        self.noise.repeatability_sigma_deg = 0.0;
        self.noise.tracker_mpe_const_mm = 0.0;
        self.noise.tracker_mpe_per_m_mm = 0.0;
        self
    }

    /// Gravity deflection of every joint in API units (deg / mm) at commanded `q`.
    pub fn gravity_deflection(&self, q: &[f64], payload_kg: f64) -> Vec<f64> {
        let n = self.dof();
        let c = &self.compliance;
        if c.stiffness_nm_per_rad.iter().all(|k| *k <= 0.0) {
            return vec![0.0; n];
        }
        let frames = self.nominal.frames(q);
        let g = Vector3::new(0.0, 0.0, -9.81);
        // (position m, mass kg): frame origins 1..n and the payload at the TCP
        let mut masses: Vec<(Vector3<f64>, f64)> = (0..n)
            .map(|k| {
                (
                    frames[k + 1].translation.vector / 1000.0,
                    c.link_masses_kg[k],
                )
            })
            .collect();
        masses.push((frames[n + 1].translation.vector / 1000.0, payload_kg));
        (0..n)
            .map(|i| {
                let k_i = c.stiffness_nm_per_rad[i];
                let link = &self.nominal.links[i];
                if k_i <= 0.0 || link.kind != JointKind::Revolute {
                    return 0.0;
                }
                let z = frames[i].rotation * Vector3::z();
                let o = frames[i].translation.vector / 1000.0;
                let tau: f64 = masses[i..]
                    .iter()
                    .map(|(p, m)| z.cross(&(p - o)).dot(&(g * *m)))
                    .sum();
                (tau / k_i).to_degrees() / link.sign
            })
            .collect()
    }

    /// Actual joint values for commanded `q` approached in directions `dir`,
    /// without random noise.
    pub fn actual_joints(&self, q: &[f64], dir: &[f64], ctx: &PoseContext) -> Vec<f64> {
        let grav = self.gravity_deflection(q, ctx.payload_kg);
        q.iter()
            .zip(dir)
            .zip(&self.deviation)
            .zip(&grav)
            .map(|(((qi, di), dev), gi)| qi + dev.at(*qi, *di) + gi)
            .collect()
    }

    /// Noise-free TCP position of the true robot for actual joint values.
    pub fn tcp(&self, q_actual: &[f64], ctx: &PoseContext) -> Vector3<f64> {
        if ctx.length_scale == 1.0 {
            return self.actual.fk_unchecked(q_actual).translation.vector;
        }
        let mut scaled = self.actual.clone();
        for l in &mut scaled.links {
            l.a_mm *= ctx.length_scale;
            l.d_mm *= ctx.length_scale;
        }
        scaled.tool.translation.vector *= ctx.length_scale;
        scaled.fk_unchecked(q_actual).translation.vector
    }

    /// Noise-free TCP error `true − nominal` (mm) at commanded `q`, directions `dir`.
    pub fn error(&self, q: &[f64], dir: &[f64], ctx: &PoseContext) -> Vector3<f64> {
        let qa = self.actual_joints(q, dir, ctx);
        self.tcp(&qa, ctx) - self.nominal.fk_unchecked(q).translation.vector
    }

    /// Per-axis standard deviation (mm) of the noise of one measurement at `q`:
    /// tracker σ and joint repeatability propagated through the position
    /// Jacobian (linearised).
    pub fn noise_sigma(&self, q: &[f64]) -> [f64; 3] {
        let p = self.nominal.fk_unchecked(q).translation.vector;
        let st = self.noise.tracker_sigma(&p);
        let j = self
            .nominal
            .position_jacobian(q)
            .expect("joint count checked by caller");
        let mut out = [0.0; 3];
        for (a, o) in out.iter_mut().enumerate() {
            let rep: f64 = (0..self.dof())
                .map(|i| {
                    (j[(a, i)] * self.nominal.unit_scale(i) * self.noise.repeatability_sigma_deg)
                        .powi(2)
                })
                .sum();
            *o = (st * st + rep).sqrt();
        }
        out
    }
}

fn perturb_link(link: &mut MdhLink, p: &ErrorProfile, rng: &mut impl Rng) {
    link.theta_offset_deg += gaussian(rng, p.angle_sigma_deg);
    link.d_mm += gaussian(rng, p.length_sigma_mm);
    link.a_mm += gaussian(rng, p.length_sigma_mm);
    link.alpha_deg += gaussian(rng, p.angle_sigma_deg);
    link.beta_deg += gaussian(rng, p.angle_sigma_deg);
}

fn draw_harmonic(rng: &mut impl Rng, amp: f64, period: f64) -> Harmonic {
    Harmonic {
        amplitude_deg: amp * rng.random_range(0.5..1.5),
        period_deg: period,
        phase_rad: rng.random_range(0.0..TAU),
    }
}

fn draw_deviation(p: &ErrorProfile, rng: &mut impl Rng) -> JointDeviation {
    // once- and twice-per-turn (eccentricity) and a gear-pitch term
    let h1 = draw_harmonic(rng, p.harmonic_deg, 360.0);
    let h2 = draw_harmonic(rng, 0.5 * p.harmonic_deg, 180.0);
    let pitch = rng.random_range(40.0..90.0);
    let h3 = draw_harmonic(rng, 0.4 * p.harmonic_deg, pitch);
    let b0 = p.backlash_deg * rng.random_range(0.5..1.5);
    let var = draw_harmonic(rng, 0.3 * b0, 360.0);
    JointDeviation {
        harmonics: vec![h1, h2, h3],
        backlash_deg: b0,
        backlash_variation: var,
    }
}
