//! Robot presets with nominal parameters, limits and campaign ranges.
//!
//! Every preset is a chain of [`MdhLink`]s in the MD-H form of seed 003 eq 1
//! with β = 0, i.e. a standard (distal) D-H table; offsets and signs map the
//! controller's joint values onto the D-H angles as `θ = sign·q + offset`.

use super::{MdhLink, Robot};
use crate::{Error, Result};
use nalgebra::Isometry3;

/// Names accepted by [`preset`].
pub const PRESET_NAMES: [&str; 4] = ["comau-nj220", "kuka-kr30ha", "ur10", "scara-rh3frh5515"];

/// The preset robot called `name` (see [`PRESET_NAMES`]).
pub fn preset(name: &str) -> Result<Robot> {
    match name {
        "comau-nj220" => Ok(comau_nj220()),
        "kuka-kr30ha" => Ok(kuka_kr30ha()),
        "ur10" => Ok(ur10()),
        "scara-rh3frh5515" => Ok(scara_rh3frh5515()),
        _ => Err(Error::UnknownRobot {
            name: name.to_string(),
            known: PRESET_NAMES.join(", "),
        }),
    }
}

fn robot(name: &str, convention: &str, links: Vec<MdhLink>) -> Robot {
    let n = links.len();
    Robot {
        name: name.to_string(),
        convention: convention.to_string(),
        links,
        base: Isometry3::identity(),
        tool: Isometry3::identity(),
        limits: vec![(-360.0, 360.0); n],
        work_ranges: vec![(-15.0, 15.0); n],
        home: vec![0.0; n],
    }
}

/// COMAU SMART5 NJ 220-2.7, the robot of seeds 003 and 004.
///
/// Standard D-H (β = 0) from public RoboDK-derived catalogue values:
/// d1 = 830, a1 = 400, a2 = 1175, a3 = 250, d4 = 1125.33, d6 = 230 mm;
/// α = −90°, 0, −90°, 90°, −90°, 0.
/// Angle convention: `θ1 = q1`, `θ2 = −q2 − 90°`, `θ3 = −q3 − 90°`, `θ4..6 = q4..6`,
/// so `q = (0, 0, −90°, 0, 0, 0)` has the upper arm vertical and the forearm
/// horizontal (COMAU's home, A3 = −90°), negative `q2` leans the arm forward and
/// `q3` below −90° tilts the forearm down. With these signs the joint ranges of
/// seed 004 Table 2 (the campaign default) put the TCP in front of and below
/// the shoulder. Signs of the real controller axes are not verified.
/// Limits are approximate catalogue values.
pub fn comau_nj220() -> Robot {
    let links = vec![
        MdhLink::revolute(0.0, 830.0, 400.0, -90.0),
        MdhLink::revolute(-90.0, 0.0, 1175.0, 0.0).with_sign(-1.0),
        MdhLink::revolute(-90.0, 0.0, 250.0, -90.0).with_sign(-1.0),
        MdhLink::revolute(0.0, 1125.33, 0.0, 90.0),
        MdhLink::revolute(0.0, 0.0, 0.0, -90.0),
        MdhLink::revolute(0.0, 230.0, 0.0, 0.0),
    ];
    let mut r = robot(
        "comau-nj220",
        "standard D-H + beta (MD-H, seed 003 eq 1); theta = sign*q + offset, q2/q3 sign -1",
        links,
    );
    r.limits = vec![
        (-180.0, 180.0),
        (-75.0, 95.0),
        (-256.0, -10.0),
        (-270.0, 270.0),
        (-125.0, 125.0),
        (-270.0, 270.0),
    ];
    // seed 004 Table 2
    r.work_ranges = vec![
        (-20.0, 20.0),
        (-40.0, 0.0),
        (-150.0, -100.0),
        (-15.0, 15.0),
        (-55.0, 15.0),
        (-15.0, 15.0),
    ];
    r.home = vec![0.0, -20.0, -125.0, 0.0, -20.0, 0.0];
    r
}

/// KUKA KR 30 HA, the robot of seed 002.
///
/// Standard D-H (β = 0) from public RoboDK-derived catalogue values:
/// d1 = 815, a1 = 350, a2 = 850, a3 = 145, d4 = 820, d6 = 170 mm;
/// α = −90°, 0, −90°, 90°, −90°, 0.
/// KUKA convention: `θ1 = −q1` (A1 positive is clockwise seen from above),
/// `θ2 = q2` (A2 = −90° upper arm vertical, A2 = 0 horizontal forward),
/// `θ3 = q3 − 90°` (A3 = 90° forearm horizontal), `θ4..6 = q4..6`.
/// Limits are approximate catalogue values.
pub fn kuka_kr30ha() -> Robot {
    let links = vec![
        MdhLink::revolute(0.0, 815.0, 350.0, -90.0).with_sign(-1.0),
        MdhLink::revolute(0.0, 0.0, 850.0, 0.0),
        MdhLink::revolute(-90.0, 0.0, 145.0, -90.0),
        MdhLink::revolute(0.0, 820.0, 0.0, 90.0),
        MdhLink::revolute(0.0, 0.0, 0.0, -90.0),
        MdhLink::revolute(0.0, 170.0, 0.0, 0.0),
    ];
    let mut r = robot(
        "kuka-kr30ha",
        "standard D-H + beta (MD-H, seed 003 eq 1); KUKA angles: theta1 = -q1, theta3 = q3 - 90",
        links,
    );
    r.limits = vec![
        (-185.0, 185.0),
        (-135.0, 35.0),
        (-120.0, 158.0),
        (-350.0, 350.0),
        (-119.0, 119.0),
        (-350.0, 350.0),
    ];
    r.work_ranges = vec![
        (-20.0, 20.0),
        (-70.0, -30.0),
        (80.0, 130.0),
        (-15.0, 15.0),
        (-40.0, 40.0),
        (-15.0, 15.0),
    ];
    r.home = vec![0.0, -50.0, 105.0, 0.0, 0.0, 0.0];
    r
}

/// Universal Robots UR10 (the public IPA data set in `../shared/data/ipa-ur10`).
///
/// The manufacturer's standard D-H table, unchanged (offsets 0, signs +1):
/// d1 = 127.3, a2 = −612, a3 = −572.3, d4 = 163.941, d5 = 115.7, d6 = 92.2 mm;
/// α = 90°, 0, 0, 90°, −90°, 0. Joints turn ±360°.
pub fn ur10() -> Robot {
    let links = vec![
        MdhLink::revolute(0.0, 127.3, 0.0, 90.0),
        MdhLink::revolute(0.0, 0.0, -612.0, 0.0),
        MdhLink::revolute(0.0, 0.0, -572.3, 0.0),
        MdhLink::revolute(0.0, 163.941, 0.0, 90.0),
        MdhLink::revolute(0.0, 115.7, 0.0, -90.0),
        MdhLink::revolute(0.0, 92.2, 0.0, 0.0),
    ];
    let mut r = robot(
        "ur10",
        "Universal Robots standard D-H table, theta = q",
        links,
    );
    r.work_ranges = vec![
        (-180.0, 180.0),
        (-150.0, -30.0),
        (-140.0, 140.0),
        (-180.0, 0.0),
        (30.0, 150.0),
        (-180.0, 180.0),
    ];
    r.home = vec![0.0, -90.0, 90.0, -90.0, 90.0, 0.0];
    r
}

/// Mitsubishi RH-3FRH5515 SCARA, the robot of seed 000 (L1 = 325, L2 = 225 mm).
///
/// Standard D-H with all twists 0: J1 and J2 revolute about z with link lengths
/// L1, L2; J3 prismatic along z (its value is the TCP height Z*, mm); J4
/// revolute (tool roll). With zero errors the TCP is exactly seed 000 eq 1:
/// `(L1 cos θ1 + L2 cos(θ1+θ2), L1 sin θ1 + L2 sin(θ1+θ2), Z*)`.
pub fn scara_rh3frh5515() -> Robot {
    let links = vec![
        MdhLink::revolute(0.0, 0.0, 325.0, 0.0),
        MdhLink::revolute(0.0, 0.0, 225.0, 0.0),
        MdhLink::prismatic(0.0, 0.0, 0.0, 0.0),
        MdhLink::revolute(0.0, 0.0, 0.0, 0.0),
    ];
    let mut r = robot(
        "scara-rh3frh5515",
        "standard D-H, all twists 0; q3 is a prismatic height in mm (seed 000 eq 1)",
        links,
    );
    r.limits = vec![
        (-170.0, 170.0),
        (-145.0, 145.0),
        (0.0, 150.0),
        (-360.0, 360.0),
    ];
    r.work_ranges = vec![
        (-165.0, 165.0),
        (-143.0, 143.0),
        (50.0, 100.0),
        (-90.0, 90.0),
    ];
    r.home = vec![0.0, 45.0, 75.0, 0.0];
    r
}
