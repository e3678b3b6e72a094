//! The recording described as before issue 10 (moved from the `lavi` stage):
//! the record as measured (dips and the repair audit), friction torque against
//! bit speed with a velocity-weakening fit, the stick-slip fundamental,
//! severity, and the study's least-squares baseline run free over the
//! calibration window.
//!
//! Only derived numbers leave here: binned curves, fits, spectra and summary
//! values.

use crate::data::derivative;
use crate::data::{Prepared, RPM_TO_RAD_S};
use crate::fit::Derivation;
use crate::render::StudyOutput;
use crate::sim::{Inputs, Model, Start, simulate};
use crate::{LaviError, StudyParams};
use rig_ingest::lavi::LaviRecording;
use rig_spectra::stickslip::{bin_means, fit_weakening, severity};
use rig_spectra::{Detrend, Window, amplitude_spectrum};
use rig_types::{SeriesStyle, Table, fmt_fixed};
use rig_types::{figure, series};
use std::fmt::Write as _;

/// The description of the calibration window (tables and figures pushed to `out`); returns its markdown.
pub fn describe(
    rec: &LaviRecording,
    d: &Prepared,
    p: &StudyParams,
    base: &Model,
    der: &Derivation,
    out: &mut StudyOutput,
) -> Result<String, LaviError> {
    let n = rec.len();
    let fs_hz = d.fs_hz;
    let glitches = d.glitches;
    let (top, bit, torque) = (&d.top_rpm, &d.bit_rpm, &d.torque_nm);
    let win: Vec<usize> =
        (0..n).filter(|&i| rec.time_s[i] >= p.window_start_s && rec.time_s[i] < p.window_end_s).collect();
    if win.len() <= 100 {
        return Err(LaviError::Params {
            key: "window_start_s",
            rule: format!(
                "the window {}-{} s holds {} samples, more than 100 needed",
                p.window_start_s,
                p.window_end_s,
                win.len()
            ),
        });
    }
    let pick = |x: &[f64]| win.iter().map(|&i| x[i]).collect::<Vec<f64>>();
    let (top_w, bit_w, tq_w) = (pick(top), pick(bit), pick(torque));

    // 3. Friction torque against bit speed (slip samples for the fit).
    let vmax = bit_w.iter().cloned().fold(0.0, f64::max);
    let bins = bin_means(&bit_w, &tq_w, 0.0, vmax * (1.0 + 1e-9), p.bins);
    let (vs, ts): (Vec<f64>, Vec<f64>) =
        bit_w.iter().zip(&tq_w).filter(|(v, _)| **v > p.slip_speed_rpm).map(|(v, t)| (*v, *t)).unzip();
    // Both shapes (exponential δ = 1, Gaussian Stribeck δ = 2); the lower rmse drives the model.
    let fit_exp = fit_weakening(&vs, &ts, 1.0, 0.5, 2000.0)?;
    let fit_gauss = fit_weakening(&vs, &ts, 2.0, 0.5, 2000.0)?;
    let wfit = if fit_gauss.rmse <= fit_exp.rmse { fit_gauss } else { fit_exp };
    // Break-away: the largest torque of each stick phase (bit speed below the slip threshold), averaged.
    let breakaway = crate::features::stick_phase_maxima(&bit_w, &tq_w, p.slip_speed_rpm);
    let breakaway_mean = mean(&breakaway);
    let fastest_bin = bins.iter().rev().find(|b| b.count > 0).map_or(f64::NAN, |b| b.mean);

    // 4. Fundamental: spectrum of the filtered bit speed, whole record and window.
    let lines_whole = line_analysis(bit, fs_hz, p.cutoff_hz)?;
    let lines_win = line_analysis(&bit_w, fs_hz, p.cutoff_hz)?;

    // 5. Severity in the window.
    let sev_bit = severity(&bit_w);
    let sev_top = severity(&top_w);

    // 6. 1-DOF model: the study's baseline (J, k, c by least squares on the window,
    // rig_lavi::fit::derive; friction from step 3), run free over the window from its measured start.
    let (dof_free, dof) = (&der.free, &der.used);
    let i0 = win[0];
    let span = i0..i0 + win.len();
    let rad = |x: &[f64]| x.iter().map(|v| v * RPM_TO_RAD_S).collect::<Vec<f64>>();
    let top_r = rad(&top[span.clone()]);
    let acc0 = derivative(&rad(&bit[span.clone()]), fs_hz)[0];
    let inputs = Inputs { fs_hz, top_rad_s: &top_r, wob_n: &d.wob_n[span.clone()], top_ref_rad_s: &top_r };
    // The baseline's contact does not follow the bit's angle: no angle needed.
    let start =
        Start { bit_rad_s: bit[i0] * RPM_TO_RAD_S, bit_acc_rad_s2: acc0, torque_nm: torque[i0], bit_angle_rad: 0.0 };
    let sim = simulate(base, &inputs, start, p.substeps)?;
    let sim_rpm: Vec<f64> = sim.bit_rad_s.iter().map(|v| v / RPM_TO_RAD_S).collect();
    let nrmse = rms(&sim_rpm.iter().zip(&bit_w).map(|(a, b)| a - b).collect::<Vec<_>>()) / rms(&bit_w);
    let sev_sim = severity(&sim_rpm);
    let lines_sim = line_analysis(&sim_rpm, fs_hz, p.cutoff_hz)?;

    // Tables.
    let mut summary = Table::new(["quantity", "value", "unit", "how"]);
    let mut row =
        |q: &str, v: String, u: &str, how: &str| summary.push([q.to_string(), v, u.to_string(), how.to_string()]);
    row("samples", n.to_string(), "", "rows of run-175.csv");
    row("sample_rate", fmt_fixed(fs_hz, 1), "Hz", "from the time column");
    row("dip_runs", glitches.runs.to_string(), "", "runs of top-speed samples flagged as dips (whole record)");
    row("dip_samples", glitches.samples.to_string(), "", "samples flagged (whole record)");
    row("dip_longest", glitches.longest_run.to_string(), "samples", "longest flagged run");
    row(
        "twist_min",
        fmt_fixed(d.twist_excursion_rad.0, 3),
        "rad",
        "raw record: min of the integral of top - bit speed",
    );
    row(
        "twist_max",
        fmt_fixed(d.twist_excursion_rad.1, 3),
        "rad",
        "raw record: max of the integral of top - bit speed",
    );
    row(
        "top_speed_noise",
        fmt_fixed(d.top_noise_rad_s, 3),
        "rad/s",
        "rms of raw - low-passed top speed outside the dips",
    );
    row("window", format!("{}-{}", p.window_start_s, p.window_end_s), "s", "the authors' calibration window");
    row("bit_speed_min", fmt_fixed(sev_bit.min, 1), "rpm", "10 Hz low-passed, window");
    row("bit_speed_max", fmt_fixed(sev_bit.max, 1), "rpm", "10 Hz low-passed, window");
    row("bit_speed_mean", fmt_fixed(sev_bit.mean, 1), "rpm", "10 Hz low-passed, window");
    row("severity_half_range", fmt_fixed(sev_bit.half_range_over_mean, 2), "", "(max-min)/(2 mean) of bit speed");
    row("severity_range", fmt_fixed(sev_bit.range_over_mean, 2), "", "(max-min)/mean of bit speed");
    row("top_severity_half_range", fmt_fixed(sev_top.half_range_over_mean, 2), "", "(max-min)/(2 mean) of top speed");
    row("fundamental_whole", opt(lines_whole.0.f0_hz, 3), "Hz", "line analysis of bit-speed spectrum, 0-59 s");
    row("fundamental_window", opt(lines_win.0.f0_hz, 2), "Hz", "line analysis of bit-speed spectrum, window");
    row("resolution_whole", fmt_fixed(lines_whole.1, 4), "Hz", "1 / record length");
    row("resolution_window", fmt_fixed(lines_win.1, 3), "Hz", "1 / window length");
    for (tag, f) in [("exp", &fit_exp), ("gauss", &fit_gauss)] {
        let how = format!("T = a + b exp(-(v/vs)^{}), slip samples (v > slip_speed_rpm)", f.shape_exponent);
        row(&format!("friction_{tag}_a"), fmt_fixed(f.a, 3), "N m", &how);
        row(&format!("friction_{tag}_b"), fmt_fixed(f.b, 3), "N m", "same fit");
        row(&format!("friction_{tag}_vs"), fmt_fixed(f.vs, 1), "rpm", "same fit");
        row(&format!("friction_{tag}_rmse"), fmt_fixed(f.rmse, 3), "N m", "residual rms");
        row(
            &format!("friction_{tag}_converged"),
            f.converged.to_string(),
            "",
            "interior optimum of vs in 0.5-2000 rpm",
        );
    }
    row("friction_constant_rmse", fmt_fixed(wfit.rmse_constant, 3), "N m", "rms about the mean slip torque");
    row("friction_law_used", fmt_fixed(wfit.shape_exponent, 0), "", "exponent of the lower-rmse fit, used below");
    row(
        "static_over_kinetic_fit",
        fmt_fixed(wfit.eval(0.0) / wfit.eval(vmax), 2),
        "",
        "T_fit(0) / T_fit(max bit speed)",
    );
    row("breakaway_torque", fmt_fixed(breakaway_mean, 3), "N m", "mean of the stick phases' maximum torque");
    row("stick_phases", breakaway.len().to_string(), "", "bit speed below slip_speed_rpm");
    row(
        "breakaway_over_fastest_bin",
        fmt_fixed(breakaway_mean / fastest_bin, 2),
        "",
        "break-away / mean torque of the fastest bin",
    );
    let mut dtab = Table::new(["quantity", "value", "stderr", "unit"]);
    dtab.push([
        "c_unconstrained".into(),
        fmt_sig(dof_free.damping_nm_s_rad),
        fmt_sig(dof_free.damping_stderr),
        "N m s/rad".to_string(),
    ]);
    dtab.push([
        "J_unconstrained".into(),
        fmt_sig(dof_free.inertia_kgm2),
        fmt_sig(dof_free.inertia_stderr),
        "kg m2".to_string(),
    ]);
    dtab.push([
        "k_unconstrained".into(),
        fmt_sig(dof_free.stiffness_nm_rad),
        fmt_sig(dof_free.stiffness_stderr),
        "N m/rad".to_string(),
    ]);
    dtab.push(["J".into(), fmt_sig(dof.inertia_kgm2), fmt_sig(dof.inertia_stderr), "kg m2".to_string()]);
    dtab.push(["k".into(), fmt_sig(dof.stiffness_nm_rad), fmt_sig(dof.stiffness_stderr), "N m/rad".to_string()]);
    dtab.push(["c".into(), fmt_sig(dof.damping_nm_s_rad), fmt_sig(dof.damping_stderr), "N m s/rad".to_string()]);
    let fnat = (dof.stiffness_nm_rad / dof.inertia_kgm2).sqrt() / (2.0 * std::f64::consts::PI);
    dtab.push(["f_n = sqrt(k/J)/2pi".into(), fmt_fixed(fnat, 2), String::new(), "Hz".to_string()]);
    dtab.push(["initial_twist".into(), fmt_fixed(dof.initial_twist_rad, 3), String::new(), "rad".to_string()]);
    dtab.push(["r_squared_accel".into(), fmt_fixed(dof.r_squared, 3), String::new(), String::new()]);
    dtab.push(["nrmse_bit_speed".into(), fmt_fixed(nrmse, 3), String::new(), "rms(sim-meas)/rms(meas)".into()]);
    for (name, m, s) in [
        ("bit_speed_min", sev_bit.min, sev_sim.min),
        ("bit_speed_max", sev_bit.max, sev_sim.max),
        ("severity_half_range", sev_bit.half_range_over_mean, sev_sim.half_range_over_mean),
    ] {
        dtab.push([format!("{name} measured/simulated"), fmt_fixed(m, 2), fmt_fixed(s, 2), String::new()]);
    }
    dtab.push([
        "fundamental measured/simulated".into(),
        opt(lines_win.0.f0_hz, 2),
        opt(lines_sim.0.f0_hz, 2),
        "Hz".into(),
    ]);
    let mut btab = Table::new(["bit_speed_lo_rpm", "bit_speed_hi_rpm", "samples", "torque_mean_nm", "torque_std_nm"]);
    for b in &bins {
        let f = |x: f64| if b.count > 0 { fmt_fixed(x, 3) } else { String::new() };
        btab.push([fmt_fixed(b.x_lo, 1), fmt_fixed(b.x_hi, 1), b.count.to_string(), f(b.mean), f(b.std)]);
    }
    let mut ltab = Table::new(["record", "freq_hz", "amplitude_rpm", "class", "relation", "error_hz", "tolerance_hz"]);
    for (name, (a, _)) in [("whole", &lines_whole), ("window", &lines_win), ("one_dof_sim", &lines_sim)] {
        for r in &a.rows {
            ltab.push([
                name.to_string(),
                fmt_fixed(r.freq_hz, 3),
                fmt_fixed(r.amplitude, 2),
                r.class.as_str().to_string(),
                r.relation.clone(),
                fmt_fixed(r.error_hz, 3),
                fmt_fixed(r.tolerance_hz, 3),
            ]);
        }
    }
    out.tables.push(("tables/lavi-summary.csv".to_string(), summary));
    out.tables.push(("tables/lavi-friction-bins.csv".to_string(), btab));
    out.tables.push(("tables/lavi-lines.csv".to_string(), ltab));
    out.tables.push(("tables/lavi-one-dof.csv".to_string(), dtab));

    // Figures (derived curves only).
    let centres: Vec<(f64, f64)> =
        bins.iter().filter(|b| b.count > 0).map(|b| (0.5 * (b.x_lo + b.x_hi), b.mean)).collect();
    let grid: Vec<f64> = (1..=100).map(|i| p.slip_speed_rpm + (vmax - p.slip_speed_rpm) * i as f64 / 100.0).collect();
    let law_exp: Vec<f64> = grid.iter().map(|v| fit_exp.eval(*v)).collect();
    let law_gauss: Vec<f64> = grid.iter().map(|v| fit_gauss.eval(*v)).collect();
    out.figures.push(figure(
        "lavi-friction",
        "LAVI run 175: bit torque against bit speed",
        &format!(
            "Torque on bit against bit speed in the authors' window {}-{} s, both low-passed at {} Hz (zero-phase FFT filter): \
             mean torque per bit-speed bin ({} bins), and the laws T = a + b exp(-(v/vs)^d) fitted to the slip samples \
             (v > {} rpm): exponential d = 1 (a = {:.3}, b = {:.3} N m, vs = {:.1} rpm, rmse {:.3} N m) and Gaussian \
             Stribeck d = 2 (a = {:.3}, b = {:.3} N m, vs = {:.1} rpm, rmse {:.3} N m).",
            p.window_start_s, p.window_end_s, p.cutoff_hz, p.bins, p.slip_speed_rpm,
            fit_exp.a, fit_exp.b, fit_exp.vs, fit_exp.rmse, fit_gauss.a, fit_gauss.b, fit_gauss.vs, fit_gauss.rmse
        ),
        ("bit speed [rpm]", 1),
        ("torque on bit [N m]", 3),
        vec![
            series("binned mean", centres.iter().map(|c| c.0).collect(), centres.iter().map(|c| c.1).collect(), SeriesStyle::Markers),
            series("fit d = 1 (exponential)", grid.clone(), law_exp, SeriesStyle::Dashed),
            series("fit d = 2 (Gaussian Stribeck)", grid, law_gauss, SeriesStyle::Line),
        ],
    ));
    let spec_whole = amplitude_spectrum(bit, fs_hz, Window::Hann, Detrend::Constant)?;
    let spec_meas = amplitude_spectrum(&bit_w, fs_hz, Window::Hann, Detrend::Constant)?;
    let spec_sim = amplitude_spectrum(&sim_rpm, fs_hz, Window::Hann, Detrend::Constant)?;
    let band = |s: &rig_spectra::Spectrum| {
        let k: Vec<usize> = (1..s.freq_hz.len()).filter(|&k| s.freq_hz[k] <= p.cutoff_hz).collect();
        (k.iter().map(|&k| s.freq_hz[k]).collect::<Vec<f64>>(), k.iter().map(|&k| s.amplitude[k]).collect::<Vec<f64>>())
    };
    let (fw, aw) = band(&spec_whole);
    out.figures.push(figure(
        "lavi-spectrum",
        "LAVI run 175: amplitude spectrum of the bit speed",
        &format!(
            "One-sided amplitude spectrum (Hann window, mean removed) of the bit speed over the whole record (0-59 s, \
             resolution {:.4} Hz) after the {} Hz low-pass, shown to the cut-off. Fundamental by line analysis: {} Hz.",
            spec_whole.resolution_hz,
            p.cutoff_hz,
            opt(lines_whole.0.f0_hz, 3)
        ),
        ("frequency [Hz]", 3),
        ("amplitude [rpm]", 3),
        vec![series("bit speed", fw, aw, SeriesStyle::Line)],
    ));
    let (fm, am) = band(&spec_meas);
    let (fsim, asim) = band(&spec_sim);
    out.figures.push(figure(
        "lavi-one-dof",
        "LAVI run 175: measured and 1-DOF bit-speed spectra",
        &format!(
            "Amplitude spectra (Hann) of the measured bit speed and of the 1-DOF model (J = {:.3e} kg m2, k = {:.3} N m/rad, \
             c = {:.3e} N m s/rad from least squares on the window; friction from the fit of lavi-friction) driven by \
             the measured, glitch-repaired top speed over {}-{} s. Time-domain NRMSE {:.2}. Spectra, not time series, \
             so that no sample of the recording is copied into the outputs.",
            dof.inertia_kgm2, dof.stiffness_nm_rad, dof.damping_nm_s_rad, p.window_start_s, p.window_end_s, nrmse
        ),
        ("frequency [Hz]", 2),
        ("amplitude [rpm]", 2),
        vec![series("measured", fm, am, SeriesStyle::Line), series("1-DOF model", fsim, asim, SeriesStyle::Dashed)],
    ));

    // lavi.md
    let mut md = String::new();
    let _ = writeln!(md, "# UFRJ LAVI 2018, run 175: stick-slip measured on a laboratory drill string\n");
    let _ = writeln!(
        md,
        "Data: Real, Lobo, Ritto, Pinto (2018), J. Petroleum Sci. Eng. 170, 755-762 (doi:10.1016/j.petrol.2018.07.008); \
         read from ../shared, never copied. Window {}-{} s and {} Hz cut-off as the authors (Lobo et al. 2020, \
         doi:10.1016/j.ijmecsci.2020.105578).\n",
        p.window_start_s, p.window_end_s, p.cutoff_hz
    );
    let _ = writeln!(md, "{}", repairs_paragraph(d, p));
    let weakening = wfit.b > 0.0 && wfit.rmse < 0.9 * wfit.rmse_constant;
    let _ = writeln!(
        md,
        "**Friction against bit speed.** Binned means (tables/lavi-friction-bins.csv) go from {:.2} N m in the lowest \
         bit-speed bin to {:.2} N m in the highest. Fits of T = a + b exp(-(v/vs)^d) on {} slip samples (v > {} rpm): \
         d = 1: a = {:.3}, b = {:.3} N m, vs = {:.1} rpm, rmse {:.3} N m{}; d = 2 (Gaussian Stribeck): a = {:.3}, \
         b = {:.3} N m, vs = {:.1} rpm, rmse {:.3} N m{}; a constant torque leaves {:.3} N m. {} With the d = {} law, \
         the static level T(0) is {:.2} × the torque at the highest bit speed ({:.0} rpm); the measured break-away \
         (mean of the {} stick phases' largest torque) is {:.3} N m, {:.2} × the mean torque of the fastest bin. The torque-speed cloud is a loop, not a curve (the std per bin is up to {:.2} N m): \
         torque at a given speed differs between acceleration and deceleration, which no single-valued law captures.\n",
        bins.first().map_or(f64::NAN, |b| b.mean),
        bins.last().map_or(f64::NAN, |b| b.mean),
        wfit.points,
        p.slip_speed_rpm,
        fit_exp.a,
        fit_exp.b,
        fit_exp.vs,
        fit_exp.rmse,
        fit_note(&fit_exp),
        fit_gauss.a,
        fit_gauss.b,
        fit_gauss.vs,
        fit_gauss.rmse,
        fit_note(&fit_gauss),
        wfit.rmse_constant,
        if weakening {
            "The torque falls with speed: velocity weakening."
        } else {
            "The better fit is not 10 % better than a constant torque: no clear velocity weakening."
        },
        wfit.shape_exponent,
        wfit.eval(0.0) / wfit.eval(vmax),
        vmax,
        breakaway.len(),
        breakaway_mean,
        breakaway_mean / fastest_bin,
        bins.iter().filter(|b| b.count > 1).map(|b| b.std).fold(0.0, f64::max)
    );
    let _ = writeln!(
        md,
        "**Fundamental.** Line analysis of the bit-speed spectrum: {} Hz over the whole record (resolution {:.4} Hz), \
         {} Hz in the window (resolution {:.2} Hz).\n",
        opt(lines_whole.0.f0_hz, 3),
        lines_whole.1,
        opt(lines_win.0.f0_hz, 2),
        lines_win.1
    );
    let _ = writeln!(
        md,
        "**Severity** (bit speed, window): min {:.1} rpm, max {:.1} rpm, mean {:.1} rpm; (max-min)/(2 mean) = {:.2}, \
         (max-min)/mean = {:.2}.\n",
        sev_bit.min, sev_bit.max, sev_bit.mean, sev_bit.half_range_over_mean, sev_bit.range_over_mean
    );
    let _ = writeln!(
        md,
        "**1-DOF model** J θ'' = k(θ_top - θ) + c(Ω_top - Ω) - T(Ω), driven by the measured top speed. J, k, c from \
         linear least squares on the equation of motion (measured torque, differentiated filtered bit speed): \
         J = {:.4} ± {:.4} kg m2, k = {:.3} ± {:.3} N m/rad, c = {:.4} ± {:.4} N m s/rad (f_n = {:.2} Hz, R² of the \
         acceleration fit {:.3}){}. Simulated with the d = {} friction law above: NRMSE of bit speed {:.2}; bit speed \
         {:.1}..{:.1} rpm (measured {:.1}..{:.1}); severity {:.2} (measured {:.2}); fundamental {} Hz (measured {} Hz).\n",
        dof.inertia_kgm2,
        dof.inertia_stderr,
        dof.stiffness_nm_rad,
        dof.stiffness_stderr,
        dof.damping_nm_s_rad,
        dof.damping_stderr,
        fnat,
        dof.r_squared,
        if dof_free.damping_nm_s_rad < 0.0 {
            format!(
                "; the unconstrained fit gave c = {:.4} ± {:.4} N m s/rad, negative: an energy input. c is pinned at its \
                 bound 0 and J, k refitted, and this is reported as a finding (`parameters_at_bounds` of \
                 lavi-diagnosis.json), not a fix: the structural candidates of rung 2 try what it points at",
                dof_free.damping_nm_s_rad, dof_free.damping_stderr
            )
        } else {
            String::new()
        },
        wfit.shape_exponent,
        nrmse,
        sev_sim.min,
        sev_sim.max,
        sev_bit.min,
        sev_bit.max,
        sev_sim.half_range_over_mean,
        sev_bit.half_range_over_mean,
        opt(lines_sim.0.f0_hz, 2),
        opt(lines_win.0.f0_hz, 2)
    );
    Ok(md)
}

/// The record as measured: the dips, the twist they carry, and the audit of every repair (tables/lavi-repairs.csv).
fn repairs_paragraph(d: &Prepared, p: &StudyParams) -> String {
    let g = d.glitches;
    let counted = crate::data::glitch_options(&d.time_s, p);
    let mut s = format!(
        "**The record as measured.** The top speed has {} dips (samples more than {} rpm from the {}-sample running median \
         or below {} rpm, widened by {} samples each side: {} samples, longest {}). They carry angle: the twist \
         ∫(top − bit speed) dt of the raw record stays within {:.2}..{:+.2} rad over the {:.0} s. Every repair of the \
         top speed is audited by what it changes in that twist (averaged over ±{:.0} ms, the compared band) against \
         the channel's noise integrated over the same span (top-speed noise {:.3} rad/s rms outside the dips, as a \
         random walk): ",
        g.runs,
        p.glitch_threshold_rpm,
        counted.median_window,
        p.glitch_floor_rpm,
        counted.dilate,
        g.samples,
        g.longest_run,
        d.twist_excursion_rad.0,
        d.twist_excursion_rad.1,
        d.time_s[d.len() - 1] - d.time_s[0],
        500.0 / p.cutoff_hz,
        d.top_noise_rad_s
    );
    let parts: Vec<String> = d
        .repairs
        .iter()
        .map(|r| {
            let worst = r.window_change_rad.iter().cloned().fold(0.0, f64::max);
            let noise = r.window_noise_rad.iter().cloned().fold(f64::INFINITY, f64::min);
            format!(
                "`{}` changes it by up to {:.3} rad over the record (noise {:.3} rad; {:+.3} rad at the end) and by up to \
                 {:.3} rad within a window's span (noise at least {:.3} rad): {}",
                r.repair,
                r.record_change_rad,
                r.record_noise_rad,
                r.record_end_change_rad,
                worst,
                noise,
                if r.applied { "applied" } else { "**refused**, the record is used as measured" }
            )
        })
        .collect();
    s.push_str(&parts.join("; "));
    s.push_str(". Every free run below is driven by the top speed as measured (low-passed).\n");
    s
}

/// The repair audit, one row per repair and span (the record, then each window).
pub fn repairs_table(d: &Prepared, labels: &[String]) -> Table {
    let mut t = Table::new(["repair", "span", "twist_change_rad", "noise_rad", "above_noise", "applied"]);
    for r in &d.repairs {
        let mut push = |span: &str, c: f64, n: f64| {
            t.push([
                r.repair.to_string(),
                span.to_string(),
                fmt_fixed(c, 4),
                fmt_fixed(n, 4),
                (c > n).to_string(),
                r.applied.to_string(),
            ])
        };
        push("record", r.record_change_rad, r.record_noise_rad);
        for ((l, c), n) in labels.iter().zip(&r.window_change_rad).zip(&r.window_noise_rad) {
            push(l, *c, *n);
        }
    }
    t
}

/// Line analysis of a speed record (`rig_spectra::line_analysis` with the
/// study's band, `features::line_options`): the lines and the resolution.
fn line_analysis(x: &[f64], fs_hz: f64, max_hz: f64) -> Result<(rig_spectra::LineAnalysis, f64), LaviError> {
    let sl = rig_spectra::line_analysis(x, fs_hz, &crate::features::line_options(max_hz))?;
    Ok((sl.lines, sl.spectrum.resolution_hz))
}

/// Why a fit's parameters sit on a bound, for the text.
fn fit_note(f: &rig_spectra::stickslip::WeakeningFit) -> String {
    let mut s = String::new();
    if f.a_at_bound {
        s.push_str(" (a held at its bound 0: the unconstrained optimum has a < 0, no kinetic plateau in range)");
    }
    if !f.converged {
        s.push_str(" (vs at the edge of the 0.5-2000 rpm scan: no interior optimum)");
    }
    s
}

fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

fn rms(x: &[f64]) -> f64 {
    (x.iter().map(|v| v * v).sum::<f64>() / x.len().max(1) as f64).sqrt()
}

fn opt(x: Option<f64>, d: usize) -> String {
    x.map_or_else(|| "none".to_string(), |v| fmt_fixed(v, d))
}

/// Four significant digits in scientific notation (parameters spanning decades).
fn fmt_sig(x: f64) -> String {
    format!("{x:.3e}")
}
