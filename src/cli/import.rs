//! `import`: a tracker or controller export → a measurement CSV.

use clap::Args;
use robokrige::Result;
use robokrige::dataset::import::{AngleUnit, ImportSpec, LengthUnit};
use robokrige::dataset::write_csv;
use robokrige::kinematics::{self, import_for, locate_imported};
use robokrige::report::import as report;
use std::path::PathBuf;

#[derive(Debug, Args)]
#[command(after_help = "\
Maps the export's columns onto the measurement format: q1..qN (required),
dir1..dirN (else derived from the row order), ex,ey,ez (errors) or x,y,z
(measured TCP positions), id, and any other name as a covariate. Export
columns no target names are listed, not silently dropped.

With measured positions and --robot, the tracker-to-base frame and the TCP
offset are identified by least squares over all rows and the errors
ex,ey,ez = measured − nominal (base frame) are written instead of x,y,z.

Example (the original UR10 export of the IPA data set):
  robokrige import measurements_random_poses.csv --angles rad --robot ur10 \\
      --map q1=shoulder_pan_joint,q2=shoulder_lift_joint,q3=elbow_joint \\
      --map q4=wrist_1_joint,q5=wrist_2_joint,q6=wrist_3_joint \\
      --map x=measurement_x,y=measurement_y,z=measurement_z \\
      --map temp_c=measurement_temperature -o series_c.csv
The same as a mapping file (--map-file ur10_map.toml):
  angles = \"rad\"
  [columns]
  q1 = \"shoulder_pan_joint\"   # … q6, x, y, z likewise
  temp_c = \"measurement_temperature\"")]
pub struct ImportArgs {
    /// The export (CSV-like text).
    export: PathBuf,
    /// Output measurement CSV.
    #[arg(short, long)]
    output: PathBuf,
    /// Column map target=column, comma-separated; repeat as needed. Overrides
    /// the same targets in --map-file.
    #[arg(long, value_name = "PAIRS")]
    map: Vec<String>,
    /// Mapping file (TOML): delimiter, decimal, angles, lengths, [columns].
    #[arg(long, value_name = "FILE")]
    map_file: Option<PathBuf>,
    /// Field separator [default: the mapping file's, else sniffed from the header].
    #[arg(long)]
    delimiter: Option<char>,
    /// Decimal separator, . or , [default: "," when the delimiter is not a comma and cells use it].
    #[arg(long)]
    decimal: Option<char>,
    /// Unit of revolute joint values [default: the mapping file's, else deg].
    #[arg(long, value_enum)]
    angles: Option<AngleUnit>,
    /// Unit of lengths: positions, errors, prismatic joints [default: the mapping file's, else mm].
    #[arg(long, value_enum)]
    lengths: Option<LengthUnit>,
    /// The measured robot (preset or robot file): gives prismatic joints their
    /// unit and, with x,y,z, turns positions into errors.
    #[arg(long)]
    robot: Option<String>,
    /// Write the import report (mapping, units, identified frame and tool) as
    /// JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

pub fn run(a: ImportArgs) -> Result<()> {
    let inputs = [Some(a.export.as_path()), a.map_file.as_deref()];
    super::check_files(&inputs, &[Some(a.output.as_path()), a.json.as_deref()])?;
    let spec = ImportSpec::read(a.map_file.as_deref(), &a.map)?;
    let spec = spec.overridden(a.delimiter, a.decimal, a.angles, a.lengths);
    let robot = a.robot.as_deref().map(kinematics::load_robot).transpose()?;
    let mut imported = import_for(&a.export, &spec, robot.as_ref())?;
    say_part!("{}", report::read(&imported, &spec, &a.export));
    let located = locate_imported(robot.as_ref(), &mut imported.data)?;
    if let Some(fit) = &located {
        super::warn(fit.warnings(&imported.data));
    }
    let name = robot.as_ref().map(|r| r.name.as_str());
    say_part!("{}", report::located(name, &imported, located.as_ref()));
    write_csv(&a.output, &imported.data)?;
    say!("wrote {}", a.output.display());
    let v = report::json(
        (&a.export, &a.output),
        &imported,
        &spec,
        (name, located.as_ref()),
    );
    super::json_to(a.json.as_deref(), &v, "import report")
}
