//! Every read of `ErrorModel`, `KrigingModel` or `KrigingOptions`, and every
//! `KrigingOptions` built, is here and nowhere else in this crate. Their
//! fields are private in the library: models have getters of the fields'
//! names, options builder setters of the fields' names and `get_` getters.

use robokrige::features::Feature;
use robokrige::kriging::{CorrChoice, FitReport, KrigingOptions, OptimizerKind, TrendKind};
use robokrige::model::{ErrorModel, RobotRecord};
use robokrige::space::Space;

/// JS or EJS.
pub fn space(m: &ErrorModel) -> Space {
    m.space()
}

/// Joints of the robot the model was fitted on.
pub fn n_joints(m: &ErrorModel) -> usize {
    m.n_joints()
}

/// Name of every input column.
pub fn input_names(m: &ErrorModel) -> &[String] {
    m.input_names()
}

/// The options the model was fitted with.
pub fn options(m: &ErrorModel) -> &KrigingOptions {
    m.options()
}

/// One fit report per axis.
pub fn reports(m: &ErrorModel) -> &[FitReport] {
    m.reports()
}

/// Joints entered as (sin θ, cos θ), 0-based.
pub fn periodic(m: &ErrorModel) -> &[usize] {
    m.periodic()
}

/// Extra inputs (effects added by `diagnose`).
pub fn extras(m: &ErrorModel) -> &[Feature] {
    m.extras()
}

/// The robot the model records, if any.
pub fn robot(m: &ErrorModel) -> Option<&RobotRecord> {
    m.robot()
}

/// Training rows (0 for a model without outputs).
pub fn training_rows(m: &ErrorModel) -> usize {
    m.n_train()
}

/// The correlation family of each output, by name.
pub fn families(m: &ErrorModel) -> Vec<String> {
    m.outputs().iter().map(|o| o.corr().to_string()).collect()
}

/// Whether each output's family was chosen by CV.
pub fn corr_auto(o: &KrigingOptions) -> bool {
    o.get_corr().is_by_cv()
}

/// Whether a nugget was estimated.
pub fn nugget(o: &KrigingOptions) -> bool {
    o.get_nugget()
}

/// `KrigingOptions::default()` with what `robokrige fit` sets from its flags.
#[allow(clippy::too_many_arguments)]
pub fn fit_options(
    trend: TrendKind,
    corr: CorrChoice,
    optimizer: OptimizerKind,
    nugget: bool,
    starts: usize,
    seed: u64,
) -> KrigingOptions {
    KrigingOptions::default()
        .trend(trend)
        .corr(corr)
        .optimizer(optimizer)
        .nugget(nugget)
        .starts(starts)
        .seed(seed)
}

/// `KrigingOptions::default()` with what `robokrige diagnose` sets.
pub fn diagnose_options(optimizer: OptimizerKind, nugget: bool, seed: u64) -> KrigingOptions {
    KrigingOptions::default()
        .optimizer(optimizer)
        .nugget(nugget)
        .seed(seed)
}
