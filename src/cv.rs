//! K-fold cross-validation (seed 003 eq 21; seed 004 eq 16).
//!
//! A seeded random partition of the rows into K folds of (nearly) equal size.
//! Two modes, named in every result:
//!
//! - *refit*: for each fold the model is refitted (hyperparameters
//!   re-optimised) on the other K − 1 folds and predicts the held-out fold;
//! - *closed-form*: ξ, the input normalisation and the nugget are those of one
//!   fit on all rows; each fold's residuals come from the bordered-system
//!   identity of [`KrigingModel::held_out_residuals`](crate::kriging::KrigingModel::held_out_residuals)
//!   (Dubrule 1983) — one factorisation instead of K fits.
//!
//! The out-of-fold residuals `e_cv = δ − δ̂` are returned in measurement order,
//! with their statistics.

use crate::dataset::Dataset;
use crate::model::ErrorModel;
use crate::stats::{ErrorSummary, summarize};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::time::Instant;

pub use crate::stats::kfold_partition;

/// Result of a cross-validation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CvResult {
    /// Number of folds K.
    pub folds: usize,
    /// Seed of the random fold partition ([`kfold_partition`]).
    pub seed: u64,
    /// How the folds were predicted: `"refit"` (hyperparameters re-optimised per
    /// fold) or `"closed-form"` (one fit's ξ and nugget on all rows).
    pub mode: String,
    /// Fold of every row.
    pub fold: Vec<usize>,
    /// Out-of-fold residuals δ − δ̂ (mm), measurement order.
    pub residuals: Vec<[f64; 3]>,
    /// Statistics of the residuals (RMSE per axis = `rms_mm`, eq 17).
    pub summary: ErrorSummary,
    /// Wall-clock time of the whole cross-validation, seconds.
    pub seconds: f64,
}

/// K-fold CV refitting the model on every training fold with `fit`.
///
/// ```
/// use robokrige::{cv::cross_validate_refit, dataset::read_csv};
/// use robokrige::{kriging::KrigingOptions, model::ErrorModel, space::Space};
/// let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
/// let data = read_csv(path.as_ref())?.select(&(0..60).collect::<Vec<_>>());
/// let opts = KrigingOptions::default();
/// let cv = cross_validate_refit(&data, 5, 1, |t| ErrorModel::fit(t, Space::Ejs, &opts))?;
/// assert_eq!(cv.residuals.len(), 60); // one out-of-fold residual per row
/// println!("mean 3D error {:.4} mm", cv.summary.mean_3d_mm);
/// # Ok::<(), robokrige::Error>(())
/// ```
pub fn cross_validate_refit<F>(data: &Dataset, k: usize, seed: u64, fit: F) -> Result<CvResult>
where
    F: Fn(&Dataset) -> Result<ErrorModel>,
{
    let t0 = Instant::now();
    let errors = data.errors_or_err()?;
    let fold = kfold_partition(data.len(), k, seed)?;
    let mut residuals = vec![[0.0; 3]; data.len()];
    for f in 0..k {
        let (test, train): (Vec<usize>, Vec<usize>) = (0..data.len()).partition(|&i| fold[i] == f);
        let model = fit(&data.select(&train))?;
        let held = data.select(&test);
        let pred = model.predict_dataset(&held)?;
        for (j, &i) in test.iter().enumerate() {
            for a in 0..3 {
                residuals[i][a] = errors[i][a] - pred.mean[j][a];
            }
        }
    }
    Ok(CvResult {
        folds: k,
        seed,
        mode: "refit".into(),
        summary: summarize(&residuals),
        fold,
        residuals,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

/// K-fold CV in closed form at the hyperparameters of `model`, which must
/// have been fitted on exactly the rows of `data`, in order.
pub fn cross_validate_closed_form(
    data: &Dataset,
    model: &ErrorModel,
    k: usize,
    seed: u64,
) -> Result<CvResult> {
    let t0 = Instant::now();
    data.errors_or_err()?;
    let m = data.len();
    let x = model.input_map().encode_dataset(data)?;
    if model.outputs.iter().any(|o| o.data.x_train != x) {
        return Err(Error::InvalidParameter(format!(
            "closed-form CV needs the model fitted on exactly these {m} rows, in order"
        )));
    }
    let fold = kfold_partition(m, k, seed)?;
    let blocks = crate::stats::fold_blocks(&fold);
    let mut residuals = vec![[0.0; 3]; m];
    for (a, out) in model.outputs.iter().enumerate() {
        let e = out.held_out_residuals(&blocks)?;
        for (r, v) in residuals.iter_mut().zip(e) {
            r[a] = v;
        }
    }
    Ok(CvResult {
        folds: k,
        seed,
        mode: "closed-form".into(),
        summary: summarize(&residuals),
        fold,
        residuals,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn partition_is_balanced_seeded_and_checked() {
        let f = kfold_partition(23, 5, 1).unwrap();
        let mut counts = [0; 5];
        for &x in &f {
            counts[x] += 1;
        }
        assert!(counts.iter().all(|&c| c == 4 || c == 5));
        assert_eq!(f, kfold_partition(23, 5, 1).unwrap());
        assert_ne!(f, kfold_partition(23, 5, 2).unwrap());
        assert!(kfold_partition(3, 5, 1).is_err());
        assert!(kfold_partition(10, 1, 1).is_err());
    }
}
