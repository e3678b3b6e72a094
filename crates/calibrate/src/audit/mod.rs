//! The audit of the chapter: every published number that can be recomputed
//! from its own inputs (or checked against the chapter's own equations and
//! statements) is recomputed here, and the row says whether it follows.
//!
//! Status rules (see [`Status`]): `ok` when the recomputed value rounds to the
//! printed one; `rounding` when the printed value lies within
//! `rounding_tolerance` units of its last digit of the range the recomputation
//! spans as its printed inputs move within their own rounding (±½ unit);
//! `inconsistent` otherwise; `note` for findings that are not errors. Inputs
//! that are the chapter's stated constants (Table 4.1, Tables 4.4/4.5) are
//! taken as exact; inputs that are printed results of other computations
//! (δ, ξ, ω, K_sA, J) are taken as rounded. Nothing here knows which rows are
//! wrong: every status comes from the arithmetic.

use crate::CalibrateError;
use crate::published::{Printed, ThesisTables};
use rig_types::{Table, fmt_fixed};
use serde::{Deserialize, Serialize};

mod characterisation;
mod model;

#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Status {
    Ok,
    Rounding,
    Inconsistent,
    Note,
}

impl Status {
    pub fn as_str(&self) -> &'static str {
        match self {
            Status::Ok => "ok",
            Status::Rounding => "rounding",
            Status::Inconsistent => "inconsistent",
            Status::Note => "note",
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct AuditRow {
    pub table: String,
    pub row: String,
    pub column: String,
    /// As printed (or the statement's value).
    pub published: String,
    pub recomputed: String,
    pub status: Status,
    pub reason: String,
}

/// An input of a recomputation: its value and the half-width it may have
/// moved by rounding (0 for a stated constant).
#[derive(Debug, Clone, Copy)]
struct In {
    v: f64,
    half: f64,
}

fn exact(p: Printed) -> In {
    In { v: p.value, half: 0.0 }
}
fn rounded(p: Printed) -> In {
    In { v: p.value, half: 0.5 * p.unit() }
}
fn val(v: f64) -> In {
    In { v, half: 0.0 }
}

/// Range of `g` over every corner of the inputs' rounding box. The formulas
/// passed here are monotone in each input over the box, so the corners bound
/// the range; absolute values go through [`Audit::check_abs`].
fn corner_range(inputs: &[In], g: &dyn Fn(&[f64]) -> f64) -> (f64, f64) {
    let n = inputs.len();
    let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
    for mask in 0..(1usize << n) {
        let x: Vec<f64> = inputs
            .iter()
            .enumerate()
            .map(|(i, p)| if mask >> i & 1 == 1 { p.v + p.half } else { p.v - p.half })
            .collect();
        let y = g(&x);
        lo = lo.min(y);
        hi = hi.max(y);
    }
    (lo, hi)
}

fn fmt_printed(p: Printed) -> String {
    fmt_fixed(p.value, p.decimals.max(0) as usize)
}

/// Decimals to show a recomputed value with: two more than printed.
fn rec_decimals(p: Printed) -> usize {
    (p.decimals.max(0) + 2) as usize
}

/// The audit under construction.
pub struct Audit {
    tolerance: f64,
    rows: Vec<AuditRow>,
}

/// One recomputation: where it is, the printed value, the formula and inputs,
/// and the sentence (with numbers) to give if it does not follow.
struct Check<'a> {
    table: &'a str,
    row: &'a str,
    column: &'a str,
    published: Printed,
    inputs: Vec<In>,
    what: &'a str,
}

impl Audit {
    pub fn new(rounding_tolerance: f64) -> Self {
        Audit { tolerance: rounding_tolerance, rows: Vec::new() }
    }

    /// Runs a check; returns the recomputed value and the status.
    fn check(&mut self, c: Check, g: &dyn Fn(&[f64]) -> f64, if_wrong: &dyn Fn(f64) -> String) -> (f64, Status) {
        let nominal = g(&c.inputs.iter().map(|p| p.v).collect::<Vec<_>>());
        let (lo, hi) = corner_range(&c.inputs, g);
        self.judge(c, nominal, (lo, hi), if_wrong)
    }

    /// Like [`Audit::check`] for |g| where g is monotone but changes sign
    /// inside the rounding box (relative errors): the corners bound g, and the
    /// range of |g| follows from g's (0 when g's range straddles 0).
    fn check_abs(&mut self, c: Check, g: &dyn Fn(&[f64]) -> f64, if_wrong: &dyn Fn(f64) -> String) -> (f64, Status) {
        let nominal = g(&c.inputs.iter().map(|p| p.v).collect::<Vec<_>>()).abs();
        let (lo, hi) = corner_range(&c.inputs, g);
        let range =
            if lo <= 0.0 && hi >= 0.0 { (0.0, hi.max(-lo)) } else { (lo.abs().min(hi.abs()), lo.abs().max(hi.abs())) };
        self.judge(c, nominal, range, if_wrong)
    }

    fn judge(
        &mut self,
        c: Check,
        nominal: f64,
        (lo, hi): (f64, f64),
        if_wrong: &dyn Fn(f64) -> String,
    ) -> (f64, Status) {
        let unit = c.published.unit();
        let p = c.published.value;
        let eps = 1e-9 * unit;
        let status = if (p - nominal).abs() <= 0.5 * unit + eps {
            Status::Ok
        } else if p >= lo - self.tolerance * unit - eps && p <= hi + self.tolerance * unit + eps {
            Status::Rounding
        } else {
            Status::Inconsistent
        };
        let d = rec_decimals(c.published);
        let reason = match status {
            Status::Ok => c.what.to_string(),
            Status::Rounding => format!(
                "{}; printed inputs rounded by ±½ digit give {} to {}",
                c.what,
                fmt_fixed(lo, d),
                fmt_fixed(hi, d)
            ),
            _ => format!("{}; {}", c.what, if_wrong(nominal)),
        };
        self.rows.push(AuditRow {
            table: c.table.into(),
            row: c.row.into(),
            column: c.column.into(),
            published: fmt_printed(c.published),
            recomputed: fmt_fixed(nominal, d),
            status,
            reason,
        });
        (nominal, status)
    }

    fn note(&mut self, table: &str, row: &str, column: &str, published: String, recomputed: String, reason: String) {
        self.rows.push(AuditRow {
            table: table.into(),
            row: row.into(),
            column: column.into(),
            published,
            recomputed,
            status: Status::Note,
            reason,
        });
    }

    fn flag(&mut self, table: &str, row: &str, column: &str, published: String, recomputed: String, reason: String) {
        self.rows.push(AuditRow {
            table: table.into(),
            row: row.into(),
            column: column.into(),
            published,
            recomputed,
            status: Status::Inconsistent,
            reason,
        });
    }

    /// Rows sorted by (table, row, column) in natural order (`eq-4-4` before
    /// `eq-4-10`) — deterministic, and a table's rows stay together.
    pub fn into_rows(mut self) -> Vec<AuditRow> {
        self.rows.sort_by_cached_key(|r| (natural_key(&r.table), natural_key(&r.row), natural_key(&r.column)));
        self.rows
    }
}

/// A sort key in which digit runs compare as numbers: each run is zero-padded to 9 digits.
fn natural_key(s: &str) -> String {
    let mut out = String::new();
    let mut digits = String::new();
    for c in s.chars().chain(std::iter::once('\0')) {
        if c.is_ascii_digit() {
            digits.push(c);
            continue;
        }
        if !digits.is_empty() {
            out.push_str(&format!("{digits:0>9}"));
            digits.clear();
        }
        if c != '\0' {
            out.push(c);
        }
    }
    out
}

/// Audits every recomputable number of the chapter.
pub fn audit(t: &ThesisTables, rounding_tolerance: f64) -> Result<Vec<AuditRow>, CalibrateError> {
    let mut a = Audit::new(rounding_tolerance);
    characterisation::eq_4_1_to_4_5(&mut a, t)?;
    characterisation::table_4_2(&mut a, t)?;
    characterisation::table_4_3(&mut a, t)?;
    characterisation::table_4_6(&mut a, t)?;
    model::motor_and_friction(&mut a, t)?;
    model::table_4_8(&mut a, t)?;
    Ok(a.into_rows())
}

fn missing_row(table: &str, row: &str) -> CalibrateError {
    CalibrateError::Published { table: table.into(), reason: format!("row `{row}` is missing") }
}

/// The audit as a table (columns `table,row,column,published,recomputed,status,reason`).
pub fn audit_table(rows: &[AuditRow]) -> Table {
    let mut t = Table::new(["table", "row", "column", "published", "recomputed", "status", "reason"]);
    for r in rows {
        t.push([
            r.table.clone(),
            r.row.clone(),
            r.column.clone(),
            r.published.clone(),
            r.recomputed.clone(),
            r.status.as_str().to_string(),
            r.reason.clone(),
        ]);
    }
    t
}

/// audit.md: counts, then one sentence per inconsistency (with its numbers), then the notes.
pub fn audit_markdown(rows: &[AuditRow], rounding_tolerance: f64) -> String {
    let count = |s: Status| rows.iter().filter(|r| r.status == s).count();
    let mut md = String::new();
    md.push_str("# Audit of thesis chapter 4\n\n");
    md.push_str(&format!(
        "{} published numbers and statements recomputed from their own inputs: {} ok, {} rounding, {} inconsistent, {} notes.\n\n",
        rows.len(),
        count(Status::Ok),
        count(Status::Rounding),
        count(Status::Inconsistent),
        count(Status::Note)
    ));
    md.push_str(&format!(
        "`ok`: the recomputed value rounds to the printed one. `rounding`: it does not, but the printed value lies within \
         {rounding_tolerance} of its last digit of the range the recomputation spans when its printed inputs move by ±½ digit. \
         `inconsistent`: neither. `note`: a finding that is not an error. Full table: `audit.csv`.\n\n"
    ));
    md.push_str("## Inconsistencies\n\n");
    for r in rows.iter().filter(|r| r.status == Status::Inconsistent) {
        md.push_str(&format!(
            "- **{} / {} / {}**: printed {}, recomputed {}. {}.\n",
            r.table, r.row, r.column, r.published, r.recomputed, r.reason
        ));
    }
    md.push_str("\n## Notes\n\n");
    for r in rows.iter().filter(|r| r.status == Status::Note) {
        md.push_str(&format!("- **{} / {} / {}**: {}.\n", r.table, r.row, r.column, r.reason));
    }
    md.push_str("\n## Explained by rounding\n\n");
    for r in rows.iter().filter(|r| r.status == Status::Rounding) {
        md.push_str(&format!(
            "- {} / {} / {}: printed {}, recomputed {} ({}).\n",
            r.table, r.row, r.column, r.published, r.recomputed, r.reason
        ));
    }
    md
}

#[cfg(test)]
mod tests {
    use super::*;

    fn p(value: f64, decimals: i32) -> Printed {
        Printed { value, decimals }
    }

    fn run(published: Printed, inputs: Vec<In>, g: &dyn Fn(&[f64]) -> f64, abs: bool) -> Status {
        let mut a = Audit::new(0.5);
        let c = Check { table: "t", row: "r", column: "c", published, inputs, what: "w" };
        if abs { a.check_abs(c, g, &|_| String::new()).1 } else { a.check(c, g, &|_| String::new()).1 }
    }

    #[test]
    fn statuses_follow_the_arithmetic() {
        let ratio = |x: &[f64]| x[0] / x[1];
        // 1/3 = 0.3333 → printed 0.333 is ok.
        assert_eq!(run(p(0.333, 3), vec![val(1.0), val(3.0)], &ratio, false), Status::Ok);
        // 0.139/0.532 = 0.26128: printed 0.260 is reachable from inputs rounded at 3 decimals.
        assert_eq!(run(p(0.260, 3), vec![rounded(p(0.139, 3)), rounded(p(0.532, 3))], &ratio, false), Status::Rounding);
        // ... but not from exact inputs.
        assert_eq!(run(p(0.260, 3), vec![val(0.139), val(0.532)], &ratio, false), Status::Inconsistent);
    }

    /// |x − 1| with x = 1.0 ± 0.1 (printed 1.0): the magnitude reaches 0 inside
    /// the box although no corner does; check_abs must see that.
    #[test]
    fn absolute_values_straddling_zero() {
        let signed = |x: &[f64]| x[0] - 1.0;
        assert_eq!(run(p(0.02, 2), vec![rounded(p(1.0, 1))], &signed, true), Status::Rounding);
        assert_eq!(
            run(p(0.02, 2), vec![rounded(p(1.0, 1))], &|x: &[f64]| (x[0] - 1.0).abs(), false),
            Status::Inconsistent
        );
    }

    #[test]
    fn natural_order() {
        assert!(natural_key("eq-4-4") < natural_key("eq-4-10"));
        assert!(natural_key("table-4-2") < natural_key("table-4-10"));
    }
}
