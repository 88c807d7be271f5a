//! Choosing the correlation family of one output by closed-form K-fold
//! cross-validation (issue 17 §3).
//!
//! Each family of [`Correlation::ALL`] is fitted by maximum likelihood —
//! the Gaussian by the full search of the options (or from the caller's
//! warm start), the others by a local BFGS from the Gaussian's ξ, ν and
//! inverse Hessian, which costs a fraction of a search — and scored by the RMSE of its
//! closed-form leave-fold-out residuals
//! ([`KrigingModel::held_out_residuals`]: ξ and ν held at the fitted
//! values, β re-estimated without the fold), on the same
//! [`FAMILY_FOLDS`] folds for every family. The lowest RMSE wins; ties go
//! to the earlier family (the Gaussian first). Likelihoods are not
//! compared: families with different smoothness do not share a scale of
//! ln ψ that predicts held-out error.

use serde::{Deserialize, Serialize};

use super::{
    Correlation, FitReport, KrigingModel, KrigingOptions, TrainingInputs, Trend, WarmStart,
    fit_output_from,
};
use crate::Result;

/// Folds of the family choice (fewer when there are fewer rows).
pub const FAMILY_FOLDS: usize = 10;

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
}

/// Fit one output with every family and keep the best by closed-form
/// K-fold CV: the Gaussian by the options' full search (or from `start`),
/// the others by a local BFGS from the Gaussian's ξ, ν and inverse
/// Hessian; the lowest RMSE of the leave-fold-out residuals on
/// [`FAMILY_FOLDS`] folds wins, ties to the earlier family. The report lists the scores
/// ([`FitReport::families`]), and its evaluations and seconds are those of
/// the whole choice. Arguments as [`fit_output_from`], whose `opts.corr` is
/// ignored.
pub fn fit_output_auto(
    x: &[Vec<f64>],
    inputs: &TrainingInputs,
    y: &[f64],
    trend: &Trend,
    names: &[String],
    opts: &KrigingOptions,
    start: Option<&WarmStart>,
) -> Result<(KrigingModel, FitReport)> {
    let t0 = std::time::Instant::now();
    let gaussian = KrigingOptions {
        corr: Correlation::Gaussian,
        ..opts.clone()
    };
    let first = fit_output_from(x, inputs, y, trend, names, &gaussian, start)?;
    let m = y.len();
    let k = FAMILY_FOLDS.min(m);
    let blocks = crate::stats::fold_blocks(&crate::stats::kfold_partition(m, k, opts.seed)?);
    let score = |model: &KrigingModel| -> f64 {
        model
            .held_out_residuals(&blocks)
            .map_or(f64::INFINITY, |e| {
                let s = (e.iter().map(|v| v * v).sum::<f64>() / m as f64).sqrt();
                if s.is_finite() { s } else { f64::INFINITY }
            })
    };
    let warm = WarmStart {
        theta: first.1.theta[..inputs.d].to_vec(),
        nugget: first.1.nugget,
        inverse_hessian: first.1.inverse_hessian.clone(),
    };
    let mut table = vec![FamilyScore {
        corr: Correlation::Gaussian,
        ln_psi: first.1.ln_psi,
        cv_rmse: score(&first.0),
    }];
    let mut evals = first.1.evals;
    let mut best = first;
    let mut best_rmse = table[0].cv_rmse;
    for corr in Correlation::ALL.into_iter().skip(1) {
        let o = KrigingOptions {
            corr,
            ..opts.clone()
        };
        let Ok(fit) = fit_output_from(x, inputs, y, trend, names, &o, Some(&warm)) else {
            table.push(FamilyScore {
                corr,
                ln_psi: f64::NAN,
                cv_rmse: f64::INFINITY,
            });
            continue;
        };
        evals += fit.1.evals;
        let rmse = score(&fit.0);
        table.push(FamilyScore {
            corr,
            ln_psi: fit.1.ln_psi,
            cv_rmse: rmse,
        });
        if rmse < best_rmse {
            best_rmse = rmse;
            best = fit;
        }
    }
    // the report counts the whole choice, not only the winner's search
    best.1.families = table;
    best.1.evals = evals;
    best.1.seconds = t0.elapsed().as_secs_f64();
    Ok(best)
}
