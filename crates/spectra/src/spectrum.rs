//! One-sided amplitude spectrum, Welch PSD / cross-spectrum, the H1 FRF with
//! magnitude-squared coherence, and a zero-phase FFT low-pass.
//!
//! Scaling conventions (checked by the Parseval and tone tests):
//! - amplitude spectrum: a sinusoid A sin(2π f t) on a bin centre reads A at
//!   that bin, whatever the window (divide |X_k| by Σw, double off DC/Nyquist);
//! - PSD: units²/Hz, one-sided, Σ_k PSD_k · Δf = mean square of the detrended
//!   signal (divide |X_k|² by fs Σw², double off DC/Nyquist), as scipy's
//!   `welch(..., scaling="density")`.

use crate::error::{SpectraError, check_finite, check_rate};
use crate::window::{Detrend, Window, detrend, gains};
use realfft::num_complex::Complex;
use realfft::{ComplexToReal, RealFftPlanner, RealToComplex};
use serde::{Deserialize, Serialize};
use std::cell::RefCell;
use std::sync::Arc;

thread_local! {
    /// Each thread's planner: it keeps every plan it made (twiddle factors and
    /// the chosen algorithm), so the many FFTs of one length — a low-pass per
    /// free run in LAVI's fits, a scan per fold in the diagnosis — plan once
    /// per thread instead of once per call (planning was ≈ 12 % of the LAVI
    /// stage). A cached plan is the same object a fresh planner would build,
    /// so results are unchanged.
    static PLANNER: RefCell<RealFftPlanner<f64>> = RefCell::new(RealFftPlanner::new());
}

/// The forward real FFT of length `n` from this thread's plan cache.
pub fn forward_plan(n: usize) -> Arc<dyn RealToComplex<f64>> {
    PLANNER.with(|p| p.borrow_mut().plan_fft_forward(n))
}

/// The inverse real FFT of length `n` from this thread's plan cache.
pub fn inverse_plan(n: usize) -> Arc<dyn ComplexToReal<f64>> {
    PLANNER.with(|p| p.borrow_mut().plan_fft_inverse(n))
}

/// A one-sided amplitude spectrum.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Spectrum {
    pub freq_hz: Vec<f64>,
    /// Peak amplitude in the signal's unit.
    pub amplitude: Vec<f64>,
    /// Bin width fs/N = 1 / record length, Hz.
    pub resolution_hz: f64,
    /// Equivalent noise bandwidth of the window, in bins.
    pub enbw_bins: f64,
    pub window: Window,
    /// Record length N in samples.
    pub n_samples: usize,
}

fn rfft(x: &[f64]) -> Vec<Complex<f64>> {
    let r2c = forward_plan(x.len());
    let mut input = x.to_vec();
    let mut out = r2c.make_output_vec();
    r2c.process(&mut input, &mut out).expect("buffer lengths come from the plan");
    out
}

/// Factor that turns a one-sided bin into the two-sided total: 2 except at DC and Nyquist.
fn one_sided_factor(k: usize, n: usize) -> f64 {
    if k == 0 || (n.is_multiple_of(2) && k == n / 2) { 1.0 } else { 2.0 }
}

/// Amplitude spectrum of the whole record (detrended, windowed).
pub fn amplitude_spectrum(x: &[f64], fs_hz: f64, window: Window, how: Detrend) -> Result<Spectrum, SpectraError> {
    check_rate(fs_hz)?;
    check_finite("x", x)?;
    if x.len() < 4 {
        return Err(SpectraError::TooShort { name: "x", len: x.len(), min: 4, rule: "a spectrum needs 4 samples" });
    }
    let n = x.len();
    let w = window.samples(n);
    let g = gains(&w);
    let sum_w = g.coherent * n as f64;
    let xw: Vec<f64> = detrend(x, how).iter().zip(&w).map(|(a, b)| a * b).collect();
    let spec = rfft(&xw);
    let df = fs_hz / n as f64;
    Ok(Spectrum {
        freq_hz: (0..spec.len()).map(|k| k as f64 * df).collect(),
        amplitude: spec.iter().enumerate().map(|(k, c)| one_sided_factor(k, n) * c.norm() / sum_w).collect(),
        resolution_hz: df,
        enbw_bins: g.enbw_bins,
        window,
        n_samples: n,
    })
}

/// Welch averaging settings.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WelchOptions {
    pub segment_len: usize,
    /// Samples shared by consecutive segments (segment_len / 2 is usual with Hann).
    pub overlap: usize,
    pub window: Window,
    pub detrend: Detrend,
}

impl WelchOptions {
    /// Hann, 50 % overlap, constant detrend: the usual choice (scipy's defaults).
    pub fn hann(segment_len: usize) -> Self {
        WelchOptions { segment_len, overlap: segment_len / 2, window: Window::Hann, detrend: Detrend::Constant }
    }
}

/// Welch auto-spectra of x and y and their cross-spectrum (one-sided, units²/Hz).
#[derive(Debug, Clone, PartialEq)]
pub struct CrossSpectra {
    pub freq_hz: Vec<f64>,
    pub sxx: Vec<f64>,
    pub syy: Vec<f64>,
    /// S_xy = E[conj(X) Y] (scipy's `csd(x, y)` convention).
    pub sxy: Vec<Complex<f64>>,
    pub segments: usize,
    pub resolution_hz: f64,
}

fn validate_welch(name: &'static str, n: usize, o: &WelchOptions) -> Result<(), SpectraError> {
    if o.segment_len < 4 {
        return Err(SpectraError::InvalidParameter {
            name: "segment_len",
            value: o.segment_len as f64,
            rule: "a Welch segment needs at least 4 samples",
        });
    }
    if o.overlap >= o.segment_len {
        return Err(SpectraError::InvalidParameter {
            name: "overlap",
            value: o.overlap as f64,
            rule: "overlap must be smaller than segment_len",
        });
    }
    if n < o.segment_len {
        return Err(SpectraError::TooShort { name, len: n, min: o.segment_len, rule: "Welch segment_len" });
    }
    Ok(())
}

/// Segment start indices: step segment_len − overlap, trailing partial segment dropped.
fn segment_starts(n: usize, o: &WelchOptions) -> Vec<usize> {
    let step = o.segment_len - o.overlap;
    (0..=(n - o.segment_len) / step).map(|s| s * step).collect()
}

/// Welch cross-spectral estimate of two equally sampled signals.
pub fn cross_spectra(x: &[f64], y: &[f64], fs_hz: f64, o: &WelchOptions) -> Result<CrossSpectra, SpectraError> {
    check_rate(fs_hz)?;
    check_finite("x", x)?;
    check_finite("y", y)?;
    if x.len() != y.len() {
        return Err(SpectraError::LengthMismatch { a: "x", len_a: x.len(), b: "y", len_b: y.len() });
    }
    validate_welch("x", x.len(), o)?;
    let l = o.segment_len;
    let w = o.window.samples(l);
    let s2: f64 = w.iter().map(|v| v * v).sum();
    let r2c = forward_plan(l);
    let nb = l / 2 + 1;
    let (mut sxx, mut syy, mut sxy) = (vec![0.0; nb], vec![0.0; nb], vec![Complex::new(0.0, 0.0); nb]);
    let starts = segment_starts(x.len(), o);
    let mut bx = r2c.make_output_vec();
    let mut by = r2c.make_output_vec();
    for &s in &starts {
        let mut sx: Vec<f64> = detrend(&x[s..s + l], o.detrend).iter().zip(&w).map(|(a, b)| a * b).collect();
        let mut sy: Vec<f64> = detrend(&y[s..s + l], o.detrend).iter().zip(&w).map(|(a, b)| a * b).collect();
        r2c.process(&mut sx, &mut bx).expect("plan lengths");
        r2c.process(&mut sy, &mut by).expect("plan lengths");
        for k in 0..nb {
            sxx[k] += bx[k].norm_sqr();
            syy[k] += by[k].norm_sqr();
            sxy[k] += bx[k].conj() * by[k];
        }
    }
    let m = starts.len() as f64;
    for k in 0..nb {
        let scale = one_sided_factor(k, l) / (fs_hz * s2 * m);
        sxx[k] *= scale;
        syy[k] *= scale;
        sxy[k] *= scale;
    }
    let df = fs_hz / l as f64;
    Ok(CrossSpectra {
        freq_hz: (0..nb).map(|k| k as f64 * df).collect(),
        sxx,
        syy,
        sxy,
        segments: starts.len(),
        resolution_hz: df,
    })
}

/// A power spectral density, units²/Hz, one-sided.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Psd {
    pub freq_hz: Vec<f64>,
    pub psd: Vec<f64>,
    pub segments: usize,
    pub resolution_hz: f64,
}

/// Welch PSD of one signal.
pub fn welch_psd(x: &[f64], fs_hz: f64, o: &WelchOptions) -> Result<Psd, SpectraError> {
    let c = cross_spectra(x, x, fs_hz, o)?;
    Ok(Psd { freq_hz: c.freq_hz, psd: c.sxx, segments: c.segments, resolution_hz: c.resolution_hz })
}

/// H1 frequency response y/x with its magnitude-squared coherence.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Frf {
    pub freq_hz: Vec<f64>,
    /// |H1| = |S_xy| / S_xx, in (unit of y) / (unit of x).
    pub magnitude: Vec<f64>,
    pub phase_rad: Vec<f64>,
    /// γ² = |S_xy|² / (S_xx S_yy) ∈ [0, 1]; 1 for a noise-free linear relation.
    pub coherence: Vec<f64>,
    /// The auto-spectra, for plotting beside |H1|.
    pub sxx: Vec<f64>,
    pub syy: Vec<f64>,
    pub segments: usize,
    pub resolution_hz: f64,
}

/// H1 = S_xy / S_xx (the estimator unbiased by noise on the output y) and coherence.
/// A bin where S_xx is exactly zero gets magnitude 0 and coherence 0.
pub fn frf_h1(x: &[f64], y: &[f64], fs_hz: f64, o: &WelchOptions) -> Result<Frf, SpectraError> {
    let c = cross_spectra(x, y, fs_hz, o)?;
    let nb = c.freq_hz.len();
    let (mut mag, mut ph, mut coh) = (vec![0.0; nb], vec![0.0; nb], vec![0.0; nb]);
    for k in 0..nb {
        if c.sxx[k] > 0.0 {
            let h = c.sxy[k] / c.sxx[k];
            mag[k] = h.norm();
            ph[k] = h.arg();
            if c.syy[k] > 0.0 {
                coh[k] = (c.sxy[k].norm_sqr() / (c.sxx[k] * c.syy[k])).min(1.0);
            }
        }
    }
    Ok(Frf {
        freq_hz: c.freq_hz,
        magnitude: mag,
        phase_rad: ph,
        coherence: coh,
        sxx: c.sxx,
        syy: c.syy,
        segments: c.segments,
        resolution_hz: c.resolution_hz,
    })
}

/// Zero-phase low-pass by FFT: gain 1 below `cutoff_hz`, a raised-cosine roll-off
/// to 0 over `transition_hz` above it (a hard brick wall would ring). The line
/// through the first and last samples is removed before and restored after, so
/// the record's ends meet when the FFT wraps them (no jump to ring at the ends).
pub fn lowpass_fft(x: &[f64], fs_hz: f64, cutoff_hz: f64, transition_hz: f64) -> Result<Vec<f64>, SpectraError> {
    check_rate(fs_hz)?;
    check_finite("x", x)?;
    if !(cutoff_hz > 0.0 && transition_hz >= 0.0 && cutoff_hz.is_finite() && transition_hz.is_finite()) {
        return Err(SpectraError::InvalidParameter {
            name: "cutoff_hz",
            value: cutoff_hz,
            rule: "cut-off must be > 0 and the transition width >= 0",
        });
    }
    let n = x.len();
    if n < 4 {
        return Err(SpectraError::TooShort { name: "x", len: n, min: 4, rule: "low-pass needs 4 samples" });
    }
    let slope = (x[n - 1] - x[0]) / (n - 1) as f64;
    let trend: Vec<f64> = (0..n).map(|i| x[0] + slope * i as f64).collect();
    let resid: Vec<f64> = x.iter().zip(&trend).map(|(a, b)| a - b).collect();
    let (fwd, inv) = (forward_plan(n), inverse_plan(n));
    let mut buf = resid.clone();
    let mut spec = fwd.make_output_vec();
    fwd.process(&mut buf, &mut spec).expect("plan lengths");
    let df = fs_hz / n as f64;
    for (k, c) in spec.iter_mut().enumerate() {
        let f = k as f64 * df;
        let g = if f <= cutoff_hz {
            1.0
        } else if f >= cutoff_hz + transition_hz {
            0.0
        } else {
            0.5 * (1.0 + (std::f64::consts::PI * (f - cutoff_hz) / transition_hz).cos())
        };
        *c *= g / n as f64;
    }
    // c2r requires real DC and Nyquist bins; they are real already up to rounding.
    spec[0].im = 0.0;
    if n.is_multiple_of(2) {
        let last = spec.len() - 1;
        spec[last].im = 0.0;
    }
    let mut out = inv.make_output_vec();
    inv.process(&mut spec, &mut out).expect("plan lengths");
    Ok(out.iter().zip(&trend).map(|(a, b)| a + b).collect())
}
