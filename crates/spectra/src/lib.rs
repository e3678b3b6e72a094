//! Windows, FFT, Welch PSD, peaks, FRF with coherence, harmonic/combination line analysis.
