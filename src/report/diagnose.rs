//! `diagnose`: the summary it prints and its Markdown report.

use super::xyz;
use crate::diagnose::{CvStats, Diagnosis, EffectReport, LeftOut, params_text};
use crate::study::diagnosis::{CompensationComparison, DiagnosisBase};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// The JSON of `diagnose --json`: the diagnosis with the campaign file
/// and the base method of `names`, and the compensation before and after,
/// if there was one.
pub fn json(
    d: &Diagnosis,
    names: Names<'_>,
    compensation: Option<&CompensationComparison>,
) -> crate::Result<serde_json::Value> {
    let mut v = serde_json::to_value(d).map_err(|e| crate::Error::Json {
        context: "diagnosis".into(),
        source: e,
    })?;
    v["data"] = serde_json::json!(names.data);
    v["method"] = serde_json::json!(names.method);
    if let Some(c) = compensation {
        v["compensation"] = serde_json::json!(c);
    }
    Ok(v)
}

/// What the diagnosis ran on, by name: the campaign file and the base
/// method.
#[derive(Debug, Clone, Copy)]
pub struct Names<'a> {
    /// The campaign file, as the user gave it.
    pub data: &'a Path,
    /// The base model's method name.
    pub method: &'a str,
}

/// The summary `diagnose` prints: the set-up, the CV before, the best
/// candidates of every round (the first five and the added one), and the CV
/// and size of every added effect.
pub fn summary(d: &Diagnosis, names: Names<'_>) -> String {
    let mut s = String::new();
    let _ = writeln!(
        s,
        "{} ({} rows{}): {}-fold {} CV ({}), {} candidates scanning {} parameter values, up to {} resamples, FDR {}, {:.1} s",
        names.data.display(),
        d.before.residuals.len(),
        if d.scanned_rows > 0 && d.scanned_rows < d.rows {
            format!(
                ", candidates scanned on {} of them, evenly spread",
                d.scanned_rows
            )
        } else {
            String::new()
        },
        d.folds,
        d.cv_mode(),
        names.method,
        d.candidates[0],
        d.candidates[1],
        d.permutations,
        d.fdr,
        d.seconds
    );
    for c in &d.dropped_covariates {
        let _ = writeln!(s, "  left out: covariate {}: {}", c.name, c.reason);
    }
    let _ = writeln!(
        s,
        "  before: CV RMSE x/y/z {} mm, mean 3D {:.4}",
        xyz(&d.before.cv_rmse_mm),
        d.before.mean_3d_mm
    );
    candidate_lines(&mut s, d);
    let added: Vec<&EffectReport> = d.effects.iter().filter(|e| e.accepted).collect();
    for (k, st) in d.steps.iter().enumerate() {
        let _ = writeln!(
            s,
            "  after effect {}: CV RMSE x/y/z {} mm, mean 3D {:.4}",
            k + 1,
            xyz(&st.cv_rmse_mm),
            st.mean_3d_mm
        );
        if let Some(e) = added.get(k) {
            for line in effect_lines(e) {
                let _ = writeln!(s, "    {line}");
            }
        }
    }
    for line in cap_lines(d) {
        let _ = writeln!(s, "  {line}");
    }
    if let Some(text) = order_text(d) {
        let _ = writeln!(s, "  not separable on this campaign: {text}");
    }
    if d.steps.is_empty() {
        if d.effects.iter().any(|e| e.significant) {
            let _ = writeln!(
                s,
                "  significant candidates, but none lowered the CV RMSE enough to be added"
            );
        } else {
            let _ = writeln!(s, "  no significant effect: nothing to add");
        }
    }
    s
}

/// The rank (0-based) of `e` among the candidates of its round.
fn rank(d: &Diagnosis, e: &EffectReport) -> usize {
    d.effects
        .iter()
        .filter(|x| x.round == e.round)
        .position(|x| x == e)
        .unwrap_or(0)
}

/// Per round, its five best candidates and the added one, one line each.
fn candidate_lines(s: &mut String, d: &Diagnosis) {
    let mut round = 0;
    for e in &d.effects {
        if e.round != round {
            round = e.round;
            let _ = writeln!(
                s,
                "  round {round} (best 5 of {}):",
                d.effects.iter().filter(|x| x.round == round).count()
            );
        }
        if rank(d, e) < 5 || e.accepted {
            let _ = writeln!(
                s,
                "    {:<48} score {:>6.3}{} p {:.4}  q {:.4}  evidence {:>6.3}{}{}{}",
                e.describe(),
                e.score,
                if e.refit_xi { " ξ" } else { "  " },
                e.p_value,
                e.q_value,
                e.evidence,
                e.refit_gain
                    .map(|g| format!("  refit CV {:+.1} %", -100.0 * g))
                    .unwrap_or_default(),
                if e.accepted {
                    "  ADDED"
                } else if e.significant {
                    "  significant"
                } else {
                    ""
                },
                e.note
                    .as_deref()
                    .map(|n| format!("  ({n})"))
                    .unwrap_or_default()
            );
        }
    }
}

/// The size of an added effect (its trend coefficients with 95 % intervals)
/// and its "after" check, one line each.
pub fn effect_lines(e: &EffectReport) -> Vec<String> {
    let mut out: Vec<String> = e
        .size
        .iter()
        .map(|c| {
            // per unit of a column in degree·mm/rad (a lag through the
            // Jacobian) a coefficient is ~1e-5: four decimals would print 0
            let largest = c
                .estimate
                .iter()
                .chain(&c.ci95)
                .fold(0.0f64, |m, v| m.max(v.abs()));
            let num = |v: f64| {
                if largest > 0.0 && largest < 1e-3 {
                    format!("{v:.3e}")
                } else {
                    format!("{v:.4}")
                }
            };
            let v: Vec<String> = (0..3)
                .filter(|&a| c.axis.is_none_or(|b| b == a))
                .map(|a| {
                    format!(
                        "{} {} ± {}",
                        ["x", "y", "z"][a],
                        num(c.estimate[a]),
                        num(c.ci95[a])
                    )
                })
                .collect();
            format!("{}: {} (mm per unit, 95 %)", c.column, v.join(", "))
        })
        .collect();
    if let Some(c) = &e.after_check {
        out.push(c.verdict.clone());
    }
    if !e.confounded_with.is_empty() {
        out.push(not_separable(&e.confounded_with));
    }
    out
}

/// Competing explanations a report line names; the JSON's
/// `confounded_with` holds them all.
const NAMED_SHOWN: usize = 5;

/// The first [`NAMED_SHOWN`] of `competitors`, and how many more.
fn named_list(competitors: &[String]) -> String {
    let mut out = competitors
        .iter()
        .take(NAMED_SHOWN)
        .cloned()
        .collect::<Vec<_>>()
        .join("; ");
    if competitors.len() > NAMED_SHOWN {
        let _ = write!(
            out,
            "; and {} more (the JSON's confounded_with lists them)",
            competitors.len() - NAMED_SHOWN
        );
    }
    out
}

/// The line that names the explanations the data cannot tell an effect
/// from.
fn not_separable(competitors: &[String]) -> String {
    format!(
        "not separable on this campaign from: {} (each explains the same residual as this one)",
        named_list(competitors)
    )
}

/// What one candidate left by the cap would add.
fn left_line(l: &LeftOut) -> String {
    let mut line = format!(
        "{}{}: evidence {:.3}, would lower the CV RMSE by {:.1} % (closed form){}",
        l.label,
        params_text(&l.params),
        l.evidence,
        100.0 * l.promised,
        l.refit_gain
            .map(|g| format!(", {:.1} % refitted", 100.0 * g))
            .unwrap_or_default()
    );
    if !l.confounded_with.is_empty() {
        let _ = write!(line, "; {}", not_separable(&l.confounded_with));
    }
    line
}

/// The cap reached with significant candidates left: a heading and one
/// line each (none when the loop stopped on its own).
pub fn cap_lines(d: &Diagnosis) -> Vec<String> {
    if d.left_by_cap.is_empty() {
        return Vec::new();
    }
    let mut out = vec![format!(
        "the cap of {} effects was reached with {} significant candidates left (--max-effects to add more):",
        d.steps.len(),
        d.left_by_cap.len()
    )];
    out.extend(d.left_by_cap.iter().map(|l| format!("  {}", left_line(l))));
    out
}

/// What the report says of the measurement order against the joint space
/// ([`crate::diagnose::OrderInJointSpace::text`]), when it matters.
fn order_text(d: &Diagnosis) -> Option<String> {
    d.order_in_joint_space.as_ref().and_then(|o| o.text())
}

/// The line on the calibration whose residual is diagnosed, if there is
/// one ([`DiagnosisBase::calibration`]); empty without.
pub fn calibrated_base(base: &DiagnosisBase) -> String {
    match &base.calibration {
        Some(cal) => {
            let line = cal.summary_line();
            format!("calibrated base: {line}; diagnosing its residual\n")
        }
        None => String::new(),
    }
}

/// The plots written into the folder `dir` (`--plots`), one line each; or,
/// when a folder was given but no effect was added, that it holds none.
pub fn plot_lines(dir: Option<&Path>, plots: &[PathBuf]) -> String {
    match dir {
        Some(dir) if plots.is_empty() => {
            format!("no plots in {}: no effect was added\n", dir.display())
        }
        _ => plots
            .iter()
            .map(|p| format!("plot: {}\n", p.display()))
            .collect(),
    }
}

/// The line `diagnose` prints for the compensation of trajectory `traj`
/// with the models before and after.
pub fn compensation_line(traj: &Path, c: &CompensationComparison) -> String {
    let (b, a, traj) = (&c.before_model, &c.after_model, traj.display());
    format!(
        "compensation of {traj} (iterative, on the simulated robot): nominal mean |δ| {:.4} mm; model before {:.4} mm, after {:.4} mm",
        b.0.mean_abs_mm, b.1.mean_abs_mm, a.1.mean_abs_mm
    )
}

/// What the Markdown report shows beyond the diagnosis: the compensated
/// trajectory and its comparison, and the plots drawn.
#[derive(Debug, Clone, Copy, Default)]
pub struct Extras<'a> {
    /// The trajectory compensated, and the comparison of the models on it.
    pub compensation: Option<(&'a Path, &'a CompensationComparison)>,
    /// Residual-vs-effect plots.
    pub plots: &'a [PathBuf],
}

/// The Markdown report of `diagnose --report`.
pub fn markdown(d: &Diagnosis, names: Names<'_>, extras: Extras<'_>) -> String {
    let mut s = String::new();
    setup_paragraphs(&mut s, d, names);
    cv_table(&mut s, d);
    for (k, e) in d.effects.iter().filter(|e| e.accepted).enumerate() {
        let _ = writeln!(s, "Effect {}, {}:\n", k + 1, e.describe());
        for line in effect_lines(e) {
            let _ = writeln!(s, "- {line}");
        }
        let _ = writeln!(s);
    }
    let cap = cap_lines(d);
    if let Some((head, rest)) = cap.split_first() {
        let _ = writeln!(s, "**{head}**\n");
        for line in rest {
            let _ = writeln!(s, "- {}", line.trim_start());
        }
        let _ = writeln!(s);
    }
    if let Some(text) = order_text(d) {
        let _ = writeln!(s, "**Not separable on this campaign**: {text}.\n");
    }
    if d.steps.is_empty() {
        let text = if d.effects.iter().any(|e| e.significant) {
            "**Nothing added**: significant candidates were found (below), but none lowered the CV RMSE enough."
        } else {
            "**No significant effect**: the residual is not explained by any candidate beyond chance."
        };
        let _ = writeln!(s, "{text}\n");
    }
    round_tables(&mut s, d);
    if let Some((traj, c)) = extras.compensation {
        let traj = traj.display();
        let ((nb, bb), (_, ab)) = (&c.before_model, &c.after_model);
        let _ = writeln!(s, "\n## Compensation\n");
        let _ = writeln!(
            s,
            "Iterative compensation of `{traj}` run on the simulated robot: nominal mean |δ| {:.4} mm (max {:.4}); \
             with the model before {:.4} mm (max {:.4}); after {:.4} mm (max {:.4}).",
            nb.mean_abs_mm,
            nb.max_abs_mm,
            bb.mean_abs_mm,
            bb.max_abs_mm,
            ab.mean_abs_mm,
            ab.max_abs_mm
        );
    }
    if !extras.plots.is_empty() {
        let _ = writeln!(s, "\n## Plots\n");
        for p in extras.plots {
            let _ = writeln!(
                s,
                "- `{}`: out-of-fold residual against the traced variable, before and after",
                p.display()
            );
        }
    }
    let _ = writeln!(
        s,
        "\nScore: relative drop of the model's K-fold CV squared error with the candidate in its trend (closed \
         form; at the correlation parameters refitted with it for the strongest candidates, marked ξ). p: \
         share of sign-flipped pseudo-campaigns of the fitted model in which the candidate's best leave-one-out \
         gain over its parameter scan is as large. q: Benjamini–Hochberg adjusted p over all candidates of the round. \
         Evidence: the candidate's leave-one-out gain minus the mean of that null distribution (what scanning its \
         grid finds by chance), as a share of the model's leave-one-out error; significant candidates are ranked \
         by it, and the best of each kind are tried for adding in the order of what they add on the refitted model."
    );
    s
}

/// The title and the paragraphs on how the diagnosis ran.
fn setup_paragraphs(s: &mut String, d: &Diagnosis, names: Names<'_>) {
    let _ = writeln!(s, "# Diagnosis of `{}`\n", names.data.display());
    let _ = writeln!(
        s,
        "Base model `{}`; out-of-fold residuals of a {}-fold CV {} (fold seed {}); \
         {} candidates (scanning {} parameter values in all), each tried inside the model and tested against up to {} \
         sign-flipped pseudo-campaigns (maximum over its parameter scan), Benjamini–Hochberg at FDR {}; an effect \
         is added only if it lowers the pooled CV RMSE by ≥ 2 % or by its worth at the noise floor. {:.1} s.\n",
        names.method,
        d.folds,
        if d.cv_mode() == "closed-form" {
            "in closed form at the hyperparameters of the model fitted on all rows"
        } else {
            "refitted on every training fold"
        },
        d.seed,
        d.candidates[0],
        d.candidates[1],
        d.permutations,
        d.fdr,
        d.seconds
    );
    if d.scanned_rows > 0 && d.scanned_rows < d.rows {
        let _ = writeln!(
            s,
            "Candidates scanned on {} of the {} rows, evenly spread in measurement order (their statistics, p-values, scores and evidence are of those rows; a step or block edge found on them is placed among the rows before it by the CV residuals of all rows); every model compared was fitted and cross-validated on all rows.\n",
            d.scanned_rows, d.rows
        );
    }
    for c in &d.dropped_covariates {
        let _ = writeln!(
            s,
            "Covariate `{}` left out of the candidates: {} (it cannot explain anything here).\n",
            c.name, c.reason
        );
    }
}

/// The CV of the model before and after each added effect.
fn cv_table(s: &mut String, d: &Diagnosis) {
    let _ = writeln!(
        s,
        "| model | extra inputs | CV RMSE x / y / z (mm) | mean 3D (mm) | max 3D (mm) |"
    );
    let _ = writeln!(s, "|---|---|---|---|---|");
    let row = |s: &mut String, name: &str, c: &CvStats| {
        let ex = if c.extras.is_empty() {
            "–".to_string()
        } else {
            c.extras.join(", ")
        };
        let _ = writeln!(
            s,
            "| {name} | {ex} | {} | {:.4} | {:.4} |",
            xyz(&c.cv_rmse_mm),
            c.mean_3d_mm,
            c.max_3d_mm
        );
    };
    row(s, "before", &d.before);
    for (k, st) in d.steps.iter().enumerate() {
        row(s, &format!("after effect {}", k + 1), st);
    }
    let _ = writeln!(s);
}

/// Per round, the table of its ten best candidates (and the added one).
fn round_tables(s: &mut String, d: &Diagnosis) {
    let mut round = 0;
    for e in &d.effects {
        if e.round != round {
            round = e.round;
            let _ = writeln!(s, "\n## Round {round}\n");
            let _ = writeln!(
                s,
                "| rank | kind | source | candidate | score | p | q (BH) | evidence | |"
            );
            let _ = writeln!(s, "|---|---|---|---|---|---|---|---|---|");
        }
        let rank = rank(d, e) + 1;
        if rank <= 10 || e.accepted {
            let status = if e.accepted {
                "**added**".to_string()
            } else if e.significant {
                e.note.clone().unwrap_or_else(|| "significant".into())
            } else {
                String::new()
            };
            let status = if e.confounded_with.is_empty() {
                status
            } else {
                format!(
                    "{status}; not separable on this campaign from {}",
                    named_list(&e.confounded_with)
                )
            };
            let _ = writeln!(
                s,
                "| {rank} | {} | {} | {} | {:.3} | {:.4} | {:.4} | {:.3} | {status} |",
                e.kind.name(),
                e.source.join(", "),
                e.describe(),
                e.score,
                e.p_value,
                e.q_value,
                e.evidence
            );
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A long list of competing explanations is cut to the first few, with
    /// how many more the JSON holds.
    #[test]
    fn a_long_list_of_competitors_names_the_first_and_counts_the_rest() {
        let named: Vec<String> = (1..=7).map(|i| format!("candidate {i}")).collect();
        let line = not_separable(&named);
        assert!(line.contains("candidate 5; and 2 more"), "{line}");
        assert!(!line.contains("candidate 6"), "{line}");
        assert_eq!(
            named_list(&named[..2]),
            "candidate 1; candidate 2".to_string()
        );
    }
}
