//! The robot presets: robot files (see [`super::RobotFile`]) shipped in the
//! crate, in `src/kinematics/robots/`.
//!
//! Every preset is a chain of MD-H links (seed 003 eq 1) with β = 0, i.e. a
//! standard (distal) D-H table; offsets and signs map the controller's joint
//! values onto the D-H angles as `θ = sign·q + offset`. Each file's comment
//! gives its source and convention.

use super::{Robot, RobotFile};
use crate::{Error, Result};

/// Names accepted by [`preset`].
pub const PRESET_NAMES: [&str; 4] = ["comau-nj220", "kuka-kr30ha", "ur10", "scara-rh3frh5515"];

/// The robot file of each preset, in [`PRESET_NAMES`] order.
const PRESET_FILES: [&str; 4] = [
    include_str!("robots/comau-nj220.toml"),
    include_str!("robots/kuka-kr30ha.toml"),
    include_str!("robots/ur10.toml"),
    include_str!("robots/scara-rh3frh5515.toml"),
];

/// The robot-file text of preset `name` (what `--robot NAME` reads), if it is one.
pub fn preset_file(name: &str) -> Option<&'static str> {
    let k = PRESET_NAMES.iter().position(|p| *p == name)?;
    Some(PRESET_FILES[k])
}

/// The preset `name`, or `None` if no preset has that name.
pub(super) fn try_preset(name: &str) -> Option<Result<Robot>> {
    let text = preset_file(name)?;
    let source = format!("preset {name}");
    Some(RobotFile::from_toml(text, &source).and_then(|f| f.robot(&source)))
}

/// The preset robot called `name` (see [`PRESET_NAMES`]). COMAU SMART5 NJ
/// 220-2.7 (seeds 003, 004), KUKA KR 30 HA (seed 002), Universal Robots UR10
/// (the IPA data set) and the Mitsubishi RH-3FRH5515 SCARA (seed 000).
pub fn preset(name: &str) -> Result<Robot> {
    try_preset(name).unwrap_or_else(|| {
        Err(Error::UnknownRobot {
            name: name.to_string(),
            known: PRESET_NAMES.join(", "),
        })
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn every_preset_parses_with_its_own_name() {
        for name in PRESET_NAMES {
            let r = preset(name).unwrap();
            assert_eq!(r.name, name);
            assert_eq!(r.home.len(), r.dof());
        }
    }
}
