//! Fitting an [`ErrorModel`]: the three outputs' universal-Kriging fits on
//! one input map. `params::ValidErrorModelParams::fit` drives it; the
//! selections choose the trends it is given.

use super::{AXES, ErrorModel, MODEL_FORMAT, MODEL_VERSION_UNCALIBRATED, SOFTWARE};
use crate::calibration::Calibration;
use crate::cancel::Cancel;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::inputs::InputMap;
use crate::kriging::{
    FitReport, Hyperparameters, KrigingModel, KrigingOptions, KrigingParams, Monomials, Trend,
    TrendModel, Tuning, share_coefficients,
};
use crate::selection::{
    KINEMATIC_AXIS_TOL, Terms, kinematic_trend_set_in, shared_kinematic_trends_in,
};
use crate::space::Space;
use crate::{Error, Result};
use rayon::prelude::*;

/// The three outputs' results in [`AXES`] order, the first failure named
/// by its axis ([`Error::Interrupted`] as it is: no axis failed).
fn by_axis<T>(fits: Vec<Result<T>>) -> Result<Vec<T>> {
    fits.into_iter()
        .enumerate()
        .map(|(a, f)| {
            f.map_err(|e| match e {
                Error::Interrupted => e,
                e => Error::Axis {
                    axis: AXES[a],
                    source: Box::new(e),
                },
            })
        })
        .collect()
}

/// Per joint `(min, max)` of the rows.
fn joint_range(q: &[Vec<f64>]) -> Vec<(f64, f64)> {
    let n = q.first().map_or(0, Vec::len);
    (0..n)
        .map(|j| {
            q.iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), r| {
                    (lo.min(r[j]), hi.max(r[j]))
                })
        })
        .collect()
}

/// The plan of a 3-output fit of `rows` rows ([`crate::kriging::FitPlan`])
/// with the default options and `optimizer`, refused with
/// [`Error::Memory`] when its estimated peak exceeds the memory limit
/// ([`crate::memory`]); the message says how to fit the most rows that
/// fit: `subset(rows)` (e.g. "`--rows 5000`"), or raising the limit.
pub fn check_fit_memory(
    rows: usize,
    optimizer: crate::kriging::OptimizerKind,
    subset: impl Fn(usize) -> String,
) -> Result<crate::kriging::FitPlan> {
    let opts = KrigingOptions {
        optimizer,
        ..KrigingOptions::default()
    };
    check_fit_memory_with(rows, &opts, subset)
}

/// [`check_fit_memory`] as a command checks a fit of a file's `rows` rows
/// before it starts: the advice names `option`, the command's option that
/// takes fewer rows (e.g. `--train`), or else a subset of the file. Returns
/// the plan when it is worth showing (above
/// [`crate::kriging::SEARCH_ROWS`] rows, where the search converges on a
/// subset), `None` for a small fit.
pub fn check_fit_rows(
    rows: usize,
    optimizer: crate::kriging::OptimizerKind,
    option: Option<&str>,
) -> Result<Option<crate::kriging::FitPlan>> {
    let subset = |n: usize| match option {
        Some(o) => format!("`{o} {n}`"),
        None => format!(
            "a subset: e.g. the first {n} rows, `head -n {} data.csv > subset.csv`",
            n + 1
        ),
    };
    let plan = check_fit_memory(rows, optimizer, subset)?;
    Ok((rows > crate::kriging::SEARCH_ROWS).then_some(plan))
}

/// [`check_fit_memory`] for a fit with `opts`.
fn check_fit_memory_with(
    rows: usize,
    opts: &KrigingOptions,
    subset: impl Fn(usize) -> String,
) -> Result<crate::kriging::FitPlan> {
    let threads = rayon::current_num_threads();
    let plan = crate::kriging::FitPlan::new(rows, 3, opts, threads);
    if let Some((limit, _)) = crate::memory::limit() {
        let fits = crate::kriging::FitPlan::max_rows(limit, 3, opts, threads);
        crate::memory::check(
            &format!("a fit of {rows} rows"),
            plan.bytes,
            &format!(
                "fit at most {fits} rows ({}), or raise {}",
                subset(fits),
                crate::memory::LIMIT_ENV
            ),
        )?;
    }
    Ok(plan)
}

/// Fit the three outputs of `data` on the input map `map` (fitted on
/// `data`, whose normalised inputs are `x`), output `a` with `trends[a]`,
/// its hyperparameters searched or, with `starts` (one per output), by a
/// local search from there ([`Tuning::Warm`]). Outputs (and the optimiser's
/// starts) run in parallel, unless the memory plan says one output at a
/// time.
pub(crate) fn fit_outputs(
    data: &Dataset,
    map: &InputMap,
    x: &[Vec<f64>],
    opts: &KrigingOptions,
    trends: &[Trend; 3],
    starts: Option<&[Hyperparameters]>,
) -> Result<ErrorModel> {
    opts.validate()?;
    let errors = data.errors_or_err()?;
    if data.len() < 3 {
        return Err(Error::Input {
            source_name: data.source.clone(),
            message: format!(
                "{} rows are too few to fit a model (need at least 3)",
                data.len()
            ),
        });
    }
    if let Some(s) = starts.filter(|s| s.len() != 3) {
        return Err(Error::InvalidParameter(format!(
            "warm starts must be one per output (3), not {}",
            s.len()
        )));
    }
    let plan = check_fit_memory_with(data.len(), opts, |n| format!("a subset of {n} rows"))?;
    let fit_axis = |a: usize| {
        let y: Vec<f64> = errors.iter().map(|e| e[a]).collect();
        KrigingParams::new(trends[a].clone())
            .options(opts.clone())
            .tuning(starts.map_or(Tuning::Search, |s| Tuning::Warm(s[a].clone())))
            .correlation_inputs(map.corr_dims())
            .names(map.names().to_vec())
            .check()?
            .fit(x, &y)
    };
    // large campaigns: one output at a time, one m × m factor in memory
    let fits: Vec<Result<(KrigingModel, FitReport)>> = if plan.sequential_outputs {
        (0..3).map(fit_axis).collect()
    } else {
        (0..3).into_par_iter().map(fit_axis).collect()
    };
    let (outputs, mut reports): (Vec<KrigingModel>, Vec<FitReport>) =
        by_axis(fits)?.into_iter().unzip();
    let ys: [Vec<f64>; 3] = std::array::from_fn(|a| errors.iter().map(|e| e[a]).collect());
    let outputs = share_coefficients(
        outputs,
        &[&trends[0], &trends[1], &trends[2]],
        &[&ys[0], &ys[1], &ys[2]],
    )?;
    // a shared trend's model keeps every term (its search saw a screened copy)
    for (r, o) in reports.iter_mut().zip(&outputs) {
        let t = &o.data.trend;
        if t.has_shared() {
            r.trend_terms = (0..t.len()).map(|j| t.term_name(j, map.names())).collect();
            r.dropped_terms.clear();
        }
    }
    let mut model = ErrorModel {
        format: MODEL_FORMAT.into(),
        version: MODEL_VERSION_UNCALIBRATED,
        inputs: map.clone(),
        // the token stopped this fit; a refit of the model must not inherit it
        options: opts.clone().cancel(Cancel::never()),
        outputs,
        reports,
        selection: None,
        joint_range: joint_range(&data.q),
        robot: None,
        software: SOFTWARE.into(),
        calibration: None,
        loo: Default::default(),
    };
    model.version = model.file_version();
    Ok(model)
}

/// The three outputs solved at given hyperparameters, no search: output
/// `a` on the normalised inputs `x` (the first `corr_dims` columns
/// correlation inputs), response `y(a)`, trend `trends[a]`, family of
/// `families[a]`, ξ and ν `at[a]`. The one refit every fixed-hyperparameter
/// path shares ([`ErrorModel::refit`], [`ErrorModel::restricted`],
/// `diagnose`'s candidate systems).
pub(crate) fn solve_outputs(
    x: &[Vec<f64>],
    corr_dims: usize,
    y: impl Fn(usize) -> Vec<f64> + Sync,
    trends: &[&Trend; 3],
    families: [crate::kriging::Correlation; 3],
    at: [Hyperparameters; 3],
    opts: &KrigingOptions,
) -> Result<Vec<KrigingModel>> {
    let fits: Vec<Result<KrigingModel>> = (0..3)
        .into_par_iter()
        .map(|a| {
            KrigingParams::new(trends[a].clone())
                .options(opts.clone())
                .corr(families[a])
                .tuning(Tuning::Fixed(at[a].clone()))
                .correlation_inputs(corr_dims)
                .check()?
                .fit(x, &y(a))
                .map(|(model, _)| model)
        })
        .collect();
    let ys: [Vec<f64>; 3] = std::array::from_fn(&y);
    share_coefficients(by_axis(fits)?, trends, &[&ys[0], &ys[1], &ys[2]])
}

/// `base` with `axes.len()` extra input columns appended after its
/// `base.dim` inputs, and a linear trend term `s_{dim+j}` for each column
/// `j` that is a regressor of output `axis` (`axes[j]` is `None`, every
/// axis, or `Some(axis)`; [`Feature::column_axes`]). A column of another
/// axis stays an input of the model without a term on this one.
pub(crate) fn with_linear_columns(
    base: &Monomials,
    axes: &[Option<usize>],
    axis: usize,
) -> Monomials {
    let d = base.dim;
    let k = axes.len();
    let mut terms = base.clone();
    terms.dim = d + k;
    terms.exponents.iter_mut().for_each(|e| e.resize(d + k, 0));
    for (j, on) in axes.iter().enumerate() {
        if on.is_none_or(|a| a == axis) {
            let mut e = vec![0u8; d + k];
            e[d + j] = 1;
            terms.exponents.push(e);
        }
    }
    terms
}

impl ErrorModel {
    /// Fit with extra inputs `extras` after `[θ, λ]` (the joints `periodic`
    /// as sin/cos): each gets a linear
    /// trend term next to the options' trend in `[θ, λ]`, and those that are
    /// not [`Feature::trend_only`] are also input dimensions of the
    /// correlation. The model stores the extras with the correlation inputs
    /// first (the order of its input columns).
    pub(crate) fn fit_with_extras(
        data: &Dataset,
        space: Space,
        periodic: &[usize],
        opts: &KrigingOptions,
        extras: &[Feature],
        starts: Option<&[Hyperparameters]>,
    ) -> Result<Self> {
        let mut extras = extras.to_vec();
        extras.sort_by_key(Feature::trend_only);
        let extras = &extras[..];
        let d0 = space.encoded_dim(data.n_joints(), periodic);
        let axes: Vec<Option<usize>> = extras.iter().flat_map(Feature::column_axes).collect();
        let base = opts.trend.monomials(d0);
        let trends: [Trend; 3] =
            std::array::from_fn(|a| Trend::from(with_linear_columns(&base, &axes, a)));
        let (map, x) = InputMap::fit(data, space, periodic, extras)?;
        fit_outputs(data, &map, &x, opts, &trends, starts)
    }

    /// This model refitted on `data` at its own hyperparameters — ξ, ν and
    /// family per output, no search — with the same space, periodic joints,
    /// options and kind of trend (linfa's `FitWith`). The input
    /// normalisation is re-fitted on `data`; a kinematic trend is rebuilt
    /// for it, a polynomial one reused; a calibrated model is identified
    /// anew on `data` and its Kriging outputs refitted on what that
    /// calibration leaves. The reports keep the search's figures (ln ψ,
    /// evaluations). The way to scale to thousands of rows when the O(m³)
    /// search is too slow (ξ on a subset, then one factorisation on
    /// everything), and what refit-mode CV folds use.
    pub fn refit(&self, data: &Dataset) -> Result<Self> {
        match &self.calibration {
            Some(c) => self.refit_with_calibration(data, c.reidentify(data)?),
            None => self.refit_outputs(data),
        }
    }

    /// The Kriging outputs of [`ErrorModel::refit`] on `data` as it is
    /// (the calibration, if any, is kept as it was).
    fn refit_outputs(&self, data: &Dataset) -> Result<Self> {
        if !self.extras().is_empty() {
            return Err(Error::InvalidParameter(
                "refit at fixed hyperparameters does not support extra inputs".into(),
            ));
        }
        let t0 = std::time::Instant::now();
        let errors = data.errors_or_err()?;
        self.check_rows(&data.q, &data.dir)?;
        let (map, x) = InputMap::fit(data, self.space(), self.periodic(), &[])?;
        let trends: [Trend; 3] = match &self.outputs[0].data.trend {
            Trend::Kinematic(k) if k.shared => {
                shared_kinematic_trends_in(data, &map, &x, self.options.trend, &k.robot)?
            }
            Trend::Kinematic(k) => kinematic_trend_set_in(
                data,
                &map,
                &x,
                self.options.trend,
                &k.robot,
                Terms::Screened(KINEMATIC_AXIS_TOL),
            )?,
            _ => std::array::from_fn(|a| self.outputs[a].data.trend.clone()),
        };
        let outputs = solve_outputs(
            &x,
            map.corr_dims(),
            |a| errors.iter().map(|e| e[a]).collect(),
            &[&trends[0], &trends[1], &trends[2]],
            self.families(),
            self.hyperparameters(),
            &self.options,
        )?;
        let secs = t0.elapsed().as_secs_f64();
        let reports = self
            .reports
            .iter()
            .map(|r| FitReport {
                seconds: secs,
                ..r.clone()
            })
            .collect();
        Ok(self.with_outputs(map, outputs, reports, joint_range(&data.q)))
    }

    /// This model's settings, robot and calibration with other outputs (and
    /// their input map, reports and joint range): without cloning the old
    /// outputs, whose kept factors are m² numbers each.
    fn with_outputs(
        &self,
        inputs: InputMap,
        outputs: Vec<KrigingModel>,
        reports: Vec<FitReport>,
        joint_range: Vec<(f64, f64)>,
    ) -> Self {
        let mut model = ErrorModel {
            format: self.format.clone(),
            version: self.version,
            inputs,
            options: self.options.clone(),
            outputs,
            reports,
            selection: self.selection.clone(),
            joint_range,
            robot: self.robot.clone(),
            software: self.software.clone(),
            calibration: self.calibration.clone(),
            loo: Default::default(),
        };
        model.version = model.file_version();
        model
    }

    /// Each output's correlation family.
    fn families(&self) -> [crate::kriging::Correlation; 3] {
        std::array::from_fn(|a| self.outputs[a].corr())
    }

    /// Each output's ξ (correlation inputs only) and ν, without curvature.
    fn hyperparameters(&self) -> [Hyperparameters; 3] {
        let d = self.correlation_dims();
        std::array::from_fn(|a| {
            let km = &self.outputs[a].data;
            Hyperparameters::new(km.theta[..d].to_vec(), km.nugget)
        })
    }

    /// [`ErrorModel::refit`] on top of the calibration
    /// `cal` (identified on `data` by the caller): the Kriging outputs are
    /// refitted to what `cal` leaves, and the model holds `cal`.
    pub(crate) fn refit_with_calibration(&self, data: &Dataset, cal: Calibration) -> Result<Self> {
        Ok(self
            .refit_outputs(&cal.residual(data)?)?
            .with_calibration(cal))
    }

    /// Drop every output's factors kept in memory (recomputed when next
    /// needed).
    pub(crate) fn release_factors(&mut self) {
        self.outputs
            .iter_mut()
            .for_each(KrigingModel::release_factors);
    }

    /// This model at its hyperparameters (ξ, ν, the trend's terms) on the
    /// training rows `rows` only, `errors` being the responses of every
    /// training row (mm): β, σ² and γ are those of the GLS on those rows, the
    /// input normalisation stays that of all rows, no search. What
    /// `diagnose` scans candidates on when a campaign has more rows than it
    /// scans (its `ScanRows`); unlike
    /// [`ErrorModel::refit`] it keeps the model's extra
    /// inputs, whose values on those rows are already in the training
    /// inputs. The fit reports are kept (the search's figures).
    pub(crate) fn restricted(&self, rows: &[usize], errors: &[[f64; 3]]) -> Result<Self> {
        // (the fits keep their factors up to KEEP_FACTOR_MAX_M rows:
        // `release_factors` when they are no longer needed)
        let x: Vec<Vec<f64>> = rows
            .iter()
            .map(|&i| self.outputs[0].data.x_train[i].clone())
            .collect();
        let o = &self.outputs;
        let outputs = solve_outputs(
            &x,
            self.correlation_dims(),
            |a| rows.iter().map(|&i| errors[i][a]).collect(),
            &[&o[0].data.trend, &o[1].data.trend, &o[2].data.trend],
            self.families(),
            self.hyperparameters(),
            &self.options,
        )?;
        Ok(self.with_outputs(
            self.inputs.clone(),
            outputs,
            self.reports.clone(),
            self.joint_range.clone(),
        ))
    }
}

#[cfg(test)]
mod tests {
    use crate::kriging::KrigingOptions;
    use crate::params::ErrorModelParams;

    #[test]
    fn a_model_restricted_to_rows_keeps_its_hyperparameters_and_solves_there() {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
        let data = crate::dataset::read_csv(path.as_ref())
            .unwrap()
            .select(&(0..60).collect::<Vec<_>>());
        let opts = KrigingOptions::default().starts(2);
        let params = ErrorModelParams::new().kriging(opts).check().unwrap();
        let model = params.fit(&data).unwrap();
        let errors = data.errors_or_err().unwrap();
        // on all rows: the model's own GLS (β, γ) at its ξ
        let all: Vec<usize> = (0..60).collect();
        let same = model.restricted(&all, errors).unwrap();
        for (a, b) in same.outputs.iter().zip(&model.outputs) {
            let close = |u: &[f64], v: &[f64]| {
                u.len() == v.len() && u.iter().zip(v).all(|(x, y)| (x - y).abs() < 1e-8)
            };
            assert!(close(&a.data.gamma, &b.data.gamma));
            assert!(close(&a.data.beta, &b.data.beta));
            assert!((a.data.sigma2 - b.data.sigma2).abs() < 1e-10);
        }
        // on every other row: the same ξ, ν and input normalisation, the
        // GLS of those rows
        let half: Vec<usize> = (0..60).step_by(2).collect();
        let r = model.restricted(&half, errors).unwrap();
        assert_eq!(r.input_map(), model.input_map());
        for (a, b) in r.outputs.iter().zip(&model.outputs) {
            assert_eq!(a.data.theta, b.data.theta);
            assert_eq!(a.data.nugget, b.data.nugget);
            assert_eq!(a.data.gamma.len(), 30);
            let rows: Vec<&Vec<f64>> = half.iter().map(|&i| &b.data.x_train[i]).collect();
            assert!(a.data.x_train.iter().eq(rows));
        }
    }
}
