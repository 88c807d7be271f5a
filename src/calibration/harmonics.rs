//! Periodic joint errors: the transmission error of a joint's gears.
//!
//! A gear train does not turn its output by exactly the commanded angle: the
//! eccentricities and tooth errors of its stages add periodic terms in the
//! joint angle. Joint `j` then reaches
//!
//! ```text
//! q_j + δq_j(q_j),    δq_j(q) = Σ_h s_h sin(2π q / P_h) + c_h cos(2π q / P_h)   (degrees),
//! ```
//!
//! and, to first order, the TCP moves by `∂P/∂q_j(q) · δq_j(q_j)`: a
//! harmonic of the joint seen through the Jacobian, whose amplitude at the
//! TCP changes over the workspace with the lever arm. One deviation of the
//! joint moves all three axes, so `s_h, c_h` are shared by x, y and z.
//!
//! # Which periods: a forward search tied to the noise
//!
//! On the residual `r` (3m, stacked x, y, z per pose) of the geometric
//! calibration, each candidate period `P` of joint `j` gives two columns
//! `h_s = J_j(q) sin(2πq_j/P)` and `h_c = J_j(q) cos(2πq_j/P)`. With `H̃`
//! these columns made orthogonal to the geometric directions the campaign
//! sees and to the harmonics already added (Frisch–Waugh), adding the pair
//! lowers the residual sum of squares by
//!
//! ```text
//! Δ = bᵀ A⁻¹ b,    A = H̃ᵀH̃,  b = H̃ᵀ r.
//! ```
//!
//! Without a harmonic at `P` and with residual noise of variance `s²` per
//! coordinate, `Δ / s²` is χ² with 2 degrees of freedom, `P(χ²₂ > x) =
//! e^{−x/2}`. Over the `N` periods scanned, the largest exceeds
//!
//! ```text
//! Δ / s² > 2 ln(N / α)
//! ```
//!
//! with probability at most `α` (Bonferroni): a harmonic is added only
//! then, with `α =` [`FALSE_ALARM`]. The search repeats on the new residual
//! until nothing passes (at most [`MAX_PER_JOINT`] per joint: the periods
//! of a joint are a short Fourier series of its angular deviation, as the
//! lookup tables of the physics models keep it). A harmonic must also be a
//! small deviation: its amplitude `A` (radians) keeps the second-order
//! term the Jacobian leaves out, `ℓ A²/2` with `ℓ` the joint's largest
//! lever over the campaign, below the noise `s`; a larger one is a
//! direction the joint barely moves the TCP in, not a gear error. The noise
//! `s` is the residual's own (everything the geometric model leaves). On
//! a campaign of random poses its smooth part is nearly uncorrelated with
//! a short-period harmonic and acts as noise; a smooth structure the
//! geometric model lacks can still pass as a series of periods, which is
//! one reason for the bound per joint. A backlash of each joint whose
//! direction reverses (`∂P/∂q_j · λ_j`) is refitted beside every candidate
//! and left to the Kriging, so that a harmonic does not take up a
//! direction effect.
//!
//! The coefficients are then fitted to the geometric residual beside the
//! geometric directions, which are refitted with them, when that lowers
//! the residual by more than the level-`α` bound of χ²ₖ (`chi2_bound`,
//! `k` the directions seen); otherwise beside the backlash alone, the
//! geometry kept (see `Geometric::with_harmonics` in the parent module).
//!
//! The periods scanned are those of the diagnosis' harmonic candidates
//! ([`scan_periods`]): from half the joint's range down to [`MIN_PERIOD`],
//! a tenth of a cycle over the range apart, and no shorter than four
//! spacings of the campaign's distinct joint values (a period must be
//! sampled to be seen). The best period of each joint is then refined
//! three times, each ten times finer (as [`zoom_periods`]), to 10⁻⁴ of a
//! cycle over the range.

use crate::kinematics::{JointKind, Robot};
use crate::{Error, Result};
use nalgebra::{DMatrix, DVector, Matrix3xX};
use rayon::prelude::*;
use serde::{Deserialize, Serialize};

/// Cycles over a joint's range between two scanned periods.
pub const CYCLE_STEP: f64 = 0.1;

/// Steps of a zoom per [`CYCLE_STEP`].
pub const ZOOM_STEPS: usize = 10;

/// The shortest period scanned (degrees).
pub const MIN_PERIOD: f64 = 2.0;

/// Most periods scanned per joint.
const MAX_PERIODS: usize = 480;

/// Chance that noise alone adds a harmonic in one round of the search.
pub const FALSE_ALARM: f64 = 0.01;

/// Most harmonics added per joint. A gear train has a few stages; a longer
/// series fits a campaign's local structure between its samples: on UR10
/// series B with 16 per joint, a held-out pose in a gap of q2 got 1.9 mm
/// of error from a coherent sum of its harmonics, with 4 it did not.
pub const MAX_PER_JOINT: usize = 4;

/// One periodic error of a joint: it reaches `q + s·sin(2πq/P) + c·cos(2πq/P)`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct JointHarmonic {
    /// 1-based joint.
    pub joint: usize,
    /// Period P in the joint's value, degrees.
    pub period_deg: f64,
    /// Coefficient `s` of the sine, degrees.
    pub sin_deg: f64,
    /// Coefficient `c` of the cosine, degrees.
    pub cos_deg: f64,
    /// `Δ / s²` when it was added: χ²₂ if there were no harmonic.
    pub evidence: f64,
    /// RMS over the campaign's poses of the TCP displacement it causes
    /// (3D, mm): what it matters at the tool, whatever the joint's lever.
    #[serde(default)]
    pub tcp_rms_mm: f64,
}

impl JointHarmonic {
    /// The joint's deviation at value `q`, degrees.
    pub fn deviation(&self, q: f64) -> f64 {
        let (s, c) = self.unit_terms(q);
        self.sin_deg * s + self.cos_deg * c
    }

    /// `(sin, cos)` of the harmonic's phase at joint value `q`: the
    /// deviation per unit coefficient.
    pub fn unit_terms(&self, q: f64) -> (f64, f64) {
        self.phase(q).sin_cos()
    }

    /// Amplitude `√(s² + c²)`, degrees.
    pub fn amplitude_deg(&self) -> f64 {
        self.sin_deg.hypot(self.cos_deg)
    }

    fn phase(&self, q: f64) -> f64 {
        std::f64::consts::TAU * q / self.period_deg
    }

    /// Error unless the joint exists, the period is positive and the
    /// coefficients are finite.
    pub(crate) fn validate(&self, dof: usize) -> std::result::Result<(), String> {
        if self.joint == 0 || self.joint > dof {
            return Err(format!(
                "a joint harmonic of joint {} on a {dof}-joint robot",
                self.joint
            ));
        }
        let finite = [self.sin_deg, self.cos_deg, self.evidence, self.tcp_rms_mm]
            .iter()
            .all(|v| v.is_finite());
        if !(self.period_deg.is_finite() && self.period_deg > 0.0 && finite) {
            return Err(format!(
                "a joint harmonic of q{} is not finite or has no positive period",
                self.joint
            ));
        }
        Ok(())
    }
}

/// The harmonics of each joint (1-based), joints in order.
pub fn by_joint(
    harmonics: &[JointHarmonic],
) -> std::collections::BTreeMap<usize, Vec<&JointHarmonic>> {
    let mut out = std::collections::BTreeMap::<usize, Vec<&JointHarmonic>>::new();
    for h in harmonics {
        out.entry(h.joint).or_default().push(h);
    }
    out
}

/// The joint values `q` with every harmonic's deviation added.
pub fn deviated(harmonics: &[JointHarmonic], q: &[f64]) -> Vec<f64> {
    let mut out = q.to_vec();
    for h in harmonics {
        out[h.joint - 1] += h.deviation(q[h.joint - 1]);
    }
    out
}

/// The periods a harmonic of a joint with range `range` (degrees) is
/// scanned at: from half the range down to `shortest` (at least
/// [`MIN_PERIOD`]), [`CYCLE_STEP`] of a cycle over the range apart, at most
/// 480.
pub fn scan_periods(range: f64, shortest: f64) -> Vec<f64> {
    let shortest = shortest.max(MIN_PERIOD);
    let mut periods = Vec::new();
    let mut cycles = 2.0;
    while range / cycles >= shortest && periods.len() < MAX_PERIODS {
        periods.push(range / cycles);
        cycles += CYCLE_STEP;
    }
    periods
}

/// The periods within one scanned step of `period` on a joint of range
/// `range`, a tenth of a step apart (both sides, nearest first), inside
/// the scanned span.
pub fn zoom_periods(range: f64, period: f64) -> Vec<f64> {
    zoom_at(range, period, CYCLE_STEP / ZOOM_STEPS as f64)
}

/// The periods `1..=ZOOM_STEPS` steps of `step` cycles over the range
/// either side of `period`, inside the scanned span.
fn zoom_at(range: f64, period: f64, step: f64) -> Vec<f64> {
    let cycles = range / period;
    (1..=ZOOM_STEPS)
        .flat_map(|k| [-(k as f64), k as f64])
        .map(|k| range / (cycles + k * step))
        .filter(|p| p.is_finite() && *p >= MIN_PERIOD && *p <= range / 2.0)
        .collect()
}

/// What [`search`] chose: the periods, before their coefficients.
#[derive(Debug, Clone)]
pub(crate) struct Found {
    /// Per harmonic added: 0-based joint, period (degrees), evidence `Δ/s²`.
    pub chosen: Vec<(usize, f64, f64)>,
    /// Their stacked columns (3m), two per harmonic (sine, cosine).
    pub columns: Vec<DVector<f64>>,
    /// Residual variance per coordinate with the geometric directions, the
    /// backlash and the harmonics fitted, mm².
    pub noise: f64,
}

/// The harmonics' coefficients ([`coefficients`]).
#[derive(Debug, Clone)]
pub(crate) struct HarmonicFit {
    /// The harmonics added, with their coefficients.
    pub harmonics: Vec<JointHarmonic>,
    /// Covariance of the coefficients `(s_1, c_1, s_2, …)`, degrees²,
    /// row-major `2h × 2h`.
    pub covariance: Vec<f64>,
    /// TCP displacement of the harmonics at each pose (first order), mm.
    pub shift: Vec<[f64; 3]>,
}

/// Per-pose position Jacobians per degree (per mm) of each joint value, at
/// `robot`'s parameters.
pub(crate) fn jacobians(robot: &Robot, joints: &[Vec<f64>]) -> Result<Vec<Matrix3xX<f64>>> {
    joints
        .par_iter()
        .map(|q| {
            let mut j = robot.position_jacobian(q)?;
            for i in 0..robot.dof() {
                j.column_mut(i).scale_mut(robot.unit_scale(i));
            }
            Ok(j)
        })
        .collect()
}

/// A backlash of each joint whose approach direction reverses in `dirs`:
/// the stacked column `J_j(q_k) λ_kj` (3m), the TCP displacement of a joint
/// step that follows the direction.
pub(crate) fn backlash_columns(
    jac: &[Matrix3xX<f64>],
    dirs: Option<&[Vec<f64>]>,
) -> Vec<DVector<f64>> {
    let Some(dirs) = dirs.filter(|d| d.len() == jac.len()) else {
        return Vec::new();
    };
    let n = jac.first().map_or(0, |j| j.ncols());
    super::backlash::reversing(dirs, n)
        .into_iter()
        .map(|j| super::backlash::column(jac, dirs, j))
        .collect()
}

/// The two stacked columns (3m each, x, y, z per pose) of joint `j`
/// (0-based) at `period`: [`crate::features::jacobian_sin_cos_at`], laid
/// out as the residual is.
fn columns(
    jac: &[Matrix3xX<f64>],
    joints: &[Vec<f64>],
    j: usize,
    period: f64,
) -> [DVector<f64>; 2] {
    let w = std::f64::consts::TAU / period;
    let c = crate::features::jacobian_sin_cos_at(jac, joints, j + 1, |q| w * q[j]);
    let stacked = |f: usize| DVector::from_fn(3 * joints.len(), |i, _| c[3 * f + i % 3][i / 3]);
    [stacked(0), stacked(1)]
}

/// `A⁻¹b` of a symmetric 2×2 `A = [a₀ a₁; a₁ a₂]`, or `None` if `A` is
/// not positive definite.
fn solve_2x2(a: [f64; 3], b: [f64; 2]) -> Option<[f64; 2]> {
    let [ass, asc, acc] = a;
    let det = ass * acc - asc * asc;
    if det.is_nan() || det <= 1e-12 * (ass * acc).max(f64::MIN_POSITIVE) {
        return None;
    }
    Some([
        (acc * b[0] - asc * b[1]) / det,
        (ass * b[1] - asc * b[0]) / det,
    ])
}

/// `Δ = bᵀA⁻¹b` of a 2×2 `A` (0 if `A` is not positive definite).
fn drop_2x2(a: [f64; 3], b: [f64; 2]) -> f64 {
    solve_2x2(a, b).map_or(0.0, |x| b[0] * x[0] + b[1] * x[1])
}

/// Per pose of joint `j`: `‖J_j‖²` and `J_j·r_k` (the scan's sums need nothing else).
fn per_pose(jac: &[Matrix3xX<f64>], r: &DVector<f64>, j: usize) -> Vec<(f64, f64)> {
    jac.iter()
        .enumerate()
        .map(|(k, jq)| {
            let col = jq.column(j);
            let rk = r.fixed_rows::<3>(3 * k);
            (col.norm_squared(), col.dot(&rk))
        })
        .collect()
}

/// Unprojected `Δ` of joint `j` at `period` (an upper bound of `A` and so
/// a slight underestimate of the drop: the scan's ranking).
fn scan_drop(joints: &[Vec<f64>], pp: &[(f64, f64)], j: usize, period: f64) -> f64 {
    let w = std::f64::consts::TAU / period;
    let (mut a, mut b) = ([0.0; 3], [0.0; 2]);
    for (q, (n2, jr)) in joints.iter().zip(pp) {
        let (s, c) = (w * q[j]).sin_cos();
        a[0] += s * s * n2;
        a[1] += s * c * n2;
        a[2] += c * c * n2;
        b[0] += s * jr;
        b[1] += c * jr;
    }
    drop_2x2(a, b)
}

/// The range of joint `j` over `joints` and the shortest period its
/// sampling resolves (four spacings of its distinct values, 0.01° apart).
fn sampling(joints: &[Vec<f64>], j: usize) -> (f64, f64) {
    let mut v: Vec<i64> = joints
        .iter()
        .map(|q| (q[j] * 100.0).round() as i64)
        .collect();
    v.sort_unstable();
    v.dedup();
    let range = v
        .last()
        .zip(v.first())
        .map_or(0.0, |(hi, lo)| (hi - lo) as f64 / 100.0);
    (range, 4.0 * range / v.len().max(1) as f64)
}

/// Zoom levels after the scan, each ten times finer: the last resolves
/// 10⁻⁴ of a cycle over the range, so that a harmonic's period is not off
/// by enough to leave a sideband of it above the noise.
const ZOOM_LEVELS: i32 = 3;

/// The best period of joint `j` on the residual: scanned, then zoomed
/// [`ZOOM_LEVELS`] times around the best so far.
fn best_period(
    joints: &[Vec<f64>],
    pp: &[(f64, f64)],
    j: usize,
    periods: &[f64],
    range: f64,
) -> Option<f64> {
    let best = |ps: &[f64]| {
        ps.par_iter()
            .map(|&p| (p, scan_drop(joints, pp, j, p)))
            .max_by(|a, b| a.1.total_cmp(&b.1))
    };
    let mut top = best(periods)?;
    for level in 1..=ZOOM_LEVELS {
        let step = CYCLE_STEP / (ZOOM_STEPS as f64).powi(level);
        if let Some(z) = best(&zoom_at(range, top.0, step))
            && z.1 > top.1
        {
            top = z;
        }
    }
    Some(top.0)
}

/// An orthonormal basis grown one column at a time (twice-run
/// Gram–Schmidt), and the residual of `r_geo` projected off it.
#[derive(Clone)]
pub(super) struct Basis {
    q: Vec<DVector<f64>>,
    r: DVector<f64>,
}

impl Basis {
    /// The span of `columns`, with `r` projected off it.
    pub(super) fn new<C: std::borrow::Borrow<DVector<f64>>>(
        columns: impl Iterator<Item = C>,
        r: &DVector<f64>,
    ) -> Self {
        let mut b = Basis {
            q: Vec::new(),
            r: r.clone(),
        };
        for c in columns {
            b.push(c.borrow());
        }
        b
    }

    /// `v` with its part in the span removed.
    pub(super) fn project_out(&self, v: &DVector<f64>) -> DVector<f64> {
        let mut v = v.clone();
        for _ in 0..2 {
            for q in &self.q {
                let d = q.dot(&v);
                v.axpy(-d, q, 1.0);
            }
        }
        v
    }

    /// Add `v`'s new direction (if it has one), and take it off the residual.
    pub(super) fn push(&mut self, v: &DVector<f64>) {
        let w = self.project_out(v);
        let n = w.norm();
        if n > 1e-10 * v.norm() {
            let w = w / n;
            let d = w.dot(&self.r);
            self.r.axpy(-d, &w, 1.0);
            self.q.push(w);
        }
    }

    /// The residual, projected off the span.
    pub(super) fn residual(&self) -> &DVector<f64> {
        &self.r
    }

    /// The least squares of `r` on `cols` beside the span (Frisch–Waugh:
    /// each column with its part in the span removed): the coefficients,
    /// and their covariance `noise · (C̃ᵀC̃)⁻¹`, row-major. An error names
    /// `what` when the columns are not independent beside the span.
    pub(super) fn fit_beside(
        &self,
        cols: impl Iterator<Item = DVector<f64>>,
        r: &DVector<f64>,
        noise: f64,
        what: &str,
    ) -> Result<(DVector<f64>, Vec<f64>)> {
        let tilde: Vec<DVector<f64>> = cols.map(|c| self.project_out(&c)).collect();
        let c = DMatrix::from_columns(&tilde);
        let chol = c
            .tr_mul(&c)
            .cholesky()
            .ok_or_else(|| Error::Numerical(format!("{what} are not independent")))?;
        let beta = chol.solve(&c.tr_mul(r));
        let covariance = (chol.inverse() * noise).transpose().as_slice().to_vec();
        Ok((beta, covariance))
    }

    /// Residual variance per coordinate.
    pub(super) fn noise(&self) -> f64 {
        let left = self.r.len().saturating_sub(self.q.len()).max(1);
        self.r.norm_squared() / left as f64
    }
}

/// `Δ / s²` of the columns of joint `j` at `period` beside `basis`, or 0
/// when the harmonic it would fit is not a small deviation (see the
/// module documentation; `lever` is the joint's largest `‖J_j‖`, mm per
/// degree).
fn evidence(
    basis: &Basis,
    (jac, joints): (&[Matrix3xX<f64>], &[Vec<f64>]),
    (j, p): (usize, f64),
    lever: f64,
) -> f64 {
    let [hs, hc] = columns(jac, joints, j, p).map(|h| basis.project_out(&h));
    let b = [hs.dot(&basis.r), hc.dot(&basis.r)];
    let Some(coef) = solve_2x2([hs.dot(&hs), hs.dot(&hc), hc.dot(&hc)], b) else {
        return 0.0;
    };
    let rad = coef[0].hypot(coef[1]).to_radians();
    // lever per degree → per radian: ℓ = lever·180/π
    let second_order = lever.to_degrees() * rad * rad / 2.0;
    if second_order.is_nan() || second_order >= basis.noise().sqrt() {
        return 0.0;
    }
    (b[0] * coef[0] + b[1] * coef[1]) / basis.noise()
}

/// Forward search for joint harmonics on the residual `r_geo` (3m) of a
/// geometric calibration whose seen directions move the TCP by the
/// columns of `geometric` (3m × k), with the `backlash` columns
/// ([`backlash_columns`]) refitted beside every candidate: see the module
/// documentation. Each round takes every joint's best period, strongest
/// first, and adds those that still pass beside the ones added before
/// them. `jac` are the per-pose Jacobians per degree ([`jacobians`]).
pub(crate) fn search(
    robot: &Robot,
    joints: &[Vec<f64>],
    jac: &[Matrix3xX<f64>],
    r_geo: &DVector<f64>,
    geometric: &DMatrix<f64>,
    backlash: &[DVector<f64>],
) -> Found {
    let grids: Vec<(usize, f64, Vec<f64>)> = (0..robot.dof())
        .filter(|&j| robot.links[j].kind == JointKind::Revolute)
        .map(|j| {
            let (range, shortest) = sampling(joints, j);
            (j, range, scan_periods(range, shortest))
        })
        .filter(|(_, _, p)| !p.is_empty())
        .collect();
    let scanned: usize = grids.iter().map(|(_, _, p)| p.len()).sum();
    let threshold = 2.0 * (scanned.max(1) as f64 / FALSE_ALARM).ln();
    let mut chosen: Vec<(usize, f64, f64)> = Vec::new(); // joint, period, evidence
    let mut columns_added = Vec::new();
    let mut basis = Basis::new(
        geometric
            .column_iter()
            .map(|c| c.into_owned())
            .chain(backlash.iter().cloned()),
        r_geo,
    );
    let levers: Vec<f64> = (0..robot.dof())
        .map(|j| jac.iter().map(|jq| jq.column(j).norm()).fold(0.0, f64::max))
        .collect();
    loop {
        let mut round: Vec<(usize, f64, f64)> = grids
            .par_iter()
            .filter(|(j, _, _)| chosen.iter().filter(|c| c.0 == *j).count() < MAX_PER_JOINT)
            .filter_map(|(j, range, periods)| {
                let pp = per_pose(jac, &basis.r, *j);
                let p = best_period(joints, &pp, *j, periods, *range)?;
                Some((*j, p, evidence(&basis, (jac, joints), (*j, p), levers[*j])))
            })
            .collect();
        round.sort_by(|a, b| b.2.total_cmp(&a.2));
        let before = chosen.len();
        for (i, &(j, p, first)) in round.iter().enumerate() {
            // the strongest as scanned; the others beside those just added
            let e = if i == 0 {
                first
            } else {
                evidence(&basis, (jac, joints), (j, p), levers[j])
            };
            if e > threshold {
                chosen.push((j, p, e));
                for h in columns(jac, joints, j, p) {
                    basis.push(&h);
                    columns_added.push(h);
                }
            }
        }
        if chosen.len() == before {
            break;
        }
    }
    Found {
        chosen,
        columns: columns_added,
        noise: basis.noise(),
    }
}

/// The coefficients of the harmonics `found`, fitted to the geometric
/// residual `r_geo` beside the columns `beside` (the geometric directions
/// refitted with them and the backlash; Frisch–Waugh): `(H̃ᵀH̃)⁻¹ H̃ᵀ r_geo`
/// with `H̃` the harmonics' columns off the span of `beside`, and
/// covariance `s² (H̃ᵀH̃)⁻¹`. Without the geometric directions in
/// `beside`, `r_geo` is already off their span and this bounds the
/// covariance from above.
pub(crate) fn coefficients(
    found: &Found,
    beside: impl Iterator<Item = DVector<f64>>,
    r_geo: &DVector<f64>,
) -> Result<HarmonicFit> {
    let (beta, covariance) = Basis::new(beside, r_geo).fit_beside(
        found.columns.iter().cloned(),
        r_geo,
        found.noise,
        "the joint harmonics' columns",
    )?;
    let raw = &found.columns;
    let m = r_geo.len() / 3;
    let harmonics = found
        .chosen
        .iter()
        .enumerate()
        .map(|(i, &(j, p, evidence))| {
            let tcp = &raw[2 * i] * beta[2 * i] + &raw[2 * i + 1] * beta[2 * i + 1];
            JointHarmonic {
                joint: j + 1,
                period_deg: p,
                sin_deg: beta[2 * i],
                cos_deg: beta[2 * i + 1],
                evidence,
                tcp_rms_mm: tcp.norm() / (m as f64).sqrt(),
            }
        })
        .collect();
    let mut shift = vec![[0.0; 3]; m];
    for (h, b) in raw.iter().zip(beta.iter()) {
        for (k, s) in shift.iter_mut().enumerate() {
            for a in 0..3 {
                s[a] += h[3 * k + a] * b;
            }
        }
    }
    Ok(HarmonicFit {
        harmonics,
        covariance,
        shift,
    })
}

/// The Laurent–Massart bound of χ²ₖ: `P(χ²ₖ ≥ k + 2√(k x) + 2x) ≤ e^{−x}`
/// (Laurent & Massart 2000, *Ann. Statist.* 28(5), Lemma 1), at
/// `x = ln(1/α)`: a level-`α` threshold without a quantile function.
pub(crate) fn chi2_bound(k: usize, alpha: f64) -> f64 {
    let (k, x) = (k as f64, (1.0 / alpha).ln());
    k + 2.0 * (k * x).sqrt() + 2.0 * x
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_chi2_bound_is_above_the_quantile_and_not_far() {
        // 99 % quantiles of χ²ₖ (tables)
        for (k, q) in [(1, 6.635), (10, 23.209), (23, 41.638), (39, 62.428)] {
            let b = chi2_bound(k, 0.01);
            assert!(b >= q, "k {k}: {b} below {q}");
            assert!(k < 10 || b < 1.5 * q, "k {k}: {b} against {q}");
        }
    }

    #[test]
    fn periods_span_half_the_range_down_to_the_sampling_limit() {
        let p = scan_periods(360.0, 0.5);
        assert_eq!(p[0], 180.0);
        assert!(p.iter().all(|&x| x >= MIN_PERIOD));
        assert!(p.len() <= MAX_PERIODS);
        let coarse = scan_periods(360.0, 30.0);
        assert!(coarse.iter().all(|&x| x >= 30.0) && coarse.len() < p.len());
        let z = zoom_periods(360.0, 20.0);
        assert_eq!(z.len(), 2 * ZOOM_STEPS);
        assert!(
            z.iter()
                .all(|&x| (x - 20.0).abs() < 20.0 * 20.0 / 360.0 * CYCLE_STEP * 1.01)
        );
    }

    #[test]
    fn the_drop_of_a_pair_is_its_projection() {
        // A = I: Δ = |b|²; singular A: nothing
        assert!((drop_2x2([1.0, 0.0, 1.0], [3.0, 4.0]) - 25.0).abs() < 1e-12);
        assert_eq!(drop_2x2([1.0, 1.0, 1.0], [1.0, 1.0]), 0.0);
    }
}
