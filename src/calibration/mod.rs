//! Kinematic calibration: the MD-H, tool and base errors a campaign can
//! identify, by Levenberg–Marquardt on the directions it sees.
//!
//! The measured TCP of pose `k` is `P_k = P_nom(q_k) + e_k`. The model is the
//! nominal robot with parameter errors `p` (per link `Δθ_off, Δd, Δa, Δα,
//! Δβ`, the tool offset, the base pose; [`crate::kinematics::apply_errors`]),
//! fitted by
//!
//! ```text
//! min_u ‖ P − FK(p = T u; q) ‖²,       T = D V_k,
//! ```
//!
//! where `D V_k` spans the `k` directions of the scaled identification
//! Jacobian at nominal that the campaign sees above its residual noise
//! ([`identifiability`]): every other direction stays at its nominal value.
//! The noise `s` is the residual standard deviation of a first fit on every
//! numerically identifiable direction (or the caller's
//! [`CalibrationOptions::noise_mm`]); when it hides some directions, the
//! fit is repeated on the directions it leaves.
//!
//! With [`CalibrationOptions::backlash`] the geometry is fitted beside the
//! backlash of the joints the campaign approaches from both sides
//! ([`backlash`]): the joints as reached, `q + b∘λ`. By default
//! ([`CalibrationOptions::joint_harmonics`]) the calibration then looks
//! for the periodic transmission errors of the joints' gears on what the
//! geometric fit leaves ([`harmonics`]), adds those the noise
//! cannot explain, and refits the geometric directions beside them when
//! that lowers the residual significantly.
//!
//! A [`Calibration`] predicts the kinematic part of the error,
//! `δ̂_cal(q, λ) = P_cal(q' + δq(q')) − P_nom(q)` with `q' = q + b∘λ` (`b`
//! the half backlashes, `δq` the joint harmonics, zero without them), and
//! gives the residual `e − δ̂_cal` that a Kriging model
//! learns next (the calibrated error model).
//!
//! One concept a file: `geometric.rs` (the geometric fit and the stages
//! after it), [`identifiability`] (the scaled Jacobian's directions and
//! the report), [`backlash`], [`harmonics`], `predict.rs` (the prediction,
//! its variance and the displacements of the directions seen); this file
//! holds the options, the entry points and the [`Calibration`] as a file
//! stores it.

pub mod backlash;
mod geometric;
pub mod harmonics;
pub mod identifiability;
mod predict;

pub use backlash::JointBacklash;
pub use geometric::MIN_NOISE_DOF;
pub use harmonics::JointHarmonic;
pub use identifiability::{Identifiability, ParameterReport};

use crate::dataset::Dataset;
use crate::kinematics::{Robot, apply_errors};
use crate::{Error, Result};
use geometric::Geometric;
use nalgebra::Vector3;
use serde::{Deserialize, Serialize};

/// Options of [`calibrate`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CalibrationOptions {
    /// Residual standard deviation per coordinate (mm) that decides which
    /// directions the campaign sees; `None`: estimated from a first fit.
    #[serde(default)]
    pub noise_mm: Option<f64>,
    /// Levenberg–Marquardt trial steps per fit.
    #[serde(default = "default_max_iter")]
    pub max_iter: usize,
    /// Search for periodic joint errors after the geometric fit
    /// ([`harmonics`]); the default. Files written before it existed read
    /// as `false`: their calibrations were geometric.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub joint_harmonics: bool,
    /// Fit the geometry beside the backlash of the joints the campaign
    /// approaches from both sides ([`backlash`]). Off by default: on UR10
    /// series B (harmonic drives) the search keeps four joints whose
    /// "backlash" stands for other direction-linked structure, and the
    /// calibrated Kriging models' 10-fold CV error rose by 3–9 % with it;
    /// on simulated robots with backlash it carries over to poses far from
    /// the campaign (see the module documentation of [`backlash`]).
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub backlash: bool,
}

fn default_max_iter() -> usize {
    100
}

impl Default for CalibrationOptions {
    fn default() -> Self {
        CalibrationOptions {
            noise_mm: None,
            max_iter: default_max_iter(),
            joint_harmonics: true,
            backlash: false,
        }
    }
}

impl CalibrationOptions {
    /// The default options with the joints' periodic errors identified or
    /// not (`joint_harmonics`) and the residual noise per coordinate
    /// (`noise_mm`, mm; `None`: estimated from a first fit): what a front
    /// end's calibration flags set.
    pub fn new(joint_harmonics: bool, noise_mm: Option<f64>) -> Self {
        CalibrationOptions {
            noise_mm,
            joint_harmonics,
            ..CalibrationOptions::default()
        }
    }

    /// These options with the joints' backlash identified or not.
    pub fn with_backlash(mut self, on: bool) -> Self {
        self.backlash = on;
        self
    }

    /// The MD-H, tool and base errors alone, without the joints' backlash
    /// and harmonics: the D-H calibration of the literature.
    pub fn geometric() -> Self {
        CalibrationOptions {
            joint_harmonics: false,
            backlash: false,
            ..CalibrationOptions::default()
        }
    }

    /// Error unless the noise is finite and positive and the iterations
    /// at least one.
    pub fn validate(&self) -> Result<()> {
        if let Some(s) = self.noise_mm
            && !(s.is_finite() && s > 0.0)
        {
            return Err(Error::InvalidParameter(format!(
                "the calibration's noise must be a positive number of mm, not {s}"
            )));
        }
        if self.max_iter == 0 {
            return Err(Error::InvalidParameter(
                "the calibration needs at least one Levenberg–Marquardt step".into(),
            ));
        }
        Ok(())
    }
}

/// An identified kinematic calibration of one robot on one campaign.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Calibration {
    nominal: Robot,
    identified: Robot,
    parameters: Vec<f64>,
    identifiability: Identifiability,
    /// The parameter directions `D v_i` (one per singular value, P values
    /// each) and the posterior variance of each one's coordinate: what
    /// [`Calibration::predict_variance`] needs.
    #[serde(default)]
    uncertainty: Vec<(Vec<f64>, f64)>,
    /// Largest [`Calibration::predict_variance`] over the campaign's poses,
    /// mm² per axis: the calibration's uncertainty where it was measured.
    #[serde(default)]
    campaign_variance: [f64; 3],
    /// The joint harmonics added after the geometric fit.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    harmonics: Vec<JointHarmonic>,
    /// Covariance of their coefficients (degrees², row-major, 2h × 2h).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    harmonic_covariance: Vec<f64>,
    /// The joints' half backlashes the geometry was fitted beside.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    backlash: Vec<JointBacklash>,
    /// Covariance of the half backlashes (degrees², row-major, n × n).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    backlash_covariance: Vec<f64>,
    options: CalibrationOptions,
    rows: usize,
    rms_before_mm: f64,
    rms_after_mm: f64,
    iterations: usize,
    stop: String,
}

/// Columns over a campaign's rows per output axis: `d[a][i][k]`, axis a,
/// column i, row k ([`Calibration::seen_displacements`]).
pub type Displacements = [Vec<Vec<f64>>; 3];

/// Identify the kinematic errors of `nominal` on the measured campaign
/// `data` (joints as commanded): see the module documentation.
pub fn calibrate(
    data: &Dataset,
    nominal: &Robot,
    opts: &CalibrationOptions,
) -> Result<Calibration> {
    let targets = measured_targets(data, nominal, opts)?;
    Geometric::fit(&data.q, &targets, nominal, opts)?.full(data)
}

/// The measured TCP positions of `data` (nominal position plus error),
/// after the checks of [`calibrate`].
fn measured_targets(
    data: &Dataset,
    nominal: &Robot,
    opts: &CalibrationOptions,
) -> Result<Vec<Vector3<f64>>> {
    opts.validate()?;
    nominal.check_dataset(data)?;
    let errors = data.errors_or_err()?;
    if data.len() < 3 {
        return Err(Error::Input {
            source_name: data.source.clone(),
            message: format!(
                "a calibration needs at least 3 measured poses, not {}",
                data.len()
            ),
        });
    }
    Ok(data
        .q
        .iter()
        .zip(errors)
        .map(|(q, e)| nominal.fk_unchecked(q).translation.vector + Vector3::from(*e))
        .collect())
}

/// [`calibrate`] on joint values `joints` (e.g. corrected by lookup tables)
/// and measured TCP positions `targets`, both in campaign order.
pub fn calibrate_joints(
    joints: &[Vec<f64>],
    targets: &[Vector3<f64>],
    nominal: &Robot,
    opts: &CalibrationOptions,
) -> Result<Calibration> {
    Geometric::fit(joints, targets, nominal, opts)?.finish()
}

/// The geometric calibration and, from the same geometric fit, the one
/// `opts` asks for (with the backlash and the joint harmonics when
/// [`CalibrationOptions::backlash`] and
/// [`CalibrationOptions::joint_harmonics`]): what a comparison of the two
/// needs without fitting the geometry twice (but where a backlash is found:
/// the geometry is refitted beside it).
pub fn calibrate_both(
    data: &Dataset,
    nominal: &Robot,
    opts: &CalibrationOptions,
) -> Result<(Calibration, Calibration)> {
    let targets = measured_targets(data, nominal, opts)?;
    let geometric_opts = CalibrationOptions {
        joint_harmonics: false,
        backlash: false,
        ..opts.clone()
    };
    let stage = Geometric::fit(&data.q, &targets, nominal, &geometric_opts)?;
    let geometric = stage.calibration(&stage.fit, None)?;
    if !opts.joint_harmonics && !opts.backlash {
        return Ok((geometric.clone(), geometric));
    }
    // the stage fitted with the geometric options: the full one records
    // the options asked for
    let full = Geometric { opts, ..stage }.full(data)?;
    Ok((geometric, full))
}

impl Calibration {
    /// The robot as the controller knows it.
    pub fn nominal(&self) -> &Robot {
        &self.nominal
    }

    /// The robot with its identified errors applied: what
    /// `robot calibrated` writes as a robot file.
    pub fn identified(&self) -> &Robot {
        &self.identified
    }

    /// The identified robot as a robot of its own: named
    /// `<nominal>-calibrated`, its convention noting the poses and the
    /// directions seen (for `robot calibrated`). A robot file holds the
    /// MD-H table, tool and base: the joints' backlash and harmonics are
    /// not in it.
    pub fn calibrated_robot(&self) -> Robot {
        let mut robot = self.identified().clone();
        robot.name = format!("{}-calibrated", self.nominal().name);
        robot.convention = format!(
            "{}; MD-H, tool and base errors identified on {} poses ({} of {} directions seen{})",
            self.nominal().convention,
            self.rows(),
            self.identifiability().directions_seen,
            self.identifiability().parameters_total,
            match (self.backlash.len(), self.harmonics.len()) {
                (0, 0) => String::new(),
                (b, 0) => format!("; its backlash of {b} joint(s) is in the model file only"),
                (0, h) => format!("; its {h} joint harmonics are in the model file only"),
                (b, h) => format!(
                    "; its backlash of {b} joint(s) and {h} joint harmonics are in the model file only"
                ),
            }
        );
        robot
    }

    /// The joint harmonics added after the geometric fit (none for a
    /// geometric calibration).
    pub fn harmonics(&self) -> &[JointHarmonic] {
        &self.harmonics
    }

    /// The joints' half backlashes the geometry was fitted beside (none for
    /// a geometric calibration, or where the campaign showed none).
    pub fn backlash(&self) -> &[JointBacklash] {
        &self.backlash
    }

    /// The identified parameter errors (degrees and mm), in the order of
    /// [`crate::kinematics::calib_names`].
    pub fn parameters(&self) -> &[f64] {
        &self.parameters
    }

    /// What the campaign could identify: directions seen, observability
    /// indices, per-parameter standard errors.
    pub fn identifiability(&self) -> &Identifiability {
        &self.identifiability
    }

    /// The options it was identified with.
    pub fn options(&self) -> &CalibrationOptions {
        &self.options
    }

    /// Measured poses it was identified on.
    pub fn rows(&self) -> usize {
        self.rows
    }

    /// RMS per coordinate of the measured error before (nominal) and after
    /// the calibration, mm.
    pub fn rms_mm(&self) -> (f64, f64) {
        (self.rms_before_mm, self.rms_after_mm)
    }

    /// Levenberg–Marquardt steps of the final fit, and why it stopped.
    pub fn solver(&self) -> (usize, &str) {
        (self.iterations, &self.stop)
    }

    /// The same calibration identified anew on `data` (same nominal robot
    /// and options): what a refit on other rows does.
    pub fn reidentify(&self, data: &Dataset) -> Result<Calibration> {
        calibrate(data, &self.nominal, &self.options)
    }

    /// Checks after loading: the identified robot is the nominal one with
    /// the stored parameter errors applied.
    pub fn validate(&self, source_name: &str) -> Result<()> {
        let n = self.nominal.dof();
        let bad = |m: String| Error::Input {
            source_name: source_name.into(),
            message: m,
        };
        if self.parameters.len() != crate::kinematics::calib_len(n) {
            return Err(bad(format!(
                "the calibration has {} parameters, a {n}-joint robot needs {}",
                self.parameters.len(),
                crate::kinematics::calib_len(n)
            )));
        }
        let np = self.parameters.len();
        if self.uncertainty.iter().any(|(d, v)| {
            d.len() != np || !(v.is_finite() && *v >= 0.0) || d.iter().any(|x| !x.is_finite())
        }) {
            return Err(bad(
                "the calibration's uncertainty directions are inconsistent".into(),
            ));
        }
        for h in &self.harmonics {
            h.validate(n).map_err(bad)?;
        }
        for (i, b) in self.backlash.iter().enumerate() {
            b.validate(n).map_err(bad)?;
            if self.backlash[..i].iter().any(|c| c.joint == b.joint) {
                return Err(bad(format!(
                    "the calibration has two backlashes of q{}",
                    b.joint
                )));
            }
        }
        let nb = self.backlash.len();
        if self.backlash_covariance.len() != nb * nb
            || self.backlash_covariance.iter().any(|v| !v.is_finite())
        {
            return Err(bad(
                "the covariance of the calibration's backlash is inconsistent".into(),
            ));
        }
        let w = 2 * self.harmonics.len();
        if self.harmonic_covariance.len() != w * w
            || self.harmonic_covariance.iter().any(|v| !v.is_finite())
        {
            return Err(bad(
                "the covariance of the calibration's joint harmonics is inconsistent".into(),
            ));
        }
        if self.parameters.iter().any(|v| !v.is_finite()) {
            return Err(bad(
                "the calibration has a parameter that is not finite".into()
            ));
        }
        let again = apply_errors(&self.nominal, &self.parameters);
        let q = &self.nominal.home;
        let d = (again.fk_unchecked(q).translation.vector
            - self.identified.fk_unchecked(q).translation.vector)
            .norm();
        if d > 1e-6 {
            return Err(bad(format!(
                "the calibration's identified robot is not its nominal robot with its parameters ({d:.3e} mm apart at home)"
            )));
        }
        Ok(())
    }

    /// One line: "27 of 39 directions seen (noise 0.21 mm, cond 41, O1 …)",
    /// and the backlash and joint harmonics, if any.
    pub fn summary_line(&self) -> String {
        let id = &self.identifiability;
        let backlash = if self.backlash.is_empty() {
            String::new()
        } else {
            let per_joint: Vec<String> = self
                .backlash
                .iter()
                .map(|b| format!("q{} {}", b.joint, b.display_on(&self.nominal)))
                .collect();
            format!("; half backlash {}", per_joint.join(", "))
        };
        let harmonics = if self.harmonics.is_empty() {
            String::new()
        } else {
            let per_joint: Vec<String> = harmonics::by_joint(&self.harmonics)
                .iter()
                .map(|(j, of)| format!("q{j} {}", of.len()))
                .collect();
            format!(
                "; {} joint harmonics ({})",
                self.harmonics.len(),
                per_joint.join(", ")
            )
        };
        format!(
            "{} of {} directions seen above the residual noise {:.3} mm (condition number {:.3e}, O1 {:.3e}, O3 {:.3e}); RMS per coordinate {:.4} → {:.4} mm on {} poses",
            id.directions_seen,
            id.parameters_total,
            id.noise_mm,
            id.condition_number,
            id.o1,
            id.o3,
            self.rms_before_mm,
            self.rms_after_mm,
            self.rows
        ) + &backlash
            + &harmonics
    }
}

#[cfg(test)]
mod tests {
    use super::geometric::{position_residual, residual_jacobian};
    use super::*;
    use crate::kinematics::load_robot;
    use crate::kinematics::{IDENTIFICATION_STEP, identification_jacobian};
    use crate::vec3::residuals;

    /// The chain's residual Jacobian is the generic central differences'
    /// bit for bit, away from the nominal errors and with a base and tool.
    #[test]
    fn the_residual_jacobian_is_the_generic_central_differences() {
        let mut robot = load_robot("ur10").unwrap();
        robot.tool = nalgebra::Isometry3::translation(-0.14, 0.30, 92.82);
        let np = robot.dof() * 5 + 9;
        let data = campaign(&robot, &robot, 40, 0.0);
        let targets: Vec<Vector3<f64>> =
            data.q.iter().map(|q| robot.position(q).unwrap()).collect();
        let p: Vec<f64> = (0..np)
            .map(|j| 0.01 * ((j * 7 % 11) as f64 - 5.0))
            .collect();
        let generic = crate::optim::numerical_jacobian(
            |x| {
                Ok(position_residual(
                    &apply_errors(&robot, x),
                    &data.q,
                    &targets,
                ))
            },
            &p,
            &vec![IDENTIFICATION_STEP; np],
        )
        .unwrap();
        let fast = residual_jacobian(&robot, &p, IDENTIFICATION_STEP, &data.q, &targets);
        assert_eq!(fast.shape(), generic.shape());
        assert!(
            fast.iter()
                .zip(generic.iter())
                .all(|(a, b)| a.to_bits() == b.to_bits())
        );
    }

    fn campaign(robot: &Robot, truth: &Robot, m: usize, noise: f64) -> Dataset {
        campaign_with(robot, truth, &[], m, noise, 5)
    }

    /// `m` random poses of `robot` measured on `truth` whose joints also
    /// have the periodic errors `harmonics`, with noise `noise` mm.
    fn campaign_with(
        robot: &Robot,
        truth: &Robot,
        harmonics: &[JointHarmonic],
        m: usize,
        noise: f64,
        seed: u64,
    ) -> Dataset {
        campaign_played(robot, truth, harmonics, &[], m, noise, seed)
    }

    /// [`campaign_with`] whose joints also have the half backlashes
    /// `backlash` (each pose approached as the random sequence moves).
    fn campaign_played(
        robot: &Robot,
        truth: &Robot,
        harmonics: &[JointHarmonic],
        backlash: &[JointBacklash],
        m: usize,
        noise: f64,
        seed: u64,
    ) -> Dataset {
        let mut rng = crate::stats::rng_for(seed, "calibration test");
        let ranges = robot.work_ranges.clone();
        let q: Vec<Vec<f64>> = (0..m)
            .map(|_| {
                ranges
                    .iter()
                    .map(|(lo, hi)| lo + (hi - lo) * rand::RngExt::random::<f64>(&mut rng))
                    .collect()
            })
            .collect();
        let mut data = Dataset::from_poses("<calibration test>", q, None).unwrap();
        data.errors = Some(
            data.q
                .iter()
                .zip(&data.dir)
                .map(|(q, dir)| {
                    let played = backlash::reached(backlash, q, dir);
                    let reached = harmonics::deviated(harmonics, &played);
                    let d = truth.fk_unchecked(&reached).translation.vector
                        - robot.fk_unchecked(q).translation.vector;
                    std::array::from_fn(|a| {
                        d[a] + noise
                            * rand_distr::Distribution::<f64>::sample(
                                &rand_distr::StandardNormal,
                                &mut rng,
                            )
                    })
                })
                .collect(),
        );
        data
    }

    /// A backlash planted on seeded random joints, with seeded random sizes
    /// and signs: the calibration keeps those joints with their half
    /// backlashes, and predicts new poses from either side; the geometric
    /// calibration, which lacks it, does not.
    #[test]
    fn identifies_a_planted_backlash_beside_the_geometry() {
        let robot = crate::kinematics::load_robot("comau-nj220").unwrap();
        let n = robot.dof();
        let mut p = vec![0.0; crate::kinematics::calib_len(n)];
        p[2] = 0.3; // a1
        p[5 * 2 + 3] = 0.02; // alpha3
        let truth = apply_errors(&robot, &p);
        for seed in [3u64, 8] {
            let mut rng = crate::stats::rng_for(seed, "planted backlash");
            let mut joints: Vec<usize> = (1..=n).collect();
            let mut planted = Vec::new();
            for _ in 0..2 {
                let i = rand::RngExt::random_range(&mut rng, 0..joints.len());
                let size = 0.01 + 0.04 * rand::RngExt::random::<f64>(&mut rng);
                let sign = if rand::RngExt::random_bool(&mut rng, 0.5) {
                    1.0
                } else {
                    -1.0
                };
                planted.push(JointBacklash {
                    joint: joints.remove(i),
                    half_deg: sign * size,
                    evidence: 0.0,
                    tcp_rms_mm: 0.0,
                });
            }
            planted.sort_by_key(|b| b.joint);
            let data = campaign_played(&robot, &truth, &[], &planted, 300, 0.01, seed);
            let opts = CalibrationOptions::default().with_backlash(true);
            let cal = calibrate(&data, &robot, &opts).unwrap();
            // off by default
            assert!(
                calibrate(&data, &robot, &CalibrationOptions::default())
                    .unwrap()
                    .backlash()
                    .is_empty()
            );
            // what a planted backlash moves the TCP by (a wrist joint near
            // the flange may move it less than the noise: not to be seen)
            let jac = harmonics::jacobians(&robot, &data.q).unwrap();
            let at_tcp = |b: &JointBacklash| {
                let cols = backlash::unit_columns(std::slice::from_ref(b), &jac, &data.dir);
                let ss: f64 = cols
                    .iter()
                    .flat_map(|c| c.iter().map(|a| a[0] * a[0]))
                    .sum();
                b.half_deg.abs() * (ss / data.len() as f64).sqrt()
            };
            let seen: Vec<&JointBacklash> = planted.iter().filter(|b| at_tcp(b) > 0.03).collect();
            assert!(!seen.is_empty(), "seed {seed}: nothing planted to see");
            let found: Vec<usize> = cal.backlash().iter().map(|b| b.joint).collect();
            let want: Vec<usize> = seen.iter().map(|b| b.joint).collect();
            assert!(
                want.iter().all(|j| found.contains(j))
                    && found.iter().all(|j| planted.iter().any(|b| b.joint == *j)),
                "seed {seed}: {} against {want:?}",
                cal.summary_line()
            );
            for w in &seen {
                let b = cal.backlash().iter().find(|b| b.joint == w.joint).unwrap();
                assert!(
                    (b.half_deg - w.half_deg).abs() < 0.1 * w.half_deg.abs(),
                    "seed {seed}: q{} {} against {}",
                    b.joint,
                    b.half_deg,
                    w.half_deg
                );
            }
            cal.validate("<test>").unwrap();
            assert_eq!(
                cal.seen_displacements(&data.q, &data.dir).unwrap()[0].len(),
                cal.identifiability().directions_seen + cal.backlash().len()
            );
            // new poses, approached as a new sequence moves
            let check = campaign_played(&robot, &truth, &[], &planted, 60, 0.0, seed + 100);
            let worst = |c: &Calibration| {
                residuals(
                    check.errors.as_ref().unwrap(),
                    &c.predict(&check.q, &check.dir).unwrap(),
                )
                .iter()
                .map(|e| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt())
                .fold(0.0, f64::max)
            };
            let geometric = calibrate(&data, &robot, &CalibrationOptions::geometric()).unwrap();
            assert!(geometric.backlash().is_empty());
            let (with, without) = (worst(&cal), worst(&geometric));
            assert!(
                with < 0.03 && without > 2.0 * with,
                "seed {seed}: {with} against {without}"
            );
            // a file round-trips with its backlash
            let back: Calibration =
                serde_json::from_str(&serde_json::to_string(&cal).unwrap()).unwrap();
            assert_eq!(back.backlash(), cal.backlash());
            assert_eq!(
                back.predict(&check.q, &check.dir).unwrap(),
                cal.predict(&check.q, &check.dir).unwrap()
            );
            // directions not known: each joint at the middle of its play
            let mid = cal.predict(&check.q, &[]).unwrap();
            let stripped = Calibration {
                backlash: Vec::new(),
                backlash_covariance: Vec::new(),
                ..cal.clone()
            };
            assert_eq!(mid, stripped.predict(&check.q, &check.dir).unwrap());
            assert!(cal.predict(&check.q, &check.dir[..3]).is_err());
            let var = cal.predict_variance(&check.q, &[]).unwrap();
            assert_eq!(var.len(), check.len());
            assert_eq!(
                cal.seen_displacements(&check.q, &[]).unwrap()[0][0].len(),
                check.len()
            );
        }
    }

    #[test]
    fn recovers_the_errors_it_can_see_and_fixes_the_rest() {
        let robot = load_robot("comau-nj220").unwrap();
        let n = robot.dof();
        let mut p = vec![0.0; crate::kinematics::calib_len(n)];
        p[2] = 0.4; // a1
        p[5 + 1] = -0.3; // d2
        p[5 * 2 + 3] = 0.02; // alpha3
        let truth = apply_errors(&robot, &p);
        let data = campaign(&robot, &truth, 120, 0.01);
        let cal = calibrate(&data, &robot, &CalibrationOptions::default()).unwrap();
        let (before, after) = cal.rms_mm();
        assert!(after < 0.02 && before > 0.1, "{before} → {after}");
        let id = cal.identifiability();
        assert!(
            id.directions_seen < id.parameters_total,
            "{}",
            cal.summary_line()
        );
        assert!((id.noise_mm - 0.01).abs() < 0.003, "{}", id.noise_mm);
        // the calibration predicts the true kinematic error at new poses
        let check = campaign(&robot, &truth, 40, 0.0);
        let pred = cal.predict(&check.q, &check.dir).unwrap();
        let worst = residuals(check.errors.as_ref().unwrap(), &pred)
            .iter()
            .map(|e| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt())
            .fold(0.0, f64::max);
        assert!(worst < 0.02, "worst {worst}");
        cal.validate("<test>").unwrap();
        // more noise hides more directions
        let noisy = calibrate(
            &data,
            &robot,
            &CalibrationOptions {
                noise_mm: Some(5.0),
                ..CalibrationOptions::default()
            },
        )
        .unwrap();
        assert!(noisy.identifiability().directions_seen < id.directions_seen);
    }

    /// Geometric errors of the tests' truth: a1, d2, α3.
    fn geometric_truth(robot: &Robot) -> Robot {
        let mut p = vec![0.0; crate::kinematics::calib_len(robot.dof())];
        p[2] = 0.4;
        p[5 + 1] = -0.3;
        p[5 * 2 + 3] = 0.02;
        apply_errors(robot, &p)
    }

    #[test]
    fn finds_a_planted_joint_harmonic_and_nothing_on_a_campaign_without_one() {
        use rand::RngExt;
        let robot = load_robot("comau-nj220").unwrap();
        let truth = geometric_truth(&robot);
        for seed in 1..=3u64 {
            let mut rng = crate::stats::rng_for(seed, "planted joint harmonic");
            let (s, c) = (rng.random::<f64>() * std::f64::consts::TAU).sin_cos();
            let amp = 0.004 + 0.016 * rng.random::<f64>();
            // 3 to 12 cycles over the joint's work range: a harmonic, not
            // a smooth curve the geometric model and Kriging take up
            let joint = 1 + rng.random_range(0..3usize);
            let (lo, hi) = robot.work_ranges[joint - 1];
            let planted = JointHarmonic {
                joint,
                period_deg: (hi - lo) / (3.0 + 9.0 * rng.random::<f64>()),
                sin_deg: amp * s,
                cos_deg: amp * c,
                evidence: 0.0,
                tcp_rms_mm: 0.0,
            };
            let data = campaign_with(
                &robot,
                &truth,
                std::slice::from_ref(&planted),
                300,
                0.01,
                seed,
            );
            let cal = calibrate(&data, &robot, &CalibrationOptions::default()).unwrap();
            let found = cal.harmonics();
            assert_eq!(
                found.len(),
                1,
                "seed {seed}: {found:?}, planted {planted:?}"
            );
            let h = &found[0];
            assert_eq!(h.joint, planted.joint, "seed {seed}");
            assert!(
                (h.period_deg / planted.period_deg - 1.0).abs() < 0.01,
                "seed {seed}: {} against {}",
                h.period_deg,
                planted.period_deg
            );
            assert!(
                (h.amplitude_deg() / amp - 1.0).abs() < 0.15,
                "seed {seed}: {} against {amp}",
                h.amplitude_deg()
            );
            // what is left is the noise, and the geometric calibration alone
            // leaves more
            assert!(
                cal.rms_mm().1 < 0.0115,
                "seed {seed}: {}",
                cal.summary_line()
            );
            let geometric = calibrate(&data, &robot, &CalibrationOptions::geometric()).unwrap();
            assert!(geometric.harmonics().is_empty());
            assert!(geometric.rms_mm().1 > 1.2 * cal.rms_mm().1);
            // the harmonics' columns join the directions a diagnosis refits,
            // and their coefficients' uncertainty the prediction's variance
            let seen = cal.identifiability().directions_seen;
            assert!(
                cal.backlash().is_empty(),
                "seed {seed}: {}",
                cal.summary_line()
            );
            assert_eq!(
                cal.seen_displacements(&data.q, &data.dir).unwrap()[0].len(),
                seen + 2
            );
            let with = cal
                .predict_variance(&data.q[..20], &data.dir[..20])
                .unwrap();
            let mut without = cal.clone();
            without.harmonic_covariance = vec![0.0; 4];
            let base = without
                .predict_variance(&data.q[..20], &data.dir[..20])
                .unwrap();
            assert!(with.iter().zip(&base).all(|(a, b)| a[0] >= b[0]));
            assert!(with.iter().zip(&base).any(|(a, b)| a[0] > b[0]));
            // a file round-trips; one written before joint harmonics existed
            // reads as a geometric calibration
            let text = serde_json::to_string(&cal).unwrap();
            let back: Calibration = serde_json::from_str(&text).unwrap();
            assert_eq!(
                back.predict(&data.q[..5], &data.dir[..5]).unwrap(),
                cal.predict(&data.q[..5], &data.dir[..5]).unwrap()
            );
            let old = serde_json::to_string(&geometric).unwrap();
            assert!(!old.contains("harmonic"), "{old}");
            let back: Calibration = serde_json::from_str(&old).unwrap();
            assert!(!back.options().joint_harmonics);
            assert!(!back.options().backlash);
        }
        for seed in 11..=15u64 {
            let data = campaign_with(&robot, &truth, &[], 300, 0.01, seed);
            let cal = calibrate(&data, &robot, &CalibrationOptions::default()).unwrap();
            assert!(
                cal.harmonics().is_empty(),
                "seed {seed}: {}",
                cal.summary_line()
            );
        }
    }

    #[test]
    fn bad_input_is_an_error() {
        let robot = load_robot("comau-nj220").unwrap();
        let data = campaign(&robot, &robot, 10, 0.0);
        // all-zero errors: nothing to calibrate
        assert!(calibrate(&data, &robot, &CalibrationOptions::default()).is_err());
        let bad = CalibrationOptions {
            noise_mm: Some(-1.0),
            ..CalibrationOptions::default()
        };
        assert!(bad.validate().is_err());
    }

    /// The stated variance is the sum of its parts written out (the
    /// directions' `Σ_i var_i (J D v_i)²`, then the joint harmonics' and
    /// the backlash's quadratic forms), with the joint terms and without
    /// directions (each backlash at mid-play: no share), and the diagonal
    /// of `G' Σ' G'ᵀ` from the design and its covariance.
    #[test]
    fn the_design_rows_and_covariance_give_the_stated_variance() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
        let data = crate::dataset::read_csv(path.as_ref()).unwrap();
        let robot = load_robot("comau-nj220").unwrap();
        let cal = calibrate(
            &data,
            &robot,
            &CalibrationOptions::default().with_backlash(true),
        )
        .unwrap();
        assert!(!cal.backlash().is_empty());
        let rows: Vec<usize> = (0..data.len()).step_by(37).collect();
        let part = data.select(&rows);
        let sigma = cal.design_covariance();
        let p = sigma.nrows();
        assert_eq!(
            p,
            cal.parameters().len() + 2 * cal.harmonics().len() + cal.backlash().len()
        );
        for dir in [&part.dir[..], &[]] {
            let g = cal.design_rows(&part.q, dir).unwrap();
            let stated = cal.predict_variance(&part.q, dir).unwrap();
            let terms = cal.joint_term_columns_at(&part.q, dir).unwrap();
            let nh = 2 * cal.harmonics().len();
            let quadratic = |h: &[f64], c: &[f64]| -> f64 {
                let w = h.len();
                (0..w)
                    .flat_map(|i| (0..w).map(move |j| h[i] * c[i * w + j] * h[j]))
                    .sum()
            };
            for (k, w) in stated.iter().enumerate() {
                let jac = identification_jacobian(&robot, &part.q[k]);
                let gk = nalgebra::DMatrix::from_row_slice(3, p, &g[k * 3 * p..(k + 1) * 3 * p]);
                let v = &gk * &sigma * gk.transpose();
                for a in 0..3 {
                    let along: f64 = cal
                        .uncertainty
                        .iter()
                        .map(|(d, var)| {
                            var * jac[a]
                                .iter()
                                .zip(d)
                                .map(|(x, y)| x * y)
                                .sum::<f64>()
                                .powi(2)
                        })
                        .sum();
                    let (h, b) = terms[k][a].split_at(nh);
                    let parts = along
                        + quadratic(h, &cal.harmonic_covariance)
                        + quadratic(b, &cal.backlash_covariance);
                    for (what, x) in [("parts", parts), ("G Σ Gᵀ", v[(a, a)])] {
                        assert!(
                            (x - w[a]).abs() <= 1e-9 * w[a].max(1e-12),
                            "pose {k} axis {a}: {what} {x} vs stated {}",
                            w[a]
                        );
                    }
                }
            }
        }
    }
}
