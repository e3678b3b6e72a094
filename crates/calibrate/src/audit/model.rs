//! Audit checks of the model and results (§4.2, 4.5, 4.6): the 8 V ≈ 16 rad/s
//! statement against Eq. 4-6, Table 4.5 vs 4.4, Table 4.7 vs Eq. 4-10, Eq. 4-9's
//! shape, Table 4.8 and the figure captions that quote it.

use super::{Audit, AuditRow, Check, Status, exact, fmt_printed, missing_row, rounded};
use crate::CalibrateError;
use crate::formulas::{self as f};
use crate::published::{Printed, PublishedTables, ThesisTables};
use rig_types::fmt_fixed;
use std::f64::consts::PI;

pub(super) fn motor_and_friction(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
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
    let tol_rad_s_in_rpm = rig_types::units::rad_s_to_rpm(tol);
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

pub(super) fn table_4_8(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
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
