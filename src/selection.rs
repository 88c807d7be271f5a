//! Trend selection that needs model fits: the genetic algorithm of seed 004
//! over the quadratic (and kinematic) candidates, with the closed-form CV
//! RMSE as fitness. PCC + PCA, which needs no fit, is [`crate::basis::pcc_pca`].

use crate::Result;
use crate::basis::{GaSelection, Selection, screen_candidates};
use crate::dataset::Dataset;
use crate::kriging::{
    KrigingOptions, Monomials, TrainingInputs, Trend, TrendKind, TrendModel, fit_output,
};
use crate::model::ErrorModel;
use crate::optim::{GaOptions, ga};
use crate::space::Space;
use crate::stats::kfold_partition;

/// Progress of a GA selection: `(output axis, generation, best CV RMSE mm)`.
pub type GaProgress<'a> = &'a (dyn Fn(usize, usize, f64) + Sync);

/// EJS&GA+GPS (seed 004): per output, ξ from a constant-trend GPS fit; the
/// quadratic candidates screened for linear dependence
/// ([`screen_candidates`]); a GA over the survivors (the constant always
/// kept) minimising the closed-form `k`-fold CV RMSE (eq 17) at that ξ, with
/// the size cap C ≤ (k−1)m/k; then a GPS fit with the selected trend. The
/// model's `selection` holds each output's [`GaSelection`] (its fitness
/// history is seed 004 Fig 10); `progress` is called after every generation.
///
/// With `kinematic = Some(robot)` the candidates of each output are the
/// quadratic monomials *and* the rows of `robot`'s identification Jacobian
/// ([`crate::kriging::KinematicTrend`], issue 10): the GA chooses among
/// polynomial terms and kinematic-error terms alike. `opts.periodic` joints
/// enter as (sin, cos).
pub fn fit_ga(
    data: &Dataset,
    opts: &KrigingOptions,
    k: usize,
    seed: u64,
    progress: GaProgress,
    kinematic: Option<&crate::kinematics::Robot>,
) -> Result<ErrorModel> {
    fit_ga_in(Space::Ejs, data, opts, k, seed, progress, kinematic)
}

/// [`fit_ga`] in either space (seed 004 uses EJS; JS is reachable through
/// `params::ErrorModelParams`).
pub(crate) fn fit_ga_in(
    space: Space,
    data: &Dataset,
    opts: &KrigingOptions,
    k: usize,
    seed: u64,
    progress: GaProgress,
    kinematic: Option<&crate::kinematics::Robot>,
) -> Result<ErrorModel> {
    let errors = data.errors_or_err()?;
    let m = data.len();
    let (map, x) = crate::inputs::InputMap::fit(data, space, &opts.periodic, &[])?;
    let d = map.dim();
    let inputs = TrainingInputs::new(&x);
    let names = map.names().to_vec();
    let fold = kfold_partition(m, k, seed)?;
    let blocks = crate::stats::fold_blocks(&fold);
    let quad = KrigingOptions {
        trend: TrendKind::Quadratic,
        ..opts.clone()
    };
    let all: [Trend; 3] = match kinematic {
        Some(robot) => crate::model::kinematic_candidates(data, space, &quad, robot)?,
        None => std::array::from_fn(|_| Trend::from(Monomials::quadratic(d))),
    };
    let cap = (k - 1) * m / k;
    let constant = TrendKind::Constant.trend(d);
    let mut trends = Vec::with_capacity(3);
    let mut reports = Vec::with_capacity(3);
    for a in 0..3 {
        let screen = screen_candidates(&all[a], &x, &names);
        let cand = all[a].subset(&screen.kept);
        let y: Vec<f64> = errors.iter().map(|e| e[a]).collect();
        let (_, base) = fit_output(&x, &inputs, &y, &constant, &names, opts)?;
        let at = crate::kriging::Hyperparameters {
            corr: opts.corr,
            theta: &base.theta,
            nugget: base.nugget,
            min_jitter: opts.min_jitter,
        };
        let rmse = |bits: &[bool]| {
            let keep: Vec<usize> = (0..cand.len()).filter(|&j| j == 0 || bits[j]).collect();
            crate::kriging::fit_output_with(&x, &inputs, &y, &cand.subset(&keep), &at)
                .and_then(|model| model.held_out_residuals(&blocks))
                .map_or(f64::INFINITY, |e| {
                    (e.iter().map(|v| v * v).sum::<f64>() / m as f64).sqrt()
                })
        };
        let ga_opts = GaOptions {
            max_ones: cap.saturating_sub(1),
            seed: seed.wrapping_add(a as u64),
            ..GaOptions::default()
        };
        let best = ga(cand.len(), rmse, &ga_opts, |g, f| progress(a, g, f));
        let keep: Vec<usize> = (0..cand.len())
            .filter(|&j| j == 0 || best.best[j])
            .collect();
        let trend = cand.subset(&keep);
        reports.push(GaSelection {
            candidates: screen.total,
            dropped: screen.dropped.clone(),
            size_cap: cap,
            selected: (0..trend.len())
                .map(|j| trend.term_name(j, &names))
                .collect(),
            cv_rmse_mm: best.fitness,
            history: best.history,
            generations: best.generations,
            evaluations: best.evaluations,
        });
        trends.push(trend);
    }
    let trends: [Trend; 3] = trends.try_into().expect("three outputs");
    let mut model = ErrorModel::fit_with_trend(data, space, opts, &trends)?;
    model.selection = Some(Selection::Ga { outputs: reports });
    Ok(model)
}
