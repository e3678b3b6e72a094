//! The classifier on signals whose regime is known by construction: steady
//! sliding with quantisation-sized ripple, a stick-slip cycle, a period-2
//! cycle, two incommensurate tones, and the Lorenz system (chaotic).

use rig_sweep::{ClassifyOptions, Regime, classify};
use std::f64::consts::PI;

const FS_HZ: f64 = 100.0;

fn signal(window_s: f64, f: impl Fn(f64) -> f64) -> Vec<f64> {
    (0..(window_s * FS_HZ) as usize).map(|k| f(k as f64 / FS_HZ)).collect()
}

fn check(x: &[f64], expected: Regime) {
    let c = classify(x, FS_HZ, &ClassifyOptions::default());
    assert_eq!(c.regime, expected, "{c:?}");
}

#[test]
fn steady_sliding_with_ripple_is_equilibrium() {
    // 5 rad/s with 0.1 rad/s ripple at 3 Hz: peak-to-peak 0.2 < 0.5 rad/s floor.
    check(&signal(20.0, |t| 5.0 + 0.1 * (2.0 * PI * 3.0 * t).sin()), Regime::Equilibrium);
}

#[test]
fn ringing_down_transient_is_equilibrium() {
    // A step's ringing at 0.45 Hz and ξ = 0.03 around 5 rad/s, starting at 2 rad/s amplitude.
    let w = 2.0 * PI * 0.45;
    let x = signal(20.0, |t| 5.0 + 2.0 * (-0.03 * w * t).exp() * (w * t).sin());
    let c = classify(&x, FS_HZ, &ClassifyOptions::default());
    assert_eq!((c.regime, c.decided_by.as_str()), (Regime::Equilibrium, "decay"));
}

/// Half-wave rectified sine: the rotor is stuck (0) half the cycle, slips in a hump.
fn stick_slip(t: f64, f_hz: f64, peak: f64) -> f64 {
    (peak * (2.0 * PI * f_hz * t).sin()).max(0.0)
}

#[test]
fn stick_slip_cycle_is_period_one_with_stick() {
    let c = classify(&signal(20.0, |t| stick_slip(t, 0.4, 6.0)), FS_HZ, &ClassifyOptions::default());
    assert_eq!(c.regime, Regime::Periodic { period: 1, stick: true });
    assert_eq!(c.decided_by, "section");
    // 0.4 Hz over 20 s: 8 crossings, 7 full cycles.
    assert_eq!(c.cycles, 7);
    // Mean of a half-wave rectified sine is peak/π: severity (max − min)/mean = π, half of it π/2.
    assert!((c.severity_full - PI).abs() < 0.02, "{}", c.severity_full);
    assert!((c.severity_half - PI / 2.0).abs() < 0.01);
}

#[test]
fn alternating_humps_are_period_two() {
    // Humps alternate between 6 and 4 rad/s: two clusters 2 rad/s apart, repeating ABAB.
    let x = signal(30.0, |t| {
        let cycle = (t * 0.5).floor() as i64;
        stick_slip(t, 0.5, if cycle % 2 == 0 { 6.0 } else { 4.0 })
    });
    check(&x, Regime::Periodic { period: 2, stick: true });
}

#[test]
fn two_incommensurate_tones_are_quasi_periodic() {
    // f2 / f0 = √2: the nearest p/q (q ≤ 3) misses by 0.04 Hz, ~0.8 bins of a 20 s window.
    let x = signal(20.0, |t| 5.0 + 2.0 * (2.0 * PI * 0.5 * t).sin() + 1.0 * (2.0 * PI * 0.5 * 2f64.sqrt() * t).sin());
    check(&x, Regime::QuasiPeriodic { stick: false });
}

#[test]
fn lorenz_is_chaotic() {
    // Lorenz (σ 10, ρ 28, β 8/3), RK4 at 1e-3 time units, x sampled every 0.01 time units
    // (one time unit per second at 100 Hz) after 20 time units; 40 s hold ~30 lobe switches.
    let (mut s, h) = ([1.0f64, 1.0, 1.0], 1e-3);
    let f = |v: [f64; 3]| [10.0 * (v[1] - v[0]), v[0] * (28.0 - v[2]) - v[1], v[0] * v[1] - 8.0 / 3.0 * v[2]];
    let step = |v: [f64; 3]| {
        let add = |a: [f64; 3], b: [f64; 3], k: f64| [a[0] + k * b[0], a[1] + k * b[1], a[2] + k * b[2]];
        let k1 = f(v);
        let k2 = f(add(v, k1, h / 2.0));
        let k3 = f(add(v, k2, h / 2.0));
        let k4 = f(add(v, k3, h));
        [0, 1, 2].map(|i| v[i] + h / 6.0 * (k1[i] + 2.0 * k2[i] + 2.0 * k3[i] + k4[i]))
    };
    for _ in 0..20_000 {
        s = step(s);
    }
    let mut x = Vec::new();
    for _ in 0..4000 {
        for _ in 0..10 {
            s = step(s);
        }
        x.push(10.0 + 0.3 * s[0]);
    }
    check(&x, Regime::Chaotic { stick: false });
}

#[test]
fn labels_and_codes() {
    assert_eq!(Regime::Periodic { period: 1, stick: true }.label(), "stick-slip P1");
    assert_eq!(Regime::Periodic { period: 3, stick: false }.label(), "oscillation P3");
    assert_eq!(Regime::QuasiPeriodic { stick: true }.label(), "quasi-periodic stick-slip");
    assert!(!Regime::Equilibrium.vibrating());
    assert!(Regime::Chaotic { stick: false }.vibrating());
}
