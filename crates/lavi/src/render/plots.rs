//! The study's figures (`figures/lavi-*`).

use super::*;

pub(super) fn figures(s: &Study, d: &Prepared, out: &mut StudyOutput) -> Result<(), LaviError> {
    let ev = crate::score::Evaluator::of_study(d, s.windows.clone(), &s.params)?;
    let wi = s
        .windows
        .iter()
        .position(|w| {
            (w.start_s - s.params.figure_window_start_s).abs() < 1e-9 && w.split == crate::data::Split::Heldout
        })
        .unwrap_or(1);
    let w = &s.windows[wi];
    let lp = |x: &[f64]| lowpass_fft(x, d.fs_hz, s.params.cutoff_hz, s.params.transition_hz);
    let meas_v = d.bit_rpm[w.span.clone()].to_vec();
    let meas_t = d.torque_nm[w.span.clone()].to_vec();
    let mut curves = vec![("measured".to_string(), meas_v, meas_t, SeriesStyle::Line)];
    for (name, m, style) in
        [("baseline", &s.baseline, SeriesStyle::Dashed), ("extended", &s.selection.final_model, SeriesStyle::Line)]
    {
        let r = ev.simulate(m, wi)?;
        let v: Vec<f64> = r.bit_rad_s.iter().map(|x| x / RPM_TO_RAD_S).collect();
        curves.push((name.to_string(), lp(&v)?, lp(&r.torque_nm)?, style));
    }
    // Every 10th sample (100 Hz, ten times the cut-off) of the window.
    let idx: Vec<usize> = w.window.clone().step_by(10).collect();
    let t0 = d.time_s[w.span.start];
    let time: Vec<f64> = idx.iter().map(|&i| t0 + i as f64 / d.fs_hz).collect();
    let pick = |x: &[f64]| idx.iter().map(|&i| x[i]).collect::<Vec<f64>>();
    let extended = effects_label(s);
    out.figures.push(figure(
        "lavi-bit-speed",
        &format!("LAVI run 175: bit speed over the held-out window {} s", w.label),
        &format!(
            "Bit speed measured, simulated by the baseline 1-DOF model and by the extended model ({extended}), each run free from the \
             measured state {} s before the window under the measured top speed{}; all low-passed at {} Hz, shown at 100 Hz. \
             Neither model saw this window when it was fitted.",
            s.params.warmup_s,
            if s.selection.final_model.wob_ref_n.is_some() { " and weight on bit" } else { "" },
            s.params.cutoff_hz
        ),
        ("time [s]", 2),
        ("bit speed [rpm]", 1),
        curves.iter().map(|(n, v, _, st)| series(n, time.clone(), pick(v), *st)).collect(),
    ));
    out.figures.push(figure(
        "lavi-loops",
        &format!("LAVI run 175: torque on bit against bit speed, held-out window {} s", w.label),
        &format!(
            "Torque-bit-speed trajectories of the measurement, the baseline and the extended model ({extended}) over the held-out \
             window (low-passed at {} Hz, 100 Hz). Mean loop area per cycle: measured {:.1}, baseline {:.1}, extended {:.1} N m·rpm.",
            s.params.cutoff_hz, s.measured[wi].loop_area, s.baseline_features[wi].loop_area, s.final_features[wi].loop_area
        ),
        ("bit speed [rpm]", 1),
        ("torque on bit [N m]", 3),
        curves.iter().map(|(n, v, t, st)| series(n, pick(v), pick(t), *st)).collect(),
    ));
    Ok(())
}
