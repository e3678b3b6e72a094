//! Proof test of the diagnosis' friction extension
//! (rig_types::Effect::FrictionExtension, rig_model::extension): every
//! break-away happens at μs·(1 + c0 + cd ln(1 + t_stick/τd))·N·r of its own
//! stick, every slip sample carries μk·(1 + av|Ω1| + ab exp(−t_slip/τb))·N·r
//! with t_slip the time since that break-away, and all-zero coefficients
//! give the plain model's motion.

mod common;

use common::*;
use rig_model::extension::{BREAKAWAY_TIME_S, DWELL_TIME_S};
use rig_model::simulate;
use rig_types::{Effect, FrictionLaw, RunInput};

fn extension(av: f64, ab: f64, c0: f64, cd: f64) -> Effect {
    Effect::FrictionExtension {
        slip_speed_per_rad_s: av,
        breakaway_transient: ab,
        static_level: c0,
        dwell_per_efold: cd,
    }
}

#[test]
fn break_away_and_slip_friction_follow_the_extension() {
    let mut p = rig_params();
    p.shaft_damping_nm_s_rad *= 0.3;
    let FrictionLaw::Coulomb { mu_static, mu_kinetic } = p.friction else { panic!() };
    let (n0, r) = (20.0, p.brake_disc_radius_m);
    let (av, ab, c0, cd) = (0.01, 0.1, 0.05, 0.02);
    p.effects = vec![extension(av, ab, c0, cd)];
    let t = grid(30.0, 4000.0);
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 15.0, normal_force_n: n0, ramp_s: 1.0 };
    let tr = simulate(&p, &input, &t, &opts(1e-9)).unwrap();
    let (mut stick_start, mut slip_start) = (None, Some(0.0));
    let (mut breaks, mut slip_checked) = (0, 0);
    for k in 1..tr.len() {
        match (tr.stuck[k - 1], tr.stuck[k]) {
            (false, true) => stick_start = Some(tr.time_s[k]),
            (true, false) => {
                if let Some(s) = stick_start.take() {
                    let t_stick = tr.time_s[k] - s;
                    let expect = mu_static * (1.0 + c0 + cd * (t_stick / DWELL_TIME_S).ln_1p()) * n0 * r;
                    let torque = tr.friction_torque_nm[k - 1].abs();
                    assert!((torque - expect).abs() < 0.01 * expect, "stick {t_stick} s: {torque} vs {expect}");
                    breaks += 1;
                }
                slip_start = Some(tr.time_s[k]);
            }
            (false, false) => {
                // The break-away instant lies within the sample before `slip_start`.
                if let Some(s) = slip_start.filter(|s| tr.time_s[k] - s > 0.01) {
                    let w = tr.rotor_speed_rad_s[k].abs();
                    let since = tr.time_s[k] - s;
                    let expect = mu_kinetic * (1.0 + av * w + ab * (-since / BREAKAWAY_TIME_S).exp()) * n0 * r;
                    let got = tr.friction_torque_nm[k].abs();
                    // One sample (0.25 ms) of uncertainty in t_slip: ab·(0.25e-3/τb) relative.
                    assert!((got - expect).abs() < 2e-3 * expect, "t {}: {got} vs {expect}", tr.time_s[k]);
                    slip_checked += 1;
                }
            }
            _ => {}
        }
    }
    assert!(
        breaks >= 5 && slip_checked > 1000,
        "the run stick-slips: {breaks} break-aways, {slip_checked} slip samples"
    );
}

#[test]
fn zero_coefficients_move_nothing_and_the_pad_state_is_not_shared() {
    let mut p = rig_params();
    p.shaft_damping_nm_s_rad *= 0.3;
    let t = grid(20.0, 500.0);
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 15.0, normal_force_n: 20.0, ramp_s: 1.0 };
    let plain = simulate(&p, &input, &t, &opts(1e-10)).unwrap();
    p.effects = vec![extension(0.0, 0.0, 0.0, 0.0)];
    let zero = simulate(&p, &input, &t, &opts(1e-10)).unwrap();
    let worst =
        plain.rotor_speed_rad_s.iter().zip(&zero.rotor_speed_rad_s).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-5, "rotor speed moved by {worst} rad/s");
    p.effects.push(Effect::StaticFrictionAging { aging_mu_per_efold: 0.05, aging_time_s: 0.05 });
    let e = simulate(&p, &input, &t, &opts(1e-8)).unwrap_err().to_string();
    assert!(e.contains("friction_extension"), "{e}");
}
