//! The correlation family of a fit ([`CorrChoice`]: fixed, or chosen per
//! output), and its choice by closed-form K-fold cross-validation
//! ([`CorrChoice::ByCv`]).
//!
//! The families of [`Correlation::ALL`] are tried from the smoothest to the
//! roughest (Gaussian, Matérn 5/2, Matérn 3/2, exponential). Each is fitted
//! by maximum likelihood — the Gaussian by the full search of the options
//! (or from the caller's warm start), the others by a local BFGS from the
//! Gaussian's ξ, ν and inverse Hessian, which costs a fraction of a search —
//! and scored by the RMSE of its closed-form leave-fold-out residuals
//! ([`KrigingModel::held_out_residuals`]: ξ and ν held at the fitted
//! values, β re-estimated without the fold), on the same [`FAMILY_FOLDS`]
//! folds for every family. The lowest RMSE wins; ties go to the smoother
//! family. Likelihoods are not compared: families with different
//! smoothness do not share a scale of ln ψ that predicts held-out error.
//!
//! **Stopping early.** The rule assumes that the CV error, as a function of
//! the family's smoothness, falls to the smoothness the data support and
//! rises beyond it (one minimum): once a rougher family scores worse than
//! the best so far, the rougher ones after it are not fitted. On the bench
//! campaigns it chose the same families as trying all
//! four. With a nugget this usually stops after Matérn
//! 5/2 (the noise, not the roughness, is what the Gaussian lacked); without
//! one, an interpolator on noisy data keeps improving down to Matérn 3/2 or
//! the exponential, and all four are tried. The report lists the families
//! tried.
//!
//! **Large campaigns.** Over [`SEARCH_ROWS`] rows (BFGS, no warm start) the
//! choice is made on the search stage's own seeded subset of
//! [`SEARCH_ROWS`] rows — the same subset and the same multistart as the
//! Gaussian-only fit — and only the chosen family converges on all rows,
//! from its subset optimum: one full-data convergence per output, as with a
//! single family.

use serde::{Deserialize, Serialize};

use super::fit::Job;
use super::{
    Correlation, FitReport, Hyperparameters, KrigingModel, OptimizerKind, SEARCH_ROWS, row_subset,
};
use crate::{Error, Result};

/// Folds of the family choice by default ([`CorrChoice::ByCv`];
/// fewer when there are fewer rows).
pub const FAMILY_FOLDS: usize = 10;

/// The correlation family of a fit, or how it is chosen.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
#[non_exhaustive]
pub enum CorrChoice {
    /// This family on every output.
    Fixed(Correlation),
    /// Each output's family chosen by closed-form `folds`-fold
    /// cross-validation among [`Correlation::ALL`] (smoothest first; the
    /// `family` module docs give the rule and its early stop).
    ByCv {
        /// CV folds of the choice (fewer when there are fewer rows).
        folds: usize,
    },
}

/// `--corr`: a family by its name, or `auto`, the choice by CV with
/// [`FAMILY_FOLDS`] folds ([`CorrChoice::from_name`]'s names).
#[cfg(feature = "cli")]
impl clap::ValueEnum for CorrChoice {
    fn value_variants<'a>() -> &'a [Self] {
        &[
            CorrChoice::Fixed(Correlation::Gaussian),
            CorrChoice::Fixed(Correlation::Matern52),
            CorrChoice::Fixed(Correlation::Matern32),
            CorrChoice::Fixed(Correlation::Exponential),
            CorrChoice::AUTO,
        ]
    }

    fn to_possible_value(&self) -> Option<clap::builder::PossibleValue> {
        let (name, help) = match *self {
            CorrChoice::Fixed(c) => (
                c.name(),
                match c {
                    Correlation::Gaussian => "exp(−h²), seed 003 eq 8 (the papers')",
                    Correlation::Matern52 => "Matérn ν = 5/2",
                    Correlation::Matern32 => "Matérn ν = 3/2",
                    Correlation::Exponential => "exp(−h) (Matérn ν = 1/2)",
                    // a registered family is the library's, not a --corr value
                    Correlation::Custom(_) => return None,
                },
            ),
            CorrChoice::AUTO => (
                "auto",
                "Each output's family chosen by closed-form 10-fold CV among the four",
            ),
            CorrChoice::ByCv { .. } => return None,
        };
        Some(clap::builder::PossibleValue::new(name).help(help))
    }
}

impl CorrChoice {
    /// `auto`: each output's family by closed-form CV with [`FAMILY_FOLDS`]
    /// folds (the `recommended` method's, the command line's default).
    pub const AUTO: CorrChoice = CorrChoice::ByCv {
        folds: FAMILY_FOLDS,
    };

    /// The family when it is fixed.
    pub fn fixed(self) -> Option<Correlation> {
        match self {
            CorrChoice::Fixed(c) => Some(c),
            CorrChoice::ByCv { .. } => None,
        }
    }

    /// Whether the family is chosen by CV.
    pub fn is_by_cv(self) -> bool {
        matches!(self, CorrChoice::ByCv { .. })
    }

    /// `auto` (the choice by CV with [`FAMILY_FOLDS`] folds) or a family's
    /// name ([`Correlation::name`]), as on the command line; an error naming
    /// the choices otherwise.
    pub fn from_name(name: &str) -> Result<CorrChoice> {
        match name {
            "auto" => Ok(CorrChoice::AUTO),
            _ => Correlation::parse(name).map(CorrChoice::Fixed).ok_or_else(|| {
                Error::InvalidParameter(format!(
                    "corr '{name}': expected 'auto', 'gaussian', 'matern52', 'matern32' or 'exponential'"
                ))
            }),
        }
    }
}

impl From<Correlation> for CorrChoice {
    fn from(c: Correlation) -> Self {
        CorrChoice::Fixed(c)
    }
}

impl std::fmt::Display for CorrChoice {
    /// `auto` or the family's name.
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            CorrChoice::Fixed(c) => c.fmt(f),
            CorrChoice::ByCv { .. } => f.write_str("auto"),
        }
    }
}

/// One family's score in a choice.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FamilyScore {
    /// The family.
    pub corr: Correlation,
    /// ln ψ at its fitted ξ, ν.
    pub ln_psi: f64,
    /// RMSE of the closed-form K-fold residuals, output units; ∞ when the
    /// family's fit or residuals failed.
    pub cv_rmse: f64,
    /// Rows the score was computed on: all of them, or the search subset
    /// of a large campaign (0 in files written before it was recorded).
    #[serde(default)]
    pub rows: usize,
}

/// Fit one output with the families in order of smoothness and keep the
/// best by closed-form `folds`-fold CV (see the module docs for the order,
/// the early stop and large campaigns). The report lists the scores
/// ([`FitReport::families`]), and its evaluations and seconds are those of
/// the whole choice. `start`: the Gaussian's warm start.
pub(super) fn choose_by_cv(
    job: &Job,
    folds: usize,
    start: Option<&Hyperparameters>,
) -> Result<(KrigingModel, FitReport)> {
    let m = job.y.len();
    if m > SEARCH_ROWS && start.is_none() && job.opts.optimizer == OptimizerKind::Bfgs {
        return choose_on_subset(job, folds);
    }
    let t0 = std::time::Instant::now();
    let first = job.search(Correlation::Gaussian, start)?;
    let k = folds.min(m);
    let blocks = crate::stats::fold_blocks(&crate::stats::kfold_partition(m, k, job.opts.seed)?);
    let score = |model: &KrigingModel| -> f64 {
        model
            .held_out_residuals(&blocks)
            .map_or(f64::INFINITY, |e| {
                let s = (e.iter().map(|v| v * v).sum::<f64>() / m as f64).sqrt();
                if s.is_finite() { s } else { f64::INFINITY }
            })
    };
    let warm = Hyperparameters::of(&first.1, job.inputs.d);
    let mut table = vec![FamilyScore {
        corr: Correlation::Gaussian,
        ln_psi: first.1.ln_psi,
        cv_rmse: score(&first.0),
        rows: m,
    }];
    let mut evals = first.1.evals;
    let mut best = first;
    let mut best_rmse = table[0].cv_rmse;
    for corr in Correlation::ALL.into_iter().skip(1) {
        // a family whose fit fails scores ∞ (and stops the search)
        let fit = job.search(corr, Some(&warm)).ok();
        let (ln_psi, rmse) = fit
            .as_ref()
            .map_or((f64::NAN, f64::INFINITY), |f| (f.1.ln_psi, score(&f.0)));
        evals += fit.as_ref().map_or(0, |f| f.1.evals);
        table.push(FamilyScore {
            corr,
            ln_psi,
            cv_rmse: rmse,
            rows: m,
        });
        match fit {
            Some(f) if rmse < best_rmse => {
                best_rmse = rmse;
                best = f;
            }
            // rougher than the best and worse: the rougher ones are not tried
            _ if rmse > best_rmse => break,
            _ => {}
        }
    }
    // a family's search cancelled above scored ∞: the choice is not made
    job.opts.cancel.check()?;
    // the report counts the whole choice, not only the winner's search
    best.1.families = table;
    best.1.evals = evals;
    best.1.seconds = t0.elapsed().as_secs_f64();
    Ok(best)
}

/// The choice on the search subset of a large campaign, then the chosen
/// family converged on all rows from its subset optimum.
fn choose_on_subset(job: &Job, folds: usize) -> Result<(KrigingModel, FitReport)> {
    let t0 = std::time::Instant::now();
    let rows = row_subset(job.y.len(), SEARCH_ROWS, job.opts.seed);
    let (chosen, sub) = job.rows(&rows, |sub| choose_by_cv(sub, folds, None))?;
    let (model, mut report) = job.search(
        chosen.corr(),
        Some(&Hyperparameters::of(&sub, job.inputs.d)),
    )?;
    report.families = sub.families;
    report.evals += sub.evals;
    report.starts = sub.starts;
    report.seconds = t0.elapsed().as_secs_f64();
    Ok((model, report))
}
