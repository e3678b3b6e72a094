//! Voltage-step checks: the free response of the calibrated model against
//! the record (brake open, so no brake effect of the vocabulary acts here).

use super::{ChannelCheck, ChannelOptions, rms};
use rig_calibrate::CampaignCalibration;
use rig_estimate::steps::{simulate_step, step_data};
use rig_model::SimOptions;
use rig_types::sensor::{median_window_samples, speed_resolution_rad_s, window_samples};
use rig_types::{Campaign, RigParams};

/// Spread of per-step values around their mean, and the RMS of their
/// standard errors scaled by √((m−1)/m) (what the spread is under noise alone).
fn spread(v: &[(f64, f64)]) -> (f64, f64) {
    let m = v.len() as f64;
    let mean = v.iter().map(|x| x.0).sum::<f64>() / m;
    let d: Vec<f64> = v.iter().map(|x| x.0 - mean).collect();
    let se: Vec<f64> = v.iter().map(|x| x.1).collect();
    (rms(&d), rms(&se) * ((m - 1.0) / m).sqrt())
}

/// The three voltage-step checks.
///
/// - frequency and decay vs amplitude: the linear model (Eq. 4-7 with the
///   viscous C of Eq. 4-2/4-3) has one damped frequency ω_d and one log
///   decrement δ whatever the step voltage; the calibration measures both
///   per step from the twist φ2 − φ1 (Eqs. 4-2a, 4-3). The statistic is their
///   spread over the steps; the floor the spread of their standard errors
///   (pair scatter / √pairs, at least the timing resolution dt/T for ω_d
///   and √2·tick/swing for δ). A shaft with dry friction or a stiffening
///   spring makes them move with amplitude.
/// - residual: the baseline simulated for each step (rig_model, from rest)
///   against the 50 ms window-mean speeds of both encoders (the estimate's
///   own operator, rig_estimate::steps); per run the RMS residual, over the
///   runs their RMS; floor: the window speed quantisation, resolution/√6
///   (difference of two independent uniform errors of one tick).
pub fn voltage_step_checks(
    c: &Campaign,
    cal: &CampaignCalibration,
    baseline: &RigParams,
    o: &ChannelOptions,
    window_s: f64,
    sim: &SimOptions,
) -> Vec<ChannelCheck> {
    let mut out = Vec::new();
    let tick_rad = rig_types::sensor::tick_rad(c.rig.encoder_ticks_per_rev);
    // The steps' sample rate as their time columns measure it: the timing
    // resolution and the window's duration are the elapsed time's.
    let rate_hz = c.clock_rate_hz("voltage_step");
    let dt = 1.0 / rate_hz;
    let ids: Vec<String> = cal.steps.iter().map(|s| s.id.clone()).collect();
    let mut freq = Vec::new();
    let mut dec = Vec::new();
    for s in &cal.steps {
        let a = &s.twist;
        let p = a.pairs.len().max(1) as f64;
        let period = a.pairs.iter().map(|q| q.t2_s - q.t1_s).sum::<f64>() / p;
        let swing = a.pairs.iter().map(|q| q.x2).sum::<f64>() / p;
        freq.push((a.damped_rad_s_mean, (a.damped_rad_s_std / p.sqrt()).max(a.damped_rad_s_mean * dt / period)));
        dec.push((a.log_decrement_mean, (a.log_decrement_std / p.sqrt()).max(2f64.sqrt() * tick_rad / swing)));
    }
    if freq.len() < 2 {
        for ch in ["voltage_step.frequency", "voltage_step.decay"] {
            out.push(ChannelCheck::not_testable(
                ch,
                ids.clone(),
                format!("{} steps with a decay: 2 needed", freq.len()),
            ));
        }
    } else {
        let text = |v: &[(f64, f64)]| {
            v.iter()
                .zip(&cal.steps)
                .map(|(x, s)| format!("{:.3} at {} V", x.0, s.voltage_v))
                .collect::<Vec<_>>()
                .join(", ")
        };
        let (s, f) = spread(&freq);
        out.push(ChannelCheck::new(
            "voltage_step.frequency",
            ids.clone(),
            s,
            f,
            o.step_frequency_ratio,
            format!("damped twist frequency per step, rad/s: {}", text(&freq)),
        ));
        let (s, f) = spread(&dec);
        out.push(ChannelCheck::new(
            "voltage_step.decay",
            ids.clone(),
            s,
            f,
            o.step_decay_ratio,
            format!("log decrement per step: {}", text(&dec)),
        ));
    }

    // The windows `step_data` made: each step's count from its time column
    // (`window_samples`; their median, one recorder, one count), their
    // duration at the steps' clock (a window at the clock can round the
    // other way: 0.05 s at 510 Hz is 25.5 samples).
    let counts = c.runs_of("voltage_step").map(|r| window_samples(&r.data.time_s, window_s).max(1)).collect();
    let w = median_window_samples(counts, window_s, rate_hz);
    let Ok(data) = step_data(c, window_s) else {
        out.push(ChannelCheck::not_testable("voltage_step.residual", ids, "no usable voltage_step run".into()));
        return out;
    };
    use rayon::prelude::*;
    let per_run: Vec<Option<(f64, f64)>> = data
        .par_iter()
        .map(|s| {
            let (m2, m1) = simulate_step(baseline, s, sim).ok()?;
            let r: Vec<f64> = s
                .motor_speed_rad_s
                .iter()
                .zip(&m2)
                .chain(s.rotor_speed_rad_s.iter().zip(&m1))
                .map(|(a, b)| a - b)
                .collect();
            // Lag-1 autocorrelation of the residual: structure, not quantisation, when near 1.
            let var: f64 = r.iter().map(|x| x * x).sum();
            let lag: f64 = r.windows(2).map(|p| p[0] * p[1]).sum();
            Some((rms(&r), if var > 0.0 { lag / var } else { 0.0 }))
        })
        .collect();
    let ids: Vec<String> = data.iter().map(|s| s.id.clone()).collect();
    let ok: Vec<(f64, f64)> = per_run.iter().flatten().copied().collect();
    if ok.is_empty() {
        out.push(ChannelCheck::not_testable("voltage_step.residual", ids, "the model did not integrate".into()));
        return out;
    }
    let stat = rms(&ok.iter().map(|x| x.0).collect::<Vec<_>>());
    let floor = speed_resolution_rad_s(c.rig.encoder_ticks_per_rev, w, dt) / 6f64.sqrt();
    let rows: Vec<String> = ids
        .iter()
        .zip(&per_run)
        .filter_map(|(id, r)| r.map(|r| format!("{id} {:.3} rad/s (ρ1 {:.2})", r.0, r.1)))
        .collect();
    out.push(ChannelCheck::new(
        "voltage_step.residual",
        ids,
        stat,
        floor,
        o.step_residual_ratio,
        format!("free response of the baseline vs the {w}-sample window speeds, RMS per step: {}", rows.join(", ")),
    ));
    out
}
