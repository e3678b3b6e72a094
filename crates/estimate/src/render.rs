//! A [`RigEstimate`] as artifacts: the CSV tables, Figs. 4.11/4.12 as
//! `FigureSpec`s and the estimation report in Markdown. Pure functions;
//! the pipeline stage writes them. Numbers are printed to the precision
//! their standard errors support (two significant digits of the error).

use crate::fit_stats::Identifiability;
use crate::options::EstimateOptions;
use crate::rig::RigEstimate;
use crate::steps::StepResidual;
use rig_types::{FigureSpec, Series, SeriesStyle, Table, fmt_fixed};
use std::fmt::Write;

/// Decimals that show `sig` significant digits of `x`.
pub fn sig_decimals(x: f64, sig: i32) -> usize {
    if !x.is_finite() || x == 0.0 {
        return sig.max(0) as usize;
    }
    (sig - 1 - x.abs().log10().floor() as i32).clamp(0, 12) as usize
}

/// A value at the precision of its standard error (2 digits of the error),
/// or 4 significant digits without one.
fn value_text(x: f64, se: Option<f64>) -> String {
    match se.filter(|s| s.is_finite() && *s > 0.0) {
        Some(s) => fmt_fixed(x, sig_decimals(s, 2)),
        None => fmt_fixed(x, sig_decimals(x, 4)),
    }
}

fn se_text(se: Option<f64>) -> String {
    se.filter(|s| s.is_finite()).map_or(String::new(), |s| fmt_fixed(s, sig_decimals(s, 2)))
}

/// `tables/campaign-estimation.csv`: every estimated or held quantity.
pub fn estimation_table(e: &RigEstimate) -> Table {
    let mut t = Table::new(["parameter", "table_4_4", "initial", "estimate", "stderr", "unit", "identifiable"]);
    for p in &e.report.params {
        let t44 = e.table_4_4.iter().find(|(n, _)| *n == p.name).and_then(|(_, v)| *v);
        t.push([
            p.name.clone(),
            t44.map_or(String::new(), |v| fmt_fixed(v, sig_decimals(v, 4))),
            value_text(p.initial, None),
            value_text(p.estimate, p.stderr),
            se_text(p.stderr),
            p.unit.clone(),
            p.identifiable.flag(),
        ]);
    }
    let pi = &e.pi;
    let fr = &e.friction;
    let rows: [(&str, f64, Option<f64>, &str, String); 4] = [
        ("kp", pi.kp_v_s_rad, Some(pi.kp_stderr), "V s/rad", "yes (operating points)".into()),
        ("ki", pi.ki_v_rad, Some(pi.ki_stderr), "V/rad", "yes (operating points)".into()),
        ("mu_static", fr.mu_static, fr.mu_static_stderr, "", format!("{} stick episodes", fr.n_stick_episodes)),
        ("mu_kinetic", fr.mu_kinetic, fr.mu_kinetic_stderr, "", format!("{} slipping runs", fr.n_slip_runs)),
    ];
    for (name, v, se, unit, flag) in rows {
        t.push([name.to_string(), String::new(), String::new(), value_text(v, se), se_text(se), unit.into(), flag]);
    }
    t
}

/// `tables/campaign-estimation-correlation.csv`: correlation of the estimated parameters.
pub fn correlation_table(e: &RigEstimate) -> Table {
    let mut cols = vec!["parameter".to_string()];
    cols.extend(e.report.estimated.iter().cloned());
    let mut t = Table::new(cols);
    for (name, row) in e.report.estimated.iter().zip(&e.report.correlation) {
        let mut r = vec![name.clone()];
        r.extend(row.iter().map(|v| if v.is_finite() { fmt_fixed(*v, 3) } else { "nan".into() }));
        t.push(r);
    }
    t
}

/// `tables/campaign-estimation-validation.csv`: per step and channel.
pub fn validation_table(e: &RigEstimate) -> Table {
    let mut t = Table::new(["run", "voltage_v", "role", "channel", "fit_percent", "nrmse"]);
    for (r, s) in e.report.runs.iter().zip(&e.steps) {
        for c in &r.channels {
            t.push([
                r.run.clone(),
                fmt_fixed(s.voltage_v, 3),
                if r.used { "estimation".into() } else { "held-out".to_string() },
                c.channel.clone(),
                fmt_fixed(c.fit_percent, 2),
                fmt_fixed(c.nrmse, 4),
            ]);
        }
    }
    t
}

/// `tables/campaign-estimation-history.csv`: SSR per iteration (Fig. 4.12's data).
pub fn history_table(e: &RigEstimate) -> Table {
    let mut t = Table::new(["iteration", "ssr", "lambda", "evaluations"]);
    let d = sig_decimals(e.report.ssr, 4);
    for h in &e.report.history {
        t.push([h.iteration.to_string(), fmt_fixed(h.ssr, d), format!("{:.3e}", h.lambda), h.evaluations.to_string()]);
    }
    t
}

/// The step shown in Fig. 4.11: the held-out step closest to 8 V (the
/// thesis' Fig. 4.8 voltage), else the used one closest to 8 V.
fn figure_step(e: &RigEstimate) -> Option<usize> {
    let closest = |held: bool| {
        (0..e.steps.len())
            .filter(|&i| e.steps[i].used != held)
            .min_by(|&a, &b| (e.steps[a].voltage_v - 8.0).abs().total_cmp(&(e.steps[b].voltage_v - 8.0).abs()))
    };
    closest(true).or_else(|| closest(false))
}

/// Fig. 4.11: measured (blue in the thesis) vs estimated (red) response of a voltage step.
pub fn fig_4_11(e: &RigEstimate) -> Option<FigureSpec> {
    let s = &e.steps[figure_step(e)?];
    let fit = e.report.runs.iter().find(|r| r.run == s.run)?;
    let fits: Vec<String> =
        fit.channels.iter().map(|c| format!("{} {:.1} %", c.channel.replace('_', " "), c.fit_percent)).collect();
    let series = |name: &str, y: &[f64], style| Series { name: name.into(), x: s.time_s.clone(), y: y.to_vec(), style };
    Some(FigureSpec {
        id: "fig-4-11".into(),
        title: format!("Fig. 4.11 (campaign): voltage step {} ({:.2} V), measured and estimated", s.run, s.voltage_v),
        caption: format!(
            "Window-mean speeds over {} ms from the encoder angles (measured) and the same operator on the rig model \
             simulated with the estimated parameters and the mean recorded voltage (estimated). Run {} was {} the \
             estimation. Fit in simulation: {}.",
            ((s.time_s.get(1).copied().unwrap_or(0.0) - s.time_s.first().copied().unwrap_or(0.0)) * 1000.0).round(),
            s.run,
            if s.used { "used in" } else { "held out of" },
            fits.join(", ")
        ),
        x_label: "time [s]".into(),
        y_label: "speed [rad/s]".into(),
        series: vec![
            series("rotor speed Ω1, measured", &s.rotor_speed_meas_rad_s, SeriesStyle::Line),
            series("rotor speed Ω1, estimated model", &s.rotor_speed_sim_rad_s, SeriesStyle::Dashed),
            series("motor-side speed Ω2, measured", &s.motor_speed_meas_rad_s, SeriesStyle::Line),
            series("motor-side speed Ω2, estimated model", &s.motor_speed_sim_rad_s, SeriesStyle::Dashed),
        ],
        x_decimals: 3,
        y_decimals: 3,
        heatmap: None,
    })
}

/// Fig. 4.12: misfit (SSR) vs iteration.
pub fn fig_4_12(e: &RigEstimate) -> FigureSpec {
    let h = &e.report.history;
    FigureSpec {
        id: "fig-4-12".into(),
        title: "Fig. 4.12 (campaign): convergence of the misfit function".into(),
        caption: format!(
            "Sum of squared residuals of the voltage-step fit after each Levenberg–Marquardt iteration (iteration 0 is \
             Table 4.4 with J1, K from the campaign calibration). {} after {} iterations ({}).",
            if e.report.converged { "Converged" } else { "Not converged" },
            e.report.iterations,
            e.report.stop_reason
        ),
        x_label: "iteration".into(),
        y_label: "misfit (SSR)".into(),
        series: vec![Series {
            name: "SSR".into(),
            x: h.iter().map(|r| r.iteration as f64).collect(),
            y: h.iter().map(|r| r.ssr).collect(),
            style: SeriesStyle::Markers,
        }],
        x_decimals: 0,
        y_decimals: sig_decimals(e.report.ssr, 4),
        heatmap: None,
    }
}

fn md_table(t: &Table) -> String {
    let mut s = format!("| {} |\n|{}\n", t.columns.join(" | "), "---|".repeat(t.columns.len()));
    for r in &t.rows {
        let _ = writeln!(s, "| {} |", r.join(" | "));
    }
    s
}

/// `estimation.md`: the identification in prose and tables.
pub fn report_markdown(e: &RigEstimate, campaign: &str, o: &EstimateOptions) -> String {
    let r = &e.report;
    let mut s = String::new();
    let used: Vec<String> =
        e.steps.iter().filter(|x| x.used).map(|x| format!("{} ({:.2} V)", x.run, x.voltage_v)).collect();
    let held: Vec<String> =
        e.steps.iter().filter(|x| !x.used).map(|x| format!("{} ({:.2} V)", x.run, x.voltage_v)).collect();
    let _ = writeln!(s, "# Estimation: campaign {campaign}\n");
    let _ = writeln!(
        s,
        "Least-squares identification of the rig model (thesis §4.3.2, Table 4.4 → Table 4.5) on the open-brake \
         voltage steps, PI gains and baseline Coulomb friction from the operating points. Blind: only the recordings, \
         campaign.toml and the campaign calibration are read.\n"
    );
    let _ = writeln!(s, "## Voltage steps\n");
    let _ = writeln!(
        s,
        "- Estimation on: {}. Held out for validation: {}. Rule: {}.",
        used.join(", "),
        if held.is_empty() { "none".into() } else { held.join(", ") },
        if o.holdout.is_some() {
            "run ids from pipeline.toml"
        } else {
            "estimate on the lowest and highest voltage, validate on the ones in between"
        }
    );
    let _ = writeln!(
        s,
        "- Model: rig_model::simulate (Eqs. 4-6, 4-7, gear n = {} explicit, string damping on the twist rate), input the \
         mean recorded armature voltage of each step, from rest.",
        o.gear_ratio
    );
    let _ = writeln!(
        s,
        "- Residuals: {}, every {} s, both encoders.",
        match o.step_residual {
            StepResidual::Angle =>
                "encoder angles (motor side and rotor 1) minus simulated angles (maximum likelihood if \
                                    the residual is the encoder quantisation)",
            StepResidual::Speed => "window-mean speeds (angle differences over the window) of measurement and model",
        },
        o.speed_window_s
    );
    let _ = writeln!(
        s,
        "- Solver: {:?}, central finite-difference Jacobian in log-parameters; {} after {} iterations ({}). \
         {} residuals, SSR = {:.6e}, σ = {:.4e}, AIC = {:.1}, BIC = {:.1}.\n",
        o.solver_kind,
        if r.converged { "converged" } else { "NOT converged" },
        r.iterations,
        r.stop_reason,
        r.n_residuals,
        r.ssr,
        r.sigma2.sqrt(),
        r.aic,
        r.bic
    );
    let _ = writeln!(s, "{}", md_table(&estimation_table(e)));
    let _ = writeln!(
        s,
        "**What the data separate.** With L → 0 the shaft sees n·k_T/R·V − n²(k_T k_e/R + C_m)·Ω2 − n·T_f, inertias \
         n²J_m and J1, and the string. R enters only through k_T/R and C_m only through k_e + R·C_m/k_T, so R and C_m \
         are held at Table 4.4 and k_T, k_e carry the combinations (their values are meaningful only together with the \
         held R, C_m). L/R is about one sample interval (L held). The gear n only scales n·k_T, n·k_e, n²J_m (held at \
         the thesis' 8:1). Multiplying all torque-like parameters by one factor leaves the motion unchanged, so K_s is \
         held at the static-twist calibration and its relative error is added in quadrature to the standard errors of \
         J_m, k_T, T_f, J1 and C. The `identifiable` column gives, for each held parameter, the correlation and \
         standard error it would have if freed alone (computed, not assumed).\n"
    );
    let m = &e.params.motor;
    let n = m.gear_ratio;
    let _ = writeln!(s, "Shaft-side combinations (comparable with Table 4.5, whose model has n = 1):\n");
    let _ = writeln!(s, "| combination | estimate | unit |\n|---|---|---|");
    let _ = writeln!(s, "| n·k_T/R | {:.4} | N m/V |", n * m.torque_constant_nm_a / m.resistance_ohm);
    let _ = writeln!(
        s,
        "| n²(k_T k_e/R + C_m) | {:.4} | N m s/rad |",
        n * n * (m.torque_constant_nm_a * m.voltage_constant_v_s_rad / m.resistance_ohm + m.speed_regulation_nm_s_rad)
    );
    let _ = writeln!(s, "| n·T_f | {:.4} | N m |", n * m.friction_torque_nm);
    let _ = writeln!(s, "| n²·J_m | {:.5} | kg m^2 |\n", n * n * m.inertia_kgm2);
    if r.flagged_pairs.is_empty() {
        let _ = writeln!(s, "No pair of estimated parameters has |ρ| > 0.9.\n");
    } else {
        let pairs: Vec<String> = r.flagged_pairs.iter().map(|(a, b, c)| format!("{a}–{b} (ρ = {c:.3})")).collect();
        let _ = writeln!(
            s,
            "Pairs with |ρ| > 0.9, not separately identifiable in the strict sense (their standard errors, which \
             account for the correlation, say how well each is still determined): {}.\n",
            pairs.join(", ")
        );
    }
    let w = &r.whiteness;
    let _ = writeln!(
        s,
        "Residual whiteness (lags 1–{} windows, per channel and step): {:.0} % of the autocorrelations outside ±2.58/√N \
         = ±{:.4}; Ljung–Box Q = {:.1} against the 99 % critical value {:.1} of χ²({}): the residuals are {}.\n",
        w.max_lag,
        100.0 * w.fraction_outside,
        w.bound,
        w.ljung_box_q,
        w.ljung_box_critical_99,
        w.max_lag,
        if w.ljung_box_q > w.ljung_box_critical_99 {
            "not white (structure the model leaves unexplained, or the deterministic encoder quantisation at constant speed)"
        } else {
            "compatible with white noise"
        }
    );
    let _ = writeln!(s, "### Fit in simulation, estimation and held-out steps\n\n{}", md_table(&validation_table(e)));
    let md = &e.modes;
    let _ = writeln!(s, "### Damping and natural frequency against the log decrement\n");
    let _ = writeln!(s, "| source | ω_n [rad/s] | ξ |\n|---|---|---|");
    let _ = writeln!(
        s,
        "| log decrement of the same steps (campaign calibration, Eqs. 4-2, 4-3) | {:.4} ± {:.4} | {:.4} ± {:.4} |",
        md.log_decrement_natural_rad_s,
        md.log_decrement_natural_rad_s_stderr,
        md.log_decrement_damping_ratio,
        md.log_decrement_damping_ratio_stderr
    );
    if let (Some(w), Some(x)) = (md.coupled_natural_rad_s, md.coupled_damping_ratio) {
        let _ = writeln!(s, "| fitted model, coupled mode (motor side free, damped by the drive) | {w:.4} | {x:.4} |");
    }
    let _ = writeln!(
        s,
        "| fitted model, motor side held fixed: √(K/J1), C/(2√(J1 K)) | {:.4} | {:.4} |\n",
        md.fixed_base_natural_rad_s, md.fixed_base_damping_ratio
    );
    let _ = writeln!(
        s,
        "The log decrement measures the decay of the coupled torsional mode. The motor side is not fixed: it is \
         coupled to ground through the back-EMF and the speed-regulation damping n²(k_T k_e/R + C_m), so energy of the \
         twist oscillation also leaves through the motor. The string's own damping C therefore gives a smaller ξ \
         (motor side fixed) than the decay shows; the coupled mode of the fitted model is what the log decrement \
         should be compared with, and the chapter's C = 2ξ√(J1 K) (Eq. 4-7 text) attributes all of the decay to the string.\n"
    );
    let pi = &e.pi;
    let _ = writeln!(s, "## Drive PI gains (operating points)\n");
    let _ = writeln!(
        s,
        "V = kp·e + ki·∫e + c_k, e = Ω_ref − Ω2, Ω_ref the ramp 0 → set-point over ramp_s; both sides averaged over \
         windows of {} s, ∫e = ∫Ω_ref − φ2 from the encoder (no derivative), ē from angle differences. {} \
         One constant c_k per unsaturated segment and run (encoder rounding, anti-windup after saturation). Samples \
         with |V| ≥ supply − {} V are saturated: {:.2} % of all samples; {} windows, {} offsets.\n\nkp = {} ± {} V s/rad, \
         ki = {} ± {} V/rad; residual RMS {:.4} V. {}\n",
        o.pi.window_s,
        match o.pi.method {
            crate::pi::PiMethod::CorrectedLs => {
                "The encoder quantisation in ē and Ī (variance Δ²/12 per sample) would attenuate kp; its known variance \
                 is subtracted from the normal equations (corrected least squares)."
            }
            crate::pi::PiMethod::Ols => "Plain least squares (no correction for the encoder quantisation).",
            crate::pi::PiMethod::Iv => {
                "ē is instrumented by the mean error over the window widened by half a window on each side \
                 (its quantisation would otherwise attenuate kp)."
            }
        },
        o.pi.saturation_margin_v,
        100.0 * pi.saturated_fraction,
        pi.n_windows,
        pi.n_offsets,
        value_text(pi.kp_v_s_rad, Some(pi.kp_stderr)),
        se_text(Some(pi.kp_stderr)),
        value_text(pi.ki_v_rad, Some(pi.ki_stderr)),
        se_text(Some(pi.ki_stderr)),
        pi.residual_rms_v,
        match pi.voltage_plateau_v {
            Some(p) => format!(
                "The recorded |V| piles up at {p:.2} V in several runs: the drive clips there, below the nominal supply \
                 (samples within the margin of it are treated as saturated)."
            ),
            None => "No saturation plateau of |V| below the supply is seen in the records.".into(),
        }
    );
    let fr = &e.friction;
    let _ = writeln!(s, "## Baseline friction (Coulomb, Eq. 4-10 without its lookup)\n");
    let _ = writeln!(
        s,
        "The force sensor measures the tangential pad force F = (mV − offset)/factor (campaign calibration), so \
         μ = T1/(N0 r) = F/N0. μk: mean μ over slip samples, |Ω1| > {} rad/s from a centred difference over ±{} \
         s (at least twice its one-count resolution, so no stuck sample counts as slip), averaged per run and \
         pooled over {} runs ({} samples), standard error from the between-run scatter. μs: the peak μ of each stick \
         episode (≥ {} s) up to its break-away, median over {} episodes, standard error 1.2533·1.4826·MAD/√n. \
         Runs with N0 < {} N are skipped.\n\nμs = {} ± {}, μk = {} ± {}.{}\n",
        o.friction.slip_threshold_rad_s,
        o.friction.speed_half_window_s,
        fr.n_slip_runs,
        fr.n_slip_samples,
        o.friction.min_stick_s,
        fr.n_stick_episodes,
        o.friction.min_normal_force_n,
        value_text(fr.mu_static, fr.mu_static_stderr),
        se_text(fr.mu_static_stderr),
        value_text(fr.mu_kinetic, fr.mu_kinetic_stderr),
        se_text(fr.mu_kinetic_stderr),
        if fr.n_stick_episodes == 0 { " No break-away was observed: μs is set to μk." } else { "" }
    );
    let _ = writeln!(
        s,
        "These values, with drive.limit_v = the supply voltage, are data/rig-params.json (kind `rig`): the baseline \
         the diagnosis extends."
    );
    let ids: Vec<String> = r
        .params
        .iter()
        .filter(|p| matches!(p.identifiable, Identifiability::Correlated { .. }))
        .map(|p| p.name.clone())
        .collect();
    if !ids.is_empty() {
        let _ = writeln!(s, "\nCorrelated estimated parameters: {}.", ids.join(", "));
    }
    s
}
