//! A small synthetic campaign for round-trip tests: known RigParams simulated
//! through rig_model, then recorded as the rig would record it (encoder
//! quantisation to whole counts, voltage and force-sensor noise, seeded).
#![allow(dead_code)]

use rand::SeedableRng;
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rig_model::SimOptions;
use rig_types::{
    Campaign, DriveParams, FrictionLaw, ModelKind, MotorParams, RigInfo, RigParams, Run, RunData, RunInput, RunKind,
};
use std::f64::consts::TAU;

pub const TICKS: u32 = 1000;
pub const FORCE_FACTOR_MV_N: f64 = 214.0;
pub const FORCE_OFFSET_MV: f64 = 3.5;
pub const VOLTAGE_NOISE_V: f64 = 0.02;
pub const FORCE_NOISE_MV: f64 = 1.0;

/// Plausible truth: Table 4.5's motor with the 8:1 gear, string and rotor near the campaign's.
pub fn truth() -> RigParams {
    RigParams {
        kind: ModelKind::Rig,
        rotor_inertia_kgm2: 0.031,
        shaft_stiffness_nm_rad: 0.262,
        shaft_damping_nm_s_rad: 0.006,
        rotor_damping_nm_s_rad: 0.0,
        motor: MotorParams {
            inertia_kgm2: 4.7e-4,
            inductance_h: 8.4e-4,
            resistance_ohm: 0.526,
            torque_constant_nm_a: 0.126,
            voltage_constant_v_s_rad: 0.0588,
            friction_torque_nm: 0.1,
            speed_regulation_nm_s_rad: 1.8e-4,
            gear_ratio: 8.0,
        },
        // A stiff speed loop like the campaign's drive appears to be (kp ~ 4, ki ~ 40).
        drive: DriveParams { kp_v_s_rad: 4.0, ki_v_rad: 40.0, limit_v: 24.0 },
        friction: FrictionLaw::Coulomb { mu_static: 1.5, mu_kinetic: 1.1 },
        brake_disc_radius_m: 0.062,
        effects: vec![],
        harmonic: None,
    }
}

fn ticks(angle: &[f64]) -> Vec<i64> {
    angle.iter().map(|a| (a * TICKS as f64 / TAU).floor() as i64).collect()
}

fn times(duration_s: f64, rate_hz: f64) -> Vec<f64> {
    (0..(duration_s * rate_hz).round() as usize).map(|i| i as f64 / rate_hz).collect()
}

/// The shipped integrator setting (pipeline.toml's `[shared.integrator]`):
/// the synthetic campaigns are recorded with it and the estimation fits with it.
pub fn sim() -> SimOptions {
    SimOptions::from_pipeline_toml(include_str!("../../../../pipeline.toml"))
        .expect("pipeline.toml [shared.integrator]")
}

/// Runs of one kind, with noise from `rng`.
pub fn voltage_step(p: &RigParams, id: &str, v: f64, duration_s: f64, rng: &mut ChaCha8Rng) -> Run {
    let t = times(duration_s, 500.0);
    let tr = rig_model::simulate(p, &RunInput::VoltageStep { voltage_v: v }, &t, &sim()).expect("simulate step");
    let n = Normal::new(0.0, VOLTAGE_NOISE_V).unwrap();
    Run {
        id: id.into(),
        kind: RunKind::VoltageStep { voltage_v: v },
        file: format!("runs/{id}.csv").into(),
        data: RunData {
            motor_voltage_v: Some(tr.voltage_v.iter().map(|x| x + n.sample(rng)).collect()),
            motor_ticks: Some(ticks(&tr.motor_angle_rad)),
            rotor_ticks: Some(ticks(&tr.rotor_angle_rad)),
            brake_force_mv: None,
            time_s: t,
        },
    }
}

pub fn operating_point(p: &RigParams, id: &str, rpm: f64, n0: f64, duration_s: f64, rng: &mut ChaCha8Rng) -> Run {
    let t = times(duration_s, 500.0);
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n0, ramp_s: 2.0 };
    let tr = rig_model::simulate(p, &input, &t, &sim()).expect("simulate operating point");
    let nv = Normal::new(0.0, VOLTAGE_NOISE_V).unwrap();
    let nf = Normal::new(0.0, FORCE_NOISE_MV).unwrap();
    Run {
        id: id.into(),
        kind: RunKind::OperatingPoint { motor_rpm_setpoint: rpm, normal_force_n: n0, ramp_s: 2.0 },
        file: format!("runs/{id}.csv").into(),
        data: RunData {
            motor_voltage_v: Some(tr.voltage_v.iter().map(|x| x + nv.sample(rng)).collect()),
            motor_ticks: Some(ticks(&tr.motor_angle_rad)),
            rotor_ticks: Some(ticks(&tr.rotor_angle_rad)),
            brake_force_mv: Some(
                tr.friction_torque_nm
                    .iter()
                    .map(|tq| FORCE_OFFSET_MV + FORCE_FACTOR_MV_N * tq / p.brake_disc_radius_m + nf.sample(rng))
                    .collect(),
            ),
            time_s: t,
        },
    }
}

fn force_calibration(id: &str, load_n: f64, rng: &mut ChaCha8Rng) -> Run {
    let t = times(2.0, 500.0);
    let nf = Normal::new(0.0, FORCE_NOISE_MV).unwrap();
    let mv = t.iter().map(|_| FORCE_OFFSET_MV + FORCE_FACTOR_MV_N * load_n + nf.sample(rng)).collect();
    Run {
        id: id.into(),
        kind: RunKind::ForceCalibration { load_n },
        file: format!("runs/{id}.csv").into(),
        data: RunData { brake_force_mv: Some(mv), time_s: t, ..Default::default() },
    }
}

fn static_twist(p: &RigParams, id: &str, torque_nm: f64) -> Run {
    let t = times(2.0, 500.0);
    let angle = torque_nm / p.shaft_stiffness_nm_rad;
    Run {
        id: id.into(),
        kind: RunKind::StaticTwist { torque_nm },
        file: format!("runs/{id}.csv").into(),
        data: RunData { rotor_ticks: Some(ticks(&vec![angle; t.len()])), time_s: t, ..Default::default() },
    }
}

/// A campaign: force calibration, static twist, voltage steps `volts`
/// (`step_s` long) and the operating points `ops` (rpm, N0), `op_s` long.
pub fn campaign(p: &RigParams, volts: &[f64], step_s: f64, ops: &[(f64, f64)], op_s: f64, seed: u64) -> Campaign {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let mut runs = Vec::new();
    for (i, load) in [0.7, 2.0, 3.3, 4.4, 5.8].iter().enumerate() {
        runs.push(force_calibration(&format!("cal-{}", i + 1), *load, &mut rng));
    }
    for (i, tq) in [0.12, 0.17, 0.23, 0.29, 0.34].iter().enumerate() {
        runs.push(static_twist(p, &format!("twist-{}", i + 1), *tq));
    }
    for v in volts {
        runs.push(voltage_step(p, &format!("step-{v}v"), *v, step_s, &mut rng));
    }
    for (i, (rpm, n0)) in ops.iter().enumerate() {
        runs.push(operating_point(p, &format!("op-{:02}", i + 1), *rpm, *n0, op_s, &mut rng));
    }
    Campaign {
        name: format!("synthetic-{seed}"),
        description: "round-trip test campaign".into(),
        rig: RigInfo {
            encoder_ticks_per_rev: TICKS,
            brake_disc_radius_m: p.brake_disc_radius_m,
            supply_voltage_v: p.drive.limit_v,
            sample_rate_hz: 500.0,
        },
        runs,
    }
}
