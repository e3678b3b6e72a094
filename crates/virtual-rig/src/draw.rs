//! Seeded draws of the truth: rig parameters in plausible ranges around the
//! thesis' Table 4.5 (with the 8:1 gearbox), the sensor chain, and the hidden effect.

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rig_types::{DriveParams, Effect, FrictionLaw, ModelKind, MotorParams, RigParams};

/// The effect hidden in a campaign, with the parameters the diagnosis must recover.
#[derive(Debug, Clone, PartialEq)]
pub enum Hidden {
    None,
    NormalForceModulation {
        amplitude_ratio: f64,
        frequency_hz: f64,
    },
    AnglePeriodicFriction {
        amplitude_ratio: f64,
        order: u32,
    },
    VelocityWeakening {
        mu_static: f64,
        mu_kinetic: f64,
        stribeck_speed_rad_s: f64,
    },
    ViscousBrake {
        mu_kinetic: f64,
        viscous_per_rad_s: f64,
    },
    DriveVoltageLimit {
        limit_v: f64,
    },
    /// Outside the vocabulary: the diagnosis must answer `unexplained`.
    MotorCogging {
        amplitude_nm: f64,
        order: u32,
    },
}

impl Hidden {
    /// The verdict a correct diagnosis returns.
    pub fn id(&self) -> &'static str {
        match self {
            Hidden::None => "none",
            Hidden::NormalForceModulation { .. } => "normal_force_modulation",
            Hidden::AnglePeriodicFriction { .. } => "angle_periodic_friction",
            Hidden::VelocityWeakening { .. } => "velocity_weakening_friction",
            Hidden::ViscousBrake { .. } => "viscous_brake_friction",
            Hidden::DriveVoltageLimit { .. } => "drive_voltage_limit",
            Hidden::MotorCogging { .. } => "unexplained",
        }
    }

    /// True parameters under the JSON keys of diagnosis.md.
    pub fn params(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Hidden::None | Hidden::MotorCogging { .. } => vec![],
            Hidden::NormalForceModulation { amplitude_ratio, frequency_hz } => {
                vec![("amplitude_ratio", amplitude_ratio), ("frequency_hz", frequency_hz)]
            }
            Hidden::AnglePeriodicFriction { amplitude_ratio, order } => {
                vec![("amplitude_ratio", amplitude_ratio), ("order", order as f64)]
            }
            Hidden::VelocityWeakening { mu_static, mu_kinetic, stribeck_speed_rad_s } => vec![
                ("mu_static", mu_static),
                ("mu_kinetic", mu_kinetic),
                ("stribeck_speed_rad_s", stribeck_speed_rad_s),
            ],
            Hidden::ViscousBrake { mu_kinetic, viscous_per_rad_s } => {
                vec![("mu_kinetic", mu_kinetic), ("viscous_per_rad_s", viscous_per_rad_s)]
            }
            Hidden::DriveVoltageLimit { limit_v } => vec![("limit_v", limit_v)],
        }
    }

    /// The classes in the order of the confusion matrix.
    pub const CLASSES: [&'static str; 7] = [
        "none",
        "normal_force_modulation",
        "angle_periodic_friction",
        "velocity_weakening_friction",
        "viscous_brake_friction",
        "drive_voltage_limit",
        "motor_cogging",
    ];
}

/// Everything the virtual rig knows and the diagnosis must not.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    pub params: RigParams,
    pub hidden: Hidden,
    pub supply_voltage_v: f64,
    pub force_factor_mv_per_n: f64,
    pub force_offset_mv: f64,
    pub force_noise_mv: f64,
    pub voltage_noise_v: f64,
}

/// Draws a hidden effect of class `class` (one of [`Hidden::CLASSES`]) with
/// random parameters in ranges where it matters on this rig. `mu_kinetic` is
/// the rig's slip coefficient (the laws are built around it).
pub fn draw_hidden(class: &str, mu_kinetic: f64, max_setpoint_rpm: f64, seed: u64) -> Hidden {
    let mut r = ChaCha8Rng::seed_from_u64(seed ^ 0x5eed_0f_4e55);
    match class {
        "normal_force_modulation" => Hidden::NormalForceModulation {
            amplitude_ratio: r.random_range(0.08..0.3),
            frequency_hz: r.random_range(0.5..3.0),
        },
        "angle_periodic_friction" => {
            Hidden::AnglePeriodicFriction { amplitude_ratio: r.random_range(0.08..0.3), order: r.random_range(1..=6) }
        }
        "velocity_weakening_friction" => Hidden::VelocityWeakening {
            mu_static: mu_kinetic * r.random_range(1.3..1.8),
            mu_kinetic,
            stribeck_speed_rad_s: r.random_range(0.8..4.0),
        },
        "viscous_brake_friction" => Hidden::ViscousBrake {
            mu_kinetic,
            // 10–40 % more friction at 10 rad/s of slip.
            viscous_per_rad_s: mu_kinetic * r.random_range(0.01..0.04),
        },
        "drive_voltage_limit" => {
            // Armature back-EMF at the highest set-point with the default motor (n = 8, k_e ≈ 0.0588):
            // a limit between 45 % and 80 % of it saturates the fast runs.
            let w_arm = 8.0 * max_setpoint_rpm * 2.0 * std::f64::consts::PI / 60.0;
            Hidden::DriveVoltageLimit { limit_v: 0.0588 * w_arm * r.random_range(0.45..0.8) }
        }
        "motor_cogging" => {
            Hidden::MotorCogging { amplitude_nm: r.random_range(0.08..0.2), order: r.random_range(2..=6) }
        }
        _ => Hidden::None,
    }
}

/// Draws the rig (seeded, plausible ranges) and builds the truth model with `class` hidden.
pub fn draw_truth(class: &str, max_setpoint_rpm: f64, seed: u64) -> Truth {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let mut u = |lo: f64, hi: f64| r.random_range(lo..hi);
    let j1 = 0.0298 * u(0.9, 1.1);
    let k = 0.271 * u(0.9, 1.1);
    let xi = u(0.06, 0.12);
    let mu_k = u(0.3, 0.6);
    let mu_s = mu_k * u(1.2, 1.5);
    let motor = MotorParams {
        inertia_kgm2: 4.698e-4 * u(0.9, 1.1),
        inductance_h: 8.437e-4 * u(0.9, 1.1),
        resistance_ohm: 0.526 * u(0.9, 1.1),
        torque_constant_nm_a: 0.126 * u(0.95, 1.05),
        voltage_constant_v_s_rad: 0.0588 * u(0.95, 1.05),
        friction_torque_nm: 0.1 * u(0.7, 1.3),
        speed_regulation_nm_s_rad: 1.784e-4 * u(0.8, 1.2),
        gear_ratio: 8.0,
    };
    let drive = DriveParams { kp_v_s_rad: u(1.5, 3.0), ki_v_rad: u(6.0, 15.0), limit_v: 24.0 };
    let truth_extra = (u(190.0, 240.0), u(-8.0, 8.0), u(1.0, 3.0), u(0.01, 0.04));
    let hidden = draw_hidden(class, mu_k, max_setpoint_rpm, seed);
    let mut params = RigParams {
        kind: ModelKind::Rig,
        rotor_inertia_kgm2: j1,
        shaft_stiffness_nm_rad: k,
        shaft_damping_nm_s_rad: 2.0 * xi * (j1 * k).sqrt(),
        motor,
        drive,
        friction: FrictionLaw::Coulomb { mu_static: mu_s, mu_kinetic: mu_k },
        brake_disc_radius_m: 0.062,
        effects: vec![],
        harmonic: None,
    };
    match hidden {
        Hidden::None => {}
        Hidden::NormalForceModulation { amplitude_ratio, frequency_hz } => {
            params.effects.push(Effect::NormalForceModulation { amplitude_ratio, frequency_hz, phase_rad: 0.0 })
        }
        Hidden::AnglePeriodicFriction { amplitude_ratio, order } => {
            params.effects.push(Effect::AnglePeriodicFriction { amplitude_ratio, order, phase_rad: 0.0 })
        }
        Hidden::VelocityWeakening { mu_static, mu_kinetic, stribeck_speed_rad_s } => {
            params.friction = FrictionLaw::Stribeck { mu_static, mu_kinetic, stribeck_speed_rad_s }
        }
        Hidden::ViscousBrake { mu_kinetic, viscous_per_rad_s } => {
            params.friction = FrictionLaw::Viscous { mu_static: mu_s, mu_kinetic, viscous_per_rad_s }
        }
        Hidden::DriveVoltageLimit { limit_v } => params.drive.limit_v = limit_v,
        Hidden::MotorCogging { amplitude_nm, order } => {
            params.effects.push(Effect::MotorCogging { amplitude_nm, order, phase_rad: 0.0 })
        }
    }
    Truth {
        params,
        hidden,
        supply_voltage_v: 24.0,
        force_factor_mv_per_n: truth_extra.0,
        force_offset_mv: truth_extra.1,
        force_noise_mv: truth_extra.2,
        voltage_noise_v: truth_extra.3,
    }
}
