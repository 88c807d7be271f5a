//! TCP error vectors: `[x, y, z]` in mm, the unit every error model
//! predicts and every campaign measures. A plain array (so that CSV, JSON
//! and numpy see three numbers) with the few operations the crate needs on
//! it, written once.

/// A TCP error (or position) vector `[x, y, z]`, mm.
pub type ErrorVec = [f64; 3];

/// The operations on an [`ErrorVec`].
pub trait Vec3 {
    /// The Euclidean norm `√(x² + y² + z²)` (the "3D error").
    fn norm(&self) -> f64;
    /// The norm of the `x, y` part (the planar error of a SCARA).
    fn norm_xy(&self) -> f64;
    /// `self − other`, component-wise.
    fn minus(&self, other: &ErrorVec) -> ErrorVec;
}

impl Vec3 for ErrorVec {
    fn norm(&self) -> f64 {
        (self[0] * self[0] + self[1] * self[1] + self[2] * self[2]).sqrt()
    }

    fn norm_xy(&self) -> f64 {
        self[0].hypot(self[1])
    }

    fn minus(&self, other: &ErrorVec) -> ErrorVec {
        [self[0] - other[0], self[1] - other[1], self[2] - other[2]]
    }
}

/// `a[i] − b[i]` for every pair (e.g. measured − predicted: the residuals).
/// Extra entries of the longer slice are ignored.
pub fn residuals(a: &[ErrorVec], b: &[ErrorVec]) -> Vec<ErrorVec> {
    a.iter().zip(b).map(|(x, y)| x.minus(y)).collect()
}

/// The norm of every vector.
pub fn norms(v: &[ErrorVec]) -> Vec<f64> {
    v.iter().map(Vec3::norm).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn norms_and_residuals() {
        let a = [[3.0, 4.0, 12.0], [1.0, 0.0, 0.0]];
        let b = [[0.0, 0.0, 0.0], [1.0, 2.0, 2.0]];
        assert_eq!(norms(&a), vec![13.0, 1.0]);
        assert_eq!(residuals(&a, &b), vec![a[0], [0.0, -2.0, -2.0]]);
        assert_eq!(a[0].norm_xy(), 5.0);
    }
}
