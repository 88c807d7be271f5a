//! Candidates that are functions of the pose alone (the kinds the GP can
//! soak up by shortening its length scales, [`EffectKind::pose_function`]),
//! added as trend terms:
//! - a harmonic of joint j, `sin(2π (θ_j − c) / P)` and `cos(2π (θ_j − c) / P)`,
//!   with the period P scanned from half the joint's range down to 2° in
//!   steps of a tenth of a cycle over the range and the phase counted from
//!   the joint's mean c on the campaign ([`Feature::Harmonic`]);
//! - the product of two z-scored joint angles, `u_a · u_b`
//!   ([`Feature::Interaction`]);
//! - with a robot, joint j deviating with `sin θ_k` and `cos θ_k`, mapped
//!   to the TCP through the Jacobian ([`Feature::Crosstalk`]);
//! - with a robot, a harmonic of joint j as a deviation of that joint,
//!   mapped to the TCP through the Jacobian, over the same periods as the
//!   plain harmonic ([`Feature::HarmonicJacobian`]).

use super::{EffectKind, Family, GridPoint, Sink, params, single, z_all, zscore};
use crate::calibration::harmonics::{MIN_PERIOD, scan_periods, zoom_periods};
use crate::dataset::Dataset;
use crate::diagnose::rows::ScanRows;
use crate::features::{Feature, jacobian_sin_cos_at};
use crate::kinematics::Robot;
use std::collections::BTreeMap;

/// Joint `j`'s range on `data`.
fn joint_range(data: &Dataset, j: usize) -> f64 {
    let (lo, hi) = data
        .q
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
            (a.min(r[j]), b.max(r[j]))
        });
    hi - lo
}

/// Joint `j`'s mean on `data`, to 0.01°: where a harmonic's phase is
/// counted from ([`Feature::Harmonic`]'s `centre_deg`).
fn joint_centre(data: &Dataset, j: usize) -> f64 {
    let mean = data.q.iter().map(|r| r[j]).sum::<f64>() / data.len().max(1) as f64;
    (mean * 100.0).round() / 100.0
}

/// The periods a harmonic of joint `j` is scanned at: those of the
/// calibration's joint harmonics ([`scan_periods`]) from half its range on
/// `data` down to 2°.
fn harmonic_periods(data: &Dataset, j: usize) -> Vec<f64> {
    scan_periods(joint_range(data, j), MIN_PERIOD)
}

/// [`Zoom`](super::Zoom) of a harmonic (plain or through the Jacobian):
/// the periods within one scanned step of the point's, a tenth of a step
/// apart. The lattice puts a period between two of its own points a
/// twentieth of a cycle over the range off at the ends, and its support
/// interval then sits beside the period rather than around it.
fn zoom_harmonic(point: &GridPoint, rows: &ScanRows, data: &Dataset) -> Vec<GridPoint> {
    let (Some(&period), Some(first)) = (point.params.get("period_deg"), point.add.first()) else {
        return Vec::new();
    };
    let (joint, centre_deg, robot) = match first {
        Feature::Harmonic {
            joint, centre_deg, ..
        } => (*joint, *centre_deg, None),
        Feature::HarmonicJacobian {
            robot,
            joint,
            centre_deg,
            ..
        } => (*joint, *centre_deg, Some(robot)),
        _ => return Vec::new(),
    };
    let with_period = |period_deg: f64| match robot {
        None => Feature::Harmonic {
            joint,
            period_deg,
            centre_deg,
        },
        Some(robot) => Feature::HarmonicJacobian {
            robot: robot.clone(),
            joint,
            period_deg,
            centre_deg,
        },
    };
    zoom_periods(joint_range(data, joint - 1), period)
        .into_iter()
        .filter_map(|p| {
            let f = with_period(p);
            let columns = f.columns(data).ok()?;
            let columns = columns.iter().map(|c| zscore(&rows.pick(c))).collect();
            Some(GridPoint::of_features(
                params(&[("period_deg", p)]),
                columns,
                vec![f],
            ))
        })
        .collect()
}

/// The family `label` of joint `j`'s harmonics: `point(P)` at each of its
/// periods P ([`harmonic_periods`]).
fn push_harmonics(
    out: &mut Sink,
    data: &Dataset,
    j: usize,
    label: String,
    point: impl Fn(f64) -> GridPoint,
) {
    let grid: Vec<GridPoint> = harmonic_periods(data, j).into_iter().map(point).collect();
    if !grid.is_empty() {
        out.push(Family {
            kind: EffectKind::Harmonic,
            source: vec![format!("q{}", j + 1)],
            label,
            grid,
            zoom: Some(zoom_harmonic),
        });
    }
}

/// Harmonics of each joint, periods from 2° to half its range.
pub(super) fn harmonic_families(data: &Dataset, out: &mut Sink) {
    for j in 0..data.n_joints() {
        let label = format!("harmonic of q{}", j + 1);
        let centre_deg = joint_centre(data, j);
        push_harmonics(out, data, j, label, |period| {
            let w = std::f64::consts::TAU / period;
            let phase: Vec<f64> = data.q.iter().map(|r| w * (r[j] - centre_deg)).collect();
            let s: Vec<f64> = phase.iter().map(|p| p.sin()).collect();
            let c: Vec<f64> = phase.iter().map(|p| p.cos()).collect();
            GridPoint::new(
                params(&[("period_deg", period)]),
                vec![zscore(&s), zscore(&c)],
                vec![Feature::Harmonic {
                    joint: j + 1,
                    period_deg: period,
                    centre_deg,
                }],
            )
        });
    }
}

/// Harmonics of each joint as a deviation of the joint, mapped to the TCP
/// through `robot`'s Jacobian; the periods of [`harmonic_families`].
pub(super) fn harmonic_jacobian_families(data: &Dataset, robot: &Robot, out: &mut Sink) {
    let Ok(jac) = data
        .q
        .iter()
        .map(|q| robot.position_jacobian(q))
        .collect::<crate::Result<Vec<_>>>()
    else {
        return;
    };
    for j in 0..data.n_joints() {
        let label = format!("harmonic of q{} (via the Jacobian)", j + 1);
        let centre_deg = joint_centre(data, j);
        push_harmonics(out, data, j, label, |period| {
            let w = std::f64::consts::TAU / period;
            let columns = jacobian_sin_cos_at(&jac, &data.q, j + 1, |qi| w * (qi[j] - centre_deg));
            GridPoint::of_features(
                params(&[("period_deg", period)]),
                z_all(columns),
                vec![Feature::HarmonicJacobian {
                    robot: Box::new(robot.clone()),
                    joint: j + 1,
                    period_deg: period,
                    centre_deg,
                }],
            )
        });
    }
}

/// Products of two joint angles `u` (z-scored).
pub(super) fn interaction_families(u: &[Vec<f64>], out: &mut Sink) {
    let n = u.len();
    for a in 0..n {
        for b in a + 1..n {
            let col = zscore(
                &u[a]
                    .iter()
                    .zip(&u[b])
                    .map(|(x, y)| x * y)
                    .collect::<Vec<_>>(),
            );
            out.push(Family {
                kind: EffectKind::Interaction,
                source: vec![format!("q{}", a + 1), format!("q{}", b + 1)],
                label: format!("q{} × q{}", a + 1, b + 1),
                grid: vec![single(
                    BTreeMap::new(),
                    col,
                    Feature::Interaction { a: a + 1, b: b + 1 },
                )],
                zoom: None,
            });
        }
    }
}

/// Joint cross-talk mapped through `robot`'s Jacobian.
pub(super) fn crosstalk_families(data: &Dataset, robot: &Robot, out: &mut Sink) {
    let n = data.n_joints();
    for j in 1..=n {
        for k in (1..=n).filter(|&k| k != j) {
            let f = Feature::Crosstalk {
                robot: Box::new(robot.clone()),
                joint: j,
                from: k,
            };
            let Ok(cols) = f.columns_from_poses(&data.q, &data.dir) else {
                continue;
            };
            out.push(Family {
                kind: EffectKind::Interaction,
                source: vec![format!("q{j}"), format!("q{k}")],
                label: format!("q{j} deviating with sin/cos q{k} (via the Jacobian)"),
                grid: vec![GridPoint::of_features(
                    BTreeMap::new(),
                    cols.iter().map(|c| zscore(c)).collect(),
                    vec![f],
                )],
                zoom: None,
            });
        }
    }
}
