//! How much memory a diagnosis needs, estimated before anything large is
//! allocated, so that a campaign too large for the machine is refused with
//! the number of rows that fits instead of being killed half-way.
//!
//! The candidate test keeps, for every scanned parameter value of every
//! family and for each of the three outputs, its whitened columns and their
//! leave-one-out factors (m numbers each, several times over: `Q_X`, `U`,
//! `V`, the denominators), so the need grows as rows × scanned values. The
//! constant is measured: the peak resident memory of `robokrige diagnose`
//! over rows × values was 320 B at 300 rows (comau_harmonic, 2 083 values),
//! 322 B at 1 495 (UR10 series B, 4 887) and 259–268 B at 2 773 (series C
//! and series C with a bump planted, 6 018), 2026-11-25.

use super::DiagnoseOptions;
use crate::dataset::Dataset;
use crate::kriging::FitPlan;
use crate::{Error, Result};

/// Peak bytes per row and scanned parameter value (the largest measured
/// ratio, rounded up; see the module docs).
pub const BYTES_PER_ROW_VALUE: u64 = 330;

/// Rows, evenly spread over the campaign, the candidate families are
/// generated on to count their values (the families hold m numbers per
/// value: counting on all rows of a large campaign would allocate what the
/// plan is there to foresee).
const COUNT_ROWS: usize = 1000;

/// The memory a diagnosis of a campaign needs.
#[derive(Debug, Clone)]
pub struct DiagnosePlan {
    rows: usize,
    /// Scanned values that do not grow with the rows (all but the step's).
    fixed_values: usize,
    options: DiagnoseOptions,
    bytes: u64,
}

impl DiagnosePlan {
    /// The plan for diagnosing `data` with `o`: the candidate families are
    /// generated on at most 1 000 rows spread over the campaign and
    /// counted (the step's grid, one value a row, scaled to all rows).
    pub fn new(data: &Dataset, o: &DiagnoseOptions) -> Self {
        let rows = data.len();
        let sample = if rows > COUNT_ROWS {
            data.select(
                &(0..COUNT_ROWS)
                    .map(|i| i * rows / COUNT_ROWS)
                    .collect::<Vec<_>>(),
            )
        } else {
            data.clone()
        };
        let counted: usize = super::scan::families(&sample, &[], o.robot.as_ref())
            .iter()
            .map(|f| f.grid.len())
            .sum();
        let fixed_values = counted - super::scan::step_rows(sample.len()).len();
        let mut plan = DiagnosePlan {
            rows,
            fixed_values,
            options: o.clone(),
            bytes: 0,
        };
        plan.bytes = plan.bytes_at(rows);
        plan
    }

    /// Scanned values at `n` rows.
    fn values_at(&self, n: usize) -> usize {
        self.fixed_values + super::scan::step_rows(n).len()
    }

    /// The fit's plan at `n` rows, as [`super::diagnose`] fits them.
    fn fit_at(&self, n: usize) -> FitPlan {
        FitPlan::new(
            n,
            3,
            &self.options.for_rows(n).kriging,
            rayon::current_num_threads(),
        )
    }

    /// Estimated peak at `n` rows: the fit's plan, and the candidate test.
    fn bytes_at(&self, n: usize) -> u64 {
        self.fit_at(n).bytes + BYTES_PER_ROW_VALUE * (n * self.values_at(n)) as u64
    }

    /// Estimated peak memory, bytes.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Parameter values the candidate families scan.
    pub fn values(&self) -> usize {
        self.values_at(self.rows)
    }

    /// The most rows of this campaign whose diagnosis fits in `limit`
    /// bytes (0 when none does).
    pub fn max_rows(&self, limit: u64) -> usize {
        let (mut lo, mut hi) = (0, self.rows);
        while lo < hi {
            let mid = (lo + hi).div_ceil(2);
            if self.bytes_at(mid) <= limit {
                lo = mid;
            } else {
                hi = mid - 1;
            }
        }
        lo
    }

    /// Refuse when the plan needs more than the memory limit
    /// ([`crate::memory::limit`]); `hint(n)` says how to run on `n` rows.
    pub fn check(&self, hint: impl Fn(usize) -> String) -> Result<()> {
        match crate::memory::limit() {
            Some((limit, source)) if self.bytes > limit => {
                let n = self.max_rows(limit);
                let smallest = 2 * self.options.folds.max(10);
                Err(Error::Memory {
                    what: format!("a diagnosis of {} rows", self.rows),
                    needed: crate::memory::human(self.bytes),
                    limit: format!("{} ({source})", crate::memory::human(limit)),
                    hint: if n >= smallest {
                        format!(
                            "diagnose at most {n} rows ({}), or raise {}",
                            hint(n),
                            crate::memory::LIMIT_ENV
                        )
                    } else {
                        format!(
                            "not even {smallest} rows would fit: raise {}",
                            crate::memory::LIMIT_ENV
                        )
                    },
                })
            }
            _ => Ok(()),
        }
    }
}

impl std::fmt::Display for DiagnosePlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let fit = self.fit_at(self.rows);
        write!(
            f,
            "{} rows, {} scanned candidate values, about {} of memory (the fit: {fit})",
            self.rows,
            self.values(),
            crate::memory::human(self.bytes),
        )
    }
}
