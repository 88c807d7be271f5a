//! Every read of `ErrorModel`, `KrigingModel` or `KrigingOptions` is here
//! and nowhere else in this crate (options are built by the library, from
//! names: `methods::params_with`, `diagnose::base_params`). Their fields
//! are private in the library: models have getters of the fields' names,
//! options `get_` getters.

use robokrige::features::Feature;
use robokrige::kriging::{FitReport, KrigingOptions, OptimizerKind};
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

/// The hyperparameter search of the options.
pub fn optimizer(o: &KrigingOptions) -> OptimizerKind {
    o.get_optimizer()
}
