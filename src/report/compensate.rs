//! `compensate` and `evaluate`: the iterations and the errors measured on
//! the simulated robot.

use crate::compensate::{Compensated, Stop};
use crate::physics::AnyModel;
use crate::stats::PositionErrorTable;
use crate::study::{Evaluation, FileEvaluation};
use serde_json::Value;
use std::fmt::Write as _;
use std::path::Path;

/// One error table, labelled: the mean error per axis and the mean, std,
/// min and max of |δ|.
pub fn table_line(label: &str, t: &PositionErrorTable) -> String {
    format!(
        "  {label:<22} mean x/y/z {:>8.4} {:>8.4} {:>8.4}   |δ| mean {:.4}  std {:.4}  min {:.4}  max {:.4}",
        t.mean_mm[0],
        t.mean_mm[1],
        t.mean_mm[2],
        t.mean_abs_mm,
        t.std_abs_mm,
        t.min_abs_mm,
        t.max_abs_mm
    )
}

/// The reduction of the mean and of the max |δ|, after `indent`.
pub fn reduction_line(indent: &str, ev: &Evaluation) -> String {
    format!(
        "  {indent}reduction: mean |δ| {:.1} %, max |δ| {:.1} %",
        ev.reduction_mean_abs_pct, ev.reduction_max_abs_pct
    )
}

/// What `compensate` prints: the points compensated with `model` (its
/// description) in `secs` s into `output`, then one line per iteration.
pub fn iterations(
    res: &Compensated,
    iterative: bool,
    model: &str,
    secs: f64,
    output: &Path,
) -> String {
    let (mut s, output) = (String::new(), output.display());
    let _ = writeln!(
        s,
        "{} {} points with {model} in {secs:.3} s -> {output}",
        if iterative {
            "iteratively compensated"
        } else {
            "compensated (single step)"
        },
        res.commands.len(),
    );
    for it in &res.history {
        let _ = writeln!(
            s,
            "  iteration {:>2}: RMSE of the change {:.5} mm (max {:.5}), mean predicted |δ̂| {:.4} mm, λ flips {}",
            it.iteration,
            it.rmse_change_mm,
            it.max_change_mm,
            it.mean_predicted_mm,
            it.direction_flips
        );
    }
    s
}

/// The warning (without its `warning: ` prefix) for an iterative
/// compensation that did not converge below `tol` mm within `max_iter`
/// iterations, if it did not.
pub fn stop_warning(res: &Compensated, tol: f64, max_iter: usize) -> Option<String> {
    match res.stop {
        Stop::Stalled => Some(format!(
            "the change stalled above {tol} mm at direction reversals; λ still switching at points {}",
            index_list(&res.unsettled)
        )),
        Stop::MaxIterations => Some(format!(
            "the change did not fall below {tol} mm in {max_iter} iterations"
        )),
        Stop::Converged | Stop::SingleStep => None,
    }
}

/// Up to 12 indices, then an ellipsis.
fn index_list(v: &[usize]) -> String {
    let mut s: Vec<String> = v.iter().take(12).map(usize::to_string).collect();
    if v.len() > 12 {
        s.push(format!("… ({} in all)", v.len()));
    }
    s.join(", ")
}

/// The evaluation of a compensation on the simulated robot of `truth`: the
/// errors before and after, and the reduction.
pub fn evaluation(truth: &Path, ev: &Evaluation) -> String {
    format!(
        "on the simulated robot ({}), measured error vs target (mm):\n{}\n{}\n{}\n",
        truth.display(),
        table_line("before (nominal)", &ev.before),
        table_line("after (compensated)", &ev.after),
        reduction_line("", ev)
    )
}

/// What `evaluate` prints for one command file: its errors and their
/// reduction, after the nominal commands' errors for the `first` file.
pub fn file_evaluation(e: &FileEvaluation, first: bool) -> String {
    let ev = &e.evaluation;
    let mut s = String::new();
    if first {
        let _ = writeln!(s, "{}", table_line("before (nominal)", &ev.before));
    }
    let _ = writeln!(s, "{}", table_line(&e.name, &ev.after));
    let _ = writeln!(s, "{}", reduction_line(&format!("{:<22} ", ""), ev));
    s
}

/// The JSON of `evaluate --json`: the truth file, the targets, the noise
/// seed, the nominal and first file's errors, and every file's evaluation.
pub fn evaluations_json(
    truth: &Path,
    targets: &Path,
    seed: u64,
    evals: &[FileEvaluation],
) -> Value {
    let reports: Vec<Value> = evals
        .iter()
        .map(|e| serde_json::json!({"file": e.file, "evaluation": e.evaluation}))
        .collect();
    let first = reports.first().map_or(&Value::Null, |r| &r["evaluation"]);
    serde_json::json!({
        "truth": truth, "targets": targets, "seed": seed,
        "before": first["before"], "after": first["after"], "compensated": reports,
    })
}

/// The title of `compensate --plot`: the trajectory, single-step or
/// iterative, the model's space.
pub fn plot_title(traj: &Path, iterative: bool, model: &AnyModel) -> String {
    let name = traj.file_stem().and_then(|s| s.to_str());
    let mode = if iterative {
        "iterative"
    } else {
        "single-step"
    };
    let (name, space) = (name.unwrap_or("trajectory"), model.label());
    format!("{name}: {mode} compensation, {space} model")
}

/// The files of a compensation: targets, commands written, model.
#[derive(Debug, Clone, Copy)]
pub struct Files<'a> {
    /// The target trajectory.
    pub targets: &'a Path,
    /// The commands written.
    pub output: &'a Path,
    /// The model file.
    pub model: &'a Path,
}

/// The JSON of `compensate --json`: the files, the robot, the model's
/// space (`physics` for a physics model), the iteration history and how it
/// stopped, the wall time `secs`, and the evaluation on the simulated robot
/// if there is one.
pub fn json(
    files: Files<'_>,
    (robot, model): (&str, &AnyModel),
    (res, iterative, secs): (&Compensated, bool, f64),
    eval: Option<&Evaluation>,
) -> Value {
    let mut v = serde_json::json!({
        "targets": files.targets, "output": files.output, "model": files.model, "robot": robot,
        "space": match model {
            AnyModel::Kriging(m) => serde_json::to_value(m.space()).expect("plain enum"),
            AnyModel::Physics(_) => "physics".into(),
        }, "iterative": iterative, "converged": res.converged,
        "stop": res.stop, "unsettled": res.unsettled,
        "iterations": res.history, "seconds": secs,
    });
    if let Some(ev) = eval {
        v["before"] = serde_json::to_value(ev.before).expect("plain numbers");
        v["after"] = serde_json::to_value(ev.after).expect("plain numbers");
        v["evaluation"] = serde_json::to_value(ev).expect("plain numbers");
    }
    v
}
