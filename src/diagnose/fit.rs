//! The models a diagnosis compares: the base model by name
//! ([`base_params`]), a model with extra features fitted on a campaign
//! whose feature columns are precomputed on all rows ([`with_columns`],
//! [`fit_with_effects`]), and its K-fold CV (refit per fold, or closed form
//! above [`DiagnoseOptions::refit_rows`](super::DiagnoseOptions::refit_rows)),
//! warm-started from the model without the effect so that both are compared
//! in the same basin of the likelihood.

use super::options::DiagnoseOptions;
use super::report::CvStats;
use crate::cv::{cross_validate_closed_form, cross_validate_refit};
use crate::dataset::{Covariate, Dataset};
use crate::features::Feature;
use crate::kriging::{Hyperparameters, KrigingOptions};
use crate::methods::Method;
use crate::model::ErrorModel;
use crate::params::ErrorModelParams;
use crate::space::Space;
use crate::stats::summarize;
use crate::{Error, Result};

fn cv_stats(res: crate::cv::CvResult, extras: &[Feature], model: &ErrorModel) -> CvStats {
    let residuals = res.residuals;
    let s = summarize(&residuals);
    CvStats {
        mode: res.mode,
        expected_loo_rmse_mm: res.expected_loo_rmse_mm,
        noise_mm: model.noise_std(),
        cv_rmse_mm: s.rms_mm,
        pooled_rmse_mm: (s.rms_mm.iter().map(|v| v * v).sum::<f64>() / 3.0).sqrt(),
        mean_3d_mm: s.mean_3d_mm,
        max_3d_mm: s.max_3d_mm,
        extras: extras.iter().flat_map(Feature::names).collect(),
        residuals,
    }
}

/// Precompute the columns of `extras` on the whole campaign (named like the
/// feature, so they keep their values inside CV folds).
pub fn with_columns(data: &Dataset, extras: &[Feature]) -> Result<Dataset> {
    let mut work = data.clone();
    for f in extras {
        let cols = f.columns(&work)?;
        for (name, values) in f.names().into_iter().zip(cols) {
            if work.covariate(&name).is_none() {
                work.covariates.push(Covariate {
                    name,
                    values,
                    missing: 0,
                });
            }
        }
    }
    Ok(work)
}

/// The model with `extras` fitted on all of `data`, and its K-fold CV. Each
/// fold is refitted with a local search warm-started at the full model's
/// hyperparameters and curvature ([`crate::kriging::Tuning::Warm`]): a fold
/// holds 90 % of the rows, so its optimum lies in the same basin, and the
/// multistart would find it again at several times the cost. With `from`
/// (the current model) the full fit too is a local search from `from`, so
/// that the model with the effect is compared with the model without it in
/// the same basin of the multimodal likelihood (the candidate was found
/// there: [`gls::refit_systems`](super::gls::refit_systems)); see [`extended_starts`].
pub(super) fn cross_validated(
    data: &Dataset,
    extras: &[Feature],
    o: &DiagnoseOptions,
    from: Option<&ErrorModel>,
) -> Result<(CvStats, ErrorModel)> {
    let (work, model) = fit_extended(data, extras, o, from)?;
    let warm = model.warm_starts();
    let res = if data.len() > o.refit_rows {
        cross_validate_closed_form(&work, &model, o.folds, o.seed)?
    } else {
        cross_validate_refit(&work, o.folds, o.seed, |train| {
            ErrorModel::fit_with_extras(
                train,
                o.space,
                &o.periodic,
                &o.kriging,
                extras,
                Some(&warm),
            )
        })?
    };
    Ok((cv_stats(res, extras, &model), model))
}

/// The pooled closed-form K-fold CV RMSE (mm) of `model`, fitted with
/// `extras` on `data` (at its hyperparameters: no refit per fold).
pub(super) fn closed_form_rmse(
    data: &Dataset,
    extras: &[Feature],
    model: &ErrorModel,
    o: &DiagnoseOptions,
) -> Result<f64> {
    let work = with_columns(data, extras)?;
    let res = cross_validate_closed_form(&work, model, o.folds, o.seed)?;
    Ok(cv_stats(res, extras, model).pooled_rmse_mm)
}

/// What an effect adds on the refitted model: the model with `extras`
/// refitted on all of `data` (a local search from `from`, the model
/// without it, [`extended_starts`]), and its pooled closed-form K-fold CV
/// RMSE (mm). One fit and no refit per fold: the few candidates a round
/// compares are ordered by it before the one chosen is cross-validated in
/// full ([`cross_validated`]).
pub(super) fn refit_closed_form(
    data: &Dataset,
    extras: &[Feature],
    o: &DiagnoseOptions,
    from: &ErrorModel,
) -> Result<f64> {
    let (work, model) = fit_extended(data, extras, o, Some(from))?;
    let res = cross_validate_closed_form(&work, &model, o.folds, o.seed)?;
    Ok(cv_stats(res, extras, &model).pooled_rmse_mm)
}

/// Warm starts for the model of `extras` from `from`, whose extras they
/// extend (`None` otherwise: another feature, or a correlation input not
/// after `from`'s): a candidate of trend terms only keeps
/// `from`'s ξ, ν and curvature; one that adds input dimensions (a
/// covariate, a joint's moves) starts each new dimension as weakly as
/// `from`'s weakest correlation input (its smallest ξ), so that the search
/// starts from the model the candidate was tested in — the effect as trend
/// terms, the GP unchanged — and lengthens or shortens the new scale from
/// there. A search from scratch lands in another basin of the likelihood,
/// whose CV then says more about the basin than about the effect (on all
/// 2 773 rows of UR10 series C, a planted lag and a planted temperature
/// drift were found but not confirmed that way).
/// `data` with the columns of `extras`, and the model with them fitted on
/// all of it: a local search from `from` when given ([`extended_starts`]).
fn fit_extended(
    data: &Dataset,
    extras: &[Feature],
    o: &DiagnoseOptions,
    from: Option<&ErrorModel>,
) -> Result<(Dataset, ErrorModel)> {
    let work = with_columns(data, extras)?;
    let start = from.and_then(|m| extended_starts(m, extras));
    let model = ErrorModel::fit_with_extras(
        &work,
        o.space,
        &o.periodic,
        &o.kriging,
        extras,
        start.as_deref(),
    )?;
    Ok((work, model))
}

fn extended_starts(from: &ErrorModel, extras: &[Feature]) -> Option<Vec<Hyperparameters>> {
    // a model's correlation inputs are its extras that are not trend-only,
    // in their order (`ErrorModel::extras` holds them first)
    let inputs =
        |e: &[Feature]| -> Vec<Feature> { e.iter().filter(|f| !f.trend_only()).cloned().collect() };
    if !from.extras().iter().all(|f| extras.contains(f))
        || !inputs(extras).starts_with(&inputs(from.extras()))
    {
        return None;
    }
    let new_dims = crate::features::correlation_dims(extras)
        .checked_sub(crate::features::correlation_dims(from.extras()))?;
    let starts = from.warm_starts();
    if new_dims == 0 {
        return Some(starts);
    }
    Some(
        starts
            .into_iter()
            .map(|w| {
                let weakest = w.theta.iter().copied().fold(f64::INFINITY, f64::min);
                let mut theta = w.theta;
                theta.extend(std::iter::repeat_n(weakest, new_dims));
                Hyperparameters::new(theta, w.nugget)
            })
            .collect(),
    )
}

/// The base model a diagnosis starts from, by name, as fit parameters
/// (their space and Kriging options; [`DiagnoseOptions::base`]):
/// - `ejs` (the default) and `js`: BFGS, constant trend, the Gaussian
///   family, in that space (`robokrige fit --space S --corr gaussian`);
/// - the papers' methods whose trend is the options' and whose family is
///   fixed, `js-hj`, `ejs-hj` and `ejs-gps`: the method's own set-up
///   ([`Method::params`]: space, optimiser, starts).
///
/// `nugget` estimates a nugget in either (the default of `diagnose`:
/// measured data has noise); for a method that is [`Method::params`]'s own
/// switch, so `--method ejs-gps --no-nugget` is exactly `ejs-gps`.
pub fn base_params(name: &str, seed: u64, nugget: bool) -> Result<ErrorModelParams> {
    let space = match name {
        "ejs" => Some(Space::Ejs),
        "js" => Some(Space::Js),
        _ => None,
    };
    if let Some(space) = space {
        let opts = KrigingOptions::default().nugget(nugget).seed(seed);
        return Ok(ErrorModelParams::new().space(space).kriging(opts));
    }
    match Method::from_name(name) {
        Ok(m @ (Method::JsHj | Method::EjsHj | Method::EjsGps)) => Ok(m.params(seed, nugget)),
        _ => Err(Error::InvalidParameter(format!(
            "diagnose supports the base models ejs, js, js-hj, ejs-hj or ejs-gps, not '{name}'"
        ))),
    }
}

/// The model of `data` with `extras` as inputs, fitted with the options of
/// `o` (after a diagnosis: its improved model, `extras` = [`Diagnosis::extras`](super::Diagnosis::extras);
/// with no extras: the model as it was).
pub fn fit_with_effects(
    data: &Dataset,
    o: &DiagnoseOptions,
    extras: &[Feature],
) -> Result<ErrorModel> {
    let work = with_columns(data, extras)?;
    ErrorModelParams::new()
        .space(o.space)
        .periodic(o.periodic.clone())
        .kriging(o.kriging.clone())
        .extras(extras.to_vec())
        .check()?
        .fit(&work)
}
