//! calibrate_campaign on a synthetic campaign with known answers: a linear
//! force sensor, a linear shaft, and voltage steps whose twist is an exact
//! damped cosine (quantised to encoder ticks like the rig's).

use rig_calibrate::{CalibrateError, calibrate_campaign, friction_torque_nm};
use rig_types::{Campaign, RigInfo, Run, RunData, RunKind};
use std::f64::consts::PI;

const FACTOR_MV_N: f64 = 213.0;
const OFFSET_MV: f64 = 4.0;
const K_NM_RAD: f64 = 0.27;
const J1_KGM2: f64 = 0.03;
const XI: f64 = 0.09;

fn run(id: &str, kind: RunKind, data: RunData) -> Run {
    Run { id: id.into(), kind, file: format!("runs/{id}.csv").into(), data }
}

fn time(n: usize) -> Vec<f64> {
    (0..n).map(|i| i as f64 * 0.002).collect()
}

fn synthetic() -> Campaign {
    let tick = 2.0 * PI / 1000.0;
    let mut runs = Vec::new();
    for (i, load) in [0.7, 2.0, 3.3, 4.4, 5.8].iter().enumerate() {
        // Alternating ±0.5 mV noise: zero mean, so the mean is exact.
        let mv = (0..1000).map(|k| OFFSET_MV + FACTOR_MV_N * load + if k % 2 == 0 { 0.5 } else { -0.5 }).collect();
        let data = RunData { time_s: time(1000), brake_force_mv: Some(mv), ..Default::default() };
        runs.push(run(&format!("cal-{i}"), RunKind::ForceCalibration { load_n: *load }, data));
    }
    for (i, torque) in [0.11, 0.17, 0.23, 0.29, 0.34].iter().enumerate() {
        // Exactly K φ with φ an integer number of ticks: the torque is derived from the ticks.
        let ticks = (torque / K_NM_RAD / tick).round() as i64;
        let data = RunData { time_s: time(500), rotor_ticks: Some(vec![ticks; 500]), ..Default::default() };
        runs.push(run(&format!("twist-{i}"), RunKind::StaticTwist { torque_nm: ticks as f64 * tick * K_NM_RAD }, data));
    }
    let wn = (K_NM_RAD / J1_KGM2).sqrt();
    let wd = wn * (1.0 - XI * XI).sqrt();
    for (i, v) in [6.0, 10.0].iter().enumerate() {
        let omega2 = 2.0 * v; // motor side at constant speed
        let t = time(10_000);
        let motor: Vec<i64> = t.iter().map(|&t| (omega2 * t / tick).round() as i64).collect();
        let rotor: Vec<i64> = t
            .iter()
            .zip(&motor)
            .map(|(&t, &m)| {
                let twist = 0.3 + (1.5 + 0.1 * i as f64) * (-XI * wn * t).exp() * (wd * t).cos();
                m - (twist / tick).round() as i64
            })
            .collect();
        let data = RunData {
            time_s: t,
            motor_voltage_v: Some(vec![*v; 10_000]),
            motor_ticks: Some(motor),
            rotor_ticks: Some(rotor),
            brake_force_mv: None,
        };
        runs.push(run(&format!("step-{i}"), RunKind::VoltageStep { voltage_v: *v }, data));
    }
    Campaign {
        name: "synthetic".into(),
        description: String::new(),
        rig: RigInfo {
            encoder_ticks_per_rev: 1000,
            brake_disc_radius_m: 0.062,
            supply_voltage_v: 24.0,
            sample_rate_hz: 500.0,
        },
        runs,
    }
}

#[test]
fn recovers_known_constants() {
    let c = calibrate_campaign(&synthetic()).unwrap();
    assert!((c.force_factor_mv_per_n - FACTOR_MV_N).abs() < 1e-9, "{}", c.force_factor_mv_per_n);
    assert!((c.force_offset_mv - OFFSET_MV).abs() < 1e-8, "{}", c.force_offset_mv);
    assert!((c.stiffness_nm_rad - K_NM_RAD).abs() < 1e-12);
    assert!(c.stiffness_with_offset.intercept.abs() < 1e-12);
    assert_eq!(c.steps.len(), 2);
    let wn = (K_NM_RAD / J1_KGM2).sqrt();
    let delta = 2.0 * PI * XI / (1.0 - XI * XI).sqrt();
    assert!((c.log_decrement - delta).abs() < 0.01, "δ {} vs {delta}", c.log_decrement);
    assert!((c.damping_ratio - XI).abs() < 0.002, "ξ {}", c.damping_ratio);
    assert!((c.natural_frequency_rad_s - wn).abs() / wn < 0.002, "ω_n {} vs {wn}", c.natural_frequency_rad_s);
    assert!((c.rotor_inertia_kgm2 - J1_KGM2).abs() / J1_KGM2 < 0.005, "J1 {}", c.rotor_inertia_kgm2);
    // The rotor-speed cross-check sees the same oscillator.
    let sp = c.steps[0].rotor_speed.as_ref().expect("speed decay found");
    assert!((sp.log_decrement_mean - delta).abs() < 0.03, "speed δ {}", sp.log_decrement_mean);
}

#[test]
fn friction_torque_inverts_the_sensor_line() {
    let c = calibrate_campaign(&synthetic()).unwrap();
    let t = friction_torque_nm(&[OFFSET_MV + FACTOR_MV_N * 10.0], &c, 0.062);
    assert!((t[0] - 0.62).abs() < 1e-9);
}

#[test]
fn missing_kinds_are_named() {
    let mut camp = synthetic();
    camp.runs.retain(|r| r.kind.name() != "static_twist");
    let e = calibrate_campaign(&camp).unwrap_err();
    assert!(matches!(e, CalibrateError::MissingRuns { ref kind, .. } if kind == "static_twist"), "{e}");
}

/// A voltage step whose twist never oscillates (rotor locked to the motor) is
/// listed as skipped, the others still calibrate; with no decaying step at all
/// the error names the problem.
#[test]
fn steps_without_decay_are_data() {
    let mut camp = synthetic();
    let flat = camp.runs.iter_mut().find(|r| r.id == "step-1").unwrap();
    flat.data.rotor_ticks = flat.data.motor_ticks.clone();
    let c = calibrate_campaign(&camp).unwrap();
    assert_eq!(c.steps.len(), 1);
    assert_eq!(c.steps_without_decay.len(), 1);
    assert_eq!(c.steps_without_decay[0].id, "step-1");
    for r in camp.runs.iter_mut().filter(|r| r.id == "step-0") {
        r.data.rotor_ticks = r.data.motor_ticks.clone();
    }
    let e = calibrate_campaign(&camp).unwrap_err();
    assert!(matches!(e, CalibrateError::NoDecay { .. }), "{e}");
}

/// The campaign tables of the synthetic campaign, pinned. Checked: factor
/// 213.000 mV/N and offset 4.000 mV (the construction), std 0.500 mV (the ±0.5
/// alternation), K = 0.27000 exactly with zero offset; δ = 2πξ/√(1−ξ²) = 0.5678,
/// ω_d = 2.9878 rad/s
/// and ω_n = √(K/J) = 3.0000 rad/s within the tolerances asserted above.
#[test]
fn synthetic_tables() {
    let c = calibrate_campaign(&synthetic()).unwrap();
    insta::assert_snapshot!("synthetic_force", rig_calibrate::render::force_table(&c).to_csv());
    insta::assert_snapshot!("synthetic_stiffness", rig_calibrate::render::stiffness_table(&c).to_csv());
    insta::assert_snapshot!("synthetic_log_decrement", rig_calibrate::render::log_decrement_table(&c).to_csv());
}
