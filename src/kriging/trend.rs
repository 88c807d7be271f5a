//! Trend (regression) models `f(s)ᵀβ` of universal Kriging (seed 003 eq 6).
//!
//! A trend is a [`TrendModel`]: a fixed list of basis functions of the
//! normalised inputs. The built-in [`Monomials`] covers the constant, linear
//! and full quadratic trends and every candidate set of seed 003 eq 15 (all
//! monomials of total degree ≤ η, `C(d+η, η)` of them).

use serde::{Deserialize, Serialize};

/// A set of basis functions of the normalised input `s` (length `dim`).
pub trait TrendModel: Send + Sync {
    /// Number of basis functions p.
    fn len(&self) -> usize;
    /// Whether there is no basis function (ordinary Kriging needs ≥ 1).
    fn is_empty(&self) -> bool {
        self.len() == 0
    }
    /// Input dimension d.
    fn dim(&self) -> usize;
    /// `out[j] = f_j(s)`, `out.len() == self.len()`.
    fn eval_into(&self, s: &[f64], out: &mut [f64]);
    /// Human-readable name of basis function j given the input names.
    fn term_name(&self, j: usize, inputs: &[String]) -> String;
    /// The prior of coefficient `j` in Bayesian universal Kriging
    /// ([`super::problem::KrigingProblem::prior`]): physical terms whose
    /// coefficient is a parameter error get one, a free mean does not.
    /// [`CoefficientPrior::Flat`] by default.
    fn prior(&self, _j: usize) -> CoefficientPrior {
        CoefficientPrior::Flat
    }
    /// The key of coefficient `j` when several outputs share it (one
    /// physical parameter that moves them all, e.g. a kinematic parameter
    /// error moving x, y and z): coefficients of the outputs' trends with
    /// the same key are one unknown
    /// ([`super::model::share_coefficients`]). `None` (the default): the
    /// output's own coefficient.
    fn shared_key(&self, _j: usize) -> Option<usize> {
        None
    }
    /// Whether some coefficient is shared ([`TrendModel::shared_key`]).
    fn has_shared(&self) -> bool {
        (0..self.len()).any(|j| self.shared_key(j).is_some())
    }
}

/// The prior of one trend coefficient in Bayesian universal Kriging,
/// `β_j ~ N(0, τ_j²)` in the units of the normalised response `y`
/// ([`super::problem::KrigingProblem::prior`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum CoefficientPrior {
    /// No prior: a free coefficient (the mean, the monomials).
    Flat,
    /// `τ_j = ‖y‖ / max(‖F_j‖, n)`: the term alone explains at most the
    /// whole response, with its column's norm `‖F_j‖` on the training rows
    /// or `n` if larger. `n = 0` is the term's own column alone.
    Norm(f64),
}

/// Monomials `Π_k s_k^{e_k}`, one exponent vector per basis function.
#[derive(Debug, Clone, PartialEq, Eq, Serialize, Deserialize)]
pub struct Monomials {
    /// Input dimension d of `s`.
    pub dim: usize,
    /// One exponent vector (length `dim`, entries ≤ 8) per basis function.
    pub exponents: Vec<Vec<u8>>,
}

impl Monomials {
    /// Every exponent vector has `dim` entries, each at most 8 (the
    /// shapes [`Self::eval_into`] relies on; for trends read from files).
    pub fn validate(&self) -> std::result::Result<(), String> {
        match self
            .exponents
            .iter()
            .find(|e| e.len() != self.dim || e.iter().any(|&p| p > 8))
        {
            Some(e) => Err(format!(
                "monomial exponents {e:?} do not fit {} inputs of degree ≤ 8",
                self.dim
            )),
            None => Ok(()),
        }
    }

    /// All monomials of total degree ≤ `degree` in `dim` variables, ordered by
    /// degree, then lexicographically (1, s1, …, sd, s1², s1s2, …, sd²):
    /// `C(dim + degree, degree)` terms (seed 003 eq 15).
    pub fn full(dim: usize, degree: u8) -> Self {
        let mut exponents = Vec::new();
        for deg in 0..=degree {
            let mut e = vec![0u8; dim];
            push_degree(&mut exponents, &mut e, 0, deg);
        }
        Monomials { dim, exponents }
    }

    /// `[1]` (ordinary Kriging with unknown mean).
    pub fn constant(dim: usize) -> Self {
        Monomials::full(dim, 0)
    }

    /// `[1, s1, …, sd]`.
    pub fn linear(dim: usize) -> Self {
        Monomials::full(dim, 1)
    }

    /// All monomials of degree ≤ 2: `(d+1)(d+2)/2` terms (91 for d = 12).
    pub fn quadratic(dim: usize) -> Self {
        Monomials::full(dim, 2)
    }

    /// The subset of terms at `keep` (in that order).
    pub fn subset(&self, keep: &[usize]) -> Self {
        Monomials {
            dim: self.dim,
            exponents: keep.iter().map(|&j| self.exponents[j].clone()).collect(),
        }
    }
}

fn push_degree(out: &mut Vec<Vec<u8>>, e: &mut [u8], from: usize, left: u8) {
    if left == 0 {
        out.push(e.to_vec());
        return;
    }
    for k in from..e.len() {
        e[k] += 1;
        push_degree(out, e, k, left - 1);
        e[k] -= 1;
    }
}

impl TrendModel for Monomials {
    fn len(&self) -> usize {
        self.exponents.len()
    }

    fn dim(&self) -> usize {
        self.dim
    }

    fn eval_into(&self, s: &[f64], out: &mut [f64]) {
        for (o, e) in out.iter_mut().zip(&self.exponents) {
            let mut v = 1.0;
            for (x, &p) in s.iter().zip(e) {
                for _ in 0..p {
                    v *= x;
                }
            }
            *o = v;
        }
    }

    fn term_name(&self, j: usize, inputs: &[String]) -> String {
        let parts: Vec<String> = self.exponents[j]
            .iter()
            .enumerate()
            .filter(|(_, p)| **p > 0)
            .map(|(k, p)| {
                let name = inputs
                    .get(k)
                    .cloned()
                    .unwrap_or_else(|| format!("s{}", k + 1));
                if *p == 1 { name } else { format!("{name}^{p}") }
            })
            .collect();
        if parts.is_empty() {
            "1".into()
        } else {
            parts.join("*")
        }
    }
}

/// The linearised kinematic error as a trend (seed 003 eq 4, seed 004 eq 4):
/// `f(s) = [monomials(s); ∂P_a/∂p_j(θ)]` for output axis `a` and the
/// identifiable calibration parameters `p_j`
/// ([`crate::kinematics::calib_names`]). Universal Kriging then estimates
/// their β — the parameter errors — by GLS, and Kriging models what the
/// kinematic errors leave. With [`KinematicTrend::shared`] the three axes'
/// trends estimate one vector of parameter errors together
/// ([`super::model::share_coefficients`]); without it (files written
/// before), each axis its own.
/// The joint angles are recovered from the normalised joint columns
/// (`v = s·std + mean`; `θ = v`, or `θ = atan2(sin, cos)` for a periodic
/// joint, see [`crate::space::Space::encode`]).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct KinematicTrend {
    /// The nominal robot whose identification Jacobian is used.
    pub robot: crate::kinematics::Robot,
    /// Output axis 0, 1, 2 (x, y, z).
    pub axis: usize,
    /// Calibration parameters (indices into `calib_names`).
    pub params: Vec<usize>,
    /// Mean of each encoded joint column of the input (the normalisation the
    /// model's inputs went through).
    pub joint_mean: Vec<f64>,
    /// Standard deviation of each encoded joint column: the raw joint value is
    /// `s_i·joint_std_i + joint_mean_i` (degrees, or sin/cos for a periodic joint).
    pub joint_std: Vec<f64>,
    /// Joints encoded as (sin, cos).
    #[serde(default)]
    pub periodic: Vec<usize>,
    /// Polynomial part (e.g. the constant).
    pub poly: Monomials,
    /// Per calibration parameter (indexed as `calib_names`), the RMS over
    /// the three axes of its Jacobian column on the training poses,
    /// `‖∂P/∂p_j‖ / √3`: the size of the parameter's effect on the TCP,
    /// whichever axis it shows on. Its prior (see
    /// [`TrendModel::prior`]) is no wider than the whole response over that:
    /// one parameter error moves all three axes, so an axis that sees it
    /// weakly may not give it a coefficient the others would not allow.
    /// Empty in files written before it was recorded (the axis's own column
    /// then sets the prior).
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub param_norm: Vec<f64>,
    /// Whether the parameter errors are one vector for the three axes
    /// ([`TrendModel::shared_key`]: the parameter's index), solved jointly
    /// by [`super::model::share_coefficients`], rather than one β per axis.
    /// False in files written before it existed: they predict, and refit,
    /// as they were fitted.
    #[serde(default, skip_serializing_if = "std::ops::Not::not")]
    pub shared: bool,
}

impl KinematicTrend {
    /// Shapes and indices consistent with the robot (for trends read from
    /// files): encoded joint columns `n + |periodic|` with a finite
    /// normalisation, periodic joints and calibration parameters in range.
    pub fn validate(&self) -> std::result::Result<(), String> {
        let n = self.robot.dof();
        let cols = n + self.periodic.len();
        let mut periodic = self.periodic.clone();
        periodic.sort_unstable();
        periodic.dedup();
        if n == 0 || periodic.len() != self.periodic.len() || periodic.iter().any(|&j| j >= n) {
            return Err("kinematic trend: periodic joints out of range".into());
        }
        if self.joint_mean.len() != cols || self.joint_std.len() != cols || self.poly.dim < cols {
            return Err(format!(
                "kinematic trend: {} joint means, {} scales and {} inputs for {cols} joint columns",
                self.joint_mean.len(),
                self.joint_std.len(),
                self.poly.dim
            ));
        }
        let bad_scale = |(m, s): (&f64, &f64)| !(m.is_finite() && s.is_finite() && *s > 0.0);
        if self.joint_mean.iter().zip(&self.joint_std).any(bad_scale) {
            return Err("kinematic trend: a joint normalisation is not finite and positive".into());
        }
        let np = crate::kinematics::calib_len(n);
        if self.axis > 2 || self.params.iter().any(|&p| p >= np) {
            return Err("kinematic trend: axis or calibration parameter out of range".into());
        }
        if !self.param_norm.is_empty()
            && (self.param_norm.len() != np
                || self
                    .param_norm
                    .iter()
                    .any(|v| !(v.is_finite() && *v >= 0.0)))
        {
            return Err(format!(
                "kinematic trend: {} parameter norms for {np} parameters, or one not finite and ≥ 0",
                self.param_norm.len()
            ));
        }
        self.poly.validate()
    }
}

impl TrendModel for KinematicTrend {
    fn len(&self) -> usize {
        self.poly.len() + self.params.len()
    }

    fn dim(&self) -> usize {
        self.poly.dim
    }

    fn eval_into(&self, s: &[f64], out: &mut [f64]) {
        let k = self.poly.len();
        self.poly.eval_into(s, &mut out[..k]);
        let raw = |i: usize| s[i] * self.joint_std[i] + self.joint_mean[i];
        let n = self.robot.dof();
        let mut q = Vec::with_capacity(n);
        let mut c = 0;
        for j in 0..n {
            if self.periodic.contains(&j) {
                q.push(raw(c).atan2(raw(c + 1)).to_degrees());
                c += 2;
            } else {
                q.push(raw(c));
                c += 1;
            }
        }
        let j = crate::kinematics::identification_jacobian_cols(&self.robot, &q, &self.params);
        out[k..].copy_from_slice(&j[self.axis]);
    }

    /// The Jacobian columns: each coefficient is a parameter error seen by
    /// one axis, which no campaign identifies in every direction; its prior
    /// is set by the parameter's effect on all three axes
    /// ([`KinematicTrend::param_norm`]).
    fn prior(&self, j: usize) -> CoefficientPrior {
        let k = self.poly.len();
        if j < k {
            return CoefficientPrior::Flat;
        }
        CoefficientPrior::Norm(
            self.param_norm
                .get(self.params[j - k])
                .copied()
                .unwrap_or(0.0),
        )
    }

    /// With [`KinematicTrend::shared`], a Jacobian column's key is its
    /// calibration parameter (index into `calib_names`).
    fn shared_key(&self, j: usize) -> Option<usize> {
        let k = self.poly.len();
        (self.shared && j >= k).then(|| self.params[j - k])
    }

    fn term_name(&self, j: usize, inputs: &[String]) -> String {
        let k = self.poly.len();
        if j < k {
            return self.poly.term_name(j, inputs);
        }
        let names = crate::kinematics::calib_names(self.robot.dof());
        format!(
            "dP{}/d{}",
            ["x", "y", "z"][self.axis],
            names[self.params[j - k]]
        )
    }
}

/// A trend a fitted model can carry: plain monomials, a PCC+PCA fused
/// basis ([`FusedBasis`](super::FusedBasis), chosen by the `basis`
/// module's selection), or the kinematic-error basis.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "kind", rename_all = "lowercase")]
pub enum Trend {
    /// Monomials of the normalised inputs.
    Monomials(Monomials),
    /// A PCC + PCA fused basis (seed 003 eqs 16–20).
    Fused(super::fused::FusedBasis),
    /// Monomials plus the robot's kinematic-error (identification Jacobian) columns.
    Kinematic(Box<KinematicTrend>),
}

impl From<Monomials> for Trend {
    fn from(m: Monomials) -> Self {
        Trend::Monomials(m)
    }
}

impl Trend {
    /// The trend with only the terms at `keep`.
    pub fn subset(&self, keep: &[usize]) -> Self {
        match self {
            Trend::Monomials(m) => Trend::Monomials(m.subset(keep)),
            Trend::Fused(f) => Trend::Fused(f.subset(keep)),
            Trend::Kinematic(k) => {
                let np = k.poly.len();
                let poly: Vec<usize> = keep.iter().copied().filter(|&j| j < np).collect();
                Trend::Kinematic(Box::new(KinematicTrend {
                    poly: k.poly.subset(&poly),
                    params: keep
                        .iter()
                        .filter(|&&j| j >= np)
                        .map(|&j| k.params[j - np])
                        .collect(),
                    ..k.as_ref().clone()
                }))
            }
        }
    }

    /// Structural consistency of a trend read from a file, so that
    /// evaluating it cannot index out of bounds (found by fuzzing the
    /// model loader).
    pub fn validate(&self) -> std::result::Result<(), String> {
        match self {
            Trend::Monomials(m) => m.validate(),
            Trend::Fused(f) => f.validate(),
            Trend::Kinematic(k) => k.validate(),
        }
    }

    fn inner(&self) -> &dyn TrendModel {
        match self {
            Trend::Monomials(m) => m,
            Trend::Fused(f) => f,
            Trend::Kinematic(k) => k.as_ref(),
        }
    }
}

impl TrendModel for Trend {
    fn len(&self) -> usize {
        self.inner().len()
    }

    fn dim(&self) -> usize {
        self.inner().dim()
    }

    fn eval_into(&self, s: &[f64], out: &mut [f64]) {
        self.inner().eval_into(s, out)
    }

    fn term_name(&self, j: usize, inputs: &[String]) -> String {
        self.inner().term_name(j, inputs)
    }

    fn prior(&self, j: usize) -> CoefficientPrior {
        self.inner().prior(j)
    }

    fn shared_key(&self, j: usize) -> Option<usize> {
        self.inner().shared_key(j)
    }
}

/// The m × p trend matrix `F` (row-major rows of `f(s_i)ᵀ`).
pub fn trend_matrix(trend: &dyn TrendModel, rows: &[Vec<f64>]) -> faer::Mat<f64> {
    let p = trend.len();
    let mut buf = vec![0.0; p];
    let mut f = faer::Mat::zeros(rows.len(), p);
    for (i, r) in rows.iter().enumerate() {
        trend.eval_into(r, &mut buf);
        for (j, v) in buf.iter().enumerate() {
            f[(i, j)] = *v;
        }
    }
    f
}

/// Greedy rank revelation in column order (modified Gram–Schmidt with one
/// re-orthogonalisation): column j is kept when its component orthogonal to
/// the kept columns has norm > `rel_tol`·‖F_j‖ (and ‖F_j‖ > 0). Earlier
/// (lower-degree) columns win, so e.g. `λ²` (≡ affine in λ) is dropped, not `1`.
/// Returns `(kept, dropped)` column indices.
pub fn independent_columns(f: &faer::Mat<f64>, rel_tol: f64) -> (Vec<usize>, Vec<usize>) {
    supported_columns(f, rel_tol, 0.0)
}

/// [`independent_columns`] that also drops a column whose new component
/// (orthogonal to the kept columns) lives on fewer than `min_support` rows:
/// its support `(Σ v_i²)² / Σ v_i⁴` (the participation ratio: n for a
/// component spread evenly over n rows, 1 for one row). A trend coefficient
/// identified by one or two rows takes those rows' noise and residual
/// exactly (leverage 1), and multiplies it wherever the column is large: a
/// Jacobian column that vanishes over a campaign whose tool keeps one
/// direction, except at its home and check poses, gave held-out errors of
/// 4–9 mm against 0.19 mm for the D-H calibration (`tests/no_blow_up.rs`).
pub fn supported_columns(
    f: &faer::Mat<f64>,
    rel_tol: f64,
    min_support: f64,
) -> (Vec<usize>, Vec<usize>) {
    let m = f.nrows();
    let mut basis: Vec<Vec<f64>> = Vec::new();
    let (mut kept, mut dropped) = (Vec::new(), Vec::new());
    for j in 0..f.ncols() {
        let mut v: Vec<f64> = (0..m).map(|i| f[(i, j)]).collect();
        let norm0 = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        for _ in 0..2 {
            for b in &basis {
                let dot: f64 = v.iter().zip(b).map(|(x, y)| x * y).sum();
                v.iter_mut().zip(b).for_each(|(x, y)| *x -= dot * y);
            }
        }
        let norm = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        if norm0 > 0.0 && norm > rel_tol * norm0 && support(&v) >= min_support {
            v.iter_mut().for_each(|x| *x /= norm);
            basis.push(v);
            kept.push(j);
        } else {
            dropped.push(j);
        }
    }
    (kept, dropped)
}

/// Participation ratio `(Σ v_i²)² / Σ v_i⁴` of `v`: the number of rows it is
/// spread over (0 for a zero vector).
pub fn support(v: &[f64]) -> f64 {
    let s2: f64 = v.iter().map(|x| x * x).sum();
    let s4: f64 = v.iter().map(|x| (x * x) * (x * x)).sum();
    if s4 > 0.0 { s2 * s2 / s4 } else { 0.0 }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn candidate_counts_match_seed_003_eq_15() {
        assert_eq!(Monomials::quadratic(12).len(), 91);
        assert_eq!(Monomials::full(12, 3).len(), 455);
        assert_eq!(Monomials::linear(6).len(), 7);
        let q = Monomials::quadratic(2);
        let names: Vec<String> = (0..q.len())
            .map(|j| q.term_name(j, &["a".into(), "b".into()]))
            .collect();
        assert_eq!(names, ["1", "a", "b", "a^2", "a*b", "b^2"]);
        let mut out = vec![0.0; 6];
        q.eval_into(&[2.0, 3.0], &mut out);
        assert_eq!(out, [1.0, 2.0, 3.0, 4.0, 6.0, 9.0]);
    }

    #[test]
    fn binary_squares_are_detected_as_dependent() {
        // s2 is binary, so s2² is affine in (1, s2)
        let rows: Vec<Vec<f64>> = (0..20)
            .map(|i| vec![i as f64 * 0.1, if i % 3 == 0 { 0.7 } else { -1.3 }])
            .collect();
        let f = trend_matrix(&Monomials::quadratic(2), &rows);
        let (kept, dropped) = independent_columns(&f, 1e-10);
        assert_eq!(kept, vec![0, 1, 2, 3, 4]);
        assert_eq!(dropped, vec![5]);
    }
}
