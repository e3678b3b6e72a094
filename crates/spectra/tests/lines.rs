//! Line analysis on signals with known content: a harmonic series, two
//! incommensurate tones through a nonlinearity, noise, and Table 4.8's peaks.

use rig_spectra::*;
use std::f64::consts::PI;

const FS: f64 = 500.0;

/// Spectrum → peaks → line analysis, the path the stages use.
fn check(x: &[f64], min_freq_hz: f64) -> LineAnalysis {
    let s = amplitude_spectrum(x, FS, Window::Hann, Detrend::Constant).unwrap();
    let peaks = spectral_peaks(&s, &PeakOptions { min_freq_hz, max_peaks: 16, ..PeakOptions::default() });
    let lines: Vec<Line> = peaks.iter().map(Line::from).collect();
    analyse_lines(&lines, s.resolution_hz, &LineOptions::default())
}

fn signal(seconds: f64, mut f: impl FnMut(f64) -> f64) -> Vec<f64> {
    (0..(seconds * FS) as usize).map(|i| f(i as f64 / FS)).collect()
}

#[test]
fn a_harmonic_series_is_all_harmonic() {
    // Sawtooth-like series at a non-bin frequency, 40 s record (Δf = 0.025 Hz).
    let f0 = 0.4437;
    let x = signal(40.0, |t| (1..=6).map(|k| (2.0 * PI * k as f64 * f0 * t + k as f64).sin() / k as f64).sum());
    let a = check(&x, 0.1);
    assert_eq!(a.rows.len(), 6, "{a:#?}");
    assert_eq!(a.count(LineClass::Harmonic), 6, "{a:#?}");
    let rel: Vec<&str> = a.rows.iter().map(|r| r.relation.as_str()).collect();
    assert_eq!(rel, ["1×f0", "2×f0", "3×f0", "4×f0", "5×f0", "6×f0"]);
    assert!((a.f0_hz.unwrap() - f0).abs() < 0.02 * 0.025, "f0 {:?}", a.f0_hz);
    assert!(a.f2_hz.is_none() && a.ratio.is_none());
}

#[test]
fn incommensurate_tones_through_a_nonlinearity_give_a_base_pair_and_combinations() {
    // f2/f1 = golden ratio: nearest p/q with q ≤ 3 is 5/3, 0.049 Hz away (> 1.5 bins = 0.0375 Hz).
    let (f1, f2) = (1.0, 1.618_034);
    let x = signal(40.0, |t| {
        let u = (2.0 * PI * f1 * t).sin() + 0.8 * (2.0 * PI * f2 * t).sin();
        u + 0.4 * u * u + 0.2 * u * u * u
    });
    let a = check(&x, 0.1);
    assert!((a.f0_hz.unwrap() - f1).abs() < 1e-3 && (a.f2_hz.unwrap() - f2).abs() < 1e-3, "{a:#?}");
    assert!(a.ratio.unwrap().incommensurate);
    assert_eq!(a.count(LineClass::Base), 1);
    assert_eq!(a.count(LineClass::Unrelated), 0, "{a:#?}");
    assert_eq!(a.count(LineClass::Commensurate), 0, "{a:#?}");
    let find = |rel: &str| a.rows.iter().find(|r| r.relation == rel).map(|r| r.class);
    // Quadratic products f2 − f1, f1 + f2 and cubic 2f1 − f2 are all present.
    assert_eq!(find("f2−f0"), Some(LineClass::Combination), "{a:#?}");
    assert_eq!(find("f0+f2"), Some(LineClass::Combination));
    assert_eq!(find("2×f0−f2"), Some(LineClass::Combination));
    assert_eq!(find("2×f0"), Some(LineClass::Harmonic));
    assert!(a.rows.iter().all(|r| r.error_hz.abs() <= r.tolerance_hz));
}

#[test]
fn locked_tones_are_commensurate_not_quasi_periodic() {
    // A weaker line at 3/2·f0: locked to f0 (period-2 motion), not a second base.
    let x = signal(40.0, |t| (2.0 * PI * 0.8 * t).sin() + 0.3 * (2.0 * PI * 1.2 * t).sin());
    let a = check(&x, 0.1);
    let r = a.ratio.unwrap();
    assert!(!r.incommensurate && (r.p, r.q) == (3, 2), "{r:?}");
    assert_eq!(a.count(LineClass::Commensurate), 1);
    assert!(a.f2_hz.is_none());
    // With the subharmonic f0/2 present, the common divisor becomes the fundamental.
    let x = signal(40.0, |t| (2.0 * PI * 0.8 * t).sin() + 0.3 * (2.0 * PI * 0.4 * t).sin());
    let a = check(&x, 0.1);
    assert!((a.f0_hz.unwrap() - 0.4).abs() < 1e-3 && a.count(LineClass::Harmonic) == 2, "{a:#?}");
}

#[test]
fn noise_gives_nothing() {
    let mut s: u64 = 12345;
    let x = signal(40.0, |_| {
        s = s.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        (s >> 11) as f64 / (1u64 << 53) as f64 - 0.5
    });
    let a = check(&x, 0.1);
    assert!(a.rows.is_empty() && a.f0_hz.is_none(), "{a:#?}");
}

/// Table 4.8 (0.352, 0.718, 1.069 Hz; amplitudes unpublished, taken equal).
fn table_4_8(record_s: f64) -> LineAnalysis {
    let lines: Vec<Line> =
        [0.352, 0.718, 1.069].iter().map(|&f| Line { freq_hz: f, amplitude: 1.0, sigma_hz: 0.0 }).collect();
    analyse_lines(&lines, 1.0 / record_s, &LineOptions::default())
}

#[test]
fn table_4_8_is_harmonic_for_records_up_to_about_5_minutes() {
    // Independent check by hand: least squares f0 = Σk f_k / Σk² = 4.995 / 14 = 0.356786 Hz;
    // residuals −0.00479, +0.00443, −0.00136 Hz; all within 1.5/T iff T ≤ 1.5/0.00479 = 313 s.
    for t in [20.0, 60.0, 100.0, 300.0] {
        let a = table_4_8(t);
        assert_eq!(a.count(LineClass::Harmonic), 3, "T = {t}: {a:#?}");
        assert!((a.f0_hz.unwrap() - 0.356_786).abs() < 1e-6);
    }
    for t in [330.0, 600.0] {
        let a = table_4_8(t);
        assert!(a.count(LineClass::Harmonic) < 3, "T = {t}: {a:#?}");
    }
}
