//! Windows, FFT, Welch PSD, peaks, FRF with coherence, harmonic/combination line
//! analysis, and the stick-slip measures used on recordings (severity, friction
//! against speed, velocity-weakening fit). No IO.
//!
//! Front door: the names re-exported below. Every FFT is realfft/rustfft.

mod analysis;
mod error;
mod lines;
mod peaks;
mod spectrum;
pub mod stickslip;
mod window;

pub use analysis::{LineAnalysisOptions, SignalLines, line_analysis};
pub use error::SpectraError;
pub use lines::{Line, LineAnalysis, LineClass, LineOptions, LineRow, RatioTest, analyse_lines, ratio_test};
pub use peaks::{Peak, PeakOptions, RawPeak, find_peaks, interpolate_gaussian, spectral_peaks};
pub use spectrum::{
    CrossSpectra, Frf, Psd, Spectrum, WelchOptions, amplitude_spectrum, cross_spectra, forward_plan, frf_h1,
    inverse_plan, lowpass_fft, welch_psd,
};
pub use window::{Detrend, Window, WindowGains, detrend, gains};

/// Indices that thin a series of `n` samples to at most `max_points` by a fixed
/// stride (deterministic; the last sample is always kept). For figures.
pub fn thin_indices(n: usize, max_points: usize) -> Vec<usize> {
    if n == 0 || max_points == 0 {
        return Vec::new();
    }
    let stride = n.div_ceil(max_points.max(2) - 1).max(1);
    let mut idx: Vec<usize> = (0..n).step_by(stride).collect();
    if *idx.last().expect("n > 0") != n - 1 {
        idx.push(n - 1);
    }
    idx
}
