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
//!
//! Above [`DiagnoseOptions::scan_rows`] the candidate test runs on that many
//! rows ([`super::ScanRows`]), so its term stops growing with the campaign;
//! the fits and closed-form CVs on all rows are the fit's plan.

use super::DiagnoseOptions;
use crate::dataset::Dataset;
use crate::kriging::FitPlan;
use crate::{Error, Result};

/// Peak bytes per row and scanned parameter value (the largest measured
/// ratio, rounded up; see the module docs).
pub const BYTES_PER_ROW_VALUE: u64 = 330;

/// How many scanned values a grid point counts for: one per three columns
/// of its widest axis (rounded up). The constant was measured on families
/// of one to three columns a value on every axis; a harmonic through the
/// Jacobian has six columns, two on each axis (its row of the Jacobian
/// times sin and cos), and counts once: with it, all 2 773 rows of UR10
/// series C peaked at 6.9 GB for a plan of 8.5 GB.
fn value_weight(point: &super::scan::GridPoint) -> usize {
    let widest = (0..3).map(|a| point.on_axis(a).len()).max().unwrap_or(0);
    widest.div_ceil(3).max(1)
}

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
    /// The same, each weighted by its memory ([`value_weight`]).
    fixed_weight: usize,
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
            data.select(super::ScanRows::spread(rows, COUNT_ROWS).indices())
        } else {
            data.clone()
        };
        let families = super::scan::families(&sample, &[], o.robot.as_ref());
        let points = || families.iter().flat_map(|f| &f.grid);
        let steps = super::scan::step_rows(sample.len()).len();
        let mut plan = DiagnosePlan {
            rows,
            fixed_values: points().count() - steps,
            fixed_weight: points().map(value_weight).sum::<usize>() - steps,
            options: o.clone(),
            bytes: 0,
        };
        plan.bytes = plan.bytes_at(rows);
        plan
    }

    /// Rows the candidate test scans in a campaign of `n` rows.
    fn scanned_at(&self, n: usize) -> usize {
        n.min(self.options.scan_rows)
    }

    /// Parameter values the families scan on `scanned` rows.
    fn values_scanning(&self, scanned: usize) -> usize {
        self.fixed_values + super::scan::step_rows(scanned).len()
    }

    /// [`DiagnosePlan::values_scanning`] weighted by memory ([`value_weight`]).
    fn weight_scanning(&self, scanned: usize) -> usize {
        self.fixed_weight + super::scan::step_rows(scanned).len()
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

    /// Estimated peak at `n` rows, scanning `scanned` of them: the fit's
    /// plan, and the candidate test.
    fn bytes_scanning(&self, n: usize, scanned: usize) -> u64 {
        self.fit_at(n).bytes
            + BYTES_PER_ROW_VALUE * (scanned * self.weight_scanning(scanned)) as u64
    }

    /// Estimated peak at `n` rows.
    fn bytes_at(&self, n: usize) -> u64 {
        self.bytes_scanning(n, self.scanned_at(n))
    }

    /// Estimated peak memory, bytes.
    pub fn bytes(&self) -> u64 {
        self.bytes
    }

    /// Parameter values the candidate families scan.
    pub fn values(&self) -> usize {
        self.values_scanning(self.scanned_rows())
    }

    /// Rows scanned in this campaign.
    pub fn scanned_rows(&self) -> usize {
        self.scanned_at(self.rows)
    }

    /// The most rows of this campaign whose diagnosis fits in `limit`
    /// bytes (0 when none does).
    pub fn max_rows(&self, limit: u64) -> usize {
        largest(self.rows, |n| self.bytes_at(n) <= limit)
    }

    /// The most rows the candidate test may scan for a diagnosis of all
    /// rows to fit in `limit` bytes (0 when none does).
    pub fn max_scanned_rows(&self, limit: u64) -> usize {
        largest(self.scanned_rows(), |s| {
            self.bytes_scanning(self.rows, s) <= limit
        })
    }

    /// The plan of diagnosing `data` with `o` as a command checks it before
    /// it starts: refused by [`DiagnosePlan::check`] with advice that names
    /// the command's options `(rows, scan_rows)` (e.g. `("--rows",
    /// "--scan-rows")`); returned when it is worth showing (a campaign above
    /// [`crate::kriging::SEARCH_ROWS`] rows), `None` for a small one.
    pub fn check_options(
        data: &Dataset,
        o: &DiagnoseOptions,
        (rows, scan_rows): (&str, &str),
    ) -> Result<Option<Self>> {
        let plan = Self::new(data, o);
        plan.check(
            |n| format!("`{rows} {n}`"),
            |n| format!("`{scan_rows} {n}`"),
        )?;
        Ok((data.len() > crate::kriging::SEARCH_ROWS).then_some(plan))
    }

    /// Refuse when the plan needs more than the memory limit
    /// ([`crate::memory::limit`]); `rows_hint(n)` says how to diagnose `n`
    /// rows, `scan_hint(s)` how to scan `s` rows of all of them (offered
    /// first when it fits: every row stays in the models compared).
    pub fn check(
        &self,
        rows_hint: impl Fn(usize) -> String,
        scan_hint: impl Fn(usize) -> String,
    ) -> Result<()> {
        match crate::memory::limit() {
            Some((limit, source)) if self.bytes > limit => {
                let n = self.max_rows(limit);
                let s = self.max_scanned_rows(limit);
                let smallest = 2 * self.options.folds.max(10);
                Err(Error::Memory {
                    what: format!("a diagnosis of {} rows", self.rows),
                    needed: crate::memory::human(self.bytes),
                    limit: format!("{} ({source})", crate::memory::human(limit)),
                    hint: if s >= super::MIN_SCAN_ROWS {
                        format!(
                            "scan the candidates on at most {s} of the rows ({}), diagnose at most {n} rows ({}), or raise {}",
                            scan_hint(s),
                            rows_hint(n),
                            crate::memory::LIMIT_ENV
                        )
                    } else if n >= smallest {
                        format!(
                            "diagnose at most {n} rows ({}), or raise {}",
                            rows_hint(n),
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

/// The largest `n ≤ upper` with `fits(n)` (0 when none does), `fits`
/// monotone.
fn largest(upper: usize, fits: impl Fn(usize) -> bool) -> usize {
    let (mut lo, mut hi) = (0, upper);
    while lo < hi {
        let mid = (lo + hi).div_ceil(2);
        if fits(mid) {
            lo = mid;
        } else {
            hi = mid - 1;
        }
    }
    lo
}

impl std::fmt::Display for DiagnosePlan {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let fit = self.fit_at(self.rows);
        let scanned = self.scanned_rows();
        let subset = if scanned < self.rows {
            format!("candidates scanned on {scanned} of them, ")
        } else {
            String::new()
        };
        write!(
            f,
            "{} rows, {subset}{} scanned candidate values, about {} of memory (the fit: {fit})",
            self.rows,
            self.values(),
            crate::memory::human(self.bytes),
        )
    }
}
