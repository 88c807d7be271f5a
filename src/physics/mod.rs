//! Physics-based error models of seeds 000 and 002, the yardstick for the
//! Kriging engine.
//!
//! | item | paper |
//! |---|---|
//! | [`BidirectionalTable`] | lookup table per direction, linear interpolation (seed 000 eqs 3–6, 19) |
//! | [`PhysicsModel`] | identified geometry + tables: SCARA (seed 000 eqs 3, 18, 23) or MD-H chain (seed 002 eqs 1–2) |
//! | [`identify_scara`] | seed 000 §2.4: frames, circle fits, eqs 7–14, 20, 22 |
//! | [`identify_crosstalk`] | seed 000 §5.2: J1's deviation at several J2 angles, against the model |
//! | [`identify_apd`], [`identify_mdh`] | seed 002: APD tables by circle-point analysis of indexing tests, MD-H errors by Levenberg–Marquardt |
//! | [`HybridModel`] | physics first, universal Kriging on its residual |
//! | [`register_campaign`] | tracker frame → base frame by SVD registration (seed 004 eqs 29–35) |
//! | [`probe`], [`straightness`], [`probing_example`] | seed 002 eqs 3–6: probing a straightedge, straightness before/after (Table 2) |
//! | [`compare`] | nominal / D-H / D-H+APD / Kriging JS, EJS / hybrid on one simulated robot |
//! | [`PhysicsModel::check_against`] | an identified SCARA against the simulator's truth (checking only) |

mod compare;
mod crosstalk;
mod mdh;
mod model;
mod probing;
mod scara;
mod table;
mod truth;

pub use compare::{CompareOptions, CompareRow, Comparison, Score, compare};
pub use crosstalk::{CrosstalkGroup, CrosstalkReport, identify_crosstalk};
pub use mdh::{ApdIdentification, LmSummary, apply_errors, identify_apd, identify_mdh};
pub use model::{
    AnyModel, Geometry, HybridModel, PHYSICS_FORMAT, PHYSICS_VERSION, PhysicsModel, ScaraGeometry,
};
pub use probing::{
    ProbeRun, ProbingRow, Straightedge, Straightness, example_edges, probe, probed_points,
    probing_example, straightness,
};
pub use scara::{AxisReport, ScaraIdentification, ScaraOptions, identify_scara};
pub use table::BidirectionalTable;
pub use truth::{ApdCheck, TruthCheck};

use crate::Result;
use crate::dataset::Dataset;
use crate::kinematics::Robot;
use serde::{Deserialize, Serialize};

/// The physics models of one robot: D-H only and D-H + lookup tables.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PhysicsIdentification {
    /// D-H parameters and angular positioning deviation tables.
    pub full: PhysicsModel,
    /// The conventional model: D-H parameters only.
    pub dh: PhysicsModel,
    /// How it was identified, one line.
    pub method: String,
    /// What the identification saw, per identified axis.
    pub axes: Vec<AxisReport>,
    /// Axes that could not be used, with the reason.
    pub notes: Vec<String>,
    /// The calibrations, when Levenberg–Marquardt was used: D-H only, D-H + APD.
    pub lm: Vec<LmSummary>,
}

/// Whether `robot` is a SCARA in the sense of seed 000: J1 and J2 revolute
/// about parallel axes (no twist on link 1).
pub fn is_scara(robot: &Robot) -> bool {
    use crate::kinematics::JointKind::Revolute;
    robot.dof() >= 2
        && robot.links[0].kind == Revolute
        && robot.links[1].kind == Revolute
        && robot.links[0].alpha_deg.abs() < 1e-9
        && robot.links[1].alpha_deg.abs() < 1e-9
}

/// Whether a training campaign (`given`) fits `robot`'s identification
/// ([`identify_physics`]): a SCARA is identified from its indexing tests
/// alone and takes none; a six-axis robot's D-H errors are identified by
/// Levenberg–Marquardt on one, which it needs. Messages name the
/// `physics identify` option.
pub fn check_training_campaign(robot: &Robot, given: bool) -> Result<()> {
    match (is_scara(robot), given) {
        (true, true) => Err(crate::Error::InvalidParameter(format!(
            "--train is for six-axis robots; '{}' is a SCARA, identified from its indexing tests alone",
            robot.name
        ))),
        (false, false) => Err(crate::Error::InvalidParameter(format!(
            "'{}' is not a SCARA: its D-H errors are identified by Levenberg–Marquardt on a campaign; give --train CAMPAIGN.csv",
            robot.name
        ))),
        _ => Ok(()),
    }
}

/// The robot of an identification when none is named (`physics
/// identify`): the SCARA of seed 000.
pub const DEFAULT_ROBOT: &str = "scara-rh3frh5515";

/// Error unless each of `campaigns` fits `robot`
/// ([`Robot::check_dataset`]); `name` is the robot as the user named it,
/// and a campaign that does not fit the [`DEFAULT_ROBOT`] is told that it
/// met the default.
pub fn check_campaigns(robot: &Robot, name: &str, campaigns: &[&Dataset]) -> Result<()> {
    let hint = |e| match e {
        crate::Error::Input {
            source_name,
            message,
        } if name == DEFAULT_ROBOT => crate::Error::Input {
            source_name,
            message: format!("{message} (the default robot is {DEFAULT_ROBOT})"),
        },
        e => e,
    };
    campaigns
        .iter()
        .try_for_each(|d| robot.check_dataset(d).map_err(hint))
}

/// Identify the physics models of `nominal`:
/// - a SCARA (seed 000): everything from the indexing tests
///   ([`identify_scara`]); the D-H model is the same without tables (eq 2);
/// - otherwise (seed 002): APD tables from the indexing tests
///   ([`identify_apd`]), then MD-H errors by Levenberg–Marquardt on the
///   campaign `train`, once with the joints as commanded (D-H only) and once
///   with the APD-corrected joints (D-H + APD).
pub fn identify_physics(
    indexing: &Dataset,
    train: &Dataset,
    nominal: &Robot,
) -> Result<PhysicsIdentification> {
    if is_scara(nominal) {
        let id = identify_scara(indexing, nominal, &ScaraOptions::default())?;
        return Ok(PhysicsIdentification {
            dh: id.model.dh_only(),
            full: id.model,
            method: "seed 000: D-H errors, APD and radial tables and parallelism from the J1/J2 indexing tests".into(),
            axes: id.axes,
            notes: id.skipped,
            lm: Vec::new(),
        });
    }
    let apd = identify_apd(indexing, nominal, 50.0)?;
    let (dh_robot, lm_dh) = identify_mdh(train, nominal, &vec![None; nominal.dof()])?;
    let (robot, lm_full) = identify_mdh(train, nominal, &apd.apd)?;
    let mut full = PhysicsModel::new(
        format!(
            "seed 002: APD tables from the indexing tests of {}, MD-H errors by Levenberg–Marquardt on {}",
            indexing.source, train.source
        ),
        nominal.clone(),
        Geometry::Mdh { robot },
    );
    full.apd = apd.apd;
    let dh = PhysicsModel::new(
        format!("MD-H errors by Levenberg–Marquardt on {}", train.source),
        nominal.clone(),
        Geometry::Mdh { robot: dh_robot },
    );
    Ok(PhysicsIdentification {
        full,
        dh,
        method: "seed 002: APD tables from the indexing tests, MD-H errors by Levenberg–Marquardt on the campaign".into(),
        axes: apd.axes,
        notes: apd.skipped,
        lm: vec![lm_dh, lm_full],
    })
}

/// [`identify_physics`] of `robot` (named `name` by the user) from the
/// campaigns given: the indexing tests and the training campaign `train`,
/// which a six-axis robot needs and a SCARA refuses
/// ([`check_training_campaign`]; a SCARA trains on its indexing tests),
/// each checked against the robot first ([`check_campaigns`]).
pub fn identify_campaigns(
    robot: &Robot,
    name: &str,
    indexing: &Dataset,
    train: Option<&Dataset>,
) -> Result<PhysicsIdentification> {
    check_training_campaign(robot, train.is_some())?;
    let train = train.unwrap_or(indexing);
    check_campaigns(robot, name, &[indexing, train])?;
    identify_physics(indexing, train, robot)
}

/// Register a campaign measured in a tracker's frame into the robot's base
/// frame (seed 004 eqs 29–35): the rigid transform that best maps the
/// measured positions `x, y, z` onto the nominal TCP positions of the
/// commanded joints ([`crate::frames::register`], reflection-safe), applied
/// to the positions, and the errors recomputed as `registered − nominal`.
/// The best-fit rigid part of the robot's own error is absorbed by the
/// transform, as in the paper. Error unless the campaign fits `nominal`
/// ([`Robot::check_dataset`]) and has the measured positions.
pub fn register_campaign(
    data: &Dataset,
    nominal: &Robot,
) -> Result<(Dataset, crate::frames::Registration)> {
    use nalgebra::{Point3, Vector3};
    nominal.check_dataset(data)?;
    let positions = data.positions.as_ref().ok_or_else(|| crate::Error::Input {
        source_name: data.source.clone(),
        message: "registration needs the measured positions x,y,z".into(),
    })?;
    let from: Vec<Vector3<f64>> = positions.iter().map(|p| Vector3::from(*p)).collect();
    let to: Vec<Vector3<f64>> = data
        .q
        .iter()
        .map(|q| nominal.fk_unchecked(q).translation.vector)
        .collect();
    let reg = crate::frames::register(&from, &to)?;
    let moved: Vec<Vector3<f64>> = from
        .iter()
        .map(|p| (reg.transform * Point3::from(*p)).coords)
        .collect();
    let mut out = data.clone();
    out.positions = Some(moved.iter().map(|p| (*p).into()).collect());
    out.errors = Some(moved.iter().zip(&to).map(|(p, n)| (p - n).into()).collect());
    Ok((out, reg))
}
