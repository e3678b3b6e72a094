//! The one torsional-chain simulator core for rigs driven at the top of a
//! shaft and rubbing at the bottom (the UFRJ LAVI drill string; a
//! spring–slider is the same equations in translation): one bit inertia on a
//! shaft, an optional mid inertia, a drive, a contact with a stick phase.
//!
//! # Equations
//!
//! The lumped 1-DOF model of Real et al. (2018), the thesis' Eq. 4-7 reduced
//! to the bit's degree of freedom with the top speed imposed:
//!
//! J Ω̇ = k φ + c (Ω_top − Ω) − c_a Ω − T_f,   φ̇ = Ω_top − Ω,
//!
//! φ the twist (rad), c the damping on the twist rate (the rig model's
//! placement) and c_a a drag on the absolute bit speed (Eq. 4-7's diag(C, Cm)
//! placement); both may be set. With a mid inertia J_1 (a second torsional
//! degree of freedom) the shaft splits into k_1 = k/s, c_1 = c/s above it and
//! k_2 = k/(1−s), c_2 = c/(1−s) below it (series stiffness k kept).
//!
//! Contact (Karnopp stick phase): while stuck, Ω = 0 and the contact carries
//! the holding torque τ = k φ + c Ω_top (the shaft torque at Ω = 0); it breaks
//! away when |τ| exceeds the law's static level, and sticks again when Ω would
//! change sign while |τ| is within it. A law without a static level never
//! sticks.
//!
//! # API
//!
//! - [`Drive`]: what imposes the top: a sampled speed series (linear between
//!   samples; its integral, the top angle, is what the twist sees), a
//!   constant speed, or a PI speed loop on a motor inertia following a sampled
//!   reference (the top speed then is a state).
//! - [`Friction`]: a law with an optional internal state (up to
//!   [`MAX_FRICTION_STATES`] values: a lag, a rate-and-state θ), a static
//!   level or none, all scaled by an optional normal-force factor series
//!   (torque = factor × law, Coulomb's T = r μ N with N measured).
//! - [`Shaft`]: J, k, c, c_a and the optional [`MidInertia`].
//! - [`OneDofState`]: the state to start from; [`simulate`] integrates it over
//!   the sample grid and returns a [`OneDofRun`] (bit speed, top speed,
//!   twist, contact torque, bit acceleration, stick flag per sample). What a
//!   sensor reads (an inertia before it, a delay) is the caller's transform of
//!   these channels.
//!
//! - [`simulate_implicit`] (`_into`: a caller's buffers reused): the same
//!   equation without mid inertia under an imposed speed, the contact solved
//!   implicitly in the new speed (Moreau's time stepping, [`ImplicitFriction`]),
//!   for laws too stiff for [`simulate`]'s explicit friction: Coulomb
//!   ([`implicit_coulomb_step`], any kinetic law of the speed) and
//!   Dieterich–Ruina rate and state with the ageing law
//!   ([`RateStateAgeing`]). The spring–slider (`rig_slider`) runs on it.
//!
//! Integration: semi-implicit Euler with `substeps` steps per sample
//! interval (0.2 ms at 1 kHz and 5 substeps, for a compared band below
//! 10 Hz); the inputs are linear between samples. Its fixed point is the
//! exact steady slip (tested). No IO and no fitting here: identification is the
//! caller's (rig_lavi::fit).

use crate::ModelError;

mod implicit;
pub use implicit::*;

/// Internal friction states a law may carry.
pub const MAX_FRICTION_STATES: usize = 2;

/// A friction law at the contact: magnitudes (N m) at the reference normal
/// force, multiplied by the normal-force factor `scale` (1 without one).
pub trait Friction {
    /// The largest torque the contact holds while stuck; `None`: it never sticks.
    fn static_nm(&self, scale: f64, state: &[f64; MAX_FRICTION_STATES]) -> Option<f64>;
    /// The magnitude of the torque resisting slip at speed |Ω| = `speed_rad_s` ≥ 0.
    fn slip_nm(&self, speed_rad_s: f64, scale: f64, state: &[f64; MAX_FRICTION_STATES]) -> f64;
    /// Advances the internal state over `h_s`: in slip at `speed_rad_s`
    /// (`held_nm` None) or stuck carrying `held_nm` (also at the break-away
    /// instant, with the static level). Called before the torque is read.
    fn step_state(
        &self,
        _state: &mut [f64; MAX_FRICTION_STATES],
        _speed_rad_s: f64,
        _scale: f64,
        _held_nm: Option<f64>,
        _h_s: f64,
    ) {
    }
}

/// Coulomb friction with a static level above the kinetic one (the simplest
/// law with a stick phase; tests and spring–slider studies).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Coulomb {
    pub static_nm: f64,
    pub kinetic_nm: f64,
}

impl Friction for Coulomb {
    fn static_nm(&self, scale: f64, _: &[f64; MAX_FRICTION_STATES]) -> Option<f64> {
        Some(scale * self.static_nm)
    }
    fn slip_nm(&self, _: f64, scale: f64, _: &[f64; MAX_FRICTION_STATES]) -> f64 {
        scale * self.kinetic_nm
    }
}

/// What drives the top of the shaft.
#[derive(Debug, Clone, Copy)]
pub enum Drive<'a> {
    /// Imposed top speed, rad/s, one value per sample.
    Speed(&'a [f64]),
    /// Imposed constant top speed, rad/s.
    ConstantSpeed(f64),
    /// J_m Ω̇_top = K_p (Ω_ref − Ω_top) + K_i ∫(Ω_ref − Ω_top) dt − (shaft torque at the top):
    /// a PI speed loop on a motor inertia (Newton on the motor), following `reference_rad_s` per sample.
    SpeedLoop { inertia_kgm2: f64, kp_nm_s_rad: f64, ki_nm_rad: f64, reference_rad_s: &'a [f64] },
}

/// A mid inertia on the shaft (a second torsional degree of freedom).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MidInertia {
    pub inertia_kgm2: f64,
    /// s in (0, 1): k_1 = k/s (top side), k_2 = k/(1−s) (bit side).
    pub split: f64,
}

/// The mechanical part: bit inertia, shaft and damping.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Shaft {
    pub inertia_kgm2: f64,
    pub stiffness_nm_rad: f64,
    /// c on the twist rate Ω_top − Ω.
    pub twist_damping_nm_s_rad: f64,
    /// c_a on the absolute bit speed Ω.
    pub absolute_damping_nm_s_rad: f64,
    pub mid: Option<MidInertia>,
}

/// A state to start from.
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct OneDofState {
    pub bit_rad_s: f64,
    /// Twist of the (lower) shaft section at the bit, rad.
    pub twist_rad: f64,
    /// With a mid inertia: the upper section's twist and the mid speed.
    pub upper_twist_rad: f64,
    pub mid_rad_s: f64,
    /// With a speed loop: the top speed and the loop's integral ∫(Ω_ref − Ω_top) dt.
    pub top_rad_s: f64,
    pub loop_integral_rad: f64,
    pub friction_state: [f64; MAX_FRICTION_STATES],
    pub stuck: bool,
}

/// A run at the input's sample times.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct OneDofRun {
    pub bit_rad_s: Vec<f64>,
    pub top_rad_s: Vec<f64>,
    pub twist_rad: Vec<f64>,
    /// Signed torque of the contact on the bit's resistance side (holding torque while stuck).
    pub friction_nm: Vec<f64>,
    pub accel_rad_s2: Vec<f64>,
    pub stuck: Vec<bool>,
}

/// Twist φ(t) − φ(t0) = ∫ (Ω_top − Ω) dt by the trapezoid rule (rad, for speeds in rad/s):
/// the angle a model driven by `top` is wound by; one home for every caller.
pub fn integrated_twist_rad(time_s: &[f64], top: &[f64], bit: &[f64]) -> Vec<f64> {
    let mut phi = vec![0.0; time_s.len()];
    for i in 1..time_s.len() {
        let dt = time_s[i] - time_s[i - 1];
        phi[i] = phi[i - 1] + 0.5 * dt * ((top[i] - bit[i]) + (top[i - 1] - bit[i - 1]));
    }
    phi
}

fn invalid(name: &'static str, value: f64, rule: &'static str) -> ModelError {
    ModelError::InvalidParameter { name, value, rule }
}

/// Integrates `shaft` with contact `law` under `drive` over `samples` samples
/// at `fs_hz` from `start` (module docs). `normal_scale`: the normal-force
/// factor per sample (None: 1). A batch of one ([`simulate_batch`]): the
/// same steps, the same bits.
#[allow(clippy::too_many_arguments)]
pub fn simulate<F: Friction>(
    shaft: &Shaft,
    law: &F,
    drive: Drive,
    normal_scale: Option<&[f64]>,
    start: OneDofState,
    fs_hz: f64,
    samples: usize,
    substeps: usize,
) -> Result<OneDofRun, ModelError> {
    let job = OneDofJob { shaft: *shaft, law, drive, normal_scale, start, samples };
    simulate_batch(&[job], fs_hz, substeps).pop().expect("a batch of one gives one run")
}

/// One run of a batch ([`simulate_batch`]): [`simulate`]'s arguments but
/// the sample rate and the substeps, which a batch shares.
#[derive(Debug)]
pub struct OneDofJob<'a, F> {
    pub shaft: Shaft,
    pub law: &'a F,
    pub drive: Drive<'a>,
    pub normal_scale: Option<&'a [f64]>,
    pub start: OneDofState,
    pub samples: usize,
}

impl<F> Clone for OneDofJob<'_, F> {
    fn clone(&self) -> Self {
        *self
    }
}
impl<F> Copy for OneDofJob<'_, F> {}

/// Integrates every job of `jobs` as [`simulate`] would, each run's result in
/// job order. The runs are independent: they advance substep by substep in
/// one loop, so the core overlaps their dependency chains (the speed → the
/// law → the acceleration → the next speed of one run waits on its own
/// divisions and `exp`, not on another run's), and each run's operations are
/// its own, in its own order: a run's bits do not depend on its batch.
pub fn simulate_batch<F: Friction>(
    jobs: &[OneDofJob<'_, F>],
    fs_hz: f64,
    substeps: usize,
) -> Vec<Result<OneDofRun, ModelError>> {
    let steps = substeps.max(1);
    let mut lanes: Vec<Result<Lane<F>, ModelError>> = jobs.iter().map(|j| Lane::begin(*j, fs_hz, steps)).collect();
    let longest = jobs.iter().map(|j| j.samples).max().unwrap_or(0);
    for i in 1..longest {
        for sub in 0..steps {
            let a = (sub as f64 + 0.5) / steps as f64;
            for lane in lanes.iter_mut().flatten() {
                if i < lane.job.samples {
                    lane.substep(i, a);
                }
            }
        }
        for slot in lanes.iter_mut() {
            if let Ok(lane) = slot
                && i < lane.job.samples
                && let Err(e) = lane.end_sample(i, fs_hz)
            {
                *slot = Err(e);
            }
        }
    }
    lanes.into_iter().map(|l| l.map(|l| l.out)).collect()
}

/// One run of [`simulate_batch`] under way: its job, the step's constants,
/// its state and its channels so far.
struct Lane<'a, F> {
    job: OneDofJob<'a, F>,
    /// The substep, s.
    h: f64,
    /// k, c, c_a, J of the shaft; k_1, k_2, c_1, c_2 its sections (k, c without mid inertia).
    k: f64,
    c: f64,
    ca: f64,
    jb: f64,
    k1: f64,
    k2: f64,
    c1: f64,
    c2: f64,
    s: OneDofState,
    /// The bit's acceleration and the contact's torque at the last substep.
    acc: f64,
    fric: f64,
    out: OneDofRun,
}

impl<'a, F: Friction> Lane<'a, F> {
    /// Checks `job` and starts its run at sample 0 (module docs).
    fn begin(job: OneDofJob<'a, F>, fs_hz: f64, steps: usize) -> Result<Self, ModelError> {
        let (shaft, drive, normal_scale, samples) = (&job.shaft, job.drive, job.normal_scale, job.samples);
        if samples < 2 {
            return Err(invalid("samples", samples as f64, "at least 2"));
        }
        let series_ok = |x: &[f64]| x.len() == samples;
        match drive {
            Drive::Speed(u) if !series_ok(u) => {
                return Err(invalid("drive speed", u.len() as f64, "one value per sample"));
            }
            Drive::SpeedLoop { reference_rad_s: r, .. } if !series_ok(r) => {
                return Err(invalid("drive reference", r.len() as f64, "one value per sample"));
            }
            _ => {}
        }
        if normal_scale.is_some_and(|g| !series_ok(g)) {
            return Err(invalid("normal_scale", normal_scale.map_or(0, |g| g.len()) as f64, "one value per sample"));
        }
        for (name, v) in
            [("inertia_kgm2", shaft.inertia_kgm2), ("stiffness_nm_rad", shaft.stiffness_nm_rad), ("fs_hz", fs_hz)]
        {
            if !(v > 0.0 && v.is_finite()) {
                return Err(invalid(name, v, "must be finite and > 0"));
            }
        }
        if let Some(m) = shaft.mid
            && !(m.inertia_kgm2 > 0.0 && m.split > 0.0 && m.split < 1.0)
        {
            return Err(invalid("mid", m.split, "mid inertia > 0 and split in (0, 1)"));
        }
        let h = 1.0 / (fs_hz * steps as f64);
        let (k, c, ca, jb) =
            (shaft.stiffness_nm_rad, shaft.twist_damping_nm_s_rad, shaft.absolute_damping_nm_s_rad, shaft.inertia_kgm2);
        let (k1, k2, c1, c2) = match shaft.mid {
            Some(d) => (k / d.split, k / (1.0 - d.split), c / d.split, c / (1.0 - d.split)),
            None => (k, k, c, c),
        };
        let mut lane = Lane {
            job,
            h,
            k,
            c,
            ca,
            jb,
            k1,
            k2,
            c1,
            c2,
            s: job.start,
            acc: 0.0,
            fric: 0.0,
            out: OneDofRun {
                bit_rad_s: Vec::with_capacity(samples),
                top_rad_s: Vec::with_capacity(samples),
                twist_rad: Vec::with_capacity(samples),
                friction_nm: Vec::with_capacity(samples),
                accel_rad_s2: Vec::with_capacity(samples),
                stuck: Vec::with_capacity(samples),
            },
        };
        if !matches!(drive, Drive::SpeedLoop { .. }) {
            lane.s.top_rad_s = lane.imposed(0);
        }
        if lane.s.stuck {
            lane.s.bit_rad_s = 0.0;
        }
        let s = lane.s;
        let f0 = if s.stuck {
            lane.lower_torque(s.top_rad_s)
        } else {
            let g0 = normal_scale.map_or(1.0, |g| g[0]);
            s.bit_rad_s.signum() * job.law.slip_nm(s.bit_rad_s.abs(), g0, &s.friction_state)
        };
        ImplicitSink::push(&mut lane.out, &s, f0, 0.0);
        Ok(lane)
    }

    /// The imposed top speed at sample `i` (NaN under a speed loop).
    fn imposed(&self, i: usize) -> f64 {
        match self.job.drive {
            Drive::Speed(u) => u[i],
            Drive::ConstantSpeed(v) => v,
            Drive::SpeedLoop { .. } => f64::NAN,
        }
    }

    /// Torque of the (lower) shaft section on the bit, with the top at `top_rad_s`.
    #[inline(always)]
    fn lower_torque(&self, top_rad_s: f64) -> f64 {
        let s = &self.s;
        match self.job.shaft.mid {
            Some(_) => self.k2 * s.twist_rad + self.c2 * (s.mid_rad_s - s.bit_rad_s),
            None => self.k * s.twist_rad + self.c * (top_rad_s - s.bit_rad_s),
        }
    }

    /// One substep of the interval before sample `i`, at its fraction `a` (module docs).
    #[inline(always)]
    fn substep(&mut self, i: usize, a: f64) {
        let (law, drive, h) = (self.job.law, self.job.drive, self.h);
        let lin = |x: &[f64]| x[i - 1] + a * (x[i] - x[i - 1]);
        let top = match drive {
            Drive::SpeedLoop { .. } => self.s.top_rad_s,
            Drive::Speed(u) => lin(u),
            Drive::ConstantSpeed(v) => v,
        };
        let g = self.job.normal_scale.map_or(1.0, lin);
        // Torque the shaft applies to the bit, and at the top.
        let drive_bit = self.lower_torque(top);
        let shaft_top = match self.job.shaft.mid {
            Some(_) => self.k1 * self.s.upper_twist_rad + self.c1 * (top - self.s.mid_rad_s),
            None => drive_bit,
        };
        let s = &mut self.s;
        let ts = law.static_nm(g, &s.friction_state);
        if s.stuck && ts.is_none_or(|ts| drive_bit.abs() > ts) {
            s.stuck = false;
            let held = ts.map(|t| t * drive_bit.signum());
            law.step_state(&mut s.friction_state, 0.0, g, held.map(f64::abs), h);
        }
        if s.stuck {
            self.acc = 0.0;
            self.fric = drive_bit;
            law.step_state(&mut s.friction_state, 0.0, g, Some(drive_bit.abs()), h);
        } else {
            let om = s.bit_rad_s;
            let dir = if om != 0.0 { om.signum() } else { drive_bit.signum() };
            law.step_state(&mut s.friction_state, om.abs(), g, if om == 0.0 { ts } else { None }, h);
            let mag = if om == 0.0 {
                ts.unwrap_or_else(|| law.slip_nm(0.0, g, &s.friction_state))
            } else {
                law.slip_nm(om.abs(), g, &s.friction_state)
            };
            self.fric = dir * mag;
            self.acc = (drive_bit - self.ca * om - self.fric) / self.jb;
            let next = om + h * self.acc;
            let holds = ts.is_some_and(|ts| drive_bit.abs() <= ts);
            if (next == 0.0 || next.signum() != dir) && holds {
                s.stuck = true;
                s.bit_rad_s = 0.0;
                self.acc = 0.0;
            } else {
                s.bit_rad_s = next;
            }
        }
        if let Some(d) = self.job.shaft.mid {
            s.mid_rad_s += h * (shaft_top - drive_bit) / d.inertia_kgm2;
            s.upper_twist_rad += h * (top - s.mid_rad_s);
            s.twist_rad += h * (s.mid_rad_s - s.bit_rad_s);
        } else {
            s.twist_rad += h * (top - s.bit_rad_s);
        }
        if let Drive::SpeedLoop { inertia_kgm2, kp_nm_s_rad, ki_nm_rad, reference_rad_s } = drive {
            let r = lin(reference_rad_s);
            let motor = kp_nm_s_rad * (r - s.top_rad_s) + ki_nm_rad * s.loop_integral_rad;
            s.top_rad_s += h * (motor - shaft_top) / inertia_kgm2;
            s.loop_integral_rad += h * (r - s.top_rad_s);
        }
    }

    /// Closes sample `i`: the state checked, the top read, the sample kept.
    fn end_sample(&mut self, i: usize, fs_hz: f64) -> Result<(), ModelError> {
        let s = &mut self.s;
        let finite =
            [s.bit_rad_s, s.twist_rad, s.upper_twist_rad, s.mid_rad_s, s.top_rad_s].iter().all(|v| v.is_finite());
        if !finite || s.bit_rad_s.abs() > 1e4 {
            return Err(ModelError::IntegratorFailed {
                time_s: i as f64 / fs_hz,
                reason: format!("state left the physical range at sample {i}"),
            });
        }
        if !matches!(self.job.drive, Drive::SpeedLoop { .. }) {
            self.s.top_rad_s = self.imposed(i);
        }
        ImplicitSink::push(&mut self.out, &self.s, self.fric, self.acc);
        Ok(())
    }
}

#[cfg(test)]
mod tests;
