//! Parameter sets for the sweep tests: the same Table 4.5 values as
//! rig-model's proof tests (crates/model/tests/common), as thesis and rig models.
#![allow(dead_code)]

use rig_model::SimOptions;
use rig_sweep::{ClassifyOptions, SweepSettings, WindowSpec};
use rig_types::{DriveParams, FrictionLaw, ModelKind, MotorParams, RigParams, ThesisFriction};

fn table_4_5_motor(gear_ratio: f64) -> MotorParams {
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

/// The thesis model as published (Table 4.5, ξ = 0.098, Table 4.7; PI gains not published).
pub fn thesis_params() -> RigParams {
    rig_model::thesis_model_params(&rig_model::ThesisModelInputs {
        motor: table_4_5_motor(1.0),
        rotor_inertia_kgm2: 0.0298,
        shaft_stiffness_nm_rad: 0.2710,
        damping_ratio: 0.098,
        friction: ThesisFriction {
            mu_static: 1.6,
            mu_dynamic: 1.2,
            mu_negative: -0.2,
            tolerance: 0.001,
            static_setpoint_rpm: 0.05,
            dynamic_setpoint_rpm: 0.5,
        },
        brake_disc_radius_m: 0.062,
        drive: DriveParams { kp_v_s_rad: 1.0, ki_v_rad: 5.0, limit_v: 24.0 },
    })
}

/// The rig model: Table 4.5, n = 8, Coulomb brake μs 0.5 / μk 0.35.
pub fn rig_params() -> RigParams {
    RigParams {
        kind: ModelKind::Rig,
        shaft_damping_nm_s_rad: 2.0 * 0.098 * (0.0298f64 * 0.2710).sqrt(),
        rotor_damping_nm_s_rad: 0.0,
        motor: table_4_5_motor(8.0),
        drive: DriveParams { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 24.0 },
        friction: FrictionLaw::Coulomb { mu_static: 0.5, mu_kinetic: 0.35 },
        ..thesis_params()
    }
}

pub fn settings(first_transient_s: f64, transient_s: f64, window_s: f64) -> SweepSettings {
    SweepSettings {
        window: WindowSpec { first_transient_s, transient_s, window_s, sample_rate_hz: 100.0 },
        // The shipped integrator: pipeline.toml's [shared.integrator].
        sim: SimOptions::from_pipeline_toml(include_str!("../../../../pipeline.toml")).expect("pipeline.toml"),
        classify: ClassifyOptions::default(),
    }
}
