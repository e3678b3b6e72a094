//! The spectra study as tables and figures: the line tables of the campaign
//! and the simulation, Table 4.8 at several record lengths, Figs. 4.22-4.26.

use super::{NamedLines, OperatingPoint, SpectraOptions, SpectraStudy, TABLE_4_8_PEAKS_HZ, lines_of, table_4_8_lines};
use crate::SweepError;
use rig_spectra::{LineClass, WelchOptions, frf_h1, thin_indices};
use rig_types::{AxisScale, FigureSpec, Panel, SeriesStyle, Sheet, Table, fmt_fixed};
use rig_types::{figure as fig, series};

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
fn push_lines(t: &mut Table, p: &OperatingPoint, window_s: f64, l: &NamedLines) {
    let amp_dec = if l.signal == "rotor_rpm" { 2 } else { 4 };
    let a = &l.lines.lines;
    let head = [
        p.run.id.clone(),
        fmt_fixed(p.motor_rpm_setpoint, 1),
        fmt_fixed(p.normal_force_n, 1),
        l.signal.to_string(),
        fmt_fixed(window_s, 1),
        fmt_fixed(l.lines.spectrum.resolution_hz, 4),
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

/// Every table of the study, by its path under the out dir.
pub fn tables(study: &SpectraStudy, o: &SpectraOptions) -> Vec<(&'static str, Table)> {
    let mut meas = line_header();
    let mut sim = line_header();
    for p in &study.points {
        let win = p.window_s();
        for l in &p.measured_lines {
            push_lines(&mut meas, p, win, l);
        }
        for l in &p.simulated_lines {
            push_lines(&mut sim, p, win, l);
        }
    }
    let (t48, t48_summary) = table_4_8(&o.table_4_8_records_s);
    let mut out = vec![
        ("tables/lines-campaign.csv", meas),
        ("tables/lines-simulation.csv", sim),
        ("tables/lines-table-4-8.csv", t48),
        ("tables/lines-table-4-8-summary.csv", t48_summary),
    ];
    // Written only when a run was left out (a campaign whose every run has a
    // steady window, the shipped one, has no such table).
    if !study.short.is_empty() {
        let mut t = Table::new(["run", "duration_s", "steady_from_s", "why"]);
        for r in &study.short {
            t.push([
                r.id.clone(),
                fmt_fixed(r.duration_s, 3),
                fmt_fixed(r.steady_from_s, 3),
                "left out: the record ends before its steady window (ramp_s + settle_s) holds enough samples"
                    .to_string(),
            ]);
        }
        out.push(("tables/lines-short-runs.csv", t));
    }
    out
}

/// Table 4.8's three peaks through the line analysis at several record lengths
/// T (resolution 1/T), plus the largest T at which all three are harmonic.
/// Amplitudes are not published: taken equal.
fn table_4_8(records_s: &[f64]) -> (Table, Table) {
    let published = TABLE_4_8_PEAKS_HZ;
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
        let a = table_4_8_lines(t);
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
    let t_max = (1..=2000).rev().map(f64::from).find(|&t| table_4_8_lines(t).count(LineClass::Harmonic) == 3);
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

/// The thesis' operating points of Figs. 4.22-4.24: (figure id, rpm, N).
const TARGETS: [(&str, f64, f64); 3] = [("fig-4-22", 54.4, 4.5), ("fig-4-23", 84.0, 15.0), ("fig-4-24", 122.0, 25.0)];

/// Figs. 4.22-4.26: limit cycle and time response of the operating points
/// nearest to the thesis' (a, b of 4.22-4.24), then on the run of Fig. 4.24
/// its time responses (4.25), FRF, coherence and line spectrum (4.26).
/// Fig. 4.26 (a) is a sheet (magnitude and coherence panels over a log
/// frequency axis), the others single panels.
pub fn figures(study: &SpectraStudy, o: &SpectraOptions) -> Result<(Vec<FigureSpec>, Vec<Sheet>), SweepError> {
    let mut out = Vec::new();
    let mut fig24 = None;
    for (id, rpm, n) in TARGETS {
        let p = study.nearest(rpm, n).ok_or_else(|| SweepError::Analysis("no operating point".into()))?;
        if id == "fig-4-24" {
            fig24 = Some(p);
        }
        out.extend(limit_cycle_and_time_response(p, id, rpm, n, o));
    }
    let p = fig24.expect("TARGETS ends with fig-4-24");
    let m = &p.measured;
    let im = thin_indices(m.time_s.len(), 2000);
    let pick = |v: &[f64]| im.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    let which = format!(
        "Run {} ({} rpm, {} N, the run of Fig. 4.24), steady window.",
        p.run.id, p.motor_rpm_setpoint, p.normal_force_n
    );
    out.push(fig(
        "fig-4-25a",
        "Time response of the rotor speed RRPM",
        &format!("(a) Rotor speed from the encoder. {which}"),
        ("time [s]", 3),
        ("RRPM [rpm]", 1),
        vec![series("RRPM", pick(&m.time_s), pick(&m.rotor_rpm), SeriesStyle::Line)],
    ));
    out.push(fig(
        "fig-4-25b",
        "Time response of the friction torque RTor",
        &format!(
            "(b) Friction torque on rotor 1 from the force sensor: (mV - offset) / factor x r, factor and offset from \
             data/campaign-calibration.json, r = {} m. {which}",
            study.brake_disc_radius_m
        ),
        ("time [s]", 3),
        ("RTor [N m]", 4),
        vec![series("RTor", pick(&m.time_s), pick(&m.torque_nm), SeriesStyle::Line)],
    ));
    let (frf_sheet, coherence) = fig_4_26ab_frf(p, o, &which)?;
    out.push(coherence);
    out.push(fig_4_26c_line_spectrum(p, o, &which)?);
    Ok((out, vec![frf_sheet]))
}

/// Panels (a) limit cycle and (b) time response of one of Figs. 4.22-4.24.
fn limit_cycle_and_time_response(
    p: &OperatingPoint,
    id: &str,
    rpm: f64,
    n: f64,
    o: &SpectraOptions,
) -> [FigureSpec; 2] {
    let (m, s) = (&p.measured, &p.simulated);
    let used = format!(
        "Run {} ({} rpm set-point, {} N), the campaign's operating point nearest to the thesis' {} rpm / {} N \
         (distance with rpm and N scaled by the campaign's spans); steady window from {} s (ramp {} s + settling {} s) \
         to the end. Rotor speed from the encoder ticks by rig_calibrate::rotor_speed_rad_s (central difference \
         over ±20 ms + centred moving average); twist φ2 − φ1 from the two encoders.",
        p.run.id,
        p.motor_rpm_setpoint,
        p.normal_force_n,
        rpm,
        n,
        p.ramp_s + o.settle_s,
        p.ramp_s,
        o.settle_s
    );
    let im = thin_indices(m.time_s.len(), 2000);
    let is = thin_indices(s.time_s.len(), 2000);
    let pick = |v: &[f64], idx: &[usize]| idx.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    [
        fig(
            &format!("{id}a"),
            &format!("Limit cycle near {rpm} rpm and {n} N (measured and rig model)"),
            &format!(
                "(a) Phase portrait rotor speed against twist. {used} Rig model: rig_model::simulate with data/rig-params.json at the same set-point."
            ),
            ("twist phi2 - phi1 [rad]", 3),
            ("rotor speed [rpm]", 1),
            vec![
                series(
                    &format!("measured {}", p.run.id),
                    pick(&m.twist_rad, &im),
                    pick(&m.rotor_rpm, &im),
                    SeriesStyle::Line,
                ),
                series("rig model", pick(&s.twist_rad, &is), pick(&s.rotor_rpm, &is), SeriesStyle::Dashed),
            ],
        ),
        fig(
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
        ),
    ]
}

/// Fig. 4.26 (a) FRF magnitude |H1| from RRPM to RTor and (b) their coherence
/// (Welch, Hann segments), in the study's band.
pub fn fig_4_26ab_frf(p: &OperatingPoint, o: &SpectraOptions, which: &str) -> Result<(Sheet, FigureSpec), SweepError> {
    let m = &p.measured;
    let fs = m.fs_hz();
    let seg = ((o.welch_segment_s * fs) as usize).min(m.time_s.len());
    let frf = frf_h1(&m.rotor_rpm, &m.torque_nm, fs, &WelchOptions::hann(seg))
        .map_err(|e| SweepError::Analysis(format!("run {}: FRF: {e}", p.run.id)))?;
    let band: Vec<usize> = (1..frf.freq_hz.len())
        .filter(|&k| frf.freq_hz[k] >= o.min_freq_hz && frf.freq_hz[k] <= o.max_freq_hz)
        .collect();
    let fb = |v: &[f64]| band.iter().map(|&k| v[k]).collect::<Vec<f64>>();
    let welch_note = format!(
        "Welch: Hann segments of {} s ({} samples), 50 % overlap, {} segments, mean removed; resolution {:.3} Hz. {which}",
        o.welch_segment_s, seg, frf.segments, frf.resolution_hz
    );
    // The field's convention for a frequency response: magnitude in dB over a
    // logarithmic frequency axis, coherence in its own panel below (where the
    // coherence is low the magnitude estimate is not to be read).
    let db: Vec<f64> = fb(&frf.magnitude).iter().map(|a| 20.0 * a.max(1e-300).log10()).collect();
    let log = |spec| Panel { spec, x_scale: AxisScale::Log10 };
    let sheet = Sheet {
        id: "fig-4-26a".into(),
        title: "FRF from RRPM to RTor: magnitude and coherence".into(),
        caption: format!(
            "(a) H1 = S_xy / S_xx with x = RRPM (rpm), y = RTor (N m), magnitude 20 log10(|H1| / (1 N m/rpm)) dB \
             over a logarithmic frequency axis, magnitude-squared coherence |S_xy|^2 / (S_xx S_yy) below it. {welch_note}"
        ),
        columns: 1,
        panels: vec![
            log(fig(
                "fig-4-26a-magnitude",
                "|H1|",
                "",
                ("frequency [Hz]", 3),
                ("|H1| [dB re 1 N m/rpm]", 2),
                vec![series("|H1|", fb(&frf.freq_hz), db, SeriesStyle::Line)],
            )),
            log(fig(
                "fig-4-26a-coherence",
                "coherence",
                "",
                ("frequency [Hz]", 3),
                ("coherence [-]", 3),
                vec![series("coherence", fb(&frf.freq_hz), fb(&frf.coherence), SeriesStyle::Line)],
            )),
        ],
    };
    let coherence = fig(
        "fig-4-26b",
        "Coherence of RRPM and RTor",
        &format!(
            "(b) Magnitude-squared coherence |S_xy|^2 / (S_xx S_yy), linear frequency axis as in the thesis. {welch_note}"
        ),
        ("frequency [Hz]", 3),
        ("coherence [-]", 3),
        vec![series("coherence", fb(&frf.freq_hz), fb(&frf.coherence), SeriesStyle::Line)],
    );
    Ok((sheet, coherence))
}

/// Fig. 4.26 (c): the amplitude spectrum of RRPM with the peaks given to the line analysis.
fn fig_4_26c_line_spectrum(p: &OperatingPoint, o: &SpectraOptions, which: &str) -> Result<FigureSpec, SweepError> {
    let m = &p.measured;
    let sl = lines_of(&m.rotor_rpm, m.fs_hz(), o)?;
    let (spec, peaks, a) = (&sl.spectrum, &sl.peaks, &sl.lines);
    let kb: Vec<usize> = (1..spec.freq_hz.len())
        .filter(|&k| spec.freq_hz[k] >= o.min_freq_hz && spec.freq_hz[k] <= o.max_freq_hz)
        .collect();
    Ok(fig(
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
            series(
                "RRPM",
                kb.iter().map(|&k| spec.freq_hz[k]).collect(),
                kb.iter().map(|&k| spec.amplitude[k]).collect(),
                SeriesStyle::Line,
            ),
            series(
                "peaks",
                peaks.iter().map(|q| q.freq_hz).collect(),
                peaks.iter().map(|q| q.amplitude).collect(),
                SeriesStyle::Markers,
            ),
        ],
    ))
}
