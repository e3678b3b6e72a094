//! Proof test of [`rig_model::Channels`]: a run without the friction torque's
//! channel is the full run to the bit on every other channel (T1 is an
//! output only), over runs of every path of the integration loop: exact
//! steps and blocks, Dormand–Prince steps, stick/slip events, the thesis
//! model, a voltage step, a normal-force modulation and an angle-periodic
//! friction (whose samples of T1 take a `sin` each), friction ageing.

mod common;

use common::*;
use rig_model::{Channels, SimStats, simulate_channels, simulate_with_stats};
use rig_types::{Effect, FrictionLaw, RigParams, RunInput, Trajectory};

fn operating_point(rpm: f64, normal_force_n: f64) -> RunInput {
    RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n, ramp_s: 1.0 }
}

fn with(effects: Vec<Effect>) -> RigParams {
    RigParams { effects, ..rig_params() }
}

/// Each channel of `without` against `all`'s, bit for bit; T1 empty.
fn check(name: &str, p: &RigParams, input: &RunInput, times: &[f64]) -> SimStats {
    let (all, stats) = simulate_with_stats(p, input, times, &shipped()).unwrap();
    let full = simulate_channels(p, input, times, &shipped(), Channels::All).unwrap();
    assert_eq!(bits(&full), bits(&all), "{name}: Channels::All is simulate");
    let without = simulate_channels(p, input, times, &shipped(), Channels::WithoutFriction).unwrap();
    assert!(without.friction_torque_nm.is_empty(), "{name}");
    assert_eq!(all.len(), times.len(), "{name}");
    let t1_only = Trajectory { friction_torque_nm: Vec::new(), ..all.clone() };
    assert_eq!(bits(&without), bits(&t1_only), "{name}: the other channels");
    // T1 is not trivially absent: the full run has a sample per time and a nonzero one.
    assert_eq!(all.friction_torque_nm.len(), times.len(), "{name}");
    assert!(all.friction_torque_nm.iter().any(|&f| f != 0.0) || name.starts_with("voltage"), "{name}");
    stats
}

fn bits(tr: &Trajectory) -> (Vec<Vec<u64>>, Vec<bool>) {
    (tr.numeric_channels().iter().map(|c| c.iter().map(|x| x.to_bits()).collect()).collect(), tr.stuck.clone())
}

#[test]
fn a_run_without_the_friction_channel_is_the_full_run_to_the_bit() {
    let times = grid(12.0, 500.0);
    let modulation = Effect::NormalForceModulation { amplitude_ratio: 0.3, frequency_hz: 1.7, phase_rad: 0.4 };
    let angle = Effect::AnglePeriodicFriction { amplitude_ratio: 0.2, order: 3, phase_rad: 1.1 };
    let ageing = Effect::StaticFrictionAging { aging_mu_per_efold: 0.05, aging_time_s: 0.5 };
    let stribeck = RigParams {
        friction: FrictionLaw::Stribeck { mu_static: 0.5, mu_kinetic: 0.3, stribeck_speed_rad_s: 0.3 },
        ..rig_params()
    };
    let (mut events, mut exact, mut dopri) = (0, 0, 0);
    for (name, p, input) in [
        ("plain, stick-slip", rig_params(), operating_point(5.0, 30.0)),
        ("plain, steady slip", rig_params(), operating_point(400.0, 10.0)),
        ("modulated N, stick-slip", with(vec![modulation.clone()]), operating_point(5.0, 30.0)),
        ("modulated N, slip", with(vec![modulation]), operating_point(300.0, 15.0)),
        ("angle-periodic", with(vec![angle]), operating_point(15.0, 20.0)),
        ("ageing", with(vec![ageing]), operating_point(5.0, 30.0)),
        ("Stribeck", stribeck, operating_point(15.0, 20.0)),
        ("thesis model", thesis_params(), operating_point(60.0, 20.0)),
        ("voltage step", rig_params(), RunInput::VoltageStep { voltage_v: 6.0 }),
    ] {
        let s = check(name, &p, &input, &times);
        (events, exact, dopri) = (events + s.events, exact + s.exact_steps, dopri + s.accepted_steps);
    }
    // Every path of the loop was taken.
    assert!(events >= 15 && exact > 100 && dopri > 1000, "events {events}, exact {exact}, Dormand–Prince {dopri}");
}
