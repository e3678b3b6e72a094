//! Verdict ids and the tight per-parameter tolerances of the single-draw
//! hidden-effect tests (crates/virtual-rig/tests/hidden_effects.rs). The
//! many-campaign experiment is [`crate::battery`].

/// All verdict ids a diagnosis can return, in the matrix's column order.
pub const VERDICTS: [&str; 8] = [
    "none",
    "normal_force_modulation",
    "angle_periodic_friction",
    "velocity_weakening_friction",
    "viscous_brake_friction",
    "drive_voltage_limit",
    "unexplained",
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
