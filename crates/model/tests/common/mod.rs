//! Parameter sets shared by the rig-model proof tests: Table 4.5 with the
//! chapter's damping, as the thesis model and as the rig model (n = 8).
#![allow(dead_code)]

use rig_model::SimOptions;
use rig_types::{DriveParams, FrictionLaw, ModelKind, MotorParams, RigParams, ThesisFriction};

/// C = 2 ξ √(J1 K) with the chapter's mean ξ = 0.098 (Table 4.2) and Table 4.5.
pub fn thesis_damping() -> f64 {
    2.0 * 0.098 * (0.0298f64 * 0.2710).sqrt()
}

pub fn table_4_5_motor(gear_ratio: f64) -> MotorParams {
    MotorParams {
        inertia_kgm2: 4.698e-4,
        inductance_h: 8.437e-4,
        resistance_ohm: 0.526,
        torque_constant_nm_a: 0.126,
        voltage_constant_v_s_rad: 0.0588,
        friction_torque_nm: 0.1,
        speed_regulation_nm_s_rad: 1.784e-4,
        gear_ratio,
    }
}

pub fn table_4_7() -> ThesisFriction {
    ThesisFriction {
        mu_static: 1.6,
        mu_dynamic: 1.2,
        mu_negative: -0.2,
        tolerance: 0.001,
        static_setpoint_rpm: 0.05,
        dynamic_setpoint_rpm: 0.5,
    }
}

/// The thesis model as published (PI gains are not published: ours).
pub fn thesis_params() -> RigParams {
    rig_model::thesis_model_params(&rig_model::ThesisModelInputs {
        motor: table_4_5_motor(8.0),
        rotor_inertia_kgm2: 0.0298,
        shaft_stiffness_nm_rad: 0.2710,
        damping_ratio: 0.098,
        friction: table_4_7(),
        brake_disc_radius_m: 0.062,
        drive: DriveParams { kp_v_s_rad: 1.0, ki_v_rad: 5.0, limit_v: 24.0 },
    })
}

/// The rig model: Table 4.5, n = 8, Coulomb brake μs 0.5 / μk 0.35.
pub fn rig_params() -> RigParams {
    RigParams {
        kind: ModelKind::Rig,
        shaft_damping_nm_s_rad: thesis_damping(),
        rotor_damping_nm_s_rad: 0.0,
        motor: table_4_5_motor(8.0),
        drive: DriveParams { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 24.0 },
        friction: FrictionLaw::Coulomb { mu_static: 0.5, mu_kinetic: 0.35 },
        ..thesis_params()
    }
}

pub fn grid(t_end_s: f64, rate_hz: f64) -> Vec<f64> {
    let n = (t_end_s * rate_hz).round() as usize;
    (0..=n).map(|k| k as f64 / rate_hz).collect()
}

/// The shipped integrator setting: pipeline.toml's `[shared.integrator]`.
/// Parsed on a thread of its own, so that its allocations go to that
/// thread's malloc arena: a bench or `cpu_time` that reads it starts from
/// the heap it started from when the setting was a code default (parsed on
/// the main thread, the toml left glibc's main arena so that a fresh 500 Hz
/// thesis-model trajectory in `cpu_time` faulted 241 pages a run instead of
/// 0 and cost 0.86 ms of CPU instead of 0.36).
pub fn shipped() -> SimOptions {
    std::thread::spawn(|| SimOptions::from_pipeline_toml(include_str!("../../../../pipeline.toml")))
        .join()
        .expect("reading pipeline.toml")
        .expect("pipeline.toml [shared.integrator]")
}

/// A tolerance chosen by a test, not the shipped one (a convergence study, a
/// reference tighter than the shipped setting, a proof that needs more digits):
/// rtol `rtol`, atol `rtol`/100, the shipped largest step.
pub fn at_rtol(rtol: f64) -> SimOptions {
    SimOptions { rtol, atol: rtol * 1e-2, ..shipped() }
}
