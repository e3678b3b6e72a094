//! Free-run checks of the operating points: a model (baseline or extended)
//! simulated from rest under the run's protocol and compared with the record
//! on phase-insensitive steady-state features of every recorded channel.
//!
//! # Features and their noise floors (issue 25, item 3)
//!
//! Over the steady window (ramp + settle to + `free_run_steady_s`), through
//! the same operators on both sides (Ω1, Ω2 by the diagnosis' centred
//! differences, the force by the calibrated sensor line, smoothed over the
//! rotor-speed window for the break-away peak):
//!
//! | check | feature | floor of run r (from the record) |
//! |---|---|---|
//! | `regime` | stick-slip or not (the classifier of [`steady_features`]) at the end of the run and over the window ([`attractor_stick_slip`]) | one run |
//! | `rotor_max`, `rotor_min` | extreme of Ω1, rad/s | resolution tick/(2h·dt)/√6 ⊕ spread of the extreme over cycles |
//! | `motor_max`, `motor_min` | extreme of Ω2, rad/s | the same with Ω2's window |
//! | `fundamental` | stick-slip frequency | Rayleigh resolution 1/(T·f) |
//! | `voltage_mean` | mean drive voltage, V | σ_V/√n ⊕ spread of cycle means/√cycles |
//! | `voltage_swing` | SD of the voltage, white noise removed: √(var − σ_V²), V | σ_V/√(2n) ⊕ spread of cycle SDs/√cycles |
//! | `slip_friction` | mean friction force over slip samples (μ·N), N | σ_F/√n_slip ⊕ spread of cycle means/√cycles ⊕ N0·se(μk) of the model's fitted level |
//! | `breakaway_friction` | mean over break-aways (at least [`MIN_BREAKAWAYS`]) of the raw peak friction force of the stick episode before, N, by the estimation's rules ([`breakaway_peaks`]) | σ_F ⊕ spread of the peaks/√events |
//! | `stick_fraction` | fraction of the window with \|Ω1\| below the slip speed | 2h·dt per cycle ⊕ spread of cycle fractions/√cycles |
//!
//! ⊕ is the root sum of squares; σ_V, σ_F the white noise of the recorded
//! channel (first differences, [`crate::prepare::diff_noise`]); a *cycle* is
//! one measured stick-slip period 1/f0 (1 s without stick-slip). The spread
//! over cycles is the floor of an effect that makes stick-slip irregular
//! (angle-periodic friction, a modulation): the window's extreme is one draw
//! of the cycles' extremes, and a free run started from rest visits other
//! cycles than the record (issue 25's regression: angle-periodic + viscous
//! friction, op-30's rotor maximum 4.52 measured vs 6.70 simulated is one
//! cycle of a record whose cycle maxima spread over several rad/s).
//!
//! A check's ratio is the RMS over runs of the run's error in units of its
//! floor, z_r = (measured − simulated)/floor_r (runs of very different force
//! levels count alike); the table's statistic is the RMS error in the
//! feature's unit and its floor the statistic over that ratio. The runs a
//! check uses: those that define the feature on both sides; the break-away
//! and stick-fraction checks only runs that stick and slip on both sides (a
//! regime change is the regime check's).
//!
//! # Calibration (crates/virtual-rig/tests/free_run_calibration.rs)
//!
//! `free_run_nulls`, 24 stick-slipping effect-free campaigns (seeds
//! 9100–9123, 3–9 of 12 runs stick-slip), final model's largest ratios:
//! rotor_max 1.47, rotor_min 0.19 (with the cycle-spread floors; 1.81 and
//! 1.37 before), fundamental 0.01, regime 0 runs, motor_max 2.30, motor_min
//! 2.01, voltage_mean 4.66, voltage_swing 2.27, slip_friction 1.79,
//! breakaway_friction 1.35, stick_fraction 0.18. Thresholds ≈ 2× the null
//! maximum, at least 4 ([`FreeRunThresholds`], pipeline.toml): 0/24 nulls
//! flagged (95 % Clopper–Pearson 0–14.2 %; in-sample, the same campaigns set
//! the thresholds; voltage mean and swing ≈ 2× would be 9.5 and 5).
//! `free_run_right_models` (each vocabulary effect on the same
//! stick-slipping rigs, diagnosed right): 0/20 flagged (95 % Clopper–Pearson
//! 0–16.8 %), break-away ratio at most 1.41, regime at most 2 runs; the
//! voltage mean and swing are reported, not in the adequacy test
//! (thresholds unset: right drive-limit models give 81–116×); details in
//! [`ChannelOptions`]' docs.
//!
//! # Why the features are not read on the attractor (measured, 2026-11)
//!
//! Reading every feature over the run's last `free_run_steady_s` (where the
//! regime is read), the break-aways over the whole run (the first from rest
//! included) and a run whose regime differs in either reading in no other
//! check was tried: the 24 stick-slipping nulls stay 0/24 flagged with every
//! maximum under half its threshold (rotor_max 1.68, motor_max 2.08,
//! motor_min 2.20, slip 1.71, break-away 1.33, stick fraction 0.18), and
//! the shipped campaign keeps its answer, but (1) the stick fraction on the
//! attractor flags 2/20 right models (normal-force modulation seed 9300,
//! op-04: record 0.267, model 0.054, 7.2× its floor: the model's sticking
//! decays toward the end of the run, the record's does not, a length the
//! modulation's phase sets; angle-periodic seed 9312, op-02: 0.803 against
//! 0.730, 11× a floor of 0.007 left by settled cycles); read after ramp +
//! settle, 0/20; (2) with that, the right drive-limit model of
//! `channel_calibration.rs` (`free_run_sees_a_drive_limit_and_not_its_fix`,
//! seed 16) fails motor_max at 5.20 (threshold 5; floor the encoder's 0.043
//! rad/s in steady slip) and the rotor-drag campaign of
//! `free_run_calibration.rs` loses its free-run significance (gain 76 % ±
//! 64 %, t = −0.003, where it needs 2). So the window stays; moving it
//! needs floors that carry the fitted model's uncertainty (as
//! `slip_friction` carries N0·se(μk)) first.
//!
//! # One break-away reading
//!
//! The break-away level used to be the smoothed force's peak over every
//! stretch with |Ω1| below the slip speed. On a record most such stretches
//! are encoder chatter: a rotor creeping at one or two ticks per difference
//! window crosses 0.5 rad/s back and forth (shipped op-03, 5–21 s: 50
//! stretches of which 7 end in a break-away, at 13.5–16.6 N; the mean over
//! all read 10.7 N, below the slip level), while a simulation crosses once.
//! Nulls then sat at 6–14× the floor. The estimation's μs is the median of
//! the raw peaks over its stick episodes (`[shared.stick_episodes]`,
//! `rig_estimate::friction::stick_episodes`), so the feature is now that
//! reading on both sides: the model's level and the record's break-aways are
//! measured by one rule (max ratio of the nulls 1.35).

use super::{ChannelCheck, ChannelOptions, rms};
use crate::DiagnoseOptions;
use crate::extension::dwell::{DwellRow, dwell_row};
use crate::prepare::{SensorLaw, centred_speed, diff_noise};
use crate::result::{ChannelFeatures, Features};
use crate::select::steady_features;
use rig_model::SimOptions;
use rig_types::sensor::centred_moving_average;
use rig_types::sensor::{half_window_samples, nominal_window_samples, tick_rad, ticks_to_rad};
use rig_types::{Campaign, RigParams, RunInput, RunKind};
use serde::{Deserialize, Serialize};

/// What the free-run comparison needs from the diagnosis options.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeRunSettings {
    pub settle_s: f64,
    pub steady_s: f64,
    pub slip_speed_rad_s: f64,
    pub rotor_speed_half_window_s: f64,
    pub motor_speed_half_window_s: f64,
    /// The regime classifier's thresholds (`[shared.classify]`).
    pub classify: rig_sweep::ClassifyOptions,
    /// `[shared.integrator]`.
    pub integrator: SimOptions,
    /// How the force sensor's mV are read as newtons (the diagnosis' slip
    /// channel's law); `None`: no friction-level features.
    pub force: Option<SensorLaw>,
    /// Standard error of the model's kinetic friction coefficient (the
    /// estimation's μk, fitted on these records: between-run scatter,
    /// rig_estimate::estimate_friction); N0 times it joins the
    /// `slip_friction` floor, since the simulated slip force is only as
    /// certain as the level it was given (0: not known).
    pub mu_kinetic_stderr: f64,
    /// `[shared.stick_episodes]`: what a stick episode and its break-away are
    /// (the estimation's μs rules, `rig_estimate::friction::stick_episodes`),
    /// for the `breakaway_friction` feature of record and simulation alike.
    pub stick_episodes: rig_estimate::FrictionOptions,
}

/// Thresholds (ratio to the noise floor) of the free-run checks of every
/// channel beyond the rotor speed: `[stage.params.channels.free_run]` of
/// pipeline.toml, calibrated on stick-slipping nulls
/// (crates/virtual-rig/tests/free_run_calibration.rs; the numbers are in
/// pipeline.toml's comment and [`ChannelOptions`]' docs).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FreeRunThresholds {
    pub motor_max_ratio: f64,
    pub motor_min_ratio: f64,
    /// `None`: the check is reported, not part of the adequacy test (the
    /// voltage mean and swing: their floors lack the fitted drive's
    /// uncertainty, [`ChannelOptions`]' docs).
    #[serde(default)]
    pub voltage_mean_ratio: Option<f64>,
    #[serde(default)]
    pub voltage_swing_ratio: Option<f64>,
    pub slip_friction_ratio: f64,
    pub breakaway_friction_ratio: f64,
    pub stick_fraction_ratio: f64,
}

impl FreeRunSettings {
    pub fn of(opts: &DiagnoseOptions, o: &ChannelOptions) -> Self {
        FreeRunSettings {
            settle_s: opts.settle_s,
            steady_s: o.free_run_steady_s,
            slip_speed_rad_s: opts.slip_speed_rad_s,
            rotor_speed_half_window_s: opts.rotor_speed_half_window_s,
            motor_speed_half_window_s: opts.motor_speed_half_window_s,
            classify: opts.classify.clone(),
            integrator: opts.integrator.clone(),
            force: None,
            mu_kinetic_stderr: 0.0,
            stick_episodes: opts.stick_episodes.clone(),
        }
    }

    /// The settings with the force sensor read through `law` (enables the
    /// friction-level features).
    pub fn with_force(mut self, law: SensorLaw) -> Self {
        self.force = Some(law);
        self
    }

    /// The settings with the model's kinetic level known to ± `se`.
    pub fn with_mu_kinetic_stderr(mut self, se: f64) -> Self {
        self.mu_kinetic_stderr = se;
        self
    }
}

/// Measured and simulated features of one run over the same window, with
/// the window length.
#[derive(Debug, Clone)]
pub struct Pair {
    pub id: String,
    pub measured: Features,
    pub simulated: Option<Features>,
    pub window_s: f64,
    /// Rotor speed over the steady window, for the small-multiples figure.
    pub trace: Trace,
    /// One encoder tick over the motor-speed differentiator window,
    /// tick/(2h·dt), rad/s: the smallest motor-speed step (dip) it can show.
    pub motor_tick_rad_s: f64,
    /// Every channel's features, measured and simulated (module docs).
    pub channels_measured: ChannelFeatures,
    pub channels_simulated: Option<ChannelFeatures>,
    /// Each feature's noise floor in this run, from the record (module docs).
    pub floors: ChannelFeatures,
    /// Stick-slip over the features' window (after ramp + settle, `steady_s`
    /// long), measured and simulated; `measured`/`simulated`'s `stick_slip`
    /// is the attractor's, read at the end of the run
    /// ([`attractor_stick_slip`]). The regime check counts a run whose
    /// regimes differ in both readings.
    pub window_stick_slip: (bool, Option<bool>),
    /// The first break-away from rest against the steady sticks over the
    /// whole run, record and simulation read by one rule
    /// ([`crate::extension::dwell::dwell_row`]; `None` where a side has no
    /// first break-away and two steady sticks): the dwell check against the
    /// model's free run.
    pub dwell: (Option<DwellRow>, Option<DwellRow>),
}

/// Ω1 over a run's steady window at about [`TRACE_RATE_HZ`] (every k-th
/// sample of the centred difference the features use), measured and simulated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trace {
    pub time_s: Vec<f64>,
    pub measured_rad_s: Vec<f64>,
    pub simulated_rad_s: Option<Vec<f64>>,
}

/// Rate of a [`Trace`]: ten points per second of the fastest stick-slip
/// cycle the rig shows (periods 2-6 s) and then some.
pub const TRACE_RATE_HZ: f64 = 20.0;

/// One [`Pair`] per operating point of `c` with model `p` (one simulation per
/// run over ramp + settle + `steady_s` only, in parallel, campaign order kept;
/// `simulated` is `None` where the integrator failed — data, not an error).
pub fn free_run_pairs(c: &Campaign, p: &RigParams, s: &FreeRunSettings) -> Vec<Pair> {
    free_run_pairs_by(c, s, |_| Some(p.clone()))
}

/// [`free_run_pairs`] with each run's own model: `params_of(run id)`, runs
/// for which it gives `None` are skipped (a cross-validation fold's held-out
/// runs, each with the model fitted without them).
pub fn free_run_pairs_by(
    c: &Campaign,
    s: &FreeRunSettings,
    params_of: impl Fn(&str) -> Option<RigParams> + Sync,
) -> Vec<Pair> {
    use rayon::prelude::*;
    let runs: Vec<&rig_types::Run> = c.runs_of("operating_point").collect();
    runs.par_iter()
        .map(|r| params_of(&r.id).and_then(|p| pair(c, r, &p, s)))
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// The speed resolution of the centred difference, tick/(2h·dt)/√6, rad/s:
/// the noise floor of a rotor-speed extremum.
pub fn speed_floor_rad_s(c: &Campaign, s: &FreeRunSettings) -> f64 {
    tick_rad(c.rig.encoder_ticks_per_rev)
        / (2.0 * nominal_window_samples(s.rotor_speed_half_window_s, c.rig.sample_rate_hz) as f64
            / c.rig.sample_rate_hz)
        / 6f64.sqrt()
}

/// Free-run misfit of one run's motion (crate docs, "The free-run misfit";
/// the structure's selection criterion): M_fr = sqrt(1 + mean(e²)) over
/// e_max, e_min, the measured − simulated extremes of Ω1 over the speed
/// resolution `floor_rad_s` (the criterion the structure was calibrated
/// with: with the per-run floors of the checks, ⊕ the spread over cycles,
/// the rotor-drag campaign of `free_run_calibration.rs` gives t = 1.98 for
/// its placement instead of ≥ 2), and e_f, the relative error of the stick-slip fundamental
/// over the window's relative Rayleigh resolution 1/(T·f) when both stick
/// and slip. The 1 is the floor itself (a model at the noise scores ≈ 1.4,
/// never 0, so ln ratios stay finite). `None` when the simulation failed.
pub fn free_run_misfit(q: &Pair, floor_rad_s: f64) -> Option<f64> {
    misfit_over(q, floor_rad_s, ChannelFeatures::ROTOR_MIN + 1, false)
}

/// [`free_run_misfit`] over every channel's feature (module docs: Ω1 and Ω2
/// extremes, voltage mean and swing, slip and break-away friction, stick
/// fraction — the last two when both stick and slip) and the fundamental:
/// the extension's selection criterion ([`crate::extension`]).
pub fn free_run_misfit_channels(q: &Pair, floor_rad_s: f64) -> Option<f64> {
    misfit_over(q, floor_rad_s, ChannelFeatures::N, true)
}

/// M_fr over the first `n_features` channel features and the fundamental;
/// the Ω1 extremes over the run's own floors (≥ `floor_rad_s`) when
/// `run_floors`, else over `floor_rad_s`.
fn misfit_over(q: &Pair, floor_rad_s: f64, n_features: usize, run_floors: bool) -> Option<f64> {
    let f = q.simulated?;
    let sim = q.channels_simulated?;
    let m = &q.measured;
    let both = m.stick_slip() && f.stick_slip();
    let mut e2 = Vec::new();
    for i in 0..n_features {
        if !both && (i == ChannelFeatures::BREAKAWAY || i == ChannelFeatures::STICK_FRACTION) {
            continue;
        }
        let (a, b) = (q.channels_measured.values[i], sim.values[i]);
        let floor = match (i <= ChannelFeatures::ROTOR_MIN, run_floors) {
            (true, true) => q.floors.values[i].max(floor_rad_s),
            (true, false) => floor_rad_s,
            (false, _) => q.floors.values[i],
        };
        if a.is_finite() && b.is_finite() && floor > 0.0 {
            e2.push(((a - b) / floor).powi(2));
        }
    }
    if both && m.fundamental_hz > 0.0 {
        e2.push(((m.fundamental_hz - f.fundamental_hz) * q.window_s).powi(2));
    }
    let mean = if e2.is_empty() { 0.0 } else { e2.iter().sum::<f64>() / e2.len() as f64 };
    Some((1.0 + mean).sqrt())
}

/// The steady-window signals of one side (measured or simulated) that the
/// channel features are computed from.
struct Window<'a> {
    w1: &'a [f64],
    w2: &'a [f64],
    voltage_v: Option<&'a [f64]>,
    /// Friction force, N, smoothed over the rotor-speed window.
    force_n: Option<&'a [f64]>,
    /// The window's break-away peaks, N ([`breakaway_peaks`]; empty for a
    /// cycle's sub-window, whose floor does not use them).
    peaks: &'a [f64],
}

/// Every stuck stretch (|Ω1| below the slip speed) that starts and ends
/// inside the window, as [first, end) sample ranges: the extension's
/// break-away rows. Not the free-run break-away feature any more: on a
/// record most such stretches are encoder chatter of a creeping rotor
/// ([`breakaway_peaks`] reads the estimation's stick episodes instead); the
/// extension's rows should move to those too (open).
pub fn stuck_stretches(w1: &[f64], slip_rad_s: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for k in 1..w1.len() {
        let (was, is) = (w1[k - 1].abs() < slip_rad_s, w1[k].abs() < slip_rad_s);
        if is && !was {
            start = Some(k);
        } else if was
            && !is
            && let Some(j) = start.take()
        {
            out.push((j, k));
        }
    }
    out
}

/// Break-aways a window needs to define its break-away level: the floor
/// carries their spread, which one or two do not measure (an angle-periodic
/// normal force sets each break-away by the angle the rotor stuck at: a
/// right model of seed 9313 broke away at 9.4 N in the record and 11.5 N in
/// the simulation, one episode each, 219× a floor of force noise alone).
pub const MIN_BREAKAWAYS: usize = 3;

/// The break-away peaks of one side over samples `from..` of a run: the
/// peak of the raw friction force `force_n`, N, over each stick episode that
/// starts in the window and ends in a break-away, by the estimation's rules
/// (`rig_estimate::friction::stick_episodes`, `[shared.stick_episodes]`: the
/// encoder did not move over the difference window, for at least
/// `min_stick_s`, and the rotor reaches slip right after). The estimation
/// reads μs as the median of the same peaks over N0, so the model's static
/// level and this feature are one reading of the record. `rotor_angle_rad`
/// is the encoder's (a simulated angle quantised first); no episode below
/// `min_normal_force_n`, where the estimation reads none either.
fn breakaway_peaks(
    time_s: &[f64],
    rotor_angle_rad: &[f64],
    force_n: &[f64],
    from: usize,
    normal_force_n: f64,
    o: &rig_estimate::FrictionOptions,
) -> Vec<f64> {
    if normal_force_n < o.min_normal_force_n {
        return Vec::new();
    }
    rig_estimate::friction::stick_episodes(time_s, rotor_angle_rad, o)
        .into_iter()
        .filter(|r| r.start >= from)
        .map(|r| force_n[r].iter().copied().fold(f64::NEG_INFINITY, f64::max))
        .collect()
}

fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { f64::NAN } else { x.iter().sum::<f64>() / x.len() as f64 }
}

/// Sample standard deviation (NaN below two values).
fn sd(x: &[f64]) -> f64 {
    if x.len() < 2 {
        return f64::NAN;
    }
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// The channel features of one window (module docs); `sigma_v` is removed
/// from the voltage's SD (0 for a simulation).
fn channel_values(w: &Window, slip_rad_s: f64, sigma_v: f64) -> [f64; ChannelFeatures::N] {
    let ext = |x: &[f64], max: bool| {
        x.iter()
            .copied()
            .fold(if max { f64::NEG_INFINITY } else { f64::INFINITY }, if max { f64::max } else { f64::min })
    };
    let (vm, vs) = match w.voltage_v {
        Some(v) => {
            let m = mean(v);
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64;
            (m, (var - sigma_v * sigma_v).max(0.0).sqrt())
        }
        None => (f64::NAN, f64::NAN),
    };
    let (slip, breakaway) = match w.force_n {
        Some(f) => {
            let s: Vec<f64> = w.w1.iter().zip(f).filter(|(w, _)| w.abs() >= slip_rad_s).map(|(_, f)| *f).collect();
            let level = if w.peaks.len() >= MIN_BREAKAWAYS { mean(w.peaks) } else { f64::NAN };
            (mean(&s), level)
        }
        None => (f64::NAN, f64::NAN),
    };
    let stuck = w.w1.iter().filter(|x| x.abs() < slip_rad_s).count() as f64 / w.w1.len().max(1) as f64;
    [ext(w.w1, true), ext(w.w1, false), ext(w.w2, true), ext(w.w2, false), vm, vs, slip, breakaway, stuck]
}

/// The resolution and white noise a run's floors start from: the speed
/// resolutions of Ω1 and Ω2, rad/s, σ_V, V, and σ_F of the raw force, N.
struct Noise {
    res_rad_s: (f64, f64),
    sigma_v: f64,
    sigma_f: f64,
}

/// Each feature's floor in one run, from the record (module docs): the
/// sensor's resolution or noise ⊕ the feature's spread over cycles of
/// `cycle` samples.
fn channel_floors(w: &Window, slip_rad_s: f64, noise: &Noise, h1: usize, cycle: usize) -> ChannelFeatures {
    let n = w.w1.len();
    let Noise { res_rad_s, sigma_v, sigma_f } = *noise;
    let cycles: Vec<[f64; ChannelFeatures::N]> = (0..n / cycle.max(1))
        .map(|i| {
            let r = i * cycle..(i + 1) * cycle;
            let sub = Window {
                w1: &w.w1[r.clone()],
                w2: &w.w2[r.clone()],
                voltage_v: w.voltage_v.map(|v| &v[r.clone()]),
                force_n: w.force_n.map(|f| &f[r.clone()]),
                peaks: &[],
            };
            channel_values(&sub, slip_rad_s, sigma_v.max(0.0))
        })
        .collect();
    // Spread over cycles (0 below two cycles that define it) and its count.
    let spread = |i: usize| {
        let v: Vec<f64> = cycles.iter().map(|c| c[i]).filter(|x| x.is_finite()).collect();
        let s = sd(&v);
        (if s.is_finite() { s } else { 0.0 }, v.len().max(1) as f64)
    };
    let q = |a: f64, b: f64| a.hypot(b);
    let nf = n.max(1) as f64;
    let n_slip = w.w1.iter().filter(|x| x.abs() >= slip_rad_s).count().max(1) as f64;
    let peaks = w.peaks;
    let sd_peaks = if peaks.len() >= 2 { sd(peaks) } else { 0.0 };
    let mut v = [0.0; ChannelFeatures::N];
    for (i, x) in v.iter_mut().enumerate() {
        let (s, nc) = spread(i);
        *x = match i {
            0 | 1 => q(res_rad_s.0, s),
            2 | 3 => q(res_rad_s.1, s),
            4 => q(sigma_v / nf.sqrt(), s / nc.sqrt()),
            5 => q(sigma_v / (2.0 * nf).sqrt(), s / nc.sqrt()),
            6 => q(sigma_f / n_slip.sqrt(), s / nc.sqrt()),
            7 => q(sigma_f, sd_peaks / (peaks.len().max(1) as f64).sqrt()),
            _ => q(2.0 * h1 as f64 / cycle.max(1) as f64, s / nc.sqrt()),
        };
    }
    ChannelFeatures { values: v }
}

/// What [`pair`] reads from one run's record alone, the same for every model
/// simulated against it: built once per run ([`MeasuredRuns`]) and shared by
/// the baseline's, the extended and the final model's free runs.
#[derive(Debug, Clone)]
pub struct MeasuredRun {
    id: String,
    normal_force_n: f64,
    input: RunInput,
    from: usize,
    to: usize,
    h1: usize,
    h2: usize,
    dt: f64,
    stride: usize,
    regime_from: usize,
    measured: Features,
    window_measured: Features,
    /// Whether the friction-level features are read (force law, force channel, N0 > 0).
    has_force: bool,
    has_voltage: bool,
    channels_measured: ChannelFeatures,
    floors: ChannelFeatures,
    measured_trace: Vec<f64>,
    /// The record's dwell row ([`dwell_of`]; `None` without a force channel).
    dwell: Option<DwellRow>,
}

/// Every operating point's [`MeasuredRun`] of one campaign under one set of
/// [`FreeRunSettings`], campaign order kept (`None`: a run [`pair`] skips).
#[derive(Debug, Clone)]
pub struct MeasuredRuns {
    runs: Vec<Option<MeasuredRun>>,
    settings: FreeRunSettings,
}

impl MeasuredRuns {
    /// The record's side of every operating point of `c` (in parallel).
    pub fn of(c: &Campaign, s: &FreeRunSettings) -> Self {
        use rayon::prelude::*;
        let runs: Vec<&rig_types::Run> = c.runs_of("operating_point").collect();
        MeasuredRuns { runs: runs.par_iter().map(|r| measure(c, r, s)).collect(), settings: s.clone() }
    }
}

/// [`free_run_pairs_by`] against records already measured with the same
/// settings (`m` from [`MeasuredRuns::of`] with `s`): only the simulations
/// run; the pairs are the same to the bit.
pub fn free_run_pairs_measured(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    params_of: impl Fn(&str) -> Option<RigParams> + Sync,
) -> Vec<Pair> {
    use rayon::prelude::*;
    assert!(m.settings == *s, "free_run_pairs_measured: records measured under other settings");
    let runs: Vec<&rig_types::Run> = c.runs_of("operating_point").collect();
    assert_eq!(runs.len(), m.runs.len(), "free_run_pairs_measured: records of another campaign");
    runs.par_iter()
        .zip(&m.runs)
        .map(|(r, mr)| {
            let mr = mr.as_ref()?;
            debug_assert_eq!(mr.id, r.id);
            params_of(&r.id).map(|p| simulate_pair(c, r, mr, &p, s, false))
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// [`free_run_misfit`] of the run `id` simulated with `p`, against its
/// record measured under `s` (`m` from [`MeasuredRuns::of`] with `s`): the
/// same value to the bit as [`free_run_pairs_measured`]'s pair gives, without
/// the features that misfit does not read (the force's, the break-away
/// peaks, the dwell row). `None` where that pair would be missing or have no
/// misfit.
pub fn free_run_misfit_measured(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    id: &str,
    p: &RigParams,
    floor_rad_s: f64,
) -> Option<f64> {
    assert!(m.settings == *s, "free_run_misfit_measured: records measured under other settings");
    let (r, mr) = c.runs_of("operating_point").zip(&m.runs).find(|(r, _)| r.id == id)?;
    let mr = mr.as_ref()?;
    free_run_misfit(&simulate_pair(c, r, mr, p, s, true), floor_rad_s)
}

/// Features of one run: measured from the encoders, the voltage and force
/// channels, and simulated with `p`, all through the same operators (the
/// diagnosis' centred differences, so the smoothing of the extrema is the
/// same on both sides; the force smoothed over the rotor-speed window).
fn pair(c: &Campaign, run: &rig_types::Run, p: &RigParams, s: &FreeRunSettings) -> Option<Pair> {
    let m = measure(c, run, s)?;
    Some(simulate_pair(c, run, &m, p, s, false))
}

/// The record's side of [`pair`]: features, floors and trace of one run.
fn measure(c: &Campaign, run: &rig_types::Run, s: &FreeRunSettings) -> Option<MeasuredRun> {
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else { return None };
    let t = &run.data.time_s;
    let from = t.partition_point(|&x| x < ramp_s + s.settle_s);
    let to = t.partition_point(|&x| x < ramp_s + s.settle_s + s.steady_s);
    if to < from + 16 {
        return None;
    }
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    let phi1_all = ticks_to_rad(run.data.rotor_ticks.as_ref()?, c.rig.encoder_ticks_per_rev);
    let phi1 = &phi1_all[..to];
    let phi2 = ticks_to_rad(&run.data.motor_ticks.as_ref()?[..to], c.rig.encoder_ticks_per_rev);
    let tt = &t[..to];
    let w_set = rig_types::units::rpm_to_rad_s(motor_rpm_setpoint);
    let dt = (tt[to - 1] - tt[0]) / (to - 1) as f64;
    let stride = ((1.0 / (TRACE_RATE_HZ * dt)).round() as usize).max(1);
    let (h1, h2) =
        (half_window_samples(tt, s.rotor_speed_half_window_s), half_window_samples(tt, s.motor_speed_half_window_s));
    let (m1, m2) = (centred_speed(tt, phi1, h1), centred_speed(tt, &phi2, h2));
    // The regime is the attractor's, read over the record's last `steady_s`
    // ([`attractor_stick_slip`]); every other feature over the window.
    let regime_from = t.partition_point(|&x| x < t[t.len() - 1] - s.steady_s).max(from);
    let window_measured =
        steady_features(&tt[from..], &m1[from..], &m2[from..], w_set, s.slip_speed_rad_s, &s.classify);
    let measured =
        Features { stick_slip: attractor_stick_slip(t, &phi1_all, regime_from, h1, &s.classify), ..window_measured };
    let m_voltage = run.data.motor_voltage_v.as_ref().map(|v| v[from..to].to_vec());
    let m_force = match (s.force, run.data.brake_force_mv.as_ref()) {
        (Some(law), Some(mv)) if normal_force_n > 0.0 => Some(law.force_n(&mv[..to])),
        _ => None,
    };
    let m_force_smooth = m_force.as_ref().map(|f| centred_moving_average(f, h1)[from..].to_vec());
    let m_peaks = m_force
        .as_ref()
        .map(|f| breakaway_peaks(tt, phi1, f, from, normal_force_n, &s.stick_episodes))
        .unwrap_or_default();
    let m_win = Window {
        w1: &m1[from..],
        w2: &m2[from..],
        voltage_v: m_voltage.as_deref(),
        force_n: m_force_smooth.as_deref(),
        peaks: &m_peaks,
    };
    let sigma_v = m_voltage.as_deref().map_or(f64::NAN, diff_noise);
    let channels_measured = ChannelFeatures { values: channel_values(&m_win, s.slip_speed_rad_s, sigma_v.max(0.0)) };
    let cycle_s = if window_measured.stick_slip() && window_measured.fundamental_hz > 0.0 {
        1.0 / window_measured.fundamental_hz
    } else {
        1.0
    };
    let res = |h: usize| rad / (2.0 * h as f64 * dt) / 6f64.sqrt();
    let noise = Noise {
        res_rad_s: (res(h1), res(h2)),
        sigma_v,
        sigma_f: m_force.as_ref().map_or(f64::NAN, |f| diff_noise(&f[from..])),
    };
    let mut floors = channel_floors(&m_win, s.slip_speed_rad_s, &noise, h1, (cycle_s / dt).round() as usize);
    // The dwell rows read the whole run, from rest (record and simulation alike).
    let dwell = match (s.force, run.data.brake_force_mv.as_ref()) {
        (Some(law), Some(mv)) if normal_force_n > 0.0 => {
            dwell_of(&run.id, t, &centred_speed(t, &phi1_all, h1), &law.force_n(mv), h1, s.slip_speed_rad_s)
        }
        _ => None,
    };
    let slip = &mut floors.values[6];
    *slip = slip.hypot(normal_force_n * s.mu_kinetic_stderr);
    Some(MeasuredRun {
        id: run.id.clone(),
        normal_force_n,
        input: RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s },
        from,
        to,
        h1,
        h2,
        dt,
        stride,
        regime_from,
        measured,
        window_measured,
        has_force: m_force.is_some(),
        has_voltage: m_voltage.is_some(),
        channels_measured,
        floors,
        measured_trace: m1[from..].iter().step_by(stride).copied().collect(),
        dwell,
    })
}

/// A run's dwell row ([`dwell_row`]) from its rotor speed and friction force
/// over the whole run, from rest: one rule for the record and a simulation.
fn dwell_of(id: &str, t: &[f64], w1: &[f64], force_n: &[f64], h1: usize, slip_speed_rad_s: f64) -> Option<DwellRow> {
    let slip: Vec<f64> = w1.iter().zip(force_n).filter(|(w, _)| w.abs() >= slip_speed_rad_s).map(|x| *x.1).collect();
    let smooth = centred_moving_average(force_n, h1);
    dwell_row(id, t, w1, &smooth, mean(&slip), slip_speed_rad_s)
}

/// The model's side of [`pair`]: run `p` on the record `m` was measured from.
/// `rotor_only`: the features [`free_run_misfit`] reads and no others (the
/// force's, its break-away peaks and the dwell row are left out: NaN, empty,
/// `None`), for [`free_run_misfit_measured`] alone.
fn simulate_pair(
    c: &Campaign,
    run: &rig_types::Run,
    m: &MeasuredRun,
    p: &RigParams,
    s: &FreeRunSettings,
    rotor_only: bool,
) -> Pair {
    let t = &run.data.time_s;
    let MeasuredRun { from, to, h1, h2, dt, stride, regime_from, normal_force_n, .. } = *m;
    let tt = &t[..to];
    let w_set = match m.input {
        RunInput::OperatingPoint { motor_rpm_setpoint, .. } => rig_types::units::rpm_to_rad_s(motor_rpm_setpoint),
        _ => unreachable!("a MeasuredRun is an operating point's"),
    };
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    // The whole record is simulated (the regime is read at its end); the
    // window's features from its first `to` samples.
    let sim = rig_model::simulate(p, &m.input, t, &s.integrator).ok().map(|tr| {
        let (w1, w2) =
            (centred_speed(tt, &tr.rotor_angle_rad[..to], h1), centred_speed(tt, &tr.motor_angle_rad[..to], h2));
        let has_force = m.has_force && !rotor_only;
        let force: Vec<f64> = if has_force {
            tr.friction_torque_nm[..to].iter().map(|x| x / p.brake_disc_radius_m).collect()
        } else {
            Vec::new()
        };
        let force_smooth = has_force.then(|| centred_moving_average(&force, h1)[from..].to_vec());
        // The simulated angle through the encoder, as the record's: the
        // window's first `to` samples for the peaks, the whole run for the
        // dwell row (only where the record has one).
        let peaks = if has_force {
            let ticks = rig_types::sensor::encoder_ticks(&tr.rotor_angle_rad[..to], c.rig.encoder_ticks_per_rev);
            let enc = ticks_to_rad(&ticks, c.rig.encoder_ticks_per_rev);
            breakaway_peaks(tt, &enc, &force, from, normal_force_n, &s.stick_episodes)
        } else {
            Vec::new()
        };
        let dwell = m.dwell.as_ref().filter(|_| !rotor_only).and_then(|_| {
            let ticks = rig_types::sensor::encoder_ticks(&tr.rotor_angle_rad, c.rig.encoder_ticks_per_rev);
            let enc = ticks_to_rad(&ticks, c.rig.encoder_ticks_per_rev);
            let all: Vec<f64> = tr.friction_torque_nm.iter().map(|x| x / p.brake_disc_radius_m).collect();
            dwell_of(&m.id, t, &centred_speed(t, &enc, h1), &all, h1, s.slip_speed_rad_s)
        });
        let win = Window {
            w1: &w1[from..],
            w2: &w2[from..],
            voltage_v: m.has_voltage.then(|| &tr.voltage_v[from..to]),
            force_n: force_smooth.as_deref(),
            peaks: &peaks,
        };
        let window = steady_features(&tt[from..], &w1[from..], &w2[from..], w_set, s.slip_speed_rad_s, &s.classify);
        let f = Features {
            stick_slip: attractor_stick_slip(t, &tr.rotor_angle_rad, regime_from, h1, &s.classify),
            ..window
        };
        let trace = w1[from..].iter().step_by(stride).copied().collect::<Vec<f64>>();
        (f, trace, ChannelFeatures { values: channel_values(&win, s.slip_speed_rad_s, 0.0) }, window.stick_slip, dwell)
    });
    let (simulated, simulated_rad_s, channels_simulated, sim_window_ss, sim_dwell) =
        sim.map_or((None, None, None, None, None), |(f, w, ch, ss, d)| (Some(f), Some(w), Some(ch), Some(ss), d));
    let trace = Trace {
        time_s: tt[from..].iter().step_by(stride).copied().collect(),
        measured_rad_s: m.measured_trace.clone(),
        simulated_rad_s,
    };
    let motor_tick_rad_s = rad / (2.0 * h2 as f64 * dt);
    Pair {
        id: m.id.clone(),
        measured: m.measured,
        simulated,
        window_s: tt[to - 1] - tt[from],
        trace,
        motor_tick_rad_s,
        channels_measured: m.channels_measured,
        channels_simulated,
        floors: m.floors,
        window_stick_slip: (m.window_measured.stick_slip, sim_window_ss),
        dwell: (m.dwell.clone(), sim_dwell),
    }
}

/// Stick-slip of the attractor a run settles to: the regime classifier
/// (`rig_sweep::classify`, `[shared.classify]`, the one definition of
/// stick-slip) on Ω1 (centred difference of half window `h`) over samples
/// `from..` of the whole run, its last `steady_s`.
///
/// Why not the features' window (issue 25's regime changes of op-19, op-27):
/// at the stick-slip boundary a run from rest sticks and slips for a while
/// and then decays to steady slip, and how long it keeps sticking is set by
/// the phase of the normal-force modulation at each break-away, not by the
/// model's level: the final model of the shipped campaign keeps op-26
/// sticking until 3.8 s, 12.6 s or 10.4 s for modulation phases moved by
/// −0.01, 0 and +0.03 rad, op-19 until 4.3 s or 17.4 s (record 19.5 s) for
/// 0 and +0.3 rad. A window that starts after the ramp (5–21 s) cuts such a
/// transient at an arbitrary point, and the classifier's decay rule (second
/// half's swing below 0.6 of the first's) then reads the same behaviour
/// both ways: the record's op-22, op-26, op-27 all stop sticking at
/// 8.6–10.5 s, and their decay ratios 0.63, 0.64, 0.56 made two of them
/// stick-slip and one not. What the rig settles to is determined; how long
/// it takes near the boundary is not, within the modulation's phase: over 8
/// phases spread over 2π the final model ends in steady slip at every one
/// for op-02, op-19, op-20, op-22, op-26, op-27, op-28 and sticks and slips
/// at every one for op-03, as the record does, while its last stick ranges
/// over 4.3–11.0 s for op-19 (record 19.5 s), 0–16.3 s for op-22 (10.0),
/// 3.8–12.6 s for op-26 (10.5) and 4.0–10.7 s for op-27 (8.6)
/// (`crates/pipeline/examples/breakaway_probe.rs`, `TRANSIENT=1`). So a
/// run changes regime in the check only when the end of the run and the
/// features' window both differ; a difference in one of them is listed.
fn attractor_stick_slip(
    t: &[f64],
    rotor_angle_rad: &[f64],
    from: usize,
    h: usize,
    classify: &rig_sweep::ClassifyOptions,
) -> bool {
    let n = t.len().min(rotor_angle_rad.len());
    if n < from + 16 {
        return false;
    }
    let w1 = centred_speed(&t[..n], &rotor_angle_rad[..n], h);
    let fs_hz = (n - from - 1) as f64 / (t[n - 1] - t[from]);
    rig_sweep::classify(&w1[from..], fs_hz, classify).regime.stick_slip()
}

/// Each operating point's measured rotor speed with the baseline's and the
/// extended model's free runs (pairs of [`free_run_pairs`], matched by run id).
pub fn speed_traces(baseline: &[Pair], extended: &[Pair]) -> Vec<crate::result::SpeedTraces> {
    baseline
        .iter()
        .map(|b| crate::result::SpeedTraces {
            id: b.id.clone(),
            time_s: b.trace.time_s.clone(),
            measured_rad_s: b.trace.measured_rad_s.clone(),
            baseline_rad_s: b.trace.simulated_rad_s.clone(),
            extended_rad_s: extended.iter().find(|e| e.id == b.id).and_then(|e| e.trace.simulated_rad_s.clone()),
        })
        .collect()
}

/// The free-run checks of model `p` (one simulation per operating point,
/// over ramp + settle + `steady_s` only, in parallel, campaign order kept).
///
/// The thesis compares measured and simulated motion on the same features
/// (Figs. 4.16–4.29: regime, rotor speed range, stick-slip frequency); issue
/// 25 asks for every recorded channel at its level. The features and floors
/// are in the module docs; the regime and fundamental come from
/// [`steady_features`], the one definition the per-run table uses:
/// - regime: runs where one side sticks-and-slips and the other does not
///   (floor: one run, the boundary of the severity map being uncertain);
/// - every channel feature: RMS over runs of (measured − simulated)/floor_r;
/// - fundamental: RMS over the runs that stick-slip on both sides of the
///   relative error of the stick-slip frequency; floor: the relative Rayleigh
///   resolution 1/(T·f) of the window, RMS over those runs.
///
/// Extrema, means and the fundamental over a window of many cycles do not
/// depend on the phases of a modulation beyond the spread over cycles that
/// the floors carry.
pub fn free_run_checks(c: &Campaign, p: &RigParams, s: &FreeRunSettings, o: &ChannelOptions) -> Vec<ChannelCheck> {
    free_run_checks_of(c, &free_run_pairs(c, p, s), s, o)
}

/// Check names of [`free_run_checks_of`], in its order.
pub fn free_run_check_names() -> Vec<String> {
    let mut v = vec!["operating_point.regime".to_string()];
    v.extend(ChannelFeatures::NAMES[..2].iter().map(|n| format!("operating_point.{n}")));
    v.push("operating_point.fundamental".into());
    v.extend(ChannelFeatures::NAMES[2..].iter().map(|n| format!("operating_point.{n}")));
    v
}

/// The free-run checks of pairs already simulated ([`free_run_pairs`]):
/// regime, rotor_max, rotor_min, fundamental, then the other channels'.
pub fn free_run_checks_of(c: &Campaign, pairs: &[Pair], s: &FreeRunSettings, o: &ChannelOptions) -> Vec<ChannelCheck> {
    let names = free_run_check_names();
    let ids: Vec<String> = pairs.iter().map(|q| q.id.clone()).collect();
    let failed: Vec<&str> = pairs.iter().filter(|q| q.simulated.is_none()).map(|q| q.id.as_str()).collect();
    let ok: Vec<(&Pair, Features)> = pairs.iter().filter_map(|q| q.simulated.map(|f| (q, f))).collect();
    if ok.is_empty() {
        return names
            .iter()
            .map(|ch| ChannelCheck::not_testable(ch, ids.clone(), "no operating point simulated".into()))
            .collect();
    }
    let fail_note = if failed.is_empty() { String::new() } else { format!("; not integrated: {}", failed.join(", ")) };
    let mut out = Vec::new();

    // A run changes regime when record and simulation differ both at the
    // end (the attractor) and over the features' window: a difference in one
    // reading only is a transient of another length near the boundary
    // ([`attractor_stick_slip`]), listed, not counted.
    let at_end = |q: &Pair, f: &Features| q.measured.stick_slip() != f.stick_slip();
    let in_window = |q: &Pair| Some(q.window_stick_slip.0) != q.window_stick_slip.1;
    let differ: Vec<&str> =
        ok.iter().filter(|(q, f)| at_end(q, f) && in_window(q)).map(|(q, _)| q.id.as_str()).collect();
    let one: Vec<&str> = ok.iter().filter(|(q, f)| at_end(q, f) != in_window(q)).map(|(q, _)| q.id.as_str()).collect();
    let one_note = if one.is_empty() {
        String::new()
    } else {
        format!(
            "; in one reading only (end of run or window, a transient's length at the boundary): {}",
            one.join(", ")
        )
    };
    out.push(ChannelCheck::new(
        &names[0],
        ids.clone(),
        differ.len() as f64,
        1.0,
        o.regime_ratio,
        format!(
            "{} of {} runs change regime (stick-slip ↔ pure slip) in the simulation{}{one_note}{fail_note}",
            differ.len(),
            ok.len(),
            if differ.is_empty() { String::new() } else { format!(": {}", differ.join(", ")) }
        ),
    ));

    let floor = speed_floor_rad_s(c, s);
    let t = &o.free_run;
    let thresholds = [
        o.rotor_max_ratio,
        o.rotor_min_ratio,
        t.motor_max_ratio,
        t.motor_min_ratio,
        t.voltage_mean_ratio.unwrap_or(f64::INFINITY),
        t.voltage_swing_ratio.unwrap_or(f64::INFINITY),
        t.slip_friction_ratio,
        t.breakaway_friction_ratio,
        t.stick_fraction_ratio,
    ];
    let mut channel_checks: Vec<ChannelCheck> = (0..ChannelFeatures::N)
        .map(|i| feature_check(&names, i, &ok, floor, thresholds[i], &ids, &fail_note))
        .collect();
    out.extend(channel_checks.drain(..2));

    // Both attractors stick and slip and both windows have a fundamental: a
    // window without one while the attractor sticks and slips is a
    // transient of another length, the regime check's "one reading only"
    // (full battery `ladder-angle_periodic_friction-0-0`, op-17: 0.42 Hz
    // measured, no fundamental in the simulated window, ratio 4.72 from
    // that run's 100 % error alone).
    let both: Vec<(&Pair, Features)> = ok
        .iter()
        .filter(|(q, f)| {
            q.measured.stick_slip() && f.stick_slip() && q.measured.fundamental_hz > 0.0 && f.fundamental_hz > 0.0
        })
        .map(|(q, f)| (*q, *f))
        .collect();
    if both.is_empty() {
        out.push(ChannelCheck::not_testable(
            &names[3],
            ids,
            "no run sticks and slips in both record and simulation".into(),
        ));
    } else {
        let rel: Vec<f64> = both
            .iter()
            .map(|(q, f)| (q.measured.fundamental_hz - f.fundamental_hz) / q.measured.fundamental_hz)
            .collect();
        let res: Vec<f64> = both.iter().map(|(q, _)| 1.0 / (q.window_s * q.measured.fundamental_hz)).collect();
        let rows: Vec<String> = both
            .iter()
            .map(|(q, f)| format!("{} {:.2}/{:.2} Hz", q.id, q.measured.fundamental_hz, f.fundamental_hz))
            .collect();
        out.push(ChannelCheck::new(
            &names[3],
            both.iter().map(|(q, _)| q.id.clone()).collect(),
            rms(&rel),
            rms(&res),
            o.fundamental_ratio,
            format!("stick-slip fundamental measured/simulated: {}", rows.join(", ")),
        ));
    }
    out.extend(channel_checks);
    out
}

/// The check of channel feature `i` over the runs that define it on both
/// sides (module docs): ratio = RMS of z_r = (measured − simulated)/floor_r;
/// statistic = RMS error in the feature's unit, floor = statistic / ratio.
fn feature_check(
    names: &[String],
    i: usize,
    ok: &[(&Pair, Features)],
    floor_rad_s: f64,
    threshold: f64,
    ids: &[String],
    fail_note: &str,
) -> ChannelCheck {
    let name = &names[if i < 2 { i + 1 } else { i + 2 }];
    let unit = ChannelFeatures::UNITS[i];
    let needs_both_stick_slip = i == ChannelFeatures::BREAKAWAY || i == ChannelFeatures::STICK_FRACTION;
    // (run, measured, simulated, floor).
    let rows: Vec<(&str, f64, f64, f64)> = ok
        .iter()
        .filter(|(q, f)| !needs_both_stick_slip || (q.measured.stick_slip() && f.stick_slip()))
        .filter_map(|(q, _)| {
            let (m, sim) = (q.channels_measured.values[i], q.channels_simulated?.values[i]);
            let fl =
                if i <= ChannelFeatures::ROTOR_MIN { q.floors.values[i].max(floor_rad_s) } else { q.floors.values[i] };
            (m.is_finite() && sim.is_finite() && fl > 0.0).then_some((q.id.as_str(), m, sim, fl))
        })
        .collect();
    if rows.is_empty() {
        let why = if needs_both_stick_slip {
            "no run sticks and slips in both record and simulation"
        } else {
            "no run records this channel"
        };
        return ChannelCheck::not_testable(name, ids.to_vec(), why.into());
    }
    let d: Vec<f64> = rows.iter().map(|r| r.1 - r.2).collect();
    let z: Vec<f64> = rows.iter().map(|r| (r.1 - r.2) / r.3).collect();
    let (stat, ratio) = (rms(&d), rms(&z));
    let noise_floor = if ratio > 0.0 { stat / ratio } else { rms(&rows.iter().map(|r| r.3).collect::<Vec<_>>()) };
    let bias = d.iter().sum::<f64>() / d.len() as f64;
    let worst = rows
        .iter()
        .zip(&z)
        .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
        .map(|(r, z)| {
            format!("{} measured {:.3}, simulated {:.3} {unit} ({z:+.1}× its floor {:.3})", r.0, r.1, r.2, r.3)
        })
        .unwrap_or_default();
    ChannelCheck::new(
        name,
        rows.iter().map(|r| r.0.to_string()).collect(),
        stat,
        noise_floor,
        threshold,
        format!(
            "measured − simulated over {} runs: RMS {stat:.3} {unit}, mean {bias:+.3} {unit}; worst {worst}{fail_note}",
            rows.len()
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A rotor that creeps below the slip speed (encoder chatter across it
    /// in the ±16 ms difference), then sticks while the pad force rises to
    /// 14 N and breaks away, three times: the estimation's episodes give the
    /// three break-aways at 14 N; the stretches below the slip speed give
    /// many more, most of them chatter at the creep's force.
    #[test]
    fn creep_chatter_is_no_break_away() {
        let (dt, tick) = (0.002, tick_rad(1000));
        let (mut t, mut phi, mut force) = (vec![], vec![], vec![]);
        let mut angle = 0.0;
        for k in 0..(3 * 1500) {
            let s = (k % 1500) as f64 * dt; // one cycle: 1 s creep, 0.5 s stuck, 1.5 s slip
            let (speed, f) = if s < 1.0 {
                (0.45, 11.0)
            } else if s < 1.5 {
                (0.0, 11.0 + 3.0 * (s - 1.0) / 0.5)
            } else {
                (3.0, 11.0)
            };
            angle += speed * dt;
            t.push(k as f64 * dt);
            phi.push((angle / tick).floor() * tick);
            force.push(f);
        }
        let o = rig_estimate::FrictionOptions::default();
        let peaks = breakaway_peaks(&t, &phi, &force, 0, 10.0, &o);
        assert_eq!(peaks.len(), 3, "{peaks:?}");
        assert!(peaks.iter().all(|p| (p - 14.0).abs() < 0.05), "{peaks:?}");
        let w1 = centred_speed(&t, &phi, 8);
        let stretches = stuck_stretches(&w1, 0.5);
        assert!(stretches.len() > 10, "{} stretches below the slip speed", stretches.len());
        assert!(breakaway_peaks(&t, &phi, &force, 0, 0.1, &o).is_empty(), "N0 below min_normal_force_n");
    }

    /// Stick-slip at 0.45 Hz (rotor speed 4(1 − cos) clipped at 0, stuck
    /// part of each cycle) that stops at `until_s` and rings down to steady
    /// slip at 2 rad/s; 40 s at 500 Hz. Read at the end of the run: a
    /// transient that stops at 10 s or 19.5 s is steady slip, one that lasts
    /// the run is stick-slip.
    #[test]
    fn the_regime_is_read_where_the_run_settles() {
        let dt = 0.002;
        let t: Vec<f64> = (0..20_000).map(|k| k as f64 * dt).collect();
        let run = |until_s: f64| {
            let mut angle = 0.0;
            let phi: Vec<f64> = t
                .iter()
                .map(|&x| {
                    let w = if x < until_s {
                        (4.0 * (1.0 - (2.0 * std::f64::consts::PI * 0.45 * x).cos()) - 1.5).max(0.0)
                    } else {
                        2.0 + 1.5 * (-(x - until_s) / 3.0).exp() * (2.0 * std::f64::consts::PI * 0.48 * x).sin()
                    };
                    angle += w * dt;
                    angle
                })
                .collect();
            let from = t.partition_point(|&x| x < 40.0 - 16.0);
            attractor_stick_slip(&t, &phi, from, 8, &rig_sweep::ClassifyOptions::default())
        };
        assert!(!run(10.0), "stops sticking at 10 s");
        assert!(!run(19.5), "stops sticking at 19.5 s");
        assert!(run(100.0), "sticks and slips to the end");
    }
}
