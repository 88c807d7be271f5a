//! The six-axis model of seed 002 (eqs 1–2): MD-H errors on every parameter
//! plus a bidirectional APD table on every axis, and its identification.
//!
//! - **APD tables** from the single-axis indexing tests by circle-point
//!   analysis: for axis `n` the measured TCP turns on a circle about the
//!   axis line; [`crate::frames::fit_circle_3d`] gives the line, and eq 11 of
//!   seed 000 the deviation `Δθ_n,map(i, ±) = ∠(P(i, ±) − Q) − ∠_ref −
//!   (θ*(i) − θ*(i⁰))`, relative to the mean of both directions at the rest
//!   angle. An axis whose circle is smaller than `min_radius_mm` (the TCP lies
//!   near its line, e.g. the wrist axes of a robot without tool offset) is
//!   skipped and said so: its angle cannot be resolved from a position.
//! - **MD-H errors** by Levenberg–Marquardt on a measurement campaign:
//!   `min Σ_k ‖P_k − FK(p; θ̂_k)‖²` over `p` = per link (Δθ_off, Δd, Δa, Δα,
//!   Δβ), the tool offset and the base pose (translation, small rotation),
//!   `θ̂_k = q_k + Δθ_map(q_k, λ_k)` when APD tables are given (seed 002 eq 1
//!   with the encoder angle replaced by its estimate). Redundant parameters
//!   (e.g. β of a link whose axes are not parallel, a base rotation about
//!   J1) are frozen at zero by the solver's rank rule and reported.

use super::scara::{Row, angle_table, extreme_pair, indexing_rows};
use super::{AxisReport, BidirectionalTable};
use crate::Result;
use crate::dataset::Dataset;
use crate::frames::{fit_circle_3d, wrap_pi};
use crate::kinematics::{JointKind, Robot};
use crate::optim::{LmOptions, levenberg_marquardt, numerical_jacobian};
use nalgebra::{DVector, Vector3};
use serde::{Deserialize, Serialize};

/// APD tables identified from indexing tests.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ApdIdentification {
    /// One table per joint (`None`: no table: not indexed, prismatic, or skipped).
    pub apd: Vec<Option<BidirectionalTable>>,
    /// What the identification saw, per identified axis.
    pub axes: Vec<AxisReport>,
    /// Indexed axes that could not be used, with the reason.
    pub skipped: Vec<String>,
}

/// Identify an APD table for every revolute axis with an indexing test whose
/// TCP circle has a radius of at least `min_radius_mm`.
pub fn identify_apd(
    data: &Dataset,
    nominal: &Robot,
    min_radius_mm: f64,
) -> Result<ApdIdentification> {
    let n = nominal.dof();
    nominal.check_dataset(data)?;
    let by_axis = indexing_rows(data)?;
    let mut out = ApdIdentification {
        apd: vec![None; n],
        axes: Vec::new(),
        skipped: Vec::new(),
    };
    for (j, rows) in by_axis.iter().enumerate() {
        if rows.is_empty() {
            continue;
        }
        if nominal.links[j].kind != JointKind::Revolute {
            out.skipped
                .push(format!("J{}: prismatic, no angular table", j + 1));
            continue;
        }
        if rows.len() < 6 {
            out.skipped
                .push(format!("J{}: only {} indexing rows", j + 1, rows.len()));
            continue;
        }
        let pts: Vec<Vector3<f64>> = rows.iter().map(|r| r.p).collect();
        let c = match fit_circle_3d(&pts) {
            Ok(c) => c,
            Err(e) => {
                out.skipped.push(format!("J{}: no circle ({e})", j + 1));
                continue;
            }
        };
        if c.radius < min_radius_mm {
            out.skipped.push(format!(
                "J{}: the TCP turns on a circle of radius {:.3} mm about the axis (< {min_radius_mm} mm): its angle cannot be resolved",
                j + 1,
                c.radius
            ));
            continue;
        }
        let rest = rest_of(rows, j);
        let x_ref = rows
            .iter()
            .find(|r| (r.q[j] - rest).abs() < 1e-6)
            .map_or(rows[0].p, |r| r.p)
            - c.center;
        // sign: the angle must increase with q_j
        let (lo, hi) = extreme_pair(rows, j);
        let turn = wrap_pi(c.angle_of(&rows[hi].p, &x_ref) - c.angle_of(&rows[lo].p, &x_ref));
        let s = if turn < 0.0 { -1.0 } else { 1.0 };
        let angle = move |p: &Vector3<f64>| s * c.angle_of(p, &x_ref);
        let radius = move |p: &Vector3<f64>| {
            let v = p - c.center;
            (v - c.normal * v.dot(&c.normal)).norm()
        };
        let t = angle_table(rows, j, rest, &angle, &radius)?;
        out.axes.push(AxisReport {
            axis: j + 1,
            rows: t.rows,
            angles: t.table.angles_deg.len(),
            cycles: t.cycles,
            radius_mm: c.radius,
            circle_rms_mm: c.rms,
            plane_rms_mm: c.plane_rms,
            repeat_spread_deg: t.spread,
            backlash_half_deg: t.table.mean_half_difference(),
        });
        out.apd[j] = Some(t.table);
    }
    Ok(out)
}

/// The reference angle of joint `j`'s own test: 0 if it was indexed across
/// zero (the campaign's rest), else the middle of its indexed range.
fn rest_of(rows: &[Row], j: usize) -> f64 {
    let (lo, hi) = rows.iter().fold((f64::MAX, f64::MIN), |(l, h), r| {
        (l.min(r.q[j]), h.max(r.q[j]))
    });
    if lo <= 0.0 && 0.0 <= hi {
        0.0
    } else {
        0.5 * (lo + hi)
    }
}

/// Summary of a Levenberg–Marquardt calibration.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LmSummary {
    /// Parameters identified (of `5n + 9`: per link Δθ_off, Δd, Δa, Δα, Δβ, the
    /// tool offset and the base pose), those frozen excluded.
    pub parameters: usize,
    /// Names of the parameters frozen as unidentifiable.
    pub frozen: Vec<String>,
    /// rms of the position residual per coordinate before the fit (nominal
    /// parameters), mm.
    pub rms_before_mm: f64,
    /// rms of the position residual per coordinate after the fit, mm.
    pub rms_after_mm: f64,
    /// Levenberg–Marquardt iterations run.
    pub iterations: usize,
    /// Why the solver stopped (the `LmStop` variant's name).
    pub stop: String,
}

pub use crate::kinematics::apply_errors;

/// Identify the MD-H, tool and base errors of `nominal` from a campaign with
/// measured errors, joints corrected by `apd` where given.
pub fn identify_mdh(
    data: &Dataset,
    nominal: &Robot,
    apd: &[Option<BidirectionalTable>],
) -> Result<(Robot, LmSummary)> {
    let n = nominal.dof();
    nominal.check_dataset(data)?;
    let errors = data.errors_or_err()?;
    let targets: Vec<Vector3<f64>> = data
        .q
        .iter()
        .zip(errors)
        .map(|(q, e)| nominal.fk_unchecked(q).translation.vector + Vector3::from(*e))
        .collect();
    let joints: Vec<Vec<f64>> = data
        .q
        .iter()
        .zip(&data.dir)
        .map(|(q, d)| {
            q.iter()
                .zip(d)
                .zip(apd)
                .map(|((qi, di), t)| qi + t.as_ref().map_or(0.0, |t| t.at(*qi, *di)))
                .collect()
        })
        .collect();
    let residual = |x: &[f64]| -> Result<DVector<f64>> {
        let r = apply_errors(nominal, x);
        let mut v = DVector::zeros(3 * joints.len());
        for (k, (q, p)) in joints.iter().zip(&targets).enumerate() {
            let d = p - r.fk_unchecked(q).translation.vector;
            v[3 * k] = d.x;
            v[3 * k + 1] = d.y;
            v[3 * k + 2] = d.z;
        }
        Ok(v)
    };
    let np = 5 * n + 9;
    let x0 = vec![0.0; np];
    let h = vec![1e-4; np];
    let r0 = residual(&x0)?;
    let res = levenberg_marquardt(
        |x| {
            let r = residual(x)?;
            let j = numerical_jacobian(residual, x, &h)?;
            Ok((r, j))
        },
        &x0,
        &LmOptions {
            rank_tol: 1e-7,
            ..LmOptions::default()
        },
    )?;
    let names = crate::kinematics::calib_names(n);
    let summary = LmSummary {
        parameters: np - res.unidentifiable.len(),
        frozen: res
            .unidentifiable
            .iter()
            .map(|&i| names[i].clone())
            .collect(),
        rms_before_mm: r0.norm() / (r0.len() as f64).sqrt(),
        rms_after_mm: res.rms,
        iterations: res.iterations,
        stop: format!("{:?}", res.stop),
    };
    Ok((apply_errors(nominal, &res.x), summary))
}
