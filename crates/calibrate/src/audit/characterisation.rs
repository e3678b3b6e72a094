//! Audit checks of the characterisation (§4.3–4.4): Eqs. 4-1, 4-4, 4-5 and
//! the "1.39 %" statement, Tables 4.2, 4.3 and 4.6.

use super::{Audit, Check, In, exact, fmt_printed, missing_row, rounded, val};
use crate::formulas::{self as f};
use crate::published::{Printed, PublishedTables, ThesisTables};
use crate::{CalibrateError, stats};
use rig_types::fmt_fixed;
use std::f64::consts::PI;

fn k_sa(x: &[f64]) -> f64 {
    // x = [E GPa, ν, D mm, L mm]
    f::shaft_stiffness_nm_rad(f::shear_modulus_pa(x[0] * 1e9, x[1]), f::polar_moment_m4(x[2] * 1e-3), x[3] * 1e-3)
}

pub(super) fn eq_4_1_to_4_5(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
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
    // Signed relative error (x − ref)/ref in %; check_abs takes its magnitude.
    let rel_ref_a = |x: &[f64]| 100.0 * (x[0] - x[1]) / x[1];
    a.check_abs(
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
    a.check_abs(
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
    a.check_abs(
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

pub(super) fn table_4_2(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
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

pub(super) fn table_4_3(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
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
        a.check_abs(
            Check {
                table: "table-4-3",
                row: tr,
                column: "rel_error_pct",
                published: r.rel_error_pct,
                inputs: vec![rounded(r.k_se_nm_rad), rounded(ksa)],
                what: "|K_SE − K_sA|/K_sA from the printed K_SE and K_sA = 0.268",
            },
            &|x| 100.0 * (x[0] - x[1]) / x[1],
            &|v| format!("gives {v:.3} %"),
        );
        a.check_abs(
            Check {
                table: "table-4-3",
                row: tr,
                column: "rel_error_pct (K_SE = torque/angle)",
                published: r.rel_error_pct,
                inputs: vec![rounded(tq), rounded(ang), rounded(ksa)],
                what: "|torque/angle − K_sA|/K_sA",
            },
            &|x| 100.0 * (x[0] / x[1] - x[2]) / x[2],
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

pub(super) fn table_4_6(a: &mut Audit, t: &ThesisTables) -> Result<(), CalibrateError> {
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
