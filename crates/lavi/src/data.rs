//! The recording made ready for the study: read (rig_ingest), top-speed
//! glitches repaired, every channel low-passed once over the whole record, and
//! the windows (calibration and held-out) as sample ranges.

use crate::{LaviError, StudyParams};
use rig_ingest::lavi::{LaviRecording, read_lavi};
use rig_spectra::lowpass_fft;
use rig_spectra::stickslip::{GlitchOptions, GlitchReport, repair_glitches};
use serde::Serialize;
use std::ops::Range;
use std::path::Path;

/// rpm → rad/s (2π/60).
pub use rig_types::units::RPM_TO_RAD_S;

/// The recording after glitch repair and the 10 Hz low-pass (every channel).
#[derive(Debug, Clone)]
pub struct Prepared {
    pub fs_hz: f64,
    pub time_s: Vec<f64>,
    /// Top speed, glitches bridged, not filtered (the glitch table compares it with the raw one).
    pub top_repaired_rpm: Vec<f64>,
    pub top_rpm: Vec<f64>,
    pub bit_rpm: Vec<f64>,
    pub torque_nm: Vec<f64>,
    pub wob_n: Vec<f64>,
    pub glitches: GlitchReport,
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

/// Reads run 175 (or any LAVI CSV), repairs the top-speed glitches and
/// low-passes every channel at `cutoff_hz` (zero-phase FFT filter, as the
/// authors compare below 10 Hz: Lobo et al. 2020).
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
    let glitch = GlitchOptions {
        median_window: p.glitch_median_window,
        threshold: p.glitch_threshold_rpm,
        floor: p.glitch_floor_rpm,
        dilate: p.glitch_dilate,
    };
    let (top_fixed, glitches) = repair_glitches(&rec.top_speed_rpm, &glitch)?;
    let lp = |x: &[f64]| lowpass_fft(x, fs_hz, p.cutoff_hz, p.transition_hz);
    let prepared = Prepared {
        fs_hz,
        time_s: rec.time_s.clone(),
        top_rpm: lp(&top_fixed)?,
        top_repaired_rpm: top_fixed,
        bit_rpm: lp(&rec.bit_speed_rpm)?,
        torque_nm: lp(&rec.bit_torque_nm)?,
        wob_n: lp(&rec.wob_n)?,
        glitches,
    };
    Ok((rec, prepared))
}

/// The calibration window first, then the held-out windows in time order.
/// Each window must fit in the record with its warm-up, and no held-out window
/// may overlap the calibration window.
pub fn windows(d: &Prepared, p: &StudyParams) -> Result<Vec<WindowSpec>, LaviError> {
    let mut out = Vec::new();
    let t_end = d.time_s[d.len() - 1];
    let mut starts: Vec<(f64, f64, Split)> = vec![(p.window_start_s, p.window_end_s, Split::Train)];
    let mut held = p.heldout_starts_s.clone();
    held.sort_by(f64::total_cmp);
    starts.extend(held.iter().map(|s| (*s, s + p.heldout_length_s, Split::Heldout)));
    for (a, b, split) in starts {
        let bad = |rule: String| LaviError::Params { key: "heldout_starts_s", rule };
        if !(b > a && a - p.warmup_s >= d.time_s[0] - 1e-9 && b <= t_end + 1e-9) {
            return Err(bad(format!(
                "window {a}-{b} s with {} s of warm-up must lie inside the record ({}-{t_end} s)",
                p.warmup_s, d.time_s[0]
            )));
        }
        if split == Split::Heldout && a < p.window_end_s && b > p.window_start_s {
            return Err(bad(format!(
                "held-out window {a}-{b} s overlaps the calibration window {}-{} s",
                p.window_start_s, p.window_end_s
            )));
        }
        let (i0, iw, i1) = (d.index_at(a - p.warmup_s), d.index_at(a), d.index_at(b));
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
