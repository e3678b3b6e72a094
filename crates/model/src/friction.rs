//! Brake friction laws μ(Ω1) (Eq. 4-10, Table 4.7 and the vocabulary laws of
//! ../shared/spec/diagnosis.md) and the normal force with its effects.

pub(crate) use rig_types::units::RAD_S_TO_RPM;
use rig_types::{Effect, FrictionLaw, HarmonicFriction, ThesisFriction};
use std::f64::consts::PI;

/// The Stribeck law, written once for the model and the diagnosis:
/// μ(Ω) = μk + (μs − μk)·exp(−(Ω/vs)²) (Eq. 4-10's velocity weakening as the
/// diagnosis vocabulary states it, ../shared/spec/diagnosis.md; exponent δ = 2).
pub fn stribeck_mu(mu_static: f64, mu_kinetic: f64, stribeck_speed_rad_s: f64, omega_rad_s: f64) -> f64 {
    mu_kinetic + (mu_static - mu_kinetic) * stribeck_decay(omega_rad_s, stribeck_speed_rad_s)
}

/// The Stribeck decay exp(−(Ω/vs)²) of [`stribeck_mu`] (its shape alone: the
/// diagnosis' linear fits use it as a regressor).
///
/// Beyond (Ω/vs)² ≈ 745.13 the exponential is below half the smallest
/// subnormal and rounds to +0; libm reaches that +0 through its underflow
/// path (a special case that sets errno), which the diagnosis' Stribeck
/// fits take for every sample slipping faster than ≈ 27 vs — 2.3 % of a
/// ladder rung's CPU in `perf` (issue 23). Past [`DECAY_ZERO_BEYOND`] the
/// decay is that +0 without the call: the same bits (test
/// `the_decay_past_its_underflow_is_libm_s_zero`).
#[inline]
pub fn stribeck_decay(omega_rad_s: f64, stribeck_speed_rad_s: f64) -> f64 {
    let x2 = (omega_rad_s / stribeck_speed_rad_s).powi(2);
    if x2 > DECAY_ZERO_BEYOND { 0.0 } else { (-x2).exp() }
}

/// (Ω/vs)² past which exp(−(Ω/vs)²) is +0 in f64 (it is from ≈ 745.14 on;
/// at 750 the exact value is 0.004 of the smallest subnormal, so any libm
/// within an ulp rounds it to +0).
const DECAY_ZERO_BEYOND: f64 = 750.0;

/// Eq. 4-10 with Table 4.7, read as a piecewise-linear lookup over rotor rpm
/// (the reading is argued in the crate docs, "Friction as published"):
/// μneg for rpm ≤ 0, linear μneg → μst on (0, static set-point], linear
/// μst → μdyn on (static, dynamic set-point], μdyn above. Signed: the
/// published table is not symmetric in the sign of Ω1.
pub fn thesis_lookup(f: &ThesisFriction, omega_rad_s: f64) -> f64 {
    let (_, mu0, mu1) = thesis_segment(f, omega_rad_s);
    mu0 + mu1 * omega_rad_s
}

/// The segment of [`thesis_lookup`] that holds `omega_rad_s` as (index 0–3,
/// μ0, μ1 per rad/s) with μ = μ0 + μ1·Ω1 on the whole segment: the lookup is
/// piecewise affine, which the exact propagator of the drive uses.
pub(crate) fn thesis_segment(f: &ThesisFriction, omega_rad_s: f64) -> (i8, f64, f64) {
    let rpm = omega_rad_s * RAD_S_TO_RPM;
    let (s, d) = (f.static_setpoint_rpm, f.dynamic_setpoint_rpm);
    if rpm <= 0.0 {
        (0, f.mu_negative, 0.0)
    } else if rpm <= s {
        // μneg + (μst − μneg)·rpm/s
        (1, f.mu_negative, (f.mu_static - f.mu_negative) * RAD_S_TO_RPM / s)
    } else if rpm <= d {
        // μst + (μdyn − μst)·(rpm − s)/(d − s)
        let slope = (f.mu_dynamic - f.mu_static) / (d - s);
        (2, f.mu_static - slope * s, slope * RAD_S_TO_RPM)
    } else {
        (3, f.mu_dynamic, 0.0)
    }
}

/// Slip coefficient at slip speed |Ω1| (vocabulary laws; symmetric in sign).
/// For the thesis law used inside the rig model, the lookup at |Ω1|.
pub fn slip_mu(law: &FrictionLaw, speed_abs_rad_s: f64) -> f64 {
    let w = speed_abs_rad_s.abs();
    match (law, slip_mu_affine(law, w)) {
        (_, Some((_, mu0, mu1))) => mu0 + mu1 * w,
        (FrictionLaw::Stribeck { mu_static, mu_kinetic, stribeck_speed_rad_s }, None) => {
            stribeck_mu(*mu_static, *mu_kinetic, *stribeck_speed_rad_s, w)
        }
        (_, None) => unreachable!("only the Stribeck law is not piecewise affine"),
    }
}

/// [`slip_mu`] as μ0 + μ1·|Ω1| on the segment holding `speed_abs_rad_s`
/// (segment index, μ0, μ1): Coulomb μk + 0, viscous μk + c|Ω1|, the thesis
/// lookup's segment; `None` for the Stribeck law (not affine).
pub(crate) fn slip_mu_affine(law: &FrictionLaw, speed_abs_rad_s: f64) -> Option<(i8, f64, f64)> {
    match law {
        FrictionLaw::Thesis(f) => Some(thesis_segment(f, speed_abs_rad_s)),
        FrictionLaw::Coulomb { mu_kinetic, .. } => Some((0, *mu_kinetic, 0.0)),
        FrictionLaw::Viscous { mu_kinetic, viscous_per_rad_s, .. } => Some((0, *mu_kinetic, *viscous_per_rad_s)),
        FrictionLaw::Stribeck { .. } => None,
    }
}

/// Static (break-away) coefficient μs of the stick phase.
pub fn static_mu(law: &FrictionLaw) -> f64 {
    match law {
        FrictionLaw::Thesis(f) => f.mu_static,
        FrictionLaw::Coulomb { mu_static, .. }
        | FrictionLaw::Stribeck { mu_static, .. }
        | FrictionLaw::Viscous { mu_static, .. } => *mu_static,
    }
}

/// The normal force N(t, φ1) = N0 · Π (effect factors), vocabulary effects
/// `normal_force_modulation` and `angle_periodic_friction` and the
/// normal-force variant of the harmonic friction (issue 4).
pub fn normal_force_n(n0: f64, effects: &[Effect], harmonic: Option<&HarmonicFriction>, t: f64, phi1: f64) -> f64 {
    let mut n = n0;
    for e in effects {
        match e {
            Effect::NormalForceModulation { amplitude_ratio, frequency_hz, phase_rad } => {
                n *= 1.0 + amplitude_ratio * (2.0 * PI * frequency_hz * t + phase_rad).sin();
            }
            Effect::AnglePeriodicFriction { amplitude_ratio, order, phase_rad } => {
                n *= 1.0 + amplitude_ratio * (f64::from(*order) * phi1 + phase_rad).sin();
            }
            _ => {}
        }
    }
    if let Some(HarmonicFriction::NormalForce { omega_p_rad_s, amplitude_ratio }) = harmonic {
        n *= 1.0 + amplitude_ratio * (omega_p_rad_s * t).sin();
    }
    n
}

/// Eq. 4-11 as published multiplies the whole friction torque by sin(ω_p t).
pub fn torque_factor(harmonic: Option<&HarmonicFriction>, t: f64) -> f64 {
    match harmonic {
        Some(HarmonicFriction::MultiplyTorque { omega_p_rad_s }) => (omega_p_rad_s * t).sin(),
        _ => 1.0,
    }
}

/// Motor cogging torque at the shaft, Σ τ sin(n φ2 + θ) (outside the vocabulary).
pub fn cogging_nm(effects: &[Effect], phi2: f64) -> f64 {
    effects
        .iter()
        .map(|e| match e {
            Effect::MotorCogging { amplitude_nm, order, phase_rad } => {
                amplitude_nm * (f64::from(*order) * phi2 + phase_rad).sin()
            }
            _ => 0.0,
        })
        .sum()
}

/// Standard gravity, m/s² (CGPM 1901), for [`Effect::RotorImbalance`].
pub const STANDARD_GRAVITY_M_S2: f64 = 9.80665;

/// Gravity torque on rotor 1 from its imbalance, Σ m·e·g·sin(φ1 + θ), N·m
/// (positive acts like friction: it is subtracted from the shaft torque).
pub fn imbalance_torque_nm(effects: &[Effect], phi1: f64) -> f64 {
    effects
        .iter()
        .map(|e| match e {
            Effect::RotorImbalance { imbalance_kg_m, phase_rad } => {
                imbalance_kg_m * STANDARD_GRAVITY_M_S2 * (phi1 + phase_rad).sin()
            }
            _ => 0.0,
        })
        .sum()
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// The decay's shortcut past the underflow gives libm's bits: on a dense
    /// grid of (Ω/vs)² across the shortcut's edge and the underflow (700–800)
    /// and on ratios far either side, including ∞ and NaN.
    #[test]
    fn the_decay_past_its_underflow_is_libm_s_zero() {
        let libm = |w: f64, vs: f64| (-(w / vs).powi(2)).exp();
        let mut ratios: Vec<f64> = (0..=200_000).map(|k| (700.0 + k as f64 * 5e-4).sqrt()).collect();
        ratios.extend([0.0, 1e-3, 1.0, 10.0, 27.0, 27.4, 28.0, 1e3, 1e200, f64::INFINITY, f64::NAN]);
        for &x in &ratios {
            for (w, vs) in [(x, 1.0), (-x * 0.37, 0.37), (x * 4.5, 4.5)] {
                assert_eq!(stribeck_decay(w, vs).to_bits(), libm(w, vs).to_bits(), "Ω {w}, vs {vs}");
            }
        }
        assert_eq!(stribeck_decay(1.0, 0.0).to_bits(), 0.0f64.to_bits());
        assert!(libm(27.4, 1.0) == 0.0 && libm(27.2, 1.0) > 0.0, "the underflow lies inside the grid");
    }

    /// Table 4.7 (also used by the unit tests of `system`).
    pub(crate) fn table_4_7() -> ThesisFriction {
        ThesisFriction {
            mu_static: 1.6,
            mu_dynamic: 1.2,
            mu_negative: -0.2,
            tolerance: 0.001,
            static_setpoint_rpm: 0.05,
            dynamic_setpoint_rpm: 0.5,
        }
    }

    #[test]
    fn thesis_lookup_hits_the_table_4_7_set_points() {
        let f = table_4_7();
        let rpm = |x: f64| x / RAD_S_TO_RPM;
        assert_eq!(thesis_lookup(&f, -1.0), -0.2);
        assert_eq!(thesis_lookup(&f, 0.0), -0.2);
        assert!((thesis_lookup(&f, rpm(0.05)) - 1.6).abs() < 1e-12);
        assert!((thesis_lookup(&f, rpm(0.5)) - 1.2).abs() < 1e-12);
        assert!((thesis_lookup(&f, rpm(0.275)) - 1.4).abs() < 1e-12);
        assert_eq!(thesis_lookup(&f, 10.0), 1.2);
    }

    #[test]
    fn stribeck_starts_at_static_and_decays_to_kinetic() {
        let law = FrictionLaw::Stribeck { mu_static: 0.5, mu_kinetic: 0.3, stribeck_speed_rad_s: 2.0 };
        assert_eq!(slip_mu(&law, 0.0), 0.5);
        assert!((slip_mu(&law, 2.0) - (0.3 + 0.2 * (-1.0f64).exp())).abs() < 1e-15);
        assert!((slip_mu(&law, 100.0) - 0.3).abs() < 1e-15);
        assert_eq!(slip_mu(&law, -2.0), slip_mu(&law, 2.0));
    }
}
