//! The measurement CSV: read, validate, write.
//!
//! # File format
//!
//! One row per measured pose, in the order the robot visited them. The first
//! line is a header; column names are case-sensitive, cells are trimmed of
//! surrounding whitespace, and a UTF-8 byte-order mark is accepted.
//!
//! | column | meaning |
//! |---|---|
//! | `q1`..`qN` | commanded joint positions in degrees (mm for a prismatic joint). Required, numbered contiguously from 1 without leading zeros; N ≥ 1 |
//! | `dir1`..`dirN` | optional direction of approach, `+1` or `-1` (`1`, `+1`, `-1`, `1.0`, `-1.0`, …). All N or none; when absent they are derived from the row order with [`derive_directions`] |
//! | `ex`,`ey`,`ez` | optional TCP error in mm (measured − nominal); all three or none |
//! | `x`,`y`,`z` | optional measured TCP position in mm; all three or none. May appear together with `ex`,`ey`,`ez` |
//! | `id` | optional row label (any text) |
//! | anything else | a covariate, e.g. `time_s`, `temp_c`, `payload_kg` |
//!
//! Joint, direction, error and position cells must be finite numbers; an empty
//! cell there is an error. A covariate column whose non-empty cells all parse
//! as finite numbers is a numeric [`Covariate`] (empty cells are missing and
//! stored as NaN); any other covariate column is kept as a [`TextColumn`].
//! A file with neither `ex`,`ey`,`ez` nor `x`,`y`,`z` is valid: a plain pose
//! list, e.g. for prediction.
//!
//! Every problem is reported as a [`crate::Error`] naming the file, the line
//! (the header is line 1) and the column where there is one.
//!
//! [`write_csv`] writes the columns in the order `id`, `q1..qN`, `dir1..dirN`,
//! `ex,ey,ez`, `x,y,z`, covariates, text columns. Directions are always
//! written, so a dataset whose directions were [`DirSource::Derived`] reads
//! back as [`DirSource::Given`]; everything else round-trips exactly.

pub mod import;
mod predictions;
mod read;
pub(crate) mod table;
mod write;

pub use predictions::write_predictions;
pub(crate) use read::from_table;
pub use read::{read_csv, read_csv_from};
pub use write::{write_csv, write_csv_to};

use crate::space::derive_directions;
use crate::{Error, Result};

/// Largest |joint value| accepted (degrees, or mm for a prismatic joint):
/// a thousand turns, or a kilometre of travel.
pub const MAX_ABS_JOINT: f64 = 1e6;

/// Largest |TCP error| accepted, in mm. Absolute errors of industrial
/// robots are 0.1–10 mm; a metre is not an error in mm but a unit or
/// column mistake (one `ex` of `1e300` would overflow the model).
pub const MAX_ABS_ERROR_MM: f64 = 1e3;

/// Largest |measured TCP coordinate| accepted, in mm (a kilometre).
pub const MAX_ABS_POSITION_MM: f64 = 1e6;

/// Largest |covariate value| accepted: room for a time stamp in
/// nanoseconds, far from where squares overflow.
pub const MAX_ABS_COVARIATE: f64 = 1e20;

/// Column names with a fixed meaning; covariates and text columns may not use them.
const RESERVED: [&str; 7] = ["ex", "ey", "ez", "x", "y", "z", "id"];

/// Where the direction coefficients came from.
#[derive(Debug, Clone, Copy, PartialEq, Eq, serde::Serialize, serde::Deserialize)]
pub enum DirSource {
    /// Read from `dir1..dirN` columns (or passed in explicitly).
    Given,
    /// Derived from the order of the poses with [`derive_directions`].
    Derived,
}

/// A numeric covariate column such as `temp_c`.
///
/// Missing cells are NaN; `missing` counts them. Equality treats two missing
/// cells as equal, so a dataset with gaps still equals itself after a round trip.
#[derive(Debug, Clone)]
pub struct Covariate {
    /// Column name as in the header.
    pub name: String,
    /// One value per row; NaN where the cell was empty.
    pub values: Vec<f64>,
    /// Number of missing (NaN) values.
    pub missing: usize,
}

impl PartialEq for Covariate {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name
            && self.missing == other.missing
            && self.values.len() == other.values.len()
            && self
                .values
                .iter()
                .zip(&other.values)
                .all(|(a, b)| a == b || (a.is_nan() && b.is_nan()))
    }
}

/// A covariate column with at least one non-numeric cell, kept as text.
///
/// Equality compares names and cells, not the `note`.
#[derive(Debug, Clone)]
pub struct TextColumn {
    /// Column name as in the header.
    pub name: String,
    /// One (trimmed) cell per row.
    pub values: Vec<String>,
    /// For a column that is numeric but for some cells (e.g. one `inf`):
    /// the first such cell, with its line, so that the user is told why
    /// the column is not a covariate ([`Dataset::warnings`]).
    pub note: Option<String>,
}

impl PartialEq for TextColumn {
    fn eq(&self, other: &Self) -> bool {
        self.name == other.name && self.values == other.values
    }
}

/// The line of the source file each row was read from (the header is line
/// 1); empty for a dataset made in memory. Where a row came from is not
/// part of the data: any two compare equal.
#[derive(Debug, Clone, Default)]
pub struct SourceLines(pub Vec<u64>);

impl PartialEq for SourceLines {
    fn eq(&self, _: &Self) -> bool {
        true
    }
}

/// A measurement campaign: poses in visiting order plus what was measured there.
#[derive(Debug, Clone, PartialEq)]
pub struct Dataset {
    /// File name (or `"<memory>"`) used in messages.
    pub source: String,
    /// Commanded joint positions, m rows × n joints (degrees, or mm for a prismatic joint).
    pub q: Vec<Vec<f64>>,
    /// Direction coefficients λ, m × n, each exactly ±1.0.
    pub dir: Vec<Vec<f64>>,
    /// Whether `dir` was given or derived from the row order.
    pub dir_source: DirSource,
    /// TCP errors `[ex, ey, ez]` in mm (measured − nominal), if measured.
    pub errors: Option<Vec<[f64; 3]>>,
    /// Measured TCP positions `[x, y, z]` in mm, if recorded.
    pub positions: Option<Vec<[f64; 3]>>,
    /// Row labels from the `id` column.
    pub ids: Option<Vec<String>>,
    /// Numeric covariates in header order.
    pub covariates: Vec<Covariate>,
    /// Text covariates in header order.
    pub text: Vec<TextColumn>,
    /// Where each row was read from, for messages ([`Dataset::line`]).
    pub lines: SourceLines,
}

impl Dataset {
    /// Build a pose list (no measurements) from joint vectors in visiting order.
    ///
    /// With `dir == None` the directions are derived from the order of `q`
    /// (first pose +1 on every joint) and `dir_source` is [`DirSource::Derived`].
    /// The result is checked with [`Dataset::validate`].
    pub fn from_poses(
        source: impl Into<String>,
        q: Vec<Vec<f64>>,
        dir: Option<Vec<Vec<f64>>>,
    ) -> Result<Dataset> {
        let mut d = Dataset {
            source: source.into(),
            q,
            dir: Vec::new(),
            dir_source: DirSource::Given,
            errors: None,
            positions: None,
            ids: None,
            covariates: Vec::new(),
            text: Vec::new(),
            lines: SourceLines::default(),
        };
        d.check_q()?;
        match dir {
            Some(dir) => d.dir = dir,
            None => {
                d.dir = derive_directions(&d.q, None);
                d.dir_source = DirSource::Derived;
            }
        }
        d.validate()?;
        Ok(d)
    }

    /// Number of joints n (0 for an empty dataset).
    pub fn n_joints(&self) -> usize {
        self.q.first().map_or(0, Vec::len)
    }

    /// Number of poses m.
    pub fn len(&self) -> usize {
        self.q.len()
    }

    /// True when there are no poses.
    pub fn is_empty(&self) -> bool {
        self.q.is_empty()
    }

    /// Plausibility warnings: units (joint angles are degrees, mm for a
    /// prismatic joint: when every joint value lies within ±2π and some joint
    /// moves by more than 0.5, the file probably holds radians), and poses that
    /// repeat an earlier one exactly (an interpolating model must pass through
    /// both measurements; `--nugget` lets it average them).
    pub fn warnings(&self) -> Vec<String> {
        let mut out = self.unit_warnings();
        let mut seen = std::collections::HashSet::new();
        let repeats = self
            .q
            .iter()
            .zip(&self.dir)
            .filter(|(q, d)| {
                // `+ 0.0` makes −0.0 equal to 0.0
                let key: Vec<u64> = q
                    .iter()
                    .chain(d.iter())
                    .map(|v| (v + 0.0).to_bits())
                    .collect();
                !seen.insert(key)
            })
            .count();
        if repeats > 0 {
            out.push(format!(
                "{}: {repeats} pose(s) repeat an earlier pose exactly; the default nugget takes their differences as noise (with --no-nugget the model would have to interpolate both measurements)",
                self.source
            ));
        }
        for t in &self.text {
            if let Some(note) = &t.note {
                out.push(format!(
                    "{}: column '{}' is read as text, not as a numeric covariate: {note}; fix the cell (an empty cell counts as missing)",
                    self.source, t.name
                ));
            }
        }
        out
    }

    /// The line of the source file row `row` (0-based) was read from, when
    /// the dataset was read from a file.
    pub fn line(&self, row: usize) -> Option<u64> {
        self.lines.0.get(row).copied()
    }

    /// "line L" of row `row` when known, else "row k (1-based data row)".
    pub fn row_label(&self, row: usize) -> String {
        self.line(row)
            .map_or_else(|| format!("data row {}", row + 1), |l| format!("line {l}"))
    }

    fn unit_warnings(&self) -> Vec<String> {
        let n = self.n_joints();
        if self.is_empty() || n == 0 {
            return Vec::new();
        }
        let tau = std::f64::consts::TAU + 1e-9;
        let all_small = self.q.iter().flatten().all(|v| v.abs() <= tau);
        let moving = (0..n).any(|j| {
            let (lo, hi) = self
                .q
                .iter()
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), r| {
                    (a.min(r[j]), b.max(r[j]))
                });
            hi - lo > 0.5
        });
        if all_small && moving {
            vec![format!(
                "{}: every joint value lies within ±2π; robokrige expects degrees (mm for prismatic joints) — if these are radians, convert them (× 180/π)",
                self.source
            )]
        } else {
            Vec::new()
        }
    }

    /// The numeric covariate called `name`, if any.
    pub fn covariate(&self, name: &str) -> Option<&Covariate> {
        self.covariates.iter().find(|c| c.name == name)
    }

    /// The label of every row in column `name` (a text column or a numeric
    /// covariate), for grouped cross-validation: an error naming the
    /// columns there are when it has none of that name, or naming the first
    /// row whose cell is empty.
    pub fn group_labels(&self, name: &str) -> Result<Vec<String>> {
        if let Some(t) = self.text.iter().find(|t| t.name == name) {
            if let Some(i) = t.values.iter().position(String::is_empty) {
                return Err(self.input_err(format!(
                    "column '{name}' has no group at {}",
                    self.row_label(i)
                )));
            }
            return Ok(t.values.clone());
        }
        if let Some(c) = self.covariate(name) {
            if let Some(i) = c.values.iter().position(|v| v.is_nan()) {
                return Err(self.input_err(format!(
                    "column '{name}' has no group at {}",
                    self.row_label(i)
                )));
            }
            return Ok(c.values.iter().map(|v| v.to_string()).collect());
        }
        let known: Vec<&str> = self
            .covariates
            .iter()
            .map(|c| c.name.as_str())
            .chain(self.text.iter().map(|t| t.name.as_str()))
            .collect();
        let digits = |s: &str| !s.is_empty() && s.bytes().all(|b| b.is_ascii_digit());
        let measurement = name == "id"
            || ["ex", "ey", "ez", "x", "y", "z"].contains(&name)
            || name.strip_prefix("dir").is_some_and(digits)
            || name.strip_prefix('q').is_some_and(digits);
        Err(self.input_err(format!(
            "{} to group by (extra columns: {})",
            if measurement {
                format!(
                    "'{name}' is a measurement column (id, joints, directions, errors), not a group: name an extra column"
                )
            } else {
                format!("has no column '{name}'")
            },
            if known.is_empty() {
                "none".to_string()
            } else {
                known.join(", ")
            }
        )))
    }

    /// The TCP errors, or an [`Error::Input`] if the data has no `ex,ey,ez` columns.
    pub fn errors_or_err(&self) -> Result<&[[f64; 3]]> {
        self.errors
            .as_deref()
            .ok_or_else(|| self.input_err("has no ex,ey,ez columns; add the measured TCP errors"))
    }

    /// The first `n` rows (all of them if there are no more).
    pub fn head(self, n: usize) -> Dataset {
        if n >= self.len() {
            return self;
        }
        self.select(&(0..n).collect::<Vec<_>>())
    }

    /// The rows at `rows` (in that order), every column kept. Directions are
    /// copied, not re-derived: a row keeps the λ it was measured with.
    pub fn select(&self, rows: &[usize]) -> Dataset {
        let pick = |v: &Vec<[f64; 3]>| rows.iter().map(|&i| v[i]).collect();
        Dataset {
            source: self.source.clone(),
            q: rows.iter().map(|&i| self.q[i].clone()).collect(),
            dir: rows.iter().map(|&i| self.dir[i].clone()).collect(),
            dir_source: self.dir_source,
            errors: self.errors.as_ref().map(pick),
            positions: self.positions.as_ref().map(pick),
            ids: self
                .ids
                .as_ref()
                .map(|v| rows.iter().map(|&i| v[i].clone()).collect()),
            covariates: self
                .covariates
                .iter()
                .map(|c| {
                    let values: Vec<f64> = rows.iter().map(|&i| c.values[i]).collect();
                    Covariate {
                        name: c.name.clone(),
                        missing: values.iter().filter(|v| v.is_nan()).count(),
                        values,
                    }
                })
                .collect(),
            text: self
                .text
                .iter()
                .map(|t| TextColumn {
                    name: t.name.clone(),
                    values: rows.iter().map(|&i| t.values[i].clone()).collect(),
                    note: t.note.clone(),
                })
                .collect(),
            lines: SourceLines(
                rows.iter()
                    .filter_map(|&i| self.lines.0.get(i).copied())
                    .collect(),
            ),
        }
    }

    /// Check internal consistency, for datasets built or edited in memory.
    ///
    /// Requires at least one pose and one joint; every row of `q` and `dir`
    /// has n entries; `q`, errors and positions are finite; directions are
    /// exactly ±1; every column has m entries; a covariate's `missing` equals
    /// its NaN count and its other values are finite; covariate and text
    /// column names are unique and not reserved (`qK`, `dirK`, `ex`.., `x`.., `id`).
    pub fn validate(&self) -> Result<()> {
        self.check_q()?;
        self.check_dir()?;
        self.check_triplets("errors", self.errors.as_deref(), MAX_ABS_ERROR_MM)?;
        self.check_triplets("positions", self.positions.as_deref(), MAX_ABS_POSITION_MM)?;
        if let Some(ids) = &self.ids {
            self.check_len("ids", ids.len())?;
        }
        for c in &self.covariates {
            self.check_covariate(c)?;
        }
        for t in &self.text {
            self.check_len(&format!("text column '{}'", t.name), t.values.len())?;
        }
        self.check_names()
    }

    /// An [`Error::Input`] about this dataset.
    fn input_err(&self, message: impl Into<String>) -> Error {
        Error::Input {
            source_name: self.source.clone(),
            message: message.into(),
        }
    }

    /// Non-empty, rectangular, finite joint matrix.
    fn check_q(&self) -> Result<()> {
        let n = self.n_joints();
        if self.q.is_empty() || n == 0 {
            return Err(self.input_err("no poses (need at least one row with one joint)"));
        }
        for (i, row) in self.q.iter().enumerate() {
            if row.len() != n {
                return Err(self.input_err(format!(
                    "q row {i} (0-based) has {} joints but row 0 has {n}",
                    row.len()
                )));
            }
            if row.iter().any(|v| !v.is_finite()) {
                return Err(self.input_err(format!("q row {i} (0-based) has a NaN/inf value")));
            }
            if let Some(v) = row.iter().find(|v| v.abs() > MAX_ABS_JOINT) {
                return Err(self.input_err(format!(
                    "q row {i} (0-based): joint value {v} is beyond ±{MAX_ABS_JOINT:e}"
                )));
            }
        }
        Ok(())
    }

    /// `dir` is m × n with entries exactly ±1.
    fn check_dir(&self) -> Result<()> {
        let n = self.n_joints();
        self.check_len("dir", self.dir.len())?;
        for (i, row) in self.dir.iter().enumerate() {
            if row.len() != n {
                return Err(self.input_err(format!(
                    "dir row {i} (0-based) has {} entries but there are {n} joints",
                    row.len()
                )));
            }
            if let Some(v) = row.iter().find(|v| **v != 1.0 && **v != -1.0) {
                return Err(self.input_err(format!(
                    "dir row {i} (0-based): direction must be +1 or -1, found {v}"
                )));
            }
        }
        Ok(())
    }

    /// Optional xyz triplets: m rows, all finite and within ±`limit` mm.
    fn check_triplets(&self, what: &str, rows: Option<&[[f64; 3]]>, limit: f64) -> Result<()> {
        let Some(rows) = rows else { return Ok(()) };
        self.check_len(what, rows.len())?;
        if let Some(i) = rows.iter().position(|r| r.iter().any(|v| !v.is_finite())) {
            return Err(self.input_err(format!("{what} row {i} (0-based) has a NaN/inf value")));
        }
        match rows.iter().position(|r| r.iter().any(|v| v.abs() > limit)) {
            Some(i) => Err(self.input_err(format!(
                "{what} row {i} (0-based) has a value beyond ±{limit:e} mm"
            ))),
            None => Ok(()),
        }
    }

    /// Length m, consistent missing count, no infinities.
    fn check_covariate(&self, c: &Covariate) -> Result<()> {
        self.check_len(&format!("covariate '{}'", c.name), c.values.len())?;
        let nan = c.values.iter().filter(|v| v.is_nan()).count();
        if nan != c.missing {
            return Err(self.input_err(format!(
                "covariate '{}' says {} missing but has {nan} NaN values",
                c.name, c.missing
            )));
        }
        if c.values.iter().any(|v| v.abs() > MAX_ABS_COVARIATE) {
            return Err(self.input_err(format!(
                "covariate '{}' has a value beyond ±{MAX_ABS_COVARIATE:e} (or infinite)",
                c.name
            )));
        }
        Ok(())
    }

    /// A column has one entry per pose.
    fn check_len(&self, what: &str, len: usize) -> Result<()> {
        if len == self.len() {
            Ok(())
        } else {
            Err(self.input_err(format!("{what} has {len} rows but q has {}", self.len())))
        }
    }

    /// Covariate and text names are unique, non-empty and not reserved.
    fn check_names(&self) -> Result<()> {
        let names = self.covariates.iter().map(|c| &c.name);
        let names: Vec<&String> = names.chain(self.text.iter().map(|t| &t.name)).collect();
        for (i, name) in names.iter().enumerate() {
            if name.is_empty() || name.trim() != name.as_str() {
                return Err(self.input_err(format!("column name '{name}' is empty or padded")));
            }
            if is_reserved(name) {
                return Err(self.input_err(format!("column name '{name}' is reserved")));
            }
            if names[..i].contains(name) {
                return Err(self.input_err(format!("column name '{name}' is used twice")));
            }
        }
        Ok(())
    }
}

// ----- column-name and cell rules of the format, shared with `read` -----

/// True for names with a fixed meaning in the file format (`q7`, `dir2`, `ex`, `id`, …),
/// including malformed joint names such as `q0` or `dir01`.
fn is_reserved(name: &str) -> bool {
    RESERVED.contains(&name)
        || joint_suffix(name, "q").is_some()
        || joint_suffix(name, "dir").is_some()
}

/// The digits after `prefix` if `name` is `prefix` followed by one or more ASCII digits.
fn joint_suffix<'a>(name: &'a str, prefix: &str) -> Option<&'a str> {
    let digits = name.strip_prefix(prefix)?;
    (!digits.is_empty() && digits.bytes().all(|b| b.is_ascii_digit())).then_some(digits)
}

/// Parses one trimmed cell, or says what is wrong with it.
type CellParser = fn(&str) -> std::result::Result<f64, String>;

/// A required finite number.
pub(crate) fn number(cell: &str) -> std::result::Result<f64, String> {
    if cell.is_empty() {
        return Err("missing value; fill in the cell or remove the row".into());
    }
    match cell.parse::<f64>() {
        Err(_) => Err(format!("expected a number, found '{cell}'")),
        Ok(v) if !v.is_finite() => Err(format!(
            "value is NaN/inf ('{cell}'); remove or fix the row"
        )),
        Ok(v) => Ok(v),
    }
}

/// A number within ±`limit`; `what` names it in the message, `hint` says what to check.
fn bounded(cell: &str, limit: f64, what: &str, hint: &str) -> std::result::Result<f64, String> {
    let v = number(cell)?;
    if v.abs() > limit {
        return Err(format!("{what} '{cell}' is beyond ±{limit:e}; {hint}"));
    }
    Ok(v)
}

/// A joint value: degrees, or mm for a prismatic joint.
fn joint_value(cell: &str) -> std::result::Result<f64, String> {
    bounded(
        cell,
        MAX_ABS_JOINT,
        "joint value",
        "joint values are degrees (mm for a prismatic joint)",
    )
}

/// A TCP error in mm.
fn error_value(cell: &str) -> std::result::Result<f64, String> {
    bounded(
        cell,
        MAX_ABS_ERROR_MM,
        "TCP error",
        "that cannot be a TCP error in mm: check the units and the column",
    )
}

/// A measured TCP coordinate in mm.
pub(crate) fn position_value(cell: &str) -> std::result::Result<f64, String> {
    bounded(
        cell,
        MAX_ABS_POSITION_MM,
        "TCP coordinate",
        "coordinates are mm in the robot's frame",
    )
}

/// A direction coefficient: exactly +1 or -1.
fn direction(cell: &str) -> std::result::Result<f64, String> {
    if cell.is_empty() {
        return Err("missing value; direction must be +1 or -1".into());
    }
    match cell.parse::<f64>() {
        Ok(v) if v == 1.0 || v == -1.0 => Ok(v),
        _ => Err(format!("direction must be +1 or -1, found {cell}")),
    }
}

/// Values and missing count if every non-empty cell is a finite number
/// within ±[`MAX_ABS_COVARIATE`]; otherwise the index of the first cell
/// that is not and what is wrong with it.
fn numeric_column(cells: &[String]) -> std::result::Result<(Vec<f64>, usize), (usize, String)> {
    let mut missing = 0;
    let mut values = Vec::with_capacity(cells.len());
    for (i, cell) in cells.iter().enumerate() {
        if cell.is_empty() {
            missing += 1;
            values.push(f64::NAN);
            continue;
        }
        match cell.parse::<f64>() {
            Ok(v) if v.abs() <= MAX_ABS_COVARIATE => values.push(v),
            Ok(v) if v.is_nan() => return Err((i, format!("'{cell}' is not a number"))),
            Ok(_) => {
                return Err((
                    i,
                    format!("'{cell}' is infinite or beyond ±{MAX_ABS_COVARIATE:e}"),
                ));
            }
            Err(_) => return Err((i, format!("'{cell}' is not a number"))),
        }
    }
    Ok((values, missing))
}
