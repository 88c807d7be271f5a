//! `robokrige physics identify | compare`.

use super::progress::bar;
use super::read_data;
use clap::{Args, Subcommand};
use robokrige::kinematics;
use robokrige::methods::Method;
use robokrige::physics::{
    CompareOptions, Comparison, Geometry, PhysicsIdentification, compare, identify_physics,
    is_scara,
};
use robokrige::sim::Truth;
use robokrige::{Error, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Physics-based models of seeds 000 and 002 (lookup tables of angular
/// positioning deviation per direction), and their comparison with Kriging.
#[derive(Debug, Args)]
pub struct PhysicsArgs {
    #[command(subcommand)]
    command: PhysicsCommand,
}

#[derive(Debug, Subcommand)]
enum PhysicsCommand {
    /// Identify a physics model from indexing tests (and, for a six-axis
    /// robot, a measurement campaign for the D-H errors).
    Identify(IdentifyArgs),
    /// Simulate a robot and compare nominal, D-H, D-H + APD, Kriging JS/EJS
    /// and the hybrid on prediction and compensation.
    Compare(CompareArgs),
    /// Seed 000 §5.2: J1's deviation at several J2 angles against an
    /// identified SCARA model (cross-talk).
    Crosstalk(CrosstalkArgs),
    /// Seed 004 eqs 29–35: move a campaign measured in the tracker's frame
    /// into the robot's base frame (SVD registration onto the nominal TCP
    /// positions) and recompute ex, ey, ez.
    Register(RegisterArgs),
    /// Seed 002's probing example: a straightedge probed at three locations,
    /// straightness with the nominal, D-H and D-H + APD models (Table 2).
    Probing(ProbingArgs),
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige simulate --robot scara-rh3frh5515 --kind crosstalk --seed 1 -o xt.csv
  robokrige physics identify datasets/scara_indexing.csv -o scara_physics.json
  robokrige physics crosstalk xt.csv --model scara_physics.json")]
pub struct CrosstalkArgs {
    /// Cross-talk test CSV (J1 indexed with J2 held at several angles; `axis` = 1).
    data: PathBuf,
    /// Physics model identified from the indexing tests of the same set-up.
    #[arg(long)]
    model: PathBuf,
    /// Write the cross-talk tables and the fit as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
The tracker frame is found by SVD registration of the measured points onto
the nominal robot's (seed 004 eqs 29–35); the errors are then recomputed in
the base frame.

Example:
  robokrige simulate --robot comau-nj220 --poses 200 --seed 1 -o c.csv
  robokrige physics register c.csv --robot comau-nj220 -o c_base.csv")]
pub struct RegisterArgs {
    /// Campaign with q.. and the measured x,y,z in the tracker's frame.
    data: PathBuf,
    /// The robot (preset or robot file) whose nominal kinematics give the base frame.
    #[arg(long)]
    robot: String,
    /// Output CSV: the same rows, x,y,z in the base frame, ex,ey,ez recomputed.
    #[arg(short, long)]
    output: PathBuf,
    /// Write the registration (transform, residuals) as JSON to FILE ("-":
    /// standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige physics probing --robot kuka-kr30ha --seed 1 --json probing.json")]
pub struct ProbingArgs {
    /// Six-axis robot preset of the simulated set-up.
    #[arg(long, default_value = "kuka-kr30ha")]
    robot: String,
    /// Seed of the simulated robot and its noise.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Switch the tracker and repeatability noise off (the systematic part alone).
    #[arg(long)]
    noise_free: bool,
    /// Write the straightness table as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
A SCARA (seed 000) is identified from its J1 and J2 indexing tests alone:
reference frame from the J1 plane and circle, link errors ΔL1, ΔL2, the J2
offset θ20, bidirectional APD and radial-error-motion tables, parallelism of
J2 to J1. A six-axis robot (seed 002) gets its APD tables from the indexing
tests (circle-point analysis of every axis whose TCP circle is ≥ 50 mm) and its
MD-H, tool and base errors by Levenberg–Marquardt on --train.

Example:
  robokrige physics identify datasets/scara_indexing.csv --robot scara-rh3frh5515 \\
      -o scara_physics.json --truth datasets/scara_indexing.truth.json")]
pub struct IdentifyArgs {
    /// Indexing-test CSV (columns q.., dir.., x,y,z and `axis`).
    indexing: PathBuf,
    /// Robot: preset name or robot file.
    #[arg(long, default_value = DEFAULT_ROBOT)]
    robot: String,
    /// Measurement campaign with ex,ey,ez for the Levenberg–Marquardt D-H
    /// calibration (needed for a six-axis robot, unused for a SCARA).
    #[arg(long)]
    train: Option<PathBuf>,
    /// Output model (D-H + tables), usable with `compensate --model`.
    #[arg(short, long)]
    output: PathBuf,
    /// Also write the D-H-only model here.
    #[arg(long)]
    dh_output: Option<PathBuf>,
    /// Simulator truth of the indexing campaign: print identified vs true.
    #[arg(long)]
    truth: Option<PathBuf>,
    /// Write the identification report as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
}

#[derive(Debug, Args)]
#[command(after_help = "\
Everything is simulated from --seed: the true robot, its indexing tests, a
Latin-hypercube training campaign for Kriging, a Ø--path-mm circle path run
forward and back, and --verify-poses random poses. Every model predicts the
path's and the poses' errors (score: measured − predicted) and compensates
them (iterative feed-forward; score: measured − target on the true robot).

Example:
  robokrige physics compare --robot scara-rh3frh5515 --seed 1 --report compare.md")]
pub struct CompareArgs {
    /// Robot (preset name or robot file) of the simulated set-up (SCARA: seed 000; six-axis: seed 002).
    #[arg(long, default_value = "scara-rh3frh5515")]
    robot: String,
    /// Seed of everything simulated.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Poses of the Latin-hypercube campaign the Kriging models train on.
    #[arg(long, default_value_t = 300)]
    train_poses: usize,
    /// Points of the circle path.
    #[arg(long, default_value_t = 72)]
    path_points: usize,
    /// Diameter of the circle path, mm.
    #[arg(long, default_value_t = 100.0)]
    path_mm: f64,
    /// Random verification poses.
    #[arg(long, default_value_t = 50)]
    verify_poses: usize,
    /// Kriging method of the JS row.
    #[arg(long, default_value = "js-hj")]
    js: String,
    /// Kriging method of the EJS row and of the hybrid's residual model.
    #[arg(long, default_value = "ejs-gps")]
    ejs: String,
    /// Estimate a nugget in the papers' Kriging methods too (default: they
    /// interpolate; `recommended` always estimates one).
    #[arg(long)]
    nugget: bool,
    /// Write the comparison table as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Markdown report.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Write path plots here (seed 000 Figs 9–11): the measured path and
    /// each model's prediction, errors magnified ×1000 in XY.
    #[arg(long)]
    plots: Option<PathBuf>,
}

pub fn run(a: PhysicsArgs) -> Result<()> {
    match a.command {
        PhysicsCommand::Identify(a) => run_identify(a),
        PhysicsCommand::Compare(a) => run_compare(a),
        PhysicsCommand::Probing(a) => run_probing(a),
        PhysicsCommand::Crosstalk(a) => run_crosstalk(a),
        PhysicsCommand::Register(a) => run_register(a),
    }
}

fn write(path: &Path, text: &str) -> Result<()> {
    robokrige::output::write_text(path, text)
}

fn run_identify(a: IdentifyArgs) -> Result<()> {
    let inputs: Vec<&Path> = std::iter::once(&a.indexing)
        .chain(&a.train)
        .chain(&a.truth)
        .map(PathBuf::as_path)
        .collect();
    let outputs: Vec<&Path> = std::iter::once(&a.output)
        .chain(&a.dh_output)
        .chain(&a.json)
        .map(PathBuf::as_path)
        .collect();
    robokrige::output::check_outputs(&inputs, &outputs)?;
    let robot = kinematics::load_robot(&a.robot)?;
    // repeated poses are the design of an indexing test: no warning for them
    let indexing = robokrige::dataset::read_csv(&a.indexing)?;
    let train = match &a.train {
        Some(_) if is_scara(&robot) => {
            return Err(Error::InvalidParameter(format!(
                "--train is for six-axis robots; '{}' is a SCARA, identified from its indexing tests alone",
                robot.name
            )));
        }
        Some(p) => read_data(p)?,
        None if is_scara(&robot) => indexing.clone(),
        None => {
            return Err(Error::InvalidParameter(format!(
                "'{}' is not a SCARA: its D-H errors are identified by Levenberg–Marquardt on a campaign; give --train CAMPAIGN.csv",
                robot.name
            )));
        }
    };
    for d in [&indexing, &train] {
        robot
            .check_dataset(d)
            .map_err(|e| default_robot_hint(e, &a.robot))?;
    }
    let id = identify_physics(&indexing, &train, &robot)?;
    id.full.save(&a.output)?;
    if let Some(p) = &a.dh_output {
        id.dh.save(p)?;
    }
    say_part!("{}", identify_text(&id));
    if let Some(tp) = &a.truth {
        let truth = robokrige::study::load_truth(tp)?;
        say_part!("{}", truth_text(&id, &truth));
    }
    say!("model: {}", a.output.display());
    if let Some(p) = &a.json {
        super::write_json(p, &id, "identification report")?;
    }
    Ok(())
}

/// The SCARA is the default robot of `physics identify`: say so when a
/// six-axis campaign meets it.
fn default_robot_hint(e: Error, robot: &str) -> Error {
    match e {
        Error::Input {
            source_name,
            message,
        } if robot == DEFAULT_ROBOT => Error::Input {
            source_name,
            message: format!("{message} (the default robot is {DEFAULT_ROBOT})"),
        },
        e => e,
    }
}

/// `physics identify`'s robot when `--robot` is not given.
const DEFAULT_ROBOT: &str = "scara-rh3frh5515";

fn identify_text(id: &PhysicsIdentification) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "{}", id.method);
    let _ = writeln!(
        s,
        "axis  rows angles cycles  radius(mm)  circle rms  plane rms  repeat spread(°)  backlash ½(°)"
    );
    for ax in &id.axes {
        let _ = writeln!(
            s,
            "J{:<4} {:>4} {:>6} {:>6} {:>11.4} {:>11.4} {:>10.4} {:>17.5} {:>14.5}",
            ax.axis,
            ax.rows,
            ax.angles,
            ax.cycles,
            ax.radius_mm,
            ax.circle_rms_mm,
            ax.plane_rms_mm,
            ax.repeat_spread_deg,
            ax.backlash_half_deg
        );
    }
    if let Geometry::Scara(g) = &id.full.geometry {
        let _ = writeln!(
            s,
            "ΔL1 = {:+.4} mm, ΔL2 = {:+.4} mm, θ20 = {:+.5}° (eqs 12–14); parallelism J2→J1: a = {:+.2e}, b = {:+.2e}, z1 = {:+.4} mm (eq 22)",
            g.dl1_mm, g.dl2_mm, g.theta20_deg, g.parallel_a, g.parallel_b, g.z1_mm
        );
    }
    for lm in &id.lm {
        let _ = writeln!(
            s,
            "Levenberg–Marquardt: {} parameters ({} frozen as unidentifiable), rms {:.4} → {:.4} mm in {} steps ({})",
            lm.parameters,
            lm.frozen.len(),
            lm.rms_before_mm,
            lm.rms_after_mm,
            lm.iterations,
            lm.stop
        );
    }
    for n in &id.notes {
        let _ = writeln!(s, "note: {n}");
    }
    s
}

fn truth_text(id: &PhysicsIdentification, truth: &Truth) -> String {
    let mut s = String::new();
    let (Geometry::Scara(g), Some(check)) =
        (&id.full.geometry, id.full.check_against(&truth.robot))
    else {
        let _ = writeln!(
            s,
            "(--truth: parameter comparison is printed for a SCARA only)"
        );
        return s;
    };
    let t = &check.truth;
    let _ = writeln!(s, "identified vs simulator truth:");
    let _ = writeln!(
        s,
        "  ΔL1 {:+.4} vs {:+.4} mm, ΔL2 {:+.4} vs {:+.4} mm, θ20 {:+.5} vs {:+.5}°",
        g.dl1_mm, t.dl1_mm, g.dl2_mm, t.dl2_mm, g.theta20_deg, t.theta20_deg
    );
    for a in &check.apd {
        let _ = writeln!(
            s,
            "  J{} APD table: error rms {:.5}°, max {:.5}° over {} entries",
            a.joint, a.rms_deg, a.max_deg, a.entries
        );
    }
    s
}

fn run_compare(a: CompareArgs) -> Result<()> {
    let outputs: Vec<&Path> = a
        .json
        .iter()
        .chain(&a.report)
        .map(PathBuf::as_path)
        .collect();
    robokrige::output::check_outputs(&[], &outputs)?;
    let opts = CompareOptions {
        robot: a.robot.clone(),
        seed: a.seed,
        train_poses: a.train_poses,
        path_points: a.path_points,
        path_mm: a.path_mm,
        verify_poses: a.verify_poses,
        js: Method::from_name(&a.js)?,
        ejs: Method::from_name(&a.ejs)?,
        nugget: a.nugget,
    };
    if a.nugget && opts.js == Method::Recommended && opts.ejs == Method::Recommended {
        return Err(Error::InvalidParameter(
            "--nugget changes the papers' methods only; --js and --ejs are both `recommended`, which always estimates one".into(),
        ));
    }
    let pb = bar(1, "compare");
    let t0 = std::time::Instant::now();
    let res = compare(&opts, &|k, total, what| {
        pb.set_length(total as u64);
        pb.set_position(k as u64);
        pb.set_message(what.to_string());
    });
    pb.finish_and_clear();
    let res = res?;
    let text = compare_text(&res, t0.elapsed().as_secs_f64());
    say_part!("{text}");
    if let Some(p) = &a.report {
        write(p, &text)?;
    }
    if let Some(p) = &a.json {
        super::write_json(p, &res, "comparison")?;
    }
    if let Some(dir) = &a.plots {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        for f in robokrige::plot::path_plots(&res, dir)? {
            say!("plot: {}", f.display());
        }
    }
    Ok(())
}

/// The comparison as Markdown.
pub fn compare_text(c: &Comparison, secs: f64) -> String {
    let o = &c.options;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Physics vs Kriging: {} (true robot of seed {})\n",
        o.robot, o.seed
    );
    let _ = writeln!(
        s,
        "Physics model: {}. Data: {} indexing rows, {} training poses, a Ø{} mm circle path of {} points (forward and back), {} random poses. {secs:.0} s.\n",
        c.physics, c.sizes[0], c.sizes[1], o.path_mm, c.sizes[2], c.sizes[3]
    );
    let _ = writeln!(
        s,
        "Prediction: |measured − predicted error|; compensation: |measured − target| after iterative feed-forward, on the simulated robot. Mean / max, mm; 3D and XY (seed 000's model is 2D).\n"
    );
    let _ = writeln!(
        s,
        "| model | predict path 3D | predict path XY | predict poses 3D | compensate path 3D | compensate path XY | compensate poses 3D | compensate poses XY |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|---|---|");
    let f = |x: &robokrige::physics::Score, xy: bool| {
        if xy {
            format!("{:.4} / {:.4}", x.mean_xy_mm, x.max_xy_mm)
        } else {
            format!("{:.4} / {:.4}", x.mean_3d_mm, x.max_3d_mm)
        }
    };
    for r in &c.rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} |",
            r.model,
            f(&r.predict_path, false),
            f(&r.predict_path, true),
            f(&r.predict_poses, false),
            f(&r.compensate_path, false),
            f(&r.compensate_path, true),
            f(&r.compensate_poses, false),
            f(&r.compensate_poses, true),
        );
    }
    let (np, nq) = (&c.noise_path, &c.noise_poses);
    let _ = writeln!(
        s,
        "| *noise alone (simulator truth)* | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} | {:.4} |",
        np.mean_3d_mm,
        np.mean_xy_mm,
        nq.mean_3d_mm,
        np.mean_3d_mm,
        np.mean_xy_mm,
        nq.mean_3d_mm,
        nq.mean_xy_mm
    );
    let _ = writeln!(s);
    for n in &c.notes {
        let _ = writeln!(s, "- {n}");
    }
    s
}

fn run_probing(a: ProbingArgs) -> Result<()> {
    let outputs: Vec<&Path> = a.json.iter().map(PathBuf::as_path).collect();
    robokrige::output::check_outputs(&[], &outputs)?;
    let (rows, how) = robokrige::physics::probing_example(&a.robot, a.seed, !a.noise_free)?;
    say!(
        "# Probing a 1000 mm straightedge, 100 points: {} (true robot of seed {}{})\n",
        a.robot,
        a.seed,
        if a.noise_free { ", noise off" } else { "" }
    );
    say!("Physics model: {how}.\n");
    say!(
        "| location / face | nominal: straightness / std (mm) | D-H only | D-H + APD | reduction (straightness), D-H + APD vs nominal |"
    );
    say!("|---|---|---|---|---|");
    for r in &rows {
        let f = |s: &robokrige::physics::Straightness| {
            format!("{:.4} / {:.4}", s.straightness_mm, s.std_mm)
        };
        say!(
            "| {} | {} | {} | {} | {:.0} % |",
            r.edge,
            f(&r.nominal),
            f(&r.dh),
            f(&r.full),
            r.reduction_pct()
        );
    }
    if let Some(p) = &a.json {
        super::write_json(p, &rows, "probing table")?;
    }
    Ok(())
}

fn run_crosstalk(a: CrosstalkArgs) -> Result<()> {
    let outputs: Vec<&Path> = a.json.iter().map(PathBuf::as_path).collect();
    robokrige::output::check_outputs(&[&a.data, &a.model], &outputs)?;
    let model = robokrige::physics::PhysicsModel::load(&a.model)?;
    let data = robokrige::dataset::read_csv(&a.data)?;
    let r = robokrige::physics::identify_crosstalk(&data, &model)?;
    say!("J1 deviation the model misses, by J2 angle (seed 000 §5.2), degrees:");
    say!("  J2      rows   mean shift   peak-to-peak");
    for g in &r.groups {
        say!(
            "  {:>6.1} {:>6} {:>+12.5} {:>14.5}",
            g.j2_deg,
            g.rows,
            g.mean_deg,
            g.peak_to_peak_deg
        );
    }
    say!(
        "largest shift vs J2 = {:.1}°: {:.5}° (standard error {:.5}°, one entry {:.5}°): {}",
        r.groups[0].j2_deg,
        r.max_shift_deg,
        r.shift_se_deg,
        r.entry_se_deg,
        if r.significant {
            "cross-talk: J1 depends on J2 (> 4 standard errors)"
        } else {
            "no significant cross-talk"
        }
    );
    if let Some(p) = &a.json {
        super::write_json(p, &r, "cross-talk report")?;
    }
    Ok(())
}

fn run_register(a: RegisterArgs) -> Result<()> {
    let mut outputs = vec![a.output.as_path()];
    outputs.extend(a.json.as_deref());
    robokrige::output::check_outputs(&[&a.data], &outputs)?;
    let robot = kinematics::load_robot(&a.robot)?;
    let data = read_data(&a.data)?;
    robot.check_dataset(&data)?;
    let (out, reg) = robokrige::physics::register_campaign(&data, &robot)?;
    robokrige::dataset::write_csv(&a.output, &out)?;
    let t = reg.transform.translation.vector;
    let (axis, angle) = reg
        .transform
        .rotation
        .axis_angle()
        .map_or(([0.0, 0.0, 1.0], 0.0), |(ax, an)| ([ax.x, ax.y, ax.z], an));
    say!(
        "base ← tracker: translation ({:.3}, {:.3}, {:.3}) mm, rotation {:.5}° about ({:.4}, {:.4}, {:.4}){}",
        t.x,
        t.y,
        t.z,
        angle.to_degrees(),
        axis[0],
        axis[1],
        axis[2],
        if reg.reflection_guarded {
            " (reflection guarded)"
        } else {
            ""
        }
    );
    say!(
        "residual |registered − nominal| over {} rows: rms {:.4} mm, max {:.4} mm -> {}",
        out.len(),
        reg.rms,
        reg.max,
        a.output.display()
    );
    if let Some(p) = &a.json {
        let v = serde_json::json!({
            "data": a.data, "output": a.output, "robot": robot.name, "rows": out.len(),
            "base_from_tracker": reg.transform, "rotation_axis": axis,
            "rotation_deg": angle.to_degrees(), "reflection_guarded": reg.reflection_guarded,
            "rms_mm": reg.rms, "max_mm": reg.max,
        });
        super::write_json(p, &v, "registration")?;
    }
    Ok(())
}
