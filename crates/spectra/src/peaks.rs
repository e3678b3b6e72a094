//! Peak detection with prominence (as `scipy.signal.find_peaks` defines it) and
//! sub-bin peak frequency by Gaussian interpolation (a parabola through the
//! log magnitudes of the three bins around a maximum).

use crate::spectrum::Spectrum;
use serde::{Deserialize, Serialize};

/// A local maximum of a sampled curve.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct RawPeak {
    pub index: usize,
    pub height: f64,
    /// scipy's prominence: height above the higher of the two lowest points
    /// reached before a higher sample (or the end) on each side.
    pub prominence: f64,
}

/// Local maxima (a flat top counts once, at its middle, as scipy does) with
/// their prominence, in index order. The end points are never peaks.
pub fn find_peaks(y: &[f64]) -> Vec<RawPeak> {
    let n = y.len();
    let mut out = Vec::new();
    if n < 3 {
        return out;
    }
    let mut i = 1;
    while i < n - 1 {
        if y[i - 1] < y[i] {
            let mut ahead = i + 1;
            while ahead < n - 1 && y[ahead] == y[i] {
                ahead += 1;
            }
            if y[ahead] < y[i] {
                let index = (i + ahead - 1) / 2;
                out.push(RawPeak { index, height: y[index], prominence: prominence(y, index) });
                i = ahead;
                continue;
            }
        }
        i += 1;
    }
    out
}

/// scipy's `_peak_prominences` without a window length.
fn prominence(y: &[f64], peak: usize) -> f64 {
    let h = y[peak];
    let mut left_min = h;
    let mut i = peak as isize;
    while i >= 0 && y[i as usize] <= h {
        left_min = left_min.min(y[i as usize]);
        i -= 1;
    }
    let mut right_min = h;
    let mut j = peak;
    while j < y.len() && y[j] <= h {
        right_min = right_min.min(y[j]);
        j += 1;
    }
    h - left_min.max(right_min)
}

/// Which maxima of a spectrum count as spectral lines.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct PeakOptions {
    pub min_freq_hz: f64,
    pub max_freq_hz: f64,
    /// Prominence at least this fraction of the largest amplitude in the band.
    pub min_prominence_rel: f64,
    /// Prominence at least this many times the median amplitude in the band
    /// (a robust noise-floor estimate: for white noise the largest of ~10³
    /// Rayleigh-distributed bins is ≈ 3.5 medians, so 6 rejects noise).
    pub min_prominence_over_median: f64,
    /// Keep at most this many (the most prominent), reported in frequency order.
    pub max_peaks: usize,
}

impl Default for PeakOptions {
    fn default() -> Self {
        PeakOptions {
            min_freq_hz: 0.0,
            max_freq_hz: f64::INFINITY,
            min_prominence_rel: 0.05,
            min_prominence_over_median: 6.0,
            max_peaks: 12,
        }
    }
}

/// One spectral line.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Peak {
    /// Interpolated frequency, Hz.
    pub freq_hz: f64,
    /// Amplitude (signal unit): the bin's amplitude corrected for the window's
    /// scalloping loss at the interpolated offset.
    pub amplitude: f64,
    pub prominence: f64,
    /// The spectrum bin of the maximum.
    pub bin: usize,
    /// Frequency standard uncertainty, Hz: Δf / (π R) with R = amplitude / noise
    /// floor (the band's median amplitude). This is the Cramér–Rao bound for a
    /// tone in white noise written with the windowed spectrum's own numbers
    /// (σ_f ≥ √(3 / (π² η N)) bins, η N = 3 R² for a Hann window), so it is a
    /// lower bound: jitter of a real oscillation only widens it.
    pub sigma_hz: f64,
}

/// Gaussian interpolation: the vertex of the parabola through (−1, ln a),
/// (0, ln b), (1, ln c). Exact for a Gaussian-shaped main lobe; with a Hann
/// window the bias is a few hundredths of a bin (see tests). Returns (δ bins, amplitude).
pub fn interpolate_gaussian(a: f64, b: f64, c: f64) -> (f64, f64) {
    let tiny = f64::MIN_POSITIVE;
    let (la, lb, lc) = (a.max(tiny).ln(), b.max(tiny).ln(), c.max(tiny).ln());
    let den = la - 2.0 * lb + lc;
    if den >= 0.0 || !den.is_finite() {
        return (0.0, b);
    }
    let delta = (0.5 * (la - lc) / den).clamp(-0.5, 0.5);
    (delta, (lb - 0.25 * (la - lc) * delta).exp())
}

/// |W(δ)| / W(0): the window's response to a tone δ bins off a bin centre
/// (the DTFT of the actual window, so exact for every window and length).
/// Dividing a bin's amplitude by it removes the scalloping loss.
fn window_response(w: &[f64], delta: f64) -> f64 {
    let n = w.len() as f64;
    let (mut re, mut im) = (0.0, 0.0);
    for (i, v) in w.iter().enumerate() {
        let ph = -2.0 * std::f64::consts::PI * delta * i as f64 / n;
        re += v * ph.cos();
        im += v * ph.sin();
    }
    (re.hypot(im) / w.iter().sum::<f64>()).max(1e-12)
}

/// Lines of an amplitude spectrum: local maxima in the band passing both
/// prominence thresholds, at most `max_peaks` (most prominent), in frequency order.
pub fn spectral_peaks(s: &Spectrum, o: &PeakOptions) -> Vec<Peak> {
    let band: Vec<usize> =
        (0..s.freq_hz.len()).filter(|&k| s.freq_hz[k] >= o.min_freq_hz && s.freq_hz[k] <= o.max_freq_hz).collect();
    if band.len() < 3 {
        return Vec::new();
    }
    let (lo, hi) = (band[0], band[band.len() - 1]);
    let y = &s.amplitude[lo..=hi];
    let max = y.iter().cloned().fold(0.0, f64::max);
    let mut sorted = y.to_vec();
    sorted.sort_by(f64::total_cmp);
    let median = sorted[sorted.len() / 2];
    let w = s.window.samples(s.n_samples);
    let threshold = (o.min_prominence_rel * max).max(o.min_prominence_over_median * median);
    let mut peaks: Vec<Peak> = find_peaks(y)
        .into_iter()
        .filter(|p| p.prominence >= threshold && p.prominence > 0.0)
        .map(|p| {
            let k = lo + p.index;
            let (delta, _) = interpolate_gaussian(s.amplitude[k - 1], s.amplitude[k], s.amplitude[k + 1]);
            let amplitude = s.amplitude[k] / window_response(&w, delta);
            let sigma_hz = s.resolution_hz / (std::f64::consts::PI * (amplitude / median.max(f64::MIN_POSITIVE)));
            Peak {
                freq_hz: (k as f64 + delta) * s.resolution_hz,
                amplitude,
                prominence: p.prominence,
                bin: k,
                sigma_hz,
            }
        })
        .collect();
    peaks.sort_by(|a, b| b.prominence.total_cmp(&a.prominence).then(a.bin.cmp(&b.bin)));
    peaks.truncate(o.max_peaks);
    peaks.sort_by_key(|p| p.bin);
    peaks
}
