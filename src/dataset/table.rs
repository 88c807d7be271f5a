//! The one CSV table reader behind every CSV input (measurements,
//! trajectories): the same rules everywhere.
//!
//! - A UTF-8 byte-order mark is accepted; other text must be UTF-8.
//! - Cells are trimmed of surrounding whitespace.
//! - Lines holding nothing but whitespace are skipped, wherever they are.
//! - Line numbers count every line break (`\n`, `\r\n` or a lone `\r`);
//!   the header is line 1 unless the file starts with blank lines.
//! - Header names are non-empty and unique: a trailing comma is an error.
//! - Every row has as many cells as the header.

use crate::{Error, Result};

/// The UTF-8 byte-order mark some spreadsheet programs put at the start.
const BOM: &[u8] = b"\xEF\xBB\xBF";

/// A CSV file's header and rows, each row with the line it starts on.
pub(crate) struct Table {
    /// Column names, trimmed.
    pub header: Vec<String>,
    /// Line of the header.
    pub header_line: u64,
    /// Data rows and their lines, blank lines left out.
    pub rows: Vec<(u64, csv::StringRecord)>,
}

impl Table {
    /// Read `bytes` (a whole file); `src` names it in messages, and
    /// `empty_hint` says what the header must hold when the file is empty.
    pub fn read(bytes: &[u8], src: &str, empty_hint: &str) -> Result<Table> {
        let body = bytes.strip_prefix(BOM).unwrap_or(bytes);
        let mut rdr = csv::ReaderBuilder::new()
            .has_headers(false)
            .flexible(true)
            .trim(csv::Trim::All)
            .from_reader(body);
        let mut lines = LineCounter {
            body,
            offset: 0,
            line: 1,
        };
        let mut records = rdr.records();
        let lib_err = |e: csv::Error, lines: &mut LineCounter| match e.kind() {
            csv::ErrorKind::Utf8 { pos: Some(pos), .. } => Error::Csv {
                file: src.to_string(),
                line: lines.line_at(pos.byte()),
                column: None,
                message: "text is not valid UTF-8; save the file as UTF-8".into(),
            },
            _ => Error::Input {
                source_name: src.to_string(),
                message: format!("cannot parse as CSV: {e}"),
            },
        };
        let header = loop {
            match records.next() {
                None => {
                    return Err(Error::Input {
                        source_name: src.to_string(),
                        message: format!(
                            "file is empty; the first line must be a header {empty_hint}"
                        ),
                    });
                }
                Some(rec) => {
                    let rec = rec.map_err(|e| lib_err(e, &mut lines))?;
                    if !is_blank(&rec) {
                        break rec;
                    }
                }
            }
        };
        let header_line = lines.line_of(&header);
        let names: Vec<String> = header.iter().map(str::to_string).collect();
        check_names(&names, src, header_line)?;
        let mut rows = Vec::new();
        for rec in records {
            let rec = rec.map_err(|e| lib_err(e, &mut lines))?;
            if is_blank(&rec) {
                continue;
            }
            let line = lines.line_of(&rec);
            if rec.len() != names.len() {
                return Err(Error::Csv {
                    file: src.to_string(),
                    line,
                    column: None,
                    message: format!(
                        "row has {} cells but the header has {}; fix the missing or extra commas",
                        rec.len(),
                        names.len()
                    ),
                });
            }
            rows.push((line, rec));
        }
        Ok(Table {
            header: names,
            header_line,
            rows,
        })
    }

    /// Index of the column called `name`.
    pub fn column(&self, name: &str) -> Option<usize> {
        self.header.iter().position(|h| h == name)
    }
}

/// Column indices of a triplet such as `ex,ey,ez` in `names`: all three or
/// none; otherwise what is found and what is missing (the message).
pub(crate) fn triplet(
    names: &[String],
    want: [&str; 3],
) -> std::result::Result<Option<[usize; 3]>, String> {
    let found = want.map(|w| names.iter().position(|n| n == w));
    match found {
        [Some(a), Some(b), Some(c)] => Ok(Some([a, b, c])),
        [None, None, None] => Ok(None),
        _ => {
            let pick = |present: bool| -> Vec<&str> {
                (0..3)
                    .filter(|&i| found[i].is_some() == present)
                    .map(|i| want[i])
                    .collect()
            };
            Err(format!(
                "found {} but not {}; give all of {} or none",
                pick(true).join(","),
                pick(false).join(","),
                want.join(",")
            ))
        }
    }
}

/// No empty and no duplicate column names.
fn check_names(names: &[String], src: &str, line: u64) -> Result<()> {
    let err = |column: Option<&str>, message: String| Error::Csv {
        file: src.to_string(),
        line,
        column: column.map(str::to_string),
        message,
    };
    for (i, name) in names.iter().enumerate() {
        if name.is_empty() {
            return Err(err(
                None,
                format!(
                    "header cell {} is empty; name the column or remove the stray comma",
                    i + 1
                ),
            ));
        }
        if names[..i].contains(name) {
            return Err(err(
                Some(name),
                "column name appears twice in the header; rename or remove one".into(),
            ));
        }
    }
    Ok(())
}

/// Finds the 1-based line a record starts on.
///
/// The `csv` crate's own line numbers go wrong after skipped blank lines and
/// with CRLF or CR-only endings, so lines are counted here from the
/// records' byte offsets.
struct LineCounter<'a> {
    body: &'a [u8],
    offset: usize,
    line: u64,
}

impl LineCounter<'_> {
    /// Line of `rec`; records must be passed in file order.
    fn line_of(&mut self, rec: &csv::StringRecord) -> u64 {
        self.line_at(rec.position().map_or(0, csv::Position::byte))
    }

    /// Line of the record the `csv` crate says starts at `byte` (it may
    /// point at line breaks before the record).
    fn line_at(&mut self, byte: u64) -> u64 {
        let mut start = usize::try_from(byte).map_or(self.body.len(), |b| b.min(self.body.len()));
        start = start.max(self.offset);
        while self
            .body
            .get(start)
            .is_some_and(|b| matches!(b, b'\r' | b'\n'))
        {
            start += 1;
        }
        let skipped = &self.body[self.offset..start];
        let breaks = skipped
            .iter()
            .enumerate()
            .filter(|&(i, &b)| b == b'\n' || (b == b'\r' && skipped.get(i + 1) != Some(&b'\n')));
        self.line += breaks.count() as u64;
        self.offset = start;
        self.line
    }
}

/// A line holding nothing but whitespace (the csv crate already skips empty lines).
fn is_blank(rec: &csv::StringRecord) -> bool {
    rec.len() == 1 && rec.get(0).is_some_and(str::is_empty)
}
