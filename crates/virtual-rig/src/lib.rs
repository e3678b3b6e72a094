//! A campaign generator for tests only (truth model with hidden effects, sensor chain).
//!
//! The virtual rig draws plausible rig parameters (seeded, [`draw_rig`]),
//! hides one or several effects in the truth model ([`Truth::with_hidden`]:
//! any vocabulary effect of ../shared/spec/diagnosis.md, or one of
//! [`Hidden::OUTSIDE`]), simulates a whole `rig-campaign/1` campaign with
//! `rig_model` and passes it through a sensor chain: encoders quantised to
//! 1000 ticks/rev (floor), a force sensor with gain, offset and noise in mV,
//! and voltage noise. [`write_campaign`] writes campaign.toml + runs/*.csv so
//! tests read it back through rig-ingest like a user's data. No analysis
//! crate may depend on this crate.
//!
//! Effects outside the vocabulary and where they live:
//! - simulator ([`rig_types::Effect`], equations in its docs): motor cogging,
//!   coupling backlash, cubic shaft, rotor imbalance, brake fade, drive
//!   current limit. Those that act with the brake open (backlash, cubic
//!   shaft, imbalance, current limit) also act in the voltage steps; the
//!   static-twist runs hold the twist of the shaft law
//!   ([`rig_model::static_twist_rad`]);
//! - generator, per run: [`Hidden::MotorWarmUp`] (R and k_e = k_T follow the
//!   winding temperature along the campaign's recorded time);
//! - sensor chain: [`Hidden::ForceSensorNonlinearity`] (q F²),
//!   [`Hidden::ForceOffsetDrift`] (d·t from each run's start),
//!   [`Hidden::EncoderMissingTicks`] (rotor encoder, own RNG per run so the
//!   campaign's other noise is unchanged).
//!
//! Draw ranges ([`draw_hidden`]): fade C 4–10 J/K, τ 20–60 s, ϑ_fade
//! 30–80 K; backlash 0.02–0.08 rad; cubic β +0.01…+0.04 or −0.002…−0.004
//! 1/rad²; imbalance m·e 0.005–0.015 kg·m (0.05–0.15 N·m); current limit
//! 2.5–4 A; warm-up ΔT 30–60 K, τ 200–600 s; force q 0.3–0.8 mV/N²;
//! offset drift ±0.5–1.5 mV/s; missed ticks p 0.002–0.01.

pub mod battery;
pub mod confusion;
mod draw;
pub mod ids;
mod sensor;
mod stick;
mod write;

pub use draw::{Hidden, SensorChannel, Truth, draw_hidden, draw_rig, draw_truth};
pub use sensor::second_order_response;
pub use stick::{MIN_STICK_SLIP_RUNS, StickSlip, draw_stick_slip_rig, stick_slip_runs};
pub use write::write_campaign;

use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rand_distr::{Distribution, Normal};
use rig_model::SimOptions;
use rig_types::sensor::encoder_ticks;
use rig_types::{Campaign, Effect, RigInfo, Run, RunData, RunInput, RunKind};
use std::f64::consts::PI;
use std::path::PathBuf;

/// The protocol of a generated campaign (defaults: the shipped campaign's).
#[derive(Debug, Clone, PartialEq)]
pub struct Protocol {
    pub sample_rate_hz: f64,
    pub force_loads_n: Vec<f64>,
    pub twist_torques_nm: Vec<f64>,
    pub step_voltages_v: Vec<f64>,
    pub step_duration_s: f64,
    /// (motor rpm set-point, normal force N) of each operating point.
    pub op_points: Vec<(f64, f64)>,
    pub op_duration_s: f64,
    pub ramp_s: f64,
}

impl Protocol {
    /// The shipped campaign's protocol: 30 operating points across the severity
    /// map, 40 s each at 500 Hz with a 2 s ramp.
    pub fn full() -> Self {
        let mut op = Vec::new();
        for rpm in [20.0, 45.0, 85.0, 130.0] {
            for n in [1.0, 4.0, 10.0, 25.0] {
                op.push((rpm, n));
            }
        }
        for rpm in [10.0, 15.0, 25.0, 32.0, 38.0, 55.0, 65.0] {
            op.push((rpm, 10.0));
        }
        for n in [2.0, 3.0, 5.0, 6.0, 7.5, 13.0, 18.0] {
            op.push((20.0, n));
        }
        Protocol {
            sample_rate_hz: 500.0,
            force_loads_n: vec![0.7, 2.0, 3.3, 4.4, 5.8],
            twist_torques_nm: vec![0.115, 0.17, 0.23, 0.29, 0.34],
            step_voltages_v: vec![6.0, 8.0, 10.0, 12.0],
            step_duration_s: 20.0,
            op_points: op,
            op_duration_s: 40.0,
            ramp_s: 2.0,
        }
    }

    /// A smaller campaign for fast tests: 12 operating points of 30 s.
    pub fn small() -> Self {
        let op = vec![
            (20.0, 4.0),
            (45.0, 10.0),
            (85.0, 4.0),
            (130.0, 10.0),
            (20.0, 10.0),
            (45.0, 25.0),
            (85.0, 10.0),
            (130.0, 25.0),
            (32.0, 6.0),
            (65.0, 7.5),
            (25.0, 13.0),
            (55.0, 18.0),
        ];
        Protocol { op_points: op, op_duration_s: 30.0, step_voltages_v: vec![8.0, 12.0], ..Protocol::full() }
    }
}

/// The generator's own integrator tolerances for the truth it records: the
/// generator's, not the analysis' (the analysis integrates with pipeline.toml's
/// `[shared.integrator]`). Equal to those today; a campaign is data, so
/// changing the analysis' tolerances must not change what the rig recorded.
pub const TRUTH_SIM_OPTIONS: SimOptions = SimOptions { rtol: 1e-8, atol: 1e-10, max_step_s: 0.01 };

/// Why a campaign could not be generated.
#[derive(Debug, thiserror::Error)]
pub enum VirtualRigError {
    #[error("simulating run {run}: {source}")]
    Model { run: String, source: rig_model::ModelError },
    #[error("writing {path}: {source}")]
    Io { path: PathBuf, source: std::io::Error },
}

fn times(duration_s: f64, rate_hz: f64) -> Vec<f64> {
    let n = (duration_s * rate_hz).round() as usize;
    (0..n).map(|k| k as f64 / rate_hz).collect()
}

/// Generates a whole campaign (in memory) from `truth` under `protocol`; the
/// noise and the per-run phases come from `seed`.
pub fn generate(name: &str, truth: &Truth, protocol: &Protocol, seed: u64) -> Result<Campaign, VirtualRigError> {
    let mut rng = ChaCha8Rng::seed_from_u64(seed);
    let faults = SensorFaults::of(truth, seed);
    // Recorded time before each run (motor warm-up follows it).
    let mut clock_s = 0.0;
    let per_rev = 1000u32;
    let rate = protocol.sample_rate_hz;
    let mv_noise = Normal::new(0.0, truth.force_noise_mv).expect("finite σ");
    let v_noise = Normal::new(0.0, truth.voltage_noise_v).expect("finite σ");
    let mut runs = Vec::new();
    for (j, &load) in protocol.force_loads_n.iter().enumerate() {
        let t = times(2.0, rate);
        let mv = t.iter().map(|&tk| faults.force_mv(truth, load, tk) + mv_noise.sample(&mut rng)).collect();
        clock_s += 2.0;
        runs.push(run(
            format!("cal-{}", j + 1),
            RunKind::ForceCalibration { load_n: load },
            RunData { time_s: t, brake_force_mv: Some(mv), ..Default::default() },
        ));
    }
    for (j, &torque) in protocol.twist_torques_nm.iter().enumerate() {
        let t = times(2.0, rate);
        // torque/K for the linear shaft; the inverse of the shaft law with backlash or a cubic shaft.
        let angle = rig_model::static_twist_rad(&truth.params, torque);
        // The held angle wanders by a fraction of a tick (hand-held torque).
        let a: Vec<f64> = t.iter().map(|_| angle + rng.random_range(-0.004..0.004)).collect();
        let id = format!("twist-{}", j + 1);
        let a = faults.delayed(SensorChannel::RotorEncoder, a);
        let rotor = faults.rotor_ticks(encoder_ticks(&a, per_rev), &id);
        runs.push(run(
            id,
            RunKind::StaticTwist { torque_nm: torque },
            RunData { time_s: t, rotor_ticks: Some(rotor), ..Default::default() },
        ));
        clock_s += 2.0;
    }
    let sim_opts = TRUTH_SIM_OPTIONS;
    for &v in &protocol.step_voltages_v {
        let t = times(protocol.step_duration_s, rate);
        let id = format!("step-{}v", v);
        let mut p = truth.params.clone();
        // Brake open: only effects that act without brake contact stay (the
        // vocabulary effects and cogging were always left out of the steps).
        p.effects.retain(acts_with_brake_open);
        faults.warm_motor(&mut p, clock_s);
        clock_s += protocol.step_duration_s;
        let tr = rig_model::simulate(&p, &RunInput::VoltageStep { voltage_v: v }, &t, &sim_opts)
            .map_err(|source| VirtualRigError::Model { run: id.clone(), source })?;
        let volt = tr.voltage_v.iter().map(|x| x + v_noise.sample(&mut rng)).collect();
        let angle = faults.rotor_angle_seen(&tr.rotor_angle_rad, &tr.rotor_speed_rad_s, rate);
        let rotor = faults.rotor_ticks(encoder_ticks(&angle, per_rev), &id);
        runs.push(run(
            id,
            RunKind::VoltageStep { voltage_v: v },
            RunData {
                motor_voltage_v: Some(volt),
                motor_ticks: Some(encoder_ticks(&tr.motor_angle_rad, per_rev)),
                rotor_ticks: Some(rotor),
                time_s: t,
                ..Default::default()
            },
        ));
    }
    // Operating points: per-run phases of the hidden effect drawn here (θ free per run).
    let mut ops = Vec::new();
    for (j, &(rpm, n0)) in protocol.op_points.iter().enumerate() {
        let mut p = truth.params.clone();
        for e in p.effects.iter_mut() {
            let th = rng.random_range(0.0..2.0 * PI);
            match e {
                Effect::NormalForceModulation { phase_rad, .. }
                | Effect::AnglePeriodicFriction { phase_rad, .. }
                | Effect::MotorCogging { phase_rad, .. }
                | Effect::RotorImbalance { phase_rad, .. } => *phase_rad = th,
                _ => {}
            }
        }
        faults.warm_motor(&mut p, clock_s);
        clock_s += protocol.op_duration_s;
        let seed_j: u64 = rng.random();
        ops.push((format!("op-{:02}", j + 1), rpm, n0, p, seed_j));
    }
    let op_runs: Vec<Result<Run, VirtualRigError>> = {
        use rayon::prelude::*;
        ops.par_iter()
            .map(|(id, rpm, n0, p, seed_j)| {
                let mut rng = ChaCha8Rng::seed_from_u64(*seed_j);
                let t = times(protocol.op_duration_s, rate);
                let input =
                    RunInput::OperatingPoint { motor_rpm_setpoint: *rpm, normal_force_n: *n0, ramp_s: protocol.ramp_s };
                let tr = rig_model::simulate(p, &input, &t, &sim_opts)
                    .map_err(|source| VirtualRigError::Model { run: id.clone(), source })?;
                let r = p.brake_disc_radius_m;
                let force_n = faults.force_seen(tr.friction_torque_nm.iter().map(|tq| tq / r).collect(), rate);
                let mv = force_n
                    .iter()
                    .zip(&t)
                    .map(|(&f, &tk)| faults.force_mv(truth, f, tk) + mv_noise.sample(&mut rng))
                    .collect();
                let volt = tr.voltage_v.iter().map(|x| x + v_noise.sample(&mut rng)).collect();
                let angle = faults.rotor_angle_seen(&tr.rotor_angle_rad, &tr.rotor_speed_rad_s, rate);
                Ok(run(
                    id.clone(),
                    RunKind::OperatingPoint { motor_rpm_setpoint: *rpm, normal_force_n: *n0, ramp_s: protocol.ramp_s },
                    RunData {
                        motor_voltage_v: Some(volt),
                        motor_ticks: Some(encoder_ticks(&tr.motor_angle_rad, per_rev)),
                        rotor_ticks: Some(faults.rotor_ticks(encoder_ticks(&angle, per_rev), id)),
                        brake_force_mv: Some(mv),
                        time_s: t,
                    },
                ))
            })
            .collect()
    };
    for r in op_runs {
        runs.push(r?);
    }
    Ok(Campaign {
        name: name.to_string(),
        description: format!("virtual rig, hidden effect: {}", truth.hidden.id()),
        rig: RigInfo {
            encoder_ticks_per_rev: per_rev,
            brake_disc_radius_m: truth.params.brake_disc_radius_m,
            supply_voltage_v: truth.supply_voltage_v,
            sample_rate_hz: rate,
        },
        runs,
    })
}

/// Effects of the truth model that act with the brake open (voltage steps).
fn acts_with_brake_open(e: &Effect) -> bool {
    matches!(
        e,
        Effect::CouplingBacklash { .. }
            | Effect::ShaftCubicStiffness { .. }
            | Effect::RotorImbalance { .. }
            | Effect::DriveCurrentLimit { .. }
    )
}

/// The hidden effects that live in the sensor chain or act per run, not in
/// the simulated equations.
#[derive(Debug, Clone, Default)]
struct SensorFaults {
    quadratic_mv_per_n2: f64,
    drift_mv_per_s: f64,
    miss_probability: f64,
    /// (ΔT in K, τ in s) of the motor warm-up.
    warm_up: Option<(f64, f64)>,
    /// A channel's transport delay, samples.
    delay: Option<(SensorChannel, usize)>,
    /// (f_n in Hz, ζ) of the force sensor's second-order response.
    force_dynamics: Option<(f64, f64)>,
    /// (f_n in Hz, ζ) of the rotor encoder's compliant coupling.
    encoder_coupling: Option<(f64, f64)>,
    seed: u64,
}

/// Temperature coefficient of copper resistance, 1/K (IEC 60028, annealed copper at 20 °C).
const COPPER_TEMPCO_PER_K: f64 = 0.00393;
/// Reversible temperature coefficient of ferrite-magnet remanence, 1/K (k_T = k_e ∝ B_r).
const FERRITE_TEMPCO_PER_K: f64 = -0.002;

impl SensorFaults {
    fn of(truth: &Truth, seed: u64) -> Self {
        let mut f = SensorFaults { seed, ..Default::default() };
        for h in truth.hidden_all() {
            match *h {
                Hidden::ForceSensorNonlinearity { quadratic_mv_per_n2 } => f.quadratic_mv_per_n2 += quadratic_mv_per_n2,
                Hidden::ForceOffsetDrift { drift_mv_per_s } => f.drift_mv_per_s += drift_mv_per_s,
                Hidden::EncoderMissingTicks { miss_probability } => f.miss_probability = miss_probability,
                Hidden::MotorWarmUp { temperature_rise_k, time_constant_s } => {
                    f.warm_up = Some((temperature_rise_k, time_constant_s))
                }
                Hidden::ChannelDelay { channel, delay_samples } => f.delay = Some((channel, delay_samples as usize)),
                Hidden::ForceSensorDynamics { natural_frequency_hz, damping_ratio } => {
                    f.force_dynamics = Some((natural_frequency_hz, damping_ratio))
                }
                Hidden::EncoderCouplingCompliance { natural_frequency_hz, damping_ratio } => {
                    f.encoder_coupling = Some((natural_frequency_hz, damping_ratio))
                }
                _ => {}
            }
        }
        f
    }

    /// Sensor voltage for force `force_n` at `t_s` into the run, before noise:
    /// offset + g F, plus q F² and d t when those faults are hidden.
    fn force_mv(&self, truth: &Truth, force_n: f64, t_s: f64) -> f64 {
        let linear = truth.force_offset_mv + truth.force_factor_mv_per_n * force_n;
        if self.quadratic_mv_per_n2 == 0.0 && self.drift_mv_per_s == 0.0 {
            return linear;
        }
        linear + self.quadratic_mv_per_n2 * force_n * force_n + self.drift_mv_per_s * t_s
    }

    /// `x` as recorded on `channel`: delayed by whole samples under
    /// [`Hidden::ChannelDelay`] (x_rec[k] = x[k − d], the first sample held
    /// before the record starts: the rig was at rest), else unchanged.
    fn delayed(&self, channel: SensorChannel, x: Vec<f64>) -> Vec<f64> {
        match self.delay {
            Some((c, d)) if c == channel && d > 0 && !x.is_empty() => {
                let mut out = Vec::with_capacity(x.len());
                out.extend(std::iter::repeat_n(x[0], d.min(x.len())));
                out.extend_from_slice(&x[..x.len() - d.min(x.len())]);
                out
            }
            _ => x,
        }
    }

    /// The brake force the force sensor sees (N, before its voltage line):
    /// the second-order response of [`Hidden::ForceSensorDynamics`], then the
    /// channel's delay.
    fn force_seen(&self, force_n: Vec<f64>, rate_hz: f64) -> Vec<f64> {
        let seen = match self.force_dynamics {
            Some((f_n, zeta)) => second_order_response(&force_n, None, rate_hz, f_n, zeta),
            None => force_n,
        };
        self.delayed(SensorChannel::Force, seen)
    }

    /// The angle the rotor encoder's disc turns through: rotor 1's angle
    /// through the compliant coupling of [`Hidden::EncoderCouplingCompliance`]
    /// (its speed drives the coupling's damper), then the channel's delay.
    fn rotor_angle_seen(&self, angle_rad: &[f64], speed_rad_s: &[f64], rate_hz: f64) -> Vec<f64> {
        let seen = match self.encoder_coupling {
            Some((f_n, zeta)) => second_order_response(angle_rad, Some(speed_rad_s), rate_hz, f_n, zeta),
            None => angle_rad.to_vec(),
        };
        self.delayed(SensorChannel::RotorEncoder, seen)
    }

    /// The rotor encoder's count with each tick missed with probability p
    /// (its own RNG per run, so the rest of the campaign's noise is unchanged).
    fn rotor_ticks(&self, ticks: Vec<i64>, run_id: &str) -> Vec<i64> {
        let p = self.miss_probability;
        if p <= 0.0 || ticks.is_empty() {
            return ticks;
        }
        let run_hash =
            run_id.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ u64::from(b)).wrapping_mul(0x100_0000_01b3));
        let mut rng = ChaCha8Rng::seed_from_u64(self.seed ^ 0x7e11_c0de ^ run_hash);
        let mut out = Vec::with_capacity(ticks.len());
        let mut count = ticks[0];
        out.push(count);
        for w in ticks.windows(2) {
            let d = w[1] - w[0];
            let kept = (0..d.abs()).filter(|_| !rng.random_bool(p)).count() as i64;
            count += d.signum() * kept;
            out.push(count);
        }
        out
    }

    /// Motor constants after `clock_s` of recorded campaign time under
    /// [`Hidden::MotorWarmUp`]: ϑ = ΔT(1 − e^(−t/τ)), R(1 + α_Cu ϑ), k(1 + α_B ϑ).
    fn warm_motor(&self, p: &mut rig_types::RigParams, clock_s: f64) {
        if let Some((rise_k, tau_s)) = self.warm_up {
            let theta = rise_k * (1.0 - (-clock_s / tau_s).exp());
            p.motor.resistance_ohm *= 1.0 + COPPER_TEMPCO_PER_K * theta;
            p.motor.torque_constant_nm_a *= 1.0 + FERRITE_TEMPCO_PER_K * theta;
            p.motor.voltage_constant_v_s_rad *= 1.0 + FERRITE_TEMPCO_PER_K * theta;
        }
    }
}

fn run(id: String, kind: RunKind, data: RunData) -> Run {
    Run { file: PathBuf::from(format!("runs/{id}.csv")), id, kind, data }
}

#[cfg(test)]
mod tests {
    use super::{SensorChannel, SensorFaults};

    /// A channel delay of d samples shifts that channel only, holding its first sample.
    #[test]
    fn delay_shifts_one_channel_by_whole_samples() {
        let f = SensorFaults { delay: Some((SensorChannel::Force, 2)), ..Default::default() };
        let x = vec![1.0, 2.0, 3.0, 4.0, 5.0];
        assert_eq!(f.delayed(SensorChannel::Force, x.clone()), vec![1.0, 1.0, 1.0, 2.0, 3.0]);
        assert_eq!(f.delayed(SensorChannel::RotorEncoder, x.clone()), x);
        let long = SensorFaults { delay: Some((SensorChannel::RotorEncoder, 9)), ..Default::default() };
        assert_eq!(long.delayed(SensorChannel::RotorEncoder, x), vec![1.0; 5]);
    }
}
