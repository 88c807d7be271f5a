//! Summaries of TCP error sets: the numbers of seed 003 Table 2 and seed 004
//! Table 3 (range, mean, standard deviation of the 3D error; per-axis mean and
//! RMS).

use serde::{Deserialize, Serialize};

/// Statistics of a set of 3D errors (mm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorSummary {
    pub n: usize,
    /// Mean of |δ|.
    pub mean_3d_mm: f64,
    /// Population standard deviation of |δ|.
    pub std_3d_mm: f64,
    pub min_3d_mm: f64,
    pub max_3d_mm: f64,
    /// Per-axis mean (signed).
    pub mean_mm: [f64; 3],
    /// Per-axis root mean square.
    pub rms_mm: [f64; 3],
}

/// Summarise errors; an empty set gives zeros with `n = 0`.
pub fn summarize(errors: &[[f64; 3]]) -> ErrorSummary {
    let n = errors.len();
    if n == 0 {
        return ErrorSummary {
            n,
            mean_3d_mm: 0.0,
            std_3d_mm: 0.0,
            min_3d_mm: 0.0,
            max_3d_mm: 0.0,
            mean_mm: [0.0; 3],
            rms_mm: [0.0; 3],
        };
    }
    let nf = n as f64;
    let norms: Vec<f64> = errors
        .iter()
        .map(|e| (e[0] * e[0] + e[1] * e[1] + e[2] * e[2]).sqrt())
        .collect();
    let mean = norms.iter().sum::<f64>() / nf;
    let var = norms.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / nf;
    let mut mean_mm = [0.0; 3];
    let mut rms_mm = [0.0; 3];
    for a in 0..3 {
        mean_mm[a] = errors.iter().map(|e| e[a]).sum::<f64>() / nf;
        rms_mm[a] = (errors.iter().map(|e| e[a] * e[a]).sum::<f64>() / nf).sqrt();
    }
    ErrorSummary {
        n,
        mean_3d_mm: mean,
        std_3d_mm: var.sqrt(),
        min_3d_mm: norms.iter().copied().fold(f64::INFINITY, f64::min),
        max_3d_mm: norms.iter().copied().fold(0.0, f64::max),
        mean_mm,
        rms_mm,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn summary_of_known_set() {
        let s = summarize(&[[3.0, 4.0, 0.0], [0.0, 0.0, 1.0]]);
        assert_eq!(s.n, 2);
        assert!((s.mean_3d_mm - 3.0).abs() < 1e-12);
        assert!((s.std_3d_mm - 2.0).abs() < 1e-12);
        assert_eq!(s.max_3d_mm, 5.0);
        assert_eq!(s.min_3d_mm, 1.0);
        assert!((s.rms_mm[0] - (4.5f64).sqrt()).abs() < 1e-12);
        assert_eq!(s.mean_mm, [1.5, 2.0, 0.5]);
    }
}
