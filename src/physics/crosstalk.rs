//! Axis-to-axis cross-talk of a SCARA (seed 000 §5.2): does J1's angular
//! positioning deviation depend on where J2 stands?
//!
//! The test (`robokrige simulate --kind crosstalk`): J1 indexed at −100°,
//! −80°, …, 100° (eq 21) bidirectionally, with J2 held at 0°, 20°, 40°, 60°.
//! The paper identifies a J1 table per J2 angle by eq 11, which is relative to
//! the reference angle, so a cross-talk that *shifts* J1 by a constant at a
//! given J2 (e.g. gravity torque on J1 changing with the arm's reach) would
//! not show. Here every measured point is compared with the identified model
//! instead: the J1 deviation the model misses is
//!
//! `Δθ1,xt(i, ±; θ2) = ∠P_meas − ∠P̂_model` about the J1 axis,
//!
//! averaged over the cycles per indexed angle and direction. The model already
//! holds J1's own table and J2's table and geometry, so what is left is the
//! dependence on J2 (plus noise). Each J2 angle's mean shift and its
//! peak-to-peak are compared with the noise of an entry estimated from the
//! repeated cycles.

use super::scara::indexing_rows;
use super::{BidirectionalTable, Geometry, PhysicsModel};
use crate::dataset::Dataset;
use crate::frames::wrap_pi;
use crate::{Error, Result};
use nalgebra::{Point3, Vector3};
use serde::{Deserialize, Serialize};

/// J1's unexplained deviation at one J2 angle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrosstalkGroup {
    /// The J2 angle held during these J1 rows, degrees.
    pub j2_deg: f64,
    /// J1 rows measured at this J2 angle.
    pub rows: usize,
    /// `Δθ1,xt` per indexed J1 angle and direction, degrees.
    pub table: BidirectionalTable,
    /// Mean over the table, degrees (a constant shift of J1 at this J2).
    pub mean_deg: f64,
    /// max − min over the table, degrees.
    pub peak_to_peak_deg: f64,
}

/// Result of [`identify_crosstalk`].
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CrosstalkReport {
    /// One group per held J2 angle, ascending.
    pub groups: Vec<CrosstalkGroup>,
    /// Standard error of one table entry (cycle mean), degrees, pooled over
    /// all entries from the spread of the repeated cycles.
    pub entry_se_deg: f64,
    /// Largest |mean shift| of a J2 angle relative to the first (J2 = 0°).
    pub max_shift_deg: f64,
    /// Its standard error: the noise of the group means (√(2/entries) ·
    /// entry_se) combined with the model's own uncertainty at the held J2
    /// angle (J2's table entry standard error × ∂∠P/∂θ2 about J1, twice).
    pub shift_se_deg: f64,
    /// `max_shift > 4 · shift_se`.
    pub significant: bool,
}

/// Compare the J1 rows of a cross-talk test with the identified `model`.
pub fn identify_crosstalk(data: &Dataset, model: &PhysicsModel) -> Result<CrosstalkReport> {
    let rows = indexing_rows(data)?.swap_remove(0);
    if rows.is_empty() {
        return Err(Error::Input {
            source_name: data.source.clone(),
            message: "no J1 rows (axis = 1) in the cross-talk test".into(),
        });
    }
    let inv = model.frame.inverse();
    let angle = |p: &Vector3<f64>| {
        let r = inv * Point3::from(*p);
        r.y.atan2(r.x)
    };
    let mut held: Vec<f64> = rows.iter().map(|r| r.q[1]).collect();
    held.sort_by(f64::total_cmp);
    held.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
    let mut groups = Vec::new();
    let (mut ss, mut dof) = (0.0, 0usize);
    let mut cycles_seen = 1usize;
    for &h in &held {
        let g: Vec<_> = rows.iter().filter(|r| (r.q[1] - h).abs() < 1e-6).collect();
        let mut angles: Vec<f64> = g.iter().map(|r| r.q[0]).collect();
        angles.sort_by(f64::total_cmp);
        angles.dedup_by(|a, b| (*a - *b).abs() < 1e-6);
        let mut acc = vec![[Vec::new(), Vec::new()]; angles.len()];
        for r in &g {
            let i = angles
                .iter()
                .position(|a| (a - r.q[0]).abs() < 1e-6)
                .unwrap();
            let pred = model.tcp(&r.q, &r.dir);
            let d = wrap_pi(angle(&r.p) - angle(&pred)).to_degrees();
            acc[i][usize::from(r.dir[0] < 0.0)].push(d);
        }
        let mut plus = Vec::new();
        let mut minus = Vec::new();
        for (i, a) in angles.iter().enumerate() {
            for (k, out) in [(0, &mut plus), (1, &mut minus)] {
                let v = &acc[i][k];
                if v.is_empty() {
                    return Err(Error::InvalidParameter(format!(
                        "cross-talk test: J1 = {a}° at J2 = {h}° was not measured in both directions"
                    )));
                }
                let m = v.iter().sum::<f64>() / v.len() as f64;
                ss += v.iter().map(|x| (x - m).powi(2)).sum::<f64>();
                dof += v.len() - 1;
                cycles_seen = cycles_seen.max(v.len());
                out.push(m);
            }
        }
        let all: Vec<f64> = plus.iter().chain(&minus).copied().collect();
        let (lo, hi) = all
            .iter()
            .fold((f64::MAX, f64::MIN), |(l, x), v| (l.min(*v), x.max(*v)));
        groups.push(CrosstalkGroup {
            j2_deg: h,
            rows: g.len(),
            mean_deg: all.iter().sum::<f64>() / all.len() as f64,
            peak_to_peak_deg: hi - lo,
            table: BidirectionalTable::new(angles, plus, minus)?,
        });
    }
    let sigma = if dof > 0 {
        (ss / dof as f64).sqrt()
    } else {
        f64::NAN
    };
    let entry_se = sigma / (cycles_seen as f64).sqrt();
    let entries = groups[0].table.angles_deg.len() * 2;
    // the model's J2 table entry at the held angle is itself a noisy mean:
    // it moves the TCP's angle about J1 by ∂∠P/∂θ2 = L2(L2 + L1 cos φ)/|P|²
    let Geometry::Scara(geo) = &model.geometry else {
        return Err(Error::InvalidParameter(
            "the cross-talk test compares with a SCARA model (seed 000)".into(),
        ));
    };
    let j2_se = model.apd[1].as_ref().map_or(0.0, |t| t.entry_se);
    let (l1, l2) = (geo.l1_mm + geo.dl1_mm, geo.l2_mm + geo.dl2_mm);
    let gain = held
        .iter()
        .map(|h| {
            let c = (h + geo.theta20_deg).to_radians().cos();
            l2 * (l2 + l1 * c) / (l1 * l1 + l2 * l2 + 2.0 * l1 * l2 * c)
        })
        .fold(0.0, f64::max);
    let shift_se = (entry_se.powi(2) * 2.0 / entries as f64 + 2.0 * (gain * j2_se).powi(2)).sqrt();
    let base = groups[0].mean_deg;
    let max_shift = groups
        .iter()
        .map(|g| (g.mean_deg - base).abs())
        .fold(0.0, f64::max);
    Ok(CrosstalkReport {
        groups,
        entry_se_deg: entry_se,
        max_shift_deg: max_shift,
        shift_se_deg: shift_se,
        significant: max_shift > 4.0 * shift_se,
    })
}
