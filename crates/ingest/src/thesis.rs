//! Thesis tables (data/thesis/*.csv, see data/thesis/README.md) to typed data.
//! Plain std CSV parsing (the files are tiny and hand-written); every number
//! keeps its printed precision; every refusal names the file and line.
//!
//! The types are `rig_types::thesis`, shared with rig-calibrate.

use crate::IngestError;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

pub use rig_types::thesis::*;

/// Parses a printed number and counts its printed decimals. Accepts
/// `[-]digits[.digits][e[-]digits]`; a decimal comma is refused (the README
/// says they were converted).
pub fn parse_printed(text: &str) -> Result<Printed, String> {
    let t = text.trim();
    let (mantissa, exp) = match t.split_once(['e', 'E']) {
        Some((m, e)) => (m, e.parse::<i32>().map_err(|_| format!("`{t}`: bad exponent"))?),
        None => (t, 0),
    };
    let digits = mantissa.trim_start_matches('-');
    let ok = !digits.is_empty()
        && digits.chars().all(|c| c.is_ascii_digit() || c == '.')
        && digits.matches('.').count() <= 1
        && digits.chars().any(|c| c.is_ascii_digit());
    if !ok {
        return Err(format!("`{t}` is not a number as printed (digits, one `.`, optional exponent)"));
    }
    let decimals = mantissa.split_once('.').map(|(_, f)| f.len() as i32).unwrap_or(0) - exp;
    let value: f64 = t.parse().map_err(|_| format!("`{t}` is not a number"))?;
    if !value.is_finite() {
        return Err(format!("`{t}` is not finite"));
    }
    Ok(Printed { value, decimals })
}

/// Splits one CSV line (RFC 4180 quoting, `""` inside quotes).
fn split_csv_line(line: &str) -> Result<Vec<String>, String> {
    let mut cells = Vec::new();
    let mut cur = String::new();
    let mut chars = line.chars().peekable();
    let mut quoted = false;
    while let Some(c) = chars.next() {
        match (quoted, c) {
            (true, '"') if chars.peek() == Some(&'"') => {
                cur.push('"');
                chars.next();
            }
            (true, '"') => quoted = false,
            (false, '"') if cur.is_empty() => quoted = true,
            (false, ',') => cells.push(std::mem::take(&mut cur)),
            (_, c) => cur.push(c),
        }
    }
    if quoted {
        return Err("unterminated quote".into());
    }
    cells.push(cur);
    Ok(cells)
}

/// One data row with its 1-based line number and cells by column name.
struct Row<'a> {
    file: &'a Path,
    line: usize,
    cells: BTreeMap<&'a str, String>,
}

impl Row<'_> {
    fn err(&self, rule: String) -> IngestError {
        IngestError::rule(self.file, Some(self.line), rule)
    }
    fn text(&self, col: &str) -> String {
        self.cells.get(col).cloned().unwrap_or_default()
    }
    fn printed(&self, col: &str) -> Result<Printed, IngestError> {
        parse_printed(&self.text(col)).map_err(|e| self.err(format!("column {col}: {e}")))
    }
    /// Empty cell → `None` (the printed `-` of mean rows).
    fn printed_opt(&self, col: &str) -> Result<Option<Printed>, IngestError> {
        if self.text(col).trim().is_empty() { Ok(None) } else { self.printed(col).map(Some) }
    }
    fn number(&self, col: &str) -> Result<f64, IngestError> {
        Ok(self.printed(col)?.value)
    }
}

/// Reads `dir/name`, checks the header is exactly `columns`, and maps each row.
fn read_rows<T>(
    dir: &Path,
    name: &str,
    columns: &[&str],
    mut f: impl FnMut(&Row) -> Result<T, IngestError>,
) -> Result<Vec<T>, IngestError> {
    let file: PathBuf = dir.join(name);
    let text = std::fs::read_to_string(&file).map_err(|source| IngestError::Io {
        file: file.clone(),
        rule: "thesis table must be readable UTF-8".into(),
        source,
    })?;
    let mut lines = text.lines().enumerate();
    let header = match lines.next() {
        Some((_, h)) => split_csv_line(h).map_err(|e| IngestError::rule(&file, Some(1), e))?,
        None => return Err(IngestError::rule(&file, Some(1), "header row is missing")),
    };
    if header.iter().map(String::as_str).ne(columns.iter().copied()) {
        return Err(IngestError::rule(
            &file,
            Some(1),
            format!("header must be `{}` (found `{}`)", columns.join(","), header.join(",")),
        ));
    }
    let mut out = Vec::new();
    for (i, line) in lines {
        let line_no = i + 1;
        if line.trim().is_empty() {
            return Err(IngestError::rule(&file, Some(line_no), "empty line"));
        }
        let cells = split_csv_line(line).map_err(|e| IngestError::rule(&file, Some(line_no), e))?;
        if cells.len() != columns.len() {
            return Err(IngestError::rule(
                &file,
                Some(line_no),
                format!("row has {} cells, header has {}", cells.len(), columns.len()),
            ));
        }
        let row = Row { file: &file, line: line_no, cells: columns.iter().copied().zip(cells).collect() };
        out.push(f(&row)?);
    }
    if out.is_empty() {
        return Err(IngestError::rule(&file, None, "table has no data rows"));
    }
    Ok(out)
}

fn param_rows(dir: &Path, name: &str) -> Result<Vec<ParamRow>, IngestError> {
    read_rows(dir, name, &["symbol", "description", "value", "unit"], |r| {
        Ok(ParamRow {
            symbol: r.text("symbol"),
            description: r.text("description"),
            value: r.printed("value")?,
            unit: r.text("unit"),
        })
    })
}

/// Reads every thesis table in `dir` (normally `data/thesis`).
pub fn read_thesis_tables(dir: &Path) -> Result<ThesisTables, IngestError> {
    let table_4_2 = read_rows(
        dir,
        "table-4-2.csv",
        &["trial", "x1_rad", "x2_rad", "log_decrement", "damping_ratio", "damped_hz", "natural_hz"],
        |r| {
            Ok(DecayRow {
                trial: r.text("trial"),
                x1_rad: r.printed("x1_rad")?,
                x2_rad: r.printed("x2_rad")?,
                log_decrement: r.printed("log_decrement")?,
                damping_ratio: r.printed("damping_ratio")?,
                damped_hz: r.printed("damped_hz")?,
                natural_hz: r.printed("natural_hz")?,
            })
        },
    )?;
    let table_4_3 =
        read_rows(dir, "table-4-3.csv", &["trial", "torque_nm", "angle_rad", "k_se_nm_rad", "rel_error_pct"], |r| {
            Ok(StiffnessRow {
                trial: r.text("trial"),
                torque_nm: r.printed_opt("torque_nm")?,
                angle_rad: r.printed_opt("angle_rad")?,
                k_se_nm_rad: r.printed("k_se_nm_rad")?,
                rel_error_pct: r.printed("rel_error_pct")?,
            })
        })?;
    let table_4_6 = read_rows(dir, "table-4-6.csv", &["trial", "weight_n", "voltage_mv", "factor_mv_per_n"], |r| {
        Ok(ForceRow {
            trial: r.text("trial"),
            weight_n: r.printed_opt("weight_n")?,
            voltage_mv: r.printed_opt("voltage_mv")?,
            factor_mv_per_n: r.printed("factor_mv_per_n")?,
        })
    })?;
    let table_4_7 = read_rows(
        dir,
        "table-4-7.csv",
        &["symbol", "description", "value", "setpoint_relation", "setpoint_rpm"],
        |r| {
            let rel = r.text("setpoint_relation");
            if rel != "=" && rel != "<=" {
                return Err(r.err(format!("column setpoint_relation: `{rel}` must be `=` or `<=`")));
            }
            Ok(FrictionRow {
                symbol: r.text("symbol"),
                description: r.text("description"),
                value: r.printed("value")?,
                setpoint_relation: rel,
                setpoint_rpm: r.printed("setpoint_rpm")?,
            })
        },
    )?;
    let table_4_8 = read_rows(dir, "table-4-8.csv", &["peak", "freq_hz", "freq_rad_s"], |r| {
        Ok(PeakRow { peak: r.text("peak"), freq_hz: r.printed("freq_hz")?, freq_rad_s: r.printed("freq_rad_s")? })
    })?;
    let statements = read_rows(dir, "equations.csv", &["id", "symbol", "value", "unit", "where", "statement"], |r| {
        Ok(Statement {
            id: r.text("id"),
            symbol: r.text("symbol"),
            value: r.printed("value")?,
            unit: r.text("unit"),
            location: r.text("where"),
            statement: r.text("statement"),
        })
    })?;
    let labelled_points = read_rows(
        dir,
        "labelled-operating-points.csv",
        &["figure", "panel", "motor_rpm", "frict_n", "label", "source"],
        |r| {
            let (label, source) = (r.text("label"), r.text("source"));
            if label != "vibrating" && label != "quiet" {
                return Err(r.err(format!("column label: `{label}` must be `vibrating` or `quiet`")));
            }
            if source != "numerical" && source != "experimental" {
                return Err(r.err(format!("column source: `{source}` must be `numerical` or `experimental`")));
            }
            Ok(LabelledPoint {
                figure: r.text("figure"),
                panel: r.text("panel"),
                motor_rpm: r.number("motor_rpm")?,
                frict_n: r.number("frict_n")?,
                label,
                source,
            })
        },
    )?;
    Ok(ThesisTables {
        table_4_1: param_rows(dir, "table-4-1.csv")?,
        table_4_2,
        table_4_3,
        table_4_4: param_rows(dir, "table-4-4.csv")?,
        table_4_5: param_rows(dir, "table-4-5.csv")?,
        table_4_6,
        table_4_7,
        table_4_8,
        statements,
        labelled_points,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn printed_precision() {
        assert_eq!(parse_printed("0.30").unwrap(), Printed { value: 0.30, decimals: 2 });
        assert_eq!(parse_printed("7850").unwrap(), Printed { value: 7850.0, decimals: 0 });
        assert_eq!(parse_printed("0.37e-3").unwrap(), Printed { value: 0.37e-3, decimals: 5 });
        assert_eq!(parse_printed("-0.20").unwrap(), Printed { value: -0.2, decimals: 2 });
        assert!(parse_printed("0,30").is_err());
        assert!(parse_printed("-").is_err());
    }

    #[test]
    fn quoted_cells() {
        assert_eq!(split_csv_line(r#"a,"b, c","say ""hi""""#).unwrap(), vec!["a", "b, c", r#"say "hi""#]);
    }

    #[test]
    fn reads_the_shipped_tables() {
        let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis");
        let t = read_thesis_tables(&dir).unwrap();
        assert_eq!(t.table_4_2.len(), 5);
        assert_eq!(t.table_4_3.last().unwrap().torque_nm, None);
        assert_eq!(t.table_4_5.iter().find(|r| r.symbol == "K_s").unwrap().value.decimals, 4);
        assert_eq!(t.labelled_points.len(), 9);
    }

    #[test]
    fn errors_name_file_and_line() {
        let dir = tempfile::tempdir().unwrap();
        for f in ["table-4-1.csv", "table-4-2.csv"] {
            let src = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../data/thesis").join(f);
            std::fs::copy(src, dir.path().join(f)).unwrap();
        }
        let bad = std::fs::read_to_string(dir.path().join("table-4-2.csv")).unwrap().replace("0.889", "0.88x");
        std::fs::write(dir.path().join("table-4-2.csv"), bad).unwrap();
        let e = read_thesis_tables(dir.path()).unwrap_err().to_string();
        assert!(e.contains("table-4-2.csv:2:") && e.contains("x2_rad"), "{e}");
    }
}
