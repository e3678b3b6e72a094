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

// ---------------------------------------------------------------------------
// Implicit contact (Moreau time stepping): the option a stiff or set-valued
// friction law with an internal state needs (rate and state at creep speeds).
// Additive: `simulate` above and its trajectories are untouched.
// ---------------------------------------------------------------------------

/// A contact law solved implicitly in the new speed (Moreau's time stepping;
/// Acary & Brogliato, *Numerical methods for nonsmooth dynamical systems*,
/// 2008, ch. 10): each step solves Ω⁺ + (h/J) T(Ω⁺, state) ∋ p for Ω⁺, where
/// p is the speed every other force alone would give after the step and T
/// the contact's torque, set-valued at Ω⁺ = 0 (a stuck contact holds any
/// torque up to its static level). A law stiff in Ω (rate and state at creep
/// speeds: (∂T/∂Ω)/J ≈ 10⁸ s⁻¹ on the spring–slider) is then stable at any
/// step; explicit friction as in [`simulate`] would need steps of 10 ns.
pub trait ImplicitFriction {
    /// The state at rest (before the first step), given the drive speed the
    /// run is driven at (rad/s): e.g. θ = Dc/V, the steady state of sliding at V.
    fn initial_state(&self, drive_rad_s: f64) -> [f64; MAX_FRICTION_STATES];
    /// One step: returns Ω⁺ and the contact torque (signed, resisting) with
    /// Ω⁺ + `h_over_inertia` · torque = `p_rad_s`; updates `stuck` (Ω⁺ = 0 held
    /// by the contact) and advances `state` over `h_s` at Ω⁺.
    fn implicit_step(
        &self,
        state: &mut [f64; MAX_FRICTION_STATES],
        stuck: &mut bool,
        p_rad_s: f64,
        h_over_inertia: f64,
        h_s: f64,
    ) -> (f64, f64);
}

/// The implicit step of a law with a static level and a kinetic law
/// `kinetic_nm(|Ω|)` (Coulomb when constant): stuck (Ω⁺ = 0) while the
/// static level (the kinetic level at 0 once sliding) can hold p; else
/// sliding at the kinetic law, solved by three fixed-point passes (the law
/// varies slowly with Ω), sticking when Ω⁺ would change sign. Returns Ω⁺
/// and the signed contact torque.
pub fn implicit_coulomb_step(
    p_rad_s: f64,
    h_over_inertia: f64,
    static_nm: f64,
    kinetic_nm: impl Fn(f64) -> f64,
    stuck: &mut bool,
) -> (f64, f64) {
    let bound = if *stuck { static_nm } else { kinetic_nm(0.0) };
    if p_rad_s.abs() <= h_over_inertia * bound {
        *stuck = true;
        return (0.0, p_rad_s / h_over_inertia);
    }
    *stuck = false;
    let sign = p_rad_s.signum();
    let mut v = p_rad_s - h_over_inertia * kinetic_nm(0.0) * sign;
    for _ in 0..3 {
        let next = p_rad_s - h_over_inertia * kinetic_nm(v.abs()) * sign;
        if next.signum() != sign {
            *stuck = true;
            return (0.0, p_rad_s / h_over_inertia);
        }
        v = next;
    }
    (v, (p_rad_s - v) / h_over_inertia)
}

impl ImplicitFriction for Coulomb {
    fn initial_state(&self, _: f64) -> [f64; MAX_FRICTION_STATES] {
        [0.0; MAX_FRICTION_STATES]
    }
    fn implicit_step(
        &self,
        _: &mut [f64; MAX_FRICTION_STATES],
        stuck: &mut bool,
        p: f64,
        h_over_inertia: f64,
        _: f64,
    ) -> (f64, f64) {
        implicit_coulomb_step(p, h_over_inertia, self.static_nm, |_| self.kinetic_nm, stuck)
    }
}

/// Dieterich–Ruina rate-and-state friction with the ageing law (Ruina 1983;
/// Baumberger & Caroli, Adv. Phys. 55, 279 (2006), §3), in the form
/// regularised at Ω = 0 of Rice, Lapusta & Ranjith (J. Mech. Phys. Solids 49,
/// 1865 (2001), Eq. 4):
///
/// T = N a asinh(Ω/(2Ω*) · e^{ψ/a}),  ψ = μ0 + b ln(Ω* θ/Dc),  dθ/dt = 1 − |Ω| θ/Dc,
///
/// which is μ0 + a ln(Ω/Ω*) + b ln(Ω*θ/Dc) for Ω ≫ Ω* e^{−ψ/a}. `normal`
/// N is the normal load (N m per unit μ: the torque at μ = 1); speeds and
/// Dc in the same unit of angle (rad, or m for a slider in translation).
/// The state θ is `state[0]` (s); `state[1]` keeps the last step's
/// u = asinh(|Ω|/s), where the next step's Newton iteration starts (0 at
/// rest). The law has no stuck phase: at rest it
/// creeps (Ω tiny, finite), which is the physics of the creep before slip.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RateStateAgeing {
    pub normal_nm: f64,
    pub mu0: f64,
    pub a: f64,
    pub b: f64,
    pub dc_rad: f64,
    pub v_ref_rad_s: f64,
}

impl ImplicitFriction for RateStateAgeing {
    fn initial_state(&self, drive_rad_s: f64) -> [f64; MAX_FRICTION_STATES] {
        let mut s = [0.0; MAX_FRICTION_STATES];
        s[0] = self.dc_rad / drive_rad_s.abs().max(1e-300);
        s
    }
    fn implicit_step(
        &self,
        state: &mut [f64; MAX_FRICTION_STATES],
        stuck: &mut bool,
        p: f64,
        h_over_inertia: f64,
        h_s: f64,
    ) -> (f64, f64) {
        let psi = self.mu0 + self.b * (self.v_ref_rad_s * state[0] / self.dc_rad).ln();
        // ln s, s = 2Ω* e^{−ψ/a}: s itself underflows for ψ/a beyond ~700.
        let ln_s = (2.0 * self.v_ref_rad_s).ln() - psi / self.a;
        let (v, u) = rate_state_implicit_speed(p, h_over_inertia * self.normal_nm, self.a, ln_s, state[1]);
        state[0] = ageing_law_step(state[0], v.abs(), h_s, self.dc_rad);
        state[1] = u;
        *stuck = false;
        (v, (p - v) / h_over_inertia)
    }
}

/// Solves v + hn · a · asinh(v/s) = p for v (hn = h N/J, s = 2Ω* e^{−ψ/a},
/// given by ln s: s itself underflows where a long-aged contact makes ψ/a
/// large): the implicit step of [`RateStateAgeing`]; returns (v, u) with
/// u = asinh(|v|/s). Through u, f(u) = s sinh u + hn a u − |p| is increasing
/// and convex for u > 0, with s sinh u evaluated as ½(e^{u + ln s} − e^{ln s − u}).
/// Newton starts at `u_guess` (the last step's u: a step changes u little,
/// so two or three iterations instead of tens) clamped into
/// [0, min(|p|/(hn a), asinh(|p|/s))], the interval that holds the root;
/// started below the root, the first step lands above it (convexity) and
/// the iteration then descends monotonically.
///
/// That descent is slow where the first step overshoots far: above the root
/// s sinh u dominates and Newton gains about one unit of u per iteration, so
/// a start far below the root (u = 0 at the first step of a run, the first
/// step landing near |p|/(hn a), hundreds above the root) can use up the 100
/// iterations; and where u is below ~1e-4 the two exponentials of s sinh u
/// cancel to a few digits (to none when u is below an ulp of ln s, as for
/// every speed of a contact with s ≫ 1) and Newton does not meet its
/// tolerance. The u reached is then no solution (|v| ≫ |p|, which the
/// equation forbids: a slider at 4.3 mm/s given 1.75 m/s, whose state
/// θ = Dc/|v| then made s overflow and s sinh u = ∞ − ∞ a NaN two steps
/// later; or v = 0 for |v| ≈ |p|); so a search that has not converged in
/// 100 iterations starts again from the interval's upper end, above the
/// root, with s sinh u as e^{ln s} sinh u below u = 1. A search that
/// converges in the first 100 is the one it always was. A result that still does not
/// converge, or a NaN in `p` or `ln_s`, is returned as a NaN speed, which the
/// integrator's finite-state check turns into [`ModelError::IntegratorFailed`].
/// Where s itself overflows (ln s above ~709.78: a contact so young that the
/// law's friction N a asinh(|v|/s) vanishes to the last digit) the root is
/// v = p/(1 + hn a/s) in closed form (u = |v|/s, no Newton), where
/// ½(e^{u + ln s} − e^{ln s − u}) would be ∞ − ∞.
pub fn rate_state_implicit_speed(p: f64, hn: f64, a: f64, ln_s: f64, u_guess: f64) -> (f64, f64) {
    let (sign, p) = (p.signum(), p.abs());
    if p == 0.0 {
        return (0.0, 0.0);
    }
    let c = hn * a;
    // (s sinh u, s cosh u) from two exponentials.
    let s_sinh_cosh = |u: f64| {
        let (e_plus, e_minus) = ((u + ln_s).exp(), (ln_s - u).exp());
        (0.5 * (e_plus - e_minus), 0.5 * (e_plus + e_minus))
    };
    // asinh(p/s) = ln(p/s + √((p/s)² + 1)), ≈ ln(2p) − ln s when p/s is large.
    let ratio_ln = p.ln() - ln_s;
    let upper = if ratio_ln > 20.0 { std::f64::consts::LN_2 + ratio_ln } else { ratio_ln.exp().asinh() };
    let hi = (p / c).min(upper);
    if hi.is_nan() {
        return (f64::NAN, f64::NAN);
    }
    if ln_s.exp() == f64::INFINITY {
        // s sinh u = s u to the last digit (u < e^{ln p − ln s} < e^{−300}).
        let v = p / (1.0 + c * (-ln_s).exp());
        return (sign * v, (v.ln() - ln_s).exp());
    }
    // The same, without the cancellation of the two exponentials for u < 1
    // (there s sinh u = e^{ln s} sinh u, finite: e^{ln s} overflows above).
    let s_sinh_cosh_small = |u: f64| {
        if u < 1.0 {
            let s = ln_s.exp();
            (s * u.sinh(), s * u.cosh())
        } else {
            s_sinh_cosh(u)
        }
    };
    let newton = |mut u: f64, s_sinh_cosh: &dyn Fn(f64) -> (f64, f64)| {
        for _ in 0..100 {
            let (sh, ch) = s_sinh_cosh(u);
            let step = (sh + c * u - p) / (ch + c);
            u -= step;
            if step.abs() <= 1e-12 * u.abs().max(1e-300) {
                return Some(u);
            }
        }
        None
    };
    // u_guess into [0, hi] (hi ≥ 0 and not NaN here; a NaN u_guess stays NaN).
    let start = if u_guess < 0.0 {
        0.0
    } else if u_guess > hi {
        hi
    } else {
        u_guess
    };
    if let Some(u) = newton(start, &s_sinh_cosh) {
        return (sign * s_sinh_cosh(u).0, u);
    }
    match newton(hi, &s_sinh_cosh_small) {
        Some(u) => (sign * s_sinh_cosh_small(u).0, u),
        None => (f64::NAN, f64::NAN),
    }
}

/// The ageing law dθ/dt = 1 − v θ/Dc advanced exactly over `h_s` at constant
/// speed `v` (≥ 0): θ → Dc/v + (θ − Dc/v) e^{−v h/Dc} (θ + h (1 − vθ/Dc) below
/// v h/Dc = 1e-9, where the exponential form loses its digits).
pub fn ageing_law_step(theta_s: f64, v: f64, h_s: f64, dc: f64) -> f64 {
    let r = v * h_s / dc;
    if r < 1e-9 {
        return theta_s + h_s * (1.0 - v * theta_s / dc);
    }
    let ss = dc / v;
    ss + (theta_s - ss) * (-r).exp()
}

/// Integrates a shaft without mid inertia, driven at an imposed speed
/// (`Drive::Speed` or `Drive::ConstantSpeed`), with the contact solved
/// implicitly ([`ImplicitFriction`]): symplectic Euler with the friction
/// implicit in the new speed,
///
/// p = Ω + h (k φ + c (Ω_top − Ω) − c_a Ω)/J,  Ω⁺ + (h/J) T(Ω⁺) ∋ p,  φ⁺ = φ + h (Ω_top − Ω⁺),
///
/// the equation of the module docs. The linear oscillator keeps its energy
/// on average (no numerical damping of an undamped oscillation; period
/// error (ωh)²/24, 0.016 % at 100 steps per natural period). Starts from
/// `start` (its `friction_state` as given: see
/// [`ImplicitFriction::initial_state`]); `substeps` steps per sample.
#[allow(clippy::too_many_arguments)]
pub fn simulate_implicit<F: ImplicitFriction>(
    shaft: &Shaft,
    law: &F,
    drive: Drive,
    start: OneDofState,
    fs_hz: f64,
    samples: usize,
    substeps: usize,
) -> Result<OneDofRun, ModelError> {
    let mut out = OneDofRun::default();
    simulate_implicit_into(shaft, law, drive, start, fs_hz, samples, substeps, &mut out)?;
    Ok(out)
}

/// [`simulate_implicit`] into a caller's run, its allocations reused (a
/// batch's per-thread buffer); the run's channels are overwritten.
#[allow(clippy::too_many_arguments)]
pub fn simulate_implicit_into<F: ImplicitFriction>(
    shaft: &Shaft,
    law: &F,
    drive: Drive,
    start: OneDofState,
    fs_hz: f64,
    samples: usize,
    substeps: usize,
    out: &mut OneDofRun,
) -> Result<(), ModelError> {
    for ch in [&mut out.bit_rad_s, &mut out.top_rad_s, &mut out.twist_rad, &mut out.friction_nm, &mut out.accel_rad_s2]
    {
        ch.clear();
    }
    out.stuck.clear();
    let mut s = start;
    simulate_implicit_extend(shaft, law, drive, &mut s, fs_hz, samples, substeps, out)
}

/// Where [`simulate_implicit_extend`] puts each sample: a [`OneDofRun`]
/// keeps every channel; a caller that reads fewer (the spring–slider reads
/// the twist alone) implements this for what it reads, and the steps, the
/// same code, are the same bits.
pub trait ImplicitSink {
    /// Samples held (the run's length: where a continued run resumes).
    fn samples(&self) -> usize;
    /// Room for `more` samples.
    fn reserve(&mut self, more: usize);
    /// One sample: the state after it, the contact's torque and the bit's
    /// acceleration over its last step.
    fn push(&mut self, state: &OneDofState, friction_nm: f64, accel_rad_s2: f64);
}

impl ImplicitSink for OneDofRun {
    fn samples(&self) -> usize {
        self.stuck.len()
    }
    fn reserve(&mut self, more: usize) {
        for ch in [
            &mut self.bit_rad_s,
            &mut self.top_rad_s,
            &mut self.twist_rad,
            &mut self.friction_nm,
            &mut self.accel_rad_s2,
        ] {
            ch.reserve(more);
        }
        self.stuck.reserve(more);
    }
    fn push(&mut self, s: &OneDofState, friction_nm: f64, accel_rad_s2: f64) {
        self.bit_rad_s.push(s.bit_rad_s);
        self.top_rad_s.push(s.top_rad_s);
        self.twist_rad.push(s.twist_rad);
        self.friction_nm.push(friction_nm);
        self.accel_rad_s2.push(accel_rad_s2);
        self.stuck.push(s.stuck);
    }
}

/// [`simulate_implicit_into`] continued: `out` (a run this made or left
/// empty, or any [`ImplicitSink`]) grows to `samples` samples from `state`,
/// the state at its last sample as the previous call left it (an empty run
/// starts at `state`, as [`simulate_implicit_into`] from it). Every step is
/// the one the longer run from the start would take, so a run made in
/// pieces is bit for bit the run made at once (a caller that lengthens a
/// simulated stretch pays only for the added samples).
#[allow(clippy::too_many_arguments)]
pub fn simulate_implicit_extend<F: ImplicitFriction>(
    shaft: &Shaft,
    law: &F,
    drive: Drive,
    state: &mut OneDofState,
    fs_hz: f64,
    samples: usize,
    substeps: usize,
    out: &mut impl ImplicitSink,
) -> Result<(), ModelError> {
    if samples < 2 {
        return Err(invalid("samples", samples as f64, "at least 2"));
    }
    if shaft.mid.is_some() {
        return Err(invalid("mid", f64::NAN, "the implicit contact is for a shaft without mid inertia"));
    }
    let top_at = |i: usize, a: f64| -> Result<f64, ModelError> {
        match drive {
            Drive::ConstantSpeed(v) => Ok(v),
            Drive::Speed(u) if u.len() == samples => Ok(if a == 0.0 { u[i] } else { u[i - 1] + a * (u[i] - u[i - 1]) }),
            Drive::Speed(u) => Err(invalid("drive speed", u.len() as f64, "one value per sample")),
            Drive::SpeedLoop { .. } => {
                Err(invalid("drive", f64::NAN, "the implicit contact takes an imposed speed, not a speed loop"))
            }
        }
    };
    for (name, v) in
        [("inertia_kgm2", shaft.inertia_kgm2), ("stiffness_nm_rad", shaft.stiffness_nm_rad), ("fs_hz", fs_hz)]
    {
        if !(v > 0.0 && v.is_finite()) {
            return Err(invalid(name, v, "must be finite and > 0"));
        }
    }
    let steps = substeps.max(1);
    let h = 1.0 / (fs_hz * steps as f64);
    let (k, c, ca, j) =
        (shaft.stiffness_nm_rad, shaft.twist_damping_nm_s_rad, shaft.absolute_damping_nm_s_rad, shaft.inertia_kgm2);
    let h_j = h / j;
    let s = state;
    let first = out.samples();
    out.reserve(samples.saturating_sub(first));
    if first == 0 {
        s.top_rad_s = top_at(0, 0.0)?;
        if s.stuck {
            s.bit_rad_s = 0.0;
        }
        // At sample 0 the contact is taken to balance the shaft (quasi-static start).
        out.push(s, k * s.twist_rad + c * (s.top_rad_s - s.bit_rad_s) - ca * s.bit_rad_s, 0.0);
    }
    for i in first.max(1)..samples {
        let (mut acc, mut fric) = (0.0, 0.0);
        for sub in 0..steps {
            let top = top_at(i, (sub as f64 + 0.5) / steps as f64)?;
            let om = s.bit_rad_s;
            let p = om + h_j * (k * s.twist_rad + c * (top - om) - ca * om);
            let (next, torque) = law.implicit_step(&mut s.friction_state, &mut s.stuck, p, h_j, h);
            acc = (next - om) / h;
            fric = torque;
            s.bit_rad_s = next;
            s.twist_rad += h * (top - next);
        }
        if !(s.bit_rad_s.is_finite() && s.twist_rad.is_finite()) {
            return Err(ModelError::IntegratorFailed {
                time_s: i as f64 / fs_hz,
                reason: format!("state left the physical range at sample {i}"),
            });
        }
        s.top_rad_s = top_at(i, 0.0)?;
        out.push(s, fric, acc);
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    const FS: f64 = 1000.0;

    fn shaft() -> Shaft {
        Shaft {
            inertia_kgm2: 0.05,
            stiffness_nm_rad: 2.0,
            twist_damping_nm_s_rad: 0.02,
            absolute_damping_nm_s_rad: 0.0,
            mid: None,
        }
    }

    const LAW: Coulomb = Coulomb { static_nm: 1.8, kinetic_nm: 1.0 };

    #[test]
    fn steady_slip_is_the_exact_fixed_point() {
        // Constant top speed 20 rad/s: the oscillation decays (ζ = 0.032, decay time
        // 2J/c = 5 s; 60 s leave e^{-12}); then Ω = 20 and k φ = T_k + c_a Ω.
        for ca in [0.0, 0.01] {
            let sh = Shaft { absolute_damping_nm_s_rad: ca, ..shaft() };
            // Started 0.01 rad off the fixed point: 0.01 e^{-12} is left.
            let start =
                OneDofState { bit_rad_s: 20.0, twist_rad: (1.0 + ca * 20.0) / 2.0 + 0.01, ..Default::default() };
            let r = simulate(&sh, &LAW, Drive::ConstantSpeed(20.0), None, start, FS, 60_000, 5).unwrap();
            let n = r.bit_rad_s.len() - 1;
            let om = r.bit_rad_s[n];
            // With c_a the bit lags: J·0 = kφ + c(20 − Ω) − c_a Ω − T_k and φ constant ⇒ Ω = 20.
            assert!((om - 20.0).abs() < 1e-6, "{om}");
            assert!((r.twist_rad[n] - (1.0 + ca * 20.0) / 2.0).abs() < 1e-6, "{}", r.twist_rad[n]);
            assert!((r.friction_nm[n] - 1.0).abs() < 1e-12);
        }
    }

    #[test]
    fn slow_drive_sticks_and_slips_at_the_coulomb_period() {
        // Undamped Coulomb stick-slip driven at v: stuck until kφ = T_s, then a slip
        // half-cycle of the harmonic oscillator about φ_k = T_k/k with amplitude
        // (T_s − T_k)/k, ending (Ω = 0) at φ = (2T_k − T_s)/k; stuck again while the
        // drive winds 2(T_s − T_k)/k. Period: π√(J/k) + 2(T_s − T_k)/(k v) (v ≪ amplitude·ω_n).
        let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
        let v = 0.2;
        let start = OneDofState { stuck: true, ..Default::default() };
        let r = simulate(&sh, &LAW, Drive::ConstantSpeed(v), None, start, FS, 30_000, 10).unwrap();
        let onsets: Vec<usize> = (1..r.stuck.len()).filter(|&i| r.stuck[i - 1] && !r.stuck[i]).collect();
        assert!(onsets.len() >= 4, "{onsets:?}");
        let period = (onsets[onsets.len() - 1] - onsets[1]) as f64 / FS / (onsets.len() - 2) as f64;
        let slip = std::f64::consts::PI * (0.05f64 / 2.0).sqrt();
        // The slip starts with Ω = v ≠ 0 (the drive winds on): the half-cycle is slightly
        // longer than π√(J/k); bound the period between the two idealisations.
        let expect = slip + 2.0 * 0.8 / (2.0 * v);
        assert!((period / expect - 1.0).abs() < 0.03, "{period} vs {expect}");
        // The contact never holds more than its static level.
        assert!(r.friction_nm.iter().all(|t| t.abs() <= 1.8 + 1e-9));
    }

    #[test]
    fn a_speed_series_and_a_constant_speed_agree() {
        let u = vec![3.0; 5000];
        let start = OneDofState { bit_rad_s: 3.0, twist_rad: 0.4, ..Default::default() };
        let a = simulate(&shaft(), &LAW, Drive::Speed(&u), None, start, FS, 5000, 5).unwrap();
        let b = simulate(&shaft(), &LAW, Drive::ConstantSpeed(3.0), None, start, FS, 5000, 5).unwrap();
        assert_eq!(a, b);
    }

    #[test]
    fn the_extensions_run_and_bad_input_is_refused() {
        let sh = Shaft { mid: Some(MidInertia { inertia_kgm2: 0.02, split: 0.5 }), ..shaft() };
        let u = vec![3.0; 10_000];
        let g = vec![1.1; 10_000];
        let drive = Drive::SpeedLoop { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0, reference_rad_s: &u };
        let start = OneDofState { top_rad_s: 3.0, ..Default::default() };
        let r = simulate(&sh, &LAW, drive, Some(&g), start, FS, 10_000, 5).unwrap();
        // The loop's integral makes the mean top speed follow its reference.
        let tail = &r.top_rad_s[5000..];
        assert!((tail.iter().sum::<f64>() / tail.len() as f64 - 3.0).abs() < 0.1);
        let bad = Shaft { inertia_kgm2: 0.0, ..shaft() };
        assert!(simulate(&bad, &LAW, Drive::ConstantSpeed(1.0), None, start, FS, 10, 1).is_err());
        assert!(simulate(&shaft(), &LAW, Drive::Speed(&u[..5]), None, start, FS, 10, 1).is_err());
    }

    /// A law with a static level, a falling slip level and a first-order lag
    /// (every branch of the core's contact: the state stepped stuck, at
    /// break-away and in slip).
    struct Lagged;

    impl Friction for Lagged {
        fn static_nm(&self, scale: f64, _: &[f64; MAX_FRICTION_STATES]) -> Option<f64> {
            Some(scale * 1.8)
        }
        fn slip_nm(&self, _: f64, _: f64, state: &[f64; MAX_FRICTION_STATES]) -> f64 {
            state[0]
        }
        fn step_state(
            &self,
            state: &mut [f64; MAX_FRICTION_STATES],
            speed: f64,
            scale: f64,
            held: Option<f64>,
            h: f64,
        ) {
            let target = held.unwrap_or_else(|| scale * (1.0 + 0.8 * (-speed / 0.5).exp()));
            state[0] += if held.is_some() { 1.0 } else { (h / 0.01).min(1.0) } * (target - state[0]);
        }
    }

    #[test]
    fn a_batch_gives_each_run_its_single_runs_bits() {
        // Runs of every kind, of different lengths, one refused and one that diverges:
        // in one batch each is bit for bit the run `simulate` makes of it alone, whatever
        // its neighbours (the batch reversed as well).
        let n = 6_000;
        let wavy: Vec<f64> = (0..n).map(|i| 1.0 + 0.8 * (i as f64 * 0.003).sin()).collect();
        let g: Vec<f64> = (0..n).map(|i| 1.0 + 0.2 * (i as f64 * 0.001).cos()).collect();
        let mid = Shaft { mid: Some(MidInertia { inertia_kgm2: 0.02, split: 0.4 }), ..shaft() };
        let soft = Shaft { inertia_kgm2: 1e-9, ..shaft() };
        let stuck = OneDofState { stuck: true, friction_state: [1.8, 0.0], ..Default::default() };
        let moving = OneDofState { bit_rad_s: 0.7, twist_rad: 0.6, top_rad_s: 1.0, ..Default::default() };
        let job = |shaft: Shaft, drive: Drive<'static>, scale: Option<&'static [f64]>, start, samples| OneDofJob {
            shaft,
            law: &Lagged,
            drive,
            normal_scale: scale,
            start,
            samples,
        };
        let (wavy, g): (&'static [f64], &'static [f64]) = (wavy.leak(), g.leak());
        let loop_drive =
            Drive::SpeedLoop { inertia_kgm2: 0.1, kp_nm_s_rad: 2.0, ki_nm_rad: 5.0, reference_rad_s: &wavy[..4_000] };
        let jobs = [
            job(shaft(), Drive::Speed(wavy), None, stuck, n),
            job(shaft(), Drive::Speed(wavy), Some(g), moving, n),
            job(mid, loop_drive, Some(&g[..4_000]), moving, 4_000),
            job(shaft(), Drive::ConstantSpeed(0.3), None, stuck, 2_500),
            job(shaft(), Drive::Speed(&wavy[..10]), None, stuck, n),
            job(soft, Drive::ConstantSpeed(50.0), None, moving, n),
        ];
        let alone: Vec<Result<OneDofRun, ModelError>> = jobs
            .iter()
            .map(|j| simulate(&j.shaft, j.law, j.drive, j.normal_scale, j.start, FS, j.samples, 5))
            .collect();
        assert!(alone[..4].iter().all(|r| r.is_ok()) && alone[4].is_err(), "four runs, one refusal");
        assert!(matches!(alone[5], Err(ModelError::IntegratorFailed { .. })), "{:?}", alone[5].as_ref().err());
        let stuck_samples = alone[0].as_ref().unwrap().stuck.iter().filter(|s| **s).count();
        assert!(stuck_samples > 100 && stuck_samples < n - 100, "stick-slip: {stuck_samples} stuck samples");
        let bits = |r: &Result<OneDofRun, ModelError>| match r {
            Ok(r) => {
                format!(
                    "{:?}",
                    [&r.bit_rad_s, &r.top_rad_s, &r.twist_rad, &r.friction_nm, &r.accel_rad_s2]
                        .map(|c| c.iter().map(|v| v.to_bits()).collect::<Vec<u64>>())
                ) + &format!("{:?}", r.stuck)
            }
            Err(e) => format!("{e:?}"),
        };
        let batch = simulate_batch(&jobs, FS, 5);
        let mut reversed = jobs;
        reversed.reverse();
        let mut back = simulate_batch(&reversed, FS, 5);
        back.reverse();
        for (i, r) in alone.iter().enumerate() {
            assert_eq!(bits(&batch[i]), bits(r), "job {i} in the batch");
            assert_eq!(bits(&back[i]), bits(r), "job {i} in the batch reversed");
        }
    }

    #[test]
    fn rate_state_implicit_speed_solves_its_equation() {
        for &(p, hn, a, s) in &[(1e-3, 1e-3, 0.01, 1e-12), (-2e-4, 5e-4, 0.02, 1e-6), (5e-2, 1e-3, 0.005, 1e-3)] {
            for guess in [f64::INFINITY, 0.0, 3.0, 40.0] {
                let (v, _) = rate_state_implicit_speed(p, hn, a, f64::ln(s), guess);
                let r = v + hn * a * (v / s).asinh() - p;
                assert!(r.abs() < 1e-12 * p.abs().max(1e-9), "residual {r} from {guess}");
            }
        }
        // A long-aged contact: s = e^{-800} underflows; v stays finite and solves the equation.
        for guess in [0.0, 900.0] {
            let (v, u) = rate_state_implicit_speed(1e-3, 1e-3, 0.01, -800.0, guess);
            assert!(v.is_finite() && v > 0.0, "{v}");
            let r = v + 1e-3 * 0.01 * u - 1e-3;
            assert!(r.abs() < 1e-15 && (u - ((2.0 * v).ln() + 800.0)).abs() < 1e-9, "residual {r}, u {u}");
        }
    }

    #[test]
    fn implicit_coulomb_sticks_and_slips_at_the_closed_form_levels() {
        // Undamped Coulomb stick-slip: the contact breaks away at the static level
        // T_s; the slip is an oscillation about T_k with amplitude
        // k √(D² + (v/ω)²), D = (T_s − T_k)/k (the drive keeps winding while the
        // bit starts from rest), so the torque peaks just above T_s and the slip
        // ends as far below T_k.
        let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
        let start = OneDofState { stuck: true, ..Default::default() };
        let r = simulate_implicit(&sh, &LAW, Drive::ConstantSpeed(0.2), start, FS, 30_000, 10).unwrap();
        let torque: Vec<f64> = r.twist_rad.iter().map(|p| sh.stiffness_nm_rad * p).collect();
        let max = torque.iter().cloned().fold(f64::MIN, f64::max);
        let min = torque[10_000..].iter().cloned().fold(f64::MAX, f64::min);
        let amplitude = sh.stiffness_nm_rad * (0.4f64.powi(2) + (0.2f64 / (2.0f64 / 0.05).sqrt()).powi(2)).sqrt();
        assert!((max - (1.0 + amplitude)).abs() < 1e-3, "peak {max} vs {}", 1.0 + amplitude);
        assert!((min - (1.0 - amplitude)).abs() < 1e-3, "end of slip {min} vs {}", 1.0 - amplitude);
        let bad = Shaft { mid: Some(MidInertia { inertia_kgm2: 0.02, split: 0.5 }), ..shaft() };
        assert!(simulate_implicit(&bad, &LAW, Drive::ConstantSpeed(0.2), start, FS, 10, 1).is_err());
    }

    #[test]
    fn an_implicit_run_made_in_pieces_is_the_run_made_at_once() {
        // Stick-slip with rate and state (a friction state carried across the
        // pieces) and with Coulomb (the stuck flag): every channel bit for bit.
        let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
        let rs = RateStateAgeing { normal_nm: 1.0, mu0: 1.0, a: 0.01, b: 0.015, dc_rad: 1e-3, v_ref_rad_s: 0.1 };
        let drive = Drive::ConstantSpeed(0.2);
        let start =
            OneDofState { stuck: true, twist_rad: 0.5, friction_state: rs.initial_state(0.2), ..Default::default() };
        let whole = simulate_implicit(&sh, &rs, drive, start, FS, 9_000, 4).unwrap();
        let (mut run, mut state) = (OneDofRun::default(), start);
        for n in [2, 1_000, 1_001, 5_000, 9_000] {
            simulate_implicit_extend(&sh, &rs, drive, &mut state, FS, n, 4, &mut run).unwrap();
            assert_eq!(run.twist_rad.len(), n);
        }
        assert_eq!(run, whole);
        let (lo, hi) = whole.bit_rad_s.iter().fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
        assert!(hi - lo > 0.1, "the bit's speed moves: {lo}..{hi}");
        let whole = simulate_implicit(&sh, &LAW, drive, start, FS, 6_000, 4).unwrap();
        let (mut run, mut state) = (OneDofRun::default(), start);
        for n in [3_000, 6_000] {
            simulate_implicit_extend(&sh, &LAW, drive, &mut state, FS, n, 4, &mut run).unwrap();
        }
        assert_eq!(run, whole);
    }

    #[test]
    fn a_sink_that_keeps_the_twist_alone_gets_the_runs_twist() {
        // The steps do not depend on where the samples go: a sink keeping one
        // channel, filled in pieces, holds the full run's twist bit for bit.
        struct Twist(Vec<f64>);
        impl ImplicitSink for Twist {
            fn samples(&self) -> usize {
                self.0.len()
            }
            fn reserve(&mut self, more: usize) {
                self.0.reserve(more);
            }
            fn push(&mut self, s: &OneDofState, _: f64, _: f64) {
                self.0.push(s.twist_rad);
            }
        }
        let sh = Shaft { twist_damping_nm_s_rad: 0.0, ..shaft() };
        let rs = RateStateAgeing { normal_nm: 1.0, mu0: 1.0, a: 0.01, b: 0.015, dc_rad: 1e-3, v_ref_rad_s: 0.1 };
        let drive = Drive::ConstantSpeed(0.2);
        let start =
            OneDofState { stuck: true, twist_rad: 0.5, friction_state: rs.initial_state(0.2), ..Default::default() };
        let whole = simulate_implicit(&sh, &rs, drive, start, FS, 9_000, 4).unwrap();
        let (mut twist, mut state) = (Twist(Vec::new()), start);
        for n in [2, 4_000, 9_000] {
            simulate_implicit_extend(&sh, &rs, drive, &mut state, FS, n, 4, &mut twist).unwrap();
        }
        let bits = |v: &[f64]| v.iter().map(|x| x.to_bits()).collect::<Vec<u64>>();
        assert_eq!(bits(&twist.0), bits(&whole.twist_rad));
        let (lo, hi) = whole.twist_rad.iter().fold((f64::MAX, f64::MIN), |(l, h), v| (l.min(*v), h.max(*v)));
        assert!(hi - lo > 0.01, "the twist moves: {lo}..{hi}");
    }
}
