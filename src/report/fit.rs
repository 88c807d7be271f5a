//! `fit`: what a fitted model reports, as text.

use crate::calibration::Calibration;
use crate::model::{AXES, ErrorModel};
use crate::params::ErrorModelParams;
use crate::selection::Selection;
use std::fmt::Write as _;
use std::path::Path;

/// The JSON of `fit --json`: the files (`data`, `output`), the rows, the
/// settings ([`ErrorModelParams::settings`]), the method if one was named,
/// the robot, the wall time `secs`, each output's fit report, the trend
/// selection, the calibration's identifiability and its joint harmonics.
pub fn json(
    (data, output): (&Path, &Path),
    model: &ErrorModel,
    (params, method): (&ErrorModelParams, Option<&str>),
    (rows, secs): (usize, f64),
) -> serde_json::Value {
    serde_json::json!({"data": data, "model": output, "rows": rows,
        "settings": super::settings(params), "method": method, "robot": model.robot(),
        "seconds": secs, "outputs": model.reports(), "selection": model.selection(),
        "calibration": model.calibration().map(|c| c.identifiability()),
        "joint_harmonics": model.calibration().map(|c| c.harmonics()),
        "backlash": model.calibration().map(|c| c.backlash())})
}

/// The progress line of a GA trend selection: output `axis`, its
/// `generation`, and the best CV RMSE so far (mm).
pub fn ga_progress(axis: usize, generation: usize, best: f64) -> String {
    format!(
        "GA {} generation {generation}: best CV RMSE {best:.4} mm",
        AXES[axis]
    )
}

/// What `fit` prints after fitting `rows` rows in `secs` s into the file
/// `output`: the space, correlation and nugget; per axis the family CV (if
/// chosen by CV), ln ψ, σ², the nugget, the trend terms, the evaluations
/// and log10 ξ; the trend selection; the calibration.
pub fn summary(model: &ErrorModel, rows: usize, secs: f64, output: &Path) -> String {
    let (mut s, output) = (String::new(), output.display());
    let _ = writeln!(
        s,
        "fitted {rows} rows in {:?} space ({}, {}) in {secs:.2} s -> {output}",
        model.space(),
        if model.options().get_corr().is_by_cv() {
            let c: Vec<String> = model
                .outputs()
                .iter()
                .map(|o| o.corr().to_string())
                .collect();
            format!("correlation by CV: {}", c.join(" / "))
        } else {
            format!("{} correlation", model.outputs()[0].corr())
        },
        if model.options().get_nugget() {
            "nugget estimated"
        } else {
            "interpolating"
        },
    );
    for (ax, r) in AXES.iter().zip(model.reports()) {
        if !r.families.is_empty() {
            let t: Vec<String> = r
                .families
                .iter()
                .map(|f| format!("{} {:.4}", f.corr, f.cv_rmse))
                .collect();
            let _ = writeln!(
                s,
                "  {ax}: family by 10-fold CV RMSE (mm): {}",
                t.join(", ")
            );
        }
        let lt: Vec<String> = r
            .theta
            .iter()
            .map(|t| format!("{:.2}", t.log10()))
            .collect();
        let _ = writeln!(
            s,
            "  {ax}: ln ψ {:.4}  σ² {:.4}  nugget {:.2e}  trend terms {} (dropped {})  evals {}  {:.2} s\n      log10 ξ = [{}]",
            r.ln_psi,
            r.sigma2,
            r.nugget,
            r.trend_terms.len(),
            r.dropped_terms.len(),
            r.evals,
            r.seconds,
            lt.join(", ")
        );
    }
    s.push_str(&selection(model));
    if let Some(c) = model.calibration() {
        s.push_str(&calibration(c));
    }
    s
}

/// The calibration under a model: what the campaign identified, and the
/// parameters it left at nominal.
pub fn calibration(c: &Calibration) -> String {
    let mut s = format!("  calibration: {}\n", c.summary_line());
    for b in c.backlash() {
        let _ = writeln!(
            s,
            "  q{}: half backlash {} (at the TCP {:.4} mm RMS)",
            b.joint,
            b.display_on(c.nominal()),
            b.tcp_rms_mm
        );
    }
    for line in joint_harmonics(c) {
        let _ = writeln!(s, "  {line}");
    }
    let fixed = c.identifiability().fixed_names();
    if !fixed.is_empty() {
        let _ = writeln!(
            s,
            "  fixed at nominal (the campaign does not see them): {}",
            fixed.join(" ")
        );
    }
    s
}

/// One line per joint with harmonics: how many, their periods, and the
/// largest at the joint and at the TCP.
pub fn joint_harmonics(c: &Calibration) -> Vec<String> {
    crate::calibration::harmonics::by_joint(c.harmonics())
        .into_iter()
        .map(|(j, of)| {
            let (lo, hi) = of.iter().fold((f64::INFINITY, 0.0f64), |(a, b), h| {
                (a.min(h.period_deg), b.max(h.period_deg))
            });
            let big = of
                .iter()
                .max_by(|a, b| a.tcp_rms_mm.total_cmp(&b.tcp_rms_mm))
                .expect("a joint listed has a harmonic");
            format!(
                "q{j}: {} harmonic(s), periods {lo:.2}–{hi:.2}°; the largest at the TCP {:.4} mm RMS ({:.4}° at the joint, period {:.2}°)",
                of.len(),
                big.tcp_rms_mm,
                big.amplitude_deg(),
                big.period_deg
            )
        })
        .collect()
}

/// What a robot file of the calibration leaves out (`robot calibrated`).
pub fn not_in_robot_file(c: &Calibration) -> Option<String> {
    let (b, h) = (c.backlash().len(), c.harmonics().len());
    let left = match (b, h) {
        (0, 0) => return None,
        (b, 0) => format!("the backlash of {b} joint(s) stays"),
        (0, h) => format!("the {h} joint harmonics stay"),
        (b, h) => format!("the backlash of {b} joint(s) and the {h} joint harmonics stay"),
    };
    Some(format!(
        "the robot file holds the MD-H, tool and base errors; {left} in the model file (a controller that compensates with the model gets them, one that loads this table does not)"
    ))
}

/// One line per output of what PCC+PCA or the GA selected.
pub fn selection(model: &ErrorModel) -> String {
    let mut s = String::new();
    match &model.selection() {
        Some(Selection::PccPca { outputs }) => {
            for (ax, r) in AXES.iter().zip(outputs) {
                let _ = writeln!(
                    s,
                    "  {ax} PCC+PCA: {} candidates ranked ({} dependent dropped), {} with |r| > {}, {} components ({:.1} % of variance)",
                    r.ranking.len(),
                    r.dropped.len(),
                    r.selected,
                    r.threshold,
                    r.components,
                    100.0 * r.explained
                );
            }
        }
        Some(Selection::Ga { outputs }) => {
            for (ax, r) in AXES.iter().zip(outputs) {
                let _ = writeln!(
                    s,
                    "  {ax} GA: {} of {} candidates ({} dependent dropped), CV RMSE {:.4} mm after {} generations: {}",
                    r.selected.len(),
                    r.candidates,
                    r.dropped.len(),
                    r.cv_rmse_mm,
                    r.generations,
                    r.selected.join(" ")
                );
            }
        }
        None => {}
    }
    s
}
