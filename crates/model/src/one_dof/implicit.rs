//! Implicit contact (Moreau time stepping): the option a stiff or set-valued
//! friction law with an internal state needs (rate and state at creep
//! speeds). Additive: [`simulate`](super::simulate) and its trajectories are
//! untouched.

use super::*;

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
    if ln_s > LN_S_OVERFLOW {
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

/// The largest x whose `exp` is finite, 709.782712893384 (the float below
/// ln f64::MAX, 0x40862E42FEFA39EF): `x.exp() == ∞` exactly where
/// `x > LN_S_OVERFLOW` (its exp is ≈ 107 ulps below f64::MAX, the next
/// float's ≈ 400 above: no rounding of `exp` moves either across; a NaN is
/// neither). [`rate_state_implicit_speed`] tests this where it took an
/// `exp` per step to the same effect (test `the_overflow_bound_is_exps`).
pub const LN_S_OVERFLOW: f64 = 709.782_712_893_384;

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
