//! `cargo xtask diff --baseline REV`: every table (`tables/*.csv`,
//! `audit.csv`) and figure series (`figures/*.csv`) of the out dir in the
//! working tree against the same files at a git revision, compared cell by
//! cell at the precision each number was printed.
//!
//! A numeric cell has "moved" when old and new differ by more than half a
//! unit of the last digit printed (of the coarser of the two printings), so
//! a value that only gained printed digits is not a change; text cells
//! compare exactly. Rows are matched by their first cell when it is a
//! unique id (text or integer, e.g. `trial=4`), else by their leading text
//! cells plus occurrence number (`measured #12` in a figure series), else by
//! position (a decimal first column may itself move).

use anyhow::{Context, Result, bail};
use std::collections::{BTreeMap, BTreeSet};
use std::path::Path;
use std::process::Command;

/// Moves listed per changed file, largest relative change first.
const MOVES_SHOWN: usize = 5;

/// Compares the tree's `out_rel` artifacts with those at `baseline` and
/// returns the human-readable report (one block per file, then a summary line).
pub fn run(repo_root: &Path, baseline: &str, out_rel: &str) -> Result<String> {
    let out_rel = out_rel.trim_end_matches('/');
    let rev = git(repo_root, &["rev-parse", "--verify", "--quiet", &format!("{baseline}^{{commit}}")])
        .with_context(|| format!("diff: {baseline:?} is not a commit of the repository at {}", repo_root.display()))?;
    let rev = rev.trim().to_string();

    let mut old_files = BTreeSet::new();
    let listing = git(repo_root, &["ls-tree", "-r", "--name-only", "-z", &rev, "--", out_rel])?;
    for path in listing.split('\0').filter(|p| !p.is_empty()) {
        if let Some(rel) = path.strip_prefix(out_rel).and_then(|r| r.strip_prefix('/'))
            && compared(rel)
        {
            old_files.insert(rel.to_string());
        }
    }
    let mut new_files = BTreeSet::new();
    let out_dir = repo_root.join(out_rel);
    for sub in ["tables", "figures"] {
        let dir = out_dir.join(sub);
        if let Ok(entries) = std::fs::read_dir(&dir) {
            for e in entries.flatten() {
                let rel = format!("{sub}/{}", e.file_name().to_string_lossy());
                if compared(&rel) && e.path().is_file() {
                    new_files.insert(rel);
                }
            }
        }
    }
    if out_dir.join("audit.csv").is_file() {
        new_files.insert("audit.csv".to_string());
    }

    let short = &rev[..rev.len().min(10)];
    let mut report = format!("diff of {out_rel}/ (working tree) against {baseline} ({short})\n\n");
    let mut totals = Totals::default();
    for rel in old_files.union(&new_files) {
        let shown = format!("{out_rel}/{rel}");
        match (old_files.contains(rel), new_files.contains(rel)) {
            (true, false) => {
                totals.removed += 1;
                report.push_str(&format!("{shown}: removed\n"));
            }
            (false, true) => {
                totals.added += 1;
                report.push_str(&format!("{shown}: added\n"));
            }
            _ => {
                let old = git(repo_root, &["show", &format!("{rev}:{out_rel}/{rel}")])?;
                let new = std::fs::read_to_string(out_dir.join(rel))
                    .with_context(|| format!("diff: reading {}", out_dir.join(rel).display()))?;
                let d = compare_csv(&old, &new);
                totals.moved_cells += d.moved.len();
                if d.is_unchanged() {
                    totals.unchanged += 1;
                } else {
                    totals.changed += 1;
                    report.push_str(&d.describe(&shown));
                }
            }
        }
    }
    report.push_str(&format!(
        "\nsummary: {} files compared: {} unchanged, {} changed, {} added, {} removed; {} numeric cells moved beyond printed precision\n",
        old_files.union(&new_files).count(),
        totals.unchanged,
        totals.changed,
        totals.added,
        totals.removed,
        totals.moved_cells
    ));
    Ok(report)
}

#[derive(Default)]
struct Totals {
    unchanged: usize,
    changed: usize,
    added: usize,
    removed: usize,
    moved_cells: usize,
}

/// Which out-dir files are compared: tables, figure series and the audit.
fn compared(rel: &str) -> bool {
    let direct_csv = |dir: &str| rel.strip_prefix(dir).is_some_and(|f| !f.contains('/') && f.ends_with(".csv"));
    rel == "audit.csv" || direct_csv("tables/") || direct_csv("figures/")
}

fn git(repo_root: &Path, args: &[&str]) -> Result<String> {
    let out = Command::new("git")
        .arg("-C")
        .arg(repo_root)
        .args(args)
        .output()
        .with_context(|| format!("diff: running git {}", args.join(" ")))?;
    if !out.status.success() {
        bail!("git {} failed: {}", args.join(" "), String::from_utf8_lossy(&out.stderr).trim());
    }
    String::from_utf8(out.stdout).with_context(|| format!("git {}: output is not UTF-8", args.join(" ")))
}

/// RFC 4180 CSV (quoted cells, doubled quotes, `\n` or `\r\n` line ends) → rows of cells.
pub fn parse_csv(text: &str) -> Vec<Vec<String>> {
    let mut rows = Vec::new();
    let mut row = Vec::new();
    let mut cell = String::new();
    let mut quoted = false;
    let mut chars = text.chars().peekable();
    let mut any = false;
    while let Some(c) = chars.next() {
        any = true;
        if quoted {
            match c {
                '"' if chars.peek() == Some(&'"') => {
                    cell.push('"');
                    chars.next();
                }
                '"' => quoted = false,
                _ => cell.push(c),
            }
            continue;
        }
        match c {
            '"' => quoted = true,
            ',' => row.push(std::mem::take(&mut cell)),
            '\r' if chars.peek() == Some(&'\n') => {}
            '\n' => {
                row.push(std::mem::take(&mut cell));
                rows.push(std::mem::take(&mut row));
                any = false;
            }
            _ => cell.push(c),
        }
    }
    if any {
        row.push(cell);
        rows.push(row);
    }
    rows
}

/// A number as printed and the half unit of its last printed digit.
fn printed_number(text: &str) -> Option<(f64, f64)> {
    let t = text.trim();
    let v: f64 = t.parse().ok()?;
    if !v.is_finite() {
        return None; // NaN / inf compare as text
    }
    let (mantissa, exp) = match t.find(['e', 'E']) {
        Some(k) => (&t[..k], t[k + 1..].parse::<i32>().ok()?),
        None => (t, 0),
    };
    let decimals = mantissa.split_once('.').map_or(0, |(_, f)| f.len() as i32) - exp;
    Some((v, 0.5 * 10f64.powi(-decimals)))
}

#[derive(Debug, Clone, PartialEq)]
struct Move {
    row: String,
    column: String,
    old: String,
    new: String,
    /// |Δ| relative to max(|old|, |new|): what the largest-first ordering uses.
    relative: f64,
}

#[derive(Debug, Default)]
struct FileDiff {
    columns_added: Vec<String>,
    columns_removed: Vec<String>,
    rows_added: Vec<String>,
    rows_removed: Vec<String>,
    rows_changed: usize,
    moved: Vec<Move>,
    /// (row, column, old, new) of text cells that differ.
    text_changed: Vec<(String, String, String, String)>,
}

impl FileDiff {
    fn is_unchanged(&self) -> bool {
        self.columns_added.is_empty()
            && self.columns_removed.is_empty()
            && self.rows_added.is_empty()
            && self.rows_removed.is_empty()
            && self.rows_changed == 0
    }

    fn describe(&self, shown: &str) -> String {
        let mut s = format!(
            "{shown}: {} rows changed ({} numeric cells moved, {} text cells changed), {} rows added, {} rows removed\n",
            self.rows_changed,
            self.moved.len(),
            self.text_changed.len(),
            self.rows_added.len(),
            self.rows_removed.len()
        );
        if !self.columns_added.is_empty() {
            s.push_str(&format!("    columns added: {}\n", self.columns_added.join(", ")));
        }
        if !self.columns_removed.is_empty() {
            s.push_str(&format!("    columns removed: {}\n", self.columns_removed.join(", ")));
        }
        let mut moves = self.moved.clone();
        // Largest relative move first; ties in row/column order so the text is stable.
        moves.sort_by(|a, b| b.relative.total_cmp(&a.relative));
        for m in moves.iter().take(MOVES_SHOWN) {
            s.push_str(&format!(
                "    {} / {}: {} → {} ({:+.2} %)\n",
                m.row,
                m.column,
                m.old,
                m.new,
                100.0 * signed_relative(&m.old, &m.new)
            ));
        }
        if moves.len() > MOVES_SHOWN {
            s.push_str(&format!("    … {} more moved cells\n", moves.len() - MOVES_SHOWN));
        }
        for (row, col, old, new) in self.text_changed.iter().take(MOVES_SHOWN) {
            s.push_str(&format!("    {row} / {col}: {old:?} → {new:?}\n"));
        }
        let list = |what: &str, rows: &[String]| {
            if rows.is_empty() {
                return String::new();
            }
            let head: Vec<&str> = rows.iter().take(MOVES_SHOWN).map(String::as_str).collect();
            let more = if rows.len() > MOVES_SHOWN {
                format!(", … {} more", rows.len() - MOVES_SHOWN)
            } else {
                String::new()
            };
            format!("    rows {what}: {}{more}\n", head.join(", "))
        };
        s.push_str(&list("added", &self.rows_added));
        s.push_str(&list("removed", &self.rows_removed));
        s
    }
}

fn signed_relative(old: &str, new: &str) -> f64 {
    match (printed_number(old), printed_number(new)) {
        (Some((a, _)), Some((b, _))) if a != 0.0 => (b - a) / a.abs(),
        _ => f64::NAN,
    }
}

/// Whether rows can be keyed by their first cell: in both files every first
/// cell is non-empty, text or an integer (a decimal number may move and is
/// no identity), and unique.
fn first_column_is_key(files: [&[Vec<String>]; 2]) -> bool {
    files.iter().all(|rows| {
        let mut seen = BTreeSet::new();
        rows.iter().all(|r| {
            let c = r.first().map_or("", |c| c.trim());
            let identity = !c.is_empty() && (printed_number(c).is_none() || c.parse::<i64>().is_ok());
            identity && seen.insert(c.to_string())
        })
    })
}

/// Row keys. With a key column: `column=value`. Otherwise the leading text
/// cells (e.g. a series name) plus the occurrence number `#n`, or the row's
/// position when the first cell is a number.
fn keyed_rows<'a>(head: &[String], rows: &'a [Vec<String>], by_first: bool) -> Vec<(String, &'a Vec<String>)> {
    let mut seen: BTreeMap<String, usize> = BTreeMap::new();
    rows.iter()
        .enumerate()
        .map(|(i, r)| {
            if by_first {
                let name = head.first().map_or("", String::as_str);
                return (format!("{name}={}", r[0].trim()), r);
            }
            let lead: Vec<&str> =
                r.iter().take_while(|c| printed_number(c).is_none() && !c.is_empty()).map(String::as_str).collect();
            let key = if lead.is_empty() {
                format!("row {}", i + 1)
            } else {
                let lead = lead.join(" ");
                let n = seen.entry(lead.clone()).or_insert(0);
                *n += 1;
                format!("{lead} #{n}")
            };
            (key, r)
        })
        .collect()
}

fn compare_csv(old: &str, new: &str) -> FileDiff {
    let (old_rows, new_rows) = (parse_csv(old), parse_csv(new));
    let empty = Vec::new();
    let old_head = old_rows.first().unwrap_or(&empty);
    let new_head = new_rows.first().unwrap_or(&empty);
    let mut d = FileDiff {
        columns_added: new_head.iter().filter(|c| !old_head.contains(c)).cloned().collect(),
        columns_removed: old_head.iter().filter(|c| !new_head.contains(c)).cloned().collect(),
        ..FileDiff::default()
    };
    // Columns present in both, by name, in the new order.
    let common: Vec<(usize, usize, &String)> = new_head
        .iter()
        .enumerate()
        .filter_map(|(jn, name)| old_head.iter().position(|o| o == name).map(|jo| (jo, jn, name)))
        .collect();
    let (old_body, new_body) = (old_rows.get(1..).unwrap_or(&[]), new_rows.get(1..).unwrap_or(&[]));
    let by_first = first_column_is_key([old_body, new_body]) && old_head.first() == new_head.first();
    let old_keyed = keyed_rows(old_head, old_body, by_first);
    let new_keyed = keyed_rows(new_head, new_body, by_first);
    let old_map: BTreeMap<&str, &Vec<String>> = old_keyed.iter().map(|(k, r)| (k.as_str(), *r)).collect();
    let new_keys: BTreeSet<&str> = new_keyed.iter().map(|(k, _)| k.as_str()).collect();
    for (key, _) in &old_keyed {
        if !new_keys.contains(key.as_str()) {
            d.rows_removed.push(key.clone());
        }
    }
    for (key, new_row) in &new_keyed {
        let Some(old_row) = old_map.get(key.as_str()) else {
            d.rows_added.push(key.clone());
            continue;
        };
        let mut row_changed = false;
        for &(jo, jn, name) in &common {
            let o = old_row.get(jo).map_or("", String::as_str);
            let n = new_row.get(jn).map_or("", String::as_str);
            if o == n {
                continue;
            }
            match (printed_number(o), printed_number(n)) {
                (Some((a, ha)), Some((b, hb))) => {
                    if (b - a).abs() > ha.max(hb) {
                        let scale = a.abs().max(b.abs());
                        d.moved.push(Move {
                            row: key.clone(),
                            column: name.clone(),
                            old: o.to_string(),
                            new: n.to_string(),
                            relative: if scale > 0.0 { (b - a).abs() / scale } else { 0.0 },
                        });
                        row_changed = true;
                    }
                }
                _ => {
                    d.text_changed.push((key.clone(), name.clone(), o.to_string(), n.to_string()));
                    row_changed = true;
                }
            }
        }
        if row_changed {
            d.rows_changed += 1;
        }
    }
    d
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn csv_parsing_handles_quotes_and_crlf() {
        assert_eq!(
            parse_csv("a,b\r\n\"x, \"\"y\"\"\",2\n,\n"),
            vec![vec!["a", "b"], vec!["x, \"y\"", "2"], vec!["", ""]]
        );
        assert_eq!(parse_csv("a,b"), vec![vec!["a", "b"]]);
        assert!(parse_csv("").is_empty());
    }

    #[test]
    fn printed_precision() {
        assert_eq!(printed_number("0.30"), Some((0.30, 0.005)));
        assert_eq!(printed_number("7850"), Some((7850.0, 0.5)));
        let (v, h) = printed_number("0.37e-3").unwrap();
        assert!((v - 0.37e-3).abs() < 1e-18 && (h - 0.5e-5).abs() < 1e-20);
        assert_eq!(printed_number("NaN"), None);
        assert_eq!(printed_number("op-07"), None);
    }

    #[test]
    fn moves_are_judged_at_the_coarser_printing() {
        let old = "id,value,unit\nJ1,0.0298,kgm2\nKs,0.271,Nm/rad\nCm,1.00,x\n";
        // J1 gains a digit (0.02981 is within 0.00005 of 0.0298): not moved.
        // Ks moves by 0.002 > 0.0005: moved. Cm's unit text changes.
        let new = "id,value,unit\nJ1,0.02981,kgm2\nKs,0.273,Nm/rad\nCm,1.00,y\nTf,0.1,Nm\n";
        let d = compare_csv(old, new);
        assert_eq!(d.moved.len(), 1);
        assert_eq!(
            (d.moved[0].row.as_str(), d.moved[0].old.as_str(), d.moved[0].new.as_str()),
            ("id=Ks", "0.271", "0.273")
        );
        assert_eq!(d.text_changed, vec![("id=Cm".into(), "unit".into(), "x".into(), "y".into())]);
        assert_eq!((d.rows_changed, d.rows_added.clone(), d.rows_removed.len()), (2, vec!["id=Tf".to_string()], 0));
    }

    #[test]
    fn series_rows_match_by_name_and_occurrence() {
        let old = "series,x,y\nmeasured,0.0,1.00\nmeasured,0.1,2.00\nmodel,0.0,1.50\n";
        let new = "series,x,y\nmeasured,0.0,1.00\nmeasured,0.1,2.10\n";
        let d = compare_csv(old, new);
        assert_eq!(d.moved.len(), 1);
        assert_eq!(d.moved[0].row, "measured #2");
        assert_eq!(d.rows_removed, vec!["model #1".to_string()]);
    }

    #[test]
    fn integer_ids_key_rows_but_decimal_first_columns_do_not() {
        let d = compare_csv("trial,k\n1,0.255\n3,0.251\n", "trial,k\n1,0.255\n4,0.259\n");
        assert_eq!(
            (d.rows_added.clone(), d.rows_removed.clone()),
            (vec!["trial=4".to_string()], vec!["trial=3".to_string()])
        );
        // A decimal first column (a peak frequency) may move: rows by position.
        let d = compare_csv("f_hz,amp\n0.485,1.0\n", "f_hz,amp\n0.486,1.0\n");
        assert_eq!((d.moved.len(), d.moved[0].row.as_str()), (1, "row 1"));
    }

    #[test]
    fn columns_added_and_removed_are_reported() {
        let d = compare_csv("k,a,b\nr,1,2\n", "k,b,c\nr,2,3\n");
        assert_eq!(d.columns_added, vec!["c".to_string()]);
        assert_eq!(d.columns_removed, vec!["a".to_string()]);
        assert_eq!(d.rows_changed, 0);
        assert!(!d.is_unchanged());
    }
}
