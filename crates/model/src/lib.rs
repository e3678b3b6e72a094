//! The rig equations (thesis Eqs. 4-6 to 4-11), friction laws, the PI drive and
//! an adaptive, error-controlled integrator with stick/slip event location.
//! No IO: parameters in, trajectory out.
//!
//! CONTRACT (other crates code against these names; extend, do not rename):
//! - [`simulate`] one run at the recording's sample times ([`simulate_channels`]:
//!   without the friction torque's channel, for a caller that reads only the
//!   motion and the drive);
//! - [`simulate_from`] continue from a [`State`] under a constant set-point
//!   (sweeps: each point starts from the previous point's end state);
//! - [`friction_coefficient`] μ(Ω1) of a law (Fig. 4.15);
//! - [`SimOptions`], [`State`], [`ModelError`].
//!
//! # The equations and how the chapter's were read
//!
//! State q = [φ1, φ2, Ω1, Ω2, i, ∫e] (Eq. 4-9's five states plus the PI
//! integral). Angles and speeds are at the shaft: φ2, Ω2 are the motor-side
//! end of the string (the motor encoder after the gearbox), never the armature.
//!
//! - **Eq. 4-6a** L di/dt + R i + k_e·(n Ω2) = V: the back-EMF is that of the
//!   armature speed n·Ω2.
//! - **Eq. 4-6b / 4-7 second row** n²J_m Ω̇2 = n·(k_T i − T_f − C_m·n·Ω2) − T_s
//!   (+ cogging), T_s the torque the shaft transmits: the armature torque
//!   reaches the shaft multiplied by n and the armature inertia reflected by
//!   n². With n = 1 this is Eq. 4-7's second row exactly.
//! - **Eq. 4-7 first row** J1 Ω̇1 = T_s − C_abs·Ω1 − T1.
//! - **Eq. 4-9 is not consistent as printed** and is not used as a matrix:
//!   its third block row puts −J⁻¹K and −J⁻¹C side by side in one row of a
//!   5-column matrix (they are the 2×2 blocks of *two* rows, Ω̇1 and Ω̇2); the
//!   Ω̇2 row has no k_T/J_m coupling from i although Eq. 4-7 has k_T i on the
//!   right-hand side; the di/dt row reads −k_e/L in the Ω2 column only by
//!   position and −R/L on i, while F carries −T_f/J_m in the Ω2 row and V/L in
//!   the i row. We implement what Eqs. 4-6 and 4-7 say, which is what the
//!   matrix must have meant: rows φ̇ = Ω; Ω̇1 and Ω̇2 from the two rows of 4-7
//!   (with +k_T i/J_m in Ω̇2); di/dt = (V − R i − k_e Ω2)/L.
//! - **Thesis model** ([`rig_types::ModelKind::Thesis`]): Table 4.5 parameters,
//!   gear n = 1 (the chapter ignores the gearbox), T_s = K(φ2 − φ1),
//!   C_abs = C = 2ξ√(J1 K) on Ω1 (absolute, as Eq. 4-7's diagonal C), T_f a
//!   constant torque (as Eq. 4-6b writes it), T1 from the Eq. 4-10 lookup
//!   with no stick phase, PI drive from `params.drive`.
//! - **Rig model** ([`rig_types::ModelKind::Rig`]): explicit gear n;
//!   T_s = K(φ2 − φ1) + C(Ω2 − Ω1) — string material damping acts on the twist
//!   rate, not on absolute speed, so that a rotor turning with the motor at
//!   constant speed feels no drag (with C on Ω1 the open-brake steady state
//!   would need a permanent twist C·Ω1/K ≈ 1 rad at 16 rad/s, which the
//!   voltage steps do not show); T_f·tanh(n Ω2 / 1 rad/s) so motor friction
//!   opposes motion (see [`MOTOR_FRICTION_SPEED_RAD_S`]); a stick
//!   phase for rotor 1 (below).
//!
//! The chapter's "8 V ≈ 16 rad/s" fixes n: the open-brake steady speed under
//! constant V solves V = R i + k_e n Ω, k_T i = T_f + C_m n Ω (no load at the
//! shaft in steady rotation), Ω = (V − R T_f/k_T) / (n (k_e + R C_m / k_T)).
//! With Table 4.5 and n = 1 that is 127 rad/s at 8 V; with the 8:1 gearbox
//! n = 8 it is 15.9 rad/s — the chapter's 16 rad/s. The gearbox was in the rig
//! even though it was "not considered" in the equations.
//!
//! # Friction
//!
//! **As published (Eq. 4-10, Table 4.7).** The three cases overlap (Ω1 < Tol
//! and Ω1 < 0), Tol = 0.001 has no unit and Table 4.7 gives set-points of
//! 0.05 and 0.5 rpm that Eq. 4-10 does not mention. We read the table the way
//! a Simulink lookup block would use it: breakpoints in rotor rpm
//! (0 → μneg, 0.05 → μst, 0.5 → μdyn), linear in between, constant outside,
//! μneg for all Ω1 ≤ 0 (the "≤ 0" set-point; the more specific case wins).
//! Tol is then inside the first segment whatever its unit (0.001 rpm or
//! 0.001 rad/s = 0.0095 rpm are both below the 0.05 rpm set-point) and is not
//! used. Without a stick phase this law makes the rotor *creep* instead of
//! stick: the lookup rises by 1.8 over 0.05 rpm, a slope of ≈ 344 per rad/s,
//! so near Ω1 = 0 the rotor equation has an eigenvalue of order
//! −344·N·r/J1 (≈ −1.8·10⁴ 1/s at 25 N). An explicit method steps at
//! ≈ 10⁻⁴ s through every "stick" phase (that is the chatter a fixed-step
//! Simulink run shows as a rattling T1); the adaptive steps keep it stable and
//! accurate, at the price of ~10⁴ steps per stuck second. Negative speeds see
//! only 0.2·N·r (μneg = −0.2 gives T1 = −0.2 N r, i.e. opposing the motion
//! with a sixth of the forward friction): the published law is not symmetric.
//!
//! **Rig model.** Friction torque T1 = sign·μ(|Ω1|)·N·r in slip (symmetric in
//! the sign of Ω1; μ from [`rig_types::FrictionLaw`]). Stick phase: rotor 1 is
//! held (Ω1 = 0 exactly, φ1 frozen, T1 = T_s) while |T_s| ≤ μs·N·r; the
//! transitions are *events* located on the dense output by root finding:
//! stick → slip where |T_s| − μs N r crosses zero upwards (slip starts in the
//! direction of T_s), slip → stick where Ω1 crosses zero (the rotor sticks if
//! |T_s| ≤ μs N r there, otherwise it reverses). The integrator restarts at
//! each event. With N0 = 0 (brake open) there is no friction and no event.
//!
//! **Effects.** N(t, φ1) = N0·Π(1 + a sin(2πft + θ))·Π(1 + a sin(nφ1 + θ)) for
//! `NormalForceModulation` and `AnglePeriodicFriction`; the stick threshold
//! follows N. `MotorCogging` adds τ sin(nφ2 + θ) to the motor side at the
//! shaft. Harmonic friction (Eq. 4-11): `MultiplyTorque` multiplies T1 by
//! sin(ω_p t) as published (in the rig model the stick threshold by
//! |sin(ω_p t)|); `NormalForce` multiplies N by 1 + a sin(ω_p t).
//!
//! **Effects outside the vocabulary** (test campaigns of the virtual rig; each
//! variant's doc in [`rig_types::Effect`] gives its equation and source):
//! `CouplingBacklash` and `ShaftCubicStiffness` replace the linear shaft by
//! K·δe(1 + β δe²) with δe the twist outside a dead zone of half-width b
//! (damping only in contact); `RotorImbalance` subtracts m·e·g·sin(φ1 + θ)
//! from the torque on rotor 1, which static friction must then also hold;
//! `BrakeFade` adds a seventh state, the pad temperature rise ϑ with
//! C dϑ/dt = T1 Ω1 − C ϑ/τ, and divides N (so μs and μ alike) by
//! 1 + ϑ/ϑ_fade; the error norm covers ϑ only when the effect is present, so
//! every run without it takes exactly the steps it took before; it is not
//! part of [`State`] (a continuation starts cold). `StaticFrictionAging`
//! uses the same seventh state as the stuck contact's age (dt/dt = 1 in
//! stick, held in slip, reset to 0 each time rotor 1 comes to rest) and
//! raises the stick threshold to (μs + B ln(1 + age/τ))·N·r: a break-away
//! event whose threshold grows while stuck, found by the same root finder.
//! `FrictionExtension`, the diagnosis' data-driven term of an `unexplained`
//! answer ([`extension`]), uses the seventh state as the time since the last
//! stick/slip event (dt/dt = 1 in both modes, reset to 0 at every event) and
//! multiplies μ in slip and μs at break-away by factors linear in its
//! library's signals. `DriveCurrentLimit` clamps
//! the terminal voltage to n k_e Ω2 ± R I_max after the PI loop, whose
//! integral does not see it (windup), and in voltage steps too.
//!
//! # Drive
//!
//! Operating points: a PI loop on Ω2 (rad/s at the shaft), reference ramping
//! linearly 0 → `motor_rpm_setpoint` (rpm at the shaft, the motor encoder
//! side) over `ramp_s`, V = clamp(kp e + ki ∫e, ±limit_v). Anti-windup by
//! back-calculation, d(ki∫e)/dt = ki e + (V − V_raw)/T_t with
//! T_t = [`ANTI_WINDUP_TRACKING_S`]; conditional integration was tried and
//! rejected because its switching right-hand side makes the integral slide
//! on the saturation boundary and the adaptive step collapse. Voltage steps: V constant, drive
//! bypassed, brake open (N = 0).
//!
//! # Trajectory channels
//!
//! Every channel is interpolated on the dense output at the requested times.
//! `friction_torque_nm` is T1 (positive opposes positive Ω1): the slip law in
//! slip, the balancing shaft torque in stick. `stuck` is the stick phase of
//! the rig model; the thesis model has none, so there it marks the static
//! branch of its lookup (|Ω1| below the static set-point, 0.05 rpm), the
//! closest thing the published model has to a standstill.
//!
//! # Integrator
//!
//! Two kinds of step, both ending on the sample grid where they can:
//!
//! - **Exact steps** (module `exact`). Away from events and from the few
//!   switches inside the right-hand side, the equations are linear in the
//!   state with a forcing affine in t: the PI loop unsaturated or clamped,
//!   the rig model's motor friction on its saturated branch ±T_f (|n Ω2| ≥
//!   15 rad/s at the armature, where 1 − tanh drops < 2·10⁻¹³ T_f), a
//!   Coulomb or viscous brake in slip, held in stick or open, a segment of the
//!   thesis lookup, no effects (but the diagnosis' friction extension with
//!   its break-away terms alone: the motion is the plain model's, its
//!   threshold is the stick mode's event, and an exact step advances its pad
//!   state, the time since the last event, by the step's length; test
//!   `break_away_terms_alone_take_exact_steps_and_age_the_contact`; and,
//!   with the brake open, effects that act through the contact alone — N's
//!   modulations, harmonic friction, ageing, the extension — where T1 = 0
//!   leaves the plain model's motion: a voltage step of such a model, e.g.
//!   a motor-side refit's, takes the plain model's steps, tests
//!   `open_brake.rs`). There,
//!   with z = [q, t, 1], ż = M z and a step
//!   is z(t + h) = e^{M h} z(t), exact to rounding whatever h and however stiff
//!   the drive (the armature's R/L and the PI loop, −300…−600 1/s, or the
//!   thesis lookup's creep slope, ≈ −1.8·10⁴ 1/s). e^{M h} is computed once
//!   per (region, h) by scaling and squaring and cached, so a uniform sample
//!   grid costs one 6 × 8 matrix-vector product per sample. A step is taken
//!   only if it ends in the region it started in and no event function
//!   changed sign; its length is min(`max_step_s`, next sample, breakpoint).
//!   Steps that follow one another with the same propagator run in an inner
//!   loop with the state in registers, and the samples of consecutive blocks
//!   are appended to the trajectory together, channel by channel.
//! - **Dormand–Prince 5(4) steps** (module `dopri`), with Hairer's PI step
//!   control and 4th-order dense output, everywhere else: across an event
//!   (located on the dense output by the Illinois method and restarting
//!   there, as before), across a switch of the piecewise-affine right-hand
//!   side (the voltage clamp, a kink of the lookup — located the same way, so
//!   that no step integrates across a kink), and wherever the equations are
//!   not affine (effects, the Stribeck law, the motor friction's tanh at low
//!   armature speed, brake fade). The drive's fast modes (|λ| ≤ 480 1/s)
//!   would allow ≈ 7 ms; in the knee of the motor friction's tanh
//!   (|n Ω2| ≲ 3 rad/s at the armature) the step is held to ≈ 1.1 ms by
//!   accuracy instead, the armature current following T_f·tanh(n Ω2): 87,
//!   200 and 484 steps in the first 0.2 s at rtol 10⁻⁶, 10⁻⁸ and 10⁻¹⁰
//!   (tol^(−1/5)). Neither a higher order (scipy's DOP853 needs 2030
//!   evaluations to 0.9 s where RK45 needs 2024) nor an exponential
//!   integrator with the linear drive exact (Cox–Matthews ETDRK4: 400–750
//!   times the tolerance at h = 1 ms, the tanh's slope being explicit) does better.
//!
//! Measured (example `cpu_time`, criterion bench `simulate`): the rig model at
//! 40 rpm / 15 N takes 3904 exact and 351 Dormand–Prince steps for 40 s
//! sampled once (19 520 exact steps sampled at 500 Hz); the Dormand–Prince
//! steps fall in the first 1.9 s, while the motor turns slower than 15 rad/s
//! at the armature. Before the exact steps it took 4291 Dormand–Prince steps. At
//! the default tolerance, stick-slip peaks, break-aways and period stay
//! within 10⁻¹⁰ of a run at rtol 10⁻¹³ (test
//! `default_tolerance_is_within_a_tenth_of_a_percent_of_a_tight_reference`),
//! and a run at rtol 10⁻¹⁰ is within 1e-6 of scipy's DOP853 (`scipy_crosscheck`).
//! Samples are taken at step ends or on the dense output, so the sample rate
//! does not constrain the Dormand–Prince step. The end of the reference ramp
//! is a breakpoint. Failures (non-finite state, step below round-off, more
//! than the step budget [`MAX_STEPS`] + [`MAX_STEPS_PER_S`]·duration of
//! Dormand–Prince steps, events that do not advance time) are
//! [`ModelError::IntegratorFailed`], never a hang or a panic.

mod dopri;
mod exact;
pub mod extension;
pub mod friction;
pub mod one_dof;
mod sim;
mod system;

pub use sim::{MAX_STEPS, MAX_STEPS_PER_S, SimStats};
pub use system::{ANTI_WINDUP_TRACKING_S, MOTOR_FRICTION_SPEED_RAD_S};

use rig_types::{
    DriveParams, Effect, FrictionLaw, HarmonicFriction, ModelKind, MotorParams, RigParams, RunInput, ThesisFriction,
    Trajectory,
};
use system::{Drive, System};

/// Integrator settings. Tolerances are explicit arguments, never globals,
/// and have no default in code: pipeline.toml declares them once, in its
/// `[shared.integrator]` table (the stages are handed it; tests, benches and
/// examples read it with [`SimOptions::from_pipeline_toml`]). Tidy
/// `integrator_tolerances_have_one_home` (crates/pipeline/tests/tidy.rs).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SimOptions {
    pub rtol: f64,
    pub atol: f64,
    /// Largest step the integrator may take, s.
    pub max_step_s: f64,
}

impl SimOptions {
    /// The shipped setting: the `[shared.integrator]` table of a
    /// pipeline.toml text (the workspace's: `include_str!` of its root's
    /// pipeline.toml).
    pub fn from_pipeline_toml(text: &str) -> Result<SimOptions, String> {
        rig_types::pipeline_toml::shared_table(text, "integrator")
    }
}

/// The channels a run writes: all of them, or all but the brake's friction
/// torque T1, left empty. T1 is an output only (the integration never reads
/// a sample), so every other channel is the same to the bit either way; its
/// samples cost a friction law at every sample time (under a normal-force
/// modulation a `sin` each), which a caller that reads only the motion and
/// the drive need not pay (the diagnosis' held-out free runs).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Default)]
pub enum Channels {
    #[default]
    All,
    WithoutFriction,
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
    simulate_with_stats(params, input, sample_times_s, opts).map(|(traj, _)| traj)
}

/// [`simulate`] writing only `channels` ([`Channels`]).
pub fn simulate_channels(
    params: &RigParams,
    input: &RunInput,
    sample_times_s: &[f64],
    opts: &SimOptions,
    channels: Channels,
) -> Result<Trajectory, ModelError> {
    let mut traj = Trajectory::default();
    simulate_into_channels(params, input, sample_times_s, (opts, channels), &mut traj)?;
    Ok(traj)
}

/// [`simulate`] that also returns the integrator's counters (benches, tests).
pub fn simulate_with_stats(
    params: &RigParams,
    input: &RunInput,
    sample_times_s: &[f64],
    opts: &SimOptions,
) -> Result<(Trajectory, SimStats), ModelError> {
    let mut traj = Trajectory::default();
    let stats = simulate_into(params, input, sample_times_s, opts, &mut traj)?;
    Ok((traj, stats))
}

/// [`simulate_with_stats`] into `out`, whose channels are emptied and refilled
/// (their allocations reused): a batch of runs (a map, a campaign) that keeps
/// one trajectory per thread writes its samples into memory it already owns,
/// instead of faulting in fresh pages for every run (at 500 Hz over 40 s the
/// nine channels are 1.4 MB). After an error `out` holds no complete run: the
/// samples before an integrator failure, or, for rejected input, what it held before.
pub fn simulate_into(
    params: &RigParams,
    input: &RunInput,
    sample_times_s: &[f64],
    opts: &SimOptions,
    out: &mut Trajectory,
) -> Result<SimStats, ModelError> {
    simulate_into_channels(params, input, sample_times_s, (opts, Channels::All), out)
}

/// [`simulate_into`] writing only `channels`.
fn simulate_into_channels(
    params: &RigParams,
    input: &RunInput,
    sample_times_s: &[f64],
    (opts, channels): (&SimOptions, Channels),
    out: &mut Trajectory,
) -> Result<SimStats, ModelError> {
    validate(params, opts)?;
    check_samples(sample_times_s, 0.0)?;
    let (drive, n0, breakpoints) = match *input {
        RunInput::VoltageStep { voltage_v } => {
            finite("voltage_v", voltage_v)?;
            (Drive::Voltage { voltage_v }, 0.0, vec![])
        }
        RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } => {
            finite("motor_rpm_setpoint", motor_rpm_setpoint)?;
            non_negative("normal_force_n", normal_force_n)?;
            non_negative("ramp_s", ramp_s)?;
            let drive = Drive::Pi { setpoint_rad_s: rpm_to_rad_s(motor_rpm_setpoint), ramp_s, t_start_s: 0.0 };
            (drive, normal_force_n, vec![ramp_s])
        }
    };
    let sys = System::new(params, drive, n0);
    let y0 = [0.0; dopri::DIM];
    let mode0 = sys.mode_at_rest(0.0, &y0);
    let (_, stats) = sim::run(&sys, (0.0, y0, mode0), sample_times_s, &breakpoints, (opts, channels), out)?;
    Ok(stats)
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
    validate(params, opts)?;
    finite("motor_rpm_setpoint", motor_rpm_setpoint)?;
    non_negative("normal_force_n", normal_force_n)?;
    let y0 = [
        state.rotor_angle_rad,
        state.motor_angle_rad,
        if state.stuck { 0.0 } else { state.rotor_speed_rad_s },
        state.motor_speed_rad_s,
        state.current_a,
        state.pi_integral_rad,
        // The pad temperature of Effect::BrakeFade is not part of State: a continuation starts cold.
        0.0,
    ];
    for (name, v) in [("state.time_s", state.time_s)].into_iter().chain(
        [
            "state.rotor_angle_rad",
            "state.motor_angle_rad",
            "state.rotor_speed_rad_s",
            "state.motor_speed_rad_s",
            "state.current_a",
            "state.pi_integral_rad",
        ]
        .into_iter()
        .zip([y0[0], y0[1], y0[2], y0[3], y0[4], y0[5]]),
    ) {
        finite(name, v)?;
    }
    check_samples(sample_times_s, state.time_s)?;
    let drive = Drive::Pi { setpoint_rad_s: rpm_to_rad_s(motor_rpm_setpoint), ramp_s: 0.0, t_start_s: state.time_s };
    let sys = System::new(params, drive, normal_force_n);
    let mode0 = sys.mode_of(state.time_s, &y0, state.stuck);
    let mut traj = Trajectory::default();
    let (end, _) = sim::run(&sys, (state.time_s, y0, mode0), sample_times_s, &[], (opts, Channels::All), &mut traj)?;
    Ok((traj, end))
}

/// The chapter's published values the thesis model needs (Table 4.5, the
/// mean ξ of Table 4.2, Table 4.7, r of Eq. 4-10) plus the PI gains the
/// chapter does not publish.
#[derive(Debug, Clone, PartialEq)]
pub struct ThesisModelInputs {
    /// Table 4.5 motor constants; `gear_ratio` is ignored (set to 1).
    pub motor: MotorParams,
    /// J1 of Table 4.5.
    pub rotor_inertia_kgm2: f64,
    /// K_s of Table 4.5.
    pub shaft_stiffness_nm_rad: f64,
    /// The chapter's ξ (Table 4.2 mean), for C = 2ξ√(J1 K).
    pub damping_ratio: f64,
    /// Table 4.7 and Eq. 4-10's Tol.
    pub friction: ThesisFriction,
    pub brake_disc_radius_m: f64,
    /// Not published: take the PI gains identified for the rig (estimation stage).
    pub drive: DriveParams,
}

/// [`RigParams`] of the thesis model as published (ModelKind::Thesis):
/// n = 1 (the chapter ignores the gearbox), C = 2ξ√(J1 K) acting on Ω1
/// (Eq. 4-7), the Table 4.7 lookup, no effects.
pub fn thesis_model_params(inp: &ThesisModelInputs) -> RigParams {
    RigParams {
        kind: ModelKind::Thesis,
        rotor_inertia_kgm2: inp.rotor_inertia_kgm2,
        shaft_stiffness_nm_rad: inp.shaft_stiffness_nm_rad,
        shaft_damping_nm_s_rad: 2.0 * inp.damping_ratio * (inp.rotor_inertia_kgm2 * inp.shaft_stiffness_nm_rad).sqrt(),
        rotor_damping_nm_s_rad: 0.0,
        motor: MotorParams { gear_ratio: 1.0, ..inp.motor.clone() },
        drive: inp.drive.clone(),
        friction: FrictionLaw::Thesis(inp.friction.clone()),
        brake_disc_radius_m: inp.brake_disc_radius_m,
        effects: vec![],
        harmonic: None,
    }
}

/// Friction coefficient μ of `law` at rotor speed `omega_rad_s` in slip (Fig. 4.15).
/// The thesis law is the signed lookup of Eq. 4-10 / Table 4.7; the vocabulary
/// laws are symmetric and return μ(|Ω1|) (at Ω1 = 0 the slip limit, not μs).
pub fn friction_coefficient(law: &FrictionLaw, omega_rad_s: f64) -> f64 {
    match law {
        FrictionLaw::Thesis(f) => friction::thesis_lookup(f, omega_rad_s),
        other => friction::slip_mu(other, omega_rad_s),
    }
}

/// Twist φ2 − φ1 (rad) at which the shaft holds `torque_nm` statically
/// (a `static_twist` run): torque/K for the linear shaft; with
/// [`Effect::CouplingBacklash`] and [`Effect::ShaftCubicStiffness`] the root
/// of K·δe(1 + β δe²) = T plus the half gap on the side of T (bisection; a
/// softening shaft that cannot carry T returns NaN).
pub fn static_twist_rad(params: &RigParams, torque_nm: f64) -> f64 {
    let k = params.shaft_stiffness_nm_rad;
    let (mut half_gap, mut beta) = (0.0, 0.0);
    for e in &params.effects {
        match *e {
            Effect::CouplingBacklash { gap_rad } => half_gap += 0.5 * gap_rad,
            Effect::ShaftCubicStiffness { cubic_per_rad2 } => beta += cubic_per_rad2,
            _ => {}
        }
    }
    if half_gap == 0.0 && beta == 0.0 {
        return torque_nm / k;
    }
    let target = torque_nm.abs();
    let f = |d: f64| k * d * (1.0 + beta * d * d) - target;
    // Bracket: grow until f > 0; a softening spring peaks at d = 1/√(−3β).
    let d_max = if beta < 0.0 { 1.0 / (-3.0 * beta).sqrt() } else { f64::INFINITY };
    let mut hi = (target / k).max(1e-12);
    while f(hi) < 0.0 {
        if hi >= d_max {
            return f64::NAN;
        }
        hi = (2.0 * hi).min(d_max);
    }
    let mut lo = 0.0;
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if f(mid) < 0.0 { lo = mid } else { hi = mid }
    }
    torque_nm.signum() * (0.5 * (lo + hi) + half_gap)
}

use rig_types::units::rpm_to_rad_s;

fn finite(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() { Ok(()) } else { Err(ModelError::InvalidParameter { name, value, rule: "must be finite" }) }
}

fn non_negative(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() && value >= 0.0 {
        Ok(())
    } else {
        Err(ModelError::InvalidParameter { name, value, rule: "must be finite and >= 0" })
    }
}

fn positive(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() && value > 0.0 {
        Ok(())
    } else {
        Err(ModelError::InvalidParameter { name, value, rule: "must be finite and > 0" })
    }
}

fn check_samples(times: &[f64], t0: f64) -> Result<(), ModelError> {
    // Fast path without early exits (the compiler vectorises it): strictly
    // increasing (NaN compares false), a finite last and a first >= t0 make
    // every time finite and >= t0. Otherwise the loop below names the index.
    let increasing = times.windows(2).fold(true, |ok, w| ok & (w[1] > w[0]));
    if increasing
        && t0.is_finite()
        && times.first().is_none_or(|&t| t >= t0)
        && times.last().is_none_or(|t| t.is_finite())
    {
        return Ok(());
    }
    let mut prev = t0;
    for (index, &t) in times.iter().enumerate() {
        let ok = t.is_finite() && t >= t0 && (index == 0 || t > prev);
        if !ok {
            return Err(ModelError::BadSampleTimes { index });
        }
        prev = t;
    }
    Ok(())
}

/// Rejects parameters the equations cannot use (division by zero, negative
/// friction, a static coefficient below the slip one in the rig model).
fn validate(p: &RigParams, o: &SimOptions) -> Result<(), ModelError> {
    positive("rotor_inertia_kgm2", p.rotor_inertia_kgm2)?;
    positive("shaft_stiffness_nm_rad", p.shaft_stiffness_nm_rad)?;
    non_negative("shaft_damping_nm_s_rad", p.shaft_damping_nm_s_rad)?;
    non_negative("rotor_damping_nm_s_rad", p.rotor_damping_nm_s_rad)?;
    let m = &p.motor;
    positive("motor.inertia_kgm2", m.inertia_kgm2)?;
    positive("motor.inductance_h", m.inductance_h)?;
    positive("motor.resistance_ohm", m.resistance_ohm)?;
    finite("motor.torque_constant_nm_a", m.torque_constant_nm_a)?;
    finite("motor.voltage_constant_v_s_rad", m.voltage_constant_v_s_rad)?;
    non_negative("motor.friction_torque_nm", m.friction_torque_nm)?;
    non_negative("motor.speed_regulation_nm_s_rad", m.speed_regulation_nm_s_rad)?;
    positive("motor.gear_ratio", m.gear_ratio)?;
    finite("drive.kp_v_s_rad", p.drive.kp_v_s_rad)?;
    finite("drive.ki_v_rad", p.drive.ki_v_rad)?;
    positive("drive.limit_v", p.drive.limit_v)?;
    non_negative("brake_disc_radius_m", p.brake_disc_radius_m)?;
    positive("opts.rtol", o.rtol)?;
    positive("opts.atol", o.atol)?;
    positive("opts.max_step_s", o.max_step_s)?;
    match &p.friction {
        FrictionLaw::Thesis(f) => {
            finite("friction.mu_static", f.mu_static)?;
            finite("friction.mu_dynamic", f.mu_dynamic)?;
            finite("friction.mu_negative", f.mu_negative)?;
            positive("friction.static_setpoint_rpm", f.static_setpoint_rpm)?;
            if f.dynamic_setpoint_rpm.partial_cmp(&f.static_setpoint_rpm) != Some(std::cmp::Ordering::Greater) {
                return Err(ModelError::InvalidParameter {
                    name: "friction.dynamic_setpoint_rpm",
                    value: f.dynamic_setpoint_rpm,
                    rule: "must exceed static_setpoint_rpm (Table 4.7)",
                });
            }
        }
        FrictionLaw::Coulomb { mu_static, mu_kinetic }
        | FrictionLaw::Stribeck { mu_static, mu_kinetic, .. }
        | FrictionLaw::Viscous { mu_static, mu_kinetic, .. } => {
            non_negative("friction.mu_static", *mu_static)?;
            non_negative("friction.mu_kinetic", *mu_kinetic)?;
            if mu_kinetic > mu_static {
                return Err(ModelError::InvalidParameter {
                    name: "friction.mu_kinetic",
                    value: *mu_kinetic,
                    rule: "must not exceed mu_static (break-away needs μs >= μk)",
                });
            }
            match &p.friction {
                FrictionLaw::Stribeck { stribeck_speed_rad_s, .. } => {
                    positive("friction.stribeck_speed_rad_s", *stribeck_speed_rad_s)?
                }
                FrictionLaw::Viscous { viscous_per_rad_s, .. } => {
                    non_negative("friction.viscous_per_rad_s", *viscous_per_rad_s)?
                }
                _ => {}
            }
        }
    }
    for e in &p.effects {
        match e {
            Effect::NormalForceModulation { amplitude_ratio, frequency_hz, phase_rad } => {
                ratio("effects.amplitude_ratio", *amplitude_ratio)?;
                finite("effects.frequency_hz", *frequency_hz)?;
                finite("effects.phase_rad", *phase_rad)?;
            }
            Effect::AnglePeriodicFriction { amplitude_ratio, phase_rad, .. } => {
                ratio("effects.amplitude_ratio", *amplitude_ratio)?;
                finite("effects.phase_rad", *phase_rad)?;
            }
            Effect::MotorCogging { amplitude_nm, phase_rad, .. } => {
                finite("effects.amplitude_nm", *amplitude_nm)?;
                finite("effects.phase_rad", *phase_rad)?;
            }
            Effect::CouplingBacklash { gap_rad } => non_negative("effects.gap_rad", *gap_rad)?,
            Effect::ShaftCubicStiffness { cubic_per_rad2 } => finite("effects.cubic_per_rad2", *cubic_per_rad2)?,
            Effect::RotorImbalance { imbalance_kg_m, phase_rad } => {
                finite("effects.imbalance_kg_m", *imbalance_kg_m)?;
                finite("effects.phase_rad", *phase_rad)?;
            }
            Effect::BrakeFade { heat_capacity_j_k, cooling_time_s, fade_temperature_k } => {
                positive("effects.heat_capacity_j_k", *heat_capacity_j_k)?;
                positive("effects.cooling_time_s", *cooling_time_s)?;
                positive("effects.fade_temperature_k", *fade_temperature_k)?;
            }
            Effect::DriveCurrentLimit { current_limit_a } => positive("effects.current_limit_a", *current_limit_a)?,
            Effect::StaticFrictionAging { aging_mu_per_efold, aging_time_s } => {
                non_negative("effects.aging_mu_per_efold", *aging_mu_per_efold)?;
                positive("effects.aging_time_s", *aging_time_s)?;
            }
            Effect::FrictionExtension { slip_speed_per_rad_s, breakaway_transient, static_level, dwell_per_efold } => {
                finite("effects.slip_speed_per_rad_s", *slip_speed_per_rad_s)?;
                finite("effects.breakaway_transient", *breakaway_transient)?;
                finite("effects.static_level", *static_level)?;
                finite("effects.dwell_per_efold", *dwell_per_efold)?;
            }
        }
    }
    let pad_states = p
        .effects
        .iter()
        .filter(|e| {
            matches!(
                e,
                Effect::BrakeFade { .. } | Effect::StaticFrictionAging { .. } | Effect::FrictionExtension { .. }
            )
        })
        .count();
    if pad_states > 1 {
        // They live in the one pad state (temperature rise, contact age, time since the last event).
        return Err(ModelError::InvalidParameter {
            name: "effects",
            value: pad_states as f64,
            rule: "brake_fade, static_friction_aging and friction_extension cannot be combined (one pad state)",
        });
    }
    match &p.harmonic {
        Some(HarmonicFriction::MultiplyTorque { omega_p_rad_s }) => finite("harmonic.omega_p_rad_s", *omega_p_rad_s)?,
        Some(HarmonicFriction::NormalForce { omega_p_rad_s, amplitude_ratio }) => {
            finite("harmonic.omega_p_rad_s", *omega_p_rad_s)?;
            ratio("harmonic.amplitude_ratio", *amplitude_ratio)?;
        }
        None => {}
    }
    Ok(())
}

/// A modulation depth a in N0(1 + a sin ·): 0 <= a <= 1 keeps N >= 0.
fn ratio(name: &'static str, value: f64) -> Result<(), ModelError> {
    if value.is_finite() && (0.0..=1.0).contains(&value) {
        Ok(())
    } else {
        Err(ModelError::InvalidParameter { name, value, rule: "must be in [0, 1] so that N stays >= 0" })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The fast path accepts exactly what the loop accepts, and a rejection
    /// names the first offending index.
    #[test]
    fn sample_times_are_rejected_at_the_first_bad_index() {
        let bad = |index| Err(ModelError::BadSampleTimes { index });
        assert_eq!(check_samples(&[], 0.0), Ok(()));
        assert_eq!(check_samples(&[0.0, 0.5, 1.0], 0.0), Ok(()));
        assert_eq!(check_samples(&[2.0, 2.5], 2.0), Ok(()));
        assert_eq!(check_samples(&[1.5, 2.5], 2.0), bad(0));
        assert_eq!(check_samples(&[0.0, 0.5, 0.5, 1.0], 0.0), bad(2));
        assert_eq!(check_samples(&[0.0, 0.5, 0.4, 1.0], 0.0), bad(2));
        assert_eq!(check_samples(&[0.0, f64::NAN, 1.0], 0.0), bad(1));
        assert_eq!(check_samples(&[f64::NAN], 0.0), bad(0));
        assert_eq!(check_samples(&[0.0, 1.0, f64::INFINITY], 0.0), bad(2));
        assert_eq!(check_samples(&[f64::NEG_INFINITY, 1.0], f64::NEG_INFINITY), bad(0));
    }
}
