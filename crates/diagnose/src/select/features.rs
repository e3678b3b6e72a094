//! A run's steady-state features, measured on a record or a simulation the
//! same way (stick-slip regime, stuck fraction, rotor speed range, motor
//! speed dip, the fundamental by line analysis), for the adequacy table's
//! measured-against-predicted comparison (crate docs).

use crate::prepare::RunSignals;
use crate::result::Features;
use rig_spectra::{LineAnalysisOptions, line_analysis};
use rig_sweep::ClassifyOptions;

/// Measured features of one run's steady state.
pub fn measured_features(s: &RunSignals, slip_speed_rad_s: f64, classify: &ClassifyOptions) -> Features {
    steady_features(
        &s.time_s[s.steady_from..],
        &s.rotor_speed_rad_s[s.steady_from..],
        &s.motor_speed_rad_s[s.steady_from..],
        s.setpoint_rad_s,
        slip_speed_rad_s,
        classify,
    )
}

/// The line analysis of a steady window's rotor speed (`rig_spectra::line_analysis`):
/// 0.05 Hz (above the drift of a window of ≥ 20 s, below the slowest stick-slip
/// of the rig, ≈ 0.3 Hz) to 5 Hz (the stick-slip fundamentals and their first
/// harmonics; the differentiator smooths above); 0.1 bin, as the `spectra`
/// stage for the same signals: the tolerance is then the peak's own 3σ_f.
const STEADY_LINES: LineAnalysisOptions =
    LineAnalysisOptions { min_freq_hz: 0.05, max_freq_hz: 5.0, tolerance_bins: 0.1 };

/// Features of a steady-state record (shared by measured and simulated runs).
pub fn steady_features(
    t: &[f64],
    w1: &[f64],
    w2: &[f64],
    setpoint_rad_s: f64,
    slip_speed_rad_s: f64,
    classify: &ClassifyOptions,
) -> Features {
    if t.len() < 16 {
        return Features::default();
    }
    let fs_hz = (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]);
    let stick_slip = rig_sweep::classify(w1, fs_hz, classify).regime.stick_slip();
    let stuck = w1.iter().filter(|w| w.abs() < slip_speed_rad_s).count() as f64 / w1.len() as f64;
    let min = w1.iter().copied().fold(f64::INFINITY, f64::min);
    let max = w1.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let dip = w2.iter().map(|w| setpoint_rad_s - w).fold(0.0_f64, f64::max);
    Features {
        stuck_fraction: stuck,
        stick_slip,
        rotor_min_rad_s: min,
        rotor_max_rad_s: max,
        fundamental_hz: fundamental_of(w1, fs_hz, slip_speed_rad_s),
        motor_dip_rad_s: dip,
    }
}

/// [`steady_features`]' fundamental alone, Hz, the same value to the bit:
/// for a reader that needs no other feature (the structure candidates'
/// rotor-only free runs, `channels::free_run`).
pub fn steady_fundamental_hz(t: &[f64], w1: &[f64], slip_speed_rad_s: f64) -> f64 {
    if t.len() < 16 {
        return Features::default().fundamental_hz;
    }
    fundamental_of(w1, (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]), slip_speed_rad_s)
}

/// Fundamental: f0 of the line analysis of Ω1 (sampled at `fs_hz`) when Ω1
/// swings more than the slip speed (its standard deviation), else 0.
fn fundamental_of(w1: &[f64], fs_hz: f64, slip_speed_rad_s: f64) -> f64 {
    let n = w1.len() as f64;
    let mean = w1.iter().sum::<f64>() / n;
    let var = w1.iter().map(|w| (w - mean).powi(2)).sum::<f64>() / n;
    if var.sqrt() > slip_speed_rad_s {
        line_analysis(w1, fs_hz, &STEADY_LINES).ok().and_then(|sl| sl.lines.f0_hz).unwrap_or(0.0)
    } else {
        0.0
    }
}
