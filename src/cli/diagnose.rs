//! `robokrige diagnose`.

use super::compensate::read_targets;
use super::progress::spinner;
use clap::Args;
use robokrige::dataset::Dataset;
use robokrige::diagnose::{
    CvStats, DiagnoseOptions, Diagnosis, EffectReport, diagnose, fit_with_effects,
};
use robokrige::kinematics;
use robokrige::model::ErrorModel;
use robokrige::plot::effect_plots;
use robokrige::stats::PositionErrorTable;
use robokrige::study::{compensate_and_evaluate_each, load_truth};
use robokrige::{Error, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};

/// Find what the model still gets wrong, trace it to a missing effect, add it.
#[derive(Debug, Args)]
#[command(after_help = "\
Candidates: every numeric covariate column not in the model (alone, × joint
angles, × one joint angle, lagged), drift and a change point in the measurement
order, harmonics of each joint over a scanned period range, cross-joint
products, direction history, and the motion into each pose (a joint's last
moves with a scanned memory, their size, the TCP's last move with --robot, the
time since the previous pose with a time column).
Each is tried inside the current model (its columns join the trend at the
model's correlation parameters, refitted for the strongest few): statistic,
the leave-one-out gain maximised over its parameter scan; p-value against
sign-flipped pseudo-campaigns of the fitted model; Benjamini–Hochberg across
candidates; score, the closed-form K-fold CV drop. The best significant one
(q within the FDR and ≥ 2 % lower CV RMSE; for one tested at re-estimated
parameters, also confirmed by the refit CV) is added the way its kind needs
(trend terms for a step, harmonic, interaction, cross-talk, a lag through
the Jacobian or a product with a joint angle; an input dimension for a
covariate, the order, direction history or a joint's moves), and the model
is cross-validated again, until nothing significant remains. Each added
effect is reported with its size (trend coefficients, 95 % intervals) and an
\"after\" check: explained, or only partly modelled.

Example:
  robokrige diagnose datasets/comau_tracker_step.csv --json diag.json --report diag.md --plots diag/")]
pub struct DiagnoseArgs {
    /// Measurement CSV (any extra numeric columns are candidate covariates).
    data: PathBuf,
    /// Base model (constant trend, nugget): ejs or js (BFGS on the analytic
    /// gradient; CV folds warm-started from the full fit), or the papers'
    /// js-hj, ejs-hj, ejs-gps (the method's own set-up, with a nugget
    /// unless --no-nugget).
    #[arg(long, default_value = "ejs")]
    method: String,
    /// Fit the base model as an interpolator (no nugget). The default
    /// estimates a nugget: measured data has noise, and an interpolating
    /// model both stays far above the noise floor and leaves smooth
    /// structure that makes smooth candidates look significant.
    #[arg(long)]
    no_nugget: bool,
    /// Folds K of the cross-validation every candidate is judged by.
    #[arg(long, default_value_t = 10)]
    folds: usize,
    /// Seed of the fold partition, the permutations and the fits.
    #[arg(long, default_value_t = 1)]
    seed: u64,
    /// Sign-flip resamples of each candidate's null distribution (its p-value).
    #[arg(long, default_value_t = 1999)]
    permutations: usize,
    /// False-discovery rate (Benjamini–Hochberg).
    #[arg(long, default_value_t = 0.05)]
    fdr: f64,
    /// Effects added at most (one per round).
    #[arg(long, default_value_t = 3)]
    max_effects: usize,
    /// Joints entered as (sin θ, cos θ): "none" (default), "auto" (range >
    /// 180°), or "1,4,6". Default none: on UR10 series B the interpolating
    /// Hooke–Jeeves fits with auto encoding blew up in some folds.
    #[arg(long, default_value = "none")]
    periodic: String,
    /// Use only the first N rows.
    #[arg(long)]
    rows: Option<usize>,
    /// Above this many rows, every CV is closed-form at the hyperparameters
    /// of the model fitted on all rows (not refitted per fold), and every
    /// fit (the models compared, each candidate's re-estimated ξ) converges
    /// ξ on one seeded subset of this many rows, then solves on all rows:
    /// a whole campaign of thousands of rows in minutes.
    #[arg(long, default_value_t = robokrige::diagnose::DEFAULT_REFIT_ROWS)]
    refit_rows: usize,
    /// Most rows the candidate test scans: above it, candidates are scanned
    /// on this many rows spread evenly over the campaign, while the models
    /// with and without an effect are fitted and cross-validated on all
    /// rows (a 12 000-row campaign in minutes, not hours).
    #[arg(long, default_value_t = robokrige::diagnose::DEFAULT_SCAN_ROWS)]
    scan_rows: usize,
    /// Write the result as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Write a Markdown report.
    #[arg(long)]
    report: Option<PathBuf>,
    /// Folder for residual-vs-effect plots (SVG) of every accepted effect.
    #[arg(long)]
    plots: Option<PathBuf>,
    /// Save the final model (with the added effects) here.
    #[arg(long)]
    model_out: Option<PathBuf>,
    /// Robot (preset name or robot file): adds joint cross-talk candidates (through its Jacobian);
    /// with --traj and --truth, also compensates the trajectory with the model
    /// before and after and reports the errors.
    #[arg(long)]
    robot: Option<String>,
    /// TCP offset x,y,z (mm) on the robot's flange, replacing its tool (with --robot).
    #[arg(long, requires = "robot", allow_hyphen_values = true)]
    tool: Option<String>,
    /// Start from the calibrated robot (with --robot): a D-H calibration
    /// (Levenberg–Marquardt, on all rows) first, then the diagnosis of its
    /// residual. On real data the calibrated base leaves a far smaller
    /// misfit than plain Kriging of the raw error, so smaller effects show.
    /// The models written (--model-out) and compared (--traj) then hold the
    /// calibration and the Kriging of its residual, as `fit --robot` does.
    #[arg(long, requires = "robot")]
    calibrate: bool,
    /// Trajectory to compensate with the model before and after the effects
    /// were added (TCP x,y,z CSV, or joints q1..qN), with --robot and --truth.
    #[arg(long, requires_all = ["robot", "truth"])]
    traj: Option<PathBuf>,
    /// Simulator truth JSON of the campaign (`robokrige simulate` writes it):
    /// runs the compensated trajectory on the simulated robot to measure it
    /// (with --traj).
    #[arg(long, requires_all = ["robot", "traj"])]
    truth: Option<PathBuf>,
}

fn options(a: &DiagnoseArgs, data: &Dataset) -> Result<DiagnoseOptions> {
    let base = robokrige::diagnose::base_params(&a.method, a.seed, !a.no_nugget)?;
    Ok(DiagnoseOptions::default()
        .base(&base)
        .periodic(robokrige::space::parse_periodic(&a.periodic, &data.q)?)
        .folds(a.folds)
        .seed(a.seed)
        .permutations(a.permutations)
        .fdr(a.fdr)
        .max_effects(a.max_effects)
        .refit_rows(a.refit_rows)
        .scan_rows(a.scan_rows)
        .robot(
            a.robot
                .as_deref()
                .map(|r| kinematics::load_robot_with_tool(r, a.tool.as_deref()))
                .transpose()?,
        ))
}

pub(super) fn rmse3(v: &[f64; 3]) -> String {
    format!("{:.4} / {:.4} / {:.4}", v[0], v[1], v[2])
}

pub fn run(a: DiagnoseArgs) -> Result<()> {
    let inputs: Vec<&std::path::Path> = [
        Some(a.data.as_path()),
        a.traj.as_deref(),
        a.truth.as_deref(),
    ]
    .into_iter()
    .flatten()
    .collect();
    let outputs: Vec<&std::path::Path> = [
        a.json.as_deref(),
        a.report.as_deref(),
        a.model_out.as_deref(),
    ]
    .into_iter()
    .flatten()
    .collect();
    robokrige::output::check_outputs(&inputs, &outputs)?;
    let mut data = super::read_data(&a.data)?;
    if let Some(n) = a.rows.filter(|&n| n < data.len()) {
        data = data.select(&(0..n).collect::<Vec<_>>());
    }
    let opts = options(&a, &data)?;
    let mut calibration = None;
    if a.calibrate {
        let robot = opts
            .get_robot()
            .expect("clap: --calibrate requires --robot");
        let cal = robokrige::calibration::calibrate(&data, robot, &Default::default())?;
        data = cal.residual(&data)?;
        say!(
            "calibrated base: {}; diagnosing its residual",
            cal.summary_line()
        );
        calibration = Some(cal);
    }
    let on_calibration = |m: robokrige::model::ErrorModel| match &calibration {
        Some(c) => m.with_calibration(c.clone()),
        None => m,
    };
    let plan = robokrige::diagnose::DiagnosePlan::new(&data, &opts);
    plan.check(
        |n| format!("`--rows {n}`"),
        |n| format!("`--scan-rows {n}`"),
    )?;
    if data.len() > robokrige::kriging::SEARCH_ROWS {
        eprintln!("diagnose: {plan}");
    }
    let pb = spinner("diagnose");
    let d = diagnose(&data, &opts, &|msg| pb.set_message(msg.to_string()));
    pb.finish_and_clear();
    let d = d?;
    print_summary(&a, &d);
    let mut plots = Vec::new();
    if let Some(dir) = &a.plots {
        std::fs::create_dir_all(dir).map_err(|e| Error::io(dir, e))?;
        plots = effect_plots(dir, &data, &d)?;
        for p in &plots {
            say!("plot: {}", p.display());
        }
        if plots.is_empty() {
            say!("no plots in {}: no effect was added", dir.display());
        }
    }
    let need_models = a.model_out.is_some() || a.traj.is_some();
    let mut compensation = None;
    if need_models {
        let after = on_calibration(fit_with_effects(&data, &opts, &d.extras)?);
        if let Some(p) = &a.model_out {
            after.save(p)?;
            say!("model with the added effects: {}", p.display());
        }
        if let (Some(robot), Some(traj), Some(truth)) = (&a.robot, &a.traj, &a.truth) {
            // (--traj and --truth without --robot are rejected by clap)
            let before = on_calibration(fit_with_effects(&data, &opts, &[])?);
            compensation = Some(compare_compensation(
                robot, traj, truth, &before, &after, a.seed,
            )?);
        }
    }
    if let Some(path) = &a.json {
        let mut v = serde_json::to_value(&d).map_err(|e| Error::Json {
            context: "diagnosis".into(),
            source: e,
        })?;
        v["data"] = serde_json::json!(a.data);
        v["method"] = serde_json::json!(a.method);
        if let Some(c) = &compensation {
            v["compensation"] = serde_json::json!({"before_model": c.0, "after_model": c.1});
        }
        super::write_json(path, &v, "diagnosis")?;
    }
    if let Some(path) = &a.report {
        let text = report(&a, &d, &plots, compensation.as_ref());
        robokrige::output::write_text(path, &text)?;
        say!("report: {}", path.display());
    }
    Ok(())
}

fn print_summary(a: &DiagnoseArgs, d: &Diagnosis) {
    say!(
        "{} ({} rows{}): {}-fold {} CV ({}), {} candidates scanning {} parameter values, up to {} resamples, FDR {}, {:.1} s",
        a.data.display(),
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
        a.method,
        d.candidates[0],
        d.candidates[1],
        d.permutations,
        d.fdr,
        d.seconds
    );
    for c in &d.dropped_covariates {
        say!("  left out: covariate {}: {}", c.name, c.reason);
    }
    say!(
        "  before: CV RMSE x/y/z {} mm, mean 3D {:.4}",
        rmse3(&d.before.cv_rmse_mm),
        d.before.mean_3d_mm
    );
    let mut round = 0;
    for e in &d.effects {
        if e.round != round {
            round = e.round;
            say!(
                "  round {round} (best 5 of {}):",
                d.effects.iter().filter(|x| x.round == round).count()
            );
        }
        let rank = d
            .effects
            .iter()
            .filter(|x| x.round == round)
            .position(|x| x == e)
            .unwrap_or(0);
        if rank < 5 || e.accepted {
            say!(
                "    {:<48} score {:>6.3}{} p {:.4}  q {:.4}  evidence {:>6.3}{}{}",
                e.describe(),
                e.score,
                if e.refit_xi { " ξ" } else { "  " },
                e.p_value,
                e.q_value,
                e.evidence,
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
    let added: Vec<&EffectReport> = d.effects.iter().filter(|e| e.accepted).collect();
    for (k, s) in d.steps.iter().enumerate() {
        say!(
            "  after effect {}: CV RMSE x/y/z {} mm, mean 3D {:.4}",
            k + 1,
            rmse3(&s.cv_rmse_mm),
            s.mean_3d_mm
        );
        if let Some(e) = added.get(k) {
            for line in effect_lines(e) {
                say!("    {line}");
            }
        }
    }
    if d.steps.is_empty() {
        if d.effects.iter().any(|e| e.significant) {
            say!("  significant candidates, but none lowered the CV RMSE enough to be added");
        } else {
            say!("  no significant effect: nothing to add");
        }
    }
}

/// The size of an added effect (its trend coefficients with 95 % intervals)
/// and its "after" check, one line each.
fn effect_lines(e: &EffectReport) -> Vec<String> {
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
    out
}

type Comparison = (PositionErrorTable, PositionErrorTable);

/// Iterative compensation of `traj` with the models before and after, both run
/// on the simulated robot: (error with the before model, with the after model).
fn compare_compensation(
    robot: &str,
    traj: &Path,
    truth_path: &Path,
    before: &ErrorModel,
    after: &ErrorModel,
    seed: u64,
) -> Result<(Comparison, Comparison)> {
    let robot = kinematics::load_robot(robot)?;
    let truth = load_truth(truth_path)?;
    let start = robot.home.clone();
    let targets = read_targets(traj, &robot, None, &start)?;
    let runs = compensate_and_evaluate_each(
        &robot,
        &[before, after],
        truth_path,
        &truth,
        &targets,
        &start,
        seed,
    )?;
    let [b, a] = [&runs[0], &runs[1]].map(|r| (r.evaluation.before, r.evaluation.after));
    say!(
        "compensation of {} (iterative, on the simulated robot): nominal mean |δ| {:.4} mm; model before {:.4} mm, after {:.4} mm",
        traj.display(),
        b.0.mean_abs_mm,
        b.1.mean_abs_mm,
        a.1.mean_abs_mm
    );
    Ok((b, a))
}

fn report(
    a: &DiagnoseArgs,
    d: &Diagnosis,
    plots: &[PathBuf],
    comp: Option<&(Comparison, Comparison)>,
) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "# Diagnosis of `{}`\n", a.data.display());
    let _ = writeln!(
        s,
        "Base model `{}`; out-of-fold residuals of a {}-fold CV {} (fold seed {}); \
         {} candidates (scanning {} parameter values in all), each tried inside the model and tested against up to {} \
         sign-flipped pseudo-campaigns (maximum over its parameter scan), Benjamini–Hochberg at FDR {}; an effect \
         is added only if it lowers the pooled CV RMSE by ≥ 2 % or by its worth at the noise floor. {:.1} s.\n",
        a.method,
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
            rmse3(&c.cv_rmse_mm),
            c.mean_3d_mm,
            c.max_3d_mm
        );
    };
    row(&mut s, "before", &d.before);
    for (k, st) in d.steps.iter().enumerate() {
        row(&mut s, &format!("after effect {}", k + 1), st);
    }
    let _ = writeln!(s);
    for (k, e) in d.effects.iter().filter(|e| e.accepted).enumerate() {
        let _ = writeln!(
            s,
            "Effect {}, {}:
",
            k + 1,
            e.describe()
        );
        for line in effect_lines(e) {
            let _ = writeln!(s, "- {line}");
        }
        let _ = writeln!(s);
    }
    if d.steps.is_empty() {
        let text = if d.effects.iter().any(|e| e.significant) {
            "**Nothing added**: significant candidates were found (below), but none lowered the CV RMSE enough."
        } else {
            "**No significant effect**: the residual is not explained by any candidate beyond chance."
        };
        let _ = writeln!(s, "{text}\n");
    }
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
        let rank = d
            .effects
            .iter()
            .filter(|x| x.round == round)
            .position(|x| x == e)
            .unwrap_or(0)
            + 1;
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
                    "{status}; indistinguishable here from {}",
                    e.confounded_with.join("; ")
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
    if let Some(((nb, bb), (_, ab))) = comp {
        let _ = writeln!(s, "\n## Compensation\n");
        let _ = writeln!(
            s,
            "Iterative compensation of `{}` run on the simulated robot: nominal mean |δ| {:.4} mm (max {:.4}); \
             with the model before {:.4} mm (max {:.4}); after {:.4} mm (max {:.4}).",
            a.traj
                .as_ref()
                .map(|p| p.display().to_string())
                .unwrap_or_default(),
            nb.mean_abs_mm,
            nb.max_abs_mm,
            bb.mean_abs_mm,
            bb.max_abs_mm,
            ab.mean_abs_mm,
            ab.max_abs_mm
        );
    }
    if !plots.is_empty() {
        let _ = writeln!(s, "\n## Plots\n");
        for p in plots {
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
         (and added) by it."
    );
    s
}
