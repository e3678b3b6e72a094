//! The diagnosis for people: diagnosis.md, the tables and the evidence
//! figures (as rig_types data; the pipeline stage writes them).

use crate::ChannelCheck;
use crate::result::{Diagnosis, Features, round_sig};
use rig_types::{AxisScale, FigureSpec, Panel, Series, SeriesStyle, Sheet, Table, fmt_fixed};

mod evidence;
mod markdown;
pub use evidence::figures;
pub use markdown::markdown;

fn f4(x: f64) -> String {
    if x.is_finite() { fmt_fixed(x, 4) } else { "nan".into() }
}

/// tables/diagnosis-runs.csv: per operating point, measured vs simulated
/// features and the misfits (crate docs define the misfit).
pub fn runs_table(d: &Diagnosis) -> Table {
    let mut t = Table::new([
        "run",
        "fold",
        "motor_rpm_setpoint",
        "normal_force_n",
        "slip_samples",
        "meas_stick_slip",
        "sim_stick_slip",
        "ext_stick_slip",
        "meas_rotor_min_rad_s",
        "sim_rotor_min_rad_s",
        "ext_rotor_min_rad_s",
        "meas_rotor_max_rad_s",
        "sim_rotor_max_rad_s",
        "ext_rotor_max_rad_s",
        "meas_fundamental_hz",
        "sim_fundamental_hz",
        "ext_fundamental_hz",
        "meas_motor_dip_rad_s",
        "sim_motor_dip_rad_s",
        "misfit_baseline",
        "misfit_extended",
        "misfit_noise_floor",
    ]);
    let opt = |f: &Option<Features>, g: fn(&Features) -> String| f.as_ref().map(g).unwrap_or_else(|| "".into());
    for r in &d.detail.runs {
        t.push([
            r.id.clone(),
            r.fold.to_string(),
            fmt_fixed(r.motor_rpm_setpoint, 1),
            fmt_fixed(r.normal_force_n, 2),
            r.slip_samples.to_string(),
            r.measured.stick_slip().to_string(),
            opt(&r.simulated, |f| f.stick_slip().to_string()),
            opt(&r.extended, |f| f.stick_slip().to_string()),
            fmt_fixed(r.measured.rotor_min_rad_s, 2),
            opt(&r.simulated, |f| fmt_fixed(f.rotor_min_rad_s, 2)),
            opt(&r.extended, |f| fmt_fixed(f.rotor_min_rad_s, 2)),
            fmt_fixed(r.measured.rotor_max_rad_s, 2),
            opt(&r.simulated, |f| fmt_fixed(f.rotor_max_rad_s, 2)),
            opt(&r.extended, |f| fmt_fixed(f.rotor_max_rad_s, 2)),
            fmt_fixed(r.measured.fundamental_hz, 2),
            opt(&r.simulated, |f| fmt_fixed(f.fundamental_hz, 2)),
            opt(&r.extended, |f| fmt_fixed(f.fundamental_hz, 2)),
            fmt_fixed(r.measured.motor_dip_rad_s, 2),
            opt(&r.simulated, |f| fmt_fixed(f.motor_dip_rad_s, 2)),
            f4(r.misfit_baseline),
            f4(r.misfit_extended),
            f4(r.misfit_noise_floor),
        ]);
    }
    t
}

/// tables/diagnosis-checks.csv: every check of the other run kinds and the
/// free-run checks of the baseline and the extended model.
pub fn checks_table(d: &Diagnosis) -> Table {
    let mut t = Table::new([
        "model",
        "channel",
        "run_kind",
        "statistic",
        "noise_floor",
        "ratio",
        "threshold",
        "flagged",
        "in_adequacy",
    ]);
    let det = &d.detail;
    // With a free run, the break-away dwell is the record's against the final
    // model's (lib.rs, extension::dwell); the other run kinds judge the baseline.
    let model_of = |k: &ChannelCheck| match [crate::extension::dwell::CHECK, crate::extension::dwell::STICKS_CHECK]
        .contains(&k.channel.as_str())
        && !det.free_run_extended.is_empty()
    {
        true => "extended",
        false => "baseline",
    };
    let rows = det
        .channel_checks
        .iter()
        .map(|k| (model_of(k), k, true))
        .chain(det.free_run_baseline.iter().map(|k| ("baseline", k, false)))
        .chain(det.free_run_extended.iter().map(|k| ("extended", k, false)));
    for (model, k, adequacy) in rows {
        t.push([
            model.to_string(),
            k.channel.clone(),
            k.run_kind.clone(),
            format!("{}", round_sig(k.statistic, 4)),
            format!("{}", round_sig(k.noise_floor, 4)),
            fmt_fixed(k.ratio, 3),
            if k.threshold.is_finite() { fmt_fixed(k.threshold, 2) } else { "".into() },
            k.flagged.to_string(),
            adequacy.to_string(),
        ]);
    }
    t
}

/// tables/diagnosis-candidates.csv: every effect tried in every forward-selection
/// step, with its cross-validated misfit, gain (and its spread over folds) and
/// the paired run-level t (crate docs).
pub fn candidates_table(d: &Diagnosis) -> Table {
    let mut t = Table::new([
        "step",
        "effect",
        "misfit_before",
        "misfit_after",
        "relative_gain",
        "relative_gain_fold_sd",
        "paired_t",
        "accepted",
    ]);
    for r in &d.detail.steps {
        t.push([
            r.step.to_string(),
            r.effect.clone(),
            f4(r.misfit_before),
            f4(r.misfit_after),
            f4(r.gain),
            f4(r.gain_fold_sd),
            if r.t.is_finite() { fmt_fixed(r.t, 2) } else { "inf".into() },
            r.accepted.to_string(),
        ]);
    }
    t
}

/// tables/diagnosis-rungs.csv: thesis model → recalibrated rig model → extended model.
pub fn rungs_table(d: &Diagnosis) -> Table {
    let mut t = Table::new(["rung", "heldout_misfit", "gain_vs_previous", "cause"]);
    let mut prev: Option<f64> = None;
    for (name, m, cause) in &d.detail.rungs {
        let gain = prev.map(|p| f4(1.0 - m / p)).unwrap_or_default();
        t.push([name.clone(), f4(*m), gain, cause.clone()]);
        prev = Some(*m);
    }
    t
}

/// Every operating point's rotor speed, measured against the baseline's and
/// the extended model's free runs, one panel per run on one sheet: where the
/// models fail is seen in one look.
pub fn speed_sheet(d: &Diagnosis) -> Option<Sheet> {
    let traces = &d.detail.speed_traces;
    if traces.is_empty() {
        return None;
    }
    let panels = traces
        .iter()
        .map(|t| {
            let row = d.detail.runs.iter().find(|r| r.id == t.id);
            let title = match row {
                Some(r) => format!("{} · {:.0} rpm · {:.1} N", t.id, r.motor_rpm_setpoint, r.normal_force_n),
                None => t.id.clone(),
            };
            let nan = vec![f64::NAN; t.time_s.len()];
            let line = |name: &str, y: &Option<Vec<f64>>, style| Series {
                name: name.into(),
                x: t.time_s.clone(),
                y: y.clone().unwrap_or_else(|| nan.clone()),
                style,
            };
            let spec = FigureSpec {
                id: format!("diagnosis-speed-{}", t.id),
                title,
                caption: String::new(),
                x_label: "time [s]".into(),
                y_label: "Ω1 [rad/s]".into(),
                series: vec![
                    Series {
                        name: "measured".into(),
                        x: t.time_s.clone(),
                        y: t.measured_rad_s.clone(),
                        style: SeriesStyle::Line,
                    },
                    line("baseline", &t.baseline_rad_s, SeriesStyle::Dashed),
                    line("extended", &t.extended_rad_s, SeriesStyle::Line),
                ],
                x_decimals: 2,
                y_decimals: 3,
                heatmap: None,
            };
            Panel { spec, x_scale: AxisScale::Linear }
        })
        .collect();
    Some(Sheet {
        id: "diagnosis-speed-small-multiples".into(),
        title: format!("Rotor speed per operating point: measured, baseline and extended ({})", d.verdict),
        caption: "Ω1 over each operating point's steady window (after ramp + settle), measured (encoder, centred \
                  difference) and simulated from rest under the run's protocol by the baseline rig model and by the \
                  extended model of the verdict (the free runs of the diagnosis' free-run checks), sampled at 20 Hz. \
                  A panel where the dashed or the second solid line leaves the measured one is an operating point \
                  that model gets wrong; a missing line is a simulation that failed."
            .into(),
        columns: 6,
        panels,
    })
}

/// The traces of [`speed_sheet`] as one long table, one row per sample:
/// what a reader loads to redo the comparison (written with a Parquet twin).
pub fn speed_traces_table(d: &Diagnosis) -> Table {
    let mut t = Table::new(["run", "time_s", "measured_rotor_rad_s", "baseline_rotor_rad_s", "extended_rotor_rad_s"]);
    let cell = |v: Option<&Vec<f64>>, i: usize| v.and_then(|v| v.get(i)).map_or(String::new(), |x| fmt_fixed(*x, 3));
    for tr in &d.detail.speed_traces {
        for (i, &time) in tr.time_s.iter().enumerate() {
            t.push([
                tr.id.clone(),
                fmt_fixed(time, 3),
                fmt_fixed(tr.measured_rad_s[i], 3),
                cell(tr.baseline_rad_s.as_ref(), i),
                cell(tr.extended_rad_s.as_ref(), i),
            ]);
        }
    }
    t
}
