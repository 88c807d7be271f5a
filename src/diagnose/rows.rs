//! The rows the candidate test scans (so that a diagnosis of a whole
//! campaign of thousands of rows fits in memory and time).
//!
//! The candidate test keeps, for every scanned parameter value, whitened
//! columns of every row ([`super::plan`]), and the step family scans one
//! value a row: its cost grows as m² in memory and m³ in time. Above
//! [`super::DiagnoseOptions::scan_rows`] rows the families are therefore
//! scanned on that many rows spread evenly over the campaign, in measurement
//! order, at the current model's hyperparameters refactorised on them
//! ([`crate::model::ErrorModel::restricted`]); a history feature (a joint's
//! moves, its travel since a reversal) is computed on the whole campaign
//! first, so each scanned row keeps its own history. A subset of the rows is
//! a valid sample for the test (its p-values stay calibrated; its power is
//! that of a campaign of the subset's size), and the model with and
//! without the chosen effect is still fitted and cross-validated on every
//! row. A candidate's statistic, score and evidence are of the scanned
//! rows; the CV figures, the "after" check and the sizes of what is added
//! are of all rows. A step or block edge shows first at the scanned row after
//! it and is then placed among the campaign rows since the scanned row
//! before ([`ScanRows::gap`]) by the CV residuals of all rows
//! ([`place_steps`]).

use super::report::EffectReport;
use crate::features::Feature;

/// The rows of a campaign a candidate scan runs on: all of them, or an
/// evenly spread subset in measurement order (the first and the last row
/// included).
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct ScanRows {
    rows: Vec<usize>,
    total: usize,
}

impl ScanRows {
    /// Every row of a campaign of `m` rows.
    pub fn all(m: usize) -> Self {
        ScanRows {
            rows: (0..m).collect(),
            total: m,
        }
    }

    /// `n` rows of a campaign of `m`, evenly spread: row
    /// `round(i·(m − 1)/(n − 1))` for `i = 0 … n − 1`; all rows when
    /// `n ≥ m`, or when `n < 2` (no spread to speak of).
    pub fn spread(m: usize, n: usize) -> Self {
        if n >= m || n < 2 {
            return ScanRows::all(m);
        }
        ScanRows {
            rows: (0..n)
                .map(|i| (i * (m - 1) + (n - 1) / 2) / (n - 1))
                .collect(),
            total: m,
        }
    }

    /// Number of scanned rows.
    pub fn len(&self) -> usize {
        self.rows.len()
    }

    /// Whether no row is scanned.
    pub fn is_empty(&self) -> bool {
        self.rows.is_empty()
    }

    /// Whether every row of the campaign is scanned.
    pub fn is_all(&self) -> bool {
        self.rows.len() == self.total
    }

    /// Rows of the whole campaign.
    pub fn total(&self) -> usize {
        self.total
    }

    /// The scanned rows (campaign row numbers, increasing).
    pub fn indices(&self) -> &[usize] {
        &self.rows
    }

    /// The campaign row of scanned position `pos`.
    pub fn row(&self, pos: usize) -> usize {
        self.rows[pos]
    }

    /// The first scanned position at or after campaign row `row` (a step at
    /// `row` changes the scanned rows from there on).
    pub fn position(&self, row: usize) -> usize {
        self.rows.partition_point(|&r| r < row)
    }

    /// The campaign rows a step shown first at scanned row `row` may be at:
    /// from the row after the scanned row before it, to `row`.
    pub fn gap(&self, row: usize) -> std::ops::RangeInclusive<usize> {
        let p = self.position(row);
        let start = if p == 0 { 0 } else { self.rows[p - 1] + 1 };
        start..=row
    }

    /// The values of `v` (one per campaign row) at the scanned rows.
    pub fn pick<T: Clone>(&self, v: &[T]) -> Vec<T> {
        self.rows.iter().map(|&i| v[i].clone()).collect()
    }
}

/// A step or block edge found on scanned rows ([`ScanRows`]) is at its
/// scanned row or at one of the campaign rows just before it
/// ([`ScanRows::gap`]): each is placed at the row of its gap that best
/// splits the CV residuals of all rows — least squares, the levels on either
/// side the mean residual of the [`PLACE_WINDOW`] spacings of rows before
/// and after the gap — and the support interval is widened to the gaps.
pub(super) fn place_steps(report: &mut EffectReport, rows: &ScanRows, residuals: &[[f64; 3]]) {
    let window = PLACE_WINDOW * rows.total().div_ceil(rows.len().max(1));
    let mut moved = Vec::new();
    for f in report.add.iter_mut() {
        let Feature::Step { row } = f else { continue };
        let gap = rows.gap(*row);
        let (a, b) = (*gap.start(), *gap.end());
        let before = a.saturating_sub(window)..a;
        let after = b..(b + window).min(residuals.len());
        if a == b || before.is_empty() || after.is_empty() {
            continue;
        }
        let mean = |r: std::ops::Range<usize>| -> [f64; 3] {
            let n = r.len() as f64;
            std::array::from_fn(|x| r.clone().map(|i| residuals[i][x]).sum::<f64>() / n)
        };
        let (lo, hi) = (mean(before), mean(after));
        let d2 = |e: &[f64; 3], l: &[f64; 3]| (0..3).map(|x| (e[x] - l[x]).powi(2)).sum::<f64>();
        // rows a..b are ambiguous: before the step at lo, from it on at hi
        let cost = |c: usize| -> f64 {
            (a..b)
                .map(|i| d2(&residuals[i], if i < c { &lo } else { &hi }))
                .sum()
        };
        let best = (a..=b)
            .min_by(|&x, &y| cost(x).total_cmp(&cost(y)))
            .unwrap_or(b);
        for v in report.params.values_mut() {
            if *v == *row as f64 {
                *v = best as f64;
            }
        }
        moved.push(format!("{} → {best} (rows {a}–{b})", *row));
        *row = best;
    }
    for (key, ci) in report.params_ci.iter_mut() {
        if key.ends_with("row") {
            ci[0] = *rows.gap(ci[0] as usize).start() as f64;
        }
    }
    if !moved.is_empty() {
        report.add_note(format!(
            "found on {} scanned rows, placed between them by the CV residuals of all rows: {}",
            rows.len(),
            moved.join(", ")
        ));
    }
}

/// Rows on either side of a gap that set the levels [`place_steps`] splits
/// it between, in spacings of the scanned rows.
const PLACE_WINDOW: usize = 8;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn spread_rows_are_even_ordered_and_keep_both_ends() {
        let s = ScanRows::spread(12_000, 3_000);
        assert_eq!(s.len(), 3_000);
        assert!(!s.is_all());
        assert_eq!(s.row(0), 0);
        assert_eq!(s.row(2_999), 11_999);
        assert!(
            s.indices()
                .windows(2)
                .all(|w| (4..=5).contains(&(w[1] - w[0])))
        );
        // a step between two scanned rows shows from the next one on
        let p = s.position(s.row(10) + 1);
        assert_eq!(p, 11);
        assert_eq!(s.position(s.row(10)), 10);
        assert_eq!(s.pick(&(0..12_000).collect::<Vec<usize>>()), s.indices());
        assert_eq!(s.gap(s.row(10)), s.row(9) + 1..=s.row(10));
        assert_eq!(s.gap(0), 0..=0);
        assert_eq!(ScanRows::all(9).gap(4), 4..=4);
        // as many or more rows than the campaign: all of them
        assert!(ScanRows::spread(500, 500).is_all());
        assert_eq!(ScanRows::spread(500, 900), ScanRows::all(500));
    }
}
