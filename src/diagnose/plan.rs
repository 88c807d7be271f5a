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

/// The memory a diagnosis of a campaign needs.
#[derive(Debug, Clone)]
pub struct DiagnosePlan {
    rows: usize,
    values: usize,
    fit: FitPlan,
    bytes: u64,
}

impl DiagnosePlan {
    /// The plan for diagnosing `data` with `o` (its candidate families are
    /// generated and counted, then dropped: `m` numbers per scanned value).
    pub fn new(data: &Dataset, o: &DiagnoseOptions) -> Self {
        let rows = data.len();
        let values = super::scan::families(data, &[], o.robot.as_ref())
            .iter()
            .map(|f| f.grid.len())
            .sum();
        let fit = FitPlan::new(
            rows,
            3,
            &o.for_rows(rows).kriging,
            rayon::current_num_threads(),
        );
        let bytes = fit.bytes + BYTES_PER_ROW_VALUE * (rows * values) as u64;
        DiagnosePlan {
            rows,
            values,
            fit,
            bytes,
        }
    }

    /// Estimated peak memory, bytes.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Parameter values the candidate families scan.
    pub fn values(&self) -> usize {
        self.values
    }

    /// The most rows that fit in `limit` bytes: a smaller campaign scans at
    /// most as many values per family, so this is on the safe side.
    pub fn max_rows(&self, limit: u64) -> usize {
        let per_row = BYTES_PER_ROW_VALUE * self.values.max(1) as u64
            + self.fit.bytes / self.rows.max(1) as u64;
        (limit / per_row.max(1)) as usize
    }

    /// Refuse when the plan needs more than the memory limit
    /// ([`crate::memory::limit`]); `hint(n)` says how to run on `n` rows.
    pub fn check(&self, hint: impl Fn(usize) -> String) -> Result<()> {
        match crate::memory::limit() {
            Some((limit, source)) if self.bytes > limit => Err(Error::Memory {
                what: format!("a diagnosis of {} rows", self.rows),
                needed: crate::memory::human(self.bytes),
                limit: format!("{} ({source})", crate::memory::human(limit)),
                hint: format!(
                    "diagnose at most {} rows ({}), or raise {}",
                    self.max_rows(limit),
                    hint(self.max_rows(limit)),
                    crate::memory::LIMIT_ENV
                ),
            }),
            _ => Ok(()),
        }
    }
}

impl std::fmt::Display for DiagnosePlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(
            f,
            "{} rows, {} scanned candidate values, about {} of memory (the fit: {})",
            self.rows,
            self.values,
            crate::memory::human(self.bytes),
            self.fit
        )
    }
}
