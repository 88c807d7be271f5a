//! Intervals of an added effect that hold under confounding: with its
//! competing effects refitted, not from the chosen model alone.
//!
//! The competitors of an added effect are the candidates of its round it
//! is not separable from ([`super::confound`]) and, for every effect but
//! the drift itself, the drift over the measurement order (the row and its
//! square: a real campaign has the robot's own slow changes, and any step,
//! covariate or block projects onto them). Both intervals are computed on
//! the CV residuals of the model the effect was added to (all rows), by
//! least squares with an intercept:
//!
//! - **Row of a step, edges of a block** ([`profile_rows`]): the profile of
//!   the evidence over the row. For each row `t` the residuals are fitted
//!   with the step at `t` and the competitors' columns (a block: the other
//!   edge's step too); with `σ²_a` the mean square left at the best row (per
//!   axis, `m − p − 1` degrees of freedom), the deviance
//!   `D(t) = Σ_a (SSR_a(t) − SSR_a(t̂))/σ²_a`, and the interval is every row
//!   with `D(t) ≤ 2·ln(2/0.05) = 7.38` ([`CHANGE_95`]), joined with the
//!   scan's own support interval.
//! - **Coefficients** ([`widen_coefficients`]): the effect's columns fitted
//!   alone and with the competitors' columns; the competitors move each
//!   estimate by `Δ` and scale its standard error by `√r` (`r` the ratio of
//!   the two least-squares variances of that coefficient, the variance
//!   inflation of the competitors). The interval becomes the symmetric hull
//!   of the model's own `b ± h` and of `b + Δ ± h·√r`: half-width
//!   `max(h, |Δ| + h·√r)`. On a calibration's residual the directions the
//!   calibration saw are competitors too, on each axis its own rows of
//!   them ([`crate::calibration::Calibration::seen_displacements`]): the
//!   calibration was identified with the effect in the errors and took up
//!   its projection on them, which the effect's estimate alone misses and
//!   the estimate with them refitted gives back (Frisch–Waugh).
//! - **Period of a harmonic** ([`profile_period`]): the profile of the
//!   evidence over the period, as for a row: at each of [`PERIOD_STEPS`]
//!   periods within ±[`PERIOD_SPAN`] of the one found (log-spaced), the
//!   residuals fitted with the harmonic at that period and the competitors'
//!   columns; `D(P) = Σ_a (SSR_a(P) − SSR_a(P̂))/σ²_a`, and the interval is
//!   the hull of every period with `D(P) ≤ χ²₁(95 %) = 3.84`, joined with
//!   the scan's own support interval. The period is a regular parameter
//!   near its optimum; the hull also takes in side lobes within the
//!   threshold. The scan's grid and support interval alone were too
//!   narrow: on planted real campaigns (UR10 series C) four of nine
//!   harmonics found 0.3–2.2 % off their period were outside them.
//! - **Coefficients of a harmonic** ([`across_period`]): they are
//!   conditional on the period found, and a period a little off turns the
//!   phase over the joint's range, and the sin and cos coefficients with
//!   it. The interval is the union, over [`PERIOD_POINTS`] periods evenly
//!   across the period's 95 % interval, of the interval with the
//!   competitors refitted at that period (the shift `Δ` then measured from
//!   the estimate alone at the period found): a projection of the joint
//!   region of period and coefficients, each at 95 %. The phase is counted
//!   from the joint's mean on the campaign ([`Feature::Harmonic`]'s
//!   `centre_deg`), so a period within its interval turns it little at the
//!   data.

use super::rank::orthonormal;
use super::report::{Coefficient, EffectReport};
use crate::calibration::Displacements;
use crate::dataset::Dataset;
use crate::features::Feature;
use nalgebra::{DMatrix, DVector};

/// The profile deviance of a row within the 95 % interval: `2·ln(2/0.05)`.
/// The likelihood ratio of a change at the true row against a change at
/// another row, as that row moves away on one side, is a martingale of
/// mean 1 (Gaussian residuals, known σ and size of the change: the profile
/// re-estimates the size, an approximation), so by Ville's maximal inequality
/// some row on that side beats the true one by a factor `1/a` with
/// probability at most `a`; `a` = 2.5 % a side. χ²₁(95 %) = 3.84, the
/// regular parameter's threshold, undercovers a change point: its profile
/// is not quadratic, and a clear step's is one row wide.
const CHANGE_95: f64 = 7.377_758_908_227_871;

/// χ²₁'s 95 % quantile: the profile deviance of a regular parameter
/// within its 95 % interval ([`profile_period`]).
const CHI2_1_95: f64 = 3.841_458_820_694_124;

/// Relative half-width of the periods [`profile_period`] profiles around
/// the one found.
pub const PERIOD_SPAN: f64 = 0.15;

/// Periods [`profile_period`] evaluates across ±[`PERIOD_SPAN`].
pub const PERIOD_STEPS: usize = 301;

/// Periods across a harmonic's 95 % period interval at which its
/// coefficients are refitted ([`across_period`]).
pub const PERIOD_POINTS: usize = 17;

/// The one period of the periodic features of `add` (plain harmonics and
/// harmonics through the Jacobian), if they have one and only one.
fn period_of(add: &[Feature]) -> Option<f64> {
    let mut periods = add.iter().filter_map(|f| match f {
        Feature::Harmonic { period_deg, .. } | Feature::HarmonicJacobian { period_deg, .. } => {
            Some(*period_deg)
        }
        _ => None,
    });
    let p = periods.next()?;
    periods.all(|q| q == p).then_some(p)
}

/// `add` with the period of every periodic feature set to `p` (the same
/// features, columns and phase reference otherwise).
fn at_period(add: &[Feature], p: f64) -> Vec<Feature> {
    add.iter()
        .map(|f| {
            let mut f = f.clone();
            if let Feature::Harmonic { period_deg, .. }
            | Feature::HarmonicJacobian { period_deg, .. } = &mut f
            {
                *period_deg = p;
            }
            f
        })
        .collect()
}

/// The effect's features at [`PERIOD_POINTS`] periods evenly across the 95 %
/// interval of its period (`params_ci["period_deg"]`), ends included: one
/// feature list per period. Empty when the effect has no period or its
/// interval is a point.
pub(super) fn across_period(report: &EffectReport) -> Vec<Vec<Feature>> {
    let Some(&[lo, hi]) = report.params_ci.get("period_deg") else {
        return Vec::new();
    };
    let interval = lo.is_finite() && hi.is_finite() && hi > lo && lo > 0.0;
    if !interval || period_of(&report.add).is_none() {
        return Vec::new();
    }
    (0..PERIOD_POINTS)
        .map(|k| {
            let p = lo + (hi - lo) * k as f64 / (PERIOD_POINTS - 1) as f64;
            at_period(&report.add, p)
        })
        .collect()
}

/// The 95 % interval of the period of a harmonic effect (`report.add`)
/// from the profile of the evidence over the period (module docs), with
/// the `competitors` refitted on the CV `residuals` of `data` (columns of
/// every axis, and per axis the calibration's directions, as for the
/// coefficients), joined with its own interval. Returns whether the
/// interval changed.
pub(super) fn profile_period(
    report: &mut EffectReport,
    data: &Dataset,
    residuals: &[[f64; 3]],
    (competitors, per_axis): (&[Vec<f64>], Option<&Displacements>),
) -> bool {
    let Some(found) = period_of(&report.add) else {
        return false;
    };
    let m = residuals.len();
    let axes: Vec<Option<usize>> = report.add.iter().flat_map(Feature::column_axes).collect();
    let basis = competitor_basis(competitors, per_axis);
    let q = [&basis[0][..], &basis[1][..], &basis[2][..]];
    let ys: Vec<Vec<f64>> = (0..3)
        .map(|a| residualise(&residuals.iter().map(|r| r[a]).collect::<Vec<_>>(), q[a]))
        .collect();
    // the fitted sum of squares per axis, and the columns fitted on that
    // axis, at period p
    let fitted = |p: f64| -> Option<([f64; 3], [usize; 3])> {
        let cols = feature_columns(data, &at_period(&report.add, p));
        if cols.len() != axes.len() || cols.is_empty() {
            return None;
        }
        least_squares(&cols, &axes, &ys, q).map(|f| (f.fitted, f.columns))
    };
    let steps = PERIOD_STEPS.max(3);
    let (lo, hi) = ((1.0 - PERIOD_SPAN).ln(), (1.0 + PERIOD_SPAN).ln());
    let grid: Vec<f64> = (0..steps)
        .map(|i| found * (lo + (hi - lo) * i as f64 / (steps - 1) as f64).exp())
        .collect();
    let profile: Vec<(f64, [f64; 3], [usize; 3])> = grid
        .iter()
        .copied()
        .chain(std::iter::once(found))
        .filter_map(|p| fitted(p).map(|(ss, k)| (p, ss, k)))
        .collect();
    let Some((_, best, k)) = profile
        .iter()
        .max_by(|x, y| x.1.iter().sum::<f64>().total_cmp(&y.1.iter().sum::<f64>()))
    else {
        return false;
    };
    let s2: [f64; 3] = std::array::from_fn(|a| {
        let base: f64 = ys[a].iter().map(|v| v * v).sum();
        let dof = (m as f64 - q[a].len() as f64 - k[a] as f64 - 1.0).max(1.0);
        ((base - best[a]) / dof).max(f64::MIN_POSITIVE)
    });
    let fits: Vec<(f64, [f64; 3])> = profile.iter().map(|(p, ss, _)| (*p, *ss)).collect();
    let within = within_deviance(&fits, best, &s2, CHI2_1_95);
    let (Some(&p_lo), Some(&p_hi)) = (
        within.iter().min_by(|a, b| a.total_cmp(b)),
        within.iter().max_by(|a, b| a.total_cmp(b)),
    ) else {
        return false;
    };
    if p_lo <= grid[0] || p_hi >= grid[steps - 1] {
        report.add_note(format!(
            "the period's profile is within its 95 % threshold at ±{:.0} % of the period found: its interval may be wider",
            100.0 * PERIOD_SPAN
        ));
    }
    let ci = report
        .params_ci
        .entry("period_deg".to_string())
        .or_insert([found, found]);
    let new = [ci[0].min(p_lo), ci[1].max(p_hi)];
    let changed = new != *ci;
    *ci = new;
    changed
}

/// The points of a profile (each with its fitted sum of squares per axis)
/// whose deviance `Σ_a (best_a − fit_a)/σ²_a`, counted from its own
/// minimum (the largest unweighted fit `best` need not be the largest
/// weighted one), is within `threshold`.
fn within_deviance<T: Copy>(
    fits: &[(T, [f64; 3])],
    best: &[f64; 3],
    s2: &[f64; 3],
    threshold: f64,
) -> Vec<T> {
    let deviance: Vec<f64> = fits
        .iter()
        .map(|(_, f)| (0..3).map(|a| (best[a] - f[a]) / s2[a]).sum::<f64>())
        .collect();
    let least = deviance.iter().copied().fold(f64::INFINITY, f64::min);
    fits.iter()
        .zip(&deviance)
        .filter(|(_, d)| **d - least <= threshold)
        .map(|((t, _), _)| *t)
        .collect()
}

/// Per axis, an orthonormal basis of the `competitors` (every axis) and of
/// that axis's rows of the calibration's directions (`per_axis`).
fn competitor_basis(
    competitors: &[Vec<f64>],
    per_axis: Option<&Displacements>,
) -> [Vec<Vec<f64>>; 3] {
    std::array::from_fn(|a| {
        let mut c: Vec<&[f64]> = competitors.iter().map(Vec::as_slice).collect();
        if let Some(p) = per_axis {
            c.extend(p[a].iter().map(Vec::as_slice));
        }
        orthonormal(&c)
    })
}

/// `v` centred and with its projection on `q` (orthonormal, centred) taken off.
fn residualise(v: &[f64], q: &[Vec<f64>]) -> Vec<f64> {
    let mu = v.iter().sum::<f64>() / v.len().max(1) as f64;
    let mut out: Vec<f64> = v.iter().map(|x| x - mu).collect();
    for b in q {
        let d: f64 = out.iter().zip(b).map(|(x, y)| x * y).sum();
        out.iter_mut().zip(b).for_each(|(x, y)| *x -= d * y);
    }
    out
}

/// The drift over the measurement order as competitor columns: the row
/// and its square.
pub(super) fn drift_columns(m: usize) -> Vec<Vec<f64>> {
    let row: Vec<f64> = (0..m).map(|i| i as f64 / m.max(1) as f64).collect();
    let sq = row.iter().map(|r| r * r).collect();
    vec![row, sq]
}

/// The columns of `features` on every row of `data` (those that cannot be
/// computed are left out).
pub(super) fn feature_columns(data: &Dataset, features: &[Feature]) -> Vec<Vec<f64>> {
    features
        .iter()
        .filter_map(|f| f.columns(data).ok())
        .flatten()
        .collect()
}

/// The 95 % interval of the row of a step in `residuals` (all rows, the
/// model's CV residuals) from the profile of the evidence over rows
/// `range`, with the `competitors` columns refitted at every row; `None`
/// when nothing can be fitted.
pub(super) fn profile_rows(
    residuals: &[[f64; 3]],
    competitors: &[Vec<f64>],
    range: std::ops::Range<usize>,
) -> Option<[usize; 2]> {
    let m = residuals.len();
    if range.is_empty() || m < 4 {
        return None;
    }
    let q = orthonormal(competitors);
    let r: Vec<Vec<f64>> = (0..3)
        .map(|a| residualise(&residuals.iter().map(|x| x[a]).collect::<Vec<_>>(), &q))
        .collect();
    // suffix sums: of the residuals (s_tᵀ r̃ = Σ_{i ≥ t} r̃_i, for r̃ ⟂ 1, q)
    // and of each basis column (qᵀ s_t)
    let suffix = |v: &[f64]| -> Vec<f64> {
        let mut s = vec![0.0; v.len() + 1];
        for i in (0..v.len()).rev() {
            s[i] = s[i + 1] + v[i];
        }
        s
    };
    let rs: Vec<Vec<f64>> = r.iter().map(|v| suffix(v)).collect();
    let qs: Vec<Vec<f64>> = q.iter().map(|v| suffix(v)).collect();
    let base: [f64; 3] = std::array::from_fn(|a| r[a].iter().map(|x| x * x).sum());
    // the fitted sum of squares of the step at t, per axis
    let gain = |t: usize| -> [f64; 3] {
        let n = (m - t) as f64;
        // ‖s̃_t‖² = ‖s_t − mean‖² − ‖qᵀ s_t‖²
        let norm = n - n * n / m as f64 - qs.iter().map(|s| s[t] * s[t]).sum::<f64>();
        std::array::from_fn(|a| {
            if norm > 1e-9 {
                rs[a][t] * rs[a][t] / norm
            } else {
                0.0
            }
        })
    };
    let gains: Vec<(usize, [f64; 3])> = range.map(|t| (t, gain(t))).collect();
    let (_, best) = gains
        .iter()
        .max_by(|x, y| x.1.iter().sum::<f64>().total_cmp(&y.1.iter().sum::<f64>()))?;
    let dof = (m as f64 - q.len() as f64 - 2.0).max(1.0);
    let s2: [f64; 3] = std::array::from_fn(|a| ((base[a] - best[a]) / dof).max(f64::MIN_POSITIVE));
    let within = within_deviance(&gains, best, &s2, CHANGE_95);
    Some([*within.first()?, *within.last()?])
}

/// The interval of every row parameter (`row`, `from_row`, `to_row`) of an
/// added step or block from [`profile_rows`], joined with its own: each
/// edge profiled with the `competitors` and the block's other edge
/// refitted. Returns whether an interval changed.
pub(super) fn widen_rows(
    report: &mut EffectReport,
    residuals: &[[f64; 3]],
    competitors: &[Vec<f64>],
    range: std::ops::Range<usize>,
) -> bool {
    let steps = report.change_point_rows();
    let keys: &[&str] = match steps.len() {
        1 => &["row"],
        2 => &["from_row", "to_row"],
        _ => return false,
    };
    let m = residuals.len();
    let mut changed = false;
    for (k, key) in keys.iter().enumerate() {
        let mut cols = competitors.to_vec();
        for (j, row) in steps.iter().enumerate() {
            if j != k {
                cols.push((0..m).map(|i| if i >= *row { 1.0 } else { 0.0 }).collect());
            }
        }
        // a block's edge stays on its side of the other one
        let edge = match (steps.len(), k) {
            (2, 0) => range.start..range.end.min(steps[1]),
            (2, _) => range.start.max(steps[0] + 1)..range.end,
            _ => range.clone(),
        };
        let Some([lo, hi]) = profile_rows(residuals, &cols, edge) else {
            continue;
        };
        let own = report.params.get(*key).copied().unwrap_or(steps[k] as f64);
        let ci = report
            .params_ci
            .entry(key.to_string())
            .or_insert([own, own]);
        let new = [ci[0].min(lo as f64), ci[1].max(hi as f64)];
        changed |= new != *ci;
        *ci = new;
    }
    changed
}

/// Least-squares coefficients of the centred `ys[a]` on the centred,
/// `q[a]`-residualised `x` columns that are regressors of axis `a`
/// (`axes[i]` `None` or `Some(a)`, [`Feature::column_axes`]), and the
/// diagonal of `(XᵀX)⁻¹` of each axis's fit (by solves); a column off an
/// axis, or nothing once residualised (a joint that cannot move that axis:
/// q1's harmonic through the Jacobian on z), has 0 there. `None` when an
/// axis's fit is singular.
fn least_squares(
    x: &[Vec<f64>],
    axes: &[Option<usize>],
    ys: &[Vec<f64>],
    q: [&[Vec<f64>]; 3],
) -> Option<Fit> {
    let dot = |u: &[f64], v: &[f64]| -> f64 { u.iter().zip(v).map(|(a, b)| a * b).sum() };
    let mut beta = vec![[0.0; 3]; x.len()];
    let mut diag = vec![[0.0; 3]; x.len()];
    let (mut fitted, mut columns) = ([0.0; 3], [0usize; 3]);
    for (a, y) in ys.iter().enumerate() {
        let mut on = Vec::new();
        let mut xr: Vec<Vec<f64>> = Vec::new();
        for i in (0..x.len()).filter(|&i| axes[i].is_none_or(|b| b == a)) {
            let scale: f64 = x[i].iter().map(|v| v * v).sum();
            let r = residualise(&x[i], q[a]);
            if dot(&r, &r) > 1e-20 * scale.max(f64::MIN_POSITIVE) {
                on.push(i);
                xr.push(r);
            }
        }
        let k = on.len();
        if k == 0 {
            continue;
        }
        let g = DMatrix::from_fn(k, k, |i, j| dot(&xr[i], &xr[j]));
        let chol = g.cholesky()?;
        let rhs = DVector::from_fn(k, |i, _| dot(&xr[i], y));
        let b = chol.solve(&rhs);
        for (r, &i) in on.iter().enumerate() {
            beta[i][a] = b[r];
            let unit = DVector::from_fn(k, |j, _| if j == r { 1.0 } else { 0.0 });
            diag[i][a] = chol.solve(&unit)[r];
            fitted[a] += b[r] * rhs[r];
        }
        columns[a] = k;
    }
    Some(Fit {
        beta,
        diag,
        fitted,
        columns,
    })
}

/// A [`least_squares`] fit: per column and axis the coefficient and the
/// diagonal of `(XᵀX)⁻¹`, and per axis the fitted sum of squares
/// `bᵀXᵀy` and the columns fitted.
struct Fit {
    beta: Vec<[f64; 3]>,
    diag: Vec<[f64; 3]>,
    fitted: [f64; 3],
    columns: [usize; 3],
}

/// Widen the coefficient intervals `size` of an effect that adds `add`
/// (columns named like its coefficients) by what refitting the
/// `competitors` alongside it does to each estimate on the CV `residuals`
/// of `data` (all rows): columns of every axis, and columns per axis (a
/// calibration's directions, [`crate::calibration::Calibration::seen_displacements`]),
/// and, for each of `alternatives` (the effect's features at other
/// parameter values within their 95 % interval, [`across_period`]), by what
/// refitting it with the competitors does. Returns whether any interval
/// widened.
pub(super) fn widen_coefficients(
    size: &mut [Coefficient],
    data: &Dataset,
    residuals: &[[f64; 3]],
    (add, alternatives): (&[Feature], &[Vec<Feature>]),
    (competitors, per_axis): (&[Vec<f64>], Option<&Displacements>),
) -> bool {
    let names: Vec<String> = add.iter().flat_map(Feature::names).collect();
    let axes: Vec<Option<usize>> = add.iter().flat_map(Feature::column_axes).collect();
    let cols = feature_columns(data, add);
    if cols.len() != names.len() || cols.is_empty() {
        return false;
    }
    let ys: Vec<Vec<f64>> = (0..3)
        .map(|a| residuals.iter().map(|r| r[a]).collect())
        .collect();
    let basis = competitor_basis(competitors, per_axis);
    let none: &[Vec<f64>] = &[];
    let q = [&basis[0][..], &basis[1][..], &basis[2][..]];
    let (Some(alone), Some(with)) = (
        least_squares(&cols, &axes, &ys, [none; 3]),
        least_squares(&cols, &axes, &ys, q),
    ) else {
        return false;
    };
    // the fits with the competitors: at the effect's own parameters, then
    // at each alternative's (the same columns in the same order)
    let mut fits = vec![with];
    for alt in alternatives {
        let c = feature_columns(data, alt);
        if c.len() == cols.len()
            && let Some(fit) = least_squares(&c, &axes, &ys, q)
        {
            fits.push(fit);
        }
    }
    let mut widened = false;
    for c in size.iter_mut() {
        let Some(i) = names.iter().position(|n| n == &c.column) else {
            continue;
        };
        for a in (0..3).filter(|&a| axes[i].is_none_or(|b| b == a)) {
            let h = c.ci95[a];
            let wide = fits.iter().fold(h, |w, with| {
                let inflation = (with.diag[i][a] / alone.diag[i][a]).max(1.0).sqrt();
                let delta = (with.beta[i][a] - alone.beta[i][a]).abs();
                w.max(delta + h * inflation)
            });
            widened |= wide > h;
            c.ci95[a] = wide;
        }
    }
    widened
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A harmonic of q3 on the shipped campaign with noise, and its effect
    /// report as found at `found` with the period interval `ci`.
    fn harmonic_case(
        p0: f64,
        found: f64,
        ci: [f64; 2],
    ) -> (Dataset, Vec<[f64; 3]>, EffectReport, [f64; 2]) {
        let path = concat!(env!("CARGO_MANIFEST_DIR"), "/datasets/comau_lhs.csv");
        let data = crate::dataset::read_csv(path.as_ref()).unwrap();
        let (a0, b0) = (0.08, -0.05);
        let centre = -125.0;
        let noise = |i: usize| (((i * 7919) % 101) as f64 / 101.0 - 0.5) * 0.02;
        let res: Vec<[f64; 3]> = (0..data.len())
            .map(|i| {
                let t = 2.0 * std::f64::consts::PI * (data.q[i][2] - centre) / p0;
                let v = a0 * t.sin() + b0 * t.cos();
                [v + noise(i), noise(i + 7), noise(i + 13)]
            })
            .collect();
        let mut report: EffectReport = serde_json::from_str(
            r#"{"round": 1, "kind": "harmonic", "source": ["q3"], "label": "harmonic of q3",
                "params": {}, "score": 0.5, "explained": 0.5, "p_value": 0.001,
                "q_value": 0.01, "significant": true, "accepted": true}"#,
        )
        .unwrap();
        report.add = vec![Feature::Harmonic {
            joint: 3,
            period_deg: found,
            centre_deg: centre,
        }];
        report.params.insert("period_deg".into(), found);
        report.params_ci.insert("period_deg".into(), ci);
        (data, res, report, [a0, b0])
    }

    /// A column that is nothing on an axis (q1's harmonic through the
    /// Jacobian on z) is left out of that axis's fit, not a singular one.
    #[test]
    fn a_column_that_is_nothing_on_an_axis_is_left_out_there() {
        let m = 50;
        let x: Vec<f64> = (0..m).map(|i| ((i * 13) % 17) as f64).collect();
        let y: Vec<f64> = (0..m).map(|i| ((i * 7) % 11) as f64).collect();
        let ys: Vec<Vec<f64>> = (0..3)
            .map(|a| {
                x.iter()
                    .zip(&y)
                    .map(|(u, v)| u * (a + 1) as f64 + 0.1 * v)
                    .collect()
            })
            .collect();
        // one column per axis, z's all zero
        let cols = vec![x.clone(), x.clone(), vec![0.0; m]];
        let axes = [Some(0), Some(1), Some(2)];
        let none: &[Vec<f64>] = &[];
        let fit = least_squares(&cols, &axes, &ys, [none; 3]).unwrap();
        let (beta, diag) = (&fit.beta, &fit.diag);
        assert!((beta[0][0] - 1.0).abs() < 0.05 && (beta[1][1] - 2.0).abs() < 0.05);
        assert_eq!((beta[2][2], diag[2][2]), (0.0, 0.0));
        assert_eq!(fit.columns, [1, 1, 0]);
    }

    /// A harmonic found a little off its period, with a support interval
    /// that misses the true one: the profile over the period covers it,
    /// and stays within a few per cent.
    #[test]
    fn the_profile_over_the_period_covers_a_harmonic_found_off_it() {
        let p0 = 13.7;
        let found = p0 * 1.02;
        let (data, res, mut report, _) = harmonic_case(p0, found, [found * 0.999, found * 1.001]);
        let drift = drift_columns(data.len());
        assert!(profile_period(&mut report, &data, &res, (&drift, None)));
        let [lo, hi] = report.params_ci["period_deg"];
        assert!(lo <= p0 && p0 <= hi, "[{lo}, {hi}]");
        assert!(hi / lo < 1.1, "[{lo}, {hi}]");
        // an effect without a period has none
        let mut step = report.clone();
        step.add = vec![Feature::Step { row: 10 }];
        step.params_ci.clear();
        assert!(!profile_period(&mut step, &data, &res, (&[], None)));
        assert!(step.params_ci.is_empty());
    }

    /// A harmonic found a little off its period: its coefficients at the
    /// period found miss the true ones; refitted across the period's 95 %
    /// interval they cover them.
    #[test]
    fn a_harmonics_coefficients_cover_the_truth_across_its_period_interval() {
        let p0 = 13.7;
        // 3 % off: the phase turns by up to 0.35 rad at the ends of q3's
        // range (−150° to −100°, counted from its middle)
        let found = p0 * 1.03;
        let (data, res, report, [a0, b0]) = harmonic_case(p0, found, [p0 * 0.99, p0 * 1.04]);
        let add = report.add.clone();
        // the model's own estimate at the period found: least squares, 1.96 SE
        let cols = feature_columns(&data, &add);
        let ys: Vec<Vec<f64>> = (0..3).map(|a| res.iter().map(|r| r[a]).collect()).collect();
        let none: &[Vec<f64>] = &[];
        let fit = least_squares(&cols, &[None, None], &ys, [none; 3]).unwrap();
        let (b, v) = (&fit.beta, &fit.diag);
        let names: Vec<String> = add.iter().flat_map(Feature::names).collect();
        let size = |k: usize| Coefficient {
            column: names[k].clone(),
            estimate: b[k],
            ci95: std::array::from_fn(|a| 1.96 * (v[k][a] * 0.02f64.powi(2) / 12.0).sqrt()),
            axis: None,
        };
        let covers = |c: &[Coefficient]| {
            (c[0].estimate[0] - a0).abs() <= c[0].ci95[0]
                && (c[1].estimate[0] - b0).abs() <= c[1].ci95[0]
        };
        let periods = across_period(&report);
        assert_eq!(periods.len(), PERIOD_POINTS);
        let mut alone = vec![size(0), size(1)];
        assert!(!covers(&alone), "{alone:?}");
        widen_coefficients(&mut alone, &data, &res, (&add, &[]), (&[], None));
        assert!(!covers(&alone), "at the period found alone: {alone:?}");
        let mut across = vec![size(0), size(1)];
        assert!(widen_coefficients(
            &mut across,
            &data,
            &res,
            (&add, &periods),
            (&[], None)
        ));
        assert!(covers(&across), "{across:?}");
        // and not wildly: within a few times the estimates' size
        for c in &across {
            assert!(c.ci95[0] < 0.2, "{c:?}");
        }
    }

    /// A step at a row no grid favours is inside its profile interval, and
    /// the drift refitted alongside widens that interval.
    #[test]
    fn the_profile_interval_covers_the_step_and_widens_with_a_drift() {
        let m = 300;
        let step = 137;
        let noise = |i: usize| (((i * 7919) % 101) as f64 / 101.0 - 0.5) * 0.2;
        let res: Vec<[f64; 3]> = (0..m)
            .map(|i| {
                let s = if i >= step { 0.1 } else { 0.0 };
                let d = 0.3 * i as f64 / m as f64;
                [s + d + noise(i), -s + noise(i + 3), noise(i + 5)]
            })
            .collect();
        let alone = profile_rows(&res, &[], 15..285).unwrap();
        let with = profile_rows(&res, &drift_columns(m), 15..285).unwrap();
        assert!(with[0] <= step && step <= with[1], "{with:?}");
        assert!(
            with[1] - with[0] >= alone[1] - alone[0],
            "{alone:?} {with:?}"
        );
    }
}
