//! `physics`: the identification, the comparison with Kriging, the probing
//! example, the cross-talk test and the registration, as text.

use crate::frames::Registration;
use crate::physics::{
    Comparison, CrosstalkReport, Geometry, PhysicsIdentification, ProbingRow, Score, Straightness,
};
use crate::sim::Truth;
use std::fmt::Write as _;
use std::path::Path;

/// What `physics identify` prints: per axis what the indexing tests saw,
/// the SCARA geometry, the Levenberg–Marquardt fits and the notes.
pub fn identification(id: &PhysicsIdentification) -> String {
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

/// A SCARA identification against the simulator's truth: link errors, θ20
/// and the error of every APD table.
pub fn against_truth(id: &PhysicsIdentification, truth: &Truth) -> String {
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

/// The comparison as Markdown (`physics compare`); `secs` is its wall time.
pub fn comparison(c: &Comparison, secs: f64) -> String {
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
    let f = |x: &Score, xy: bool| {
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

/// The probing example's straightness table (seed 002 Table 2): `robot`
/// and `seed` of the set-up, `how` the physics model was identified.
pub fn probing(rows: &[ProbingRow], how: &str, (robot, seed, noise): (&str, u64, bool)) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "# Probing a 1000 mm straightedge, 100 points: {robot} (true robot of seed {seed}{})\n",
        if noise { "" } else { ", noise off" }
    );
    let _ = writeln!(s, "Physics model: {how}.\n");
    let _ = writeln!(
        s,
        "| location / face | nominal: straightness / std (mm) | D-H only | D-H + APD | reduction (straightness), D-H + APD vs nominal |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    let f = |s: &Straightness| format!("{:.4} / {:.4}", s.straightness_mm, s.std_mm);
    for r in rows {
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {:.0} % |",
            r.edge,
            f(&r.nominal),
            f(&r.dh),
            f(&r.full),
            r.reduction_pct()
        );
    }
    s
}

/// The cross-talk test (seed 000 §5.2): J1's deviation by J2 angle, and
/// whether the largest shift is significant.
pub fn crosstalk(r: &CrosstalkReport) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "J1 deviation the model misses, by J2 angle (seed 000 §5.2), degrees:"
    );
    let _ = writeln!(s, "  J2      rows   mean shift   peak-to-peak");
    for g in &r.groups {
        let _ = writeln!(
            s,
            "  {:>6.1} {:>6} {:>+12.5} {:>14.5}",
            g.j2_deg, g.rows, g.mean_deg, g.peak_to_peak_deg
        );
    }
    let _ = writeln!(
        s,
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
    s
}

/// The rotation of a registration as (unit axis, angle in radians); the Z
/// axis and 0 for the identity.
pub fn axis_angle(reg: &Registration) -> ([f64; 3], f64) {
    reg.transform
        .rotation
        .axis_angle()
        .map_or(([0.0, 0.0, 1.0], 0.0), |(ax, an)| ([ax.x, ax.y, ax.z], an))
}

/// The JSON of `physics register --json`: the files (`data`, `output`),
/// the robot, the rows, the transform (also as axis and angle), the
/// residual.
pub fn registration_json(
    (data, output): (&Path, &Path),
    robot: &str,
    rows: usize,
    reg: &Registration,
) -> serde_json::Value {
    let (axis, angle) = axis_angle(reg);
    serde_json::json!({
        "data": data, "output": output, "robot": robot, "rows": rows,
        "base_from_tracker": reg.transform, "rotation_axis": axis,
        "rotation_deg": angle.to_degrees(), "reflection_guarded": reg.reflection_guarded,
        "rms_mm": reg.rms, "max_mm": reg.max,
    })
}

/// The registration of a campaign into the base frame (`physics
/// register`): the transform, and the residual over its `rows` rows
/// written to `output`.
pub fn registration(reg: &Registration, rows: usize, output: &Path) -> String {
    let (t, output) = (reg.transform.translation.vector, output.display());
    let (axis, angle) = axis_angle(reg);
    format!(
        "base ← tracker: translation ({:.3}, {:.3}, {:.3}) mm, rotation {:.5}° about ({:.4}, {:.4}, {:.4}){}\n\
         residual |registered − nominal| over {rows} rows: rms {:.4} mm, max {:.4} mm -> {output}\n",
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
        },
        reg.rms,
        reg.max
    )
}
