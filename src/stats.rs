//! Summaries of TCP error sets: the numbers of seed 003 Table 2 and seed 004
//! Table 3 (range, mean, standard deviation of the 3D error; per-axis mean and
//! RMS).

use crate::vec3::norms;
use serde::{Deserialize, Serialize};

/// Statistics of a set of 3D errors (mm).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct ErrorSummary {
    /// Number of errors summarised.
    pub n: usize,
    /// Mean of |δ|.
    pub mean_3d_mm: f64,
    /// Population standard deviation of |δ|.
    pub std_3d_mm: f64,
    /// Smallest |δ|, mm.
    pub min_3d_mm: f64,
    /// Largest |δ|, mm.
    pub max_3d_mm: f64,
    /// Per-axis mean (signed).
    pub mean_mm: [f64; 3],
    /// Per-axis root mean square.
    pub rms_mm: [f64; 3],
    /// Box-plot statistics of |δ|.
    pub box_3d_mm: BoxStats,
}

/// Quartiles (linear interpolation between order statistics) and Tukey
/// whiskers: the most extreme values within 1.5·IQR of the box; values beyond
/// are outliers.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct BoxStats {
    /// First quartile (25 %).
    pub q1: f64,
    /// Median (50 %).
    pub median: f64,
    /// Third quartile (75 %).
    pub q3: f64,
    /// Lower whisker: the smallest value ≥ q1 − 1.5·IQR.
    pub whisker_lo: f64,
    /// Upper whisker: the largest value ≤ q3 + 1.5·IQR.
    pub whisker_hi: f64,
    /// Number of values outside the whiskers.
    pub outliers: usize,
}

/// Box-plot statistics of `v` (zeros for an empty set).
pub fn box_stats(v: &[f64]) -> BoxStats {
    if v.is_empty() {
        return BoxStats {
            q1: 0.0,
            median: 0.0,
            q3: 0.0,
            whisker_lo: 0.0,
            whisker_hi: 0.0,
            outliers: 0,
        };
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let q = |p: f64| {
        let h = p * (s.len() - 1) as f64;
        let (i, f) = (h.floor() as usize, h - h.floor());
        if i + 1 < s.len() {
            s[i] + f * (s[i + 1] - s[i])
        } else {
            s[i]
        }
    };
    let (q1, median, q3) = (q(0.25), q(0.5), q(0.75));
    let (lo, hi) = (q1 - 1.5 * (q3 - q1), q3 + 1.5 * (q3 - q1));
    let inside: Vec<f64> = s.iter().copied().filter(|x| *x >= lo && *x <= hi).collect();
    BoxStats {
        q1,
        median,
        q3,
        whisker_lo: inside.first().copied().unwrap_or(q1),
        whisker_hi: inside.last().copied().unwrap_or(q3),
        outliers: s.len() - inside.len(),
    }
}

/// Mean, population standard deviation, minimum and maximum of one quantity.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Spread {
    /// Arithmetic mean.
    pub mean: f64,
    /// Population standard deviation (divides by n).
    pub std: f64,
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
}

/// `Spread` of `v` (zeros for an empty set).
pub fn spread(v: &[f64]) -> Spread {
    if v.is_empty() {
        return Spread {
            mean: 0.0,
            std: 0.0,
            min: 0.0,
            max: 0.0,
        };
    }
    let n = v.len() as f64;
    let mean = v.iter().sum::<f64>() / n;
    Spread {
        mean,
        std: (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / n).sqrt(),
        min: v.iter().copied().fold(f64::INFINITY, f64::min),
        max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
    }
}

/// The layout of seed 004 Table 3: per-axis signed error and the absolute
/// (3D) error, each as mean / std / min / max, with the JSON names the CLI
/// promises (`mean_abs_mm`, `max_abs_mm`, `std_abs_mm`, `mean_mm`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PositionErrorTable {
    /// Number of errors.
    pub n: usize,
    /// Mean of the 3D error |δ|, mm.
    pub mean_abs_mm: f64,
    /// Population standard deviation of |δ|, mm.
    pub std_abs_mm: f64,
    /// Smallest |δ|, mm.
    pub min_abs_mm: f64,
    /// Largest |δ|, mm.
    pub max_abs_mm: f64,
    /// Per-axis mean of the signed error (x, y, z), mm.
    pub mean_mm: [f64; 3],
    /// Per-axis population standard deviation (x, y, z), mm.
    pub std_mm: [f64; 3],
    /// Per-axis smallest signed error (x, y, z), mm.
    pub min_mm: [f64; 3],
    /// Per-axis largest signed error (x, y, z), mm.
    pub max_mm: [f64; 3],
}

/// Seed 004 Table 3 statistics of a set of errors.
pub fn position_error_table(errors: &[[f64; 3]]) -> PositionErrorTable {
    let abs = norms(errors);
    let axis: [Spread; 3] =
        std::array::from_fn(|a| spread(&errors.iter().map(|e| e[a]).collect::<Vec<_>>()));
    let s = spread(&abs);
    PositionErrorTable {
        n: errors.len(),
        mean_abs_mm: s.mean,
        std_abs_mm: s.std,
        min_abs_mm: s.min,
        max_abs_mm: s.max,
        mean_mm: axis.map(|x| x.mean),
        std_mm: axis.map(|x| x.std),
        min_mm: axis.map(|x| x.min),
        max_mm: axis.map(|x| x.max),
    }
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
            box_3d_mm: box_stats(&[]),
        };
    }
    let nf = n as f64;
    let norms = norms(errors);
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
        box_3d_mm: box_stats(&norms),
    }
}

/// An independent random stream per (seed, purpose), so that e.g. the true
/// robot of seed 1 is the same whichever campaign kind is simulated.
pub fn rng_for(seed: u64, stream: &str) -> rand::rngs::StdRng {
    use rand::SeedableRng;
    // FNV-1a of the stream name, mixed with the seed
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in stream.bytes() {
        h ^= u64::from(b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    rand::rngs::StdRng::seed_from_u64(h ^ seed.wrapping_mul(0x9e37_79b9_7f4a_7c15))
}

/// The rows of every fold of a partition (fold index per row, as from
/// [`kfold_partition`]), in fold order; empty folds are left out. One pass.
pub fn fold_blocks(fold: &[usize]) -> Vec<Vec<usize>> {
    let folds = fold.iter().max().map_or(0, |f| f + 1);
    let mut blocks = vec![Vec::new(); folds];
    for (row, &f) in fold.iter().enumerate() {
        blocks[f].push(row);
    }
    blocks.retain(|b| !b.is_empty());
    blocks
}

/// The number of folds k of a partition of `m` rows (`fold[i]` in 0..k):
/// an error unless there is one label per row and every fold of at least
/// two is non-empty.
pub fn fold_count(fold: &[usize], m: usize) -> crate::Result<usize> {
    if fold.len() != m {
        return Err(crate::Error::InvalidParameter(format!(
            "{} fold labels for {m} rows",
            fold.len()
        )));
    }
    let k = fold.iter().max().map_or(0, |f| f + 1);
    let mut seen = vec![false; k];
    fold.iter().for_each(|&f| seen[f] = true);
    if k < 2 || seen.contains(&false) {
        return Err(crate::Error::InvalidParameter(format!(
            "cross-validation needs at least 2 non-empty folds numbered 0..k (got {k})"
        )));
    }
    Ok(k)
}

/// Fold index of every row for leave-one-group-out CV (scikit-learn's
/// `LeaveOneGroupOut`; `GroupKFold` with one fold per group): rows with the
/// same label share a fold, folds numbered by first appearance. Errors
/// with fewer than two groups.
pub fn group_partition(labels: &[String]) -> crate::Result<Vec<usize>> {
    let mut seen: Vec<&str> = Vec::new();
    let fold: Vec<usize> = labels
        .iter()
        .map(|l| match seen.iter().position(|s| *s == l) {
            Some(i) => i,
            None => {
                seen.push(l);
                seen.len() - 1
            }
        })
        .collect();
    if seen.len() < 2 {
        return Err(crate::Error::InvalidParameter(format!(
            "leave-one-group-out needs at least 2 groups, the column has {}",
            seen.len()
        )));
    }
    Ok(fold)
}

/// Fold index (0..k) of every row: a seeded shuffle dealt round-robin, so fold
/// sizes differ by at most one.
pub fn kfold_partition(m: usize, k: usize, seed: u64) -> crate::Result<Vec<usize>> {
    if k < 2 || k > m {
        return Err(crate::Error::InvalidParameter(format!(
            "K-fold needs 2 ≤ K ≤ rows, got K = {k} with {m} rows"
        )));
    }
    let mut order: Vec<usize> = (0..m).collect();
    let mut rng = rng_for(seed, "kfold");
    for i in (1..m).rev() {
        order.swap(i, rand::RngExt::random_range(&mut rng, 0..=i));
    }
    let mut fold = vec![0; m];
    for (pos, &row) in order.iter().enumerate() {
        fold[row] = pos % k;
    }
    Ok(fold)
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

    #[test]
    fn position_error_table_of_known_set() {
        let t = position_error_table(&[[3.0, 4.0, 0.0], [0.0, 0.0, -1.0]]);
        assert_eq!((t.n, t.mean_abs_mm, t.std_abs_mm), (2, 3.0, 2.0));
        assert_eq!((t.min_abs_mm, t.max_abs_mm), (1.0, 5.0));
        assert_eq!(t.mean_mm, [1.5, 2.0, -0.5]);
        assert_eq!(t.std_mm, [1.5, 2.0, 0.5]);
        assert_eq!((t.min_mm[2], t.max_mm[2]), (-1.0, 0.0));
    }

    #[test]
    fn box_stats_quartiles_whiskers_and_outliers() {
        let b = box_stats(&[1.0, 2.0, 3.0, 4.0, 5.0, 100.0]);
        assert_eq!((b.q1, b.median, b.q3), (2.25, 3.5, 4.75));
        assert_eq!((b.whisker_lo, b.whisker_hi, b.outliers), (1.0, 5.0, 1));
        assert_eq!(box_stats(&[7.0]).median, 7.0);
    }
}

/// How honest a model's predictive distribution and its warnings were on
/// held-out rows.
#[derive(Debug, Clone, Copy, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct PredictiveScores {
    /// Share of held-out rows inside the 95 % predictive interval
    /// `μ ± 1.96 σ` of a new measurement, per axis (x, y, z).
    pub coverage_95: [f64; 3],
    /// Mean negative log predictive density of the held-out errors under
    /// `N(μ, σ²)`, per row and axis (nats; lower is better).
    pub nlpd: f64,
    /// Share of held-out rows the model flagged as outside its coverage.
    pub flag_rate: f64,
    /// Share of the held-out rows with a gross error (3D error over
    /// [`crate::model::GROSS_FACTOR`] × the model's held-out 3D RMS) that it
    /// flagged; `None` when no row had one.
    pub flag_recall: Option<f64>,
    /// Held-out rows with a gross error.
    pub gross_rows: usize,
}

/// The 97.5 % quantile of the standard normal: half-width of a 95 %
/// interval in standard deviations.
pub const Z95: f64 = 1.959_963_984_540_054;

/// The rows whose 3D error `‖truth − mean‖` exceeds `gross_factor` × its
/// 3D RMS over all rows: the gross errors of [`PredictiveScores`].
pub fn gross_rows(truth: &[[f64; 3]], mean: &[[f64; 3]], gross_factor: f64) -> Vec<usize> {
    let mut sq = 0.0;
    for (t, m) in truth.iter().zip(mean) {
        for a in 0..3 {
            let e = t[a] - m[a];
            sq += e * e;
        }
    }
    let rms3 = (sq / truth.len().max(1) as f64).sqrt();
    truth
        .iter()
        .zip(mean)
        .enumerate()
        .filter(|(_, (t, m))| {
            let d: f64 = (0..3).map(|a| (t[a] - m[a]).powi(2)).sum();
            d.sqrt() > gross_factor * rms3
        })
        .map(|(i, _)| i)
        .collect()
}

/// [`PredictiveScores`] of predictions `mean ± std` (std of a new
/// measurement, per axis) against the measured `truth`, with the rows the
/// model flagged (`flagged[i]`). `gross_factor` × the 3D RMS of `truth −
/// mean` is what counts as a gross error.
pub fn predictive_scores(
    truth: &[[f64; 3]],
    mean: &[[f64; 3]],
    std: &[[f64; 3]],
    flagged: &[bool],
    gross_factor: f64,
) -> PredictiveScores {
    let n = truth.len().max(1) as f64;
    let mut inside = [0usize; 3];
    let mut nlpd = 0.0;
    for ((t, m), s) in truth.iter().zip(mean).zip(std) {
        for a in 0..3 {
            let e = t[a] - m[a];
            let v = (s[a] * s[a]).max(f64::MIN_POSITIVE);
            if e.abs() <= Z95 * s[a] {
                inside[a] += 1;
            }
            nlpd += 0.5 * (2.0 * std::f64::consts::PI * v).ln() + e * e / (2.0 * v);
        }
    }
    let gross = gross_rows(truth, mean, gross_factor);
    let caught = gross.iter().filter(|&&i| flagged[i]).count();
    PredictiveScores {
        coverage_95: inside.map(|c| c as f64 / n),
        nlpd: nlpd / (3.0 * n),
        flag_rate: flagged.iter().filter(|f| **f).count() as f64 / n,
        flag_recall: (!gross.is_empty()).then(|| caught as f64 / gross.len() as f64),
        gross_rows: gross.len(),
    }
}

#[cfg(test)]
mod predictive_tests {
    use super::*;

    #[test]
    fn a_calibrated_gaussian_covers_95_percent_and_flags_count() {
        let mut rng = rng_for(3, "scores");
        let m = 4000;
        let truth: Vec<[f64; 3]> = (0..m)
            .map(|_| {
                std::array::from_fn(|_| {
                    rand_distr::Distribution::<f64>::sample(&rand_distr::StandardNormal, &mut rng)
                })
            })
            .collect();
        let mean = vec![[0.0; 3]; m];
        let std = vec![[1.0; 3]; m];
        let none = vec![false; m];
        let s = predictive_scores(&truth, &mean, &std, &none, 3.0);
        for c in s.coverage_95 {
            assert!((c - 0.95).abs() < 0.015, "{c}");
        }
        // E[-ln N(e; 0, 1)] = ½ ln 2π + ½
        assert!((s.nlpd - (0.5 * (2.0 * std::f64::consts::PI).ln() + 0.5)).abs() < 0.03);
        assert_eq!(s.flag_rate, 0.0);
        // gross errors planted at seeded random rows, flagged by a rule on
        // the error's size: recall counts the planted ones caught
        let mut gross = truth.clone();
        for _ in 0..40 {
            let i = rand::RngExt::random_range(&mut rng, 0..m);
            gross[i] = gross[i].map(|v| 10.0 * v + 10.0f64.copysign(v));
        }
        let flagged: Vec<bool> = gross
            .iter()
            .map(|t| t.iter().map(|v| v * v).sum::<f64>() > 100.0)
            .collect();
        let g = predictive_scores(&gross, &mean, &std, &flagged, 3.0);
        assert!(g.gross_rows > 20, "{g:?}");
        assert_eq!(g.flag_recall, Some(1.0));
        assert!(g.flag_rate < 0.015, "{g:?}");
        assert!(g.nlpd > s.nlpd);
        // an over-confident model covers less
        let narrow = vec![[0.5; 3]; m];
        assert!(predictive_scores(&truth, &mean, &narrow, &flagged, 3.0).coverage_95[0] < 0.7);
    }
}
