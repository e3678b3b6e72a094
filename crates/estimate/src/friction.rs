//! Baseline Coulomb friction of the brake (μs, μk) from the operating points:
//! the force sensor measures the tangential pad force F directly, so
//! μ = T1/(N0·r) = F/N0 (Eq. 4-10 with T1 = μ·N·r).
//!
//! μk: mean μ over slip samples (Ω1 above a threshold), per run, pooled.
//! μs: the peak μ of each stick episode up to break-away (while stuck, the
//! pad force is whatever holds the rotor; it peaks at μs·N0 when it lets go),
//! median over episodes (robust to a missed or truncated episode).

use crate::EstimateError;
use crate::signals::{mean_sd, median};
use rig_types::sensor::{
    ForceCal, central_difference_rad_s as central_speed, force_n, half_window_samples, nominal_window_samples,
    speed_resolution_rad_s, ticks_to_rad,
};
use rig_types::{Campaign, RunKind};
use serde::{Deserialize, Serialize};
use std::ops::Range;

/// pipeline.toml's `[shared.stick_episodes]`: the estimation's μs/μk and the
/// diagnosis' break-away level under its extended model read stick and slip
/// with the same rules.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(default, deny_unknown_fields)]
pub struct FrictionOptions {
    /// Half-width of the centred difference for Ω1, s (counted in samples
    /// from each run's time column).
    pub speed_half_window_s: f64,
    /// Ω1 above this is slip. Must sit well above the speed resolution of the
    /// difference (one count over 2·half samples) so no stuck sample passes.
    pub slip_threshold_rad_s: f64,
    /// Stick episodes shorter than this are not counted (a chatter blip is no break-away).
    pub min_stick_s: f64,
    /// Runs with N0 below this are skipped (μ = F/N0 ill-conditioned, brake barely closed).
    pub min_normal_force_n: f64,
}

impl Default for FrictionOptions {
    fn default() -> Self {
        FrictionOptions {
            speed_half_window_s: 0.02,
            slip_threshold_rad_s: 0.5,
            min_stick_s: 0.05,
            min_normal_force_n: 0.5,
        }
    }
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrictionEstimate {
    pub mu_static: f64,
    /// None when fewer than 2 episodes (no scatter to estimate it from).
    pub mu_static_stderr: Option<f64>,
    pub mu_kinetic: f64,
    /// None when fewer than 2 runs slip.
    pub mu_kinetic_stderr: Option<f64>,
    pub n_stick_episodes: usize,
    pub n_slip_samples: usize,
    /// Runs that contributed a μk value.
    pub n_slip_runs: usize,
}

/// μ samples and stick/slip analysis of one run.
#[derive(Debug, Clone, PartialEq)]
pub struct RunFriction {
    /// Mean μ over slip samples, with the count.
    pub mu_slip: Option<(f64, usize)>,
    /// Peak μ of each stick episode that ended in break-away.
    pub breakaway_peaks: Vec<f64>,
}

/// Analyses one trace: times, rotor angle (rad), pad force (N), normal force N0.
pub fn analyse_trace(
    time_s: &[f64],
    rotor_angle_rad: &[f64],
    force_n: &[f64],
    normal_force_n: f64,
    opts: &FrictionOptions,
) -> RunFriction {
    analyse_trace_normal(time_s, rotor_angle_rad, force_n, &|_| normal_force_n, opts)
}

/// [`analyse_trace`] with a normal force that varies along the run,
/// `normal_force_n(sample index)`: μ = F/N(t). The baseline has N = N0; a
/// model whose normal force is modulated (rig_model::friction::normal_force_n)
/// reads its own break-away level from the same episodes (the diagnosis'
/// `breakaway` module).
pub fn analyse_trace_normal(
    time_s: &[f64],
    rotor_angle_rad: &[f64],
    force_n: &[f64],
    normal_force_n: &dyn Fn(usize) -> f64,
    opts: &FrictionOptions,
) -> RunFriction {
    let h = half_window_samples(time_s, opts.speed_half_window_s).max(1);
    let omega = central_speed(time_s, rotor_angle_rad, h);
    let mu: Vec<f64> = force_n.iter().enumerate().map(|(i, f)| f / normal_force_n(i)).collect();
    let slip: Vec<usize> = (0..omega.len()).filter(|&i| omega[i].abs() > opts.slip_threshold_rad_s).collect();
    let mu_slip =
        (!slip.is_empty()).then(|| (slip.iter().map(|&i| mu[i].abs()).sum::<f64>() / slip.len() as f64, slip.len()));

    let peaks = episodes_of(time_s, &omega, h, opts)
        .into_iter()
        .map(|r| r.map(|j| mu[j].abs()).fold(0.0_f64, f64::max))
        .collect();
    RunFriction { mu_slip, breakaway_peaks: peaks }
}

/// The stick episodes of one trace that end in a break-away, by the rules of
/// [`FrictionOptions`] (`[shared.stick_episodes]`): each as the sample range
/// over which its break-away peak is read, [first stuck sample, first moving
/// sample + h) with h the speed difference's half window. The one definition
/// of a break-away for the estimation's μs ([`analyse_trace_normal`]) and the
/// diagnosis' free-run `breakaway_friction` feature (a simulated angle is read
/// through the encoder first, so both sides pass the same rule).
pub fn stick_episodes(time_s: &[f64], rotor_angle_rad: &[f64], opts: &FrictionOptions) -> Vec<Range<usize>> {
    let h = half_window_samples(time_s, opts.speed_half_window_s).max(1);
    episodes_of(time_s, &central_speed(time_s, rotor_angle_rad, h), h, opts)
}

/// [`stick_episodes`] on the centred-difference speed `omega` of half window `h`.
fn episodes_of(time_s: &[f64], omega: &[f64], h: usize, opts: &FrictionOptions) -> Vec<Range<usize>> {
    // Stuck: the encoder did not move over ±h samples (speed estimate exactly 0).
    let stuck: Vec<bool> = omega.iter().map(|w| *w == 0.0).collect();
    let mut out = Vec::new();
    let mut i = 0;
    let n = stuck.len();
    while i < n {
        if !stuck[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && stuck[i] {
            i += 1;
        }
        let end = i; // first non-stuck sample (or n)
        let long_enough = time_s[end - 1] - time_s[start] >= opts.min_stick_s;
        // Break-away: the rotor reaches slip soon after the episode.
        let horizon = (end + 4 * h).min(n);
        let breaks_away = end < n && (end..horizon).any(|j| omega[j].abs() > opts.slip_threshold_rad_s);
        if long_enough && breaks_away {
            // The centred difference flags motion up to h samples early and
            // late; the true break-away lies in [end − h, end + h].
            out.push(start..(end + h).min(n));
        }
    }
    out
}

/// μs from break-away peaks: their median, with the standard error
/// 1.2533·σ/√n, σ = 1.4826·MAD (normal efficiency of the median); None
/// without peaks, no standard error from one.
pub fn static_level(peaks: &[f64]) -> Option<(f64, Option<f64>)> {
    if peaks.is_empty() {
        return None;
    }
    let med = median(peaks);
    let mad = median(&peaks.iter().map(|p| (p - med).abs()).collect::<Vec<_>>());
    Some((med, (peaks.len() >= 2).then(|| 1.2533 * 1.4826 * mad / (peaks.len() as f64).sqrt())))
}

/// μs and μk from every operating point; force calibration force_n = (mv − offset)/factor.
pub fn estimate_friction(
    c: &Campaign,
    force_offset_mv: f64,
    force_factor_mv_per_n: f64,
    opts: &FrictionOptions,
) -> Result<FrictionEstimate, EstimateError> {
    // The difference window's resolution at the operating points' clock
    // (their time columns, `Campaign::clock_rate_hz`), as `analyse_trace`
    // differences over the time that elapsed.
    let rate_hz = c.clock_rate_hz("operating_point");
    let dt = rate_hz.recip();
    let h = nominal_window_samples(opts.speed_half_window_s, rate_hz);
    let resolution = speed_resolution_rad_s(c.rig.encoder_ticks_per_rev, 2 * h, dt);
    if opts.slip_threshold_rad_s < 2.0 * resolution {
        return Err(EstimateError::InvalidOption {
            name: "slip_threshold_rad_s".into(),
            value: opts.slip_threshold_rad_s,
            rule: "must be at least twice the speed resolution of the difference window",
        });
    }
    let mut slip_means = Vec::new();
    let mut n_slip = 0;
    let mut peaks = Vec::new();
    for run in c.runs_of("operating_point") {
        let RunKind::OperatingPoint { normal_force_n, .. } = run.kind else { continue };
        if normal_force_n < opts.min_normal_force_n {
            continue;
        }
        let d = &run.data;
        let missing = |column| EstimateError::MissingColumn { run: run.id.clone(), column, kind: "operating_point" };
        let ticks = d.rotor_ticks.as_ref().ok_or_else(|| missing("rotor_ticks"))?;
        let mv = d.brake_force_mv.as_ref().ok_or_else(|| missing("brake_force_mv"))?;
        let phi1 = ticks_to_rad(ticks, c.rig.encoder_ticks_per_rev);
        let force = force_n(mv, ForceCal { factor_mv_per_n: force_factor_mv_per_n, offset_mv: force_offset_mv });
        let rf = analyse_trace(&d.time_s, &phi1, &force, normal_force_n, opts);
        if let Some((m, k)) = rf.mu_slip {
            slip_means.push((m, k));
            n_slip += k;
        }
        peaks.extend(rf.breakaway_peaks);
    }
    if slip_means.is_empty() {
        return Err(EstimateError::TooFewSamples {
            context: format!("campaign {}: kinetic friction", c.name),
            got: 0,
            need: 1,
            rule: "no operating point has rotor-1 slip above slip_threshold_rad_s",
        });
    }
    // μk: sample-weighted mean of run means; the standard error from the
    // between-run scatter (samples within a run are strongly autocorrelated).
    let mu_k = slip_means.iter().map(|(m, k)| m * *k as f64).sum::<f64>() / n_slip as f64;
    let run_values: Vec<f64> = slip_means.iter().map(|(m, _)| *m).collect();
    let mu_k_se = (run_values.len() >= 2).then(|| mean_sd(&run_values).1 / (run_values.len() as f64).sqrt());
    // μs: median of peaks; se = 1.2533·σ/√n with σ = 1.4826·MAD (normal efficiency of the median).
    // Without any break-away there is no evidence that μs exceeds μk: the
    // Coulomb law then degenerates to μs = μk (stated in the report).
    let (mu_s, mu_s_se) = static_level(&peaks).unwrap_or((mu_k, None));
    Ok(FrictionEstimate {
        mu_static: mu_s,
        mu_static_stderr: mu_s_se,
        mu_kinetic: mu_k,
        mu_kinetic_stderr: mu_k_se,
        n_stick_episodes: peaks.len(),
        n_slip_samples: n_slip,
        n_slip_runs: run_values.len(),
    })
}
