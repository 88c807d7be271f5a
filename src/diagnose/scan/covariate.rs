//! Covariate candidates: each numeric covariate not in the model, alone
//! (`c`, z-scored) and times the joint angles (`c`, `c·u_1 … c·u_n` with
//! `u_j` the z-scored angle of joint j), added as an input dimension with a
//! linear trend term ([`Feature::Covariate`]); and the covariates left out
//! because they do not vary over the rows used (with a constant covariate,
//! "c × joint angles" would be a joint-angle trend under c's name).

use super::{EffectKind, Family, GridPoint, Sink, single, zscore};
use crate::dataset::{Covariate, Dataset};
use crate::diagnose::rows::ScanRows;
use crate::features::Feature;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// Rows that must differ from a covariate's median for it to be a
/// candidate: a column that varies in fewer rows is an indicator of those
/// rows, not a covariate.
pub const MIN_VARYING_ROWS: usize = 5;

/// A covariate left out of the candidates because it does not vary over the
/// rows used: with a constant covariate, "covariate × joint
/// angles" is only a linear trend in the joint angles, and its name would
/// claim an effect the data cannot show.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DroppedCovariate {
    /// Column name.
    pub name: String,
    /// Why, in words, with the value.
    pub reason: String,
}

/// `Some(reason)` when covariate `c` is constant or nearly constant over its
/// rows: fewer than [`MIN_VARYING_ROWS`] rows differ from its median by more
/// than 1e-9 of its magnitude.
pub fn constant_covariate(c: &Covariate) -> Option<String> {
    let mut v: Vec<f64> = c.values.iter().copied().filter(|x| x.is_finite()).collect();
    if v.is_empty() {
        return Some(format!("no values in the {} rows used", c.values.len()));
    }
    v.sort_by(f64::total_cmp);
    let median = v[v.len() / 2];
    let tol = 1e-9 * median.abs().max(1.0);
    let varying = v.iter().filter(|x| (**x - median).abs() > tol).count();
    let m = c.values.len();
    if varying == 0 {
        Some(format!("constant ({median}) in all {m} rows used"))
    } else if varying < MIN_VARYING_ROWS.min(m) {
        Some(format!(
            "nearly constant: {median} in all but {varying} of the {m} rows used"
        ))
    } else {
        None
    }
}

/// The covariates that may become candidates: not in `exclude` (already
/// in the model), no missing values, not a precomputed feature column (`@…`).
pub(super) fn usable_covariates<'a>(
    data: &'a Dataset,
    exclude: &'a [String],
) -> impl Iterator<Item = &'a Covariate> {
    data.covariates
        .iter()
        .filter(|c| !exclude.contains(&c.name) && c.missing == 0 && !c.name.starts_with('@'))
}

/// The covariates [`families`](super::families) leaves out as constant, with the reason.
pub fn dropped_covariates(data: &Dataset, exclude: &[String]) -> Vec<DroppedCovariate> {
    dropped_covariates_on(data, exclude, &ScanRows::all(data.len()))
}

/// The covariates [`families_on`](super::families_on) leaves out as constant on the scanned
/// rows `rows`, with the reason: a column that varies in a few rows of the
/// campaign may vary in fewer still of the scanned ones, where it would be
/// an indicator of those rows under its name.
pub fn dropped_covariates_on(
    data: &Dataset,
    exclude: &[String],
    rows: &ScanRows,
) -> Vec<DroppedCovariate> {
    usable_covariates(data, exclude)
        .filter_map(|c| {
            let scanned = Covariate {
                name: c.name.clone(),
                values: rows.pick(&c.values),
                missing: c.missing,
            };
            constant_covariate(&scanned).map(|reason| DroppedCovariate {
                name: c.name.clone(),
                reason,
            })
        })
        .collect()
}

/// Each usable covariate alone and times the joint angles `u` (z-scored).
pub(super) fn covariate_families(
    data: &Dataset,
    exclude: &[String],
    u: &[Vec<f64>],
    out: &mut Sink,
) {
    // a constant column z-scores to round-off (or to ±1 everywhere): "c ×
    // joint angles" would then be a joint-angle trend in c's name
    for c in usable_covariates(data, exclude).filter(|c| constant_covariate(c).is_none()) {
        let z = zscore(&c.values);
        let add = Feature::Covariate {
            name: c.name.clone(),
            reference: Some(c.values[0]),
        };
        out.push(Family {
            kind: EffectKind::Covariate,
            source: vec![c.name.clone()],
            label: format!("{} (alone)", c.name),
            grid: vec![single(BTreeMap::new(), z.clone(), add.clone())],
            zoom: None,
        });
        let mut cols = vec![z.clone()];
        cols.extend(
            u.iter()
                .map(|uj| z.iter().zip(uj).map(|(a, b)| a * b).collect()),
        );
        out.push(Family {
            kind: EffectKind::Covariate,
            source: vec![c.name.clone()],
            label: format!("{} × joint angles", c.name),
            grid: vec![GridPoint::new(BTreeMap::new(), cols, vec![add])],
            zoom: None,
        });
    }
}
