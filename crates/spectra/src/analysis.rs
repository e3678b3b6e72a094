//! Spectrum → peaks → lines of one sampled signal: the one pipeline every
//! crate uses to find a signal's spectral lines (the regime classifier, the
//! spectra and harmonic studies, the LAVI study), and the one definition of
//! "quasi-periodic" built on it.
//!
//! Fixed for every caller: Hann window, mean removed (`Detrend::Constant`),
//! the peak thresholds of [`PeakOptions::default`] (prominence ≥ 5 % of the
//! largest and ≥ 6 × the median amplitude in the band), the line analysis of
//! [`LineOptions::default`] but for its tolerance. What a caller's physics
//! decides — the band and the line tolerance — is a field of
//! [`LineAnalysisOptions`] with no default: each caller states its own and why.

use crate::error::SpectraError;
use crate::lines::{Line, LineAnalysis, LineClass, LineOptions, analyse_lines};
use crate::peaks::{Peak, PeakOptions, spectral_peaks};
use crate::spectrum::{Spectrum, amplitude_spectrum};
use crate::window::{Detrend, Window};
use serde::{Deserialize, Serialize};

/// What a caller of [`line_analysis`] decides.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LineAnalysisOptions {
    /// Band the peaks are taken from, Hz (below: drift; above: what the
    /// caller's sensor or low-pass no longer carries).
    pub min_freq_hz: f64,
    pub max_freq_hz: f64,
    /// Line tolerance in frequency bins ([`LineOptions::tolerance_bins`]).
    pub tolerance_bins: f64,
}

impl LineAnalysisOptions {
    pub fn peak_options(&self) -> PeakOptions {
        PeakOptions { min_freq_hz: self.min_freq_hz, max_freq_hz: self.max_freq_hz, ..PeakOptions::default() }
    }

    pub fn line_options(&self) -> LineOptions {
        LineOptions { tolerance_bins: self.tolerance_bins, ..LineOptions::default() }
    }
}

/// The spectrum of one signal, its peaks in the band and their line analysis.
#[derive(Debug, Clone, PartialEq)]
pub struct SignalLines {
    pub spectrum: Spectrum,
    pub peaks: Vec<Peak>,
    pub lines: LineAnalysis,
    /// Variance of the signal (mean removed, divided by n), signal unit².
    pub variance: f64,
}

/// Spectrum (Hann, mean removed) → peaks in the band → line analysis of `x` sampled at `fs_hz`.
pub fn line_analysis(x: &[f64], fs_hz: f64, o: &LineAnalysisOptions) -> Result<SignalLines, SpectraError> {
    let spectrum = amplitude_spectrum(x, fs_hz, Window::Hann, Detrend::Constant)?;
    let peaks = spectral_peaks(&spectrum, &o.peak_options());
    let input: Vec<Line> = peaks.iter().map(Line::from).collect();
    let lines = analyse_lines(&input, spectrum.resolution_hz, &o.line_options());
    let mean = x.iter().sum::<f64>() / x.len() as f64;
    let variance = x.iter().map(|v| (v - mean).powi(2)).sum::<f64>() / x.len() as f64;
    Ok(SignalLines { spectrum, peaks, lines, variance })
}

impl SignalLines {
    /// Power carried by the peaks, Σ A²/2 (a sine of amplitude A has variance A²/2).
    pub fn line_power(&self) -> f64 {
        self.peaks.iter().map(|p| 0.5 * p.amplitude * p.amplitude).sum()
    }

    /// A line spectrum: no unrelated line, and the lines carry at least
    /// `min_line_power_fraction` of the variance — a broadband (chaotic)
    /// spectrum with a few bumps standing out is not discrete.
    pub fn discrete(&self, min_line_power_fraction: f64) -> bool {
        self.lines.count(LineClass::Unrelated) == 0 && self.line_power() >= min_line_power_fraction * self.variance
    }

    /// Quasi-periodic (the one definition): two incommensurate base
    /// frequencies f0 and f2 (f2 ≠ p/q·f0 for every q ≤ `max_denominator`
    /// within the tolerance) in a [`discrete`](Self::discrete) spectrum. The
    /// combination tones |m f0 ± n f2| show that the two interact through
    /// the nonlinearity; they are not required.
    pub fn quasi_periodic(&self, min_line_power_fraction: f64) -> bool {
        self.lines.f0_hz.is_some() && self.lines.f2_hz.is_some() && self.discrete(min_line_power_fraction)
    }
}
