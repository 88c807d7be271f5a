//! Close the loop: find what the model still gets wrong, trace it to an
//! effect the model lacks, add it, and report before and after.
//!
//! 1. **Residuals**: out-of-fold K-fold CV residuals of the current model
//!    (refit on every training fold), per axis, in measurement order.
//! 2. **Candidates** ([`scan::families`]): every numeric covariate not in the
//!    model (alone, interacting with the joint angles, with one joint angle,
//!    lagged); the measurement order (drift, and a change-point scan);
//!    harmonics of each joint over a scanned period range; cross-joint
//!    products; direction history; the motion into each pose (a joint's
//!    moves with a scanned memory, their size, the TCP's move, the time
//!    since the previous pose).
//! 3. **Tracing** ([`scan::test_families`], [`gls`]): each grid point is
//!    tried inside the current model (its columns join the trend at the
//!    model's ξ and nugget); a family's statistic is its best leave-one-out
//!    gain (for the strongest few at the ξ re-estimated with them), its
//!    p-value a test against sign-flipped pseudo-campaigns of the fitted
//!    model, Benjamini–Hochberg across families, and its score the
//!    closed-form K-fold CV drop.
//! 4. **Adding**: the significant families are ranked by evidence (the
//!    leave-one-out gain beyond the mean of its null distribution: what
//!    scanning its grid finds by chance is taken off), kinds of effect not
//!    yet in the model first; the best of each kind are then tried in the
//!    order of what each adds on the refitted model ([`EffectReport::refit_gain`],
//!    `choose.rs`), a measured column before an anonymous order effect it
//!    is not separable from (`confound.rs`). The first the refit CV
//!    confirms has its feature join the
//!    model the way its kind needs ([`crate::features::Feature`]): a step,
//!    harmonic, interaction or cross-talk basis as trend terms; a covariate,
//!    the order or direction history as an input dimension with a linear
//!    trend term. The model is refitted and cross-validated again (refit per
//!    fold); it is kept only if the CV RMSE drops by at least `min_gain`, or
//!    by what that is worth at the noise floor ([`Worth`]), and
//!    the loop repeats until nothing significant remains or `max_effects`
//!    (then the significant candidates left are reported with what each
//!    would add, [`Diagnosis::left_by_cap`]).
//! 5. **Report**: CV statistics before and after every accepted effect, its
//!    size (trend coefficients with 95 % intervals) and its "after" check
//!    ([`AfterCheck`]): did the model with it reach the level a campaign
//!    without it would, estimated from the data (the model's own
//!    leave-one-out expectation: its nugget's noise plus its interpolation
//!    error), and did it deliver what its test promised? The candidates it
//!    is not separable from on this campaign are named with it
//!    ([`EffectReport::confounded_with`]), and its row and coefficient
//!    intervals are those with them refitted (`profile.rs`).
//!
//! One concept a file: `options.rs` ([`DiagnoseOptions`]), `fit.rs` (the
//! models compared: the base model, a model with effects, their CV),
//! `scan/` (the candidate families, one file per kind, and the test that
//! scores them), `gls.rs` (a candidate inside the model), `rank.rs` (the
//! order of a round's candidates: evidence, Occam's rule), `confound.rs`
//! (what the campaign cannot separate), `choose.rs` (which candidate
//! joins the model, the cap's list), `profile.rs` (intervals with the
//! competing effects refitted), `regions.rs` (order effects that are
//! regions of the joint space),
//! `accept.rs` (when a drop is worth an effect; the "after" check),
//! `rounds.rs` (one round of the loop), `rows.rs` (the rows scanned),
//! `plan.rs` (the memory it needs), `report.rs` ([`Diagnosis`] and its
//! parts) and `describe.rs` (an effect in words).

mod accept;
mod choose;
mod confound;
mod describe;
mod fit;
pub mod gls;
mod options;
mod plan;
mod profile;
mod rank;
mod regions;
mod report;
mod rounds;
mod rows;
pub mod scan;

use crate::Result;
use crate::calibration::Calibration;
use crate::cv::kfold_partition;
use crate::dataset::Dataset;
pub use accept::{AFTER_LEVEL_RATIO, Worth};
pub use confound::SAME_RESIDUAL;
use fit::cross_validated;
pub use fit::{base_params, fit_with_effects, with_columns};
pub use options::{
    DEFAULT_REFIT_ROWS, DEFAULT_SCAN_ROWS, DiagnoseOptions, MIN_SCAN_ROWS, min_resamples,
};
pub use plan::DiagnosePlan;
pub use regions::{NEIGHBOURS, OrderInJointSpace, region_overlap};
pub use report::{AfterCheck, Coefficient, CvStats, Diagnosis, EffectReport, LeftOut, params_text};
pub use rows::ScanRows;
pub use scan::EffectKind;

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
    diagnose_residual(data, None, o, progress)
}

/// [`diagnose`] of `data`, the residual of `calibration` (its rows with
/// `ex,ey,ez` replaced by what the calibration leaves, as
/// [`Calibration::residual`] gives): the calibration took up whatever of an
/// effect lies in the span of the directions it saw, so each added
/// effect's coefficient intervals are computed with those directions
/// refitted beside it ([`Calibration::seen_displacements`]). `None`: a
/// diagnosis of the campaign as it is.
pub fn diagnose_residual(
    data: &Dataset,
    calibration: Option<&Calibration>,
    o: &DiagnoseOptions,
    progress: &dyn Fn(&str),
) -> Result<Diagnosis> {
    o.validate()?;
    let calibration = calibration
        .map(|c| c.seen_displacements(&data.q, &data.dir))
        .transpose()?;
    let t0 = std::time::Instant::now();
    let errors = data.errors_or_err()?;
    // the rows the candidates are scanned on (all, up to `scan_rows`), and
    // their fold partition
    let rows = ScanRows::spread(data.len(), o.scan_rows);
    let scan_fold = kfold_partition(rows.len(), o.folds, o.seed)?;
    DiagnosePlan::new(data, o).check(
        |n| format!("a subset, e.g. `Dataset::select` of {n} rows"),
        |n| format!("`DiagnoseOptions::scan_rows({n})`"),
    )?;
    // a whole campaign: every fit converges ξ on the same seeded subset
    let o = &o.for_rows(data.len());
    let scan_errors: std::borrow::Cow<[[f64; 3]]> = if rows.is_all() {
        errors.into()
    } else {
        progress(&format!(
            "scanning the candidates on {} of the {} rows, evenly spread (one in {:.1})",
            rows.len(),
            data.len(),
            data.len() as f64 / rows.len() as f64
        ));
        rows.pick(errors).into()
    };
    let campaign = rounds::Campaign {
        data,
        errors,
        rows: &rows,
        fold: &scan_fold,
        scan_errors: &scan_errors,
        calibration: calibration.as_ref(),
        o,
    };
    progress("cross-validating the current model");
    let (before, model) = cross_validated(data, &[], o, None)?;
    let mut state = rounds::Rounds::new(model, before, o.permutations);
    for round in 1..=o.max_effects + 1 {
        o.kriging.cancel.check()?;
        if !state.round(&campaign, round, progress)? {
            break;
        }
    }
    Ok(state.into_diagnosis(o, data, &rows, t0.elapsed().as_secs_f64()))
}
