//! The seven window features, one function for measurement and simulation:
//! bit-speed maximum and minimum (means over stick-slip cycles), stick
//! fraction, stick-slip fundamental (line analysis of rig_spectra), the
//! mean torque–bit-speed loop area per cycle, and the torque levels (issue 26):
//! the mean slip torque (mean torque while the bit turns faster than the
//! stick speed) and the break-away torque (mean over the window's complete
//! stick phases of each phase's largest torque). A free run that reproduces
//! the motion with a friction level off the measured one misses these two.

use crate::LaviError;
use rig_spectra::{LineAnalysisOptions, LineOptions, line_analysis, lowpass_fft};
use serde::Serialize;
use std::ops::Range;

/// How features are measured (the same for every signal).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FeatureOptions {
    pub fs_hz: f64,
    /// Zero-phase low-pass applied to the whole span before the window is cut (10 Hz: Lobo et al. 2020).
    pub cutoff_hz: f64,
    pub transition_hz: f64,
    /// Bit speed below which the bit counts as stuck, rpm (5 rpm: issue 10).
    pub stick_speed_rpm: f64,
}

impl FeatureOptions {
    /// The study's options at a record's sample rate.
    pub fn of_study(fs_hz: f64, p: &crate::StudyParams) -> Self {
        Self { fs_hz, cutoff_hz: p.cutoff_hz, transition_hz: p.transition_hz, stick_speed_rpm: p.stick_speed_rpm }
    }
}

/// Features of one window. `fundamental_hz` is NaN when the line analysis finds no line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Features {
    pub bit_speed_max_rpm: f64,
    pub bit_speed_min_rpm: f64,
    pub stick_fraction: f64,
    pub fundamental_hz: f64,
    /// Mean |∮ T dΩ| per cycle, N m·rpm.
    pub loop_area: f64,
    /// Mean torque over the samples with bit speed ≥ the stick speed, N m (NaN: none).
    pub slip_torque_nm: f64,
    /// Mean over the complete stick phases of each one's largest torque, N m (NaN: no stick phase ends in the window).
    pub breakaway_torque_nm: f64,
    /// Mean length of the complete stick phases, s (NaN: none); not a target, what `stick_fraction` is made of.
    pub stick_phase_s: f64,
    /// Complete stick phases in the window.
    pub stick_phases: usize,
    /// Complete cycles found (0: the window is one pseudo-cycle).
    pub cycles: usize,
}

/// Feature names in table order.
pub const FEATURES: [&str; N_FEATURES] = [
    "bit_speed_max_rpm",
    "bit_speed_min_rpm",
    "stick_fraction",
    "fundamental_hz",
    "loop_area",
    "slip_torque_nm",
    "breakaway_torque_nm",
];

/// Number of window features.
pub const N_FEATURES: usize = 7;

impl Features {
    /// Every feature NaN (a run that failed).
    pub const NAN: Features = Features {
        bit_speed_max_rpm: f64::NAN,
        bit_speed_min_rpm: f64::NAN,
        stick_fraction: f64::NAN,
        fundamental_hz: f64::NAN,
        loop_area: f64::NAN,
        slip_torque_nm: f64::NAN,
        breakaway_torque_nm: f64::NAN,
        stick_phase_s: f64::NAN,
        stick_phases: 0,
        cycles: 0,
    };

    pub fn get(&self, i: usize) -> f64 {
        [
            self.bit_speed_max_rpm,
            self.bit_speed_min_rpm,
            self.stick_fraction,
            self.fundamental_hz,
            self.loop_area,
            self.slip_torque_nm,
            self.breakaway_torque_nm,
        ][i]
    }
}

/// Features of `window` inside the span (`bit_rpm`, `torque_nm` cover the whole
/// span: warm-up and window), after the low-pass of the whole span. Cycles run
/// between successive upward crossings of a Schmitt trigger at the window's
/// mean ± 25 % of its half-range (so sensor noise makes no extra crossing).
pub fn window_features(
    bit_rpm: &[f64],
    torque_nm: &[f64],
    window: Range<usize>,
    o: &FeatureOptions,
) -> Result<Features, LaviError> {
    check_lengths(bit_rpm, torque_nm, &window)?;
    let v_all = lowpass_fft(bit_rpm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
    let t_all = lowpass_fft(torque_nm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
    features_of(&v_all[window.clone()], &t_all[window], o)
}

/// [`window_features`] and [`stick_torque`] of one window from one low-pass
/// of each channel: what a free run is judged by, made once (the same numbers
/// as the two calls, which low-pass the same span the same way).
pub fn window_features_and_stick(
    bit_rpm: &[f64],
    torque_nm: &[f64],
    window: Range<usize>,
    o: &FeatureOptions,
) -> Result<(Features, StickTorque), LaviError> {
    check_lengths(bit_rpm, torque_nm, &window)?;
    let v_all = lowpass_fft(bit_rpm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
    let t_all = lowpass_fft(torque_nm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
    let (v, t) = (&v_all[window.clone()], &t_all[window]);
    Ok((features_of(v, t, o)?, stick_torque_of(v, t, o.stick_speed_rpm)))
}

/// The window's features from its low-passed bit speed `v` (rpm) and torque `t` (N m).
fn features_of(v: &[f64], t: &[f64], o: &FeatureOptions) -> Result<Features, LaviError> {
    let stick_fraction = v.iter().filter(|x| **x < o.stick_speed_rpm).count() as f64 / v.len() as f64;
    let (slip_sum, slip_n) =
        v.iter().zip(t).filter(|(x, _)| **x >= o.stick_speed_rpm).fold((0.0, 0usize), |(s, n), (_, y)| (s + y, n + 1));
    let slip_torque_nm = if slip_n == 0 { f64::NAN } else { slip_sum / slip_n as f64 };
    let phases = stick_phases(v, t, o.stick_speed_rpm);
    let (peaks, lengths): (Vec<f64>, Vec<f64>) = phases.iter().map(|(p, n)| (*p, *n as f64 / o.fs_hz)).unzip();
    let breakaway_torque_nm = if phases.is_empty() { f64::NAN } else { mean(&peaks) };
    let stick_phase_s = if phases.is_empty() { f64::NAN } else { mean(&lengths) };
    let starts = cycle_starts(v);
    let (mut maxs, mut mins, mut areas) = (Vec::new(), Vec::new(), Vec::new());
    for w in starts.windows(2) {
        let (seg_v, seg_t) = (&v[w[0]..=w[1]], &t[w[0]..=w[1]]);
        maxs.push(seg_v.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
        mins.push(seg_v.iter().cloned().fold(f64::INFINITY, f64::min));
        areas.push(shoelace(seg_v, seg_t).abs());
    }
    let cycles = maxs.len();
    if cycles == 0 {
        maxs.push(v.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
        mins.push(v.iter().cloned().fold(f64::INFINITY, f64::min));
        areas.push(shoelace(v, t).abs());
    }
    Ok(Features {
        bit_speed_max_rpm: mean(&maxs),
        bit_speed_min_rpm: mean(&mins),
        stick_fraction,
        fundamental_hz: fundamental_hz(v, o.fs_hz, o.cutoff_hz)?.unwrap_or(f64::NAN),
        loop_area: mean(&areas),
        slip_torque_nm,
        breakaway_torque_nm,
        stick_phase_s,
        stick_phases: phases.len(),
        cycles,
    })
}

/// The two channels cover the same span and hold the window (at least 16 samples).
fn check_lengths(bit_rpm: &[f64], torque_nm: &[f64], window: &Range<usize>) -> Result<(), LaviError> {
    if bit_rpm.len() != torque_nm.len() || window.end > bit_rpm.len() || window.len() < 16 {
        return Err(LaviError::Input {
            what: "window_features",
            rule: format!(
                "bit speed ({}) and torque ({}) must have equal lengths holding the window {:?} of >= 16 samples",
                bit_rpm.len(),
                torque_nm.len(),
                window
            ),
        });
    }
    Ok(())
}

/// The torque through the complete stick phases of a window (issue 26's
/// break-away target): a bit held by a shaft that a turning top winds up sees
/// its holding torque k φ + c Ω_top rise through the whole stick, to the
/// break-away level at its end. The same low-pass and stick speed as
/// [`window_features`].
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct StickTorque {
    /// Complete stick phases in the window.
    pub phases: usize,
    /// Phases whose torque at their last sample is below the one at their first.
    pub falling: usize,
    /// Mean torque at the phases' first and last samples, N m (NaN: none).
    pub entry_nm: f64,
    pub exit_nm: f64,
    /// Mean position of each phase's largest torque, as a fraction of its length (0 entry, 1 exit).
    pub peak_position: f64,
}

/// [`StickTorque`] of `window` inside the span (arguments as [`window_features`]).
pub fn stick_torque(
    bit_rpm: &[f64],
    torque_nm: &[f64],
    window: Range<usize>,
    o: &FeatureOptions,
) -> Result<StickTorque, LaviError> {
    let v = lowpass_fft(bit_rpm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
    let t = lowpass_fft(torque_nm, o.fs_hz, o.cutoff_hz, o.transition_hz)?;
    Ok(stick_torque_of(&v[window.clone()], &t[window], o.stick_speed_rpm))
}

/// [`StickTorque`] from the window's low-passed bit speed `v` (rpm) and torque `t` (N m).
fn stick_torque_of(v: &[f64], t: &[f64], stick_speed_rpm: f64) -> StickTorque {
    // Complete phases only: begun after a slip sample of the window, ended by one.
    let (mut spans, mut start, mut armed) = (Vec::new(), None, false);
    for (i, x) in v.iter().enumerate() {
        match (start, *x < stick_speed_rpm) {
            (None, true) if armed => start = Some(i),
            (Some(a), false) => {
                spans.push(a..i);
                start = None;
            }
            (None, false) => armed = true,
            _ => {}
        }
    }
    let n = spans.len();
    let nan_if_none = |x: f64| if n == 0 { f64::NAN } else { x / n as f64 };
    let peak = |r: &Range<usize>| {
        let k = (r.start..r.end).fold(r.start, |b, i| if t[i] > t[b] { i } else { b });
        (k - r.start) as f64 / (r.len() - 1).max(1) as f64
    };
    StickTorque {
        phases: n,
        falling: spans.iter().filter(|r| t[r.end - 1] < t[r.start]).count(),
        entry_nm: nan_if_none(spans.iter().map(|r| t[r.start]).sum()),
        exit_nm: nan_if_none(spans.iter().map(|r| t[r.end - 1]).sum()),
        peak_position: nan_if_none(spans.iter().map(peak).sum()),
    }
}

/// The band and tolerance of every line analysis of the LAVI study: from
/// 0.2 Hz (a 4 s window has 0.25 Hz bins; slower changes of the drive's
/// speed are not stick-slip, whose fundamental is ≈ 2.7 Hz) to `max_hz`, the
/// low-pass cut-off (nothing is left above it); the library's 1.5 bins, as
/// the measured lines carry noise and the windows are short.
pub fn line_options(max_hz: f64) -> LineAnalysisOptions {
    LineAnalysisOptions { min_freq_hz: 0.2, max_freq_hz: max_hz, tolerance_bins: LineOptions::default().tolerance_bins }
}

/// The stick-slip fundamental by `rig_spectra::line_analysis` ([`line_options`]).
pub fn fundamental_hz(x: &[f64], fs_hz: f64, max_hz: f64) -> Result<Option<f64>, LaviError> {
    Ok(line_analysis(x, fs_hz, &line_options(max_hz))?.lines.f0_hz)
}

/// Indices of upward crossings of mean + h after the signal was below mean − h,
/// h = 25 % of the half-range.
fn cycle_starts(v: &[f64]) -> Vec<usize> {
    let (lo, hi) =
        (v.iter().cloned().fold(f64::INFINITY, f64::min), v.iter().cloned().fold(f64::NEG_INFINITY, f64::max));
    let m = mean(v);
    let h = 0.25 * 0.5 * (hi - lo);
    if h <= 0.0 {
        return Vec::new();
    }
    let mut armed = false;
    let mut out = Vec::new();
    for (i, x) in v.iter().enumerate() {
        if *x < m - h {
            armed = true;
        } else if armed && *x > m + h {
            out.push(i);
            armed = false;
        }
    }
    out
}

/// The largest torque of each complete stick phase (consecutive samples with
/// speed below `stick`, followed by a slip); a phase still open at the end is left out.
pub fn stick_phase_maxima(speed: &[f64], torque: &[f64], stick: f64) -> Vec<f64> {
    stick_phases(speed, torque, stick).into_iter().map(|(t, _)| t).collect()
}

/// Each complete stick phase (as [`stick_phase_maxima`]): its largest torque and its length in samples.
pub fn stick_phases(speed: &[f64], torque: &[f64], stick: f64) -> Vec<(f64, usize)> {
    let mut out = Vec::new();
    let mut cur: Option<(f64, usize)> = None;
    for (v, t) in speed.iter().zip(torque) {
        if *v < stick {
            cur = Some(cur.map_or((*t, 1), |(c, n)| (c.max(*t), n + 1)));
        } else if let Some(c) = cur.take() {
            out.push(c);
        }
    }
    out
}

/// Signed area of the closed polygon (x, y) (shoelace formula, closing edge included).
pub fn shoelace(x: &[f64], y: &[f64]) -> f64 {
    let n = x.len();
    let mut s = 0.0;
    for i in 0..n {
        let j = (i + 1) % n;
        s += x[i] * y[j] - x[j] * y[i];
    }
    0.5 * s
}

pub(crate) fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

#[cfg(test)]
mod tests {
    use super::*;

    const FS: f64 = 1000.0;

    fn opts() -> FeatureOptions {
        FeatureOptions { fs_hz: FS, cutoff_hz: 10.0, transition_hz: 2.0, stick_speed_rpm: 5.0 }
    }

    /// A sawtooth stick-slip record: per 0.5 s cycle (2 Hz), 30 % stuck at 0,
    /// then a slip arc 100·sin(π s) rpm; 12 s, window 2–10 s.
    fn sawtooth() -> (Vec<f64>, Vec<f64>) {
        let period = 0.5;
        let v: Vec<f64> = (0..12_000)
            .map(|i| {
                let ph = (i as f64 / FS / period).fract();
                if ph < 0.3 { 0.0 } else { 100.0 * (std::f64::consts::PI * (ph - 0.3) / 0.7).sin() }
            })
            .collect();
        let t = v.iter().map(|x| 1.0 + 0.002 * x).collect();
        (v, t)
    }

    #[test]
    fn sawtooth_stick_slip_has_its_known_features() {
        let (v, t) = sawtooth();
        let f = window_features(&v, &t, 2000..10_000, &opts()).unwrap();
        // Exact values: max 100, min 0, f0 2 Hz; stick fraction 0.3 + 0.7·2·asin(0.05)/π = 0.3223.
        let stick = 0.3 + 0.7 * 2.0 * (0.05f64).asin() / std::f64::consts::PI;
        assert!((f.bit_speed_max_rpm - 100.0).abs() < 3.0, "{f:?}");
        assert!(f.bit_speed_min_rpm.abs() < 3.0, "{f:?}");
        assert!((f.stick_fraction - stick).abs() < 0.03, "{f:?} vs {stick}");
        assert!((f.fundamental_hz - 2.0).abs() < 0.02, "{f:?}");
        assert_eq!(f.cycles, 15);
        // The torque is a single-valued function of speed: no loop.
        assert!(f.loop_area < 1.0, "{f:?}");
        // Torque 1 + 0.002 v: in slip (v ≥ 5 rpm) its mean is 1 + 0.002 · mean(100 sin) over the
        // arc above 5 rpm, 1 + 0.2 · (2/π)·cos(asin 0.05)/(1 − 2 asin(0.05)/π); stuck, the torque is 1
        // at v = 0 and at most 1.01 at 5 rpm: the phase maximum is 1.01 (the filter rounds the kink).
        let a = (0.05f64).asin();
        let slip = 1.0 + 0.2 * (2.0 / std::f64::consts::PI) * a.cos() / (1.0 - 2.0 * a / std::f64::consts::PI);
        assert!((f.slip_torque_nm - slip).abs() < 0.01, "{f:?} vs {slip}");
        assert!((f.breakaway_torque_nm - 1.01).abs() < 0.01, "{f:?}");
    }

    #[test]
    fn an_elliptic_loop_has_area_pi_a_b() {
        // Ω = 50 + 40 sin(2π t), T = 1 + 0.2 cos(2π t): area π·40·0.2 = 25.13 N m·rpm.
        let w = 2.0 * std::f64::consts::PI;
        let v: Vec<f64> = (0..10_000).map(|i| 50.0 + 40.0 * (w * i as f64 / FS).sin()).collect();
        let t: Vec<f64> = (0..10_000).map(|i| 1.0 + 0.2 * (w * i as f64 / FS).cos()).collect();
        let f = window_features(&v, &t, 2000..8000, &opts()).unwrap();
        let exact = std::f64::consts::PI * 40.0 * 0.2;
        assert!((f.loop_area - exact).abs() < 0.01 * exact, "{f:?} vs {exact}");
        assert!((f.fundamental_hz - 1.0).abs() < 0.02 && f.stick_fraction == 0.0, "{f:?}");
    }

    #[test]
    fn a_held_bit_wound_up_sees_its_torque_rise_through_the_stick() {
        // The sawtooth's torque 1 + 0.002 v is flat in stick; add a ramp through each stick
        // (a holding torque wound up at 2 N m/s): it rises from entry to exit, its peak at the exit.
        // The stick spans about −11..161 samples of each 500-sample period: a triangle wave rising
        // at 2 N m/s from sample −20 to 170 and falling back over the rest of the period.
        let (v, mut t) = sawtooth();
        for (i, y) in t.iter_mut().enumerate() {
            let k = (i + 20) % 500;
            *y += if k < 190 { 2.0 * k as f64 } else { 0.38e3 * (500 - k) as f64 / 310.0 } / FS;
        }
        let s = stick_torque(&v, &t, 2000..10_000, &opts()).unwrap();
        assert_eq!(s.phases, 15, "{s:?}");
        assert_eq!(s.falling, 0, "{s:?}");
        assert!(s.exit_nm > s.entry_nm + 0.1 && s.peak_position > 0.8, "{s:?}");
        // Reversed in time, the torque falls through every stick: the record's picture.
        let (vr, tr): (Vec<f64>, Vec<f64>) = (v.iter().rev().cloned().collect(), t.iter().rev().cloned().collect());
        let r = stick_torque(&vr, &tr, 2000..10_000, &opts()).unwrap();
        assert_eq!(r.falling, r.phases, "{r:?}");
        assert!(r.entry_nm > r.exit_nm + 0.1 && r.peak_position < 0.2, "{r:?}");
    }

    #[test]
    fn features_and_stick_torque_at_once_are_the_two_calls_bit_for_bit() {
        let (v, mut t) = sawtooth();
        for (i, y) in t.iter_mut().enumerate() {
            *y += 0.3 * (i as f64 / 97.0).sin();
        }
        let (f, s) = window_features_and_stick(&v, &t, 2000..10_000, &opts()).unwrap();
        let (f1, s1) = (
            window_features(&v, &t, 2000..10_000, &opts()).unwrap(),
            stick_torque(&v, &t, 2000..10_000, &opts()).unwrap(),
        );
        // Debug prints every float in full (shortest round trip): equal strings, equal bits, NaN included.
        assert_eq!(format!("{f:?} {s:?}"), format!("{f1:?} {s1:?}"));
        assert!(s.phases > 0 && f.stick_phases > 0, "{s:?}");
    }

    #[test]
    fn refuses_mismatched_lengths() {
        let e = window_features(&[0.0; 100], &[0.0; 99], 0..50, &opts()).unwrap_err();
        assert!(e.to_string().contains("equal lengths"), "{e}");
    }
}
