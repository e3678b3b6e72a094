//! The LAVI models, one struct for the baseline and every extension, and their
//! free run under the measured top speed (and weight on bit).
//!
//! Baseline (Real et al. 2018, the lumped 1-DOF model of the rig; physics of a
//! torsion spring driven at its top end):
//!
//! J Ω̇ = k φ + c (Ω_top − Ω) − c_a Ω − T_f,   φ̇ = Ω_top − Ω
//! (c_a = 0 in the baseline; the `absolute_damping` candidate sets it),
//!
//! T_f(Ω) = sign(Ω) [T_k + (T_s − T_k) exp(−(|Ω|/v_s)^δ) + c_v |Ω|] in slip,
//! and stick (Ω = 0) while the holding torque |k φ + c Ω_top| ≤ T_s (Karnopp).
//! The extensions (crate docs list their effect ids):
//! - `wob_normal_force`: T_f scaled by W(t)/W_ref: torque = WOB·μ(Ω) with
//!   μ = law/W_ref (Coulomb's law T = r μ N; the thesis' Eq. 4-11 idea of a
//!   varying normal force, with N measured);
//! - `sensor_inertia`: the sensor reads T_m = T_f + J_s Ω̇ (Newton on the part
//!   of the bit between sensor and contact);
//! - `friction_memory`: the slip friction magnitude lags its steady law,
//!   τ ṁ = |T_ss(Ω)| − m (a first-order frictional memory, Hess & Soom 1990);
//! - `second_dof`: a mid inertia J_1 splits the shaft: k_1 = k/s, k_2 = k/(1−s)
//!   (series stiffness k kept);
//! - `compliant_drive`: the top speed is a state, J_m Ω̇_top = K_p (Ω_ref − Ω_top)
//!   plus K_i ∫(Ω_ref − Ω_top) minus the torque into the shaft, with Ω_ref the
//!   measured top speed's moving mean (a PI speed loop; Newton on the motor);
//! - `motor_drive`: the same motor row, identified by least squares on the
//!   record ([`crate::drive`]), with the droop offset T_0 of a P loop.
//!
//! - `channel_delay`: the torque channel reads T_m(t) = T_f(t − τ).
//!
//! Every model runs on the one simulator core, rig_model::one_dof (its docs
//! state the integration: semi-implicit Euler, `substeps` steps per sample,
//! inputs linear between samples); this module maps a [`Model`] onto it and
//! applies the sensor's inertia and delay to the torque channel.

use crate::LaviError;
use crate::fit::Structure;
use rig_model::one_dof::{self, Friction, MAX_FRICTION_STATES, MidInertia, OneDofState, Shaft};
use serde::Serialize;

/// Friction law at the reference normal force: T_k + (T_s − T_k) e^{−(|Ω|/v_s)^δ} + c_v |Ω| (N m).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct FrictionLaw {
    pub static_nm: f64,
    pub kinetic_nm: f64,
    pub stribeck_speed_rad_s: f64,
    /// δ: 1 exponential, 2 Gaussian Stribeck.
    pub shape_exponent: f64,
    pub viscous_nm_s_rad: f64,
}

impl FrictionLaw {
    /// Magnitude of the slip torque at speed |Ω|. Beyond |Ω|/v_s = 746 (with
    /// δ ≥ 1) the weakening term e^{−(|Ω|/v_s)^δ} is exactly 0 in double
    /// precision (e^{−745.2} is below half the least subnormal) and its
    /// exponential is skipped: the Coulomb family's jump (v_s = 0.01 rad/s)
    /// costs none past 7.5 rad/s, with the same bits.
    pub fn slip_nm(&self, omega_rad_s: f64) -> f64 {
        let w = omega_rad_s.abs();
        let x = w / self.stribeck_speed_rad_s;
        let shape = if x > UNDERFLOW_X && self.shape_exponent >= 1.0 {
            0.0
        } else {
            rig_spectra::stickslip::weakening_shape(x, self.shape_exponent)
        };
        self.kinetic_nm + (self.static_nm - self.kinetic_nm) * shape + self.viscous_nm_s_rad * w
    }
}

/// Argument beyond which e^{−x} is exactly 0 in double precision.
const UNDERFLOW_X: f64 = 746.0;

/// A mid inertia on the shaft (the second torsional DOF).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct MidDof {
    pub inertia_kgm2: f64,
    /// s in (0, 1): k_1 = k/s (top side), k_2 = k/(1−s) (bit side).
    pub split: f64,
}

/// A speed-controlled drive whose speed is not imposed: the motor torque is
/// K_p (Ω_ref − Ω_top) + K_i ∫(Ω_ref − Ω_top) dt + T_0 (T_0 = `load_nm`, the
/// torque the loop delivers at the reference speed: a P loop's droop offset,
/// run on the core's speed loop as the reference Ω_ref + T_0/K_p).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Drive {
    pub inertia_kgm2: f64,
    pub kp_nm_s_rad: f64,
    pub ki_nm_rad: f64,
    pub load_nm: f64,
}

/// The baseline and every extension (an extension is off at its neutral value).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Model {
    pub inertia_kgm2: f64,
    pub stiffness_nm_rad: f64,
    /// c on the twist rate Ω_top − Ω.
    pub damping_nm_s_rad: f64,
    /// c_a on the absolute bit speed Ω (a drag; 0 in the baseline).
    pub absolute_damping_nm_s_rad: f64,
    /// The torque channel is late on the speed channels by this much (0 in the baseline), s.
    pub torque_delay_s: f64,
    pub friction: FrictionLaw,
    /// Some(W_ref): friction scales with W(t)/W_ref.
    pub wob_ref_n: Option<f64>,
    pub sensor_inertia_kgm2: f64,
    /// 0: no frictional memory.
    pub friction_lag_s: f64,
    pub mid: Option<MidDof>,
    pub drive: Option<Drive>,
    /// Some: the normal force is the weight on bit's slow level (`wob_level`,
    /// [`crate::wob_level`]); not serialised when None.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wob_level: Option<crate::wob_level::WobLevel>,
    /// The stuck contact holds up to the law's zero-speed torque plus this
    /// much, N m at the reference normal force (`static_friction`,
    /// [`crate::static_friction`]; 0: the break-away is the law's T(0); not serialised at 0).
    #[serde(skip_serializing_if = "crate::fit::is_zero")]
    pub static_excess_nm: f64,
    /// Some: the normal force follows the bit's angle (`wob_angle`,
    /// [`crate::wob_angle`]); not serialised when None.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub wob_angle: Option<crate::wob_angle::WobAngle>,
    /// How J, k, c (and the least-squares law) were derived (rig_lavi::fit).
    pub structure: Structure,
}

impl Model {
    /// The largest torque the stuck contact holds at the reference normal
    /// force, N m: the law's zero-speed torque T(0) plus the static excess.
    pub fn static_level_nm(&self) -> f64 {
        self.friction.static_nm + self.static_excess_nm
    }

    /// This model (a derivation's shaft, law and structure) carrying
    /// `current`'s effects that no derivation fits: the friction's lag, the
    /// middle degree of freedom, the drive, the WOB level and the static
    /// excess.
    pub(crate) fn with_effects_of(self, current: &Model) -> Model {
        Model {
            friction_lag_s: current.friction_lag_s,
            mid: current.mid,
            drive: current.drive,
            wob_level: current.wob_level,
            static_excess_nm: current.static_excess_nm,
            wob_angle: current.wob_angle,
            ..self
        }
    }
}

/// What a free run is driven by (rad/s and N, one value per sample).
#[derive(Debug, Clone, Copy)]
pub struct Inputs<'a> {
    pub fs_hz: f64,
    pub top_rad_s: &'a [f64],
    pub wob_n: &'a [f64],
    /// Set point of the compliant drive (moving mean of the measured top speed).
    pub top_ref_rad_s: &'a [f64],
}

/// Measured state at the first sample: bit speed, its derivative, and the
/// contact torque at that instant as the torque channel reads it, i.e. the
/// channel's sample `torque_delay_s` later (the caller aligns it).
#[derive(Debug, Clone, Copy)]
pub struct Start {
    pub bit_rad_s: f64,
    pub bit_acc_rad_s2: f64,
    pub torque_nm: f64,
    /// The bit's angle, rad (the record's bit speed integrated from its first
    /// sample): where a normal force that follows the angle starts (`wob_angle`).
    pub bit_angle_rad: f64,
}

/// A free run at the input's sample times.
#[derive(Debug, Clone, PartialEq)]
pub struct Run {
    pub bit_rad_s: Vec<f64>,
    /// What the torque sensor reads (friction plus J_s Ω̇).
    pub torque_nm: Vec<f64>,
    pub top_rad_s: Vec<f64>,
}

const STICK_RAD_S: f64 = 1e-3;

/// The contact of [`Model`] as a law of the one simulator core: the
/// reference law scaled by W/W_ref, with the first-order memory as its state.
#[derive(Clone, Copy)]
struct Contact {
    law: FrictionLaw,
    lag_s: f64,
    /// The largest torque held while stuck (the law's T(0) plus the static excess), N m.
    static_nm: f64,
}

impl Friction for Contact {
    fn static_nm(&self, scale: f64, _: &[f64; MAX_FRICTION_STATES]) -> Option<f64> {
        Some(scale * self.static_nm)
    }
    fn slip_nm(&self, speed_rad_s: f64, scale: f64, state: &[f64; MAX_FRICTION_STATES]) -> f64 {
        if self.lag_s > 0.0 { state[0] } else { scale * self.law.slip_nm(speed_rad_s) }
    }
    /// τ ṁ = |T_ss(Ω)| − m in slip (explicit step, clamped at one time constant); m = held torque in stick.
    fn step_state(&self, state: &mut [f64; MAX_FRICTION_STATES], speed: f64, scale: f64, held: Option<f64>, h: f64) {
        if self.lag_s > 0.0 {
            let target = held.unwrap_or_else(|| scale * self.law.slip_nm(speed));
            state[0] += if held.is_some() { 1.0 } else { (h / self.lag_s).min(1.0) } * (target - state[0]);
        }
    }
}

/// [`Contact`] whose normal force also follows the bit's angle (`wob_angle`): its
/// normal-force factor times N(θ)/N̄, θ the bit's angle in `state[1]` (rad),
/// advanced by |Ω| h (`speed` is 0 while stuck). A type of its own, run in a
/// batch of its own ([`simulate_batch`]): every other model's contact keeps
/// its loop free of the angle.
struct AngleContact {
    contact: Contact,
    angle: crate::wob_angle::WobAngle,
}

impl Friction for AngleContact {
    fn static_nm(&self, scale: f64, state: &[f64; MAX_FRICTION_STATES]) -> Option<f64> {
        self.contact.static_nm(scale * self.angle.factor(state[1]), state)
    }
    fn slip_nm(&self, speed_rad_s: f64, scale: f64, state: &[f64; MAX_FRICTION_STATES]) -> f64 {
        self.contact.slip_nm(speed_rad_s, scale * self.angle.factor(state[1]), state)
    }
    fn step_state(&self, state: &mut [f64; MAX_FRICTION_STATES], speed: f64, scale: f64, held: Option<f64>, h: f64) {
        self.contact.step_state(state, speed, scale * self.angle.factor(state[1]), held, h);
        state[1] += speed * h;
    }
}

/// A channel delay in whole samples (rounded; negative: early).
pub fn delay_samples(delay_s: f64, fs_hz: f64) -> isize {
    (delay_s * fs_hz).round() as isize
}

/// Samples `s` of the channel `x` read `k` samples later (k < 0: earlier; the
/// record's ends stand in beyond them): a channel on another clock brought onto
/// the bit speed's. Borrowed when the shifted range lies inside the record.
pub fn read_late<'x>(x: &'x [f64], s: &std::ops::Range<usize>, k: isize) -> std::borrow::Cow<'x, [f64]> {
    let (a, b) = (s.start as isize + k, s.end as isize + k);
    if a >= 0 && b <= x.len() as isize {
        std::borrow::Cow::Borrowed(&x[a as usize..b as usize])
    } else {
        s.clone().map(|i| x[(i as isize + k).clamp(0, x.len() as isize - 1) as usize]).collect()
    }
}

/// Integrates `m` from `start` under `u` (see the module docs) on the one
/// simulator core, rig_model::one_dof; the sensor's inertia and delay act on
/// its torque channel. A batch of one ([`simulate_batch`]).
pub fn simulate(m: &Model, u: &Inputs, start: Start, substeps: usize) -> Result<Run, LaviError> {
    simulate_batch(&[(m, *u, start)], substeps).pop().expect("a batch of one gives one run")
}

/// One free run of [`simulate_batch`]: the model, what drives it, where it starts.
pub type Job<'m, 'u> = (&'m Model, Inputs<'u>, Start);

/// A model mapped onto the core: the shaft, the contact, the initial state
/// and the series the core reads (owned where the model transforms the input).
struct Setup {
    shaft: Shaft,
    contact: Contact,
    /// The contact when the normal force follows the bit's angle (`wob_angle`).
    angle: Option<AngleContact>,
    state: OneDofState,
    /// W(t)/W_ref per sample (`wob_ref_n` Some).
    scale: Option<Vec<f64>>,
    /// The drive's reference shifted by T_0/K_p (a load offset T_0 ≠ 0).
    shifted: Option<Vec<f64>>,
}

fn setup(m: &Model, u: &Inputs, start: Start) -> Result<Setup, LaviError> {
    let n = u.top_rad_s.len();
    if u.wob_n.len() != n || u.top_ref_rad_s.len() != n || n < 2 {
        return Err(LaviError::Input { what: "simulate", rule: "inputs must have equal lengths >= 2".into() });
    }
    let (k, c, jb) = (m.stiffness_nm_rad, m.damping_nm_s_rad, m.inertia_kgm2);
    let shaft = Shaft {
        inertia_kgm2: jb,
        stiffness_nm_rad: k,
        twist_damping_nm_s_rad: c,
        absolute_damping_nm_s_rad: m.absolute_damping_nm_s_rad,
        mid: m.mid.map(|d| MidInertia { inertia_kgm2: d.inertia_kgm2, split: d.split }),
    };
    let w_ref = m.wob_ref_n.unwrap_or(1.0);
    let scale: Option<Vec<f64>> = m.wob_ref_n.map(|_| u.wob_n.iter().map(|w| w / w_ref).collect());
    // Initial state from the measured start (quasi-static twist: J Ω̇ = k φ + c(Ω_top − Ω) − c_a Ω − T_f).
    let top0 = u.top_rad_s[0];
    let tf0 = start.torque_nm - m.sensor_inertia_kgm2 * start.bit_acc_rad_s2;
    let om = start.bit_rad_s;
    let tau0 = jb * start.bit_acc_rad_s2 + tf0 + m.absolute_damping_nm_s_rad * om;
    let (upper, lower) = match m.mid {
        Some(d) => (tau0 * d.split / k, tau0 * (1.0 - d.split) / k),
        None => (0.0, (tau0 - c * (top0 - om)) / k),
    };
    let scale0 = scale.as_ref().map_or(1.0, |g| g[0]);
    let state = OneDofState {
        bit_rad_s: om,
        twist_rad: lower,
        upper_twist_rad: upper,
        mid_rad_s: 0.5 * (top0 + om),
        top_rad_s: top0,
        loop_integral_rad: match m.drive {
            Some(d) if d.ki_nm_rad > 0.0 => (tau0 - d.load_nm) / d.ki_nm_rad,
            _ => 0.0,
        },
        friction_state: [tf0.abs(), if m.wob_angle.is_some() { start.bit_angle_rad } else { 0.0 }],
        stuck: om.abs() < STICK_RAD_S
            && tau0.abs() <= scale0 * m.wob_angle.map_or(1.0, |a| a.factor(start.bit_angle_rad)) * m.static_level_nm(),
    };
    // T_0 as a shift of the reference: K_p (Ω_ref + T_0/K_p − Ω_top) = K_p (Ω_ref − Ω_top) + T_0.
    let shifted: Option<Vec<f64>> = m
        .drive
        .filter(|d| d.load_nm != 0.0)
        .map(|d| u.top_ref_rad_s.iter().map(|r| r + d.load_nm / d.kp_nm_s_rad).collect());
    let contact = Contact { law: m.friction, lag_s: m.friction_lag_s, static_nm: m.static_level_nm() };
    let angle = m.wob_angle.map(|angle| AngleContact { contact, angle });
    Ok(Setup { shaft, contact, angle, state, scale, shifted })
}

/// Integrates every job as [`simulate`] would, results in job order: one
/// batch of the core (`one_dof::simulate_batch`: the runs advance substep by
/// substep in one loop, each run's bits its own).
pub fn simulate_batch(jobs: &[Job<'_, '_>], substeps: usize) -> Vec<Result<Run, LaviError>> {
    let setups: Vec<Result<Setup, LaviError>> = jobs.iter().map(|(m, u, start)| setup(m, u, *start)).collect();
    // The jobs that set up, as the core's: a batch per contact type (one loop each).
    let (mut plain, mut of_plain) = (Vec::with_capacity(jobs.len()), Vec::new());
    let (mut angled, mut of_angled) = (Vec::new(), Vec::new());
    for (j, s) in setups.iter().enumerate() {
        let Ok(s) = s else { continue };
        let (m, u, _) = &jobs[j];
        let drive = match m.drive {
            Some(d) => one_dof::Drive::SpeedLoop {
                inertia_kgm2: d.inertia_kgm2,
                kp_nm_s_rad: d.kp_nm_s_rad,
                ki_nm_rad: d.ki_nm_rad,
                reference_rad_s: s.shifted.as_deref().unwrap_or(u.top_ref_rad_s),
            },
            None => one_dof::Drive::Speed(u.top_rad_s),
        };
        let (shaft, normal_scale, start, samples) = (s.shaft, s.scale.as_deref(), s.state, u.top_rad_s.len());
        match &s.angle {
            Some(law) => {
                angled.push(one_dof::OneDofJob { shaft, law, drive, normal_scale, start, samples });
                of_angled.push(j);
            }
            None => {
                plain.push(one_dof::OneDofJob { shaft, law: &s.contact, drive, normal_scale, start, samples });
                of_plain.push(j);
            }
        }
    }
    let mut runs: Vec<Option<Result<one_dof::OneDofRun, rig_model::ModelError>>> =
        (0..jobs.len()).map(|_| None).collect();
    run_core(&plain, &of_plain, jobs, substeps, &mut runs);
    run_core(&angled, &of_angled, jobs, substeps, &mut runs);
    setups
        .into_iter()
        .zip(runs)
        .zip(jobs)
        .map(|((s, r), (m, u, start))| {
            s?;
            let r = r.expect("every job that set up was run").map_err(|e| match e {
                rig_model::ModelError::IntegratorFailed { time_s, .. } => {
                    LaviError::Diverged { sample: (time_s * u.fs_hz).round() as usize }
                }
                e => LaviError::Model(e),
            })?;
            Ok(sensor_run(m, r, *start, u.fs_hz))
        })
        .collect()
}

/// The core runs of `core` (jobs `of` of `jobs`) into `runs`: one batch
/// (`one_dof::simulate_batch`: the runs advance substep by substep in one
/// loop, each run's bits its own) when the jobs share a sample rate, else one by one.
fn run_core<F: Friction>(
    core: &[one_dof::OneDofJob<'_, F>],
    of: &[usize],
    jobs: &[Job<'_, '_>],
    substeps: usize,
    runs: &mut [Option<Result<one_dof::OneDofRun, rig_model::ModelError>>],
) {
    let fs_hz = jobs.first().map_or(1.0, |j| j.1.fs_hz);
    if jobs.iter().all(|j| j.1.fs_hz == fs_hz) {
        for (j, r) in of.iter().zip(one_dof::simulate_batch(core, fs_hz, substeps)) {
            runs[*j] = Some(r);
        }
    } else {
        for (j, job) in of.iter().zip(core) {
            runs[*j] = one_dof::simulate_batch(std::slice::from_ref(job), jobs[*j].1.fs_hz, substeps).pop();
        }
    }
}

/// The core's run as the rig's channels read it: the sensor's inertia and
/// the torque channel's delay applied.
fn sensor_run(m: &Model, r: one_dof::OneDofRun, start: Start, fs_hz: f64) -> Run {
    let n = r.bit_rad_s.len();
    let mut sensor: Vec<f64> =
        r.friction_nm.iter().zip(&r.accel_rad_s2).map(|(f, a)| f + m.sensor_inertia_kgm2 * a).collect();
    sensor[0] = start.torque_nm;
    // A torque channel late by `torque_delay_s` reads, at sample i, the torque of sample i − d
    // (d < 0: early; the run's first and last samples stand in beyond its ends).
    let d = delay_samples(m.torque_delay_s, fs_hz);
    let torque_nm = (0..n).map(|i| sensor[(i as isize - d).clamp(0, n as isize - 1) as usize]).collect();
    Run { bit_rad_s: r.bit_rad_s, torque_nm, top_rad_s: r.top_rad_s }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// A model every extension off (tests of this crate build on it).
    pub(crate) fn base() -> Model {
        Model {
            inertia_kgm2: 0.05,
            stiffness_nm_rad: 2.0,
            damping_nm_s_rad: 0.02,
            absolute_damping_nm_s_rad: 0.0,
            torque_delay_s: 0.0,
            friction: FrictionLaw {
                static_nm: 1.8,
                kinetic_nm: 1.0,
                stribeck_speed_rad_s: 1.0,
                shape_exponent: 1.0,
                viscous_nm_s_rad: 0.0,
            },
            wob_ref_n: None,
            sensor_inertia_kgm2: 0.0,
            friction_lag_s: 0.0,
            mid: None,
            drive: None,
            wob_level: None,
            static_excess_nm: 0.0,
            wob_angle: None,
            structure: Structure::BASELINE,
        }
    }

    fn run(m: &Model, top: f64, secs: f64) -> Run {
        let n = (secs * 1000.0) as usize;
        let (u, w) = (vec![top; n], vec![500.0; n]);
        let inp = Inputs { fs_hz: 1000.0, top_rad_s: &u, wob_n: &w, top_ref_rad_s: &u };
        simulate(m, &inp, Start { bit_rad_s: top, bit_acc_rad_s2: 0.0, torque_nm: 1.0, bit_angle_rad: 0.0 }, 5).unwrap()
    }

    #[test]
    fn steady_slip_settles_at_the_top_speed_with_the_kinetic_torque() {
        // 20 rad/s: far past v_s, T → T_k = 1 N m; decay time 2J/c = 5 s, 60 s leave e^{-12}.
        let r = run(&base(), 20.0, 60.0);
        let n = r.bit_rad_s.len() - 1;
        assert!((r.bit_rad_s[n] - 20.0).abs() < 1e-3 && (r.torque_nm[n] - 1.0).abs() < 1e-3, "{:?}", r.bit_rad_s[n]);
    }

    /// A contact whose normal force follows the bit's angle (`wob_angle`): in steady slip at
    /// 20 rad/s past the Stribeck speed the torque is T_k (1 + 0.2 cos 2θ), θ the simulated bit's
    /// angle from its start: it swings at twice the revolution rate, in that phase.
    #[test]
    fn a_contact_that_follows_the_angle_varies_with_the_simulated_angle() {
        let a = crate::wob_angle::WobAngle { cos: [0.0, 0.2, 0.0], sin: [0.0; 3] };
        let m = Model { wob_angle: Some(a), ..base() };
        let r = run(&m, 20.0, 60.0);
        // Past the transient (decay 2J/c = 5 s): the bit's angle is ∫ Ω dt from 0.
        let mut theta = 0.0;
        let mut worst = 0.0f64;
        for i in 1..r.bit_rad_s.len() {
            theta += 0.5 * (r.bit_rad_s[i - 1] + r.bit_rad_s[i]) / 1000.0;
            if i > 50_000 {
                let want = 1.0 * (1.0 + 0.2 * (2.0 * theta).cos());
                worst = worst.max((r.torque_nm[i] - want).abs());
            }
        }
        // The torque follows the angle (to the bit speed's small ripple the swing itself drives).
        assert!(worst < 0.02, "largest departure {worst}");
        let (lo, hi) =
            r.torque_nm[50_000..].iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), t| (l.min(*t), h.max(*t)));
        assert!(lo < 0.81 && hi > 1.19, "{lo}..{hi}");
    }

    #[test]
    fn slow_drive_sticks_and_slips() {
        let r = run(&base(), 1.0, 20.0);
        let stuck = r.bit_rad_s.iter().filter(|v| **v == 0.0).count();
        assert!(stuck > 2000, "stuck samples {stuck}");
        // The sensor never reads more than the static torque in stick.
        assert!(r.torque_nm.iter().all(|t| *t <= 1.8 + 1e-9));
    }

    #[test]
    fn a_late_or_early_torque_channel_is_the_contact_torque_shifted() {
        // Stick-slip (slow drive): a torque with structure to shift.
        let on_time = run(&base(), 1.0, 5.0);
        for (delay_s, d) in [(0.02, 20isize), (-0.02, -20)] {
            let m = Model { torque_delay_s: delay_s, ..base() };
            let r = run(&m, 1.0, 5.0);
            // The motion is the contact's, whatever the channel reads.
            assert_eq!(r.bit_rad_s, on_time.bit_rad_s);
            let n = r.torque_nm.len() as isize;
            for i in 100..n - 100 {
                assert_eq!(
                    r.torque_nm[i as usize],
                    on_time.torque_nm[(i - d) as usize],
                    "delay {delay_s} s, sample {i}"
                );
            }
        }
        assert_eq!(delay_samples(-0.0204, 1000.0), -20);
    }

    #[test]
    fn the_skipped_exponential_is_exactly_zero() {
        // Past UNDERFLOW_X the skipped term is the one the exponential gives, bit for bit.
        for x in [746.0 + 1e-9, 746.5, 800.0, 1e4, 1e300] {
            for shape in [1.0, 1.5, 2.0] {
                assert_eq!(rig_spectra::stickslip::weakening_shape(x, shape), 0.0, "x {x} shape {shape}");
            }
        }
        let law = FrictionLaw { stribeck_speed_rad_s: 0.01, ..base().friction };
        assert_eq!(law.slip_nm(7.5), law.kinetic_nm);
    }

    #[test]
    fn a_proportional_drive_droops_from_its_reference_by_the_load_over_its_gain() {
        // Steady slip far past v_s (friction T_k = 1 N m): the motor's torque K_p (Ω_ref − Ω_top) + T_0
        // carries T_k, so Ω_top = Ω_ref + (T_0 − T_k)/K_p = 20 + (1.5 − 1)/0.5 = 21 rad/s.
        let m = Model {
            drive: Some(Drive { inertia_kgm2: 0.05, kp_nm_s_rad: 0.5, ki_nm_rad: 0.0, load_nm: 1.5 }),
            ..base()
        };
        let r = run(&m, 20.0, 60.0);
        let n = r.top_rad_s.len() - 1;
        assert!((r.top_rad_s[n] - 21.0).abs() < 1e-3 && (r.bit_rad_s[n] - 21.0).abs() < 1e-3, "{}", r.top_rad_s[n]);
    }

    #[test]
    fn a_batch_of_models_gives_each_its_own_runs_bits() {
        // The baseline and every extension, one batch: each run bit for bit the run alone.
        let mut ext = base();
        ext.mid = Some(MidDof { inertia_kgm2: 0.02, split: 0.5 });
        ext.drive = Some(Drive { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0, load_nm: 0.3 });
        ext.friction_lag_s = 0.02;
        ext.sensor_inertia_kgm2 = 0.01;
        ext.torque_delay_s = 0.01;
        ext.wob_ref_n = Some(450.0);
        let models = [base(), ext, Model { static_excess_nm: 0.3, ..base() }, Model { inertia_kgm2: -1.0, ..base() }];
        let n = 5000;
        let top: Vec<f64> = (0..n).map(|i| 1.0 + 0.5 * (i as f64 * 0.002).sin()).collect();
        let w: Vec<f64> = (0..n).map(|i| 500.0 + 40.0 * (i as f64 * 0.001).cos()).collect();
        let inp = Inputs { fs_hz: 1000.0, top_rad_s: &top, wob_n: &w, top_ref_rad_s: &top };
        let start = Start { bit_rad_s: 0.0, bit_acc_rad_s2: 0.0, torque_nm: 1.0, bit_angle_rad: 0.0 };
        let jobs: Vec<Job> = models.iter().map(|m| (m, inp, start)).collect();
        let batch = simulate_batch(&jobs, 5);
        let bits = |r: &Result<Run, LaviError>| match r {
            Ok(r) => format!(
                "{:?}",
                [&r.bit_rad_s, &r.torque_nm, &r.top_rad_s].map(|c| c.iter().map(|v| v.to_bits()).collect::<Vec<_>>())
            ),
            Err(e) => e.to_string(),
        };
        for (m, b) in models.iter().zip(&batch) {
            assert_eq!(bits(b), bits(&simulate(m, &inp, start, 5)));
        }
        assert!(batch[..3].iter().all(|r| r.is_ok()) && batch[3].is_err());
    }

    #[test]
    fn the_extensions_run() {
        let mut m = base();
        m.mid = Some(MidDof { inertia_kgm2: 0.02, split: 0.5 });
        m.drive = Some(Drive { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0, load_nm: 0.0 });
        m.friction_lag_s = 0.02;
        m.sensor_inertia_kgm2 = 0.01;
        m.wob_ref_n = Some(500.0);
        let r = run(&m, 3.0, 10.0);
        assert!(r.bit_rad_s.iter().all(|v| v.is_finite()));
    }
}
