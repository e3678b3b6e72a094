//! Stage `spectra`: spectra, peaks and line analysis of every operating point
//! (measured and simulated), Table 4.8's lines, Figs. 4.22-4.26.

use crate::StageCtx;
use anyhow::{Context, Result};
use rayon::prelude::*;
use rig_calibrate::{CampaignCalibration, friction_torque_nm};
use rig_model::{SimOptions, simulate};
use rig_spectra::{
    Detrend, Line, LineAnalysis, LineClass, LineOptions, Peak, PeakOptions, Spectrum, WelchOptions, Window,
    amplitude_spectrum, analyse_lines, frf_h1, spectral_peaks, thin_indices,
};
use rig_types::sensor::encoder_speed_rad_s as rotor_speed_rad_s;
use rig_types::units::RAD_S_TO_RPM;
use rig_types::{RigParams, Run, RunInput, RunKind, SeriesStyle, Table, Trajectory, fmt_fixed};
use rig_types::{figure as fig, series};
use serde::Deserialize;

/// `[stage.params]` of `spectra`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// Integrator tolerances of the rig-model runs (pipeline.toml's `[shared.integrator]`).
    pub integrator: SimOptions,
    pub settle_s: f64,
    pub min_freq_hz: f64,
    pub max_freq_hz: f64,
    pub welch_segment_s: f64,
    pub tolerance_bins: f64,
    pub table_4_8_records_s: Vec<f64>,
}

/// One operating point, measured or simulated, over its steady window.
struct Signals {
    time_s: Vec<f64>,
    rotor_rpm: Vec<f64>,
    motor_rpm: Vec<f64>,
    twist_rad: Vec<f64>,
    torque_nm: Vec<f64>,
}

impl Signals {
    fn window(&self, from_s: f64) -> Signals {
        let i0 = self.time_s.partition_point(|t| *t < from_s);
        Signals {
            time_s: self.time_s[i0..].to_vec(),
            rotor_rpm: self.rotor_rpm[i0..].to_vec(),
            motor_rpm: self.motor_rpm[i0..].to_vec(),
            twist_rad: self.twist_rad[i0..].to_vec(),
            torque_nm: self.torque_nm[i0..].to_vec(),
        }
    }
    fn fs_hz(&self) -> f64 {
        let n = self.time_s.len();
        (n - 1) as f64 / (self.time_s[n - 1] - self.time_s[0])
    }
}

fn measured(run: &Run, rig: &rig_types::RigInfo, cal: &CampaignCalibration) -> Result<Signals> {
    let d = &run.data;
    let (Some(rt), Some(mt), Some(mv)) = (&d.rotor_ticks, &d.motor_ticks, &d.brake_force_mv) else {
        anyhow::bail!("run {}: an operating_point needs rotor_ticks, motor_ticks and brake_force_mv", run.id);
    };
    let tpr = rig.encoder_ticks_per_rev;
    let rad = 2.0 * std::f64::consts::PI / tpr as f64;
    let rpm = |x: Vec<f64>| x.into_iter().map(|v| v * RAD_S_TO_RPM).collect::<Vec<f64>>();
    Ok(Signals {
        time_s: d.time_s.clone(),
        rotor_rpm: rpm(rotor_speed_rad_s(&d.time_s, rt, tpr)),
        motor_rpm: rpm(rotor_speed_rad_s(&d.time_s, mt, tpr)),
        twist_rad: mt.iter().zip(rt).map(|(m, r)| (m - r) as f64 * rad).collect(),
        torque_nm: friction_torque_nm(mv, cal, rig.brake_disc_radius_m),
    })
}

fn simulated(tr: &Trajectory) -> Signals {
    Signals {
        time_s: tr.time_s.clone(),
        rotor_rpm: tr.rotor_speed_rad_s.iter().map(|v| v * RAD_S_TO_RPM).collect(),
        motor_rpm: tr.motor_speed_rad_s.iter().map(|v| v * RAD_S_TO_RPM).collect(),
        twist_rad: tr.motor_angle_rad.iter().zip(&tr.rotor_angle_rad).map(|(m, r)| m - r).collect(),
        torque_nm: tr.friction_torque_nm.clone(),
    }
}

/// Spectrum → peaks → line analysis of one signal (Hann, mean removed).
fn lines_of(x: &[f64], fs_hz: f64, p: &Params) -> Result<(Spectrum, Vec<Peak>, LineAnalysis)> {
    let s = amplitude_spectrum(x, fs_hz, Window::Hann, Detrend::Constant)?;
    let peaks = spectral_peaks(
        &s,
        &PeakOptions { min_freq_hz: p.min_freq_hz, max_freq_hz: p.max_freq_hz, ..PeakOptions::default() },
    );
    let lines: Vec<Line> = peaks.iter().map(Line::from).collect();
    let a = analyse_lines(
        &lines,
        s.resolution_hz,
        &LineOptions { tolerance_bins: p.tolerance_bins, ..LineOptions::default() },
    );
    Ok((s, peaks, a))
}

fn line_header() -> Table {
    Table::new([
        "run_id",
        "motor_rpm_setpoint",
        "normal_force_n",
        "signal",
        "window_s",
        "resolution_hz",
        "f0_hz",
        "freq_hz",
        "amplitude",
        "class",
        "relation",
        "error_hz",
        "tolerance_hz",
    ])
}

/// Appends one signal's line analysis (a row "none" when no line passed the thresholds).
fn push_lines(t: &mut Table, id: &str, rpm: f64, n: f64, signal: &str, window_s: f64, s: &Spectrum, a: &LineAnalysis) {
    let amp_dec = if signal == "rotor_rpm" { 2 } else { 4 };
    let head = [
        id.to_string(),
        fmt_fixed(rpm, 1),
        fmt_fixed(n, 1),
        signal.to_string(),
        fmt_fixed(window_s, 1),
        fmt_fixed(s.resolution_hz, 4),
        a.f0_hz.map_or(String::new(), |f| fmt_fixed(f, 4)),
    ];
    if a.rows.is_empty() {
        let mut r: Vec<String> = head.to_vec();
        r.extend(["".into(), "".into(), "none".into(), "".into(), "".into(), "".into()]);
        t.push(r);
    }
    for row in &a.rows {
        let mut r: Vec<String> = head.to_vec();
        r.extend([
            fmt_fixed(row.freq_hz, 4),
            fmt_fixed(row.amplitude, amp_dec),
            row.class.as_str().to_string(),
            row.relation.clone(),
            fmt_fixed(row.error_hz, 4),
            fmt_fixed(row.tolerance_hz, 4),
        ]);
        t.push(r);
    }
}

/// The operating point nearest to (rpm, N), distances scaled by the campaign's spans.
fn nearest<'a>(ops: &[(&'a Run, f64, f64, f64)], rpm: f64, n: f64) -> Option<&'a Run> {
    let span = |f: fn(&(&Run, f64, f64, f64)) -> f64| {
        let lo = ops.iter().map(f).fold(f64::INFINITY, f64::min);
        let hi = ops.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
        (hi - lo).max(1e-9)
    };
    let (sr, sn) = (span(|o| o.1), span(|o| o.2));
    ops.iter()
        .min_by(|a, b| {
            let d = |o: &(&Run, f64, f64, f64)| ((o.1 - rpm) / sr).powi(2) + ((o.2 - n) / sn).powi(2);
            d(a).total_cmp(&d(b))
        })
        .map(|o| o.0)
}

fn thin(s: &Signals, max_points: usize) -> Vec<usize> {
    thin_indices(s.time_s.len(), max_points)
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let rig_params: RigParams = ctx.read_json("data/rig-params.json")?;
    let campaign = ctx.campaign()?.clone();
    let ops: Vec<(&Run, f64, f64, f64)> = campaign
        .runs
        .iter()
        .filter_map(|r| match r.kind {
            RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } => {
                Some((r, motor_rpm_setpoint, normal_force_n, ramp_s))
            }
            _ => None,
        })
        .collect();
    anyhow::ensure!(!ops.is_empty(), "campaign {}: no operating_point runs", campaign.name);

    // Measured and simulated signals of every operating point (simulations in parallel, fixed order).
    let sims: Vec<Result<Trajectory>> = ops
        .par_iter()
        .map(|(run, rpm, n, ramp)| {
            let input = RunInput::OperatingPoint { motor_rpm_setpoint: *rpm, normal_force_n: *n, ramp_s: *ramp };
            simulate(&rig_params, &input, &run.data.time_s, &p.integrator)
                .with_context(|| format!("simulating run {}", run.id))
        })
        .collect();
    let mut meas_tab = line_header();
    let mut sim_tab = line_header();
    let mut steady: Vec<(Signals, Signals)> = Vec::new();
    for ((run, rpm, n, ramp), sim) in ops.iter().zip(sims) {
        let start = ramp + p.settle_s;
        let m = measured(run, &campaign.rig, &cal)?.window(start);
        let s = simulated(&sim?).window(start);
        anyhow::ensure!(m.time_s.len() > 64, "run {}: steady window after {start} s is too short", run.id);
        let (fs, win) = (m.fs_hz(), m.time_s[m.time_s.len() - 1] - m.time_s[0]);
        for (tab, sig) in [(&mut meas_tab, &m), (&mut sim_tab, &s)] {
            for (name, x) in [("rotor_rpm", &sig.rotor_rpm), ("torque_nm", &sig.torque_nm)] {
                let (spec, _, a) = lines_of(x, fs, &p)?;
                push_lines(tab, &run.id, *rpm, *n, name, win, &spec, &a);
            }
        }
        steady.push((m, s));
    }
    ctx.write_table("tables/lines-campaign.csv", &meas_tab)?;
    ctx.write_table("tables/lines-simulation.csv", &sim_tab)?;

    // Table 4.8.
    let (t48, t48_summary) = table_4_8(&p.table_4_8_records_s);
    ctx.write_table("tables/lines-table-4-8.csv", &t48)?;
    ctx.write_table("tables/lines-table-4-8-summary.csv", &t48_summary)?;

    // Figs. 4.22-4.24: limit cycle and time response of the nearest runs.
    let index_of = |r: &Run| ops.iter().position(|o| o.0.id == r.id).expect("run from ops");
    let targets = [("fig-4-22", 54.4, 4.5), ("fig-4-23", 84.0, 15.0), ("fig-4-24", 122.0, 25.0)];
    let mut fig24_index = 0;
    for (id, rpm, n) in targets {
        let run = nearest(&ops, rpm, n).expect("ops is not empty");
        let k = index_of(run);
        if id == "fig-4-24" {
            fig24_index = k;
        }
        let (_, orpm, on, oramp) = ops[k];
        let (m, s) = &steady[k];
        let used = format!(
            "Run {} ({} rpm set-point, {} N), the campaign's operating point nearest to the thesis' {} rpm / {} N \
             (distance with rpm and N scaled by the campaign's spans); steady window from {} s (ramp {} s + settling {} s) \
             to the end. Rotor speed from the encoder ticks by rig_calibrate::rotor_speed_rad_s (central difference \
             over ±20 ms + centred moving average); twist φ2 − φ1 from the two encoders.",
            run.id,
            orpm,
            on,
            rpm,
            n,
            oramp + p.settle_s,
            oramp,
            p.settle_s
        );
        let im = thin(m, 2000);
        let is = thin(s, 2000);
        let pick = |v: &[f64], idx: &[usize]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
        ctx.write_figure(&fig(
            &format!("{id}a"),
            &format!("Limit cycle near {rpm} rpm and {n} N (measured and rig model)"),
            &format!("(a) Phase portrait rotor speed against twist. {used} Rig model: rig_model::simulate with data/rig-params.json at the same set-point."),
            ("twist phi2 - phi1 [rad]", 3),
            ("rotor speed [rpm]", 1),
            vec![
                series(&format!("measured {}", run.id), pick(&m.twist_rad, &im), pick(&m.rotor_rpm, &im), SeriesStyle::Line),
                series("rig model", pick(&s.twist_rad, &is), pick(&s.rotor_rpm, &is), SeriesStyle::Dashed),
            ],
        ))?;
        ctx.write_figure(&fig(
            &format!("{id}b"),
            &format!("Time response near {rpm} rpm and {n} N"),
            &format!("(b) Rotor speed RRPM and motor-side speed MRPM against time. {used}"),
            ("time [s]", 3),
            ("speed [rpm]", 1),
            vec![
                series("RRPM measured", pick(&m.time_s, &im), pick(&m.rotor_rpm, &im), SeriesStyle::Line),
                series("MRPM measured", pick(&m.time_s, &im), pick(&m.motor_rpm, &im), SeriesStyle::Line),
                series("RRPM rig model", pick(&s.time_s, &is), pick(&s.rotor_rpm, &is), SeriesStyle::Dashed),
            ],
        ))?;
    }

    // Figs. 4.25-4.26 on the run of Fig. 4.24.
    let (run, orpm, on, _) = ops[fig24_index];
    let (m, _) = &steady[fig24_index];
    let im = thin(m, 2000);
    let pick = |v: &[f64]| im.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    let which = format!("Run {} ({} rpm, {} N, the run of Fig. 4.24), steady window.", run.id, orpm, on);
    ctx.write_figure(&fig(
        "fig-4-25a",
        "Time response of the rotor speed RRPM",
        &format!("(a) Rotor speed from the encoder. {which}"),
        ("time [s]", 3),
        ("RRPM [rpm]", 1),
        vec![series("RRPM", pick(&m.time_s), pick(&m.rotor_rpm), SeriesStyle::Line)],
    ))?;
    ctx.write_figure(&fig(
        "fig-4-25b",
        "Time response of the friction torque RTor",
        &format!(
            "(b) Friction torque on rotor 1 from the force sensor: (mV - offset) / factor x r, factor and offset from \
             data/campaign-calibration.json, r = {} m. {which}",
            campaign.rig.brake_disc_radius_m
        ),
        ("time [s]", 3),
        ("RTor [N m]", 4),
        vec![series("RTor", pick(&m.time_s), pick(&m.torque_nm), SeriesStyle::Line)],
    ))?;
    let fs = m.fs_hz();
    let seg = ((p.welch_segment_s * fs) as usize).min(m.time_s.len());
    let frf = frf_h1(&m.rotor_rpm, &m.torque_nm, fs, &WelchOptions::hann(seg))?;
    let band: Vec<usize> = (1..frf.freq_hz.len())
        .filter(|&k| frf.freq_hz[k] >= p.min_freq_hz && frf.freq_hz[k] <= p.max_freq_hz)
        .collect();
    let fb = |v: &[f64]| band.iter().map(|&k| v[k]).collect::<Vec<f64>>();
    let welch_note = format!(
        "Welch: Hann segments of {} s ({} samples), 50 % overlap, {} segments, mean removed; resolution {:.3} Hz. {which}",
        p.welch_segment_s, seg, frf.segments, frf.resolution_hz
    );
    ctx.write_figure(&fig(
        "fig-4-26a",
        "FRF magnitude |H1| from RRPM to RTor",
        &format!("(a) H1 = S_xy / S_xx with x = RRPM (rpm), y = RTor (N m). {welch_note}"),
        ("frequency [Hz]", 3),
        ("|H1| [N m/rpm]", 6),
        vec![series("|H1|", fb(&frf.freq_hz), fb(&frf.magnitude), SeriesStyle::Line)],
    ))?;
    ctx.write_figure(&fig(
        "fig-4-26b",
        "Coherence of RRPM and RTor",
        &format!("(b) Magnitude-squared coherence |S_xy|^2 / (S_xx S_yy). {welch_note}"),
        ("frequency [Hz]", 3),
        ("coherence [-]", 3),
        vec![series("coherence", fb(&frf.freq_hz), fb(&frf.coherence), SeriesStyle::Line)],
    ))?;
    let (spec, peaks, a) = lines_of(&m.rotor_rpm, fs, &p)?;
    let kb: Vec<usize> = (1..spec.freq_hz.len())
        .filter(|&k| spec.freq_hz[k] >= p.min_freq_hz && spec.freq_hz[k] <= p.max_freq_hz)
        .collect();
    ctx.write_figure(&fig(
        "fig-4-26c",
        "Amplitude spectrum of RRPM with its lines",
        &format!(
            "(c) One-sided amplitude spectrum (Hann, whole steady window, resolution {:.4} Hz) with the peaks passed to \
             the line analysis (prominence >= 5 % of the largest and >= 6 x the median amplitude); f0 = {} Hz. {which}",
            spec.resolution_hz,
            a.f0_hz.map_or("none".to_string(), |f| fmt_fixed(f, 4))
        ),
        ("frequency [Hz]", 4),
        ("amplitude [rpm]", 3),
        vec![
            series("RRPM", kb.iter().map(|&k| spec.freq_hz[k]).collect(), kb.iter().map(|&k| spec.amplitude[k]).collect(), SeriesStyle::Line),
            series("peaks", peaks.iter().map(|q| q.freq_hz).collect(), peaks.iter().map(|q| q.amplitude).collect(), SeriesStyle::Markers),
        ],
    ))?;
    Ok(())
}

/// Table 4.8's three peaks through the line analysis at several record lengths
/// T (resolution 1/T), plus the largest T at which all three are harmonic.
/// Amplitudes are not published: taken equal.
fn table_4_8(records_s: &[f64]) -> (Table, Table) {
    let published = [0.352, 0.718, 1.069];
    let lines: Vec<Line> = published.iter().map(|&f| Line { freq_hz: f, amplitude: 1.0, sigma_hz: 0.0 }).collect();
    let analyse = |t: f64| analyse_lines(&lines, 1.0 / t, &LineOptions::default());
    let mut tab = Table::new([
        "record_length_s",
        "resolution_hz",
        "f0_hz",
        "freq_hz",
        "class",
        "relation",
        "error_hz",
        "tolerance_hz",
    ]);
    for &t in records_s {
        let a = analyse(t);
        for r in &a.rows {
            tab.push([
                fmt_fixed(t, 0),
                fmt_fixed(1.0 / t, 4),
                a.f0_hz.map_or(String::new(), |f| fmt_fixed(f, 5)),
                fmt_fixed(r.freq_hz, 3),
                r.class.as_str().to_string(),
                r.relation.clone(),
                fmt_fixed(r.error_hz, 5),
                fmt_fixed(r.tolerance_hz, 5),
            ]);
        }
    }
    // Largest whole-second T at which all three lines are harmonics (scan 1..2000 s).
    let t_max = (1..=2000).rev().map(f64::from).find(|&t| analyse(t).count(LineClass::Harmonic) == 3);
    let f0_ls = published.iter().enumerate().map(|(i, f)| (i + 1) as f64 * f).sum::<f64>() / 14.0;
    let mut s = Table::new(["quantity", "value", "how"]);
    s.push(["ratio_0.718_over_0.352".into(), fmt_fixed(0.718 / 0.352, 4), "published peaks".to_string()]);
    s.push(["ratio_1.069_over_0.352".into(), fmt_fixed(1.069 / 0.352, 4), "published peaks".to_string()]);
    s.push(["dev_0.718_from_2x0.352_hz".into(), fmt_fixed(0.718 - 2.0 * 0.352, 4), "0.718 - 2 x 0.352".to_string()]);
    s.push(["dev_1.069_from_3x0.352_hz".into(), fmt_fixed(1.069 - 3.0 * 0.352, 4), "1.069 - 3 x 0.352".to_string()]);
    s.push(["f0_least_squares_hz".into(), fmt_fixed(f0_ls, 5), "sum k f_k / sum k^2, k = 1, 2, 3".to_string()]);
    for (k, f) in published.iter().enumerate() {
        s.push([format!("residual_{f}_hz"), fmt_fixed(f - (k + 1) as f64 * f0_ls, 5), format!("{f} - {} x f0", k + 1)]);
    }
    s.push([
        "largest_record_all_harmonic_s".into(),
        t_max.map_or("none".into(), |t| fmt_fixed(t, 0)),
        "tolerance 1.5/T: all three harmonic for T up to this; longer records resolve the deviation".to_string(),
    ]);
    s.push(["printed_rounding_hz".into(), fmt_fixed(0.0005, 4), "half a unit of the printed 3rd decimal".to_string()]);
    (tab, s)
}
