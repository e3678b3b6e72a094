//! The study's figures (`figures/slider-*`).

use super::*;

pub(super) fn figures(s: &Study, out: &mut StudyOutput) {
    let ext = extension(s);
    let base = &s.candidates[0];
    for (i, r) in s.runs.iter().enumerate() {
        let (t, meas) = &s.traces[i];
        let mut sers = vec![series("measured (running median)", t.clone(), meas.clone(), SeriesStyle::Line)];
        for (c, style) in [(base, SeriesStyle::Dashed), (ext, SeriesStyle::Line)] {
            if style == SeriesStyle::Line && std::ptr::eq(c, base) {
                continue; // no candidate besides the baseline
            }
            let (ts, fs) = predict_trace(c.model, &full_fit(c).params, r, &s.params, t.len());
            sers.push(series(&format!("{} (fitted on the calibration runs)", c.model.id()), ts, fs, style));
        }
        out.figures.push(figure(
            &format!("slider-force-{}", r.name),
            &format!("Slider {}: spring force over weight, measured and simulated", r.name),
            &format!(
                "k = {} N/m, V = {} µm/s. Measured force after the running median of {} s, over about {} of its slip periods, \
                 against the Coulomb baseline and the extension ({}) fitted on the calibration runs, each simulated from a \
                 preloaded spring at rest and shown after its warm-up (time from the start of the shown stretch).",
                r.stiffness_n_m,
                r.drive_speed_um_s,
                s.params.features.median_window_s,
                s.params.sim_periods,
                ext.model.id()
            ),
            ("time [s]", 4),
            ("F/(m g)", 4),
            sers,
        ));
    }
    // Feature against driving speed, per stiffness: measured (markers) and the extension's held-out prediction.
    for (id, name, pick) in [
        ("slider-period", "period [s]", (|f: &Features| f.period_s.median) as fn(&Features) -> f64),
        ("slider-drop", "force drop per slip, F/(m g)", |f: &Features| f.drop.median),
        ("slider-onset", "force at slip onset, F/(m g)", |f: &Features| f.onset.median),
    ] {
        let mut sers = Vec::new();
        for k in distinct(s.runs.iter().map(|r| r.stiffness_n_m)) {
            let idx: Vec<usize> = (0..s.runs.len()).filter(|&i| s.runs[i].stiffness_n_m == k).collect();
            let x: Vec<f64> = idx.iter().map(|&i| s.runs[i].drive_speed_um_s.log10()).collect();
            sers.push(series(
                &format!("measured, k = {k} N/m"),
                x.clone(),
                idx.iter().map(|&i| pick(&s.runs[i].features)).collect(),
                SeriesStyle::Markers,
            ));
            for (c, style) in [(&s.candidates[0], SeriesStyle::Dashed), (ext, SeriesStyle::Line)] {
                let y: Vec<f64> = idx
                    .iter()
                    .map(|&i| c.heldout.iter().find(|h| h.0 == i).map(|h| pick(&h.2)).unwrap_or(f64::NAN))
                    .collect();
                sers.push(series(&format!("{} held out, k = {k} N/m", c.model.id()), x.clone(), y, style));
            }
        }
        out.figures.push(figure(
            id,
            &format!("Slider: {name} against driving speed"),
            &format!(
                "Median over the slip events of each run (markers: measured), and the prediction of the Coulomb baseline \
                 (dashed) and of {} (line) for runs held out of their fit ({}). NaN where a record has no slip.",
                ext.model.id(),
                if s.leave_one_out { "leave one stiffness out" } else { "fitted on the calibration stiffnesses" }
            ),
            ("log10 V [µm/s]", 3),
            (name, 4),
            sers,
        ));
    }
}

pub(super) fn distinct(v: impl Iterator<Item = f64>) -> Vec<f64> {
    let mut out: Vec<f64> = v.collect();
    out.sort_by(f64::total_cmp);
    out.dedup();
    out
}
