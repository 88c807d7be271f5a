//! Correlation models `R(s, s')` (seed 003 eqs 7–8) and the fill of the
//! correlation matrix R.
//!
//! Every family here is stationary and anisotropic, with one parameter
//! ξ_k ≥ 0 per normalised input: with the scaled distance
//! `h = √(Σ_k ξ_k (s_k − s'_k)²)` (ξ_k = 1/ℓ_k², a length scale ℓ_k per input)
//!
//! | family | `R(h)` |
//! |---|---|
//! | [`Correlation::Gaussian`] (seed 003 eq 8) | `exp(−h²)` |
//! | [`Correlation::Matern52`] | `(1 + u + u²/3)·exp(−u)`, `u = √5·h` |
//! | [`Correlation::Matern32`] | `(1 + u)·exp(−u)`, `u = √3·h` |
//! | [`Correlation::Exponential`] | `exp(−h)` |
//!
//! and `∂R/∂ln ξ_k = q(h)·ξ_k (s_k − s'_k)²` with `q = R′(h)/(2h)`:
//! `−R`, `−(5/6)(1 + u)·exp(−u)`, `−(3/2)·exp(−u)` and `−exp(−h)/(2h)`
//! (0 at h = 0, where every weighted difference vanishes).

use super::registry::CustomCorrelation;
use serde::{Deserialize, Serialize};

/// A stationary correlation model with one parameter per input dimension.
pub trait CorrelationModel: Send + Sync {
    /// `R(a, b)` for parameters `theta`.
    fn corr(&self, theta: &[f64], a: &[f64], b: &[f64]) -> f64;

    /// `out[k] = R(s_i, s_{i+1+k})` for all training rows after row `i`
    /// (one column of R's strict lower triangle). The hot loop of every
    /// likelihood evaluation; override it with a vectorised version.
    fn fill_column(&self, theta: &[f64], x: &TrainingInputs, i: usize, out: &mut [f64]) {
        let a = x.row(i);
        for (k, o) in out.iter_mut().enumerate() {
            *o = self.corr(theta, &a, &x.row(i + 1 + k));
        }
    }

    /// Gradient hook of the likelihood. Every family here has
    /// `∂R/∂ln ξ_k = q · ξ_k (s_k − s'_k)²` (module doc); for column `i` of
    /// R's strict lower triangle this scales `w[j] ← −q(s_i, s_{i+1+j}) · w[j]`,
    /// where `r[j] = R(s_i, s_{i+1+j})` are the values [`Self::fill_column`]
    /// wrote (the Gaussian's `−q` is R itself). The likelihood then contracts
    /// the weights with the squared differences of every input at once.
    fn gradient_weights(
        &self,
        theta: &[f64],
        x: &TrainingInputs,
        i: usize,
        r: &[f64],
        w: &mut [f64],
    );

    /// `out[j] = R(s, s_j)` for every training row j: the correlation vector
    /// of a prediction point. Override it with a vectorised version.
    fn fill_row(&self, theta: &[f64], x: &TrainingInputs, s: &[f64], out: &mut [f64]) {
        for (j, o) in out.iter_mut().enumerate() {
            *o = self.corr(theta, s, &x.row(j));
        }
    }
}

/// The correlation families, saved by name in model files (`"gaussian"`,
/// `"matern52"`, `"matern32"`, `"exponential"`, or a registered family's
/// name); files without one are Gaussian. See the [module docs](self) for
/// the formulas.
#[derive(Debug, Clone, Copy, Default)]
pub enum Correlation {
    /// `exp(−h²)`, seed 003 eq 8: the papers' family.
    #[default]
    Gaussian,
    /// Matérn ν = 5/2: twice differentiable.
    Matern52,
    /// Matérn ν = 3/2: once differentiable.
    Matern32,
    /// `exp(−h)` (Matérn ν = 1/2): continuous, not differentiable.
    Exponential,
    /// A family defined outside the crate, registered by name
    /// ([`Correlation::register`]). Fits, model files and predictions take it
    /// as they take the built-in families; the choice by CV
    /// ([`super::CorrChoice::ByCv`]) tries the built-in ones only.
    Custom(&'static CustomCorrelation),
}

impl PartialEq for Correlation {
    /// Families are equal when their names are (a registered name is unique).
    fn eq(&self, other: &Self) -> bool {
        self.name() == other.name()
    }
}

impl Eq for Correlation {}

impl Correlation {
    /// Every built-in family, Gaussian first.
    pub const ALL: [Correlation; 4] = [
        Correlation::Gaussian,
        Correlation::Matern52,
        Correlation::Matern32,
        Correlation::Exponential,
    ];

    /// The name used in model files and on the command line.
    pub fn name(self) -> &'static str {
        match self {
            Correlation::Gaussian => "gaussian",
            Correlation::Matern52 => "matern52",
            Correlation::Matern32 => "matern32",
            Correlation::Exponential => "exponential",
            Correlation::Custom(c) => c.name(),
        }
    }

    /// The family called `name` ([`Correlation::name`]): a built-in one or
    /// one registered in this process.
    pub fn parse(name: &str) -> Option<Correlation> {
        Self::ALL
            .into_iter()
            .find(|c| c.name() == name)
            .or_else(|| super::registry::find(name).map(Correlation::Custom))
    }

    /// `R` from the squared scaled distance `s = h²` (built-in families;
    /// a registered one answers through its own [`CorrelationModel`]).
    #[inline]
    fn radial(self, s: f64) -> f64 {
        match self {
            Correlation::Gaussian => (-s).exp(),
            Correlation::Matern52 => {
                let u = (5.0 * s).sqrt();
                (1.0 + u + u * u / 3.0) * (-u).exp()
            }
            Correlation::Matern32 => {
                let u = (3.0 * s).sqrt();
                (1.0 + u) * (-u).exp()
            }
            Correlation::Exponential => (-s.sqrt()).exp(),
            Correlation::Custom(c) => unreachable!("{} is not radial here", c.name()),
        }
    }

    /// `q(h) = R′(h)/(2h)` from `s = h²` (see the module docs; built-in
    /// families only).
    #[inline]
    fn slope(self, s: f64) -> f64 {
        match self {
            Correlation::Gaussian => -(-s).exp(),
            Correlation::Matern52 => {
                let u = (5.0 * s).sqrt();
                -(5.0 / 6.0) * (1.0 + u) * (-u).exp()
            }
            Correlation::Matern32 => -1.5 * (-(3.0 * s).sqrt()).exp(),
            Correlation::Exponential if s > 0.0 => {
                let h = s.sqrt();
                -(-h).exp() / (2.0 * h)
            }
            Correlation::Exponential => 0.0,
            Correlation::Custom(c) => unreachable!("{} is not radial here", c.name()),
        }
    }
}

impl Serialize for Correlation {
    fn serialize<S: serde::Serializer>(&self, s: S) -> std::result::Result<S::Ok, S::Error> {
        s.serialize_str(self.name())
    }
}

impl<'de> Deserialize<'de> for Correlation {
    fn deserialize<D: serde::Deserializer<'de>>(d: D) -> std::result::Result<Self, D::Error> {
        let name = String::deserialize(d)?;
        Correlation::parse(&name).ok_or_else(|| {
            serde::de::Error::custom(format!(
                "unknown correlation family \"{name}\" (built-in: gaussian, matern52, matern32, \
                 exponential; a family of your own must be registered with \
                 Correlation::register before its model file is read)"
            ))
        })
    }
}

impl std::fmt::Display for Correlation {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.name())
    }
}

/// Correlations below this are set to 0 in R ([`TrainingInputs::fill_lower`]).
///
/// With short length scales (large ξ, which the search visits and which a
/// campaign of separated clusters — ISO 9283 cubes — can keep) most of R is
/// vanishingly small, and the Cholesky factorisation's products of such
/// entries fall below `f64::MIN_POSITIVE`: subnormal arithmetic, which x86
/// CPUs run one to two orders of magnitude slower. On a 632-pose UR10 cube
/// campaign the kinematic-trend JS fit spent 85 s in it, 10 s without
/// (`cargo bench --bench xi_choice`). Entries of at least 1e-150 keep every
/// product of two normal; what is dropped is 1e-150 of the unit diagonal,
/// far below the last bit of anything R's factor enters.
pub const TINY_CORRELATION: f64 = 1e-150;

/// `out[k] = c · Σ_d ξ_d (x_id − x_{i+1+k,d})²` for the rows after row `i`
/// (`c` = −1 gives the Gaussian's exponent).
fn sq_dist_column(theta: &[f64], x: &TrainingInputs, i: usize, c: f64, out: &mut [f64]) {
    scaled_sq_dist(
        theta,
        |k| x.dim_values(k)[i],
        |k| &x.dim_values(k)[i + 1..],
        c,
        out,
    );
}

/// `out[j] = c · Σ_d ξ_d (s_d − x_jd)²` for every training row j.
fn sq_dist_row(theta: &[f64], x: &TrainingInputs, s: &[f64], c: f64, out: &mut [f64]) {
    scaled_sq_dist(theta, |k| s[k], |k| x.dim_values(k), c, out);
}

/// Values of [`scaled_sq_dist`] summed at once, in registers.
const DIST_BLOCK: usize = 8;

/// `out[j] = c · Σ_k ξ_k (a_k − b_k[j])²`, `b_k = b(k)`: [`DIST_BLOCK`]
/// values at a time summed over every dimension before one store (a pass
/// per dimension loaded and stored every value d times), in fused
/// multiply-adds where the CPU has them (`super::fma`). With
/// [`exp_in_place`](super::fastexp::exp_in_place), the fill of R:
/// 0.18 ms → 0.13 ms at m = 300, d = 12.
fn scaled_sq_dist<'x>(
    theta: &[f64],
    a: impl Fn(usize) -> f64,
    b: impl Fn(usize) -> &'x [f64],
    c: f64,
    out: &mut [f64],
) {
    super::fma::dispatch!(
        scaled_sq_dist_fused(theta, a, b, c, out),
        scaled_sq_dist_with::<false, _, _>(theta, a, b, c, out)
    )
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn scaled_sq_dist_fused<'x>(
    theta: &[f64],
    a: impl Fn(usize) -> f64,
    b: impl Fn(usize) -> &'x [f64],
    c: f64,
    out: &mut [f64],
) {
    scaled_sq_dist_with::<true, _, _>(theta, a, b, c, out);
}

#[inline(always)]
fn scaled_sq_dist_with<'x, const F: bool, A, B>(theta: &[f64], a: A, b: B, c: f64, out: &mut [f64])
where
    A: Fn(usize) -> f64,
    B: Fn(usize) -> &'x [f64],
{
    use super::fma::mul_add;
    let n = out.len();
    let full = n - n % DIST_BLOCK;
    for (j, block) in out[..full].chunks_exact_mut(DIST_BLOCK).enumerate() {
        let j = j * DIST_BLOCK;
        let mut acc = [0.0; DIST_BLOCK];
        for (k, t) in theta.iter().enumerate() {
            let (ak, ct) = (a(k), c * t);
            let bk = &b(k)[j..j + DIST_BLOCK];
            for (s, v) in acc.iter_mut().zip(bk) {
                let diff = v - ak;
                *s = mul_add::<F>(ct * diff, diff, *s);
            }
        }
        block.copy_from_slice(&acc);
    }
    for (j, o) in out.iter_mut().enumerate().skip(full) {
        *o = theta.iter().enumerate().fold(0.0, |s, (k, t)| {
            let diff = b(k)[j] - a(k);
            mul_add::<F>(c * t * diff, diff, s)
        });
    }
}

impl CorrelationModel for Correlation {
    fn corr(&self, theta: &[f64], a: &[f64], b: &[f64]) -> f64 {
        if let Correlation::Custom(c) = self {
            return c.model().corr(theta, a, b);
        }
        let s: f64 = theta
            .iter()
            .zip(a.iter().zip(b))
            .map(|(t, (x, y))| t * (x - y) * (x - y))
            .sum();
        self.radial(s)
    }

    fn fill_column(&self, theta: &[f64], x: &TrainingInputs, i: usize, out: &mut [f64]) {
        match self {
            Correlation::Gaussian => return Gaussian.fill_column(theta, x, i, out),
            Correlation::Custom(c) => return c.model().fill_column(theta, x, i, out),
            _ => {}
        }
        sq_dist_column(theta, x, i, 1.0, out);
        for v in out.iter_mut() {
            *v = self.radial(*v);
        }
    }

    fn gradient_weights(
        &self,
        theta: &[f64],
        x: &TrainingInputs,
        i: usize,
        r: &[f64],
        w: &mut [f64],
    ) {
        match self {
            Correlation::Gaussian => return Gaussian.gradient_weights(theta, x, i, r, w),
            Correlation::Custom(c) => return c.model().gradient_weights(theta, x, i, r, w),
            _ => {}
        }
        let mut s = vec![0.0; w.len()];
        sq_dist_column(theta, x, i, 1.0, &mut s);
        for (v, sj) in w.iter_mut().zip(&s) {
            *v *= -self.slope(*sj);
        }
    }

    fn fill_row(&self, theta: &[f64], x: &TrainingInputs, s: &[f64], out: &mut [f64]) {
        match self {
            Correlation::Gaussian => return Gaussian.fill_row(theta, x, s, out),
            Correlation::Custom(c) => return c.model().fill_row(theta, x, s, out),
            _ => {}
        }
        sq_dist_row(theta, x, s, 1.0, out);
        for v in out.iter_mut() {
            *v = self.radial(*v);
        }
    }
}

/// Gaussian correlation, seed 003 eq 8: `R = exp(−Σ_k ξ_k (s_k − s'_k)²)`.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
pub struct Gaussian;

impl CorrelationModel for Gaussian {
    #[inline]
    fn corr(&self, theta: &[f64], a: &[f64], b: &[f64]) -> f64 {
        let s: f64 = theta
            .iter()
            .zip(a.iter().zip(b))
            .map(|(t, (x, y))| t * (x - y) * (x - y))
            .sum();
        (-s).exp()
    }

    /// `−Σ_k ξ_k (x_ik − x_jk)²` over contiguous rows (vectorised), then
    /// one vectorised `exp`.
    fn fill_column(&self, theta: &[f64], x: &TrainingInputs, i: usize, out: &mut [f64]) {
        sq_dist_column(theta, x, i, -1.0, out);
        super::fastexp::exp_in_place(out);
    }

    /// `∂R/∂ln ξ_k = −ξ_k (s_k − s'_k)² R`: `−q = R`.
    fn gradient_weights(
        &self,
        _theta: &[f64],
        _x: &TrainingInputs,
        _i: usize,
        r: &[f64],
        w: &mut [f64],
    ) {
        for (v, b) in w.iter_mut().zip(r) {
            *v *= b;
        }
    }

    /// `−Σ_k ξ_k (s_k − x_jk)²` over contiguous rows, then one vectorised `exp`.
    fn fill_row(&self, theta: &[f64], x: &TrainingInputs, s: &[f64], out: &mut [f64]) {
        sq_dist_row(theta, x, s, -1.0, out);
        super::fastexp::exp_in_place(out);
    }
}

/// Normalised training inputs stored dimension-major (`d` contiguous vectors
/// of length m), so the fill of R streams a few kilobytes that stay in cache.
#[derive(Debug, Clone, PartialEq)]
pub struct TrainingInputs {
    /// Number of training rows m.
    pub m: usize,
    /// Input dimension d (normalised inputs per row).
    pub d: usize,
    by_dim: Vec<f64>,
}

impl TrainingInputs {
    /// From normalised rows (all of length d).
    pub fn new(rows: &[Vec<f64>]) -> Self {
        let m = rows.len();
        let d = rows.first().map_or(0, Vec::len);
        let mut by_dim = vec![0.0; m * d];
        for (i, r) in rows.iter().enumerate() {
            for (k, v) in r.iter().enumerate() {
                by_dim[k * m + i] = *v;
            }
        }
        TrainingInputs { m, d, by_dim }
    }

    /// The rows at `rows`, in that order.
    pub fn select(&self, rows: &[usize]) -> Self {
        let m = rows.len();
        let mut by_dim = Vec::with_capacity(m * self.d);
        for k in 0..self.d {
            let col = self.dim_values(k);
            by_dim.extend(rows.iter().map(|&i| col[i]));
        }
        TrainingInputs {
            m,
            d: self.d,
            by_dim,
        }
    }

    /// Values of dimension k for all rows.
    pub fn dim_values(&self, k: usize) -> &[f64] {
        &self.by_dim[k * self.m..(k + 1) * self.m]
    }

    /// Row i (allocates; for the scalar fallback).
    pub fn row(&self, i: usize) -> Vec<f64> {
        (0..self.d).map(|k| self.by_dim[k * self.m + i]).collect()
    }

    /// Fill the m × m correlation matrix (lower triangle and diagonal only:
    /// that is all the Cholesky reads) with `1 + diag` on the diagonal, and
    /// correlations below [`TINY_CORRELATION`] as 0.
    pub fn fill_lower(
        &self,
        corr: &dyn CorrelationModel,
        theta: &[f64],
        diag: f64,
        r: faer::MatMut<'_, f64>,
    ) {
        let mut r = r;
        for i in 0..self.m {
            let mut col = r.as_mut().col_mut(i);
            col[i] = 1.0 + diag;
            let slice = col
                .try_as_col_major_mut()
                .expect("contiguous column")
                .as_slice_mut();
            corr.fill_column(theta, self, i, &mut slice[i + 1..]);
            for v in &mut slice[i + 1..] {
                if v.abs() < TINY_CORRELATION {
                    *v = 0.0;
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn vanishing_correlations_are_zero_in_r() {
        // rows 0.1 apart in one input: at ξ = 4e4 neighbours correlate
        // exp(−400) ≈ 2e−174 (below the cut), and at ξ = 2e4 exp(−200)
        // ≈ 1.4e−87 (kept); farther rows underflow to 0 either way
        let rows: Vec<Vec<f64>> = (0..4).map(|i| vec![0.1 * i as f64]).collect();
        let x = TrainingInputs::new(&rows);
        for (theta, kept) in [(4e4, false), (2e4, true)] {
            let mut r = faer::Mat::<f64>::zeros(4, 4);
            x.fill_lower(&Correlation::Gaussian, &[theta], 0.0, r.as_mut());
            let neighbour = r[(1, 0)];
            let want = (-theta * 0.01f64).exp();
            assert_eq!(neighbour > 0.0, kept, "ξ {theta}: {neighbour:e}");
            if kept {
                assert!((neighbour - want).abs() <= 1e-15 * want);
            }
            assert!(r[(3, 0)] == 0.0 && r[(0, 0)] == 1.0);
        }
    }

    /// n rows of three inputs: two smooth ones and `third(i)`.
    fn sample_rows(n: usize, third: impl Fn(usize) -> f64) -> Vec<Vec<f64>> {
        (0..n)
            .map(|i| vec![(i as f64 * 0.37).sin(), (i as f64 * 1.3).cos(), third(i)])
            .collect()
    }

    #[test]
    fn vectorised_fill_matches_scalar_definition() {
        let rows = sample_rows(37, |i| if i % 2 == 0 { 1.0 } else { -1.0 });
        let x = TrainingInputs::new(&rows);
        let theta = [0.7, 0.05, 2.0];
        let mut r = faer::Mat::<f64>::zeros(37, 37);
        x.fill_lower(&Gaussian, &theta, 1e-3, r.as_mut());
        for i in 0..37 {
            assert_eq!(r[(i, i)], 1.001);
            for j in i + 1..37 {
                let want = Gaussian.corr(&theta, &rows[i], &rows[j]);
                assert!((r[(j, i)] - want).abs() <= 4e-16 * want, "({j},{i})");
            }
        }
    }

    /// The unfused distances (a CPU without FMA, where the dispatcher runs
    /// them) agree with the dispatched ones to rounding, remainders
    /// included.
    #[test]
    fn unfused_distances_match_the_dispatched_ones() {
        let rows = sample_rows(29, |i| 0.1 * i as f64);
        let x = TrainingInputs::new(&rows);
        let theta = [0.7, 0.05, 2.0];
        for i in 0..29 {
            let n = 28 - i;
            let (mut got, mut plain) = (vec![0.0; n], vec![0.0; n]);
            sq_dist_column(&theta, &x, i, -1.0, &mut got);
            scaled_sq_dist_with::<false, _, _>(
                &theta,
                |k| x.dim_values(k)[i],
                |k| &x.dim_values(k)[i + 1..],
                -1.0,
                &mut plain,
            );
            for (a, b) in got.iter().zip(&plain) {
                assert!((a - b).abs() <= 1e-15 * a.abs().max(1.0), "row {i}");
            }
        }
    }
}
