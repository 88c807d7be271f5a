//! Direction-history candidates of one joint: its previous direction
//! ([`Feature::PreviousDirection`]), and its travel `s` since its last
//! reversal ([`Feature::SinceReversal`]), linear and saturating,
//! `1 − e^(−s/S)` over a geometric scan of the scale S; each alone and
//! signed by the current direction λ (a history effect acts along λ, like
//! backlash).

use super::{EffectKind, Family, GridPoint, Sink, params, zscore};
use crate::dataset::Dataset;
use crate::features::Feature;
use std::collections::BTreeMap;

/// Direction history of joint `j` (0-based): its previous direction, and
/// its travel since the last reversal (linear, and saturating over a scan
/// of scales); each alone and signed by the current direction λ (a history
/// effect on a joint acts along its λ, like backlash).
pub(super) fn direction_families(data: &Dataset, j: usize, out: &mut Sink) {
    let lam: Vec<f64> = data.dir.iter().map(|d| d[j]).collect();
    let signed = |v: &[f64]| -> Vec<Vec<f64>> {
        vec![
            zscore(v),
            zscore(&v.iter().zip(&lam).map(|(a, l)| a * l).collect::<Vec<_>>()),
        ]
    };
    let prev = Feature::PreviousDirection { joint: j + 1 };
    let pv = prev
        .columns_from_poses(&data.q, &data.dir)
        .expect("pose feature");
    if pv[0].iter().any(|v| *v != pv[0][0]) {
        out.push(Family {
            kind: EffectKind::DirectionHistory,
            source: vec![format!("dir{}", j + 1)],
            label: format!("previous direction of q{}", j + 1),
            grid: vec![GridPoint::new(BTreeMap::new(), signed(&pv[0]), vec![prev])],
            zoom: None,
        });
    }
    // travel s since the last reversal: linear, and saturating
    // 1 − e^(−s/S) over a geometric scan of the scale S
    let since = Feature::SinceReversal { joint: j + 1 };
    let s = since
        .columns_from_poses(&data.q, &data.dir)
        .expect("pose feature")[0]
        .clone();
    let smax = s.iter().cloned().fold(0.0, f64::max);
    if smax <= 0.0 {
        return;
    }
    let mut grid = vec![GridPoint::new(
        BTreeMap::new(),
        signed(&s),
        vec![since.clone()],
    )];
    let mut scale = smax / 2.0;
    while scale >= 0.5 && grid.len() < 24 {
        let sat: Vec<f64> = s.iter().map(|v| 1.0 - (-v / scale).exp()).collect();
        grid.push(GridPoint::new(
            params(&[("scale_deg", scale)]),
            signed(&sat),
            vec![since.clone()],
        ));
        scale /= 1.5;
    }
    out.push(Family {
        kind: EffectKind::DirectionHistory,
        source: vec![format!("dir{}", j + 1)],
        label: format!("travel of q{} since its last reversal", j + 1),
        grid,
        zoom: None,
    });
}
