//! Proof test of static friction aging (rig_types::Effect::StaticFrictionAging):
//! every break-away of a stick-slipping run happens at the torque
//! (μs + B ln(1 + t_stick/τ))·N·r of its own stick duration, the slip
//! friction is unchanged, and without aging every break-away is at μs·N·r.

mod common;

use common::*;
use rig_model::simulate;
use rig_types::{Effect, FrictionLaw, RunInput};

/// (stick duration s, torque at the last stuck sample N·m) of every stick
/// phase that ends inside the record, and the largest |slip friction| error
/// against μk N r.
fn break_aways(p: &rig_types::RigParams, n0: f64, rate_hz: f64) -> (Vec<(f64, f64)>, f64) {
    let t = grid(30.0, rate_hz);
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 15.0, normal_force_n: n0, ramp_s: 1.0 };
    let tr = simulate(p, &input, &t, &at_rtol(1e-9)).unwrap();
    let FrictionLaw::Coulomb { mu_kinetic, .. } = p.friction else { panic!() };
    let slip_nm = mu_kinetic * n0 * p.brake_disc_radius_m;
    let mut out = Vec::new();
    let mut start = None;
    let mut slip_err = 0.0f64;
    for k in 1..tr.len() {
        match (tr.stuck[k - 1], tr.stuck[k]) {
            (false, true) => start = Some(tr.time_s[k]),
            (true, false) => {
                if let Some(s) = start.take() {
                    out.push((tr.time_s[k] - s, tr.friction_torque_nm[k - 1].abs()));
                }
            }
            (false, false) => slip_err = slip_err.max((tr.friction_torque_nm[k].abs() - slip_nm).abs()),
            _ => {}
        }
    }
    (out, slip_err)
}

#[test]
fn break_away_torque_grows_with_the_stick_time() {
    let mut p = rig_params();
    p.shaft_damping_nm_s_rad *= 0.3;
    let FrictionLaw::Coulomb { mu_static, .. } = p.friction else { panic!() };
    let (n0, r, rate) = (20.0, p.brake_disc_radius_m, 4000.0);
    let (plain, slip_err) = break_aways(&p, n0, rate);
    assert!(plain.len() >= 5, "the run stick-slips: {plain:?}");
    assert!(slip_err < 1e-9, "{slip_err}");
    for &(_, torque) in &plain {
        // The shaft torque rises by < 1 % of the threshold within one sample.
        let expect = mu_static * n0 * r;
        assert!(torque <= expect && torque > 0.99 * expect, "{torque} vs {expect}");
    }
    let (b, tau) = (0.05, 0.05);
    p.effects = vec![Effect::StaticFrictionAging { aging_mu_per_efold: b, aging_time_s: tau }];
    let (aged, slip_err) = break_aways(&p, n0, rate);
    assert!(aged.len() >= 5, "{aged:?}");
    assert!(slip_err < 1e-9, "slip friction unchanged: {slip_err}");
    for &(t_stick, torque) in &aged {
        let expect = (mu_static + b * (t_stick / tau).ln_1p()) * n0 * r;
        // The stick's length is known to one sample (0.25 ms); the torque rises within it.
        assert!((torque - expect).abs() < 0.01 * expect, "stick {t_stick} s: {torque} vs {expect}");
    }
    // Longer sticks than without aging (the rotor must wind the shaft further).
    let mean = |v: &[(f64, f64)]| v.iter().map(|x| x.1).sum::<f64>() / v.len() as f64;
    assert!(mean(&aged) > 1.05 * mean(&plain), "{} vs {}", mean(&aged), mean(&plain));
}

#[test]
fn aging_and_fade_cannot_share_the_pad_state() {
    let mut p = rig_params();
    p.effects = vec![
        Effect::StaticFrictionAging { aging_mu_per_efold: 0.05, aging_time_s: 0.05 },
        Effect::BrakeFade { heat_capacity_j_k: 5.0, cooling_time_s: 30.0, fade_temperature_k: 50.0 },
    ];
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 15.0, normal_force_n: 10.0, ramp_s: 1.0 };
    let e = simulate(&p, &input, &grid(1.0, 100.0), &shipped()).unwrap_err().to_string();
    assert!(e.contains("static_friction_aging"), "{e}");
}
