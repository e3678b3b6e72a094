//! Proof test of exact steps with the brake open under effects that act
//! through the contact alone (N's modulations, harmonic friction, the static
//! coefficient's ageing, the diagnosis' friction extension): with N0 = 0 the
//! friction torque T1 = μ·N·r is 0 (Eq. 4-7's first row without T1), so the
//! motion of a voltage step is the plain model's, and the integrator takes
//! the plain model's exact steps (the motor-side refits' voltage steps of a
//! model that carries such an effect, rig-estimate's `refit_motor_side`).

mod common;

use common::*;
use rig_model::simulate_with_stats;
use rig_types::{Effect, HarmonicFriction, RigParams, RunInput, Trajectory};

fn modulation() -> Effect {
    Effect::NormalForceModulation { amplitude_ratio: 0.3, frequency_hz: 1.7, phase_rad: 0.4 }
}

fn angle_periodic() -> Effect {
    Effect::AnglePeriodicFriction { amplitude_ratio: 0.2, order: 3, phase_rad: 1.1 }
}

fn ageing() -> Effect {
    Effect::StaticFrictionAging { aging_mu_per_efold: 0.05, aging_time_s: 0.5 }
}

fn extension() -> Effect {
    Effect::FrictionExtension {
        slip_speed_per_rad_s: 0.01,
        breakaway_transient: 0.1,
        static_level: 0.05,
        dwell_per_efold: 0.02,
    }
}

fn channels(tr: &Trajectory) -> [&Vec<f64>; 7] {
    [
        &tr.rotor_angle_rad,
        &tr.motor_angle_rad,
        &tr.rotor_speed_rad_s,
        &tr.motor_speed_rad_s,
        &tr.current_a,
        &tr.voltage_v,
        &tr.friction_torque_nm,
    ]
}

/// A voltage step of `voltage_v` over 6 s at 1 kHz (the brake open, N = 0).
fn step(p: &RigParams, voltage_v: f64) -> (Trajectory, rig_model::SimStats) {
    simulate_with_stats(p, &RunInput::VoltageStep { voltage_v }, &grid(6.0, 1000.0), &shipped()).unwrap()
}

#[test]
fn contact_effects_with_the_brake_open_take_the_plain_models_steps_to_the_bit() {
    // Without a pad state the error norm is the plain model's too: the same
    // Dormand–Prince steps at the start from rest (the motor friction's tanh
    // unsaturated), the same exact steps after, so the same bits.
    let plain = rig_params();
    for voltage_v in [6.0, -9.0] {
        let (a, sa) = step(&plain, voltage_v);
        for (effects, harmonic) in [
            (vec![modulation()], None),
            (vec![angle_periodic()], None),
            (vec![modulation(), angle_periodic()], None),
            (vec![], Some(HarmonicFriction::NormalForce { omega_p_rad_s: 9.0, amplitude_ratio: 0.3 })),
            (vec![modulation()], Some(HarmonicFriction::MultiplyTorque { omega_p_rad_s: 9.0 })),
        ] {
            let p = RigParams { effects: effects.clone(), harmonic: harmonic.clone(), ..plain.clone() };
            let (b, sb) = step(&p, voltage_v);
            assert!(sb.exact_steps > 10 * sb.accepted_steps, "{effects:?} {harmonic:?}: {sb:?}");
            assert_eq!(sa, sb, "{effects:?} {harmonic:?}");
            assert_eq!(a.time_s, b.time_s);
            assert_eq!(a.stuck, b.stuck);
            for (x, y) in channels(&a).into_iter().zip(channels(&b)) {
                assert!(x.iter().zip(y).all(|(u, v)| u.to_bits() == v.to_bits()), "{effects:?} {harmonic:?}");
            }
        }
    }
}

#[test]
fn contact_effects_with_the_brake_open_agree_with_dormand_prince() {
    // The reference: a cogging torque of amplitude 0 adds +0.0 to the motor
    // torque (the plain motion) but is not a contact effect, so the run is
    // Dormand–Prince throughout, as every run with an effect was before.
    let cogging = Effect::MotorCogging { amplitude_nm: 0.0, order: 6, phase_rad: 0.0 };
    for voltage_v in [6.0, -9.0] {
        for effects in [vec![modulation(), angle_periodic()], vec![ageing()], vec![extension()]] {
            let p = RigParams { effects: effects.clone(), ..rig_params() };
            let (exact, stats) = step(&p, voltage_v);
            let mut with_cogging = effects.clone();
            with_cogging.push(cogging.clone());
            let q = RigParams { effects: with_cogging, ..rig_params() };
            let (dopri, dopri_stats) = step(&q, voltage_v);
            assert!(dopri_stats.exact_steps == 0, "{dopri_stats:?}");
            assert!(stats.exact_steps > 10 * stats.accepted_steps, "{effects:?}: {stats:?}");
            assert!(exact.friction_torque_nm.iter().all(|&f| f == 0.0) && !exact.stuck.contains(&true));
            // Far below the encoder's speed resolution (≈ 10⁻² rad/s) at rtol 10⁻⁸.
            for (x, y) in channels(&exact).into_iter().zip(channels(&dopri)) {
                let worst = x.iter().zip(y).map(|(u, v)| (u - v).abs()).fold(0.0, f64::max);
                assert!(worst < 1e-6, "{effects:?} {voltage_v} V: {worst:e}");
            }
        }
    }
}
