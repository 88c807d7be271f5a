//! Robot programs: an ordered list of joint-space moves as text a
//! controller runs.
//!
//! A campaign or a compensated path is a list of [`ProgramPose`]s, each a
//! joint vector in robokrige's units (degrees; mm for a prismatic joint, as
//! in the joint CSVs), a flag saying whether the tracker measures there, and
//! an optional label. [`render`] turns it into one of four
//! [`ProgramFormat`]s:
//!
//! | format | file | a move | after a measured pose |
//! |---|---|---|---|
//! | [`Csv`](ProgramFormat::Csv) | `id,q1..qN,measure[,label]` | one row | — |
//! | [`Urscript`](ProgramFormat::Urscript) | `def name(): … end` | `movej([…rad…], a=…, v=…)` | `sleep(t)` |
//! | [`Krl`](ProgramFormat::Krl) (KUKA) | `.src`: `DEF name( ) … END` | `PTP {A1 …, …, A6 …}` (deg) | `WAIT SEC t` |
//! | [`Rapid`](ProgramFormat::Rapid) (ABB) | `MODULE name … PROC main() … ENDMODULE` | `MoveAbsJ [[…deg…],[9E9,…]], vN, fine, tool0;` | `WaitTime t;` |
//!
//! Every move of a robot program is preceded by a comment line naming it:
//! `measure k` for the k-th measured pose (0-based, counting measured poses
//! only: row k of the measurement file the campaign gives) or `via` for a
//! pose the robot only passes through (a pre-position move, or a point of a
//! compensated path), followed by the pose's label in parentheses when it
//! has one. The CSV's `id` is the move's 0-based index among all moves.
//!
//! The controllers' own rules are checked before any text is written:
//! URScript's `movej` takes the six revolute joints of a UR arm (radians);
//! KRL and RAPID programs are written for six-axis robots only, because how
//! a robot with fewer axes (a SCARA, a palletiser) or more (a track, a
//! seventh arm axis) maps onto `A1..A6`/`E1..` or `rax_1..rax_6`/`eax_a..`
//! depends on its model: write such a robot's moves as CSV and map them
//! there. A prismatic joint's value is written in mm, as KRL and RAPID take
//! a linear axis.
//!
//! Every move is an exact stop (URScript without blend radius, KRL `PTP`
//! without approximation, RAPID `fine`), and the speeds are slow by default
//! ([`ProgramOptions`]): run a generated program in the controller's
//! simulation, or at reduced override, before running it on the robot.

mod joints_csv;
mod krl;
mod rapid;
mod urscript;

use crate::{Error, Result};
use std::path::Path;

/// One move of a program: where the joints go, and whether the tracker
/// measures there.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramPose {
    /// Joint values, degrees (mm for a prismatic joint), as in robokrige's
    /// joint CSVs.
    pub q: Vec<f64>,
    /// Whether the tracker measures at this pose (the program then waits
    /// [`ProgramOptions::settle_s`] there); `false` for a via-point, a
    /// pre-position move or a point of a compensated path.
    pub measure: bool,
    /// A short note on the pose, written into its comment (printable ASCII).
    pub label: Option<String>,
}

impl ProgramPose {
    /// A pose the tracker measures.
    pub fn measured(q: Vec<f64>) -> Self {
        ProgramPose {
            q,
            measure: true,
            label: None,
        }
    }

    /// A pose the robot only passes through (a via-point).
    pub fn via(q: Vec<f64>) -> Self {
        ProgramPose {
            q,
            measure: false,
            label: None,
        }
    }

    /// The same pose with a label.
    pub fn with_label(mut self, label: impl Into<String>) -> Self {
        self.label = Some(label.into());
        self
    }
}

/// The text a program is written as.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum ProgramFormat {
    /// A joint CSV: `id,q1..qN,measure` (and `label` when a pose has one);
    /// a campaign plan writes its own CSV, with the directions (the plan's
    /// `write_csv`).
    #[cfg_attr(
        feature = "cli",
        value(
            help = "CSV, one row per move (degrees; mm for prismatic joints): compensate writes id,q1..qN,measure[,label], plan id,q1..qN,dir1..dirN,measure,source"
        )
    )]
    Csv,
    /// Universal Robots URScript: `movej` in radians.
    #[cfg_attr(
        feature = "cli",
        value(help = "Universal Robots URScript (def … end, movej in radians)")
    )]
    Urscript,
    /// KUKA KRL: a `.src` file with `PTP` axis moves in degrees.
    #[cfg_attr(
        feature = "cli",
        value(
            help = "KUKA KRL .src (DEF … END, PTP {A1 …} in degrees; the file name is the DEF name)"
        )
    )]
    Krl,
    /// ABB RAPID: a module with `MoveAbsJ` in degrees.
    #[cfg_attr(
        feature = "cli",
        value(help = "ABB RAPID module (PROC main, MoveAbsJ in degrees)")
    )]
    Rapid,
}

impl ProgramFormat {
    /// Every format, in the order of [`ProgramFormat::name`]'s list.
    pub const ALL: [ProgramFormat; 4] = [
        ProgramFormat::Csv,
        ProgramFormat::Urscript,
        ProgramFormat::Krl,
        ProgramFormat::Rapid,
    ];

    /// `csv`, `urscript`, `krl` or `rapid`, as on the command line.
    pub fn name(self) -> &'static str {
        match self {
            ProgramFormat::Csv => "csv",
            ProgramFormat::Urscript => "urscript",
            ProgramFormat::Krl => "krl",
            ProgramFormat::Rapid => "rapid",
        }
    }

    /// The format called `name` ([`ProgramFormat::name`]).
    pub fn from_name(name: &str) -> Result<ProgramFormat> {
        Self::ALL
            .into_iter()
            .find(|f| f.name() == name)
            .ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "program format '{name}': expected one of {}",
                    Self::ALL.map(|f| f.name()).join(", ")
                ))
            })
    }

    /// The usual file extension: `csv`, `script`, `src` or `mod`.
    pub fn extension(self) -> &'static str {
        match self {
            ProgramFormat::Csv => "csv",
            ProgramFormat::Urscript => "script",
            ProgramFormat::Krl => "src",
            ProgramFormat::Rapid => "mod",
        }
    }

    /// The format's name in messages: `CSV`, `URScript`, `KRL`, `RAPID`.
    fn title(self) -> &'static str {
        match self {
            ProgramFormat::Csv => "CSV",
            ProgramFormat::Urscript => "URScript",
            ProgramFormat::Krl => "KRL",
            ProgramFormat::Rapid => "RAPID",
        }
    }
}

/// The speeds `rapid_speed` may name: RAPID's predefined `speeddata`.
pub const RAPID_SPEEDS: [&str; 26] = [
    "v5", "v10", "v20", "v30", "v40", "v50", "v60", "v80", "v100", "v150", "v200", "v300", "v400",
    "v500", "v600", "v800", "v1000", "v1500", "v2000", "v2500", "v3000", "v4000", "v5000", "v6000",
    "v7000", "vmax",
];

/// The longest program name [`ProgramOptions::validate`] accepts (KRL's
/// limit; RAPID's is 32).
pub const MAX_NAME_LEN: usize = 24;

/// How a program is written; `Default` is a program called
/// `robokrige_plan`, all joints revolute, 2 s of settling at each measured
/// pose, and slow moves.
#[derive(Debug, Clone, PartialEq)]
pub struct ProgramOptions {
    /// The URScript function, KRL `DEF` or RAPID module name: a letter, then
    /// letters, digits or `_`, at most [`MAX_NAME_LEN`] characters. A KRL
    /// program's name must be its file's name ([`program_name`]).
    pub name: String,
    /// Which joints are prismatic (their values in mm), one flag per joint;
    /// empty means all revolute. URScript refuses a prismatic joint.
    pub prismatic: Vec<bool>,
    /// Time the program waits at each measured pose for the robot to settle
    /// and the tracker to measure, s (0: no wait).
    pub settle_s: f64,
    /// URScript `movej` joint acceleration `a`, rad/s².
    pub ur_acceleration: f64,
    /// URScript `movej` joint speed `v`, rad/s.
    pub ur_velocity: f64,
    /// KRL axis speed and acceleration (`$VEL_AXIS`, `$ACC_AXIS`), percent
    /// of each axis's maximum, in (0, 100].
    pub krl_percent: f64,
    /// RAPID speed data of every `MoveAbsJ`, one of [`RAPID_SPEEDS`].
    pub rapid_speed: String,
}

impl Default for ProgramOptions {
    fn default() -> Self {
        ProgramOptions {
            name: "robokrige_plan".into(),
            prismatic: Vec::new(),
            settle_s: 2.0,
            ur_acceleration: 0.5,
            ur_velocity: 0.25,
            krl_percent: 20.0,
            rapid_speed: "v100".into(),
        }
    }
}

impl ProgramOptions {
    /// The default options for a program in `format` written at `path`, of
    /// a robot whose joints are `prismatic`: named after the file
    /// ([`program_name`]), after checking that the format can program the
    /// robot ([`check_robot`]).
    pub fn for_file(path: &Path, format: ProgramFormat, prismatic: Vec<bool>) -> Result<Self> {
        check_robot(format, &prismatic)?;
        let opts = ProgramOptions {
            name: program_name(path, format)?,
            prismatic,
            ..ProgramOptions::default()
        };
        opts.validate()?;
        Ok(opts)
    }

    /// Error unless every option is in its range (see the fields).
    pub fn validate(&self) -> Result<()> {
        check_name(&self.name)?;
        let bad = |what: &str, v: f64, rule: &str| {
            Error::InvalidParameter(format!("program {what} {v}: {rule}"))
        };
        if !(self.settle_s.is_finite() && self.settle_s >= 0.0) {
            return Err(bad(
                "settle time",
                self.settle_s,
                "needs a finite time ≥ 0 s",
            ));
        }
        for (what, v) in [
            ("URScript acceleration", self.ur_acceleration),
            ("URScript speed", self.ur_velocity),
        ] {
            if !(v.is_finite() && v > 0.0) {
                return Err(bad(what, v, "needs a finite value > 0"));
            }
        }
        if !(self.krl_percent > 0.0 && self.krl_percent <= 100.0) {
            return Err(bad(
                "KRL axis speed",
                self.krl_percent,
                "needs a percentage in (0, 100]",
            ));
        }
        if !RAPID_SPEEDS.contains(&self.rapid_speed.as_str()) {
            return Err(Error::InvalidParameter(format!(
                "RAPID speed '{}': expected a predefined speeddata ({})",
                self.rapid_speed,
                RAPID_SPEEDS.join(", ")
            )));
        }
        Ok(())
    }
}

/// Error unless `name` can name a program in every format.
fn check_name(name: &str) -> Result<()> {
    let mut chars = name.chars();
    let first_ok = chars.next().is_some_and(|c| c.is_ascii_alphabetic());
    let rest_ok = chars.all(|c| c.is_ascii_alphanumeric() || c == '_');
    if first_ok && rest_ok && name.len() <= MAX_NAME_LEN {
        return Ok(());
    }
    Err(Error::InvalidParameter(format!(
        "program name '{name}': use a letter, then letters, digits or '_', at most {MAX_NAME_LEN} characters"
    )))
}

/// The program name for a file written at `path`: its stem when that is a
/// valid name ([`ProgramOptions::name`]), else `robokrige_plan`. A KRL
/// program must be called as its file, so for [`ProgramFormat::Krl`] an
/// invalid stem is an error naming the rule.
pub fn program_name(path: &Path, format: ProgramFormat) -> Result<String> {
    let stem = path.file_stem().and_then(|s| s.to_str()).unwrap_or("");
    match check_name(stem) {
        Ok(()) => Ok(stem.to_string()),
        Err(_) if format != ProgramFormat::Krl => Ok(ProgramOptions::default().name),
        Err(e) => Err(Error::Input {
            source_name: path.display().to_string(),
            message: format!(
                "a KRL program is called as its file: {}; rename the output",
                e.to_string().trim_start_matches("invalid parameter: ")
            ),
        }),
    }
}

/// The program text of `poses` in `format`, after checking the poses
/// (at least one, the same number of finite joint values each, labels of
/// printable ASCII), the options, and the format's own rules (module
/// docs).
///
/// ```
/// use robokrige::program::{ProgramFormat, ProgramOptions, ProgramPose, render};
/// let poses = vec![
///     ProgramPose::via(vec![0.0, -90.0, 90.0, 0.0, 45.0, 0.0]),
///     ProgramPose::measured(vec![10.0, -80.0, 85.0, 5.0, 40.0, -5.0]),
/// ];
/// let text = render(&poses, ProgramFormat::Krl, &ProgramOptions::default())?;
/// assert!(text.contains("PTP {A1 10.0, A2 -80.0, A3 85.0, A4 5.0, A5 40.0, A6 -5.0}"));
/// assert!(text.contains("WAIT SEC 2.0"));
/// # Ok::<(), robokrige::Error>(())
/// ```
pub fn render(
    poses: &[ProgramPose],
    format: ProgramFormat,
    opts: &ProgramOptions,
) -> Result<String> {
    opts.validate()?;
    check_poses(poses, format, opts)?;
    Ok(match format {
        ProgramFormat::Csv => joints_csv::render(poses),
        ProgramFormat::Urscript => urscript::render(poses, opts),
        ProgramFormat::Krl => krl::render(poses, opts),
        ProgramFormat::Rapid => rapid::render(poses, opts),
    })
}

/// [`render`] written atomically to `path` (nothing is written when the
/// poses or options are refused).
pub fn write(
    path: &Path,
    poses: &[ProgramPose],
    format: ProgramFormat,
    opts: &ProgramOptions,
) -> Result<()> {
    let text = render(poses, format, opts)?;
    crate::output::write_text(path, &text)
}

/// Error unless a robot whose joints are `prismatic` (one flag per joint)
/// can be programmed in `format` (module docs): a check before the work
/// that makes the poses.
pub fn check_robot(format: ProgramFormat, prismatic: &[bool]) -> Result<()> {
    check_format_rules(format, prismatic.len(), prismatic).map_err(|message| Error::Input {
        source_name: format!("{} program", format.title()),
        message,
    })
}

/// Error unless `poses` can be written in `format` (see [`render`]).
fn check_poses(poses: &[ProgramPose], format: ProgramFormat, opts: &ProgramOptions) -> Result<()> {
    let err = |message: String| Error::Input {
        source_name: format!("{} program", format.title()),
        message,
    };
    let Some(first) = poses.first() else {
        return Err(err(
            "no poses to write; a program needs at least one move".into()
        ));
    };
    let n = first.q.len();
    if n == 0 {
        return Err(err("pose 0 has no joint values".into()));
    }
    if !opts.prismatic.is_empty() && opts.prismatic.len() != n {
        return Err(err(format!(
            "{} prismatic-joint flags for poses of {n} joints",
            opts.prismatic.len()
        )));
    }
    for (i, p) in poses.iter().enumerate() {
        check_pose(i, p, n).map_err(&err)?;
    }
    check_format_rules(format, n, &opts.prismatic).map_err(err)
}

/// Error message unless pose `i` has `n` finite joint values and a
/// printable label.
fn check_pose(i: usize, p: &ProgramPose, n: usize) -> std::result::Result<(), String> {
    if p.q.len() != n {
        return Err(format!(
            "pose {i} (0-based) has {} joint values but pose 0 has {n}",
            p.q.len()
        ));
    }
    if let Some(j) = p.q.iter().position(|v| !v.is_finite()) {
        return Err(format!(
            "pose {i} (0-based), joint q{}: {} is not a finite joint value",
            j + 1,
            p.q[j]
        ));
    }
    if let Some(l) = &p.label
        && !l.chars().all(|c| c == ' ' || c.is_ascii_graphic())
    {
        return Err(format!(
            "pose {i} (0-based): label {l:?} must be printable ASCII (it goes into a comment line)"
        ));
    }
    Ok(())
}

/// Error message unless a robot of `n` joints (`prismatic` flags, empty =
/// all revolute) can be programmed in `format`.
fn check_format_rules(
    format: ProgramFormat,
    n: usize,
    prismatic: &[bool],
) -> std::result::Result<(), String> {
    let six = "write the moves as CSV (--format csv) and map the axes yourself";
    match format {
        ProgramFormat::Csv => Ok(()),
        ProgramFormat::Urscript if n != 6 => Err(format!(
            "movej takes the 6 joints of a UR arm, but the poses have {n}; {six}"
        )),
        ProgramFormat::Urscript => match prismatic.iter().position(|&p| p) {
            Some(j) => Err(format!(
                "joint q{} is prismatic (mm), but a UR arm's joints are all revolute (radians)",
                j + 1
            )),
            None => Ok(()),
        },
        ProgramFormat::Krl | ProgramFormat::Rapid if n != 6 => Err(format!(
            "written for six-axis robots only, but the poses have {n} joints (how other robots map onto the controller's axes depends on the model); {six}"
        )),
        ProgramFormat::Krl | ProgramFormat::Rapid => Ok(()),
    }
}

/// The comment of each move, in order: `measure k` (k counts the measured
/// poses from 0) or `via`, then ` (label)` when the pose has one.
fn marks(poses: &[ProgramPose]) -> Vec<String> {
    let mut measured = 0;
    poses
        .iter()
        .map(|p| {
            let mut m = if p.measure {
                measured += 1;
                format!("measure {}", measured - 1)
            } else {
                "via".to_string()
            };
            if let Some(l) = &p.label {
                m.push_str(&format!(" ({l})"));
            }
            m
        })
        .collect()
}

/// One summary line for a program's header comment.
fn summary(poses: &[ProgramPose], units: &str) -> String {
    let measured = poses.iter().filter(|p| p.measure).count();
    format!(
        "written by robokrige: {} moves ({measured} measured, {} via); joints in {units}",
        poses.len(),
        poses.len() - measured
    )
}

/// The units of KRL and RAPID joint values: `deg`, or `deg (mm for q3)`
/// with prismatic joints.
fn deg_units(opts: &ProgramOptions) -> String {
    let linear: Vec<String> = (opts.prismatic.iter().enumerate())
        .filter(|(_, p)| **p)
        .map(|(j, _)| format!("q{}", j + 1))
        .collect();
    if linear.is_empty() {
        "deg".into()
    } else {
        format!("deg (mm for {})", linear.join(", "))
    }
}

/// `v` with `decimals` decimals, trailing zeros dropped but one kept
/// (`90.0`, `-1.5707963268`); never `-0.0`.
fn fixed(v: f64, decimals: usize) -> String {
    let s = format!("{v:.decimals$}");
    let s = s.trim_end_matches('0');
    let s = if s.ends_with('.') {
        format!("{s}0")
    } else {
        s.to_string()
    };
    if s.strip_prefix('-')
        .is_some_and(|r| r.chars().all(|c| c == '0' || c == '.'))
    {
        s[1..].to_string()
    } else {
        s
    }
}

/// Decimals of a joint value in degrees or mm (KRL, RAPID).
const DEG_DECIMALS: usize = 10;
/// Decimals of a joint value in radians (URScript).
const RAD_DECIMALS: usize = 12;
