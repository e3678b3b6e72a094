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
    let tr = simulate(&p, &input, &t, &at_rtol(1e-9)).unwrap();
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
    let plain = simulate(&p, &input, &t, &at_rtol(1e-10)).unwrap();
    p.effects = vec![extension(0.0, 0.0, 0.0, 0.0)];
    let zero = simulate(&p, &input, &t, &at_rtol(1e-10)).unwrap();
    let worst =
        plain.rotor_speed_rad_s.iter().zip(&zero.rotor_speed_rad_s).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-5, "rotor speed moved by {worst} rad/s");
    p.effects.push(Effect::StaticFrictionAging { aging_mu_per_efold: 0.05, aging_time_s: 0.05 });
    let e = simulate(&p, &input, &t, &shipped()).unwrap_err().to_string();
    assert!(e.contains("friction_extension"), "{e}");
}

/// Break-away times (s) and the friction torque held just before each, N·m.
fn break_aways(tr: &rig_types::Trajectory) -> Vec<(f64, f64, f64)> {
    let mut stick_start = None;
    let mut out = Vec::new();
    for k in 1..tr.len() {
        match (tr.stuck[k - 1], tr.stuck[k]) {
            (false, true) => stick_start = Some(tr.time_s[k]),
            (true, false) => {
                if let Some(s) = stick_start.take() {
                    out.push((tr.time_s[k], tr.time_s[k] - s, tr.friction_torque_nm[k - 1].abs()));
                }
            }
            _ => {}
        }
    }
    out
}

#[test]
fn break_away_terms_alone_take_exact_steps_and_age_the_contact() {
    // The ageing law's free-run fit (rig-diagnose's extension) simulates the
    // extension with its slip coefficients at 0: the motion is the plain
    // model's, so it takes exact steps, which must advance the contact's age.
    let mut p = rig_params();
    p.shaft_damping_nm_s_rad *= 0.3;
    let FrictionLaw::Coulomb { mu_static, .. } = p.friction else { panic!() };
    let (n0, r) = (40.0, p.brake_disc_radius_m);
    let (c0, cd) = (0.05, 0.04);
    let t = grid(30.0, 1000.0);
    // 30 rpm: the motor friction's tanh saturated (|n Ω2| = 25 rad/s), as in
    // a steady operating point; 40 N: ten stick-slip cycles in 30 s.
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 30.0, normal_force_n: n0, ramp_s: 1.0 };
    p.effects = vec![extension(0.0, 0.0, c0, cd)];
    let (exact, stats) = rig_model::simulate_with_stats(&p, &input, &t, &shipped()).unwrap();
    // The same law through Dormand–Prince alone: a break-away transient of
    // 1e-300 moves no slip factor off 1 (below an ulp) but is not "alone".
    p.effects = vec![extension(0.0, 1e-300, c0, cd)];
    let (dopri, dopri_stats) = rig_model::simulate_with_stats(&p, &input, &t, &shipped()).unwrap();
    assert!(dopri_stats.exact_steps == 0 && stats.exact_steps > 10 * stats.accepted_steps, "{stats:?} {dopri_stats:?}");
    let (a, b) = (break_aways(&exact), break_aways(&dopri));
    assert!(a.len() >= 5 && a.len() == b.len(), "{} vs {} break-aways", a.len(), b.len());
    for (&(ta, dwell, torque), &(tb, _, _)) in a.iter().zip(&b) {
        // Each break-away at the aged level of its own stick (one sample of
        // 1 ms in the dwell: cd·(1 ms / (τd + dwell)) relative at most) ...
        let expect = mu_static * (1.0 + c0 + cd * (dwell / DWELL_TIME_S).ln_1p()) * n0 * r;
        assert!((torque - expect).abs() < 1e-3 * expect, "stick {dwell} s: {torque} vs {expect}");
        // ... and at the Dormand–Prince run's sample, or the next.
        assert!((ta - tb).abs() < 1.001e-3, "break-away at {ta} s vs {tb} s");
    }
    // The two integrations agree far below the speed resolution of the
    // encoder (≈ 10⁻² rad/s): 3·10⁻⁹ rad/s measured at rtol 10⁻⁸.
    let worst =
        exact.rotor_speed_rad_s.iter().zip(&dopri.rotor_speed_rad_s).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    assert!(worst < 1e-7, "rotor speeds differ by {worst:e} rad/s");
}
