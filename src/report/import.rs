//! `import`: what was read from an export, and the tracker located.

use crate::dataset::import::{AngleUnit, ImportSpec, Imported, LengthUnit};
use crate::kinematics::TrackerFit;
use std::path::Path;

/// What was read from `export`: rows, joints, the separators and units
/// used, and the export's columns no target names.
pub fn read(imported: &Imported, spec: &ImportSpec, export: &Path) -> String {
    let data = &imported.data;
    let mut s = format!(
        "read {} rows, {} joints from {} (delimiter {:?}, decimal {:?}, angles {}, lengths {})\n",
        data.len(),
        data.n_joints(),
        export.display(),
        imported.delimiter,
        imported.decimal,
        match spec.angles {
            AngleUnit::Deg => "deg",
            AngleUnit::Rad => "rad",
        },
        match spec.lengths {
            LengthUnit::Mm => "mm",
            LengthUnit::M => "m",
        }
    );
    if !imported.ignored.is_empty() {
        s += &format!(
            "  not imported (no target names them): {}\n",
            imported.ignored.join(", ")
        );
    }
    s
}

/// What became of the measured positions of `imported`: with the robot
/// (named `robot`) and the tracker located (`fit`), the tracker → base
/// transform (translation, roll-pitch-yaw), the TCP offset and the RMS of
/// the errors it leaves; without a robot, that they stay in the tracker's
/// frame; empty for a campaign that gives errors.
pub fn located(robot: Option<&str>, imported: &Imported, fit: Option<&TrackerFit>) -> String {
    match (robot, fit) {
        (Some(r), Some(fit)) => tracker(r, imported.data.len(), fit),
        (None, _) if imported.data.positions.is_some() => {
            "  measured positions kept as x,y,z (tracker frame); give --robot to turn them into errors\n".into()
        }
        _ => String::new(),
    }
}

/// The tracker located for robot `robot` over `rows` rows ([`located`]).
fn tracker(robot: &str, rows: usize, fit: &TrackerFit) -> String {
    let t = fit.tracker_to_base.translation.vector;
    let (roll, pitch, yaw) = fit.tracker_to_base.rotation.euler_angles();
    format!(
        "  tracker → base of '{robot}' by least squares over all {rows} rows ({} iterations): translation ({:.3}, {:.3}, {:.3}) mm, rpy ({:.4}, {:.4}, {:.4})°\n\
         \x20 TCP offset in the flange frame: ({:.4}, {:.4}, {:.4}) mm; errors measured − nominal: rms |e| {:.4} mm\n",
        fit.iterations,
        t.x,
        t.y,
        t.z,
        roll.to_degrees(),
        pitch.to_degrees(),
        yaw.to_degrees(),
        fit.tool_xyz_mm.x,
        fit.tool_xyz_mm.y,
        fit.tool_xyz_mm.z,
        fit.rms_mm
    )
}

/// The JSON of `import --json`: the files, the campaign's size and
/// directions, the separators, units and mapping used, the columns not
/// imported, the robot and the tracker located.
pub fn json(
    (export, output): (&Path, &Path),
    imported: &Imported,
    spec: &ImportSpec,
    (robot, located): (Option<&str>, Option<&TrackerFit>),
) -> serde_json::Value {
    let data = &imported.data;
    serde_json::json!({
        "export": export, "output": output, "rows": data.len(),
        "joints": data.n_joints(), "delimiter": imported.delimiter.to_string(),
        "decimal": imported.decimal.to_string(), "angles": spec.angles,
        "lengths": spec.lengths, "columns": spec.columns, "ignored": imported.ignored,
        "directions": format!("{:?}", data.dir_source).to_lowercase(),
        "robot": robot,
        "located": located.map(|f| serde_json::json!({
            "tracker_to_base": f.tracker_to_base, "tool_xyz_mm": f.tool_xyz_mm,
            "rms_mm": f.rms_mm, "iterations": f.iterations,
        })),
    })
}
