//! The dense kernels of a likelihood evaluation: the Cholesky factor C of
//! R ([`cholesky_lower`], m³/6 multiply-adds), and for the gradient
//! ([`super::KrigingProblem::psi_grad`]) `R⁻¹` from it — `W = C⁻¹`, then
//! `R⁻¹ = WᵀW` (lower triangles; LAPACK's `potri` = `trtri` + `lauum`),
//! m³/6 + m³/6 — and the contraction of the gradient's weights with the
//! inputs' squared differences ([`pair_sq_diff_sums`]).
//!
//! faer's triangular inverse and triangular product recurse down to 2 × 2
//! blocks, and at the sizes of a hyperparameter search (m of a few hundred
//! to a thousand) their small blocks cost more than their multiply-adds:
//! they ran at about half the rate of a rectangular product. Sequentially,
//! both are done here as a few long rectangular products of
//! [`BLOCK`]-wide panels (the zero upper triangle of W skipped panel by
//! panel, so the multiply-adds are the same), measured on one thread
//! (AMD EPYC, AVX-512 kernels):
//!
//! | m | `C⁻¹` faer → here | `WᵀW` faer → here |
//! |---|---|---|
//! | 150 | 0.056 → 0.038 ms | 0.061 → 0.027 ms |
//! | 300 | 0.286 → 0.213 ms | 0.31 → 0.18 ms |
//! | 1 000 | 7.7 → 6.5 ms | 7.9 → 6.5 ms |
//! | 2 000 | | 56 → 55 ms |
//!
//! The Cholesky factorisation itself is done the same way
//! ([`cholesky_lower`]).
//!
//! With several threads (`Par::Rayon`, from [`super::problem::PAR_MIN_ROWS`] rows)
//! faer's parallel recursions are used as they are.

use faer::dyn_stack::{MemBuffer, MemStack};
use faer::linalg::cholesky::llt::factor::{
    LltRegularization, cholesky_in_place, cholesky_in_place_scratch,
};
use faer::linalg::matmul::matmul;
use faer::linalg::matmul::triangular::{BlockStructure, matmul as tri_matmul};
use faer::linalg::triangular_inverse::invert_lower_triangular;
use faer::reborrow::*;
use faer::{Accum, Mat, MatMut, MatRef, Par};

/// Panel width: the width of the matrix-multiply kernels (8 doubles).
const BLOCK: usize = 8;
/// Below this order the inverse is faer's (its recursion is short there).
const LEAF: usize = 16;

/// Order of the square scratch [`inverse_from_cholesky`] needs for m rows
/// evaluated sequentially (below [`super::problem::PAR_MIN_ROWS`]; none above).
pub(super) fn scratch_order(m: usize) -> usize {
    if m < super::problem::PAR_MIN_ROWS {
        m.div_ceil(2) + BLOCK
    } else {
        0
    }
}

/// `r ← R⁻¹` (lower triangle; the strict upper triangle is left undefined)
/// from the lower Cholesky factor C held in `r`'s lower triangle, with `w`
/// (m × m) receiving `C⁻¹` and `scratch` grown to [`scratch_order`] as
/// needed (sequential only).
pub(super) fn inverse_from_cholesky(
    r: &mut Mat<f64>,
    w: &mut Mat<f64>,
    scratch: &mut Mat<f64>,
    par: Par,
) {
    let m = r.nrows();
    if w.nrows() != m {
        *w = Mat::zeros(m, m);
    }
    if par != Par::Seq {
        invert_lower_triangular(w.as_mut(), r.as_ref(), par);
        tri_matmul(
            r.as_mut(),
            BlockStructure::TriangularLower,
            Accum::Replace,
            w.transpose(),
            BlockStructure::TriangularUpper,
            w.as_ref(),
            BlockStructure::TriangularLower,
            1.0,
            par,
        );
        return;
    }
    let half = scratch_order(m);
    if scratch.nrows() < half || scratch.ncols() < half {
        *scratch = Mat::zeros(half, half);
    }
    // the panels below read W's strict upper triangle inside its diagonal
    // blocks: it must be zero (the inverse writes the lower triangle only)
    for start in (0..m).step_by(BLOCK) {
        let end = (start + BLOCK).min(m);
        for j in start + 1..end {
            for i in start..j {
                w[(i, j)] = 0.0;
            }
        }
    }
    invert_lower(w.as_mut(), r.as_ref(), scratch.as_mut());
    lower_gram(r.as_mut(), w.as_ref());
}

/// `w ← C⁻¹` for lower-triangular C (lower triangle of `w`; its strict upper
/// triangle inside the diagonal [`BLOCK`]s zero on entry), by halves:
/// `W₁₁ = C₁₁⁻¹`, `W₂₂ = C₂₂⁻¹`, `W₂₁ = −W₂₂ (C₂₁ W₁₁)`, the two products
/// panel by panel over the triangular factor's non-zero part. `scratch`
/// holds `C₂₁ W₁₁` ((m − h) × h).
fn invert_lower(w: MatMut<'_, f64>, c: MatRef<'_, f64>, mut scratch: MatMut<'_, f64>) {
    let n = c.nrows();
    if n <= LEAF {
        invert_lower_triangular(w, c, Par::Seq);
        return;
    }
    // a split on a panel boundary, so that the diagonal blocks stay aligned
    let h = (n / 2).next_multiple_of(BLOCK).min(n - 1);
    let (mut w11, _, mut w21, mut w22) = w.split_at_mut(h, h);
    let (c11, _, c21, c22) = c.split_at(h, h);
    invert_lower(w11.rb_mut(), c11, scratch.rb_mut());
    invert_lower(w22.rb_mut(), c22, scratch.rb_mut());
    // T = C₂₁ W₁₁: column panel J of T needs rows J_start.. of W₁₁ only
    let mut t = scratch.submatrix_mut(0, 0, n - h, h);
    for start in (0..h).step_by(BLOCK) {
        let end = (start + BLOCK).min(h);
        matmul(
            t.rb_mut().subcols_mut(start, end - start),
            Accum::Replace,
            c21.subcols(start, h - start),
            w11.rb().submatrix(start, start, h - start, end - start),
            1.0,
            Par::Seq,
        );
    }
    // W₂₁ = −W₂₂ T: row panel I of W₂₁ needs columns ..I_end of W₂₂ only
    for start in (0..n - h).step_by(BLOCK) {
        let end = (start + BLOCK).min(n - h);
        matmul(
            w21.rb_mut().subrows_mut(start, end - start),
            Accum::Replace,
            w22.rb().submatrix(start, 0, end - start, end),
            t.rb().subrows(0, end),
            -1.0,
            Par::Seq,
        );
    }
}

/// `out ← WᵀW` (lower triangle; the upper triangle of the diagonal
/// [`BLOCK`]s is written too) for lower-triangular `w` (zero above its
/// diagonal inside the diagonal blocks): row panel I is
/// `W[I_start.., I]ᵀ · W[I_start.., ..I_end]` (rows of W above `I_start`
/// add nothing).
fn lower_gram(mut out: MatMut<'_, f64>, w: MatRef<'_, f64>) {
    let m = w.nrows();
    for start in (0..m).step_by(BLOCK) {
        let end = (start + BLOCK).min(m);
        matmul(
            out.rb_mut().submatrix_mut(start, 0, end - start, end),
            Accum::Replace,
            w.submatrix(start, start, m - start, end - start)
                .transpose(),
            w.submatrix(start, 0, m - start, end),
            1.0,
            Par::Seq,
        );
    }
}

/// The lower Cholesky factor of the SPD matrix in `a`'s lower triangle,
/// in place (`A = CCᵀ`; the strict upper triangle is left undefined);
/// `false` when a pivot is not positive (or not a number): A is not
/// positive definite. Sequentially it runs left-looking by [`BLOCK`]-column
/// panels: each panel first takes `A[J_start.., J] −= C[J_start.., ..J_start]
/// C[J, ..J_start]ᵀ` as one rectangular product, then is factorised column
/// by column (m = 300: 0.27 → 0.22 ms, m = 1 000: 8.0 → 7.0 ms against
/// faer's recursive factorisation on one thread). In parallel (from
/// [`super::problem::PAR_MIN_ROWS`] rows, where an allocation is nothing
/// next to the m³/6 multiply-adds), faer's, with its scratch allocated here.
pub(super) fn cholesky_lower(a: MatMut<'_, f64>, par: Par) -> bool {
    if par != Par::Seq {
        let mut mem = MemBuffer::new(cholesky_in_place_scratch::<f64>(
            a.nrows(),
            par,
            Default::default(),
        ));
        return cholesky_in_place(
            a,
            LltRegularization::default(),
            par,
            MemStack::new(&mut mem),
            Default::default(),
        )
        .is_ok();
    }
    super::fma::dispatch!(cholesky_panels_fused(a), cholesky_panels::<false>(a))
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn cholesky_panels_fused(a: MatMut<'_, f64>) -> bool {
    cholesky_panels::<true>(a)
}

/// [`cholesky_lower`] on one thread, fused multiply-adds when `F`.
#[inline(always)]
fn cholesky_panels<const F: bool>(mut a: MatMut<'_, f64>) -> bool {
    use super::fma::mul_add;
    let m = a.nrows();
    for start in (0..m).step_by(BLOCK) {
        let end = (start + BLOCK).min(m);
        if start > 0 {
            let (done, mut panel) = a.rb_mut().split_at_col_mut(start);
            matmul(
                panel
                    .rb_mut()
                    .submatrix_mut(start, 0, m - start, end - start),
                Accum::Add,
                done.rb().subrows(start, m - start),
                done.rb()
                    .submatrix(start, 0, end - start, start)
                    .transpose(),
                -1.0,
                Par::Seq,
            );
        }
        for j in start..end {
            let (mut left, mut right) = a.rb_mut().split_at_col_mut(j + 1);
            let cj = left
                .rb_mut()
                .col_mut(j)
                .try_as_col_major_mut()
                .expect("contiguous column")
                .as_slice_mut();
            let pivot = cj[j];
            // NaN is not positive either
            if pivot.partial_cmp(&0.0) != Some(std::cmp::Ordering::Greater) {
                return false;
            }
            let d = pivot.sqrt();
            cj[j] = d;
            let inv = 1.0 / d;
            for v in &mut cj[j + 1..] {
                *v *= inv;
            }
            let cj = &cj[..];
            for c in j + 1..end {
                let f = -cj[c];
                let cc = right
                    .rb_mut()
                    .col_mut(c - j - 1)
                    .try_as_col_major_mut()
                    .expect("contiguous column")
                    .as_slice_mut();
                for (o, v) in cc[c..].iter_mut().zip(&cj[c..]) {
                    *o = mul_add::<F>(*v, f, *o);
                }
            }
        }
    }
    true
}

/// `Σ_j a_j b_j` in [`BLOCK`] interleaved partial sums (one running sum is
/// a chain of dependent adds), fused multiply-adds where the CPU has them.
pub(super) fn dot(a: &[f64], b: &[f64]) -> f64 {
    super::fma::dispatch!(dot_fused(a, b), dot_with::<false>(a, b))
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn dot_fused(a: &[f64], b: &[f64]) -> f64 {
    dot_with::<true>(a, b)
}

#[inline(always)]
fn dot_with<const F: bool>(a: &[f64], b: &[f64]) -> f64 {
    use super::fma::mul_add;
    debug_assert_eq!(a.len(), b.len(), "dot of unequal lengths");
    let n = a.len();
    let full = n - n % BLOCK;
    let mut acc = [0.0; BLOCK];
    for (x, y) in a[..full]
        .chunks_exact(BLOCK)
        .zip(b[..full].chunks_exact(BLOCK))
    {
        for l in 0..BLOCK {
            acc[l] = mul_add::<F>(x[l], y[l], acc[l]);
        }
    }
    let tail = a[full..n]
        .iter()
        .zip(&b[full..n])
        .fold(0.0, |s, (x, y)| mul_add::<F>(*x, *y, s));
    acc.iter().sum::<f64>() + tail
}

/// `y ← y + α x`, fused multiply-adds where the CPU has them.
pub(super) fn axpy(y: &mut [f64], alpha: f64, x: &[f64]) {
    super::fma::dispatch!(axpy_fused(y, alpha, x), axpy_with::<false>(y, alpha, x))
}

#[cfg(target_arch = "x86_64")]
#[target_feature(enable = "avx2,fma")]
fn axpy_fused(y: &mut [f64], alpha: f64, x: &[f64]) {
    axpy_with::<true>(y, alpha, x);
}

#[inline(always)]
fn axpy_with<const F: bool>(y: &mut [f64], alpha: f64, x: &[f64]) {
    debug_assert_eq!(y.len(), x.len(), "axpy of unequal lengths");
    for (o, v) in y.iter_mut().zip(x) {
        *o = super::fma::mul_add::<F>(*v, alpha, *o);
    }
}

/// `out[k] = Σ_{i>j} P_ij (x_ik − x_jk)²` for every input k, from `P`'s
/// strict lower triangle (its diagonal and upper triangle are overwritten
/// with zeros inside the diagonal [`BLOCK`]s). With the inputs centred
/// (`x̃`), `Σ_{i>j} P_ij (x̃_ik − x̃_jk)² = Σ_j (Y_jk − 2 x̃_jk Y_j,d+k +
/// x̃_jk² Y_j,2d)`, `Y = Pᵀ [X̃², X̃, 1]`: one product of m²/2 · (2d + 1)
/// multiply-adds in row panels of `Pᵀ`, instead of d passes over every
/// column (the same multiply-adds, but two loads each).
pub(super) fn pair_sq_diff_sums(
    mut p: MatMut<'_, f64>,
    x: &super::corr::TrainingInputs,
    out: &mut [f64],
) {
    let (m, d) = (x.m, x.d);
    let mean: Vec<f64> = (0..d)
        .map(|k| x.dim_values(k).iter().sum::<f64>() / m.max(1) as f64)
        .collect();
    let z = Mat::from_fn(m, 2 * d + 1, |i, c| {
        if c == 2 * d {
            return 1.0;
        }
        let k = c % d;
        let v = x.dim_values(k)[i] - mean[k];
        if c < d { v * v } else { v }
    });
    for start in (0..m).step_by(BLOCK) {
        let end = (start + BLOCK).min(m);
        for j in start..end {
            for i in start..=j {
                p[(i, j)] = 0.0;
            }
        }
    }
    let mut y = Mat::<f64>::zeros(m, 2 * d + 1);
    for start in (0..m).step_by(BLOCK) {
        let end = (start + BLOCK).min(m);
        matmul(
            y.as_mut().subrows_mut(start, end - start),
            Accum::Replace,
            p.rb()
                .submatrix(start, start, m - start, end - start)
                .transpose(),
            z.as_ref().subrows(start, m - start),
            1.0,
            Par::Seq,
        );
    }
    for (k, o) in out.iter_mut().enumerate().take(d) {
        *o = (0..m)
            .map(|j| {
                let v = z[(j, d + k)];
                y[(j, k)] - 2.0 * v * y[(j, d + k)] + v * v * y[(j, 2 * d)]
            })
            .sum();
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A well-conditioned SPD matrix of order m (a Gaussian correlation of
    /// scattered points plus a nugget) and its lower Cholesky factor.
    fn factor(m: usize) -> Mat<f64> {
        let x: Vec<f64> = (0..m).map(|i| (i as f64 * 0.7548776662).fract()).collect();
        let y: Vec<f64> = (0..m).map(|i| (i as f64 * 0.5698402910).fract()).collect();
        let a = Mat::from_fn(m, m, |i, j| {
            let d = (x[i] - x[j]).powi(2) + (y[i] - y[j]).powi(2);
            (-8.0 * d).exp() + if i == j { 0.05 } else { 0.0 }
        });
        let c = a.llt(faer::Side::Lower).expect("SPD");
        c.L().to_owned()
    }

    /// The panel Cholesky gives faer's factor to rounding at orders around
    /// the panel size, and refuses a matrix that is not positive definite.
    #[test]
    fn cholesky_matches_faer_and_refuses_an_indefinite_matrix() {
        for m in [1, 7, 8, 9, 17, 64, 130] {
            let c = factor(m);
            let a = &c * c.transpose();
            let mut got = Mat::from_fn(m, m, |i, j| if i >= j { a[(i, j)] } else { 5.0 });
            assert!(cholesky_lower(got.as_mut(), Par::Seq), "m = {m}");
            for j in 0..m {
                for i in j..m {
                    assert!(
                        (got[(i, j)] - c[(i, j)]).abs() < 1e-12,
                        "m = {m} ({i}, {j})"
                    );
                }
            }
            let mut bad = a.clone();
            bad[(m / 2, m / 2)] = -1.0;
            assert!(!cholesky_lower(bad.as_mut(), Par::Seq), "m = {m}");
        }
        let mut nan = Mat::<f64>::identity(9, 9);
        nan[(5, 2)] = f64::NAN;
        assert!(!cholesky_lower(nan.as_mut(), Par::Seq));
    }

    /// The unfused kernels (a CPU without FMA, where the dispatchers run
    /// them) agree with the dispatched ones to rounding.
    #[test]
    fn unfused_kernels_match_the_dispatched_ones() {
        for m in [9, 40, 130] {
            let c = factor(m);
            let a = &c * c.transpose();
            let (mut fused, mut plain) = (a.clone(), a.clone());
            assert!(cholesky_lower(fused.as_mut(), Par::Seq));
            assert!(cholesky_panels::<false>(plain.as_mut()));
            for j in 0..m {
                for i in j..m {
                    assert!((fused[(i, j)] - plain[(i, j)]).abs() < 1e-13, "m = {m}");
                }
            }
        }
        let x: Vec<f64> = (0..37).map(|i| (i as f64 * 0.61).sin()).collect();
        let y: Vec<f64> = (0..37).map(|i| (i as f64 * 1.7).cos()).collect();
        assert!((dot(&x, &y) - dot_with::<false>(&x, &y)).abs() < 1e-14);
        let (mut u, mut v) = (y.clone(), y.clone());
        axpy(&mut u, -0.3, &x);
        axpy_with::<false>(&mut v, -0.3, &x);
        for (p, q) in u.iter().zip(&v) {
            assert!((p - q).abs() < 1e-15);
        }
    }

    /// The blocked inverse and product give R⁻¹ to rounding, at orders
    /// around the panel, leaf and split sizes, with garbage in R's upper
    /// triangle and in a reused W.
    #[test]
    fn gives_the_inverse_at_every_order() {
        for m in [1, 2, 7, 8, 9, 16, 17, 23, 40, 97, 130] {
            let c = factor(m);
            let a = &c * c.transpose();
            let mut r = Mat::from_fn(m, m, |i, j| if i >= j { c[(i, j)] } else { 7.0 });
            let mut w = Mat::from_fn(m, m, |_, _| 3.0);
            let mut scratch = Mat::zeros(0, 0);
            inverse_from_cholesky(&mut r, &mut w, &mut scratch, Par::Seq);
            let full = Mat::from_fn(m, m, |i, j| if i >= j { r[(i, j)] } else { r[(j, i)] });
            let eye = &a * &full;
            for i in 0..m {
                for j in 0..m {
                    let want = if i == j { 1.0 } else { 0.0 };
                    assert!((eye[(i, j)] - want).abs() < 1e-10, "m = {m}, ({i}, {j})");
                }
            }
            // the same as faer's recursions, to rounding
            let mut r2 = c.clone();
            let mut w2 = Mat::zeros(m, m);
            inverse_from_cholesky(&mut r2, &mut w2, &mut scratch, Par::rayon(2));
            for j in 0..m {
                for i in j..m {
                    let (p, q) = (r[(i, j)], r2[(i, j)]);
                    assert!(
                        (p - q).abs() <= 1e-11 * p.abs().max(q.abs()).max(1.0),
                        "m = {m}"
                    );
                }
            }
        }
    }
}
