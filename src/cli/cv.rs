//! `robokrige cv`.

use super::fit::ModelArgs;
use super::progress::bar;
use clap::Args;
use robokrige::cv::{
    CvMode, closed_form_model, cross_validate_closed_form, cross_validate_folds,
    cross_validate_method, group_partition, largest_training_rows,
};
use robokrige::plot::box_plot;
use robokrige::report::cv as report;
use robokrige::vec3::norms;
use robokrige::{Error, Result};
use std::path::PathBuf;

/// K-fold cross-validation of a model choice (refit on every training fold).
#[derive(Debug, Args)]
#[command(after_help = "\
Example:
  robokrige cv datasets/comau_lhs.csv --methods all --folds 10 --json cv.json --plot cv.svg
  robokrige cv datasets/comau_lhs.csv --space ejs --folds 10 --seed 1
  robokrige cv datasets/comau_lhs.csv --space js --folds 10 --seed 1 --json js.json")]
pub struct CvArgs {
    /// Measurement CSV with q1..qN, optional dir1..dirN, and ex,ey,ez.
    data: PathBuf,
    #[command(flatten)]
    model: ModelArgs,
    /// Number of folds K.
    #[arg(long, default_value_t = 10)]
    folds: usize,
    /// Compare named methods instead of one model choice: `all` or a list of
    /// recommended, js-hj, ejs-hj, ejs-gps, ejs-pca, ejs-ga (refit mode: each method's
    /// selection and hyperparameters inside every training fold). Each method
    /// carries its own settings (and `--cv-seed` seeds its search): the model
    /// options (`--space`, `--trend`, `--corr`, `--optimizer`, `--no-nugget`,
    /// `--starts`, `--seed`, `--periodic`, `--robot`, `--tool`, `--kinematic`)
    /// and `--mode`, `--hyper-rows` are refused with it, not ignored.
    #[arg(long, conflicts_with_all = [
        "space", "trend", "corr", "optimizer", "no_nugget", "nugget", "starts", "seed",
        "periodic", "robot", "tool", "kinematic", "mode", "hyper_rows",
    ])]
    methods: Option<String>,
    /// refit: re-optimise ξ on every training fold; closed-form: ξ from one fit
    /// on all rows, fold residuals from the bordered system (fast).
    #[arg(long, value_enum, default_value = "refit")]
    mode: CvMode,
    /// Closed-form mode at scale: choose ξ (and the nugget) on the first N
    /// rows, then factorise all rows once at those values.
    #[arg(long)]
    hyper_rows: Option<usize>,
    /// Seed of the fold partition.
    #[arg(long = "cv-seed", default_value_t = 1)]
    cv_seed: u64,
    /// Leave-one-group-out instead of random folds: one fold per value of
    /// this column (a cube, a cell, a day; refit mode), as scikit-learn's
    /// LeaveOneGroupOut. Does the model carry over to another group?
    #[arg(long, value_name = "COLUMN", conflicts_with_all = ["methods", "mode", "folds", "cv_seed"])]
    groups: Option<String>,
    /// Write the result (residuals, statistics) as JSON to FILE ("-": standard output).
    #[arg(long, value_name = "FILE")]
    json: Option<PathBuf>,
    /// Draw box plots of the out-of-fold 3D errors (SVG).
    #[arg(long)]
    plot: Option<PathBuf>,
}

pub fn run(a: CvArgs) -> Result<()> {
    let outputs: Vec<&std::path::Path> = [a.json.as_deref(), a.plot.as_deref()]
        .into_iter()
        .flatten()
        .collect();
    robokrige::output::check_outputs(&[&a.data], &outputs)?;
    if let Some(list) = &a.methods {
        return run_methods(&a, list);
    }
    let data = super::read_data(&a.data)?;
    let params = a.model.resolve(None, &data)?;
    super::plan_fit("cv", data.len(), params.get_kriging().get_optimizer(), None)?;
    if a.hyper_rows.is_some() && !matches!(a.mode, CvMode::ClosedForm) {
        return Err(Error::InvalidParameter(
            "--hyper-rows is for --mode closed-form (refit mode searches ξ in every fold)".into(),
        ));
    }
    if let Some(n) = a.hyper_rows.filter(|&n| n >= data.len()) {
        return Err(Error::InvalidParameter(format!(
            "--hyper-rows {n}: the campaign has only {} rows; give fewer, or leave it out to choose ξ on all rows",
            data.len()
        )));
    }
    let params = params.check()?;
    let t0 = std::time::Instant::now();
    let mut res = cross_validate(&a, &data, &params)?;
    res.seconds = t0.elapsed().as_secs_f64();
    let words = params.params().settings_line();
    let how = match &a.groups {
        Some(col) => format!(
            "leave-one-group-out CV over the {} groups of '{col}'",
            res.folds
        ),
        None => format!("{}-fold CV", res.folds),
    };
    let data_name = a.data.display().to_string();
    say_part!(
        "{}",
        report::summary(&res, &how, (&data_name, data.len()), &words)
    );
    write_outputs(&a, &res, &params)
}

/// The cross-validation `a.mode` asks for: refit in every fold (random
/// folds, or one per group), or closed form at the hyperparameters of one
/// fit (on the first `--hyper-rows` rows if given).
fn cross_validate(
    a: &CvArgs,
    data: &robokrige::dataset::Dataset,
    params: &robokrige::params::ValidErrorModelParams,
) -> Result<robokrige::cv::CvResult> {
    Ok(match a.mode {
        CvMode::Refit => {
            data.errors_or_err()?;
            let fold = match &a.groups {
                Some(col) => group_partition(&data.group_labels(col)?)?,
                None => robokrige::cv::kfold_partition(data.len(), a.folds, a.cv_seed)?,
            };
            let k = fold.iter().max().map_or(0, |f| f + 1);
            let pb = bar(k as u64, "folds");
            let res = cross_validate_folds(data, &fold, |train| {
                let m = params.fit(train);
                pb.inc(1);
                m
            });
            pb.finish_and_clear();
            let mut res = res?;
            res.seed = if a.groups.is_some() { 0 } else { a.cv_seed };
            res
        }
        CvMode::ClosedForm => {
            let (model, subset) = closed_form_model(data, params, a.hyper_rows)?;
            if let Some(h) = subset {
                eprintln!(
                    "hyperparameters chosen on the first {} rows in {:.1} s",
                    h.rows, h.seconds
                );
                eprintln!(
                    "refit on all {} rows at those values in {:.1} s",
                    data.len(),
                    h.refit_seconds
                );
            }
            cross_validate_closed_form(data, &model, a.folds, a.cv_seed)?
        }
    })
}

/// `--json` and `--plot` of one model choice's CV.
fn write_outputs(
    a: &CvArgs,
    res: &robokrige::cv::CvResult,
    params: &robokrige::params::ValidErrorModelParams,
) -> Result<()> {
    if let Some(path) = &a.json {
        let mut v = serde_json::to_value(res)
            .map_err(|e| Error::InvalidParameter(format!("cv result: {e}")))?;
        if let Some(o) = v.as_object_mut() {
            o.insert("data".into(), serde_json::json!(a.data));
            let s: serde_json::Map<String, serde_json::Value> = params
                .params()
                .settings()
                .into_iter()
                .map(|(k, v)| (k.to_string(), serde_json::Value::String(v)))
                .collect();
            o.insert("settings".into(), serde_json::Value::Object(s));
        }
        super::write_json(path, &v, "cv result")?;
    }
    if let Some(path) = &a.plot {
        let axis = |k: usize| res.residuals.iter().map(|e| e[k].abs()).collect();
        let groups = vec![
            ("|ex|".to_string(), axis(0)),
            ("|ey|".to_string(), axis(1)),
            ("|ez|".to_string(), axis(2)),
            ("3D".to_string(), norms(&res.residuals)),
        ];
        let title = format!(
            "{}-fold CV ({}) out-of-fold errors, {:?}",
            res.folds,
            res.mode,
            params.params().get_space()
        );
        box_plot(path, &title, "error (mm)", &groups)?;
        say!("plot: {}", path.display());
    }
    Ok(())
}

/// `cv --methods`: the table of seed 003 Table 2 (range, mean, std of the 3D
/// error) plus per-axis RMSE, and the JSON `methods` list.
fn run_methods(a: &CvArgs, list: &str) -> Result<()> {
    let methods = robokrige::methods::parse_methods(list)?;
    let data = super::read_data(&a.data)?;
    super::plan_fit(
        "cv",
        largest_training_rows(data.len(), a.folds),
        robokrige::kriging::OptimizerKind::Gps,
        None,
    )?;
    say!(
        "{}-fold CV (refit: selection and hyperparameters inside every training fold) on {} rows, fold seed {}",
        a.folds,
        data.len(),
        a.cv_seed
    );
    say!("{}", report::methods_header());
    let mut rows = Vec::new();
    let mut groups = Vec::new();
    for m in methods {
        let pb = bar(a.folds as u64, m.name());
        let ga_progress = |axis: usize, generation: usize, best: f64| {
            pb.set_message(format!(
                "GA {} generation {generation}: best CV RMSE {best:.4} mm",
                ["ex", "ey", "ez"][axis]
            ))
        };
        let res = cross_validate_method(&data, m, a.folds, a.cv_seed, &|| pb.inc(1), &ga_progress);
        pb.finish_and_clear();
        let res = res?;
        groups.push((m.name().to_string(), norms(&res.residuals)));
        let s = &res.summary;
        say!("{}", report::methods_row(m.name(), &res));
        rows.push(serde_json::json!({
            "name": m.name(), "cv_mode": res.mode, "cv_rmse_mm": s.rms_mm,
            "mean_3d_mm": s.mean_3d_mm, "max_3d_mm": s.max_3d_mm, "std_3d_mm": s.std_3d_mm,
            "min_3d_mm": s.min_3d_mm, "box_3d_mm": s.box_3d_mm, "seconds": res.seconds,
        }));
    }
    if let Some(path) = &a.json {
        let v = serde_json::json!({"data": a.data, "folds": a.folds, "seed": a.cv_seed, "methods": rows});
        super::write_json(path, &v, "cv result")?;
    }
    if let Some(path) = &a.plot {
        let title = format!("{}-fold CV (refit) 3D error by method", a.folds);
        box_plot(path, &title, "out-of-fold 3D error (mm)", &groups)?;
        say!("plot: {}", path.display());
    }
    Ok(())
}
