//! `demo`: the summary it prints and `report.md`.

use super::xyz;
use crate::demo::Demo;
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The demo's figures (SVG files).
#[derive(Debug, Clone, PartialEq)]
pub struct Figures {
    /// Box plots of the methods' out-of-fold 3D errors.
    pub cv: PathBuf,
    /// The 3D error along the circle, nominal and compensated.
    pub circle: PathBuf,
    /// Residual against each added effect's traced variable.
    pub effects: Vec<PathBuf>,
}

/// What `demo` prints: the methods' CV, the compensation, the diagnosis;
/// `secs` is the wall time.
pub fn summary(demo: &Demo, secs: f64) -> String {
    let diag = &demo.diagnosis;
    let mut s = String::new();
    let _ = writeln!(
        s,
        "robokrige demo: COMAU SMART5 NJ 220 (simulated), {} laser-tracker poses, {secs:.0} s\n",
        demo.options.poses
    );
    let _ = writeln!(
        s,
        "{}-fold CV, out-of-fold 3D error (mm):",
        demo.options.folds
    );
    let _ = writeln!(
        s,
        "  {:<11} {:<12} {:>8} {:>8} {:>8}",
        "method", "CV mode", "mean", "std", "max"
    );
    for r in &demo.methods {
        let m = &r.cv.summary;
        let _ = writeln!(
            s,
            "  {:<11} {:<12} {:>8.4} {:>8.4} {:>8.4}",
            r.method.name(),
            r.cv.mode,
            m.mean_3d_mm,
            m.std_3d_mm,
            m.max_3d_mm
        );
    }
    let _ = writeln!(
        s,
        "\nIterative feed-forward compensation, measured on the simulated robot (mean / max 3D error, mm):"
    );
    for c in &demo.compensation {
        let (rm, rx) = c.reduction_pct();
        let _ = writeln!(
            s,
            "  {:<19} {:<4} nominal {:.3} / {:.3}  ->  {:.3} / {:.3}  ({rm:.0} % / {rx:.0} % lower, {} iterations)",
            c.target,
            c.model,
            c.nominal.mean_abs_mm,
            c.nominal.max_abs_mm,
            c.after.mean_abs_mm,
            c.after.max_abs_mm,
            c.iterations
        );
    }
    let _ = writeln!(
        s,
        "\nDiagnosis of comau_tracker_step.csv (CV RMSE x / y / z, mm):"
    );
    let _ = writeln!(s, "  before: {}", xyz(&diag.before.cv_rmse_mm));
    for e in diag.effects.iter().filter(|e| e.accepted) {
        let _ = writeln!(
            s,
            "  found:  {} (p {:.4}, score {:.3}) -> added",
            e.describe(),
            e.p_value,
            e.score
        );
    }
    if diag.steps.is_empty() {
        let _ = writeln!(s, "  found:  nothing significant");
    }
    let _ = writeln!(s, "  after:  {}", xyz(&diag.after.cv_rmse_mm));
    s
}

/// `report.md`, its figures linked relative to the output folder `out`;
/// `secs` is the wall time.
pub fn markdown(demo: &Demo, figures: &Figures, secs: f64, out: &Path) -> String {
    let rel = |p: &Path| p.strip_prefix(out).unwrap_or(p).display().to_string();
    let mut s = String::new();
    let _ = writeln!(s, "# robokrige demo report\n");
    let _ = writeln!(
        s,
        "Simulated COMAU SMART5 NJ 220-2.7 (true robot of seed 1: MD-H errors, backlash, gear harmonics, \
         compliance, tracker noise), {} Latin-hypercube poses in the joint ranges of seed 004 Table 2. \
         Data in `data/`, models in `models/`. Wall time {secs:.0} s.\n",
        demo.options.poses
    );
    methods_section(&mut s, demo, &rel(&figures.cv));
    compensation_section(&mut s, demo, &rel(&figures.circle));
    diagnosis_section(&mut s, demo);
    for p in &figures.effects {
        let _ = writeln!(s, "\n![residual vs effect]({})", rel(p));
    }
    let _ = writeln!(
        s,
        "\n## Limits\n\nA Kriging model only knows the poses and states it was trained on: far from the \
         training ranges it returns to its trend; effects of state it was not given (temperature, payload) \
         are averaged in unless `diagnose` finds and adds them; at a joint reversal the backlash correction \
         can flip λ itself, so feed-forward compensation leaves part of the backlash there."
    );
    s
}

/// Section 1: the methods' K-fold CV, and the box plots `cv_plot`.
fn methods_section(s: &mut String, demo: &Demo, cv_plot: &str) {
    let _ = writeln!(
        s,
        "## 1. Which model? {}-fold cross-validation\n",
        demo.options.folds
    );
    let _ = writeln!(
        s,
        "| method | CV mode | range (mm) | mean | std | RMSE x / y / z (mm) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for r in &demo.methods {
        let m = &r.cv.summary;
        let _ = writeln!(
            s,
            "| `{}` | {} | [{:.4}, {:.4}] | {:.4} | {:.4} | {} |",
            r.method.name(),
            r.cv.mode,
            m.min_3d_mm,
            m.max_3d_mm,
            m.mean_3d_mm,
            m.std_3d_mm,
            xyz(&m.rms_mm)
        );
    }
    let _ = writeln!(
        s,
        "\n*refit*: hyperparameters (and basis selection) redone on every training fold — honest. \
         *closed-form*: one fit on all rows, fold residuals from the bordered system at fixed ξ — fast, \
         and optimistic because ξ and the selected basis saw the held-out rows (`robokrige cv --methods all` \
         gives the refit numbers for every method). JS ignores the direction each joint moved; EJS adds λ = ±1 \
         per joint and captures backlash. *recommended* is what `robokrige fit` does by default: EJS with an \
         estimated nugget (tracker noise) and each axis's correlation family chosen by CV; the papers' methods \
         interpolate.\n\n![CV box plots]({cv_plot})\n"
    );
}

/// Section 2: the compensation table, and the circle's plot `circle_plot`.
fn compensation_section(s: &mut String, demo: &Demo, circle_plot: &str) {
    let _ = writeln!(
        s,
        "## 2. Feed-forward compensation, measured on the simulated robot\n"
    );
    let _ = writeln!(
        s,
        "| target | model | nominal mean / max (mm) | compensated mean / max (mm) | reduction mean / max | iterations |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|---|");
    for c in &demo.compensation {
        let (rm, rx) = c.reduction_pct();
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} / {:.4} | {:.4} / {:.4} | {rm:.0} % / {rx:.0} % | {} |",
            c.target,
            c.model,
            c.nominal.mean_abs_mm,
            c.nominal.max_abs_mm,
            c.after.mean_abs_mm,
            c.after.max_abs_mm,
            c.iterations
        );
    }
    let _ = writeln!(s, "\n![circle]({circle_plot})\n");
}

/// Section 3: the diagnosis of the campaign with the tracker bump.
fn diagnosis_section(s: &mut String, demo: &Demo) {
    let diag = &demo.diagnosis;
    let _ = writeln!(
        s,
        "## 3. What is the model missing? `diagnose` on a campaign with a tracker bump\n"
    );
    let _ = writeln!(
        s,
        "`data/comau_tracker_step.csv` is the same campaign with the tracker knocked by (0.15, −0.1, 0.1) mm \
         before row {}, and no column recording it.\n",
        demo.options.step_row()
    );
    let _ = writeln!(s, "| | CV RMSE x / y / z (mm) | mean 3D (mm) |");
    let _ = writeln!(s, "|---|---|---|");
    let _ = writeln!(
        s,
        "| before | {} | {:.4} |",
        xyz(&diag.before.cv_rmse_mm),
        diag.before.mean_3d_mm
    );
    let _ = writeln!(
        s,
        "| after | {} | {:.4} |",
        xyz(&diag.after.cv_rmse_mm),
        diag.after.mean_3d_mm
    );
    let _ = writeln!(s, "\nTop candidates of the first round:\n");
    let _ = writeln!(s, "| candidate | score | p | q (BH) | |");
    let _ = writeln!(s, "|---|---|---|---|---|");
    for e in diag.effects.iter().filter(|e| e.round == 1).take(5) {
        let _ = writeln!(
            s,
            "| {} | {:.3} | {:.4} | {:.4} | {} |",
            e.describe(),
            e.score,
            e.p_value,
            e.q_value,
            if e.accepted { "**added**" } else { "" }
        );
    }
}

/// The JSON summary of `demo --json`: the methods' CV, the compensation
/// rows, the diagnosis (before, after, the added effects); `out` is the
/// output folder, `secs` the wall time.
pub fn json(demo: &Demo, out: &Path, secs: f64) -> serde_json::Value {
    let diag = &demo.diagnosis;
    serde_json::json!({
        "output": out, "seconds": secs,
        "methods": demo.methods.iter().map(|r| serde_json::json!({
            "name": r.method.name(), "cv_mode": r.cv.mode, "cv_rmse_mm": r.cv.summary.rms_mm,
            "mean_3d_mm": r.cv.summary.mean_3d_mm, "max_3d_mm": r.cv.summary.max_3d_mm,
            "std_3d_mm": r.cv.summary.std_3d_mm, "seconds": r.cv.seconds,
        })).collect::<Vec<_>>(),
        "compensation": demo.compensation.iter().map(|c| serde_json::json!({
            "target": c.target, "model": c.model, "iterations": c.iterations,
            "before": c.nominal, "after": c.after,
        })).collect::<Vec<_>>(),
        "diagnose": {"before": diag.before, "after": diag.after,
            "effects": diag.effects.iter().filter(|e| e.accepted).collect::<Vec<_>>()},
    })
}
