//! The one error type of rig-spectra: every variant names the argument and the rule broken.

/// Why a spectral computation was refused. Inputs come from the caller, so each
/// message says which argument to fix and what it must satisfy.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum SpectraError {
    /// A signal shorter than the transform needs (e.g. a Welch segment longer than the record).
    #[error("signal `{name}` has {len} samples; at least {min} are needed ({rule})")]
    TooShort { name: &'static str, len: usize, min: usize, rule: &'static str },
    /// Two signals that must be sampled together have different lengths.
    #[error("signals `{a}` ({len_a} samples) and `{b}` ({len_b} samples) must have the same length")]
    LengthMismatch { a: &'static str, len_a: usize, b: &'static str, len_b: usize },
    /// A parameter outside its domain (sample rate, overlap, tolerance, ...).
    #[error("invalid parameter {name} = {value}: {rule}")]
    InvalidParameter { name: &'static str, value: f64, rule: &'static str },
    /// NaN or infinity in an input signal (the index of the first one).
    #[error("signal `{name}` has a non-finite value at index {index}")]
    NonFinite { name: &'static str, index: usize },
}

pub(crate) fn check_finite(name: &'static str, x: &[f64]) -> Result<(), SpectraError> {
    match x.iter().position(|v| !v.is_finite()) {
        Some(index) => Err(SpectraError::NonFinite { name, index }),
        None => Ok(()),
    }
}

pub(crate) fn check_rate(fs_hz: f64) -> Result<(), SpectraError> {
    if fs_hz.is_finite() && fs_hz > 0.0 {
        Ok(())
    } else {
        Err(SpectraError::InvalidParameter { name: "fs_hz", value: fs_hz, rule: "sample rate must be finite and > 0" })
    }
}
