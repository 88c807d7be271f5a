//! Fused multiply-adds for the likelihood's own loops, chosen at **run
//! time**: the exponential and distances of the correlation fill
//! (`fastexp`, `corr`), the Cholesky panels and the gradient's sums
//! (`dense`). Rust never fuses `a * b + c` itself, and in those loops the
//! dependent multiply-then-add chains were the critical path.
//!
//! The choice follows the CPU ([`available`]), not the build's target CPU:
//! the Python wheel is built for baseline x86-64 and must compute the same
//! bits as the command line's `x86-64-v3` build on the same machine
//! (`python/tests/test_same_numbers.py` compares their model files byte for
//! byte). Each kernel is generic over `F` (fused or not, [`mul_add`]) and
//! has a `#[target_feature(enable = "avx2,fma")]` instance, which
//! [`dispatch!`](crate::kriging::fma::dispatch) calls when the CPU has both.

/// Whether this CPU runs the fused kernels: x86-64 with AVX2 and FMA
/// (`is_x86_feature_detected!` caches its answer; in an `x86-64-v3` build
/// it is known at compile time).
#[inline]
pub(crate) fn available() -> bool {
    #[cfg(target_arch = "x86_64")]
    {
        std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma")
    }
    #[cfg(not(target_arch = "x86_64"))]
    {
        false
    }
}

/// `a·b + c`: one fused multiply-add when `F` (use it only inside a kernel
/// compiled for FMA, where it is one instruction; elsewhere `f64::mul_add`
/// is a slow library call), else a multiply and an add. Fused, it rounds
/// once, so the two differ in the last bits.
#[inline(always)]
pub(crate) fn mul_add<const F: bool>(a: f64, b: f64, c: f64) -> f64 {
    if F { a.mul_add(b, c) } else { a * b + c }
}

/// `dispatch!(fused_call, plain_call)`: returns `fused_call` (a call of a
/// `#[target_feature(enable = "avx2,fma")]` function) from the enclosing
/// function when [`available`], else evaluates to `plain_call`.
macro_rules! dispatch {
    ($fused:expr, $plain:expr) => {{
        #[cfg(target_arch = "x86_64")]
        if $crate::kriging::fma::available() {
            // SAFETY: the fused call needs AVX2 and FMA, and the CPU has
            // both (checked just above)
            return unsafe { $fused };
        }
        $plain
    }};
}
pub(crate) use dispatch;
