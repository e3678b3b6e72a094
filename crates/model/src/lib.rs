//! The rig equations (thesis Eqs. 4-6 to 4-11), friction laws, the PI drive and
//! an adaptive, error-controlled integrator with stick/slip event location.
//! No IO: parameters in, trajectory out.
//!
//! CONTRACT (other crates code against these names; extend, do not rename):
//! - [`simulate`] one run at the recording's sample times;
//! - [`simulate_from`] continue from a [`State`] under a constant set-point
//!   (sweeps: each point starts from the previous point's end state);
//! - [`friction_coefficient`] μ(Ω1) of a law (Fig. 4.15);
//! - [`SimOptions`], [`State`], [`ModelError`].

pub mod one_dof;

use rig_types::{FrictionLaw, RigParams, RunInput, Trajectory};

/// Integrator settings. Tolerances are explicit arguments, never globals.
#[derive(Debug, Clone, PartialEq)]
pub struct SimOptions {
    pub rtol: f64,
    pub atol: f64,
    /// Largest step the integrator may take, s.
    pub max_step_s: f64,
}

impl Default for SimOptions {
    fn default() -> Self {
        SimOptions { rtol: 1e-8, atol: 1e-10, max_step_s: 0.01 }
    }
}

/// Full state of the rig model at one instant (enough to continue a run).
#[derive(Debug, Clone, Default, PartialEq)]
pub struct State {
    pub time_s: f64,
    pub rotor_angle_rad: f64,
    pub rotor_speed_rad_s: f64,
    pub motor_angle_rad: f64,
    pub motor_speed_rad_s: f64,
    pub current_a: f64,
    /// Integral of the PI speed error, rad.
    pub pi_integral_rad: f64,
    pub stuck: bool,
}

#[derive(Debug, thiserror::Error, PartialEq)]
pub enum ModelError {
    #[error("invalid parameter {name} = {value}: {rule}")]
    InvalidParameter { name: &'static str, value: f64, rule: &'static str },
    #[error("sample times must be finite and strictly increasing from >= 0 (index {index})")]
    BadSampleTimes { index: usize },
    #[error("integrator failed at t = {time_s} s: {reason}")]
    IntegratorFailed { time_s: f64, reason: String },
}

/// Simulates one run from rest (all states zero at t = 0) and samples it at
/// `sample_times_s`.
pub fn simulate(
    params: &RigParams,
    input: &RunInput,
    sample_times_s: &[f64],
    opts: &SimOptions,
) -> Result<Trajectory, ModelError> {
    let _ = (params, input, sample_times_s, opts);
    todo!("rig-model: simulate")
}

/// Continues from `state` with the drive holding a constant motor-speed set-point
/// (no ramp) and normal force `normal_force_n`, sampling at `sample_times_s`
/// (absolute times, all >= state.time_s). Returns the trajectory and the end state.
pub fn simulate_from(
    params: &RigParams,
    state: &State,
    motor_rpm_setpoint: f64,
    normal_force_n: f64,
    sample_times_s: &[f64],
    opts: &SimOptions,
) -> Result<(Trajectory, State), ModelError> {
    let _ = (params, state, motor_rpm_setpoint, normal_force_n, sample_times_s, opts);
    todo!("rig-model: simulate_from")
}

/// Friction coefficient μ of `law` at rotor speed `omega_rad_s` in slip (Fig. 4.15).
pub fn friction_coefficient(law: &FrictionLaw, omega_rad_s: f64) -> f64 {
    let _ = (law, omega_rad_s);
    todo!("rig-model: friction_coefficient")
}
