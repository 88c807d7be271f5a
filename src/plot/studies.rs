//! The charts of the studies: the 3D error along a trajectory (before and
//! after compensation), each added effect's residual against its traced
//! variable (`diagnose`), the paths of a physics comparison (seed 000
//! Figs 9–11), and the demo's figures.

use super::{Labels, Series, box_plot, xy_plot};
use crate::Result;
use crate::cv::CvResult;
use crate::dataset::Dataset;
use crate::demo::Demo;
use crate::diagnose::{CvStats, Diagnosis};
use crate::methods::Method;
use crate::model::AXES;
use crate::physics::Comparison;
use crate::report::demo::Figures;
use crate::space::Space;
use crate::vec3::{Vec3, norms};
use std::path::{Path, PathBuf};

/// The 3D error |δ| of each run along the trajectory (x: the point's
/// index), one line per `(name, errors)` run.
pub fn error_along_path(
    path: &Path,
    labels: &Labels,
    runs: &[(String, Vec<[f64; 3]>)],
) -> Result<()> {
    let series: Vec<Series> = runs
        .iter()
        .map(|(n, e)| {
            Series::line(
                n.clone(),
                e.iter()
                    .enumerate()
                    .map(|(i, v)| (i as f64, v.norm()))
                    .collect(),
            )
        })
        .collect();
    xy_plot(path, labels, &series, false)
}

/// [`error_along_path`] of runs measured on the simulated robot, titled
/// `title`: the charts of `compensate` and `evaluate`.
pub fn measured_errors(path: &Path, title: &str, runs: &[(String, Vec<[f64; 3]>)]) -> Result<()> {
    let labels = Labels {
        title,
        x: "trajectory point",
        y: "measured 3D position error (mm)",
    };
    error_along_path(path, &labels, runs)
}

/// Box plots of a CV's out-of-fold errors (|ex|, |ey|, |ez|, 3D) of a
/// model over `space`.
pub fn cv_errors(path: &Path, res: &CvResult, space: Space) -> Result<()> {
    let axis = |k: usize| res.residuals.iter().map(|e| e[k].abs()).collect();
    let groups = vec![
        ("|ex|".to_string(), axis(0)),
        ("|ey|".to_string(), axis(1)),
        ("|ez|".to_string(), axis(2)),
        ("3D".to_string(), norms(&res.residuals)),
    ];
    let title = format!(
        "{}-fold CV ({}) out-of-fold errors, {space:?}",
        res.folds, res.mode
    );
    box_plot(path, &title, "error (mm)", &groups)
}

/// Box plots of the out-of-fold 3D errors of each method's `folds`-fold
/// refit CV.
pub fn methods_errors(path: &Path, folds: usize, results: &[(Method, CvResult)]) -> Result<()> {
    let groups: Vec<(String, Vec<f64>)> = results
        .iter()
        .map(|(m, res)| (m.name().to_string(), norms(&res.residuals)))
        .collect();
    let title = format!("{folds}-fold CV (refit) 3D error by method");
    box_plot(path, &title, "out-of-fold 3D error (mm)", &groups)
}

/// One SVG per effect the diagnosis added, in the folder `dir` (created;
/// `effect{k}_{kind}.svg`): the out-of-fold residual before and after the
/// effect against its traced variable
/// ([`EffectReport::traced_variable`](crate::diagnose::EffectReport::traced_variable)),
/// on the axis whose residual it reduced most. `data` is the diagnosed
/// campaign. Returns the files written.
pub fn effect_plots(dir: &Path, data: &Dataset, d: &Diagnosis) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::io(dir, e))?;
    let mut out = Vec::new();
    let mut prev: &CvStats = &d.before;
    for (k, e) in d.effects.iter().filter(|e| e.accepted).enumerate() {
        let next = &d.steps[k];
        // the axis whose residual the effect reduced most
        let gain = |a: usize| {
            prev.residuals.iter().map(|r| r[a] * r[a]).sum::<f64>()
                - next.residuals.iter().map(|r| r[a] * r[a]).sum::<f64>()
        };
        let axis = (0..3)
            .max_by(|x, y| gain(*x).total_cmp(&gain(*y)))
            .unwrap_or(0);
        let (xlabel, x) = e.traced_variable(data);
        let pts = |s: &CvStats| {
            x.iter()
                .zip(&s.residuals)
                .map(|(xi, r)| (*xi, r[axis]))
                .collect()
        };
        let path = dir.join(format!("effect{}_{}.svg", k + 1, e.kind.name()));
        let title = format!("{}: residual before / after", e.describe());
        let ylabel = format!("out-of-fold residual {} (mm)", AXES[axis]);
        xy_plot(
            &path,
            &Labels {
                title: &title,
                x: &xlabel,
                y: &ylabel,
            },
            &[
                Series::points("before", pts(prev)),
                Series::points("after", pts(next)),
            ],
            false,
        )?;
        out.push(path);
        prev = next;
    }
    Ok(out)
}

/// Seed 000 Figs 9–11, one SVG per model of the comparison but the nominal
/// one, in the folder `dir` (created; `path_{model}.svg`): the nominal path,
/// the measured path and the model's predicted path in XY, errors magnified
/// ×1000. Returns the files written.
pub fn path_plots(c: &Comparison, dir: &Path) -> Result<Vec<PathBuf>> {
    std::fs::create_dir_all(dir).map_err(|e| crate::Error::io(dir, e))?;
    let k = 1000.0;
    let shifted = |e: &[[f64; 3]]| -> Vec<(f64, f64)> {
        c.path_nominal
            .iter()
            .zip(e)
            .map(|(p, d)| (p[0] + k * d[0], p[1] + k * d[1]))
            .collect()
    };
    let nominal: Vec<(f64, f64)> = c.path_nominal.iter().map(|p| (p[0], p[1])).collect();
    let mut out = Vec::new();
    for r in c.rows.iter().filter(|r| r.model != "nominal") {
        let path = dir.join(format!("path_{}.svg", slug(&r.model)));
        let title = format!("{}: {} (errors ×1000)", c.options.robot, r.model);
        let labels = Labels {
            title: &title,
            x: "X (mm)",
            y: "Y (mm)",
        };
        let series = [
            Series::line("command (nominal)", nominal.clone()),
            Series::points("measured", shifted(&c.path_errors)),
            Series::line("predicted", shifted(&r.path_predicted)),
        ];
        xy_plot(&path, &labels, &series, true)?;
        out.push(path);
    }
    Ok(out)
}

/// A model's name as a file name: lower-case ASCII letters and digits,
/// every other run of characters one `_` ("D-H + APD" → "d_h_apd").
fn slug(name: &str) -> String {
    name.chars()
        .map(|ch| {
            if ch.is_ascii_alphanumeric() {
                ch.to_ascii_lowercase()
            } else {
                '_'
            }
        })
        .collect::<String>()
        .split('_')
        .filter(|t| !t.is_empty())
        .collect::<Vec<_>>()
        .join("_")
}

/// The demo's figures in the existing folder `dir`: box plots of the
/// methods' out-of-fold 3D errors (`cv_methods.svg`), the measured error
/// along the circle, nominal and compensated (`circle_compensation.svg`),
/// and the diagnosis' [`effect_plots`].
pub fn demo_plots(demo: &Demo, dir: &Path) -> Result<Figures> {
    let groups: Vec<(String, Vec<f64>)> = demo
        .methods
        .iter()
        .map(|r| {
            let mode = if r.cv.mode == "refit" { "refit" } else { "c-f" };
            (
                format!("{} ({mode})", r.method.name()),
                norms(&r.cv.residuals),
            )
        })
        .collect();
    let cv = dir.join("cv_methods.svg");
    box_plot(
        &cv,
        &format!(
            "{}-fold CV: out-of-fold 3D error by method",
            demo.options.folds
        ),
        "3D error (mm)",
        &groups,
    )?;
    let circle = dir.join("circle_compensation.svg");
    error_along_path(
        &circle,
        &Labels {
            title: "Ø100 mm circle: measured error, nominal vs compensated (iterative)",
            x: "trajectory point",
            y: "3D position error (mm)",
        },
        &demo.circle_runs,
    )?;
    let effects = effect_plots(dir, &demo.tracker_step, &demo.diagnosis)?;
    Ok(Figures {
        cv,
        circle,
        effects,
    })
}

#[cfg(test)]
mod tests {
    use super::slug;

    #[test]
    fn a_model_name_becomes_a_file_name() {
        assert_eq!(slug("D-H + APD"), "d_h_apd");
        assert_eq!(slug("Kriging EJS (ejs-gps)"), "kriging_ejs_ejs_gps");
    }
}
