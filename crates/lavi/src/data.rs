//! The recording made ready for the study, as measured: read (rig_ingest),
//! every channel low-passed once over the whole record, and the windows
//! (calibration and held-out) as sample ranges.
//!
//! # Repairs that conserve what the physics conserves (issue 26.4)
//!
//! The models are driven by the top speed, so what they use of it is its
//! integral, the top-drive angle, and through it the twist
//! φ(t) = ∫ (Ω_top − Ω_bit) dt (rig_model::one_dof::integrated_twist_rad).
//! Every repair of the top speed is audited ([`RepairCheck`]) by what it
//! changes in that twist: Δ(t) = φ_repaired(t) − φ_raw(t), averaged over
//! ±1/(2 f_c) (the band the study compares, f_c the low-pass cut-off), and
//! per window the largest |Δ(t) − Δ(span start)| over the span a free run
//! integrates (warm-up and window): the twist error it would start or end with.
//! The channel's noise in the same unit: the top speed's noise σ_Ω (rms of
//! raw − low-passed, outside the dips) integrated as a random walk over the
//! span, σ_φ = σ_Ω · Δt · √N. A repair whose change exceeds σ_φ on any window
//! or over the record is refused and the record is used as measured.
//!
//! Two repairs are audited: the zero-phase low-pass (the study's own, kept:
//! it changes the twist by far less than the noise, as a filter of unit DC
//! gain must) and the straight-line bridging of the top-speed dips
//! (rig_spectra::stickslip::repair_glitches). On run 175 the dips carry angle
//! (the README of the data: the twist stays within ±0.5 rad with them, it
//! drifts by tens of radians without): the bridge is refused.

use crate::{LaviError, StudyParams};
use rig_ingest::lavi::{LaviRecording, read_lavi};
use rig_model::one_dof::integrated_twist_rad;
use rig_spectra::lowpass_fft;
use rig_spectra::stickslip::{GlitchOptions, GlitchReport, repair_glitches};
use rig_types::sensor::{half_window_samples, window_samples};
use serde::Serialize;
use std::ops::Range;
use std::path::Path;

/// rpm → rad/s (2π/60).
pub use rig_types::units::RPM_TO_RAD_S;

/// The recording as measured after the 10 Hz low-pass (every channel), with
/// the audit of every repair considered.
#[derive(Debug, Clone)]
pub struct Prepared {
    pub fs_hz: f64,
    pub time_s: Vec<f64>,
    pub top_rpm: Vec<f64>,
    pub bit_rpm: Vec<f64>,
    pub torque_nm: Vec<f64>,
    pub wob_n: Vec<f64>,
    /// Bit speed and torque as recorded (not low-passed): the window features
    /// filter them once, as they filter a simulated run (rig_lavi::features).
    pub bit_raw_rpm: Vec<f64>,
    pub torque_raw_nm: Vec<f64>,
    /// The top-speed dips found by the glitch detector (not bridged unless its audit accepts it).
    pub glitches: GlitchReport,
    /// The top speed's noise outside the dips: rms of raw − low-passed, rad/s.
    pub top_noise_rad_s: f64,
    /// Twist of the raw record ∫(Ω_top − Ω_bit) dt from its first sample: (min, max), rad.
    pub twist_excursion_rad: (f64, f64),
    /// Every repair considered, in the order applied: low-pass, then dip bridging.
    pub repairs: Vec<RepairCheck>,
}

/// What one repair of the top speed changes in the integrated twist, against the channel's noise.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct RepairCheck {
    /// `lowpass` or `bridge_dips`.
    pub repair: &'static str,
    /// Largest |Δ(t)| over the record (band-averaged), rad.
    pub record_change_rad: f64,
    /// Δ at the record's end, rad (the drift it leaves).
    pub record_end_change_rad: f64,
    /// σ_φ over the whole record, rad.
    pub record_noise_rad: f64,
    /// Per window (the order of [`windows`]): largest |Δ(t) − Δ(span start)| over the span, rad.
    pub window_change_rad: Vec<f64>,
    /// Per window: σ_φ over the span, rad.
    pub window_noise_rad: Vec<f64>,
    /// Applied (change within the noise everywhere) or refused.
    pub applied: bool,
}

impl Prepared {
    pub fn len(&self) -> usize {
        self.time_s.len()
    }

    pub fn is_empty(&self) -> bool {
        self.time_s.is_empty()
    }

    /// First sample index at or after `t_s`.
    pub fn index_at(&self, t_s: f64) -> usize {
        self.time_s.partition_point(|t| *t < t_s - 1e-9)
    }
}

/// Whether a window calibrates the models or only judges them.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
#[serde(rename_all = "lowercase")]
pub enum Split {
    Train,
    Heldout,
}

impl Split {
    pub fn as_str(self) -> &'static str {
        match self {
            Split::Train => "train",
            Split::Heldout => "heldout",
        }
    }
}

/// One analysis window with the warm-up span before it that a free run starts from.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WindowSpec {
    /// `"37-41"`: start and end in seconds.
    pub label: String,
    pub split: Split,
    pub start_s: f64,
    pub end_s: f64,
    /// Samples simulated: warm-up start .. window end.
    pub span: Range<usize>,
    /// The window inside `span`, relative to `span.start`.
    pub window: Range<usize>,
}

/// Reads run 175 (or any LAVI CSV), low-passes every channel at `cutoff_hz`
/// (zero-phase FFT filter, as the authors compare below 10 Hz: Lobo et al.
/// 2020) and audits the repairs of the top speed (module docs); a refused
/// repair is not applied.
pub fn prepare(path: &Path, p: &StudyParams) -> Result<(LaviRecording, Prepared), LaviError> {
    let rec = read_lavi(path)?;
    let n = rec.len();
    if n < 1000 {
        return Err(LaviError::Data {
            file: path.display().to_string(),
            rule: format!("a LAVI recording needs at least 1000 samples, this one has {n}"),
        });
    }
    let fs_hz = (n - 1) as f64 / (rec.time_s[n - 1] - rec.time_s[0]);
    let (bridged, glitches) = repair_glitches(&rec.top_speed_rpm, &glitch_options(&rec.time_s, p))?;
    let lp = |x: &[f64]| lowpass_fft(x, fs_hz, p.cutoff_hz, p.transition_hz);
    let top_lp = lp(&rec.top_speed_rpm)?;
    let rad = |x: &[f64]| x.iter().map(|v| v * RPM_TO_RAD_S).collect::<Vec<f64>>();
    let dip = |i: usize| bridged[i] != rec.top_speed_rpm[i];
    let clean: Vec<f64> =
        (0..n).filter(|&i| !dip(i)).map(|i| (rec.top_speed_rpm[i] - top_lp[i]) * RPM_TO_RAD_S).collect();
    let top_noise_rad_s = (clean.iter().map(|x| x * x).sum::<f64>() / clean.len().max(1) as f64).sqrt();
    let bit = rad(&rec.bit_speed_rpm);
    let twist = |top_rpm: &[f64]| integrated_twist_rad(&rec.time_s, &rad(top_rpm), &bit);
    let raw_twist = twist(&rec.top_speed_rpm);
    let twist_excursion_rad = (
        raw_twist.iter().cloned().fold(f64::INFINITY, f64::min),
        raw_twist.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
    );
    let wins = window_specs(&rec.time_s, p)?;
    let half = ((fs_hz / (2.0 * p.cutoff_hz)).round() as usize).max(1);
    let check = |repair: &'static str, top_rpm: &[f64]| -> RepairCheck {
        let delta: Vec<f64> = twist(top_rpm).iter().zip(&raw_twist).map(|(a, b)| a - b).collect();
        let delta = centred_mean(&delta, half);
        let noise = |len: usize| top_noise_rad_s / fs_hz * (len as f64).sqrt();
        let (window_change_rad, window_noise_rad): (Vec<f64>, Vec<f64>) = wins
            .iter()
            .map(|w| {
                let d0 = delta[w.span.start];
                (delta[w.span.clone()].iter().map(|d| (d - d0).abs()).fold(0.0, f64::max), noise(w.span.len()))
            })
            .unzip();
        let record_change_rad = delta.iter().map(|d| d.abs()).fold(0.0, f64::max);
        let record_noise_rad = noise(n);
        let applied = record_change_rad <= record_noise_rad
            && window_change_rad.iter().zip(&window_noise_rad).all(|(c, s)| c <= s);
        RepairCheck {
            repair,
            record_change_rad,
            record_end_change_rad: delta[n - 1],
            record_noise_rad,
            window_change_rad,
            window_noise_rad,
            applied,
        }
    };
    let lowpass = check("lowpass", &top_lp);
    let bridge = check("bridge_dips", &bridged);
    let top_rpm = if bridge.applied { lp(&bridged)? } else { top_lp };
    let prepared = Prepared {
        fs_hz,
        time_s: rec.time_s.clone(),
        top_rpm,
        bit_rpm: lp(&rec.bit_speed_rpm)?,
        torque_nm: lp(&rec.bit_torque_nm)?,
        wob_n: lp(&rec.wob_n)?,
        bit_raw_rpm: rec.bit_speed_rpm.clone(),
        torque_raw_nm: rec.bit_torque_nm.clone(),
        glitches,
        top_noise_rad_s,
        twist_excursion_rad,
        repairs: vec![lowpass, bridge],
    };
    Ok((rec, prepared))
}

/// The top-speed dip detector of `p` on a record sampled at `time_s`: its
/// windows, declared in seconds, counted in samples from the time column
/// (`rig_types::sensor`: the median window a window, the dilation each side
/// a half window; on run 175, 1 kHz, 101 and 10 samples).
pub fn glitch_options(time_s: &[f64], p: &StudyParams) -> GlitchOptions {
    GlitchOptions {
        median_window: window_samples(time_s, p.glitch_median_window_s),
        threshold: p.glitch_threshold_rpm,
        floor: p.glitch_floor_rpm,
        dilate: half_window_samples(time_s, p.glitch_dilate_s),
    }
}

/// Centred moving mean over ±`half` samples (shortened at the ends).
fn centred_mean(x: &[f64], half: usize) -> Vec<f64> {
    let n = x.len();
    let mut prefix = vec![0.0; n + 1];
    for (i, v) in x.iter().enumerate() {
        prefix[i + 1] = prefix[i] + v;
    }
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(half), (i + half + 1).min(n));
            (prefix[b] - prefix[a]) / (b - a) as f64
        })
        .collect()
}

/// The calibration window first, then the held-out windows in time order.
/// Each window must fit in the record with its warm-up, and no held-out window
/// may overlap the calibration window.
pub fn windows(d: &Prepared, p: &StudyParams) -> Result<Vec<WindowSpec>, LaviError> {
    window_specs(&d.time_s, p)
}

fn window_specs(time_s: &[f64], p: &StudyParams) -> Result<Vec<WindowSpec>, LaviError> {
    let mut out = Vec::new();
    let t_end = time_s[time_s.len() - 1];
    let index_at = |t: f64| time_s.partition_point(|x| *x < t - 1e-9);
    let mut starts: Vec<(f64, f64, Split)> = vec![(p.window_start_s, p.window_end_s, Split::Train)];
    let mut held = p.heldout_starts_s.clone();
    held.sort_by(f64::total_cmp);
    starts.extend(held.iter().map(|s| (*s, s + p.heldout_length_s, Split::Heldout)));
    for (a, b, split) in starts {
        let bad = |rule: String| LaviError::Params { key: "heldout_starts_s", rule };
        if !(b > a && a - p.warmup_s >= time_s[0] - 1e-9 && b <= t_end + 1e-9) {
            return Err(bad(format!(
                "window {a}-{b} s with {} s of warm-up must lie inside the record ({}-{t_end} s)",
                p.warmup_s, time_s[0]
            )));
        }
        if split == Split::Heldout && a < p.window_end_s && b > p.window_start_s {
            return Err(bad(format!(
                "held-out window {a}-{b} s overlaps the calibration window {}-{} s",
                p.window_start_s, p.window_end_s
            )));
        }
        let (i0, iw, i1) = (index_at(a - p.warmup_s), index_at(a), index_at(b));
        out.push(WindowSpec {
            label: format!("{}-{}", fmt_s(a), fmt_s(b)),
            split,
            start_s: a,
            end_s: b,
            span: i0..i1,
            window: (iw - i0)..(i1 - i0),
        });
    }
    Ok(out)
}

fn fmt_s(x: f64) -> String {
    if x.fract() == 0.0 { format!("{x:.0}") } else { format!("{x}") }
}

/// Central-difference derivative (one-sided at the ends), per second.
pub fn derivative(x: &[f64], fs_hz: f64) -> Vec<f64> {
    let n = x.len();
    (0..n)
        .map(|i| {
            let (a, b) = (i.saturating_sub(1), (i + 1).min(n - 1));
            if b == a { 0.0 } else { (x[b] - x[a]) * fs_hz / (b - a) as f64 }
        })
        .collect()
}
