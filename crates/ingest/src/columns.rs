//! Numeric CSV files (a header row, then one row per sample) to typed columns
//! with polars, refusing anything malformed with the file, the 1-based line
//! (header = line 1) and the rule.
//!
//! The file is first indexed line by line (one `memchr` pass) so that the
//! header and blank lines are checked with exact line numbers and data row
//! `i` is known to be line `i + 2` (polars would read a blank line as a row
//! of nulls and cannot say which line a bad cell came from). polars then
//! parses every column with its final type (`Float64` or `Int64`) with
//! `ignore_errors`, so an unparsable or missing cell becomes a null whose row
//! points back at the raw text for the message. Cells per line are checked
//! before polars by one count of the file's commas; per-line counts are only
//! scanned when that count or polars reports a problem, to keep the common
//! path fast.

use crate::IngestError;
use polars::prelude::{CsvReadOptions, DataType, Field, Schema, SerReader};
use std::io::Cursor;
use std::path::Path;

/// How a column is parsed.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum ColType {
    /// Any finite decimal number (`1`, `0.25`, `-3e-2`).
    Float,
    /// An integer count written as an integer literal (`-12`, `0`, `1000`);
    /// `1.5`, `1.0` and `1e3` are refused (see the crate docs).
    Count,
}

/// One expected column.
#[derive(Debug, Clone, Copy)]
pub(crate) struct ColSpec {
    pub name: &'static str,
    pub ty: ColType,
}

/// The parsed values of one column.
#[derive(Debug, Clone, PartialEq)]
pub(crate) enum ColValues {
    Float(Vec<f64>),
    Count(Vec<i64>),
}

/// What the time column must satisfy besides being finite and strictly increasing.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(crate) enum TimeStart {
    /// The first sample is at exactly `time_s = 0` (campaign runs).
    Zero,
    /// Any finite start (foreign recordings).
    Any,
}

/// The name of the time column every numeric CSV has.
pub(crate) const TIME_COLUMN: &str = "time_s";

/// Line index of a CSV text: where each line starts and what it holds.
struct Lines<'a> {
    text: &'a str,
    /// Byte offset of the start of each line (line k + 1 starts at `starts[k]`).
    starts: Vec<usize>,
}

impl<'a> Lines<'a> {
    fn new(text: &'a str) -> Self {
        let mut starts = Vec::with_capacity(text.len() / 24 + 1);
        let mut pos = 0;
        // `split_inclusive` yields no empty piece after a final newline, so a
        // trailing `\n` does not count as a blank line.
        for piece in text.split_inclusive('\n') {
            starts.push(pos);
            pos += piece.len();
        }
        Lines { text, starts }
    }

    fn len(&self) -> usize {
        self.starts.len()
    }

    /// Content of the 0-based line `k`, without its `\n` or `\r\n`.
    fn get(&self, k: usize) -> &'a str {
        let end = self.starts.get(k + 1).copied().unwrap_or(self.text.len());
        let s = &self.text[self.starts[k]..end];
        let s = s.strip_suffix('\n').unwrap_or(s);
        s.strip_suffix('\r').unwrap_or(s)
    }

    /// The raw text of the cell of data row `row` in header position `col`.
    fn cell(&self, row: usize, col: usize) -> &'a str {
        self.get(row + 1).split(',').nth(col).unwrap_or("")
    }
}

/// Reads a numeric CSV whose columns are exactly `spec` (in any order) and
/// returns the values in `spec` order. One column must be [`TIME_COLUMN`].
///
/// Rules, checked in this order: UTF-8 text; a header row naming each column
/// of `spec` once and nothing else; at least one data row; no empty line;
/// then the earliest row with a wrong number of cells (too many, trailing
/// empty cells included, or too few; reported before any cell fault), then
/// the earliest row (leftmost column first) with a missing cell, text, or a
/// non-finite value;
/// then `time_s` starting at 0 (for [`TimeStart::Zero`]) and strictly increasing.
pub(crate) fn read_numeric_csv(
    path: &Path,
    spec: &[ColSpec],
    time_start: TimeStart,
) -> Result<Vec<ColValues>, IngestError> {
    let bytes = std::fs::read(path).map_err(|source| IngestError::Io {
        file: path.to_path_buf(),
        rule: "cannot read the CSV".into(),
        source,
    })?;
    let text = match std::str::from_utf8(&bytes) {
        Ok(t) => t,
        Err(e) => {
            let line = bytes[..e.valid_up_to()].iter().filter(|&&b| b == b'\n').count() + 1;
            return Err(IngestError::rule(path, Some(line), "the file is not UTF-8 text"));
        }
    };
    let lines = Lines::new(text);
    let header = check_structure(path, &lines, spec)?;
    // Every line has as many cells as the header: one count of the commas of
    // the whole text (a vectorised byte scan) against lines × (cells − 1);
    // only on a mismatch are lines counted one by one. polars would drop a
    // row's trailing empty cells (`0.2,70,`) without a word, a cell the
    // format does not describe.
    let commas = text.bytes().filter(|&b| b == b',').count();
    if commas != lines.len() * (header.len() - 1) {
        return Err(ragged_row(path, &lines, header.len()).unwrap_or_else(|| IngestError::Csv {
            file: path.to_path_buf(),
            message: "the comma count disagrees with the cells per line".into(),
        }));
    }

    // Map header position -> spec entry, then give polars the schema in file order.
    let schema = Schema::from_iter(header.iter().map(|&k| {
        let dtype = match spec[k].ty {
            ColType::Float => DataType::Float64,
            ColType::Count => DataType::Int64,
        };
        Field::new(spec[k].name.into(), dtype)
    }));
    let n_rows = lines.len() - 1;
    let df = CsvReadOptions::default()
        .with_has_header(true)
        .with_schema(Some(schema.into()))
        .with_ignore_errors(true)
        .with_rechunk(true)
        .map_parse_options(|p| p.with_quote_char(None).with_missing_is_null(true))
        .into_reader_with_file_handle(Cursor::new(bytes.as_slice()))
        .finish()
        .map_err(|e| {
            // polars refuses a row with too many cells without saying where (its
            // extra cells balanced by a short row elsewhere): find the line.
            ragged_row(path, &lines, header.len())
                .unwrap_or_else(|| IngestError::Csv { file: path.to_path_buf(), message: e.to_string() })
        })?;
    if df.height() != n_rows {
        return Err(IngestError::Csv {
            file: path.to_path_buf(),
            message: format!("polars read {} rows but the file has {n_rows} data lines", df.height()),
        });
    }

    // Extract every column (in file order) and find the earliest bad cell.
    let mut by_file_pos: Vec<ColValues> = Vec::with_capacity(header.len());
    let mut first_bad: Option<(usize, usize, CellFault)> = None;
    for (pos, &k) in header.iter().enumerate() {
        let csv_err =
            |e: polars::error::PolarsError| IngestError::Csv { file: path.to_path_buf(), message: e.to_string() };
        let series = df.column(spec[k].name).map_err(csv_err)?.as_materialized_series();
        let (values, bad) = match spec[k].ty {
            ColType::Float => {
                let ca = series.f64().map_err(csv_err)?;
                match ca.cont_slice() {
                    Ok(s) => (
                        ColValues::Float(s.to_vec()),
                        s.iter().position(|x| !x.is_finite()).map(|r| (r, CellFault::NonFinite)),
                    ),
                    Err(_) => {
                        // Some cell did not parse: the earliest fault is a null or a non-finite value.
                        let bad = ca.iter().position(|v| !v.is_some_and(f64::is_finite));
                        let fault =
                            |r: usize| if ca.get(r).is_none() { CellFault::Unparsable } else { CellFault::NonFinite };
                        (ColValues::Float(Vec::new()), bad.map(|r| (r, fault(r))))
                    }
                }
            }
            ColType::Count => {
                let ca = series.i64().map_err(csv_err)?;
                match ca.cont_slice() {
                    Ok(s) => (ColValues::Count(s.to_vec()), None),
                    Err(_) => (
                        ColValues::Count(Vec::new()),
                        ca.iter().position(|v| v.is_none()).map(|r| (r, CellFault::Unparsable)),
                    ),
                }
            }
        };
        // Each column reports its earliest fault, so the minimum over columns
        // (ties to the leftmost) is the earliest fault of the file.
        if let Some((row, fault)) = bad
            && first_bad.is_none_or(|(r, _, _)| row < r)
        {
            first_bad = Some((row, pos, fault));
        }
        by_file_pos.push(values);
    }
    if let Some((row, pos, fault)) = first_bad {
        // A row with too few cells reads as nulls in its last columns; with the
        // comma count right, an earlier row may hold its missing cells.
        if let Some(e) = (1..=row + 1).find_map(|k| ragged_line(path, &lines, k, header.len())) {
            return Err(e);
        }
        let col = spec[header[pos]];
        let raw = lines.cell(row, pos);
        return Err(IngestError::rule(path, Some(row + 2), cell_message(col, raw, fault)));
    }

    // Back to spec order.
    let mut out: Vec<Option<ColValues>> = vec![None; spec.len()];
    for (pos, values) in by_file_pos.into_iter().enumerate() {
        out[header[pos]] = Some(values);
    }
    let out: Vec<ColValues> = out.into_iter().map(|v| v.expect("every spec column is in the header")).collect();

    let time_k = spec.iter().position(|c| c.name == TIME_COLUMN).expect("spec has a time column");
    let time_pos = header.iter().position(|&k| k == time_k).expect("time column in header");
    if let ColValues::Float(t) = &out[time_k] {
        check_time(path, &lines, time_pos, t, time_start)?;
    }
    Ok(out)
}

/// Why a cell was refused.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
enum CellFault {
    Unparsable,
    NonFinite,
}

fn cell_message(col: ColSpec, raw: &str, fault: CellFault) -> String {
    let name = col.name;
    match fault {
        CellFault::NonFinite => format!("non-finite value '{raw}' in column {name} (values must be finite)"),
        CellFault::Unparsable if raw.is_empty() => format!("missing value in column {name}"),
        CellFault::Unparsable if col.ty == ColType::Count && raw.trim().parse::<f64>().is_ok() => {
            format!("{name} must be an integer count (encoder columns are integers), found '{raw}'")
        }
        CellFault::Unparsable => format!("'{raw}' in column {name} is not a number"),
    }
}

/// Header, row count, blank lines and cells per row. Returns, for each header
/// position, the index of its column in `spec`.
fn check_structure(path: &Path, lines: &Lines<'_>, spec: &[ColSpec]) -> Result<Vec<usize>, IngestError> {
    let expected = || spec.iter().map(|c| c.name).collect::<Vec<_>>().join(", ");
    if lines.len() == 0 || lines.get(0).is_empty() {
        return Err(IngestError::rule(path, Some(1), format!("empty file: a header row is required ({})", expected())));
    }
    let mut header = Vec::with_capacity(spec.len());
    for name in lines.get(0).split(',') {
        let Some(k) = spec.iter().position(|c| c.name == name) else {
            return Err(IngestError::rule(
                path,
                Some(1),
                format!("unexpected column {name:?} (the columns must be exactly: {})", expected()),
            ));
        };
        if header.contains(&k) {
            return Err(IngestError::rule(path, Some(1), format!("column {name} appears twice in the header")));
        }
        header.push(k);
    }
    if let Some(missing) = spec.iter().enumerate().find(|(k, _)| !header.contains(k)) {
        return Err(IngestError::rule(
            path,
            Some(1),
            format!("missing column {} (the columns must be exactly: {})", missing.1.name, expected()),
        ));
    }
    if lines.len() == 1 {
        return Err(IngestError::rule(path, Some(1), "header row but no data rows"));
    }
    // Blank lines would shift the row -> line mapping (polars reads them as
    // rows of nulls); a line of just `\n` or `\r\n` is at most 2 bytes long.
    // Cell counts are checked next, by one comma count (see `read_numeric_csv`).
    for k in 1..lines.len() {
        let next = lines.starts.get(k + 1).copied().unwrap_or(lines.text.len());
        if next - lines.starts[k] <= 2 && lines.get(k).is_empty() {
            let n_cells = header.len();
            return Err(IngestError::rule(path, Some(k + 1), format!("empty line (every row needs {n_cells} cells)")));
        }
    }
    Ok(header)
}

/// The first data line whose cell count differs from the header's, if any
/// (a full scan: only run once the comma count has found a problem).
fn ragged_row(path: &Path, lines: &Lines<'_>, n_cells: usize) -> Option<IngestError> {
    (1..lines.len()).find_map(|k| ragged_line(path, lines, k, n_cells))
}

/// An error if the 0-based line `k` does not have `n_cells` cells.
fn ragged_line(path: &Path, lines: &Lines<'_>, k: usize, n_cells: usize) -> Option<IngestError> {
    let cells = lines.get(k).matches(',').count() + 1;
    (cells != n_cells)
        .then(|| IngestError::rule(path, Some(k + 1), format!("row has {cells} cells but the header has {n_cells}")))
}

/// `time_s` is strictly increasing and, if asked, starts at exactly 0.
fn check_time(path: &Path, lines: &Lines<'_>, pos: usize, t: &[f64], start: TimeStart) -> Result<(), IngestError> {
    if start == TimeStart::Zero && t[0] != 0.0 {
        let raw = lines.cell(0, pos);
        return Err(IngestError::rule(path, Some(2), format!("time_s must start at 0 (found {raw})")));
    }
    if let Some(i) = t.windows(2).position(|w| w[1] <= w[0]) {
        let (before, after) = (lines.cell(i, pos), lines.cell(i + 1, pos));
        return Err(IngestError::rule(
            path,
            Some(i + 3),
            format!("time_s must be strictly increasing ({after} after {before})"),
        ));
    }
    Ok(())
}
