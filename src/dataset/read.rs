//! Reading the measurement CSV (format: see the [module docs](super)).

use std::collections::BTreeMap;
use std::io::Read;
use std::path::Path;

use super::table::Table;
use super::{
    CellParser, Covariate, Dataset, DirSource, SourceLines, TextColumn, direction, error_value,
    is_reserved, joint_suffix, joint_value, numeric_column, position_value,
};
use crate::space::derive_directions;
use crate::{Error, Result};

/// Read a measurement CSV file. Messages name the file by `path` as given.
pub fn read_csv(path: &Path) -> Result<Dataset> {
    let bytes = std::fs::read(path).map_err(|e| Error::io(path, e))?;
    read_csv_from(bytes.as_slice(), &path.display().to_string())
}

/// Read a measurement CSV from any reader; `source_name` is used in messages
/// and stored as [`Dataset::source`].
pub fn read_csv_from(mut reader: impl Read, source_name: &str) -> Result<Dataset> {
    let mut bytes = Vec::new();
    reader.read_to_end(&mut bytes).map_err(|e| Error::Input {
        source_name: source_name.to_string(),
        message: format!("reading failed: {e}"),
    })?;
    let table = Table::read(&bytes, source_name, "with q1..qN")?;
    from_table(&table, source_name)
}

/// The dataset of an already read [`Table`] (`source_name` for messages).
pub(crate) fn from_table(table: &Table, source_name: &str) -> Result<Dataset> {
    let parser = Parser {
        src: source_name.to_string(),
        ..Parser::default()
    };
    parser.parse(table)
}

/// Which cells of a row hold what, worked out from the header.
struct Layout {
    names: Vec<String>,
    q: Vec<usize>,
    dir: Option<Vec<usize>>,
    errors: Option<[usize; 3]>,
    positions: Option<[usize; 3]>,
    id: Option<usize>,
    other: Vec<usize>,
}

/// Parsing state: the source name for messages and the columns collected so far.
#[derive(Default)]
struct Parser {
    src: String,
    /// Line of the header: 1 unless the file starts with blank lines.
    header_line: u64,
    q: Vec<Vec<f64>>,
    dir: Vec<Vec<f64>>,
    errors: Vec<[f64; 3]>,
    positions: Vec<[f64; 3]>,
    ids: Vec<String>,
    other: Vec<Vec<String>>,
    lines: Vec<u64>,
}

impl Parser {
    /// Parse the whole file ([`Table`] rules).
    fn parse(mut self, table: &Table) -> Result<Dataset> {
        self.header_line = table.header_line;
        let layout = self.layout(&table.header)?;
        self.other = vec![Vec::new(); layout.other.len()];
        for (line, rec) in &table.rows {
            self.row(&layout, rec, *line)?;
        }
        if self.q.is_empty() {
            return Err(
                self.input_err("no data rows after the header; add one row per measured pose")
            );
        }
        Ok(self.finish(&layout))
    }

    // ----- header -------------------------------------------------------

    /// Classify the header's columns and check that the required ones are there.
    fn layout(&self, header: &[String]) -> Result<Layout> {
        let names = header.to_vec();
        let q_map = self.numbered(&names, "q")?;
        let q = self.joint_columns(&names, &q_map)?;
        let dir_map = self.numbered(&names, "dir")?;
        let dir = self.dir_columns(&names, &dir_map, q.len())?;
        let errors = self.triplet(&names, ["ex", "ey", "ez"])?;
        let positions = self.triplet(&names, ["x", "y", "z"])?;
        let id = names.iter().position(|n| n == "id");
        // Every reserved name present was claimed above; the rest are covariates.
        let other = (0..names.len())
            .filter(|&i| !is_reserved(&names[i]))
            .collect();
        Ok(Layout {
            names,
            q,
            dir,
            errors,
            positions,
            id,
            other,
        })
    }

    /// Map joint number → cell index for columns named `prefix` + digits.
    fn numbered(&self, names: &[String], prefix: &str) -> Result<BTreeMap<usize, usize>> {
        let mut map = BTreeMap::new();
        for (i, name) in names.iter().enumerate() {
            let Some(digits) = joint_suffix(name, prefix) else {
                continue;
            };
            match digits.parse::<usize>() {
                Ok(k) if k >= 1 && !digits.starts_with('0') => {
                    map.insert(k, i);
                }
                _ => {
                    let msg = format!(
                        "joint columns are numbered from 1 without leading zeros \
                         ({prefix}1, {prefix}2, …); rename this column"
                    );
                    return Err(self.header_err(Some(name), msg));
                }
            }
        }
        Ok(map)
    }

    /// Cell indices of q1..qN, which must be present without gaps.
    fn joint_columns(&self, names: &[String], map: &BTreeMap<usize, usize>) -> Result<Vec<usize>> {
        if !map.contains_key(&1) {
            return Err(self.input_err(format!(
                "no q1 column; the header needs joint columns q1..qN (found: {})",
                names.join(", ")
            )));
        }
        for (expected, (&k, &col)) in (1..).zip(map) {
            if k != expected {
                let msg = format!(
                    "joint columns must be q1..qN without gaps, but q{expected} is missing; \
                     add it or renumber"
                );
                return Err(self.header_err(Some(&names[col]), msg));
            }
        }
        Ok(map.values().copied().collect())
    }

    /// Cell indices of dir1..dirN: all present or none.
    fn dir_columns(
        &self,
        names: &[String],
        map: &BTreeMap<usize, usize>,
        n: usize,
    ) -> Result<Option<Vec<usize>>> {
        if map.is_empty() {
            return Ok(None);
        }
        if let Some((&k, &col)) = map.range(n + 1..).next() {
            let msg = format!("there is no joint column q{k} for this direction; remove it");
            return Err(self.header_err(Some(&names[col]), msg));
        }
        let missing: Vec<String> = (1..=n)
            .filter(|k| !map.contains_key(k))
            .map(|k| format!("dir{k}"))
            .collect();
        if !missing.is_empty() {
            let msg = format!(
                "missing direction column(s) {}; give dir1..dir{n} for all joints or none",
                missing.join(", ")
            );
            return Err(self.header_err(None, msg));
        }
        Ok(Some(map.values().copied().collect()))
    }

    /// Cell indices of a column triplet such as ex,ey,ez: all three or none.
    fn triplet(&self, names: &[String], want: [&str; 3]) -> Result<Option<[usize; 3]>> {
        super::table::triplet(names, want).map_err(|msg| self.header_err(None, msg))
    }

    // ----- rows ---------------------------------------------------------

    /// Parse one data row into the collected columns.
    fn row(&mut self, l: &Layout, rec: &csv::StringRecord, line: u64) -> Result<()> {
        let cell = |i: usize| rec.get(i).unwrap_or("");
        let get = |i: usize, parse: CellParser| {
            parse(cell(i)).map_err(|m| self.cell_err(line, Some(&l.names[i]), m))
        };
        let xyz = |cols: [usize; 3], parse: CellParser| -> Result<[f64; 3]> {
            let [a, b, c] = cols.map(|i| get(i, parse));
            Ok([a?, b?, c?])
        };
        let q: Vec<f64> =
            l.q.iter()
                .map(|&i| get(i, joint_value))
                .collect::<Result<_>>()?;
        let dir = l
            .dir
            .as_ref()
            .map(|cols| cols.iter().map(|&i| get(i, direction)).collect());
        let dir: Option<Vec<f64>> = dir.transpose()?;
        let errors = l.errors.map(|c| xyz(c, error_value)).transpose()?;
        let positions = l.positions.map(|c| xyz(c, position_value)).transpose()?;
        self.q.push(q);
        self.lines.push(line);
        self.dir.extend(dir);
        self.errors.extend(errors);
        self.positions.extend(positions);
        self.ids.extend(l.id.map(|i| cell(i).to_string()));
        for (store, &i) in self.other.iter_mut().zip(&l.other) {
            store.push(cell(i).to_string());
        }
        Ok(())
    }

    // ----- result -------------------------------------------------------

    /// Assemble the dataset once all rows are in.
    fn finish(self, l: &Layout) -> Dataset {
        let (dir, dir_source) = if l.dir.is_some() {
            (self.dir, DirSource::Given)
        } else {
            (derive_directions(&self.q, None), DirSource::Derived)
        };
        let mut covariates = Vec::new();
        let mut text = Vec::new();
        for (cells, &i) in self.other.into_iter().zip(&l.other) {
            let name = l.names[i].clone();
            match numeric_column(&cells) {
                Ok((values, missing)) => covariates.push(Covariate {
                    name,
                    values,
                    missing,
                }),
                Err((row, why)) => {
                    // a column with numbers in it was meant to be numeric
                    let numeric = cells
                        .iter()
                        .any(|c| c.parse::<f64>().is_ok_and(f64::is_finite));
                    let note = numeric.then(|| format!("line {}: {why}", self.lines[row]));
                    text.push(TextColumn {
                        name,
                        values: cells,
                        note,
                    });
                }
            }
        }
        Dataset {
            source: self.src,
            q: self.q,
            dir,
            dir_source,
            errors: l.errors.map(|_| self.errors),
            positions: l.positions.map(|_| self.positions),
            ids: l.id.map(|_| self.ids),
            covariates,
            text,
            lines: SourceLines(self.lines),
        }
    }

    // ----- errors -------------------------------------------------------

    fn input_err(&self, message: impl Into<String>) -> Error {
        Error::Input {
            source_name: self.src.clone(),
            message: message.into(),
        }
    }

    fn cell_err(&self, line: u64, column: Option<&str>, message: impl Into<String>) -> Error {
        Error::Csv {
            file: self.src.clone(),
            line,
            column: column.map(str::to_string),
            message: message.into(),
        }
    }

    fn header_err(&self, column: Option<&str>, message: impl Into<String>) -> Error {
        self.cell_err(self.header_line, column, message)
    }
}
