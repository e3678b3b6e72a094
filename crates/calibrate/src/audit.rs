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

use crate::formulas::{self as f};
use crate::published::{Printed, ThesisTables};
use crate::{CalibrateError, stats};
use rig_types::{Table, fmt_fixed};
use serde::{Deserialize, Serialize};
use std::f64::consts::PI;

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

/// Range of `g` over every corner of the inputs' rounding box (the formulas
/// here are monotone in each input, so the corners bound the range).
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
    eq_4_1_to_4_5(&mut a, t)?;
    table_4_2(&mut a, t)?;
    table_4_3(&mut a, t)?;
    table_4_6(&mut a, t)?;
    motor_and_friction(&mut a, t)?;
    table_4_8(&mut a, t)?;
    Ok(a.into_rows())
}

fn k_sa(x: &[f64]) -> f64 {
    // x = [E GPa, ν, D mm, L mm]
    f::shaft_stiffness_nm_rad(f::shear_modulus_pa(x[0] * 1e9, x[1]), f::polar_moment_m4(x[2] * 1e-3), x[3] * 1e-3)
}

fn eq_4_1_to_4_5(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
    let (e, nu, d, l) = (t.t41("E")?, t.t41("nu")?, t.t41("D_s")?, t.t41("L_s")?);
    let (m, r) = (t.t41("M_r1")?, t.t41("R_r1")?);
    let ksa = t.statement("eq-4-1")?.value;
    let (k_rec, _) = a.check(
        Check {
            table: "eq-4-1",
            row: "K_sA",
            column: "value",
            published: ksa,
            inputs: vec![exact(e), exact(nu), exact(d), exact(l)],
            what: "G I_s / L_s with G = E/(2(1+ν)), I_s = π D⁴/32 and Table 4.1",
        },
        &k_sa,
        &|v| format!("Table 4.1 gives {v:.5} N·m/rad"),
    );

    // Eq. 4-5: J_1A = ½ M R² with R from Table 4.1 (printed in mm).
    let j1a = t.statement("eq-4-5")?.value;
    let j_disc = |x: &[f64]| f::disc_inertia_kgm2(x[0], x[1] * 1e-3);
    a.check(
        Check {
            table: "eq-4-5",
            row: "J_1A",
            column: "value",
            published: j1a,
            inputs: vec![exact(m), exact(r)],
            what: "½ M_r1 R_r1² with Table 4.1's M_r1 and R_r1",
        },
        &j_disc,
        &|v| {
            let implied_r_mm = (2.0 * j1a.value / m.value).sqrt() * 1e3;
            let ratio = implied_r_mm / r.value;
            // A ratio of ½ means the printed "radius" is a diameter; say so only when the numbers show it.
            let diameter = if (ratio - 0.5).abs() < 0.01 {
                format!(" ({} mm behaves as a diameter)", fmt_printed(r))
            } else {
                String::new()
            };
            format!(
                "½·{}·({} mm)² = {v:.4} kg·m², {:.2} times the printed {}; the printed value needs R = {implied_r_mm:.1} mm, \
                 i.e. {ratio:.2} × the printed R_r1{diameter}",
                fmt_printed(m),
                fmt_printed(r),
                v / j1a.value,
                fmt_printed(j1a),
            )
        },
    );

    // Eq. 4-4: J_1E = K_sA / ω_n² with the mean ω_n of Table 4.2 converted to rad/s.
    let j1e = t.statement("eq-4-4")?.value;
    let mean = t.table_4_2.iter().find(|r| r.trial == "mean").ok_or_else(|| missing_row("table-4-2.csv", "mean"))?;
    let wn_hz = mean.natural_hz;
    let j_from = |x: &[f64]| f::inertia_from_frequency_kgm2(x[0], f::hz_to_rad_s(x[1]));
    let needed_hz = (ksa.value / j1e.value).sqrt() / (2.0 * PI);
    a.check(
        Check {
            table: "eq-4-4",
            row: "J_1E",
            column: "value",
            published: j1e,
            inputs: vec![rounded(ksa), rounded(wn_hz)],
            what: "K_sA/(2π ω_n)² with K_sA of Eq. 4-1 and Table 4.2's mean ω_n in Hz",
        },
        &j_from,
        &|v| {
            format!(
                "{} N·m/rad and {} Hz give {v:.5} kg·m²; the printed {} needs ω_n = {needed_hz:.4} Hz",
                fmt_printed(ksa),
                fmt_printed(wn_hz),
                fmt_printed(j1e)
            )
        },
    );
    let wn_trials: Vec<f64> = t.table_4_2.iter().filter(|r| r.trial != "mean").map(|r| r.natural_hz.value).collect();
    let wn_trial_mean = stats::mean(&wn_trials).unwrap_or(f64::NAN);
    a.check(
        Check {
            table: "eq-4-4",
            row: "J_1E",
            column: "value (mean of the trial ω_n)",
            published: j1e,
            inputs: vec![rounded(ksa), val(wn_trial_mean)],
            what: "K_sA/(2π ω_n)² with ω_n the mean of Table 4.2's four trial rows",
        },
        &j_from,
        &|v| format!("the trials' mean ω_n = {wn_trial_mean:.5} Hz gives {v:.5} kg·m²"),
    );
    let no_conv = f::inertia_from_frequency_kgm2(ksa.value, wn_hz.value);
    a.note(
        "eq-4-4",
        "J_1E",
        "unit of ω_n",
        fmt_printed(j1e),
        fmt_fixed(no_conv, 4),
        format!(
            "the Hz → rad/s conversion the text asks for was applied: ω_n = {} used as rad/s would give {no_conv:.3} kg·m²",
            fmt_printed(wn_hz)
        ),
    );

    // "1.39 % of relative error" between J_1E and J_1A.
    let rel = t.statement("rel-error-j1")?.value;
    let rel_ref_a = |x: &[f64]| f::relative_error_pct(x[0], x[1]);
    a.check(
        Check {
            table: "statement",
            row: "rel-error-j1",
            column: "reference J_1A",
            published: rel,
            inputs: vec![rounded(j1e), rounded(j1a)],
            what: "|J_1E − J_1A|/J_1A with the printed 0.0287 and 0.0283",
        },
        &rel_ref_a,
        &|v| format!("gives {v:.3} %"),
    );
    a.check(
        Check {
            table: "statement",
            row: "rel-error-j1",
            column: "reference J_1E",
            published: rel,
            inputs: vec![rounded(j1a), rounded(j1e)],
            what: "|J_1A − J_1E|/J_1E (the experimental value as reference)",
        },
        &rel_ref_a,
        &|v| format!("gives {v:.3} %"),
    );
    let j1a_rec = j_disc(&[m.value, r.value]);
    let j1e_rec = j_from(&[k_rec, wn_hz.value]);
    a.check(
        Check {
            table: "statement",
            row: "rel-error-j1",
            column: "recomputed J_1E and J_1A",
            published: rel,
            inputs: vec![val(j1e_rec), val(j1a_rec)],
            what: "|J_1E − J_1A|/J_1A with both inertias recomputed (Eqs. 4-4, 4-5 from Table 4.1 and 4.2)",
        },
        &rel_ref_a,
        &|v| {
            format!("J_1E = {j1e_rec:.5} and J_1A = {j1a_rec:.4} kg·m² differ by {v:.1} %: the agreement rests on Eq. 4-5's value")
        },
    );

    // Table 4.4's starting values are the analytical ones.
    for (sym, st) in [("J_1", "eq-4-5"), ("K_s", "eq-4-1")] {
        let s = t.statement(st)?.value;
        a.check(
            Check {
                table: "table-4-4",
                row: sym,
                column: "value",
                published: t.t44(sym)?,
                inputs: vec![exact(s)],
                what: if sym == "J_1" {
                    "equals J_1A of Eq. 4-5 (the stated initial value)"
                } else {
                    "equals K_sA of Eq. 4-1"
                },
            },
            &|x| x[0],
            &|v| format!("the stated source value is {v}"),
        );
    }
    Ok(())
}

fn missing_row(table: &str, row: &str) -> CalibrateError {
    CalibrateError::Published { table: table.into(), reason: format!("row `{row}` is missing") }
}

fn table_4_2(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
    let trials: Vec<_> = t.table_4_2.iter().filter(|r| r.trial != "mean").collect();
    for r in &t.table_4_2 {
        let tr = r.trial.as_str();
        a.check(
            Check {
                table: "table-4-2",
                row: tr,
                column: "log_decrement",
                published: r.log_decrement,
                inputs: vec![rounded(r.x1_rad), rounded(r.x2_rad)],
                what: "Eq. 4-2a ln(x1/x2)",
            },
            &|x| f::log_decrement(x[0], x[1]),
            &|v| format!("ln({}/{}) = {v:.4}", fmt_printed(r.x1_rad), fmt_printed(r.x2_rad)),
        );
        let (xi_rec, _) = a.check(
            Check {
                table: "table-4-2",
                row: tr,
                column: "damping_ratio",
                published: r.damping_ratio,
                inputs: vec![rounded(r.log_decrement)],
                what: "Eq. 4-2b δ/√((2π)²+δ²) from the printed δ",
            },
            &|x| f::damping_ratio(x[0]),
            &|v| {
                format!(
                    "δ = {} gives ξ = {v:.4}; the printed ξ is {:.2} times that (printed ξ/δ = {:.3}, Eq. 4-2b's ξ/δ = {:.3})",
                    fmt_printed(r.log_decrement),
                    r.damping_ratio.value / v,
                    r.damping_ratio.value / r.log_decrement.value,
                    v / r.log_decrement.value
                )
            },
        );
        a.check(
            Check {
                table: "table-4-2",
                row: tr,
                column: "natural_hz",
                published: r.natural_hz,
                inputs: vec![rounded(r.damped_hz), rounded(r.damping_ratio)],
                what: "Eq. 4-3 ω_d/√(1−ξ²) from the printed ω_d and ξ",
            },
            &|x| f::natural_from_damped(x[0], x[1]),
            &|v| format!("gives {v:.4} Hz"),
        );
        a.check(
            Check {
                table: "table-4-2",
                row: tr,
                column: "natural_hz (ξ of Eq. 4-2b)",
                published: r.natural_hz,
                inputs: vec![rounded(r.damped_hz), val(xi_rec)],
                what: "Eq. 4-3 from the printed ω_d and ξ recomputed by Eq. 4-2b",
            },
            &|x| f::natural_from_damped(x[0], x[1]),
            &|v| format!("ξ = {xi_rec:.4} gives ω_n = {v:.4} Hz (the printed ω_n follows the printed ξ)"),
        );
    }
    // The Mean row: means of the four trial rows.
    let mean = t.table_4_2.iter().find(|r| r.trial == "mean").ok_or_else(|| missing_row("table-4-2.csv", "mean"))?;
    type Col = fn(&crate::published::DecayRow) -> Printed;
    let cols: [(&str, Col); 6] = [
        ("x1_rad (mean)", |r| r.x1_rad),
        ("x2_rad (mean)", |r| r.x2_rad),
        ("log_decrement (mean)", |r| r.log_decrement),
        ("damping_ratio (mean)", |r| r.damping_ratio),
        ("damped_hz (mean)", |r| r.damped_hz),
        ("natural_hz (mean)", |r| r.natural_hz),
    ];
    for (name, col) in cols {
        let inputs: Vec<In> = trials.iter().map(|r| rounded(col(r))).collect();
        let printed: Vec<String> = trials.iter().map(|r| fmt_printed(col(r))).collect();
        a.check(
            Check {
                table: "table-4-2",
                row: "mean",
                column: name,
                published: col(mean),
                inputs,
                what: "mean of the four trial rows",
            },
            &|x| stats::mean(x).unwrap_or(f64::NAN),
            &|v| format!("the mean of {} is {v:.5}", printed.join(", ")),
        );
    }
    Ok(())
}

fn table_4_3(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
    let ksa = t.statement("eq-4-1")?.value;
    let tick_rad = 2.0 * PI / t.statement("encoder-resolution")?.value.value;
    let mut k_from_ratio = Vec::new();
    for r in t.table_4_3.iter().filter(|r| r.trial != "mean") {
        let tr = r.trial.as_str();
        let (Some(tq), Some(ang)) = (r.torque_nm, r.angle_rad) else {
            return Err(CalibrateError::Published {
                table: "table-4-3.csv".into(),
                reason: format!("trial {tr} lacks torque or angle"),
            });
        };
        let (k_rec, _) = a.check(
            Check {
                table: "table-4-3",
                row: tr,
                column: "k_se_nm_rad",
                published: r.k_se_nm_rad,
                inputs: vec![rounded(tq), rounded(ang)],
                what: "K_SE = torque/angle",
            },
            &|x| f::static_stiffness_nm_rad(x[0], x[1]),
            &|v| {
                format!(
                    "{}/{} = {v:.4} N·m/rad; the printed {} would need a torque of {:.3} N·m or an angle of {:.3} rad",
                    fmt_printed(tq),
                    fmt_printed(ang),
                    fmt_printed(r.k_se_nm_rad),
                    r.k_se_nm_rad.value * ang.value,
                    tq.value / r.k_se_nm_rad.value
                )
            },
        );
        k_from_ratio.push((tq, ang));
        a.check(
            Check {
                table: "table-4-3",
                row: tr,
                column: "rel_error_pct",
                published: r.rel_error_pct,
                inputs: vec![rounded(r.k_se_nm_rad), rounded(ksa)],
                what: "|K_SE − K_sA|/K_sA from the printed K_SE and K_sA = 0.268",
            },
            &|x| f::relative_error_pct(x[0], x[1]),
            &|v| format!("gives {v:.3} %"),
        );
        a.check(
            Check {
                table: "table-4-3",
                row: tr,
                column: "rel_error_pct (K_SE = torque/angle)",
                published: r.rel_error_pct,
                inputs: vec![rounded(tq), rounded(ang), rounded(ksa)],
                what: "|torque/angle − K_sA|/K_sA",
            },
            &|x| f::relative_error_pct(x[0] / x[1], x[2]),
            &|v| format!("K_SE = {k_rec:.4} from torque/angle gives {v:.3} %"),
        );
        let ticks = ang.value / tick_rad;
        if ang.unit() < tick_rad {
            a.note(
                "table-4-3",
                tr,
                "angle_rad (encoder resolution)",
                fmt_printed(ang),
                format!("{ticks:.2} ticks"),
                format!(
                    "printed to {} rad, finer than one encoder tick (2π/1000 = {tick_rad:.5} rad); the angle is {ticks:.2} ticks, \
                     so it is an average or the last digit is not resolved",
                    fmt_fixed(ang.unit(), ang.decimals.max(0) as usize)
                ),
            );
        }
    }
    let mean = t.table_4_3.iter().find(|r| r.trial == "mean").ok_or_else(|| missing_row("table-4-3.csv", "mean"))?;
    let trials: Vec<_> = t.table_4_3.iter().filter(|r| r.trial != "mean").collect();
    for (name, published, inputs) in [
        ("k_se_nm_rad (mean)", mean.k_se_nm_rad, trials.iter().map(|r| rounded(r.k_se_nm_rad)).collect::<Vec<_>>()),
        ("rel_error_pct (mean)", mean.rel_error_pct, trials.iter().map(|r| rounded(r.rel_error_pct)).collect()),
    ] {
        a.check(
            Check { table: "table-4-3", row: "mean", column: name, published, inputs, what: "mean of the trial rows" },
            &|x| stats::mean(x).unwrap_or(f64::NAN),
            &|v| format!("the mean of the printed trial values is {v:.5}"),
        );
    }
    // The mean of K_SE recomputed per trial as torque/angle (inputs exact here: 10 rounded inputs would
    // make 1024 corners; the rounding of a mean of ratios is below ½ digit anyway).
    let ratio_mean =
        stats::mean(&k_from_ratio.iter().map(|(q, g)| q.value / g.value).collect::<Vec<_>>()).unwrap_or(f64::NAN);
    a.check(
        Check {
            table: "table-4-3",
            row: "mean",
            column: "k_se_nm_rad (mean of torque/angle)",
            published: mean.k_se_nm_rad,
            inputs: vec![val(ratio_mean)],
            what: "mean over trials of torque/angle",
        },
        &|x| x[0],
        &|v| format!("the mean of torque/angle is {v:.5} N·m/rad"),
    );
    Ok(())
}

fn table_4_6(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
    let dyn_precision_n = t.statement("dynamometer-5n-precision")?.value.value;
    let mut factors = Vec::new();
    for r in t.table_4_6.iter().filter(|r| r.trial != "mean") {
        let (Some(w), Some(v)) = (r.weight_n, r.voltage_mv) else {
            return Err(CalibrateError::Published {
                table: "table-4-6.csv".into(),
                reason: format!("trial {} lacks weight or voltage", r.trial),
            });
        };
        a.check(
            Check {
                table: "table-4-6",
                row: &r.trial,
                column: "factor_mv_per_n",
                published: r.factor_mv_per_n,
                inputs: vec![rounded(v), rounded(w)],
                what: "voltage/weight",
            },
            &|x| f::force_factor_mv_per_n(x[0], x[1]),
            &|q| format!("{}/{} = {q:.4} mV/N", fmt_printed(v), fmt_printed(w)),
        );
        factors.push(rounded(r.factor_mv_per_n));
        // What the instruments support: the 5 N dynamometer reads to 0.05 N (Fig. 4.9).
        let spread = v.value / w.value * (dyn_precision_n / w.value);
        a.note(
            "table-4-6",
            &r.trial,
            "factor_mv_per_n (instrument precision)",
            fmt_printed(r.factor_mv_per_n),
            format!("±{}", fmt_fixed(spread, 1)),
            format!(
                "printed to {} mV/N, but a weight read to ±{dyn_precision_n} N (Fig. 4.9) moves the factor by ±{spread:.1} mV/N",
                fmt_fixed(r.factor_mv_per_n.unit(), r.factor_mv_per_n.decimals.max(0) as usize)
            ),
        );
    }
    let mean = t.table_4_6.iter().find(|r| r.trial == "mean").ok_or_else(|| missing_row("table-4-6.csv", "mean"))?;
    a.check(
        Check {
            table: "table-4-6",
            row: "mean",
            column: "factor_mv_per_n (mean)",
            published: mean.factor_mv_per_n,
            inputs: factors,
            what: "mean of the trial factors",
        },
        &|x| stats::mean(x).unwrap_or(f64::NAN),
        &|v| format!("the mean is {v:.4} mV/N"),
    );
    Ok(())
}

fn motor_and_friction(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
    // "8 V (≃ 16 rad/s)": steady no-load speed of Eq. 4-6 with each motor table.
    let volts = t.statement("step-voltage")?.value;
    let speed = t.statement("step-speed")?.value;
    let gear = t.statement("gear-ratio")?.value.value;
    for (table, get) in
        [("table-4-4", ThesisTables::t44 as fn(&ThesisTables, &str) -> _), ("table-4-5", ThesisTables::t45)]
    {
        let (r, kt, ke, tf, cm) = (get(t, "R_DC")?, get(t, "k_T")?, get(t, "k_e")?, get(t, "T_f")?, get(t, "C_m")?);
        let inputs = vec![exact(volts), exact(r), exact(kt), exact(ke), exact(tf), exact(cm)];
        let w = |x: &[f64]| f::no_load_speed_rad_s(x[0], x[1], x[2], x[3], x[4], x[5]);
        a.check(
            Check {
                table: "statement",
                row: "step-speed",
                column: &format!("{table} constants, no gearbox (Eq. 4-6 as published)"),
                published: speed,
                inputs: inputs.clone(),
                what: "steady no-load speed (V − R T_f/k_T)/(k_e + R C_m/k_T) of Eq. 4-6 at 8 V",
            },
            &w,
            &|v| {
                format!(
                    "Eq. 4-6 without the gearbox runs at {v:.1} rad/s at 8 V, {:.1} times the stated 16 rad/s",
                    v / speed.value
                )
            },
        );
        a.check(
            Check {
                table: "statement",
                row: "step-speed",
                column: &format!("{table} constants, through the 8:1 gearbox"),
                published: speed,
                inputs,
                what: "the same no-load speed divided by the stated 8:1 gear ratio",
            },
            &|x| w(x) / gear,
            &|v| format!("gives {v:.2} rad/s"),
        );
    }
    // Table 4.5 against Table 4.4: what the estimation did not move.
    for p in &t.table_4_4 {
        let est = t.t45(&p.symbol)?;
        if est.value == p.value.value {
            a.note(
                "table-4-5",
                &p.symbol,
                "value vs Table 4.4",
                fmt_printed(est),
                fmt_printed(p.value),
                format!(
                    "{} ({}) left the least-squares estimation exactly at its initial value {}: it was not identified",
                    p.symbol,
                    p.description,
                    fmt_printed(p.value)
                ),
            );
        }
    }
    // Table 4.5's J_1 and K_s against Table 4.2's natural frequency.
    let (j, k) = (t.t45("J_1")?, t.t45("K_s")?);
    let fn_hz = (k.value / j.value).sqrt() / (2.0 * PI);
    let mean_hz = t.table_4_2.iter().find(|r| r.trial == "mean").map(|r| r.natural_hz.value).unwrap_or(f64::NAN);
    a.note(
        "table-4-5",
        "J_1, K_s",
        "natural frequency",
        fmt_fixed(mean_hz, 3),
        fmt_fixed(fn_hz, 4),
        format!("Table 4.5's J_1 and K_s put √(K/J)/2π at {fn_hz:.4} Hz; Table 4.2's mean ω_n is {mean_hz:.3} Hz"),
    );

    // Table 4.7 set-points against Eq. 4-10's single threshold Tol = 0.001 (unit not printed).
    let tol = t.statement("tol")?.value.value;
    let tol_rad_s_in_rpm = tol * 60.0 / (2.0 * PI);
    for sym in ["mu_st", "mu_dyn"] {
        let row = t.friction(sym)?;
        let sp = row.setpoint_rpm.value;
        let matches = (sp - tol).abs() <= 0.5 * row.setpoint_rpm.unit()
            || (sp - tol_rad_s_in_rpm).abs() <= 0.5 * row.setpoint_rpm.unit();
        let rec = format!("{tol} rpm or {tol_rad_s_in_rpm:.4} rpm");
        let reason = format!(
            "Eq. 4-10 switches between μ_st and μ_dyn at one threshold Tol = {tol} (read as rpm: {tol} rpm; as rad/s: {tol_rad_s_in_rpm:.4} rpm), \
             but Table 4.7 prints {} rpm for {sym}",
            fmt_printed(row.setpoint_rpm)
        );
        if matches {
            a.rows.push(AuditRow {
                table: "table-4-7".into(),
                row: sym.into(),
                column: "setpoint_rpm vs Tol".into(),
                published: fmt_printed(row.setpoint_rpm),
                recomputed: rec,
                status: Status::Ok,
                reason,
            });
        } else {
            a.flag("table-4-7", sym, "setpoint_rpm vs Tol", fmt_printed(row.setpoint_rpm), rec, reason);
        }
    }
    let (st, dy) = (t.friction("mu_st")?.setpoint_rpm, t.friction("mu_dyn")?.setpoint_rpm);
    if st.value != dy.value {
        a.flag(
            "table-4-7",
            "mu_st, mu_dyn",
            "setpoint_rpm",
            format!("{} / {}", fmt_printed(st), fmt_printed(dy)),
            "one threshold".into(),
            format!(
                "Eq. 4-10 has a single switch speed Tol, but Table 4.7 gives two different set-points ({} and {} rpm); \
                 the band between them has no coefficient in Eq. 4-10",
                fmt_printed(st),
                fmt_printed(dy)
            ),
        );
    }
    // Eq. 4-10's cases as printed: μ_st if Ω1 < Tol, μ_dyn if Ω1 ≥ Tol, μ_neg if Ω1 < 0.
    // Overlap of (−∞, Tol) and (−∞, 0) is (−∞, min(Tol, 0)): nonempty for any Tol.
    let overlap_hi = tol.min(0.0);
    if overlap_hi > f64::NEG_INFINITY {
        a.flag(
            "eq-4-10",
            "cases",
            "conditions",
            "Ω1 < Tol | Ω1 ≥ Tol | Ω1 < 0".into(),
            format!("overlap Ω1 < {overlap_hi}"),
            format!(
                "the μ_st case (Ω1 < Tol = {tol}) and the μ_neg case (Ω1 < 0) both hold for every negative speed, so Eq. 4-10 \
                 (and 4-11) does not say which coefficient applies there (Eq. 4-11 repeats the same cases)"
            ),
        );
    }
    // Table 4.7's μ_neg set-point "≤ 0" against Eq. 4-10's "Ω1 < 0".
    let neg = t.friction("mu_neg")?;
    if neg.setpoint_relation != EQ_4_10_NEG_RELATION {
        a.flag(
            "table-4-7",
            "mu_neg",
            "setpoint_relation",
            format!("{} {}", neg.setpoint_relation, fmt_printed(neg.setpoint_rpm)),
            format!("{EQ_4_10_NEG_RELATION} 0 (Eq. 4-10)"),
            format!(
                "Table 4.7 applies μ_neg for speeds {} {}, Eq. 4-10 for Ω1 {EQ_4_10_NEG_RELATION} 0: at Ω1 = 0 the table says μ_neg \
                 and the equation μ_st",
                neg.setpoint_relation,
                fmt_printed(neg.setpoint_rpm)
            ),
        );
    }
    // C = 2 ξ √(J1 K) (text under Eq. 4-9) with Table 4.5's J1, K: the printed ξ against Eq. 4-2b's.
    let m42 = t.table_4_2.iter().find(|r| r.trial == "mean").ok_or_else(|| missing_row("table-4-2.csv", "mean"))?;
    let (j1, k1) = (t.t45("J_1")?.value, t.t45("K_s")?.value);
    let c_printed = 2.0 * m42.damping_ratio.value * (j1 * k1).sqrt();
    let c_eq = 2.0 * f::damping_ratio(m42.log_decrement.value) * (j1 * k1).sqrt();
    a.note(
        "eq-4-7",
        "C",
        "2 ξ √(J_1 K_s)",
        "not printed".into(),
        format!("{} / {}", fmt_fixed(c_printed, 5), fmt_fixed(c_eq, 5)),
        format!(
            "with Table 4.5's J_1, K_s the damping C is {c_printed:.5} N·m·s/rad from the printed mean ξ = {} but {c_eq:.5} from \
             ξ of Eq. 4-2b ({:.2} times less): the model's damping inherits Table 4.2's ξ error",
            fmt_printed(m42.damping_ratio),
            c_printed / c_eq
        ),
    );
    eq_4_9(a);
    Ok(())
}

/// Eq. 4-10's third case as printed: μ_neg if Ω1 < 0.
const EQ_4_10_NEG_RELATION: &str = "<";

/// Eq. 4-9 as printed (a transcription, no judgement): the state vector, and
/// each printed row of A as (row height, entries with their column widths;
/// −J⁻¹K and −J⁻¹C are 2×2 blocks), and F.
const EQ_4_9_Q: [&str; 5] = ["φ1", "φ2", "Ω1", "Ω2", "i"];
const EQ_4_9_A: [(usize, &[(&str, usize)]); 4] = [
    (1, &[("0", 1), ("0", 1), ("1", 1), ("0", 1), ("0", 1)]),
    (1, &[("0", 1), ("0", 1), ("0", 1), ("1", 1), ("0", 1)]),
    (2, &[("-J^-1 K", 2), ("-J^-1 C", 2), ("0", 1), ("0", 1), ("0", 1)]),
    (1, &[("0", 1), ("0", 1), ("0", 1), ("-k_e/L", 1), ("-R/L", 1)]),
];
const EQ_4_9_F: [&str; 5] = ["0", "0", "-T_1/J_1", "-T_f/J_m", "V/L"];

/// Shape and coupling of Eq. 4-9's state space against its own state vector and Eq. 4-7.
fn eq_4_9(a: &mut Audit) {
    let n = EQ_4_9_Q.len();
    let height: usize = EQ_4_9_A.iter().map(|(h, _)| h).sum();
    for (i, (_, row)) in EQ_4_9_A.iter().enumerate() {
        let width: usize = row.iter().map(|(_, w)| w).sum();
        if width != n || height != n {
            let printed: Vec<&str> = row.iter().map(|(e, _)| *e).collect();
            a.flag(
                "eq-4-9",
                &format!("A row {}", i + 1),
                "columns",
                printed.join(" "),
                format!("{width} columns for {n} states"),
                format!(
                    "A is printed {height} rows high, but this row spans {width} columns (2×2 blocks −J⁻¹K and −J⁻¹C plus three \
                     zeros) for a state vector of {n}; which block column multiplies which state is ambiguous"
                ),
            );
        }
    }
    // Eq. 4-7 drives the motor inertia with k_T i; Eq. 4-9 must carry k_T somewhere in A or F.
    let has_kt = EQ_4_9_A.iter().flat_map(|(_, r)| r.iter()).any(|(e, _)| e.contains("k_T"))
        || EQ_4_9_F.iter().any(|e| e.contains("k_T"));
    if !has_kt {
        a.flag(
            "eq-4-9",
            "A, F",
            "k_T i",
            format!("F = [{}]", EQ_4_9_F.join(", ")),
            "no k_T term".into(),
            "Eq. 4-7's motor torque k_T i appears nowhere in Eq. 4-9's A or F, so in the printed state space the current i \
             never drives Ω2 (and the motor equation 4-6b is decoupled from the mechanics)"
                .into(),
        );
    }
}

fn table_4_8(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
    for r in &t.table_4_8 {
        a.check(
            Check {
                table: "table-4-8",
                row: &r.peak,
                column: "freq_rad_s",
                published: r.freq_rad_s,
                inputs: vec![rounded(r.freq_hz)],
                what: "2π × the printed Hz",
            },
            &|x| f::hz_to_rad_s(x[0]),
            &|v| format!("2π·{} = {v:.4} rad/s", fmt_printed(r.freq_hz)),
        );
    }
    // Captions of Figs. 4.27–4.29 quote ω_p: find the Table 4.8 row each matches and in which unit.
    for id in ["fig-4-27-omega-p", "fig-4-28-omega-p", "fig-4-29-omega-p"] {
        let s = t.statement(id)?;
        let cap = s.value;
        let same = |p: Printed| (p.value - cap.value).abs() <= 0.5 * cap.unit();
        let hit_rad = t.table_4_8.iter().find(|r| same(r.freq_rad_s));
        let hit_hz = t.table_4_8.iter().find(|r| same(r.freq_hz));
        let fig = id.trim_end_matches("-omega-p");
        let (status_ok, rec, reason) = match (s.unit.as_str(), hit_rad, hit_hz) {
            ("rad/s", Some(r), _) => {
                (true, fmt_printed(r.freq_rad_s), format!("matches Table 4.8 peak {} in rad/s", r.peak))
            }
            ("Hz", _, Some(r)) => (true, fmt_printed(r.freq_hz), format!("matches Table 4.8 peak {} in Hz", r.peak)),
            ("Hz", Some(r), None) => (
                false,
                format!("{} Hz", fmt_printed(r.freq_hz)),
                format!(
                    "the caption's {} Hz is Table 4.8's peak {} in rad/s; in Hz that peak is {}, and {} Hz would be {:.1} rad/s, \
                     outside the FRF peaks",
                    fmt_printed(cap),
                    r.peak,
                    fmt_printed(r.freq_hz),
                    fmt_printed(cap),
                    f::hz_to_rad_s(cap.value)
                ),
            ),
            ("rad/s", None, Some(r)) => (
                false,
                format!("{} rad/s", fmt_printed(r.freq_rad_s)),
                format!("the caption's {} rad/s is Table 4.8's peak {} in Hz", fmt_printed(cap), r.peak),
            ),
            _ => (false, "no peak".into(), format!("{} {} matches no row of Table 4.8", fmt_printed(cap), s.unit)),
        };
        a.rows.push(AuditRow {
            table: fig.into(),
            row: "caption".into(),
            column: format!("omega_p [{}]", s.unit),
            published: fmt_printed(cap),
            recomputed: rec,
            status: if status_ok { Status::Ok } else { Status::Inconsistent },
            reason,
        });
    }
    // "≃ 0.4 Hz experimental": the lowest FRF peak of Table 4.8, at the statement's precision.
    let fexp = t.statement("freq-experimental")?.value;
    let lowest = t.table_4_8.iter().map(|r| r.freq_hz).min_by(|x, y| x.value.total_cmp(&y.value));
    if let Some(low) = lowest {
        a.check(
            Check {
                table: "statement",
                row: "freq-experimental",
                column: "vs lowest Table 4.8 peak",
                published: fexp,
                inputs: vec![rounded(low)],
                what: "the lowest frequency peak of Table 4.8 (the FRF of Fig. 4.26)",
            },
            &|x| x[0],
            &|v| format!("the lowest peak is {v:.3} Hz"),
        );
    }
    Ok(())
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
