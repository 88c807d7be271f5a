//! Reading a tracker's or controller's own export: any delimiter, a decimal
//! comma, radians or degrees, metres or millimetres, and its own column names.
//!
//! An [`ImportSpec`] maps the export's columns onto the measurement format
//! (see the [module docs](super)): `q1..qN` (required), `dir1..dirN`,
//! `ex,ey,ez`, `x,y,z`, `id`, and any other target name as a covariate
//! (`temp_c = "measurement_temperature"`). Columns of the export that no
//! target names are listed in [`Imported::ignored`], never dropped unsaid.
//! Every cell a target reads must be a number; an empty covariate cell is
//! missing (NaN). Directions absent from the export are derived from the row
//! order ([`super::derive_directions`]).

use super::{Covariate, Dataset, DirSource, SourceLines, derive_directions};
use crate::{Error, Result};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::Path;

/// Unit of the export's joint angles.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum AngleUnit {
    /// Degrees (the format's unit).
    #[default]
    #[cfg_attr(feature = "cli", value(help = None::<&str>))]
    Deg,
    /// Radians.
    #[cfg_attr(feature = "cli", value(help = None::<&str>))]
    Rad,
}

/// Unit of the export's lengths (positions, errors, prismatic joints).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default, Serialize, Deserialize)]
#[serde(rename_all = "lowercase")]
#[cfg_attr(feature = "cli", derive(clap::ValueEnum))]
pub enum LengthUnit {
    /// Millimetres (the format's unit).
    #[default]
    #[cfg_attr(feature = "cli", value(help = None::<&str>))]
    Mm,
    /// Metres.
    #[cfg_attr(feature = "cli", value(help = None::<&str>))]
    M,
}

impl LengthUnit {
    fn to_mm(self) -> f64 {
        match self {
            LengthUnit::Mm => 1.0,
            LengthUnit::M => 1000.0,
        }
    }
}

/// How to read an export: a mapping file (TOML) or command-line options.
///
/// ```toml
/// delimiter = ";"          # default: sniffed from the header (; tab ,)
/// decimal = ","            # default: "," when the delimiter is not a comma and cells use it
/// angles = "rad"           # deg (default) or rad
/// lengths = "mm"           # mm (default) or m
/// [columns]                # target = export column
/// q1 = "shoulder_pan_joint"
/// x = "measurement_x"
/// temp_c = "measurement_temperature"
/// ```
#[derive(Debug, Clone, PartialEq, Default, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ImportSpec {
    /// Field separator (one character); `None`: sniffed from the header.
    #[serde(default)]
    pub delimiter: Option<char>,
    /// Decimal separator, `.` or `,`; `None`: `,` when the delimiter is not a
    /// comma and a mapped cell contains one.
    #[serde(default)]
    pub decimal: Option<char>,
    /// Unit of revolute joint values.
    #[serde(default)]
    pub angles: AngleUnit,
    /// Unit of lengths.
    #[serde(default)]
    pub lengths: LengthUnit,
    /// Target column name → export column name.
    #[serde(default)]
    pub columns: BTreeMap<String, String>,
}

/// What [`import`] read.
#[derive(Debug, Clone)]
pub struct Imported {
    /// The campaign in the measurement format.
    pub data: Dataset,
    /// The delimiter and decimal separator used.
    pub delimiter: char,
    /// The decimal separator used.
    pub decimal: char,
    /// Export columns no target names, in file order.
    pub ignored: Vec<String>,
}

impl ImportSpec {
    /// Read a mapping file (TOML).
    pub fn from_file(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        toml::from_str(&text).map_err(|e| Error::Input {
            source_name: path.display().to_string(),
            message: format!("not an import mapping: {}", e.message()),
        })
    }

    /// The spec of the mapping file `file` ([`ImportSpec::from_file`]; the
    /// default without one) with the pairs of `maps` on top
    /// ([`ImportSpec::map_all`]).
    pub fn read(file: Option<&Path>, maps: &[String]) -> Result<Self> {
        let mut spec = match file {
            Some(p) => Self::from_file(p)?,
            None => Self::default(),
        };
        spec.map_all(maps)?;
        Ok(spec)
    }

    /// The spec with the settings given beside the mapping file (the
    /// command line's `--delimiter`, `--decimal`, `--angles`, `--lengths`):
    /// each one given replaces the file's.
    pub fn overridden(
        self,
        delimiter: Option<char>,
        decimal: Option<char>,
        angles: Option<AngleUnit>,
        lengths: Option<LengthUnit>,
    ) -> Self {
        ImportSpec {
            delimiter: delimiter.or(self.delimiter),
            decimal: decimal.or(self.decimal),
            angles: angles.unwrap_or(self.angles),
            lengths: lengths.unwrap_or(self.lengths),
            ..self
        }
    }

    /// [`ImportSpec::map`] of each list in order: a target named twice
    /// among them all is refused.
    pub fn map_all(&mut self, lists: &[String]) -> Result<()> {
        let mut given = Vec::new();
        lists.iter().try_for_each(|m| self.map(m, &mut given))
    }

    /// Add `target=column` pairs (comma-separated), overriding the same
    /// targets of a mapping file. Error if one call's pairs, or
    /// `already` (targets set by earlier calls), name a target twice.
    pub fn map(&mut self, pairs: &str, already: &mut Vec<String>) -> Result<()> {
        for pair in pairs.split(',').filter(|p| !p.trim().is_empty()) {
            let Some((t, c)) = pair.split_once('=') else {
                return Err(Error::InvalidParameter(format!(
                    "--map '{pair}': expected target=column, e.g. q1=shoulder_pan_joint"
                )));
            };
            let t = t.trim().to_string();
            if already.contains(&t) {
                return Err(Error::InvalidParameter(format!(
                    "--map: target {t} is given twice ({} and {})",
                    self.columns[&t],
                    c.trim()
                )));
            }
            already.push(t.clone());
            self.columns.insert(t, c.trim().into());
        }
        Ok(())
    }
}

/// Column names with a fixed meaning in the measurement format.
fn fixed_target(name: &str) -> bool {
    ["ex", "ey", "ez", "x", "y", "z", "id"].contains(&name) || numbered(name).is_some()
}

/// `("q", 3)` for `q3`, `("dir", 2)` for `dir2`.
fn numbered(name: &str) -> Option<(&str, usize)> {
    for prefix in ["dir", "q"] {
        if let Some(rest) = name.strip_prefix(prefix)
            && !rest.starts_with('0')
            && let Ok(k) = rest.parse::<usize>()
        {
            return Some((prefix, k));
        }
    }
    None
}

/// Sniff the delimiter from the header line: the most frequent of `;`, tab, `,`.
fn sniff(header: &str) -> char {
    [';', '\t', ',']
        .into_iter()
        .max_by_key(|c| header.matches(*c).count())
        .unwrap_or(',')
}

/// Read the export at `path` with `spec`. `prismatic[j]` marks joint j + 1 as
/// prismatic (its values are lengths); empty: every joint is revolute.
pub fn import(path: &Path, spec: &ImportSpec, prismatic: &[bool]) -> Result<Imported> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    import_text(&text, &path.display().to_string(), spec, prismatic)
}

/// [`import`] from text (`source` names it in messages).
pub fn import_text(
    text: &str,
    source: &str,
    spec: &ImportSpec,
    prismatic: &[bool],
) -> Result<Imported> {
    let text = text.strip_prefix('\u{feff}').unwrap_or(text);
    let header_line = text.lines().next().unwrap_or("");
    let delimiter = spec.delimiter.unwrap_or_else(|| sniff(header_line));
    if !delimiter.is_ascii() || delimiter == '"' {
        return Err(Error::InvalidParameter(format!(
            "delimiter '{delimiter}': expected one ASCII character"
        )));
    }
    let mut rdr = csv::ReaderBuilder::new()
        .delimiter(delimiter as u8)
        .has_headers(true)
        .from_reader(text.as_bytes());
    let header: Vec<String> = rdr
        .headers()
        .map_err(|e| bad(source, format!("header: {e}")))?
        .iter()
        .map(|h| h.trim().to_string())
        .collect();
    let plan = ColumnPlan::new(spec, &header, prismatic, source)?;
    let records: Vec<(u64, csv::StringRecord)> = rdr
        .records()
        .enumerate()
        .map(|(i, r)| {
            r.map(|r| (i as u64 + 2, r))
                .map_err(|e| bad(source, format!("line {}: {e}", i + 2)))
        })
        .collect::<Result<_>>()?;
    if records.is_empty() {
        return Err(bad(source, "no data rows after the header".into()));
    }
    let mapped: Vec<usize> = plan.index.values().copied().collect();
    let decimal = decimal_separator(spec, delimiter, &records, &mapped)?;
    let cells = Cells {
        source,
        header: &header,
        decimal,
    };
    let data = read_rows(&records, &plan, &cells, spec, prismatic)?.into_dataset(source, &plan);
    data.validate()?;
    let ignored = header
        .iter()
        .enumerate()
        .filter(|(k, _)| !mapped.contains(k))
        .map(|(_, h)| h.clone())
        .collect();
    Ok(Imported {
        data,
        delimiter,
        decimal,
        ignored,
    })
}

/// An input error in `source`.
fn bad(source: &str, message: String) -> Error {
    Error::Input {
        source_name: source.into(),
        message,
    }
}

/// Which export column each target reads, checked: every mapped column
/// exists, joints are `q1..qN` without gaps (with a `dir` for each or none),
/// errors and positions are whole triples.
struct ColumnPlan<'a> {
    /// Target → export column index.
    index: BTreeMap<&'a str, usize>,
    /// Joints N.
    n: usize,
    /// Columns of `ex, ey, ez`, if mapped.
    err_cols: Option<[usize; 3]>,
    /// Columns of `x, y, z`, if mapped.
    pos_cols: Option<[usize; 3]>,
    /// Columns of `dir1..dirN`, or none.
    dir_cols: Vec<usize>,
    /// Covariates: every other target, by name.
    covariates: Vec<(&'a str, usize)>,
}

impl<'a> ColumnPlan<'a> {
    fn new(
        spec: &'a ImportSpec,
        header: &[String],
        prismatic: &[bool],
        source: &str,
    ) -> Result<Self> {
        let index = column_index(spec, header, source)?;
        let n = joint_count(&index, source)?;
        if !prismatic.is_empty() && prismatic.len() != n {
            return Err(Error::JointCount {
                expected: prismatic.len(),
                got: n,
            });
        }
        let triple = |names: [&str; 3]| -> Result<Option<[usize; 3]>> {
            let found: Vec<usize> = names.iter().filter_map(|t| index.get(t).copied()).collect();
            match found.len() {
                0 => Ok(None),
                3 => Ok(Some([found[0], found[1], found[2]])),
                _ => Err(bad(
                    source,
                    format!("map all of {} or none", names.join(", ")),
                )),
            }
        };
        let err_cols = triple(["ex", "ey", "ez"])?;
        let pos_cols = triple(["x", "y", "z"])?;
        let dir_cols: Vec<usize> = (1..=n)
            .filter_map(|k| index.get(format!("dir{k}").as_str()).copied())
            .collect();
        if !dir_cols.is_empty() && dir_cols.len() != n {
            return Err(bad(source, format!("map all of dir1..dir{n} or none")));
        }
        let covariates: Vec<(&str, usize)> = index
            .iter()
            .filter(|(t, _)| !fixed_target(t))
            .map(|(t, &k)| (*t, k))
            .collect();
        Ok(ColumnPlan {
            index,
            n,
            err_cols,
            pos_cols,
            dir_cols,
            covariates,
        })
    }
}

/// Target → index of its export column in `header`.
fn column_index<'a>(
    spec: &'a ImportSpec,
    header: &[String],
    source: &str,
) -> Result<BTreeMap<&'a str, usize>> {
    if spec.columns.is_empty() {
        return Err(Error::InvalidParameter(
            "no column map: give --map target=column,… or --map-file (q1..qN are required)".into(),
        ));
    }
    let mut index: BTreeMap<&str, usize> = BTreeMap::new();
    for (target, column) in &spec.columns {
        let Some(k) = header.iter().position(|h| h == column) else {
            return Err(bad(
                source,
                format!(
                    "no column '{column}' (for {target}); found: {}",
                    header.join(", ")
                ),
            ));
        };
        index.insert(target, k);
    }
    Ok(index)
}

/// N of the mapped `q1..qN`; an error for a gap or a `qK`/`dirK` beyond N.
fn joint_count(index: &BTreeMap<&str, usize>, source: &str) -> Result<usize> {
    let n = (1..)
        .take_while(|k| index.contains_key(format!("q{k}").as_str()))
        .count();
    for t in index.keys() {
        if let Some((prefix, k)) = numbered(t)
            && (k == 0 || k > n)
        {
            return Err(bad(
                source,
                format!(
                    "target {t}: joints must be q1..qN without gaps (found q1..q{n}){}",
                    if prefix == "dir" {
                        ", with a dir for each"
                    } else {
                        ""
                    }
                ),
            ));
        }
    }
    if n == 0 {
        return Err(bad(source, "the column map has no q1 (joint 1)".into()));
    }
    Ok(n)
}

/// The decimal separator: the spec's, else `,` when the delimiter is not a
/// comma and a mapped cell of the first 20 rows holds one, else `.`.
fn decimal_separator(
    spec: &ImportSpec,
    delimiter: char,
    records: &[(u64, csv::StringRecord)],
    mapped: &[usize],
) -> Result<char> {
    let decimal = spec.decimal.unwrap_or_else(|| {
        let comma = delimiter != ','
            && records.iter().take(20).any(|(_, r)| {
                mapped
                    .iter()
                    .any(|&k| r.get(k).is_some_and(|c| c.contains(',')))
            });
        if comma { ',' } else { '.' }
    });
    if decimal == ',' && delimiter == ',' {
        return Err(Error::InvalidParameter(
            "a decimal comma needs another delimiter than ',' (give --delimiter ';' or tab)".into(),
        ));
    }
    if decimal != '.' && decimal != ',' {
        return Err(Error::InvalidParameter(format!(
            "decimal separator '{decimal}': expected . or ,"
        )));
    }
    Ok(decimal)
}

/// Reads the export's cells as numbers.
struct Cells<'a> {
    source: &'a str,
    header: &'a [String],
    decimal: char,
}

impl Cells<'_> {
    /// Cell `k` of record `r` (file line `line`) as a finite number; an
    /// empty cell is NaN when `missing_ok`.
    fn number(&self, line: u64, r: &csv::StringRecord, k: usize, missing_ok: bool) -> Result<f64> {
        let raw = r.get(k).unwrap_or("").trim();
        if raw.is_empty() && missing_ok {
            return Ok(f64::NAN);
        }
        let s = if self.decimal == ',' {
            raw.replace(',', ".")
        } else {
            raw.to_string()
        };
        match s.parse::<f64>() {
            Ok(v) if v.is_finite() => Ok(v),
            _ => Err(bad(
                self.source,
                format!(
                    "line {line}, column '{}': '{raw}' is not a finite number (decimal separator '{}')",
                    self.header[k], self.decimal
                ),
            )),
        }
    }

    /// Cell `k` as a direction: +1 or −1.
    fn direction(&self, line: u64, r: &csv::StringRecord, k: usize) -> Result<f64> {
        let v = self.number(line, r, k, false)?;
        if v == 1.0 || v == -1.0 {
            Ok(v)
        } else {
            Err(bad(
                self.source,
                format!(
                    "line {line}, column '{}': a direction is +1 or -1, not {v}",
                    self.header[k]
                ),
            ))
        }
    }
}

/// The columns read from the records, in the format's units (degrees, mm).
#[derive(Default)]
struct Rows {
    q: Vec<Vec<f64>>,
    dir: Vec<Vec<f64>>,
    errors: Vec<[f64; 3]>,
    positions: Vec<[f64; 3]>,
    cov: Vec<Vec<f64>>,
    ids: Vec<String>,
    lines: Vec<u64>,
}

/// Every record through the plan: joints (radians → degrees, prismatic
/// joints and all lengths × 1000 from metres), directions, errors,
/// positions, covariates, ids.
fn read_rows(
    records: &[(u64, csv::StringRecord)],
    plan: &ColumnPlan<'_>,
    cells: &Cells<'_>,
    spec: &ImportSpec,
    prismatic: &[bool],
) -> Result<Rows> {
    let mm = spec.lengths.to_mm();
    let joint_value = |j: usize, raw: f64| {
        if prismatic.get(j).copied().unwrap_or(false) {
            raw * mm
        } else if spec.angles == AngleUnit::Rad {
            raw.to_degrees()
        } else {
            raw
        }
    };
    let mut rows = Rows {
        cov: vec![Vec::with_capacity(records.len()); plan.covariates.len()],
        ..Rows::default()
    };
    for (line, r) in records {
        let mut qi = Vec::with_capacity(plan.n);
        for j in 0..plan.n {
            let raw = cells.number(*line, r, plan.index[format!("q{}", j + 1).as_str()], false)?;
            qi.push(joint_value(j, raw));
        }
        rows.q.push(qi);
        if !plan.dir_cols.is_empty() {
            let d: Vec<f64> = plan
                .dir_cols
                .iter()
                .map(|&k| cells.direction(*line, r, k))
                .collect::<Result<_>>()?;
            rows.dir.push(d);
        }
        for (cols, out) in [
            (&plan.err_cols, &mut rows.errors),
            (&plan.pos_cols, &mut rows.positions),
        ] {
            if let Some(c) = cols {
                let mut v = [0.0; 3];
                for a in 0..3 {
                    v[a] = cells.number(*line, r, c[a], false)? * mm;
                }
                out.push(v);
            }
        }
        for (c, (_, k)) in rows.cov.iter_mut().zip(&plan.covariates) {
            c.push(cells.number(*line, r, *k, true)?);
        }
        if let Some(&k) = plan.index.get("id") {
            rows.ids.push(r.get(k).unwrap_or("").trim().to_string());
        }
        rows.lines.push(*line);
    }
    Ok(rows)
}

impl Rows {
    /// The campaign (directions derived from the row order when the export
    /// has none), not yet validated.
    fn into_dataset(self, source: &str, plan: &ColumnPlan<'_>) -> Dataset {
        let (dir, dir_source) = if plan.dir_cols.is_empty() {
            (derive_directions(&self.q, None), DirSource::Derived)
        } else {
            (self.dir, DirSource::Given)
        };
        Dataset {
            source: source.into(),
            q: self.q,
            dir,
            dir_source,
            errors: plan.err_cols.map(|_| self.errors),
            positions: plan.pos_cols.map(|_| self.positions),
            ids: plan.index.contains_key("id").then_some(self.ids),
            covariates: plan
                .covariates
                .iter()
                .zip(self.cov)
                .map(|((name, _), values)| Covariate {
                    name: name.to_string(),
                    missing: values.iter().filter(|v| v.is_nan()).count(),
                    values,
                })
                .collect(),
            text: Vec::new(),
            lines: SourceLines(self.lines),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(map: &str) -> ImportSpec {
        let mut s = ImportSpec {
            angles: AngleUnit::Rad,
            lengths: LengthUnit::M,
            ..ImportSpec::default()
        };
        s.map(map, &mut Vec::new()).unwrap();
        s
    }

    #[test]
    fn semicolons_decimal_commas_radians_and_metres() {
        let text = "t;a;b;px;py;pz;temp\n1;0,5;-1;1;2;3;21,5\n2;0,25;-1;1,5;2;3;\n";
        let got = import_text(
            text,
            "e.csv",
            &spec("q1=a,q2=b,x=px,y=py,z=pz,temp_c=temp"),
            &[],
        )
        .unwrap();
        assert_eq!((got.delimiter, got.decimal), (';', ','));
        assert_eq!(got.ignored, vec!["t".to_string()]);
        let d = got.data;
        assert!((d.q[0][0] - 0.5f64.to_degrees()).abs() < 1e-12);
        assert_eq!(d.positions.as_ref().unwrap()[1], [1500.0, 2000.0, 3000.0]);
        assert_eq!(d.dir[1], vec![-1.0, 1.0]);
        assert_eq!(d.dir_source, DirSource::Derived);
        assert_eq!(d.covariates[0].name, "temp_c");
        assert_eq!(d.covariates[0].missing, 1);
    }

    #[test]
    fn a_bad_cell_names_its_line_and_column_and_a_missing_column_lists_the_header() {
        let text = "a;b\n1;2\n1;x\n";
        let e = import_text(text, "e.csv", &spec("q1=a,q2=b"), &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("line 3") && e.contains("column 'b'"), "{e}");
        let e = import_text(text, "e.csv", &spec("q1=a,q2=c"), &[])
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("no column 'c'") && e.contains("found: a, b"),
            "{e}"
        );
        let e = import_text(text, "e.csv", &spec("q1=a,q3=b"), &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("without gaps"), "{e}");
        let e = import_text(text, "e.csv", &spec("q1=a,ex=b"), &[])
            .unwrap_err()
            .to_string();
        assert!(e.contains("ex, ey, ez"), "{e}");
    }
}
