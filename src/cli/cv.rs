//! `robokrige cv`.

use super::fit::ModelArgs;
use super::progress::{ga, of_total, with_bar};
use clap::Args;
use robokrige::Result;
use robokrige::cv::{CvMode, CvPlan, Folds, check_methods_rows, cross_validate_method};
use robokrige::report::cv as report;
use std::path::PathBuf;

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
    super::check_files(
        &[Some(a.data.as_path())],
        &[a.json.as_deref(), a.plot.as_deref()],
    )?;
    if let Some(list) = &a.methods {
        return run_methods(&a, list);
    }
    let data = super::read_data(&a.data)?;
    let params = a.model.resolve(None, &data)?;
    if let Some(r) = params.get_robot() {
        super::warn(r.limit_warnings(&data));
    }
    super::print_plan("cv", params.check_fit_rows(data.len(), None)?);
    let plan = CvPlan {
        mode: a.mode,
        folds: Folds::new(a.groups.as_deref(), a.folds, a.cv_seed),
        hyper_rows: a.hyper_rows,
    };
    plan.validate(data.len())?;
    let params = params.check()?;
    let (res, subset) = with_bar(0, "folds", |pb| plan.run(&data, &params, &of_total(pb)))?;
    eprint!("{}", report::hyper_subset(subset.as_ref(), data.len()));
    let text = report::summary(&res, &plan.folds, (&a.data, data.len()), params.params());
    say_part!("{text}");
    let v = report::json(&res, &a.data, params.params())?;
    super::json_to(a.json.as_deref(), &v, "cv result")?;
    if let Some(path) = &a.plot {
        robokrige::plot::cv_errors(path, &res, params.params().get_space())?;
        say!("plot: {}", path.display());
    }
    Ok(())
}

/// `cv --methods`: the table of seed 003 Table 2 (range, mean, std of the 3D
/// error) plus per-axis RMSE, and the JSON `methods` list.
fn run_methods(a: &CvArgs, list: &str) -> Result<()> {
    let methods = robokrige::methods::parse_methods(list)?;
    let data = super::read_data(&a.data)?;
    super::print_plan("cv", check_methods_rows(data.len(), a.folds)?);
    say!("{}", report::methods_header(a.folds, data.len(), a.cv_seed));
    let mut results = Vec::new();
    for m in methods {
        let res = with_bar(a.folds as u64, m.name(), |pb| {
            cross_validate_method(&data, m, a.folds, a.cv_seed, &|| pb.inc(1), &ga(pb))
        })?;
        say!("{}", report::methods_row(m.name(), &res));
        results.push((m, res));
    }
    let v = report::methods_json(&a.data, a.folds, a.cv_seed, &results);
    super::json_to(a.json.as_deref(), &v, "cv result")?;
    if let Some(path) = &a.plot {
        robokrige::plot::methods_errors(path, a.folds, &results)?;
        say!("plot: {}", path.display());
    }
    Ok(())
}
