//! The generic search: one-column bases (each usable covariate, the time
//! since the previous pose with a time column, each joint's last move),
//! each times one joint angle (θ_k, sin θ_k, cos θ_k, centred at the
//! base's mean; the joint k scanned, [`Feature::Times`]), and the
//! covariates and the interval lagged by 1–3 rows ([`Feature::Lagged`]).
//! Each scan is the grid of one family, so its p-value pays for it.

use super::covariate::{constant_covariate, usable_covariates};
use super::motion::{median_interval, time_column};
use super::{EffectKind, Family, GridPoint, Sink, params, z_all, zscore};
use crate::dataset::Dataset;
use crate::features::Feature;
use std::collections::BTreeMap;

/// Lags (rows) scanned by the generic search.
const LAGS: [usize; 3] = [1, 2, 3];

/// A one-column basis of the generic search: the feature, its values, its
/// label.
pub(super) type Base = (Feature, Vec<f64>, String);

/// The one-column bases of the generic search, and how many of them (the
/// first) are also tried lagged: the usable covariates, the time since the
/// previous pose (whose family is pushed here, with a time column), each
/// joint's last move.
pub(super) fn generic_bases(
    data: &Dataset,
    exclude: &[String],
    out: &mut Sink,
) -> (Vec<Base>, usize) {
    let mut bases: Vec<Base> = Vec::new();
    for c in usable_covariates(data, exclude).filter(|c| constant_covariate(c).is_none()) {
        let f = Feature::Covariate {
            name: c.name.clone(),
            reference: Some(c.values[0]),
        };
        bases.push((f, c.values.clone(), c.name.clone()));
    }
    if let Some(t) = time_column(data, exclude) {
        let f = Feature::Interval {
            column: t.name.clone(),
            reference: median_interval(t),
        };
        if let Ok(v) = f.columns(data) {
            out.push(Family {
                kind: EffectKind::MotionHistory,
                source: vec![t.name.clone()],
                label: format!("time since the previous pose (Δ{})", t.name),
                grid: vec![GridPoint::new(
                    BTreeMap::new(),
                    vec![zscore(&v[0])],
                    vec![f.clone()],
                )],
                zoom: None,
            });
            bases.push((f, v[0].clone(), format!("Δ{}", t.name)));
        }
    }
    let lagged = bases.len();
    for j in 1..=data.n_joints() {
        let f = Feature::Moves {
            joint: j,
            tau_poses: 0.0,
            clock: None,
        };
        if let Ok(v) = f.columns_from_poses(&data.q, &data.dir) {
            bases.push((f, v[0].clone(), format!("q{j}'s last move")));
        }
    }
    (bases, lagged)
}

/// A base times one joint angle (θ, sin θ, cos θ), and lagged when
/// `lagged`.
pub(super) fn generic_families(data: &Dataset, (f, v, label): &Base, lagged: bool, out: &mut Sink) {
    let n = data.n_joints();
    let (kind, source) = match f {
        Feature::Covariate { name, .. } => (EffectKind::Covariate, name.clone()),
        Feature::Interval { column, .. } => (EffectKind::MotionHistory, column.clone()),
        other => (EffectKind::MotionHistory, other.names().concat()),
    };
    // the columns as the model would get them ([`Feature::Times`]),
    // centred at the feature's mean: the product with a covariate near
    // 22 °C must not be a joint-angle trend in the covariate's name
    let centre = v.iter().sum::<f64>() / v.len() as f64;
    let grid: Vec<GridPoint> = (1..=n)
        .filter_map(|k| {
            let t = Feature::Times {
                of: Box::new(f.clone()),
                joint: k,
                centre,
            };
            Some(GridPoint::new(
                params(&[("joint", k as f64)]),
                z_all(t.columns(data).ok()?),
                vec![t],
            ))
        })
        .collect();
    out.push(Family {
        kind,
        source: vec![source.clone()],
        label: format!("{label} × one joint angle (θ, sin θ, cos θ)"),
        grid,
        zoom: None,
    });
    if !lagged {
        return;
    }
    out.push(Family {
        kind,
        source: vec![source],
        label: format!("{label}, lagged"),
        grid: LAGS
            .iter()
            .map(|&lag| {
                GridPoint::new(
                    params(&[("lag", lag as f64)]),
                    vec![zscore(
                        &(0..v.len())
                            .map(|i| v[i.saturating_sub(lag)])
                            .collect::<Vec<_>>(),
                    )],
                    vec![Feature::Lagged {
                        of: Box::new(f.clone()),
                        lag,
                    }],
                )
            })
            .collect(),
        zoom: None,
    });
}
