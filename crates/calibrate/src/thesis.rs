//! The thesis side: Eqs. 4-1, 4-4, 4-5 and Tables 4.2, 4.3, 4.6 recomputed
//! from their published inputs (with the least-squares fits the chapter did
//! not print), and [`ThesisData`], the parameters downstream stages use.

use crate::formulas as f;
use crate::published::{PublishedTables, ThesisTables};
use crate::stats::{self, LineFit};
use crate::{CalibrateError, audit};
pub use rig_types::contract::{FrequencyPeak, ThesisData};
use rig_types::{MotorParams, Table, ThesisFriction, fmt_fixed};

/// Confidence of every interval in the thesis tables.
pub const CONFIDENCE: f64 = 0.95;

fn motor(
    t: &ThesisTables,
    get: fn(&ThesisTables, &str) -> Result<crate::published::Printed, CalibrateError>,
) -> Result<MotorParams, CalibrateError> {
    Ok(MotorParams {
        inertia_kgm2: get(t, "J_m")?.value,
        inductance_h: get(t, "L_DC")?.value,
        resistance_ohm: get(t, "R_DC")?.value,
        torque_constant_nm_a: get(t, "k_T")?.value,
        voltage_constant_v_s_rad: get(t, "k_e")?.value,
        friction_torque_nm: get(t, "T_f")?.value,
        speed_regulation_nm_s_rad: get(t, "C_m")?.value,
        gear_ratio: 1.0,
    })
}

fn mean_row<'a, R>(rows: &'a [R], trial: impl Fn(&R) -> &str, table: &str) -> Result<&'a R, CalibrateError> {
    rows.iter()
        .find(|r| trial(r) == "mean")
        .ok_or_else(|| CalibrateError::Published { table: table.into(), reason: "row `mean` is missing".into() })
}

/// Collects [`ThesisData`] from the published tables.
pub fn thesis_data(t: &ThesisTables) -> Result<ThesisData, CalibrateError> {
    let m42 = mean_row(&t.table_4_2, |r| &r.trial, "table-4-2.csv")?;
    let (j1, k) = (t.t45("J_1")?.value, t.t45("K_s")?.value);
    let xi = m42.damping_ratio.value;
    let xi_rec = f::damping_ratio(m42.log_decrement.value);
    let (st, dy, ng) = (t.friction("mu_st")?, t.friction("mu_dyn")?, t.friction("mu_neg")?);
    Ok(ThesisData {
        motor_initial: motor(t, ThesisTables::t44)?,
        motor_estimated: motor(t, ThesisTables::t45)?,
        rotor_inertia_kgm2: j1,
        shaft_stiffness_nm_rad: k,
        rotor_inertia_initial_kgm2: t.t44("J_1")?.value,
        shaft_stiffness_initial_nm_rad: t.t44("K_s")?.value,
        damping_ratio: xi,
        damping_ratio_recomputed: xi_rec,
        shaft_damping_nm_s_rad: 2.0 * xi * (j1 * k).sqrt(),
        shaft_damping_recomputed_nm_s_rad: 2.0 * xi_rec * (j1 * k).sqrt(),
        damped_frequency_hz: m42.damped_hz.value,
        natural_frequency_hz: m42.natural_hz.value,
        k_sa_nm_rad: t.statement("eq-4-1")?.value.value,
        j1e_kgm2: t.statement("eq-4-4")?.value.value,
        j1a_kgm2: t.statement("eq-4-5")?.value.value,
        friction: ThesisFriction {
            mu_static: st.value.value,
            mu_dynamic: dy.value.value,
            mu_negative: ng.value.value,
            tolerance: t.statement("tol")?.value.value,
            static_setpoint_rpm: st.setpoint_rpm.value,
            dynamic_setpoint_rpm: dy.setpoint_rpm.value,
        },
        brake_disc_radius_m: t.statement("brake-radius")?.value.value,
        peaks: t
            .table_4_8
            .iter()
            .map(|p| FrequencyPeak { freq_hz: p.freq_hz.value, omega_rad_s: p.freq_rad_s.value })
            .collect(),
        gear_ratio: t.statement("gear-ratio")?.value.value,
        step_voltage_v: t.statement("step-voltage")?.value.value,
        step_speed_rad_s: t.statement("step-speed")?.value.value,
        oscillation_experimental_hz: t.statement("freq-experimental")?.value.value,
        oscillation_numerical_hz: t.statement("freq-numerical")?.value.value,
        encoder_ticks_per_rev: t.statement("encoder-resolution")?.value.value,
        labelled_points: t.labelled_points.clone(),
    })
}

/// Eq. 4-1 step by step from Table 4.1.
pub fn eq_4_1_table(t: &ThesisTables) -> Result<Table, CalibrateError> {
    let (e, nu, d, l) =
        (t.t41("E")?.value * 1e9, t.t41("nu")?.value, t.t41("D_s")?.value * 1e-3, t.t41("L_s")?.value * 1e-3);
    let g = f::shear_modulus_pa(e, nu);
    let i = f::polar_moment_m4(d);
    let k = f::shaft_stiffness_nm_rad(g, i, l);
    let mut tab = Table::new(["quantity", "equation", "recomputed", "published"]);
    tab.push(["shear_modulus_gpa", "G = E/(2(1+nu))", &fmt_fixed(g * 1e-9, 3), ""]);
    tab.push(["polar_moment_m4_e12", "I_s = pi D^4/32", &fmt_fixed(i * 1e12, 4), ""]);
    tab.push([
        "k_sa_nm_rad",
        "K_sA = G I_s/L_s (Eq. 4-1)",
        &fmt_fixed(k, 5),
        &fmt_fixed(t.statement("eq-4-1")?.value.value, 3),
    ]);
    Ok(tab)
}

/// Table 4.2 recomputed: δ by Eq. 4-2a, ξ by Eq. 4-2b, ω_n by Eq. 4-3 (from the printed and the recomputed ξ), ω in rad/s.
pub fn table_4_2(t: &ThesisTables) -> Table {
    let mut tab = Table::new([
        "trial",
        "x1_rad",
        "x2_rad",
        "log_decrement_published",
        "log_decrement",
        "damping_ratio_published",
        "damping_ratio",
        "damped_hz",
        "natural_hz_published",
        "natural_hz_from_published_xi",
        "natural_hz",
        "natural_rad_s",
    ]);
    for r in &t.table_4_2 {
        let delta = f::log_decrement(r.x1_rad.value, r.x2_rad.value);
        let xi = f::damping_ratio(delta);
        let wn = f::natural_from_damped(r.damped_hz.value, xi);
        tab.push([
            r.trial.clone(),
            fmt_fixed(r.x1_rad.value, 3),
            fmt_fixed(r.x2_rad.value, 3),
            fmt_fixed(r.log_decrement.value, 3),
            fmt_fixed(delta, 4),
            fmt_fixed(r.damping_ratio.value, 3),
            fmt_fixed(xi, 4),
            fmt_fixed(r.damped_hz.value, 3),
            fmt_fixed(r.natural_hz.value, 3),
            fmt_fixed(f::natural_from_damped(r.damped_hz.value, r.damping_ratio.value), 4),
            fmt_fixed(wn, 4),
            fmt_fixed(f::hz_to_rad_s(wn), 4),
        ]);
    }
    tab
}

/// Eqs. 4-4 and 4-5 and the "1.39 %" statement, published against recomputed.
pub fn eq_4_4_4_5_table(t: &ThesisTables) -> Result<Table, CalibrateError> {
    let m42 = mean_row(&t.table_4_2, |r| &r.trial, "table-4-2.csv")?;
    let ksa = t.statement("eq-4-1")?.value.value;
    let (j1e_p, j1a_p) = (t.statement("eq-4-4")?.value.value, t.statement("eq-4-5")?.value.value);
    let wn = f::hz_to_rad_s(m42.natural_hz.value);
    let j1e = f::inertia_from_frequency_kgm2(ksa, wn);
    let j1a = f::disc_inertia_kgm2(t.t41("M_r1")?.value, t.t41("R_r1")?.value * 1e-3);
    let mut tab = Table::new(["quantity", "equation", "published", "recomputed"]);
    tab.push(["natural_rad_s".to_string(), "2 pi x mean omega_n (Table 4.2)".into(), String::new(), fmt_fixed(wn, 4)]);
    tab.push(["j1e_kgm2".to_string(), "K_sA/omega_n^2 (Eq. 4-4)".into(), fmt_fixed(j1e_p, 4), fmt_fixed(j1e, 5)]);
    tab.push(["j1a_kgm2".to_string(), "M R^2/2 (Eq. 4-5)".into(), fmt_fixed(j1a_p, 4), fmt_fixed(j1a, 5)]);
    tab.push([
        "rel_error_pct".to_string(),
        "|J1E - J1A|/J1A, published J".into(),
        fmt_fixed(t.statement("rel-error-j1")?.value.value, 2),
        fmt_fixed(f::relative_error_pct(j1e_p, j1a_p), 3),
    ]);
    tab.push([
        "rel_error_pct_recomputed_j".to_string(),
        "|J1E - J1A|/J1A, recomputed J".into(),
        String::new(),
        fmt_fixed(f::relative_error_pct(j1e, j1a), 2),
    ]);
    Ok(tab)
}

/// The Table 4.3 trials as (angle, torque) points.
pub fn table_4_3_points(t: &ThesisTables) -> Vec<(f64, f64)> {
    t.table_4_3.iter().filter_map(|r| Some((r.angle_rad?.value, r.torque_nm?.value))).collect()
}

/// The Table 4.6 trials as (weight, voltage) points.
pub fn table_4_6_points(t: &ThesisTables) -> Vec<(f64, f64)> {
    t.table_4_6.iter().filter_map(|r| Some((r.weight_n?.value, r.voltage_mv?.value))).collect()
}

/// Least-squares fits through the origin and with offset (95 % CI) of (x, y) points.
pub fn fits(points: &[(f64, f64)], confidence: f64) -> Result<(LineFit, LineFit), CalibrateError> {
    let (x, y): (Vec<f64>, Vec<f64>) = points.iter().copied().unzip();
    Ok((stats::fit_through_origin(&x, &y, confidence)?, stats::fit_with_offset(&x, &y, confidence)?))
}

/// Table 4.3 recomputed (K_SE = T/φ, relative error to K_sA) plus the
/// least-squares stiffness through the origin and with offset, 95 % CI.
pub fn table_4_3(t: &ThesisTables) -> Result<Table, CalibrateError> {
    let ksa = t.statement("eq-4-1")?.value.value;
    let mut tab = Table::new([
        "trial",
        "torque_nm",
        "angle_rad",
        "k_se_nm_rad_published",
        "k_se_nm_rad",
        "rel_error_pct_published",
        "rel_error_pct",
    ]);
    let mut ks = Vec::new();
    let mut es = Vec::new();
    for r in &t.table_4_3 {
        let (k, e) = match (r.torque_nm, r.angle_rad) {
            (Some(q), Some(a)) => {
                let k = f::static_stiffness_nm_rad(q.value, a.value);
                let e = f::relative_error_pct(k, ksa);
                ks.push(k);
                es.push(e);
                (fmt_fixed(k, 4), fmt_fixed(e, 3))
            }
            _ => {
                (fmt_fixed(stats::mean(&ks).unwrap_or(f64::NAN), 4), fmt_fixed(stats::mean(&es).unwrap_or(f64::NAN), 3))
            }
        };
        tab.push([
            r.trial.clone(),
            r.torque_nm.map(|p| fmt_fixed(p.value, 3)).unwrap_or_default(),
            r.angle_rad.map(|p| fmt_fixed(p.value, 3)).unwrap_or_default(),
            fmt_fixed(r.k_se_nm_rad.value, 3),
            k,
            fmt_fixed(r.rel_error_pct.value, 3),
            e,
        ]);
    }
    Ok(tab)
}

/// Table 4.6 recomputed: factor = voltage/weight per trial and their mean.
pub fn table_4_6(t: &ThesisTables) -> Table {
    let mut tab = Table::new(["trial", "weight_n", "voltage_mv", "factor_mv_per_n_published", "factor_mv_per_n"]);
    let mut fs = Vec::new();
    for r in &t.table_4_6 {
        let fac = match (r.weight_n, r.voltage_mv) {
            (Some(w), Some(v)) => {
                let x = f::force_factor_mv_per_n(v.value, w.value);
                fs.push(x);
                x
            }
            _ => stats::mean(&fs).unwrap_or(f64::NAN),
        };
        tab.push([
            r.trial.clone(),
            r.weight_n.map(|p| fmt_fixed(p.value, 3)).unwrap_or_default(),
            r.voltage_mv.map(|p| fmt_fixed(p.value, 0)).unwrap_or_default(),
            fmt_fixed(r.factor_mv_per_n.value, 3),
            fmt_fixed(fac, 3),
        ]);
    }
    tab
}

/// Appends the fit rows below a per-trial table (same columns, fit values in the ratio column),
/// so one CSV carries Table 4.3/4.6 and its regression: `trial` = fit name, ratio column = slope,
/// and the CI and intercept in the trailing columns added here.
pub fn with_fits(
    mut tab: Table,
    points: &[(f64, f64)],
    ratio_col: &str,
    dec: usize,
    icpt_unit: &str,
) -> Result<Table, CalibrateError> {
    let (o, w) = fits(points, CONFIDENCE)?;
    let col = tab
        .columns
        .iter()
        .position(|c| c == ratio_col)
        .ok_or_else(|| CalibrateError::Domain(format!("no column {ratio_col}")))?;
    let base = tab.columns.len();
    tab.columns.extend([
        format!("{ratio_col}_ci95_low"),
        format!("{ratio_col}_ci95_high"),
        format!("intercept_{icpt_unit}"),
        format!("intercept_{icpt_unit}_ci95_low"),
        format!("intercept_{icpt_unit}_ci95_high"),
    ]);
    for row in &mut tab.rows {
        row.extend(std::iter::repeat_n(String::new(), 5));
    }
    for (name, fit) in [("least_squares_through_origin", &o), ("least_squares_with_offset", &w)] {
        let mut row = vec![String::new(); base + 5];
        row[0] = name.to_string();
        row[col] = fmt_fixed(fit.slope, dec);
        row[base] = fmt_fixed(fit.slope_ci[0], dec);
        row[base + 1] = fmt_fixed(fit.slope_ci[1], dec);
        if !fit.through_origin {
            row[base + 2] = fmt_fixed(fit.intercept, dec);
            row[base + 3] = fmt_fixed(fit.intercept_ci[0], dec);
            row[base + 4] = fmt_fixed(fit.intercept_ci[1], dec);
        }
        tab.push(row);
    }
    Ok(tab)
}

/// Everything the `thesis-tables` stage writes, computed purely.
pub struct ThesisOutputs {
    pub eq_4_1: Table,
    pub table_4_2: Table,
    pub eq_4_4_4_5: Table,
    pub table_4_3: Table,
    pub table_4_6: Table,
    pub audit_rows: Vec<audit::AuditRow>,
    pub data: ThesisData,
    pub stiffness_fits: (LineFit, LineFit),
    pub force_fits: (LineFit, LineFit),
}

pub fn thesis_outputs(t: &ThesisTables, rounding_tolerance: f64) -> Result<ThesisOutputs, CalibrateError> {
    let p43 = table_4_3_points(t);
    let p46 = table_4_6_points(t);
    Ok(ThesisOutputs {
        eq_4_1: eq_4_1_table(t)?,
        table_4_2: table_4_2(t),
        eq_4_4_4_5: eq_4_4_4_5_table(t)?,
        table_4_3: with_fits(table_4_3(t)?, &p43, "k_se_nm_rad", 4, "nm")?,
        table_4_6: with_fits(table_4_6(t), &p46, "factor_mv_per_n", 3, "mv")?,
        audit_rows: audit::audit(t, rounding_tolerance)?,
        data: thesis_data(t)?,
        stiffness_fits: fits(&p43, CONFIDENCE)?,
        force_fits: fits(&p46, CONFIDENCE)?,
    })
}
