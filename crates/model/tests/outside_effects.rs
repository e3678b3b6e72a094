//! Proof tests of the effects outside the diagnosis vocabulary against
//! closed-form consequences of their equations (rig_types::Effect docs).

mod common;

use common::*;
use rig_model::{State, simulate, simulate_from, static_twist_rad};
use rig_types::{DriveParams, Effect, FrictionLaw, RunInput};
use std::f64::consts::PI;

fn motor_held(p: &mut rig_types::RigParams) {
    p.motor.inertia_kgm2 = 1e12;
    p.drive = DriveParams { kp_v_s_rad: 0.0, ki_v_rad: 0.0, limit_v: 24.0 };
}

/// Backlash: a rotor released inside the gap feels no shaft torque and stays
/// where it is; released beyond it, it oscillates about the gap's edge (the
/// elastic torque vanishes at |δ| = b, not at 0).
#[test]
fn backlash_is_a_dead_zone_of_the_twist() {
    let mut p = rig_params();
    motor_held(&mut p);
    p.effects = vec![Effect::CouplingBacklash { gap_rad: 0.4 }];
    let t = grid(10.0, 200.0);
    let inside = State { rotor_angle_rad: 0.15, ..State::default() };
    let (tr, _) = simulate_from(&p, &inside, 0.0, 0.0, &t, &at_rtol(1e-10)).unwrap();
    assert!(tr.rotor_angle_rad.iter().all(|&a| a == 0.15));
    let beyond = State { rotor_angle_rad: 1.0, ..State::default() };
    let (tr, _) = simulate_from(&p, &beyond, 0.0, 0.0, &grid(120.0, 50.0), &at_rtol(1e-10)).unwrap();
    // Released at δ = −1 it swings through the gap; damping acts only in
    // contact, so the swing decays until it ends up inside the gap, |φ1| ≤ b.
    let late = tr.rotor_angle_rad[tr.len() - 1000..].iter().fold(0.0f64, |m, a| m.max(a.abs()));
    assert!(late <= 0.2 + 1e-9, "{late}");
    let min = tr.rotor_angle_rad.iter().cloned().fold(f64::MAX, f64::min);
    assert!(min < -0.2, "it crossed the gap: {min}");
    let expect = 0.3 / p.shaft_stiffness_nm_rad + 0.2;
    assert!((static_twist_rad(&p, 0.3) - expect).abs() < 1e-12);
    assert!((static_twist_rad(&p, -0.3) + expect).abs() < 1e-12);
}

/// Cubic shaft: the static twist solves K δ (1 + β δ²) = T; a hardening shaft
/// oscillates faster at large amplitude than at small (Duffing backbone
/// ω ≈ ω0 (1 + 3/8 β A²)).
#[test]
fn cubic_shaft_hardens_and_static_twist_inverts_it() {
    let mut p = rig_params();
    p.effects = vec![Effect::ShaftCubicStiffness { cubic_per_rad2: 0.5 }];
    let k = p.shaft_stiffness_nm_rad;
    for torque in [0.1, 0.34, -0.2] {
        let d = static_twist_rad(&p, torque);
        assert!((k * d * (1.0 + 0.5 * d * d) - torque).abs() < 1e-12, "{torque} {d}");
    }
    p.effects = vec![Effect::ShaftCubicStiffness { cubic_per_rad2: -0.5 }];
    assert!(static_twist_rad(&p, 10.0).is_nan(), "a softening shaft has a torque ceiling");
    motor_held(&mut p);
    p.shaft_damping_nm_s_rad = 0.0;
    p.effects = vec![Effect::ShaftCubicStiffness { cubic_per_rad2: 0.5 }];
    let period = |amp: f64| {
        let start = State { rotor_angle_rad: amp, ..State::default() };
        let (tr, _) = simulate_from(&p, &start, 0.0, 0.0, &grid(20.0, 2000.0), &at_rtol(1e-11)).unwrap();
        let x = &tr.rotor_angle_rad;
        let c: Vec<f64> = (1..x.len()).filter(|&i| x[i - 1] > 0.0 && x[i] <= 0.0).map(|i| tr.time_s[i]).collect();
        (c[c.len() - 1] - c[0]) / (c.len() - 1) as f64
    };
    let w0 = (k / p.rotor_inertia_kgm2).sqrt();
    let (small, large) = (2.0 * PI / period(0.01), 2.0 * PI / period(1.0));
    assert!((small / w0 - 1.0).abs() < 1e-3, "{small} {w0}");
    let backbone = w0 * (1.0 + 3.0 / 8.0 * 0.5);
    assert!((large / backbone - 1.0).abs() < 0.03, "{large} {backbone}");
}

/// Imbalance: with the motor side held and the brake open the rotor settles
/// where the shaft balances gravity, K(0 − φ1) = m e g sin(φ1 + θ).
#[test]
fn imbalance_rotor_settles_where_shaft_balances_gravity() {
    let mut p = rig_params();
    motor_held(&mut p);
    let (me, th) = (0.01, 0.5);
    p.effects = vec![Effect::RotorImbalance { imbalance_kg_m: me, phase_rad: th }];
    let (tr, _) = simulate_from(&p, &State::default(), 0.0, 0.0, &grid(200.0, 10.0), &at_rtol(1e-10)).unwrap();
    let phi = *tr.rotor_angle_rad.last().unwrap();
    let residual = -p.shaft_stiffness_nm_rad * phi - me * 9.80665 * (phi + th).sin();
    assert!(residual.abs() < 1e-6, "φ1 = {phi}, residual {residual}");
    assert!(phi < -0.05, "gravity moved the rotor: {phi}");
}

/// Brake fade: at the start of a slipping run the friction torque is the
/// cold one (μk N r); friction work heats the pad and the torque falls; with
/// a smaller heat capacity it falls further.
#[test]
fn brake_fade_lowers_friction_as_work_accumulates() {
    let mut p = rig_params();
    p.friction = FrictionLaw::Coulomb { mu_static: 0.5, mu_kinetic: 0.4 };
    let t = grid(30.0, 100.0);
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 130.0, normal_force_n: 20.0, ramp_s: 1.0 };
    let cold = simulate(&p, &input, &t, &at_rtol(1e-9)).unwrap();
    let late = |tr: &rig_types::Trajectory| {
        let n = tr.len();
        tr.friction_torque_nm[n - 500..].iter().sum::<f64>() / 500.0
    };
    let mut fade = |c: f64| {
        p.effects = vec![Effect::BrakeFade { heat_capacity_j_k: c, cooling_time_s: 20.0, fade_temperature_k: 30.0 }];
        simulate(&p, &input, &t, &at_rtol(1e-9)).unwrap()
    };
    let hot = fade(5.0);
    let hotter = fade(2.0);
    let cold_torque = 0.4 * 20.0 * p.brake_disc_radius_m;
    assert!((late(&cold) - cold_torque).abs() < 0.02 * cold_torque, "{}", late(&cold));
    assert!(late(&hot) < 0.8 * cold_torque, "{}", late(&hot));
    assert!(late(&hotter) < late(&hot));
    // Before the pad has heated, the first slip samples carry the cold coefficient.
    let k = hot.stuck.iter().position(|s| !s).unwrap();
    assert!((hot.friction_torque_nm[k].abs() - cold_torque).abs() < 0.01 * cold_torque);
}

/// Current limit: L di/dt = V − R i − emf ≤ R (I_max − i) once clamped, so the
/// current of a voltage step never exceeds I_max; the steady speed (small
/// current) is the unlimited one.
#[test]
fn current_limit_caps_the_step_current_not_the_steady_speed() {
    let mut p = rig_params();
    let t = grid(20.0, 500.0);
    let step = RunInput::VoltageStep { voltage_v: 12.0 };
    let free = simulate(&p, &step, &t, &at_rtol(1e-9)).unwrap();
    let peak = |tr: &rig_types::Trajectory| tr.current_a.iter().cloned().fold(0.0, f64::max);
    assert!(peak(&free) > 5.0, "{}", peak(&free));
    p.effects = vec![Effect::DriveCurrentLimit { current_limit_a: 3.0 }];
    let lim = simulate(&p, &step, &t, &at_rtol(1e-9)).unwrap();
    assert!(peak(&lim) <= 3.0 + 1e-6, "{}", peak(&lim));
    assert!(lim.voltage_v[1] < 12.0, "the terminal voltage is clamped at start-up");
    let n = t.len();
    assert!((lim.motor_speed_rad_s[n - 1] - free.motor_speed_rad_s[n - 1]).abs() < 1e-3);
    assert!(lim.motor_speed_rad_s[n / 20] < free.motor_speed_rad_s[n / 20]);
}

/// The new variants serialise under their snake_case names next to the old ones.
#[test]
fn outside_effects_have_stable_serde_names() {
    let effects = vec![
        Effect::NormalForceModulation { amplitude_ratio: 0.1, frequency_hz: 1.0, phase_rad: 0.0 },
        Effect::CouplingBacklash { gap_rad: 0.05 },
        Effect::ShaftCubicStiffness { cubic_per_rad2: 0.02 },
        Effect::RotorImbalance { imbalance_kg_m: 0.01, phase_rad: 0.0 },
        Effect::BrakeFade { heat_capacity_j_k: 5.0, cooling_time_s: 30.0, fade_temperature_k: 40.0 },
        Effect::DriveCurrentLimit { current_limit_a: 3.0 },
    ];
    let json = serde_json::to_string(&effects).unwrap();
    for name in [
        "\"normal_force_modulation\"",
        "\"coupling_backlash\"",
        "\"shaft_cubic_stiffness\"",
        "\"rotor_imbalance\"",
        "\"brake_fade\"",
        "\"drive_current_limit\"",
    ] {
        assert!(json.contains(name), "{name} in {json}");
    }
    let back: Vec<Effect> = serde_json::from_str(&json).unwrap();
    assert_eq!(back, effects);
}
