//! Verdict ids and the tight per-parameter tolerances of the single-draw
//! hidden-effect tests (crates/virtual-rig/tests/hidden_effects.rs). The
//! many-campaign experiment is [`crate::battery`].

use crate::ids;

/// All verdict ids a diagnosis can return, in the matrix's column order.
/// The structural ids come between the vocabulary and `unexplained`.
pub const VERDICTS: [&str; 12] = [
    ids::NONE,
    ids::NORMAL_FORCE_MODULATION,
    ids::ANGLE_PERIODIC_FRICTION,
    ids::VELOCITY_WEAKENING_FRICTION,
    ids::VISCOUS_BRAKE_FRICTION,
    ids::DRIVE_VOLTAGE_LIMIT,
    ids::DAMPING_ROTOR_ABSOLUTE,
    ids::CHANNEL_DELAY,
    ids::FORCE_SENSOR_DYNAMICS,
    ids::ENCODER_COUPLING_COMPLIANCE,
    ids::UNEXPLAINED,
    "error",
];

/// Tolerance on the relative error of each parameter that the hidden-effect
/// tests require (stated once; confusion.md prints it).
pub fn tolerance(param: &str) -> f64 {
    match param {
        "order" => 0.0,
        "frequency_hz" => 0.01,
        "mu_kinetic" | "mu_static" | "limit_v" => 0.05,
        "amplitude_ratio" => 0.15,
        "stribeck_speed_rad_s" | "viscous_per_rad_s" => 0.2,
        _ => 0.1,
    }
}
