//! The one feature function of the slider, for recordings and simulations
//! alike ([`features`]): regime, stick-slip period, force drop per slip,
//! force at slip onset, stick fraction and creep before slip, each with its
//! spread over the slip events.
//!
//! The force carries impulsive noise (spikes, some below zero; Colas et al.
//! 2019 treat denoising as part of the measurement problem). A running
//! median over `median_window_s` removes spikes shorter than half the window
//! and keeps a step (a slip) sharp, which a linear low-pass would smear; the
//! window (2.5 ms by default) is a ninth of the stiffest spring's natural
//! period (23 ms at 2254 N/m), so the inertial oscillation passes.
//!
//! Events: the turning points of the filtered force with a hysteresis (a
//! maximum is confirmed when the force has fallen that much below it, and so
//! on), the larger of `min_drop` and `noise_multiple` robust deviations of
//! the record's noise ([`robust_noise_sd`]; 0 for a simulation), so noise
//! makes no event.
//! A slip is a maximum → next minimum; the force at slip onset is the
//! maximum, the drop the difference, the period the time between successive
//! maxima. The slider velocity follows from the force (the data's README):
//! v = V − (m g/k) dF̂/dt, F̂ = F/(m g); in stick dF̂/dt = L = k V/(m g).
//! Each loading phase (minimum → next maximum) is cut into `segments`
//! pieces; a piece whose least-squares slope gives v < V/2 counts as stuck
//! (stick fraction: stuck time over the cycle); creep before slip is
//! 1 − s/L for the slope s of the last piece, the slider's mean speed over
//! V just before it slips (0: stuck until the slip; 1: sliding at V); the
//! load rate is the slope over the middle three fifths of the loading phase
//! over L (what the spring as mounted does to a resting slider).
//!
//! Regime: fewer than `min_events` slips → steady sliding; slips with a
//! median stick fraction of at least `stick_regime_fraction` → stick-slip
//! (a relaxation oscillation: the slider rests, then slips); slips with less,
//! at a median period of at least `inertial_ratio` natural periods
//! 2π√(m/k) → creep (still a relaxation, but the slider creeps through the
//! loading phase instead of resting: Heslot et al. 1994's creep-dominated
//! regime); shorter → inertial oscillation (the mass oscillates on its
//! spring near its natural period and hardly rests).

use serde::{Deserialize, Serialize};

/// The feature function's settings (pipeline.toml's `[stage.params]`).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FeatureOptions {
    /// Running-median window, s.
    pub median_window_s: f64,
    /// Hysteresis of the turning points, in F/(m g).
    pub min_drop: f64,
    /// Pieces of each loading phase for the stick fraction and the creep.
    pub segments: usize,
    /// Fewer slips than this: steady sliding.
    pub min_events: usize,
    /// The hysteresis is at least this many robust noise deviations of the record.
    pub noise_multiple: f64,
    /// Slips with a median stick fraction at least this: stick-slip.
    pub stick_regime_fraction: f64,
    /// Otherwise: a median period of at least this many natural periods is creep, less is inertial oscillation.
    pub inertial_ratio: f64,
}

/// The regime of a run.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Regime {
    SteadySliding,
    StickSlip,
    Creep,
    InertialOscillation,
}

impl Regime {
    pub fn label(self) -> &'static str {
        match self {
            Regime::SteadySliding => "steady sliding",
            Regime::StickSlip => "stick-slip",
            Regime::Creep => "creep",
            Regime::InertialOscillation => "inertial oscillation",
        }
    }
}

/// A feature over the events: median, standard deviation, count, and the
/// first and third quartiles (the events' dispersion the misfit reads,
/// `rig_slider::fit::dispersion`: robust where the sd is not, one outlier
/// event moves neither).
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
pub struct Spread {
    pub median: f64,
    pub sd: f64,
    pub n: usize,
    pub q1: f64,
    pub q3: f64,
}

impl Spread {
    /// Median, sample sd, count and quartiles of `v` (NaN median, sd and
    /// quartiles when empty). Quartiles interpolate linearly between order
    /// statistics (Hyndman & Fan's type 7: q(p) at rank p (n − 1)).
    pub fn of(v: &[f64]) -> Spread {
        if v.is_empty() {
            return Spread { median: f64::NAN, sd: f64::NAN, n: 0, q1: f64::NAN, q3: f64::NAN };
        }
        let mut s = v.to_vec();
        s.sort_by(f64::total_cmp);
        let n = s.len();
        let median = if n % 2 == 1 { s[n / 2] } else { 0.5 * (s[n / 2 - 1] + s[n / 2]) };
        let mean = s.iter().sum::<f64>() / n as f64;
        let sd = if n > 1 { (s.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64).sqrt() } else { 0.0 };
        let quantile = |q: f64| {
            let r = q * (n - 1) as f64;
            let (i, w) = (r.floor() as usize, r - r.floor());
            if i + 1 < n { s[i] + w * (s[i + 1] - s[i]) } else { s[i] }
        };
        Spread { median, sd, n, q1: quantile(0.25), q3: quantile(0.75) }
    }
}

/// The features of one run (measured or simulated).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Features {
    pub regime: Regime,
    /// Slip events found.
    pub events: usize,
    pub period_s: Spread,
    /// Force drop per slip, F/(m g).
    pub drop: Spread,
    /// Force at slip onset, F/(m g).
    pub onset: Spread,
    pub stick_fraction: Spread,
    /// Creep before slip: the slider's mean speed over V in the last piece of the loading phase.
    pub creep: Spread,
    /// The force's rise over the middle three fifths of each loading phase,
    /// in units of L = k V/(m g) (stated k and m): 1 for a slider at rest on
    /// the stated spring (whatever its true stiffness when, as here, the
    /// force is its extension read through the stated k; r for a spring r
    /// times stiffer read by a load cell), below 1 while it creeps.
    pub load_rate: Spread,
    /// Force where a slip ends (the minimum after each maximum), F/(m g).
    pub trough: Spread,
    /// Mean force over the record, F/(m g).
    pub mean_force: f64,
    /// The mean force of each of the record's [`LEVEL_PARTS`] consecutive
    /// parts, over the parts: how far the friction level wanders along the
    /// track within one run (every run covers 15.8–16.3 mm of paper), the
    /// yardstick for a level that differs between runs ([`crate::level`]).
    pub level_parts: Spread,
    /// 2π √(m/k), s.
    pub natural_period_s: f64,
    /// The record's robust noise deviation, F/(m g) ([`robust_noise_sd`]).
    pub noise_sd: f64,
    /// The hysteresis the events were found with, F/(m g).
    pub hysteresis: f64,
}

impl Features {
    /// No events: the features of a record not yet measured (steady, NaN spreads).
    pub fn default_steady() -> Features {
        let none = Spread::of(&[]);
        Features {
            regime: Regime::SteadySliding,
            events: 0,
            period_s: none,
            drop: none,
            onset: none,
            trough: none,
            stick_fraction: none,
            creep: none,
            load_rate: none,
            mean_force: f64::NAN,
            level_parts: none,
            natural_period_s: f64::NAN,
            noise_sd: f64::NAN,
            hysteresis: f64::NAN,
        }
    }
}

/// What the feature function needs to know of the run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunConstants {
    pub stiffness_n_m: f64,
    pub drive_speed_m_s: f64,
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
}

/// The features of a force-over-weight record sampled at `time_s`.
pub fn features(time_s: &[f64], force: &[f64], c: &RunConstants, o: &FeatureOptions) -> Features {
    assert_eq!(time_s.len(), force.len(), "one time per sample");
    let n = time_s.len();
    let fs = (n.max(2) - 1) as f64 / (time_s[n - 1] - time_s[0]);
    let half = (o.median_window_s * fs / 2.0).round() as usize;
    let f = running_median(force, half);
    let natural_period_s = 2.0 * std::f64::consts::PI * (c.mass_kg / c.stiffness_n_m).sqrt();
    let load_rate = c.stiffness_n_m * c.drive_speed_m_s / (c.mass_kg * c.gravity_m_s2);
    let noise_sd = robust_noise_sd(force, &f);
    let hysteresis = o.min_drop.max(o.noise_multiple * noise_sd);
    let turns = turning_points(&f, hysteresis);
    let (mut period, mut drop, mut onset, mut stick, mut creep) = (vec![], vec![], vec![], vec![], vec![]);
    let mut trough = vec![];
    let mut rise = vec![];
    // turns alternate; a slip is a maximum followed by a minimum.
    let maxima: Vec<usize> = (0..turns.len()).filter(|&j| turns[j].1 && j + 1 < turns.len()).collect();
    for (e, &j) in maxima.iter().enumerate() {
        let (imax, imin) = (turns[j].0, turns[j + 1].0);
        drop.push(f[imax] - f[imin]);
        onset.push(f[imax]);
        trough.push(f[imin]);
        // The complete cycle ending at this maximum: previous maximum → min → this maximum.
        if e == 0 || j < 2 {
            continue;
        }
        let (iprev, iload) = (turns[maxima[e - 1]].0, turns[j - 1].0);
        let cycle_s = time_s[imax] - time_s[iprev];
        period.push(cycle_s);
        let segs = o.segments.max(1);
        let len = imax - iload;
        if len < 2 * segs {
            continue;
        }
        let mut stuck_s = 0.0;
        let mut last_speed = f64::NAN;
        for s in 0..segs {
            let (a, b) = (iload + s * len / segs, iload + (s + 1) * len / segs);
            let slope = ls_slope(&time_s[a..=b], &f[a..=b]);
            let speed_ratio = 1.0 - slope / load_rate;
            if speed_ratio < 0.5 {
                stuck_s += time_s[b] - time_s[a];
            }
            last_speed = speed_ratio;
        }
        stick.push(stuck_s / cycle_s);
        creep.push(last_speed);
        let (a, b) = (iload + len / 5, imax - len / 5);
        rise.push(ls_slope(&time_s[a..=b], &f[a..=b]) / load_rate);
    }
    let events = drop.len();
    let period_s = Spread::of(&period);
    let stick_fraction = Spread::of(&stick);
    let regime = if events < o.min_events || period_s.n == 0 {
        Regime::SteadySliding
    } else if stick_fraction.median >= o.stick_regime_fraction {
        Regime::StickSlip
    } else if period_s.median >= o.inertial_ratio * natural_period_s {
        Regime::Creep
    } else {
        Regime::InertialOscillation
    };
    Features {
        regime,
        events,
        period_s,
        drop: Spread::of(&drop),
        onset: Spread::of(&onset),
        stick_fraction,
        creep: Spread::of(&creep),
        load_rate: Spread::of(&rise),
        trough: Spread::of(&trough),
        mean_force: f.iter().sum::<f64>() / n as f64,
        level_parts: Spread::of(&level_parts(&f)),
        natural_period_s,
        noise_sd,
        hysteresis,
    }
}

/// Parts a record is cut into for [`Features::level_parts`].
pub const LEVEL_PARTS: usize = 4;

/// The mean of each of [`LEVEL_PARTS`] consecutive, equal parts of `f`
/// (empty when `f` has fewer samples than parts).
fn level_parts(f: &[f64]) -> Vec<f64> {
    let len = f.len() / LEVEL_PARTS;
    if len == 0 {
        return Vec::new();
    }
    f.chunks_exact(len).take(LEVEL_PARTS).map(|c| c.iter().sum::<f64>() / len as f64).collect()
}

/// An independent reading of an oscillation's period, blind to the turning
/// points: the amplitude spectrum of the whole filtered record (Hann window,
/// linear trend removed; `rig_spectra::amplitude_spectrum`), its largest bin
/// between half and twice the natural frequency 1/T0, refined by Gaussian
/// interpolation (`rig_spectra::interpolate_gaussian`); s. NaN when the
/// record is too short for a bin in that band.
///
/// Bins within [`MAINS_HALF_WIDTH_HZ`] of a multiple of `mains_hz` are
/// skipped (0: none): the shipped records carry a line at the mains
/// frequency in every run, 0.5–0.9 µm of spring extension at both springs
/// (the sensor's pick-up, not the slider's motion), which at 2254 N/m sits
/// at 1.16/T0, inside the band, and outgrows a spread-out oscillation.
pub fn spectral_period_s(filtered: &[f64], fs_hz: f64, natural_period_s: f64, mains_hz: f64) -> f64 {
    use rig_spectra::{Detrend, Window, amplitude_spectrum, interpolate_gaussian};
    let Ok(s) = amplitude_spectrum(filtered, fs_hz, Window::Hann, Detrend::Linear) else { return f64::NAN };
    let (lo, hi) = (0.5 / natural_period_s, 2.0 / natural_period_s);
    let mains = |f: f64| mains_hz > 0.0 && (f - mains_hz * (f / mains_hz).round()).abs() <= MAINS_HALF_WIDTH_HZ;
    let band = (1..s.freq_hz.len().saturating_sub(1))
        .filter(|&i| s.freq_hz[i] >= lo && s.freq_hz[i] <= hi && !mains(s.freq_hz[i]));
    let Some(k) = band.max_by(|&a, &b| s.amplitude[a].total_cmp(&s.amplitude[b])) else { return f64::NAN };
    let (delta, _) = interpolate_gaussian(s.amplitude[k - 1], s.amplitude[k], s.amplitude[k + 1]);
    1.0 / (s.freq_hz[k] + delta * s.resolution_hz)
}

/// Half width of the band skipped around each multiple of the mains
/// frequency in [`spectral_period_s`], Hz (the line's leakage under a Hann
/// window over the shortest shipped record, 3.8 s: two bins of 0.26 Hz).
pub const MAINS_HALF_WIDTH_HZ: f64 = 0.6;

/// The channel's resolution: the median spacing of the record's distinct
/// values, in the record's unit (F/(m g) here). A digitised record sits on a
/// grid (the shipped runs: 0.00059 at 168 N/m and 0.0070 at 2254 N/m, both
/// about 1 µm of spring extension, m g/k times the step); a simulation's
/// values are continuous and give a spacing near 0. NaN for fewer than two
/// distinct values.
pub fn channel_step(raw: &[f64]) -> f64 {
    let mut v: Vec<f64> = raw.iter().copied().filter(|x| x.is_finite()).collect();
    v.sort_by(f64::total_cmp);
    v.dedup();
    let gaps: Vec<f64> = v.windows(2).map(|w| w[1] - w[0]).collect();
    Spread::of(&gaps).median
}

/// 1.4826 × the median absolute deviation of the raw record from its running
/// median: the noise's standard deviation, blind to the spikes and to the
/// slips (both are rare), 0 for a noiseless simulation.
///
/// A deviation is ≥ +0 under `f64::total_cmp` (an absolute value), so when
/// more than half of them are exactly +0 (a smooth simulation, whose
/// running median is the sample itself wherever the window is monotone)
/// the median is +0 without the selection: the same bits.
pub fn robust_noise_sd(raw: &[f64], filtered: &[f64]) -> f64 {
    let n = raw.len().min(filtered.len());
    let m = n / 2;
    let zeros = raw.iter().zip(filtered).filter(|(a, b)| (*a - *b).abs().to_bits() == 0).count();
    if zeros > m {
        return 0.0;
    }
    let mut d: Vec<f64> = raw.iter().zip(filtered).map(|(a, b)| (a - b).abs()).collect();
    1.4826 * *d.select_nth_unstable_by(m, f64::total_cmp).1
}

/// Running median over 2·`half` + 1 samples (shrinking at the ends): the
/// element a selection over each window gives, bit for bit — the
/// workspace's one running median, `rig_spectra::stickslip::running_median`
/// (a monotone window read off without sorting: most of a simulated record).
pub fn running_median(x: &[f64], half: usize) -> Vec<f64> {
    rig_spectra::stickslip::running_median(x, 2 * half + 1)
}

/// Turning points with hysteresis `h`: (index, is_maximum), alternating.
pub fn turning_points(f: &[f64], h: f64) -> Vec<(usize, bool)> {
    let mut out = Vec::new();
    if f.is_empty() {
        return out;
    }
    let (mut hi, mut lo) = (0usize, 0usize);
    let mut dir = 0i8; // 1: looking for a maximum, -1: for a minimum
    for i in 1..f.len() {
        if f[i] > f[hi] {
            hi = i;
        }
        if f[i] < f[lo] {
            lo = i;
        }
        match dir {
            0 if f[hi] - f[i] >= h && hi > lo => {
                out.push((hi, true));
                dir = -1;
                lo = i;
            }
            0 if f[i] - f[lo] >= h && lo > hi => {
                out.push((lo, false));
                dir = 1;
                hi = i;
            }
            1 if f[hi] - f[i] >= h => {
                out.push((hi, true));
                dir = -1;
                lo = i;
            }
            -1 if f[i] - f[lo] >= h => {
                out.push((lo, false));
                dir = 1;
                hi = i;
            }
            _ => {}
        }
    }
    out
}

/// Least-squares slope of y against t.
fn ls_slope(t: &[f64], y: &[f64]) -> f64 {
    let n = t.len() as f64;
    let (mt, my) = (t.iter().sum::<f64>() / n, y.iter().sum::<f64>() / n);
    let (mut sxy, mut sxx) = (0.0, 0.0);
    for (a, b) in t.iter().zip(y) {
        sxy += (a - mt) * (b - my);
        sxx += (a - mt) * (a - mt);
    }
    sxy / sxx
}

#[cfg(test)]
mod tests {
    use super::*;

    fn opts() -> FeatureOptions {
        FeatureOptions {
            median_window_s: 0.0025,
            min_drop: 0.02,
            segments: 5,
            min_events: 3,
            noise_multiple: 3.0,
            stick_regime_fraction: 0.5,
            inertial_ratio: 3.0,
        }
    }

    #[test]
    fn sawtooth_with_spikes_gives_its_period_drop_and_onset() {
        // Stick at the loading rate L, then an instantaneous drop of 0.05: period 0.05/L.
        let c = RunConstants { stiffness_n_m: 168.0, drive_speed_m_s: 42e-6, mass_kg: 0.0307, gravity_m_s2: 9.81 };
        let load = c.stiffness_n_m * c.drive_speed_m_s / (c.mass_kg * c.gravity_m_s2);
        let period = 0.05 / load;
        let fs = 2000.0;
        let n = (10.0 * period * fs) as usize;
        let t: Vec<f64> = (0..n).map(|i| 3.0 + i as f64 / fs).collect();
        let mut f: Vec<f64> = t.iter().map(|&t| 0.30 + 0.05 * ((t - 3.0) / period).fract()).collect();
        for i in (17..n).step_by(997) {
            f[i] = -0.1; // impulsive noise, one sample wide
        }
        let r = features(&t, &f, &c, &opts());
        assert_eq!(r.regime, Regime::StickSlip);
        assert_eq!(r.events, 9);
        assert!((r.period_s.median / period - 1.0).abs() < 1e-3, "{:?}", r.period_s);
        assert!((r.drop.median - 0.05).abs() < 1e-3, "{:?}", r.drop);
        assert!((r.onset.median - 0.35).abs() < 1e-3, "{:?}", r.onset);
        assert!((r.trough.median - 0.30).abs() < 1e-3, "{:?}", r.trough);
        // The level over the record's parts (2.5 cycles each: 0.3225 and 0.3275 by turns), spikes filtered out.
        assert_eq!(r.level_parts.n, LEVEL_PARTS);
        assert!((r.level_parts.median - 0.325).abs() < 1e-3 && r.level_parts.sd < 4e-3, "{:?}", r.level_parts);
        assert!(r.stick_fraction.median > 0.95, "{:?}", r.stick_fraction);
        assert!(r.creep.median.abs() < 0.02, "{:?}", r.creep);
        assert!((r.load_rate.median - 1.0).abs() < 0.02, "{:?}", r.load_rate);
    }

    #[test]
    fn the_sliding_median_is_the_selection_over_each_window() {
        // On a grid (many ties), with spikes, signed zeros and both ends.
        let x: Vec<f64> = (0..3000u64)
            .map(|i| {
                let z = (i.wrapping_mul(0x9e37_79b9_7f4a_7c15) >> 40) as f64 / (1u64 << 24) as f64;
                if i % 97 == 0 {
                    -0.1
                } else if i % 89 == 0 {
                    -0.0
                } else {
                    (z * 20.0).round() * 0.007
                }
            })
            .collect();
        for half in [1, 3, 7, 40] {
            let fast = running_median(&x, half);
            for (i, &f) in fast.iter().enumerate() {
                let (a, b) = (i.saturating_sub(half), (i + half + 1).min(x.len()));
                let mut w = x[a..b].to_vec();
                let m = w.len() / 2;
                let slow = *w.select_nth_unstable_by(m, f64::total_cmp).1;
                assert_eq!(f.to_bits(), slow.to_bits(), "half {half} at {i}");
            }
        }
        assert!(running_median(&[], 3).is_empty());
        assert_eq!(running_median(&x[..2], 3).len(), 2);
    }

    #[test]
    fn the_noise_deviation_is_the_selection_with_or_without_its_shortcut() {
        // Half, just over half and just under half of the deviations exactly +0 (the shortcut's edge), and none.
        let reference = |raw: &[f64], f: &[f64]| {
            let mut d: Vec<f64> = raw.iter().zip(f).map(|(a, b)| (a - b).abs()).collect();
            let m = d.len() / 2;
            1.4826 * *d.select_nth_unstable_by(m, f64::total_cmp).1
        };
        let f: Vec<f64> = (0..101).map(|i| 0.3 + 1e-3 * i as f64).collect();
        for equal in [0, 49, 50, 51, 52, 101] {
            let raw: Vec<f64> =
                f.iter().enumerate().map(|(i, &x)| if i < equal { x } else { x + 1e-4 * (1 + i % 7) as f64 }).collect();
            let (got, want) = (robust_noise_sd(&raw, &f), reference(&raw, &f));
            assert_eq!(got.to_bits(), want.to_bits(), "{equal} equal samples: {got} vs {want}");
            assert_eq!(got == 0.0, equal > 50, "{equal} equal samples");
        }
    }

    #[test]
    fn channel_step_reads_the_grid_a_record_sits_on() {
        // A slow ramp digitised on a grid of 0.007 with noise of a few steps: the step, not the noise.
        let x: Vec<f64> = (0..5000)
            .map(|i| ((0.3 + 1e-5 * i as f64 + 0.01 * ((i * 7919) % 13) as f64 / 13.0) / 0.007).round() * 0.007)
            .collect();
        assert!((channel_step(&x) / 0.007 - 1.0).abs() < 1e-9, "{}", channel_step(&x));
        let smooth: Vec<f64> = (0..5000).map(|i| 0.3 + 1e-5 * i as f64).collect();
        assert!(channel_step(&smooth) < 1e-4);
    }

    #[test]
    fn sine_near_the_natural_period_is_inertial_and_noise_is_steady() {
        let c = RunConstants { stiffness_n_m: 2254.0, drive_speed_m_s: 1.1e-3, mass_kg: 0.0307, gravity_m_s2: 9.81 };
        let t0 = 2.0 * std::f64::consts::PI * (c.mass_kg / c.stiffness_n_m).sqrt();
        let t: Vec<f64> = (0..4000).map(|i| i as f64 / 2000.0).collect();
        let f: Vec<f64> =
            t.iter().map(|&t| 0.33 + 0.04 * (2.0 * std::f64::consts::PI * t / (1.1 * t0)).sin()).collect();
        let r = features(&t, &f, &c, &opts());
        assert_eq!(r.regime, Regime::InertialOscillation);
        assert!((r.period_s.median / (1.1 * t0) - 1.0).abs() < 0.03, "{:?}", r.period_s);
        // The spectrum reads the same period without the turning points (bins of 0.5 Hz at 39 Hz).
        let ps = spectral_period_s(&f, 2000.0, t0, 0.0);
        assert!((ps / (1.1 * t0) - 1.0).abs() < 0.003, "spectral period {ps} vs {}", 1.1 * t0);
        // A stronger mains line in the band (50 Hz, 1.16/T0) is skipped, not read as the oscillation.
        let hum: Vec<f64> =
            t.iter().zip(&f).map(|(&t, &x)| x + 0.08 * (2.0 * std::f64::consts::PI * 50.0 * t).sin()).collect();
        assert!((spectral_period_s(&hum, 2000.0, t0, 0.0) * 50.0 - 1.0).abs() < 0.003, "unmasked, the hum wins");
        let ps = spectral_period_s(&hum, 2000.0, t0, 50.0);
        assert!((ps / (1.1 * t0) - 1.0).abs() < 0.003, "spectral period with the hum skipped {ps}");
        let quiet: Vec<f64> =
            t.iter().enumerate().map(|(i, _)| 0.33 + 0.005 * ((i * 7919) % 13) as f64 / 13.0).collect();
        assert_eq!(features(&t, &quiet, &c, &opts()).regime, Regime::SteadySliding);
    }
}
