//! What a diagnosis reports: the CV statistics of each model compared
//! ([`CvStats`]), every candidate of every round ([`EffectReport`]: its
//! test, its score, its confounders, the size of an added effect as
//! trend coefficients with 95 % intervals, [`Coefficient`], and its
//! "after" check, [`AfterCheck`]), and the whole result ([`Diagnosis`]);
//! with the helpers that fill a candidate's report from its test (the
//! support interval of its scanned parameters, its coefficients, its note).

use super::scan::{self, EffectKind};
use crate::cv::CvMode;
use crate::dataset::Dataset;
use crate::features::Feature;
use crate::model::ErrorModel;
use crate::space::Space;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

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
    /// The model's noise standard deviation per axis (mm), from its nugget
    /// ([`ErrorModel::noise_std`]).
    #[serde(default)]
    pub noise_mm: [f64; 3],
    /// How the folds were predicted ([`crate::cv::CvResult::mode`]):
    /// refit, or closed form above [`DiagnoseOptions::refit_rows`](super::DiagnoseOptions::refit_rows).
    #[serde(default)]
    pub mode: CvMode,
    /// Closed-form CV only: the model's own expectation of its
    /// leave-one-out RMSE per axis on all rows, mm
    /// ([`crate::cv::CvResult::expected_loo_rmse_mm`]).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub expected_loo_rmse_mm: Option<[f64; 3]>,
    /// Out-of-fold residuals δ − δ̂ (mm), measurement order; not serialised.
    #[serde(skip)]
    pub residuals: Vec<[f64; 3]>,
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
    /// A 95 % support interval of each scanned parameter: the range over
    /// the grid points whose leave-one-out gain is within `χ²₁(95 %)` times
    /// the model's expected leave-one-out variance of the best (for a step,
    /// the rows it may be at).
    #[serde(default, skip_serializing_if = "BTreeMap::is_empty")]
    pub params_ci: BTreeMap<String, [f64; 2]>,
    /// Out of sample: relative drop of the closed-form K-fold CV squared
    /// error with the candidate in the trend ([`gls`](super::gls)).
    pub score: f64,
    /// Leave-one-out gain of the best grid point as a share of the model's
    /// leave-one-out squared error (the test statistic, relative).
    pub explained: f64,
    /// Sign-flip test p-value `(1 + exceedances) / (1 + resamples)`, before the
    /// multiple-testing correction.
    pub p_value: f64,
    /// The statistic beyond what scanning its grid finds by chance (minus
    /// its null distribution's mean), as a share of the model's leave-one-out
    /// SSE: the ranking of significant candidates.
    #[serde(default)]
    pub evidence: f64,
    /// Benjamini–Hochberg adjusted p-value.
    pub q_value: f64,
    /// Counted as a discovery: q-value within `fdr` and a closed-form CV drop
    /// of at least `min_gain`; a candidate tested at re-estimated ξ loses it
    /// when the refit CV does not confirm the drop.
    pub significant: bool,
    /// Added to the model (significant, best of its round, and it lowered the CV RMSE).
    pub accepted: bool,
    /// Other candidates this one is not separable from on this campaign,
    /// each with its score, evidence and the correlation of the two fitted
    /// contributions (a competing explanation: a step and a drift over the
    /// order, a covariate and a step at its jump, …; the measure:
    /// `diagnose::confound`), and for a step or block of rows the region
    /// of the joint space its rows were measured in, when they were.
    /// Filled for the candidates a round compares for adding, and for a
    /// significant candidate left out by the cap. An added effect also
    /// names the candidates it explained away: its columns take at least
    /// half of what they fit, and they were significant before it was
    /// added, not after, with at most half their evidence left.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confounded_with: Vec<String>,
    /// What it adds on the refitted model: the drop (share) of the pooled
    /// closed-form K-fold CV RMSE with it in the model, its hyperparameters
    /// re-estimated. Measured for the candidates a round compares for
    /// adding (the best significant one of each kind, the order's drift,
    /// step and block apart), which are tried in this order.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refit_gain: Option<f64>,
    /// Why a significant best candidate was not kept, or why a candidate
    /// with q within the FDR is not counted as significant.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub note: Option<String>,
    /// Scored at the correlation parameters refitted with the candidate in
    /// the trend (the strongest few of a round), else at the model's own;
    /// its p-value is the model's own but for a kind the GP can soak up
    /// ([`EffectKind::pose_function`]).
    #[serde(default)]
    pub refit_xi: bool,
    /// Sign-flip resamples run before its p-value settled.
    #[serde(default)]
    pub resamples: usize,
    /// For an added effect: its trend coefficients with 95 % intervals
    /// (the size of a step in mm, the share of a move left as lag, …).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub size: Vec<Coefficient>,
    /// For an added effect: how much of what it promised the refit model
    /// delivers, and how close the CV RMSE came to the model's own level.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub after_check: Option<AfterCheck>,
    /// What would be added to the model if it were accepted; not serialised.
    #[serde(skip)]
    pub add: Vec<Feature>,
}

/// One trend coefficient of an added effect, per axis: the GLS estimate
/// and its 95 % interval (± 1.96 standard errors, [`ErrorModel::trend_coefficient`]),
/// in mm per unit of the column (for a step, the step in mm).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Coefficient {
    /// The model's input column, e.g. `step@150`.
    pub column: String,
    /// Estimate per axis (x, y, z).
    pub estimate: [f64; 3],
    /// Half-width of the 95 % interval per axis.
    pub ci95: [f64; 3],
    /// The one output axis the column is a regressor of (0, 1, 2 for x, y,
    /// z: a row of the Jacobian, [`Feature::column_axes`]); the estimate
    /// and interval of the other axes are then 0. `None`: every axis.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub axis: Option<usize>,
}

/// The "after" check of an added effect: did the model with it
/// reach the level of a campaign without it?
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AfterCheck {
    /// Drop of the pooled CV RMSE the closed-form test promised (share).
    pub promised: f64,
    /// Drop of the pooled CV RMSE the refit model reached (share).
    pub achieved: f64,
    /// CV RMSE of the model with the effect, per axis (mm).
    pub cv_rmse_mm: [f64; 3],
    /// The level a campaign without the effect would reach, estimated from
    /// the data: the refit model's own expectation of its leave-one-out
    /// error, its nugget's noise plus its interpolation error, per axis (mm).
    pub level_mm: [f64; 3],
    /// The nugget's noise alone, per axis (mm).
    pub noise_mm: [f64; 3],
    /// Only partly modelled: it delivers under half of what it promised,
    /// the CV RMSE stays above 1.3× the level, or a candidate of the same
    /// source is still significant in the next round.
    pub partly: bool,
    /// The verdict in words.
    pub verdict: String,
}

impl EffectReport {
    /// The variable this effect is traced to, with its label and its value
    /// on every row of `data` (the x axis of a residual plot): the phase of
    /// a harmonic, the row for a drift or a step, the covariate, or the
    /// feature's first column. Empty when nothing would be added.
    pub fn traced_variable(&self, data: &Dataset) -> (String, Vec<f64>) {
        match self.add.first() {
            Some(
                Feature::Harmonic {
                    joint,
                    period_deg,
                    centre_deg,
                }
                | Feature::HarmonicJacobian {
                    joint,
                    period_deg,
                    centre_deg,
                    ..
                },
            ) => (
                format!(
                    "phase of q{joint} from {centre_deg:.2}° in its {period_deg:.3}° period (deg)"
                ),
                data.q
                    .iter()
                    .map(|r| (r[joint - 1] - centre_deg).rem_euclid(*period_deg))
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

/// Parameters as they follow a label in a report: " (name value, …)"
/// with three decimals, or nothing when there are none.
pub fn params_text(params: &BTreeMap<String, f64>) -> String {
    let params: Vec<String> = params.iter().map(|(k, v)| format!("{k} {v:.3}")).collect();
    if params.is_empty() {
        String::new()
    } else {
        format!(" ({})", params.join(", "))
    }
}

/// The result of [`diagnose`](super::diagnose).
#[derive(Debug, Clone, Serialize, Deserialize)]
pub struct Diagnosis {
    /// Input space of the models.
    pub space: Space,
    /// Number of CV folds K.
    pub folds: usize,
    /// Seed of the fold partition and of the resamples.
    pub seed: u64,
    /// Most sign-flip resamples per candidate, as used (the option, raised
    /// to [`min_resamples`](super::min_resamples) of the largest round when lower).
    pub permutations: usize,
    /// Candidate families tested in the first round, and the grid points
    /// (parameter values) they scan in all: the multiple testing the
    /// false-discovery control pays for.
    #[serde(default)]
    pub candidates: [usize; 2],
    /// False-discovery rate of the Benjamini–Hochberg step.
    pub fdr: f64,
    /// CV statistics of the model as given (no extra input).
    pub before: CvStats,
    /// CV statistics of the final model (equal to `before` when nothing was added).
    pub after: CvStats,
    /// CV statistics after each accepted effect, in order.
    pub steps: Vec<CvStats>,
    /// Every candidate of every round, each round ranked: the significant
    /// ones by evidence, then the others by score.
    pub effects: Vec<EffectReport>,
    /// Extra inputs of the final model.
    pub extras: Vec<Feature>,
    /// Rows of the campaign (every model compared was fitted and
    /// cross-validated on all of them; 0 in reports written before it was
    /// recorded).
    #[serde(default)]
    pub rows: usize,
    /// Rows the candidate test scanned ([`DiagnoseOptions::scan_rows`](super::DiagnoseOptions::scan_rows)):
    /// all `rows`, or an evenly spread subset of them, on which every
    /// candidate's statistic, p-value, score and evidence were computed
    /// (0 in reports written before it was recorded: all).
    #[serde(default)]
    pub scanned_rows: usize,
    /// Covariates left out of the candidates because they do not vary over
    /// the rows used ([`scan::constant_covariate`]).
    #[serde(default)]
    pub dropped_covariates: Vec<scan::DroppedCovariate>,
    /// Significant candidates left when the cap of effects
    /// (`max_effects`) was reached, with what each would add: empty when
    /// the loop stopped on its own.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub left_by_cap: Vec<LeftOut>,
    /// How far the measurement order follows the joint space
    /// ([`super::OrderInJointSpace`]): where it does, an order effect is not
    /// separable from an effect of the pose (`None`: too few rows, or a
    /// report written before it was measured).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub order_in_joint_space: Option<super::OrderInJointSpace>,
    /// Wall-clock time of the whole diagnosis, seconds.
    pub seconds: f64,
}

/// A significant candidate the cap of effects left out, with what it would
/// add.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LeftOut {
    /// Its label (as in [`EffectReport::label`]).
    pub label: String,
    /// Its kind.
    pub kind: EffectKind,
    /// Parameters of its best grid point.
    pub params: BTreeMap<String, f64>,
    /// Its evidence ([`EffectReport::evidence`]).
    pub evidence: f64,
    /// The drop (share) of the pooled CV RMSE its closed-form test promises
    /// at the current model's hyperparameters.
    pub promised: f64,
    /// The drop (share) on the refitted model ([`EffectReport::refit_gain`]),
    /// when it was measured.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub refit_gain: Option<f64>,
    /// The candidates it is not separable from ([`EffectReport::confounded_with`]).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub confounded_with: Vec<String>,
}

impl LeftOut {
    /// The entry of a candidate's report.
    pub(super) fn of(r: &EffectReport) -> Self {
        LeftOut {
            label: r.label.clone(),
            kind: r.kind,
            params: r.params.clone(),
            evidence: r.evidence,
            promised: 1.0 - (1.0 - r.score.clamp(0.0, 1.0)).sqrt(),
            refit_gain: r.refit_gain,
            confounded_with: r.confounded_with.clone(),
        }
    }
}

impl Diagnosis {
    /// How every CV of the diagnosis was run ([`CvStats::mode`]).
    pub fn cv_mode(&self) -> CvMode {
        self.before.mode
    }
}

/// The range of every parameter over the grid points of a support set (their
/// parameters).
pub(super) fn support_interval<'a>(
    support: impl IntoIterator<Item = &'a BTreeMap<String, f64>>,
) -> BTreeMap<String, [f64; 2]> {
    let mut out: BTreeMap<String, [f64; 2]> = BTreeMap::new();
    for params in support {
        for (k, v) in params {
            let e = out.entry(k.clone()).or_insert([*v, *v]);
            e[0] = e[0].min(*v);
            e[1] = e[1].max(*v);
        }
    }
    out
}

/// The trend coefficients of the columns `add` brings, with 95 % intervals.
pub(super) fn coefficients(model: &ErrorModel, add: &[Feature]) -> Vec<Coefficient> {
    add.iter()
        .flat_map(|f| f.names().into_iter().zip(f.column_axes()))
        .filter_map(|(column, axis)| {
            let c = model.trend_coefficient(&column)?;
            Some(Coefficient {
                estimate: c.map(|(b, _)| b),
                ci95: c.map(|(_, se)| crate::stats::Z95 * se),
                column,
                axis,
            })
        })
        .collect()
}

impl EffectReport {
    /// The rows of the steps this candidate adds: one for a step, two for a
    /// block of rows (its edges), none for any other kind.
    pub fn change_point_rows(&self) -> Vec<usize> {
        self.add
            .iter()
            .filter_map(|f| match f {
                Feature::Step { row } => Some(*row),
                _ => None,
            })
            .collect()
    }
}

impl EffectReport {
    /// Add `text` to the report's note (after any note it has: "ranked
    /// before …; not added: …").
    pub(super) fn add_note(&mut self, text: String) {
        self.note = Some(match self.note.take() {
            Some(n) => format!("{n}; {text}"),
            None => text,
        });
    }
}
