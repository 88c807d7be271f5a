//! Close the loop: find what the model still gets wrong, trace it to an
//! effect the model lacks, add it, and report before and after.
//!
//! 1. **Residuals**: out-of-fold K-fold CV residuals of the current model
//!    (refit on every training fold), per axis, in measurement order.
//! 2. **Candidates** ([`scan::families`]): every numeric covariate not in the
//!    model (alone, and interacting with the joint angles); the measurement
//!    order (drift, and a change-point scan); harmonics of each joint over a
//!    scanned period range; cross-joint products; direction history.
//! 3. **Tracing** ([`scan::test_families`], [`gls`]): each grid point is
//!    tried inside the current model (its columns join the trend at the
//!    model's ξ and nugget); a family's statistic is its best leave-one-out
//!    gain (for the strongest few at the ξ re-estimated with them), its
//!    p-value a test against sign-flipped pseudo-campaigns of the fitted
//!    model, Benjamini–Hochberg across families, and its score the
//!    closed-form K-fold CV drop.
//! 4. **Adding**: the best-scoring significant family's feature joins the
//!    model the way its kind needs ([`crate::features::Feature`]): a step,
//!    harmonic, interaction or cross-talk basis as trend terms; a covariate,
//!    the order or direction history as an input dimension with a linear
//!    trend term. The model is refitted and cross-validated again (refit per
//!    fold); it is kept only if the CV RMSE drops by at least `min_gain`, and
//!    the loop repeats until nothing significant remains or `max_effects`.
//! 5. **Report**: CV statistics before and after every accepted effect.

pub mod gls;
pub mod scan;

use crate::cv::{cross_validate_refit, kfold_partition};
use crate::dataset::{Covariate, Dataset};
use crate::features::Feature;
use crate::kriging::KrigingOptions;
use crate::model::ErrorModel;
use crate::space::Space;
use crate::stats::summarize;
use crate::{Error, Result};
pub use scan::EffectKind;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Significant candidates per round whose refit CV is tried before giving up.
const CONFIRMATIONS: usize = 3;

/// Options of [`diagnose`]; `Default` is EJS with the default optimiser
/// (BFGS on the analytic gradient) and a nugget (measurement noise: without one, the interpolating model cannot
/// approach the noise floor), 10 folds, 1999 permutations, FDR 5 %, at most
/// 3 effects.
#[derive(Debug, Clone, PartialEq)]
pub struct DiagnoseOptions {
    /// Input space of every model fitted: JS `[θ]` or EJS `[θ, λ]`.
    pub space: Space,
    /// Kriging options of every fit (trend, correlation, nugget, optimiser).
    pub kriging: KrigingOptions,
    /// Number of CV folds K.
    pub folds: usize,
    /// Seed of the fold partition and of the resamples.
    pub seed: u64,
    /// Most sign-flip resamples per candidate (a sign-flip permutation test;
    /// a clearly null candidate stops after a batch or two).
    pub permutations: usize,
    /// False-discovery rate for the Benjamini–Hochberg step.
    pub fdr: f64,
    /// Most effects added before the loop stops.
    pub max_effects: usize,
    /// Relative drop of the pooled CV RMSE an effect must bring to count:
    /// a candidate is *significant* when its q-value is within `fdr` and its
    /// closed-form CV drop reaches this (a detectable but negligible effect
    /// is ranked, with a note, not flagged), and it is *kept* when the refit
    /// CV confirms the drop. A candidate whose statistic comes from
    /// re-estimated ξ stays significant only if that confirmation succeeds.
    pub min_gain: f64,
    /// The measured robot: enables the joint cross-talk candidates (Jacobian).
    pub robot: Option<crate::kinematics::Robot>,
    /// Candidates (largest statistic first) tested again at the ξ the model
    /// would choose with them ([`gls::refit_systems`]).
    pub refine: usize,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions {
            space: Space::Ejs,
            kriging: KrigingOptions {
                nugget: true,
                ..KrigingOptions::default()
            },
            folds: 10,
            seed: 1,
            permutations: 1999,
            fdr: 0.05,
            max_effects: 3,
            min_gain: 0.02,
            robot: None,
            refine: 6,
        }
    }
}

impl DiagnoseOptions {
    fn validate(&self) -> Result<()> {
        if self.permutations < 19 || !(self.fdr > 0.0 && self.fdr < 1.0) || self.min_gain < 0.0 {
            return Err(Error::InvalidParameter(
                "diagnose needs ≥ 19 permutations, 0 < fdr < 1 and min_gain ≥ 0".into(),
            ));
        }
        self.kriging.validate()
    }
}

/// CV statistics of one model.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CvStats {
    /// Per-axis RMSE of the out-of-fold residuals, mm.
    pub cv_rmse_mm: [f64; 3],
    /// RMSE pooled over the axes, mm.
    pub pooled_rmse_mm: f64,
    /// Mean of the out-of-fold 3D error |δ − δ̂|, mm.
    pub mean_3d_mm: f64,
    /// Largest out-of-fold 3D error |δ − δ̂|, mm.
    pub max_3d_mm: f64,
    /// Extra inputs of the model.
    pub extras: Vec<String>,
    /// Out-of-fold residuals δ − δ̂ (mm), measurement order; not serialised.
    #[serde(skip)]
    pub residuals: Vec<[f64; 3]>,
}

fn cv_stats(residuals: Vec<[f64; 3]>, extras: &[Feature]) -> CvStats {
    let s = summarize(&residuals);
    CvStats {
        cv_rmse_mm: s.rms_mm,
        pooled_rmse_mm: (s.rms_mm.iter().map(|v| v * v).sum::<f64>() / 3.0).sqrt(),
        mean_3d_mm: s.mean_3d_mm,
        max_3d_mm: s.max_3d_mm,
        extras: extras.iter().flat_map(Feature::names).collect(),
        residuals,
    }
}

/// One candidate as ranked in one round.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct EffectReport {
    /// Round of the loop (1-based) in which it was ranked.
    pub round: usize,
    /// What kind of effect the candidate is.
    pub kind: EffectKind,
    /// Column(s) or joint(s) it comes from, e.g. `["temp_c"]`, `["q2"]`, `["row"]`.
    pub source: Vec<String>,
    /// Short description, e.g. "temp_c × joint angles".
    pub label: String,
    /// Parameters of the best grid point (e.g. `period_deg`, `row`).
    pub params: BTreeMap<String, f64>,
    /// Out of sample: relative drop of the closed-form K-fold CV squared
    /// error with the candidate in the trend ([`gls`]).
    pub score: f64,
    /// Leave-one-out gain of the best grid point as a share of the model's
    /// leave-one-out squared error (the test statistic, relative).
    pub explained: f64,
    /// Sign-flip test p-value `(1 + exceedances) / (1 + resamples)`, before the
    /// multiple-testing correction.
    pub p_value: f64,
    /// Benjamini–Hochberg adjusted p-value.
    pub q_value: f64,
    /// Counted as a discovery: q-value within `fdr` and a closed-form CV drop
    /// of at least `min_gain`; a candidate tested at re-estimated ξ loses it
    /// when the refit CV does not confirm the drop.
    pub significant: bool,
    /// Added to the model (significant, best of its round, and it lowered the CV RMSE).
    pub accepted: bool,
    /// Other significant candidates of the round that explain nearly the same
    /// residual component (cosine ≥ 0.9) with a score within 20 % of this
    /// one: the data cannot tell them apart (e.g. payload blocks and time).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confounded_with: Vec<String>,
    /// Why a significant best candidate was not kept, or why a candidate
    /// with q within the FDR is not counted as significant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Tested at the correlation parameters refitted with the candidate in
    /// the trend (the strongest few of a round), else at the model's own.
    #[serde(default)]
    pub refit_xi: bool,
    /// Sign-flip resamples run before its p-value settled.
    #[serde(default)]
    pub resamples: usize,
    /// What would be added to the model if it were accepted; not serialised.
    #[serde(skip)]
    pub add: Vec<Feature>,
}

impl EffectReport {
    /// The variable this effect is traced to, with its label and its value
    /// on every row of `data` (the x axis of a residual plot): the phase of
    /// a harmonic, the row for a drift or a step, the covariate, or the
    /// feature's first column. Empty when nothing would be added.
    pub fn traced_variable(&self, data: &Dataset) -> (String, Vec<f64>) {
        match self.add.first() {
            Some(Feature::Harmonic { joint, period_deg }) => (
                format!("phase of q{joint} in its {period_deg:.3}° period (deg)"),
                data.q
                    .iter()
                    .map(|r| r[joint - 1].rem_euclid(*period_deg))
                    .collect(),
            ),
            Some(Feature::Row | Feature::Step { .. }) => (
                "measurement order (row)".into(),
                (0..data.len()).map(|i| i as f64).collect(),
            ),
            Some(f @ Feature::Covariate { name, .. }) => (
                name.clone(),
                f.columns(data).map(|c| c[0].clone()).unwrap_or_default(),
            ),
            Some(f) => (
                f.names()[0].clone(),
                f.columns_from_poses(&data.q, &data.dir)
                    .map(|c| c[0].clone())
                    .unwrap_or_default(),
            ),
            None => (String::new(), Vec::new()),
        }
    }
}

/// The result of [`diagnose`].
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Input space of the models.
    pub space: Space,
    /// Number of CV folds K.
    pub folds: usize,
    /// Seed of the fold partition and of the resamples.
    pub seed: u64,
    /// Most sign-flip resamples per candidate.
    pub permutations: usize,
    /// False-discovery rate of the Benjamini–Hochberg step.
    pub fdr: f64,
    /// CV statistics of the model as given (no extra input).
    pub before: CvStats,
    /// CV statistics of the final model (equal to `before` when nothing was added).
    pub after: CvStats,
    /// CV statistics after each accepted effect, in order.
    pub steps: Vec<CvStats>,
    /// Every candidate of every round, each round ranked by score.
    pub effects: Vec<EffectReport>,
    /// Extra inputs of the final model.
    pub extras: Vec<Feature>,
    /// Covariates left out of the candidates because they do not vary over
    /// the rows used ([`scan::constant_covariate`]).
    #[serde(default)]
    pub dropped_covariates: Vec<scan::DroppedCovariate>,
    /// Wall-clock time of the whole diagnosis, seconds.
    pub seconds: f64,
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
/// hyperparameters and curvature ([`KrigingOptions::warm_start`]): a fold
/// holds 90 % of the rows, so its optimum lies in the same basin, and the
/// multistart would find it again at several times the cost. With `from`
/// (the current model) and the same correlation inputs — the candidate adds
/// trend terms only — the full fit too is a local search from `from`, so
/// that the model with the effect is compared with the model without it in
/// the same basin of the multimodal likelihood (the candidate was found
/// there: [`gls::refit_systems`]).
fn cross_validated(
    data: &Dataset,
    extras: &[Feature],
    o: &DiagnoseOptions,
    from: Option<&ErrorModel>,
) -> Result<(CvStats, ErrorModel)> {
    let work = with_columns(data, extras)?;
    let same_inputs = |m: &&ErrorModel| {
        crate::features::correlation_dims(&m.extras) == crate::features::correlation_dims(extras)
    };
    let start = KrigingOptions {
        warm_start: from
            .filter(same_inputs)
            .map(ErrorModel::warm_starts)
            .unwrap_or_default(),
        ..o.kriging.clone()
    };
    let model = ErrorModel::fit_with_extras(&work, o.space, &start, extras)?;
    let warm = KrigingOptions {
        warm_start: model.warm_starts(),
        ..o.kriging.clone()
    };
    let res = cross_validate_refit(&work, o.folds, o.seed, |train| {
        ErrorModel::fit_with_extras(train, o.space, &warm, extras)
    })?;
    Ok((cv_stats(res.residuals, extras), model))
}

/// The base model a diagnosis starts from, by name: `ejs` (the default)
/// and `js` (BFGS with the options' nugget), or the papers' `js-hj`,
/// `ejs-hj`, `ejs-gps`. Returns its space and optimiser.
pub fn base_method(name: &str) -> Result<(Space, crate::kriging::OptimizerKind)> {
    use crate::kriging::OptimizerKind;
    Ok(match name {
        "ejs" => (Space::Ejs, OptimizerKind::Bfgs),
        "js" => (Space::Js, OptimizerKind::Bfgs),
        "js-hj" => (Space::Js, OptimizerKind::HookeJeeves),
        "ejs-hj" => (Space::Ejs, OptimizerKind::HookeJeeves),
        "ejs-gps" => (Space::Ejs, OptimizerKind::Gps),
        other => {
            return Err(Error::InvalidParameter(format!(
                "diagnose supports the base methods ejs, js, js-hj, ejs-hj or ejs-gps, not '{other}'"
            )));
        }
    })
}

/// The model of `data` with `extras` as inputs, fitted with the options of
/// `o` (after a diagnosis: its improved model, `extras` = [`Diagnosis::extras`];
/// with no extras: the model as it was).
pub fn fit_with_effects(
    data: &Dataset,
    o: &DiagnoseOptions,
    extras: &[Feature],
) -> Result<ErrorModel> {
    let work = with_columns(data, extras)?;
    crate::params::ErrorModelParams::new()
        .space(o.space)
        .kriging(o.kriging.clone())
        .extras(extras.to_vec())
        .check()?
        .fit(&work)
}

/// Run the loop on `data` (which needs `ex,ey,ez`). `progress` receives one
/// line per step.
///
/// ```no_run
/// use robokrige::{dataset::read_csv, diagnose::{DiagnoseOptions, diagnose}};
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_tracker_step.csv");
/// let data = read_csv(path.as_ref())?;
/// let found = diagnose(&data, &DiagnoseOptions::default(), &|line| eprintln!("{line}"))?;
/// for e in found.effects.iter().filter(|e| e.accepted) {
///     println!("added {} (q {:.4})", e.label, e.q_value); // the step at row 150
/// }
/// # Ok::<(), robokrige::Error>(())
/// ```
pub fn diagnose(data: &Dataset, o: &DiagnoseOptions, progress: &dyn Fn(&str)) -> Result<Diagnosis> {
    o.validate()?;
    let t0 = std::time::Instant::now();
    let errors = data.errors_or_err()?;
    // CV RMSE drop `min_gain` as a relative drop of the SSE (the score)
    let min_score = 1.0 - (1.0 - o.min_gain).powi(2);
    let fold = kfold_partition(data.len(), o.folds, o.seed)?;
    progress("cross-validating the current model");
    let (before, mut model) = cross_validated(data, &[], o, None)?;
    let mut current = before.clone();
    let mut extras: Vec<Feature> = Vec::new();
    let mut steps = Vec::new();
    let mut effects = Vec::new();
    for round in 1..=o.max_effects + 1 {
        let used: Vec<String> = extras
            .iter()
            .filter_map(|f| match f {
                Feature::Covariate { name, .. } => Some(name.clone()),
                _ => None,
            })
            .collect();
        let fams = scan::families(data, &used, o.robot.as_ref());
        progress(&format!(
            "round {round}: testing {} candidate effects with {} permutations",
            fams.len(),
            o.permutations
        ));
        let systems: Vec<gls::AxisSystem> = model
            .outputs
            .iter()
            .map(gls::AxisSystem::new)
            .collect::<Result<_>>()?;
        let refit = |cols: &[Vec<f64>]| gls::refit_systems(&model, errors, &o.kriging, cols).ok();
        let mut tested = scan::test_families(
            &fams,
            systems,
            o.permutations,
            o.seed,
            &fold,
            o.refine,
            &refit,
            progress,
        );
        tested.sort_by(|a, b| {
            b.score
                .total_cmp(&a.score)
                .then(a.p_value.total_cmp(&b.p_value))
        });
        let mut reports: Vec<EffectReport> = tested
            .iter()
            .map(|t| {
                let f = &fams[t.family];
                let g = &f.grid[t.best];
                EffectReport {
                    round,
                    kind: f.kind,
                    source: f.source.clone(),
                    label: f.label.clone(),
                    params: g.params.clone(),
                    score: t.score,
                    explained: t.explained,
                    p_value: t.p_value,
                    q_value: t.q_value,
                    significant: t.q_value <= o.fdr && t.score >= min_score,
                    accepted: false,
                    confounded_with: Vec::new(),
                    note: (t.q_value <= o.fdr && t.score < min_score).then(|| {
                        format!(
                            "q within the FDR, but it would lower the CV RMSE by only {:.1} % (closed form), under the {:.0} % that counts",
                            100.0 * (1.0 - (1.0 - t.score.max(0.0)).sqrt()),
                            100.0 * o.min_gain
                        )
                    }),
                    refit_xi: t.refit,
                    resamples: t.resamples,
                    add: g.add.clone(),
                }
            })
            .collect();
        let pick = reports.iter().position(|r| r.significant && r.score > 0.0);
        if let Some(k) = pick {
            // `reports` is in the order of `tested`
            let cols = |i: usize| &fams[tested[i].family].grid[tested[i].best].columns;
            let top_fit = scan::fitted(cols(k), &current.residuals);
            let top_score = reports[k].score;
            let similar: Vec<String> = (0..reports.len())
                .filter(|&i| {
                    i != k && reports[i].significant && reports[i].score >= 0.8 * top_score
                })
                .filter(|&i| {
                    scan::similarity(&top_fit, &scan::fitted(cols(i), &current.residuals)) >= 0.9
                })
                .map(|i| format!("{} (score {:.3})", reports[i].label, reports[i].score))
                .collect();
            reports[k].confounded_with = similar;
        }
        // the best significant candidates in turn, until the refit CV
        // confirms one (at most CONFIRMATIONS per round)
        let mut done = true;
        let mut next_model = None;
        let order: Vec<usize> = (0..reports.len())
            .filter(|&i| reports[i].significant && reports[i].score > 0.0)
            .take(CONFIRMATIONS)
            .collect();
        for k in order {
            if round > o.max_effects {
                reports[k].note = Some(format!("not added: the cap of {} effects", o.max_effects));
                break;
            }
            let mut trial = extras.clone();
            for f in &reports[k].add {
                if !trial.contains(f) {
                    trial.push(f.clone());
                }
            }
            progress(&format!(
                "adding '{}' and cross-validating again",
                reports[k].label
            ));
            let (after, trial_model) = cross_validated(data, &trial, o, Some(&model))?;
            if after.pooled_rmse_mm <= (1.0 - o.min_gain) * current.pooled_rmse_mm {
                reports[k].accepted = true;
                extras = trial;
                next_model = Some(trial_model);
                current = after.clone();
                steps.push(after);
                done = false;
                break;
            }
            let drop = format!(
                "CV RMSE {:.4} → {:.4} mm, less than the required {:.0} % drop",
                current.pooled_rmse_mm,
                after.pooled_rmse_mm,
                100.0 * o.min_gain
            );
            if reports[k].refit_xi {
                // its statistic came from ξ re-estimated on these data, whose
                // null is optimistic: without the refit CV's confirmation it
                // does not count
                reports[k].significant = false;
                reports[k].note = Some(format!(
                    "significant only at the ξ re-estimated with it, and the refit CV does not confirm it: {drop}"
                ));
            } else {
                reports[k].note = Some(format!("not added: {drop}"));
            }
        }
        effects.extend(reports);
        if done {
            break;
        }
        model = next_model.expect("an accepted effect has its model");
    }
    Ok(Diagnosis {
        space: o.space,
        folds: o.folds,
        seed: o.seed,
        permutations: o.permutations,
        fdr: o.fdr,
        before,
        after: current,
        steps,
        effects,
        extras,
        dropped_covariates: scan::dropped_covariates(data, &[]),
        seconds: t0.elapsed().as_secs_f64(),
    })
}
