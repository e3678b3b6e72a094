//! The diagnosis' evidence figures (as rig_types data; the pipeline stage
//! draws them).

use crate::result::Diagnosis;
use rig_types::{FigureSpec, MarkerShape, Series, SeriesStyle, band};

/// The evidence figures.
pub fn figures(d: &Diagnosis) -> Vec<FigureSpec> {
    let mut out = Vec::new();
    let det = &d.detail;
    if !det.mu_vs_speed.is_empty() {
        let s = |name: &str, k: usize, style| Series {
            name: name.into(),
            x: det.mu_vs_speed.iter().map(|r| r.speed_rad_s).collect(),
            y: det.mu_vs_speed.iter().map(|r| [r.measured, r.baseline, r.extended][k]).collect(),
            style,
        };
        out.push(FigureSpec {
            id: "diagnosis-friction-vs-slip".into(),
            title: "Friction coefficient against slip speed (training runs)".into(),
            caption: format!(
                "Mean observed μ = F/N0 over slip samples binned by |Ω1| (30 bins), with the baseline (Coulomb) and the \
                 verdict's model ({}) averaged over the same samples. A speed law shows as a trend; a time or angle \
                 modulation averages out here. Shaded: 95 % interval of the measured mean, Student t over the \
                 runs' own bin means (the run is the independent unit; samples within a run are correlated); no band \
                 where fewer than two runs slip that fast.",
                d.verdict
            ),
            x_label: "slip speed |Ω1| [rad/s]".into(),
            y_label: "friction coefficient μ [-]".into(),
            series: vec![
                band(
                    "measured, 95 % interval over runs",
                    &det.mu_vs_speed.iter().map(|r| r.speed_rad_s).collect::<Vec<_>>(),
                    &det.mu_vs_speed.iter().map(|r| r.measured - r.measured_half_width_95).collect::<Vec<_>>(),
                    &det.mu_vs_speed.iter().map(|r| r.measured + r.measured_half_width_95).collect::<Vec<_>>(),
                ),
                s("measured", 0, SeriesStyle::Points),
                s("baseline", 1, SeriesStyle::Dashed),
                s("extended", 2, SeriesStyle::Line),
            ],
            x_decimals: 2,
            y_decimals: 4,
            heatmap: None,
        });
    }
    if !det.freq_scan.is_empty() {
        out.push(FigureSpec {
            id: "diagnosis-frequency-scan".into(),
            title: "Residual spectrum of the friction coefficient (normal-force scan)".into(),
            caption: "Fraction of the baseline's weighted residual sum of squares explained by a sinusoid in time at each \
                      frequency (shared frequency, own amplitude and phase per run) over the training runs' slip samples. \
                      A narrow peak is a time-periodic normal force."
                .into(),
            x_label: "frequency [Hz]".into(),
            y_label: "explained fraction of RSS [-]".into(),
            series: vec![Series {
                name: "scan".into(),
                x: det.freq_scan.iter().map(|r| r.0).collect(),
                y: det.freq_scan.iter().map(|r| r.1).collect(),
                style: SeriesStyle::Line,
            }],
            x_decimals: 2,
            y_decimals: 4,
            heatmap: None,
        });
    }
    if let Some(f) = residual_vs_angle_figure(d) {
        out.push(f);
    }
    if let Some(f) = extension_figure(d) {
        out.push(f);
    }
    let dips: Vec<_> = det.runs.iter().collect();
    if !dips.is_empty() {
        let mut series = vec![Series {
            name: "measured".into(),
            x: dips.iter().map(|r| r.motor_rpm_setpoint).collect(),
            y: dips.iter().map(|r| r.measured.motor_dip_rad_s).collect(),
            style: SeriesStyle::Marker { shape: MarkerShape::Circle, filled: true },
        }];
        let sim: Vec<_> =
            dips.iter().filter_map(|r| r.simulated.map(|f| (r.motor_rpm_setpoint, f.motor_dip_rad_s))).collect();
        if !sim.is_empty() {
            series.push(Series {
                name: "baseline simulation".into(),
                x: sim.iter().map(|p| p.0).collect(),
                y: sim.iter().map(|p| p.1).collect(),
                style: SeriesStyle::Markers,
            });
        }
        out.push(motor_dips_figure(series, det.motor_speed_tick_rad_s));
    }
    if !det.signature_curve.is_empty() {
        let best = &det.signature[0];
        let part = |held: bool| Series {
            name: if held { "held-out fold".into() } else { "training folds".into() },
            x: det.signature_curve.iter().filter(|p| p.2 == held).map(|p| p.0).collect(),
            y: det.signature_curve.iter().filter(|p| p.2 == held).map(|p| p.1).collect(),
            style: if held { SeriesStyle::Markers } else { SeriesStyle::Points },
        };
        out.push(FigureSpec {
            id: "diagnosis-residual-signature".into(),
            title: format!("What the leftover mismatch follows: {} ({} channel)", best.signal, best.channel),
            caption: format!(
                "Mean residual of the final model ({} channel; relative) in 24 bins of {}, training folds and the \
                 held-out fold apart (bins with at least 10 samples). A term in this signal removes {:.0} % of the \
                 held-out residual (rig-diagnose signature module).",
                best.channel,
                best.signal,
                100.0 * best.heldout_gain
            ),
            x_label: best.signal.into(),
            y_label: "mean residual [-]".into(),
            series: vec![part(false), part(true)],
            x_decimals: 3,
            y_decimals: 4,
            heatmap: None,
        });
    }
    out
}

/// The extension's free run beside the record and the final model's, for
/// the operating point whose rotor-speed extremes the extension moves most
/// towards the record's (held-out: that run's extension was fitted without it).
fn extension_figure(d: &Diagnosis) -> Option<FigureSpec> {
    let x = d.findings.iter().find_map(|f| f.extension.as_ref())?;
    let span = |y: &[f64]| {
        let lo = y.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    };
    let miss = |m: (f64, f64), y: &Option<Vec<f64>>| {
        y.as_ref().map(|y| {
            let (lo, hi) = span(y);
            (lo - m.0).abs() + (hi - m.1).abs()
        })
    };
    let t = d
        .detail
        .extension_traces
        .iter()
        .filter_map(|t| {
            let m = span(&t.measured_rad_s);
            Some((t, miss(m, &t.baseline_rad_s)? - miss(m, &t.extended_rad_s)?))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?
        .0;
    let line = |name: &str, y: &[f64], style| Series { name: name.into(), x: t.time_s.clone(), y: y.to_vec(), style };
    Some(FigureSpec {
        id: "diagnosis-extension-free-run".into(),
        title: format!("The extension's free run beside the record ({})", t.id),
        caption: format!(
            "Rotor speed Ω1 of {} over its steady window: measured, the final model's free run and the final model \
             with the data-driven extension ({}), each simulated from rest under the run's protocol; the extension's \
             coefficients were fitted without this run's fold. The run shown is the one whose extremes the extension \
             moves most towards the record's. Cross-validated free-run misfit over every run {} → {}.",
            t.id, x.formula, x.free_run_misfit_before, x.free_run_misfit_after
        ),
        x_label: "time [s]".into(),
        y_label: "Ω1 [rad/s]".into(),
        series: vec![
            line("measured", &t.measured_rad_s, SeriesStyle::Line),
            line("final model", t.baseline_rad_s.as_deref()?, SeriesStyle::Dashed),
            line("with the extension", t.extended_rad_s.as_deref()?, SeriesStyle::Line),
        ],
        x_decimals: 2,
        y_decimals: 3,
        heatmap: None,
    })
}

/// μ residual against rotor angle for the run with most slip: the mean over
/// revolutions in each angle bin with its 95 % interval as a band (select.rs
/// says why revolutions are the unit), so a reader sees whether a wave
/// stands out of its own uncertainty.
fn residual_vs_angle_figure(d: &Diagnosis) -> Option<FigureSpec> {
    let r = &d.detail.residual_vs_angle;
    if r.is_empty() {
        return None;
    }
    let x: Vec<f64> = r.iter().map(|r| r.0).collect();
    let revs = (r.iter().map(|r| r.4).min()?, r.iter().map(|r| r.4).max()?);
    Some(FigureSpec {
        id: "diagnosis-residual-vs-angle".into(),
        title: "Friction residual against rotor angle (training run with most slip)".into(),
        caption: format!(
            "μ_obs − μk over slip samples in 72 bins of the rotor angle φ1 mod 2π: in each bin the mean over the \
             revolutions that pass through it ({}–{} per bin) of the per-revolution mean, with its 95 % interval \
             (±1.96 standard errors over revolutions; samples within one pass are correlated, so a pass is the \
             unit). A warped or eccentric disc shows n periods per revolution standing out of the band; a wave \
             inside it is not evidence.",
            revs.0, revs.1
        ),
        x_label: "rotor angle mod 2π [rad]".into(),
        y_label: "μ residual [-]".into(),
        series: vec![
            band(
                "95 % interval of the mean",
                &x,
                &r.iter().map(|r| r.2).collect::<Vec<_>>(),
                &r.iter().map(|r| r.3).collect::<Vec<_>>(),
            ),
            Series {
                name: "mean over revolutions".into(),
                x: x.clone(),
                y: r.iter().map(|r| r.1).collect(),
                style: SeriesStyle::Line,
            },
            Series {
                name: "zero".into(),
                x: vec![0.0, 2.0 * std::f64::consts::PI],
                y: vec![0.0, 0.0],
                style: SeriesStyle::Dashed,
            },
        ],
        x_decimals: 3,
        y_decimals: 4,
        heatmap: None,
    })
}

/// The motor-speed dips with the resolution of the speed they are read from:
/// a dip of one encoder tick over the differentiator window is quantisation,
/// so that level is drawn as a shaded band from 0 and named in the caption.
fn motor_dips_figure(mut series: Vec<Series>, tick_rad_s: f64) -> FigureSpec {
    let xs: Vec<f64> = series.iter().flat_map(|s| s.x.iter().copied()).filter(|x| x.is_finite()).collect();
    let (lo, hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    if tick_rad_s > 0.0 && lo.is_finite() {
        series.push(band(
            &format!("below 1 encoder tick per differentiator window ({tick_rad_s:.3} rad/s)"),
            &[lo, hi],
            &[0.0, 0.0],
            &[tick_rad_s, tick_rad_s],
        ));
    }
    FigureSpec {
        id: "diagnosis-motor-dips".into(),
        title: "Deepest motor-speed dip below the set-point, per operating point".into(),
        caption: format!(
            "Largest Ω_set − Ω2 over each run's steady state (after ramp + settle). A drive that saturates lets the \
             motor slow while the rotor is stuck; the PI loop of the baseline holds it. Ω2 comes from encoder ticks \
             through a centred difference, so it moves in steps of one tick over the differentiator window \
             ({tick_rad_s:.3} rad/s, the grey band): a dip inside the band is quantisation, not a slow-down."
        ),
        x_label: "motor set-point [rpm]".into(),
        y_label: "motor speed dip [rad/s]".into(),
        series,
        x_decimals: 1,
        y_decimals: 3,
        heatmap: None,
    }
}
