//! The audit section of the page: the thesis audit's table (audit.csv) with
//! its status column as coloured cells and its class counts as badges, and
//! the CSV table rendering the other table sections share (`csv_table`).

use crate::diff::parse_csv;
use crate::markdown::{escape, to_html};
use crate::{TABLE_ROWS_SHOWN, not_produced, read_opt};
use std::path::Path;

/// The audit's classes, in the order they are counted and shown.
const AUDIT_CLASSES: [&str; 4] = ["ok", "rounding", "inconsistent", "note"];

/// The counts as coloured badges: "27 ok 19 rounding …".
pub(crate) fn audit_badges(counts: [usize; 4]) -> String {
    let parts: Vec<String> = AUDIT_CLASSES
        .iter()
        .zip(counts)
        .map(|(class, n)| format!("<span class=\"{class}\">{n} {class}</span>"))
        .collect();
    parts.join(" ")
}

/// The audit status of a row: one of [`AUDIT_CLASSES`].
fn status_class(cell: &str) -> Option<&'static str> {
    let c = cell.trim().to_ascii_lowercase();
    AUDIT_CLASSES.iter().find(|k| **k == c).copied()
}

/// Rows per audit class (in [`AUDIT_CLASSES`] order) and the number of rows,
/// when the table has a status column.
pub(crate) fn audit_counts(rows: &[Vec<String>]) -> Option<([usize; 4], usize)> {
    let j = status_column(rows)?;
    let mut counts = [0usize; 4];
    for r in rows.iter().skip(1) {
        if let Some(k) = r.get(j).and_then(|c| status_class(c)).and_then(|c| AUDIT_CLASSES.iter().position(|k| *k == c))
        {
            counts[k] += 1;
        }
    }
    Some((counts, rows.len().saturating_sub(1)))
}

/// The column holding the audit status: one named status/verdict/class, else
/// the first whose every non-empty cell is a status word.
pub(crate) fn status_column(rows: &[Vec<String>]) -> Option<usize> {
    let head = rows.first()?;
    let named =
        head.iter().position(|h| matches!(h.trim().to_ascii_lowercase().as_str(), "status" | "verdict" | "class"));
    named.or_else(|| {
        (0..head.len()).find(|&j| {
            let cells: Vec<&String> =
                rows[1..].iter().filter_map(|r| r.get(j)).filter(|c| !c.trim().is_empty()).collect();
            !cells.is_empty() && cells.iter().all(|c| status_class(c).is_some())
        })
    })
}

pub(crate) fn is_number(cell: &str) -> bool {
    let t = cell.trim();
    !t.is_empty() && t.parse::<f64>().is_ok()
}

/// A CSV as an HTML table; rows coloured by `status` when given.
pub(crate) fn csv_table(rows: &[Vec<String>], status: Option<usize>) -> String {
    let Some(head) = rows.first() else {
        return "<p class=\"missing\">(empty table)</p>\n".to_string();
    };
    let mut s = String::from("<table>\n<thead><tr>");
    for h in head {
        s.push_str(&format!("<th>{}</th>", escape(h)));
    }
    s.push_str("</tr></thead>\n<tbody>\n");
    for r in rows[1..].iter().take(TABLE_ROWS_SHOWN) {
        match status.and_then(|j| r.get(j)).and_then(|c| status_class(c)) {
            Some(class) => s.push_str(&format!("<tr class=\"{class}\">")),
            None => s.push_str("<tr>"),
        }
        for c in r {
            let class = if is_number(c) { " class=\"num\"" } else { "" };
            s.push_str(&format!("<td{class}>{}</td>", escape(c)));
        }
        s.push_str("</tr>\n");
    }
    s.push_str("</tbody>\n</table>\n");
    if rows.len() - 1 > TABLE_ROWS_SHOWN {
        s.push_str(&format!("<p>… {} more rows in the CSV.</p>\n", rows.len() - 1 - TABLE_ROWS_SHOWN));
    }
    s
}

pub(crate) fn section_audit(out: &Path) -> String {
    let mut s = String::from("<h2 id=\"audit\">Published numbers, recomputed</h2>\n");
    s.push_str(
        "<p>Every number the chapter prints, beside the value recomputed from its own inputs. \
         <span class=\"ok\">ok</span>: equal at the printed precision; <span class=\"rounding\">rounding</span>: \
         off by about a unit of the last printed digit; <span class=\"inconsistent\">inconsistent</span>: \
         the printed inputs do not give the printed result; <span class=\"note\">note</span>: a finding \
         that is not an error.</p>\n",
    );
    match read_opt(out, "audit.csv") {
        Some(text) => {
            let rows = parse_csv(&text);
            if let Some((counts, total)) = audit_counts(&rows) {
                s.push_str(&format!("<p>{} of {total} audited numbers.</p>\n", audit_badges(counts)));
            }
            s.push_str(&csv_table(&rows, status_column(&rows)));
        }
        None => s.push_str(&not_produced("audit.csv", "thesis-tables")),
    }
    match read_opt(out, "audit.md") {
        Some(md) => s.push_str(&to_html(&md, 2)),
        None => s.push_str(&not_produced("audit.md", "thesis-tables")),
    }
    s
}
