//! Drive PI gains from operating-point runs by linear least squares,
//! V = kp·e + ki·∫e with e = Ω_ref − Ω2 (the drive law of rig_types::DriveParams).
//!
//! Why window averages: averaging both sides over a window [a, b] keeps the
//! law exact, and the mean error needs no derivative:
//! ē = (I(b) − I(a))/(b − a) with I(t) = ∫e = ∫Ω_ref dt − φ2(t) (φ2 from the
//! encoder, zero at t = 0). Longer windows shrink the encoder quantisation in
//! ē (errors-in-variables bias on kp) without smoothing bias.
//! Offsets: every unsaturated segment of a run gets its own constant c_k.
//! After a saturation episode the drive's integrator differs from ∫e by an
//! unknown constant (anti-windup of unknown form); and even before any, the
//! encoder's count is the angle rounded one way or the other, a constant of
//! up to one count in I that, times ki, is a voltage offset which would bias
//! kp by 20 % in the round-trip test if not absorbed. ki stays identified by
//! the variation of ∫e within a segment.

use crate::{EstimateError, linear};
use rig_types::sensor::{median_window_samples, ticks_to_rad, window_samples};
use rig_types::{Campaign, Run, RunKind};
use serde::{Deserialize, Serialize};

/// How the encoder quantisation in the regressors is handled.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum PiMethod {
    /// Corrected least squares: subtract the known quantisation variance
    /// (Δ²/12 per encoder sample, independent between samples while the
    /// motor turns) from the normal equations.
    CorrectedLs,
    /// Instrumental variables: ē instrumented by the mean error over the
    /// window widened by half a window on each side.
    Iv,
    /// Plain least squares, ignoring the quantisation (biased: kp attenuated);
    /// kept to show the size of the correction.
    Ols,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PiOptions {
    pub method: PiMethod,
    /// Averaging window, s (counted in samples from each run's time column).
    /// Long windows keep the encoder quantisation in ē small against ē's own
    /// variation: at 1000 counts/rev and 500 Hz the round-trip test gives kp
    /// −7 % at 25 samples (50 ms), within 0.1 % at 100 (200 ms).
    pub window_s: f64,
    /// A sample is saturated when |V| ≥ limit − margin.
    pub saturation_margin_v: f64,
    /// Unsaturated segments (after a saturation) shorter than this many windows are dropped.
    pub min_segment_windows: usize,
}

impl Default for PiOptions {
    fn default() -> Self {
        PiOptions { method: PiMethod::CorrectedLs, window_s: 0.5, saturation_margin_v: 0.5, min_segment_windows: 4 }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct PiEstimate {
    pub kp_v_s_rad: f64,
    pub kp_stderr: f64,
    pub ki_v_rad: f64,
    pub ki_stderr: f64,
    /// Fraction of all operating-point samples at or beyond the saturation threshold.
    pub saturated_fraction: f64,
    /// Windows used in the regression.
    pub n_windows: usize,
    /// Per-segment offsets estimated (one per run and per saturation episode).
    pub n_offsets: usize,
    /// RMS of the regression residual, V.
    pub residual_rms_v: f64,
    /// A saturation plateau of |V| found in the records (see [`voltage_plateau_v`]).
    pub voltage_plateau_v: Option<f64>,
}

/// ∫₀ᵗ Ω_ref dt of the ramp 0 → ω_sp over ramp_s, then constant (rad).
pub fn reference_angle_rad(t: f64, setpoint_rad_s: f64, ramp_s: f64) -> f64 {
    if ramp_s <= 0.0 {
        setpoint_rad_s * t
    } else if t < ramp_s {
        setpoint_rad_s * t * t / (2.0 * ramp_s)
    } else {
        setpoint_rad_s * (ramp_s / 2.0 + (t - ramp_s))
    }
}

/// Trapezoidal ∫ₐᵇ y dt over samples a..=b.
fn trapz(t: &[f64], y: &[f64], a: usize, b: usize) -> f64 {
    (a..b).map(|i| 0.5 * (y[i] + y[i + 1]) * (t[i + 1] - t[i])).sum()
}

/// A saturation plateau in the recorded voltages below the supply, or
/// `None`. Its level is the largest of the runs' 99th percentiles of |V|,
/// `L` (a quantile, not the extreme: the maximum of a clipped run's tens of
/// thousands of noisy samples sits 4–6 σ_V above the clip, so samples
/// "within 0.1 V of the maximum" were only the noise's tail — 0.3 % of the
/// clipped runs' samples at σ_V = 0.032 V in the full battery's
/// `ladder-drive_voltage_limit-3-2`, whose 5.62 V clip went unseen and
/// wrecked the PI gains: kp 0.46 against 1.90, ki 0.0003 against 12.4). A
/// drive that clips piles samples up at one level, seen in either of two
/// ways:
/// - in at least two runs, each with 0.5 % of its samples within
///   [`PLATEAU_BAND_V`] of `L` and its motor falling behind its reference
///   from its first sample on the band to the run's end, the PI error's
///   integral growing by at least [`CLIP_LAG_TICKS`] encoder ticks
///   ([`lags_from_level`]). Runs that merely share an operating point
///   share a steady voltage too (five operating points at 40 rpm under
///   2–12 N held 2.49–2.59 V; every sample within the band of their 2.63 V
///   level, so none was left to fit the gains: twentieth session), but
///   their motor reaches the set-point: their integral moved by 1–8 ticks
///   from the band's first sample on (the same in the two 110 rpm runs of
///   `any_protocol.rs`' small protocol), where every run the two-run rule
///   counts in the full battery's drive-limit cases lags by 488 ticks or
///   more (a clipped drive cannot hold the speed: the error persists), or
/// - in one run that holds the level ([`holds_clipped`]): at least half its
///   samples after the ramp within the band while the motor falls behind
///   its reference, the PI error's integral growing by at least
///   [`CLIP_LAG_TICKS`] encoder ticks after the ramp. A PI with integral
///   action holds that integral bounded unless its output is clipped; a
///   steady run at its own level does not lag, and a stick-slipping run's
///   voltage swings far beyond the band. The weakest rung of the
///   battery's drive limit clips one run only, which the two-run rule
///   cannot see and whose plateau samples then gave kp −7.4
///   (`ladder-drive_voltage_limit-5-4`: op-16 at 7.14 V, 0.7 % slow for
///   the whole run) or −4.3 (`-5-11`: op-16 at 7.07 V, clipped from the
///   ramp to 14 s while its integral grew by 100 ticks, then just below
///   the limit).
///
/// Blind evidence of a drive limit below the nominal supply.
pub fn voltage_plateau_v(c: &Campaign) -> Option<f64> {
    let runs: Vec<&Run> = c.runs_of("operating_point").filter(|r| r.data.motor_voltage_v.is_some()).collect();
    fn volts(r: &Run) -> &[f64] {
        r.data.motor_voltage_v.as_deref().unwrap_or(&[])
    }
    let top = |v: &[f64]| {
        let mut a: Vec<f64> = v.iter().map(|x| x.abs()).collect();
        if a.is_empty() {
            return 0.0;
        }
        let k = ((0.99 * a.len() as f64) as usize).min(a.len() - 1);
        *a.select_nth_unstable_by(k, f64::total_cmp).1
    };
    let level = runs.iter().map(|r| top(volts(r))).fold(0.0_f64, f64::max);
    let near = |v: &[f64]| v.iter().filter(|x| x.abs() >= level - PLATEAU_BAND_V).count();
    let shared = runs
        .iter()
        .filter(|r| {
            let v = volts(r);
            !v.is_empty() && near(v) as f64 >= 0.005 * v.len() as f64 && lags_from_level(c, r, level)
        })
        .count();
    (level > 0.0 && (shared >= 2 || runs.iter().any(|r| holds_clipped(c, r, level)))).then_some(level)
}

/// How close to the plateau's level a sample counts as on it, V.
pub const PLATEAU_BAND_V: f64 = 0.1;

/// Encoder ticks the PI error's integral must grow by after the ramp for
/// [`holds_clipped`]: a clipped drive lags (the one clipped run of
/// `ladder-drive_voltage_limit-5-11`, `-5-12`, `-5-14`: 101, 61 and 41
/// ticks); an unclipped PI's integral settles after the ramp, moving by
/// ΔV/ki as the acceleration torque goes (the same campaigns' unclipped
/// runs at the top set speed: 5–7 ticks).
pub const CLIP_LAG_TICKS: f64 = 20.0;

/// One run holding the voltage `level` while its motor falls behind the
/// reference ([`voltage_plateau_v`]'s second way): at least half its
/// samples after the ramp within [`PLATEAU_BAND_V`] of the level, and
/// ∫(Ω_ref − Ω2) dt growing by at least [`CLIP_LAG_TICKS`] ticks from the
/// ramp's end to the run's.
fn holds_clipped(c: &Campaign, r: &Run, level: f64) -> bool {
    let RunKind::OperatingPoint { ramp_s, .. } = r.kind else { return false };
    let (Some(v), Some(ticks)) = (r.data.motor_voltage_v.as_ref(), r.data.motor_ticks.as_ref()) else { return false };
    let t = &r.data.time_s;
    let from = t.partition_point(|&x| x < ramp_s);
    let n = t.len().min(v.len()).min(ticks.len());
    if n < from + 4 {
        return false;
    }
    let on = v[from..n].iter().filter(|x| x.abs() >= level - PLATEAU_BAND_V).count();
    2 * on >= n - from && lags_from(c, r, from)
}

/// Whether the motor of `r` falls behind its reference from its first
/// sample within [`PLATEAU_BAND_V`] of `level` to the run's end
/// ([`voltage_plateau_v`]'s two-run rule; [`lags_from`]).
fn lags_from_level(c: &Campaign, r: &Run, level: f64) -> bool {
    let v = r.data.motor_voltage_v.as_deref().unwrap_or(&[]);
    v.iter().position(|x| x.abs() >= level - PLATEAU_BAND_V).is_some_and(|k| lags_from(c, r, k))
}

/// Whether ∫(Ω_ref − Ω2) dt of operating point `r` (the PI error's
/// integral, Ω_ref the ramped set-point of [`reference_angle_rad`]) grows
/// by at least [`CLIP_LAG_TICKS`] encoder ticks from sample `from` to the
/// run's last: a PI with integral action holds it bounded unless its
/// output is clipped.
fn lags_from(c: &Campaign, r: &Run, from: usize) -> bool {
    let RunKind::OperatingPoint { motor_rpm_setpoint, ramp_s, .. } = r.kind else { return false };
    let (Some(v), Some(ticks)) = (r.data.motor_voltage_v.as_ref(), r.data.motor_ticks.as_ref()) else { return false };
    let t = &r.data.time_s;
    let n = t.len().min(v.len()).min(ticks.len());
    if from >= n {
        return false;
    }
    let sp = rig_types::units::rpm_to_rad_s(motor_rpm_setpoint);
    let tick = rig_types::sensor::tick_rad(c.rig.encoder_ticks_per_rev);
    let integral = |k: usize| reference_angle_rad(t[k], sp, ramp_s) - ticks[k] as f64 * tick;
    integral(n - 1) - integral(from) >= CLIP_LAG_TICKS * tick
}

/// Estimates kp, ki from every operating-point run of `c`, drive limit `limit_v`
/// (the supply; a lower plateau found by [`voltage_plateau_v`] takes precedence
/// for deciding which samples are saturated).
pub fn estimate_pi(c: &Campaign, limit_v: f64, opts: &PiOptions) -> Result<PiEstimate, EstimateError> {
    let plateau = voltage_plateau_v(c);
    let limit_v = plateau.map_or(limit_v, |p| p.min(limit_v));
    // Rows: (ē, Ī, offset index or None, V̄).
    let mut rows: Vec<(f64, f64, Option<usize>, f64, f64)> = Vec::new();
    let mut n_offsets = 0usize;
    let (mut total, mut saturated) = (0usize, 0usize);
    // Each run's window count, as its rows are made (the noise correction's window).
    let mut counts: Vec<usize> = Vec::new();
    for run in c.runs_of("operating_point") {
        let RunKind::OperatingPoint { motor_rpm_setpoint, ramp_s, .. } = run.kind else { continue };
        let d = &run.data;
        let missing = |column| EstimateError::MissingColumn { run: run.id.clone(), column, kind: "operating_point" };
        let v = d.motor_voltage_v.as_ref().ok_or_else(|| missing("motor_voltage_v"))?;
        let ticks = d.motor_ticks.as_ref().ok_or_else(|| missing("motor_ticks"))?;
        let t = &d.time_s;
        let w = window_samples(t, opts.window_s).max(1);
        counts.push(w);
        let phi2 = ticks_to_rad(ticks, c.rig.encoder_ticks_per_rev);
        let sp = rig_types::units::rpm_to_rad_s(motor_rpm_setpoint);
        let integral: Vec<f64> = t.iter().zip(&phi2).map(|(&ti, &p)| reference_angle_rad(ti, sp, ramp_s) - p).collect();
        let sat: Vec<bool> = v.iter().map(|x| x.abs() >= limit_v - opts.saturation_margin_v).collect();
        total += v.len();
        saturated += sat.iter().filter(|s| **s).count();
        // Segment of a sample = number of saturation episodes that began before it.
        let mut episodes_before = Vec::with_capacity(sat.len());
        let mut count = 0usize;
        for (j, &s) in sat.iter().enumerate() {
            if s && (j == 0 || !sat[j - 1]) {
                count += 1;
            }
            episodes_before.push(count);
        }
        let mut seg_rows: Vec<(f64, f64, usize, f64, f64)> = Vec::new();
        let mut i = 0;
        let h = (w / 2).max(1);
        while i + w < t.len() {
            if let Some(off) = (i..=i + w).rev().find(|&j| sat[j]) {
                i = off + 1;
                continue;
            }
            if i < h || i + w + h >= t.len() {
                i += w;
                continue;
            }
            let dt = t[i + w] - t[i];
            let e_mean = (integral[i + w] - integral[i]) / dt;
            let i_mean = trapz(t, &integral, i, i + w) / dt;
            let v_mean = trapz(t, v, i, i + w) / dt;
            // Instrument: the mean error over the window widened by h on each
            // side. It tracks ē closely but shares no encoder sample with it,
            // so its quantisation error is independent of ē's.
            let (za, zb) = (i - h, i + w + h);
            let z = (integral[zb] - integral[za]) / (t[zb] - t[za]);
            seg_rows.push((e_mean, i_mean, episodes_before[i], v_mean, z));
            i += w;
        }
        let max_seg = seg_rows.iter().map(|r| r.2).max().unwrap_or(0);
        for s in 0..=max_seg {
            let these: Vec<_> = seg_rows.iter().filter(|r| r.2 == s).collect();
            if these.len() >= opts.min_segment_windows {
                rows.extend(these.iter().map(|r| (r.0, r.1, Some(n_offsets), r.3, r.4)));
                n_offsets += 1;
            }
        }
    }
    let p = 2 + n_offsets;
    if rows.len() < p + 2 {
        return Err(EstimateError::TooFewSamples {
            context: format!("campaign {}: PI gains from operating_point runs", c.name),
            got: rows.len(),
            need: p + 2,
            rule: "need unsaturated windows (|V| < supply − margin) in the operating points",
        });
    }
    let x: Vec<Vec<f64>> = rows
        .iter()
        .map(|r| {
            let mut row = vec![0.0; p];
            row[0] = r.0;
            row[1] = r.1;
            if let Some(k) = r.2 {
                row[2 + k] = 1.0;
            }
            row
        })
        .collect();
    let y: Vec<f64> = rows.iter().map(|r| r.3).collect();
    let z: Vec<Vec<f64>> = rows
        .iter()
        .zip(&x)
        .map(|(r, xr)| {
            let mut zr = xr.clone();
            zr[0] = r.4;
            zr
        })
        .collect();
    // ē = (I(b) − I(a))/Δt carries the encoder quantisation of φ2 at both
    // ends; as a regressor that attenuates kp (errors in variables: −20 % in
    // the round-trip test with plain least squares).
    let fit = match opts.method {
        PiMethod::CorrectedLs => {
            // Var of ē: 2·(Δ²/12)/Δt²; of Ī (trapezoid mean of w + 1 samples): ≈ (Δ²/12)/(w + 1).
            let q = rig_types::sensor::tick_rad(c.rig.encoder_ticks_per_rev).powi(2) / 12.0;
            // The windows the rows were made of: the runs' count (their
            // median; one recorder, one count) over the operating points'
            // clock (their time columns, `Campaign::clock_rate_hz`): ē
            // divides by the time its w samples took.
            let rate_hz = c.clock_rate_hz("operating_point");
            let w = median_window_samples(std::mem::take(&mut counts), opts.window_s, rate_hz);
            let dt = w as f64 / rate_hz;
            let mut noise_var = vec![0.0; p];
            noise_var[0] = 2.0 * q / (dt * dt);
            noise_var[1] = q / (w + 1) as f64;
            linear::ols_eiv(&x, &y, &noise_var, "PI gains: V = kp·e + ki·∫e + offsets")?
        }
        PiMethod::Iv => linear::iv(&x, &z, &y, "PI gains: V = kp·e + ki·∫e + offsets")?,
        PiMethod::Ols => linear::ols(&x, &y, "PI gains: V = kp·e + ki·∫e + offsets")?,
    };
    Ok(PiEstimate {
        kp_v_s_rad: fit.beta[0],
        kp_stderr: fit.stderr[0],
        ki_v_rad: fit.beta[1],
        ki_stderr: fit.stderr[1],
        saturated_fraction: if total > 0 { saturated as f64 / total as f64 } else { 0.0 },
        n_windows: rows.len(),
        n_offsets,
        residual_rms_v: (fit.ssr / rows.len() as f64).sqrt(),
        voltage_plateau_v: plateau,
    })
}
