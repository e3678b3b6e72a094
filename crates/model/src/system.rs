//! The right-hand side of the rig equations for both model kinds (Eqs. 4-6,
//! 4-7 and 4-9 made consistent; see the crate docs for every interpretation),
//! the drive, and the stick/slip modes with their event functions.

use crate::dopri::{DIM, Vector};
use crate::extension::Extension;
use crate::friction::{
    cogging_nm, imbalance_torque_nm, normal_force_n, slip_mu, static_mu, thesis_lookup, torque_factor,
};
use rig_types::{Effect, FrictionLaw, HarmonicFriction, ModelKind, RigParams};

mod affine;

// State layout.
pub(crate) const PHI1: usize = 0;
pub(crate) const PHI2: usize = 1;
pub(crate) const W1: usize = 2;
pub(crate) const W2: usize = 3;
pub(crate) const CUR: usize = 4;
pub(crate) const INT: usize = 5;
/// The pad's state: the temperature rise ϑ of [`Effect::BrakeFade`], K, or
/// the stuck contact's age of [`Effect::StaticFrictionAging`], s (the two
/// cannot be combined; 0 without either).
pub(crate) const TEMP: usize = 6;

/// Armature speed scale of the rig model's motor friction, rad/s: T_f acts as
/// T_f·tanh(n Ω2 / this). The chapter's T_f is a constant torque (Eq. 4-6b),
/// which would spin a motor at rest backwards; a Coulomb term with its own
/// stick phase is not worth a second event type because the drive never lets
/// the motor stop in an operating point. 1 rad/s at the armature is 0.125 rad/s
/// (1.2 rpm) at the shaft for n = 8, well below the 5 rpm lowest set-point, and
/// keeps the term's eigenvalue (n² T_f / (n² J_m · 1 rad/s) ≈ 210 1/s) below
/// the electrical one (R/L ≈ 620 1/s).
pub const MOTOR_FRICTION_SPEED_RAD_S: f64 = 1.0;

/// Tracking time constant T_t of the back-calculation anti-windup, s. Short
/// against the closed speed loop (≈ 0.1–1 s) so the integral stays at the
/// limit while saturated; long against nothing the integrator must resolve
/// (its eigenvalue 1/T_t = 100 1/s is below the electrical R/L ≈ 620 1/s).
pub const ANTI_WINDUP_TRACKING_S: f64 = 0.01;

/// Armature speed |n Ω2| / [`MOTOR_FRICTION_SPEED_RAD_S`] above which the exact
/// propagator takes the rig model's motor friction T_f·tanh(·) as the constant
/// ±T_f: 1 − tanh(15) = 1.9·10⁻¹³, so the torque it drops is below
/// 2·10⁻¹³·T_f (2·10⁻¹⁴ N·m with Table 4.5), five orders below what the
/// default tolerance resolves (rtol 10⁻⁸ on torques of order 0.1 N·m).
pub(crate) const MOTOR_FRICTION_SATURATED: f64 = 15.0;

/// A region of the state space in which the right-hand side is affine in
/// (q, t): ż = M z with z = [q, t, 1] (module `exact`). Two states with equal
/// regions share M; a step whose end lies in another region is not exact.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) struct Region {
    pub mode: Mode,
    /// Drive voltage: −1/+1 clamped at ∓/± limit, 0 linear (always 0 for a voltage step).
    pub saturation: i8,
    /// Rig model: sign of the saturated motor friction ±T_f; thesis: 0 (T_f constant).
    pub motor_friction: i8,
    /// Segment of the affine friction law and the sign of Ω1 it applies to.
    pub friction_segment: i8,
    pub friction_sign: i8,
    /// Inside the reference ramp (its end is a breakpoint, so a step never crosses it).
    pub ramping: bool,
}

/// How the drive voltage follows from the state inside one [`Region`]
/// ([`System::voltage_in`]).
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum VoltageIn {
    /// The same value at every state of the region (clamped, or a voltage step).
    Constant(f64),
    /// The PI's unclamped kp·e + ki·∫e ([`System::pi_unclamped_of_v`]): the clamp is
    /// inactive in the region and there is no current limit.
    Unclamped,
}

/// What drives the motor.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Drive {
    /// Constant armature voltage (voltage step, drive bypassed).
    Voltage { voltage_v: f64 },
    /// PI speed loop on Ω2 following 0 → setpoint over `ramp_s` starting at `t_start_s`.
    Pi { setpoint_rad_s: f64, ramp_s: f64, t_start_s: f64 },
}

/// Mode of rotor 1.
#[derive(Debug, Clone, Copy, PartialEq)]
pub(crate) enum Mode {
    /// No brake contact (N0 = 0) or the thesis model (no stick phase): one
    /// smooth-ish right-hand side, no events.
    Continuous,
    /// Rig model, rotor 1 held by static friction: Ω1 = 0, φ1 constant.
    Stick,
    /// Rig model, slipping in direction `sign` (±1): T1 = sign·μ(|Ω1|)·N·r.
    Slip { sign: f64 },
}

/// Everything the right-hand side needs, precomputed once per run.
#[derive(Debug, Clone)]
pub(crate) struct System<'a> {
    pub p: &'a RigParams,
    pub kind: ModelKind,
    pub drive: Drive,
    pub n0: f64,
    /// Gear ratio n.
    gear: f64,
    /// 1 / (n² J_m): reflected motor inertia at the shaft, inverted once.
    inv_j_motor: f64,
    inv_j1: f64,
    inv_inductance: f64,
    /// Back-EMF at the shaft n·k_e and viscous loss at the shaft n²·C_m.
    ke_shaft: f64,
    cm_shaft: f64,
    /// Whether any effect, harmonic term or cogging is present (skips their loops).
    plain: bool,
    /// Whether N depends on t, φ1 or the pad state: a normal-force or
    /// angle-periodic modulation, harmonic friction on N, or brake fade.
    /// Without one [`System::normal_force_n`] is N0 whatever other effects
    /// there are (e.g. the diagnosis' friction extension alone).
    varying_n: bool,
    /// Whether the motor carries cogging ([`Effect::MotorCogging`]).
    cogging: bool,
    /// Whether the only effect is the diagnosis' friction extension with its
    /// break-away terms alone (slip coefficients 0, no harmonic term): the
    /// motion is then the plain model's in slip and in stick, only the
    /// break-away threshold (the stick mode's event) reads the pad state, so
    /// exact steps apply ([`System::region`]; module `sim` advances the pad
    /// state, the time since the last event, by each exact step's length).
    static_extension_only: bool,
    /// Whether the brake is open (N0 = 0) and every effect acts through the
    /// contact alone: a normal-force or angle-periodic modulation, harmonic
    /// friction, the static coefficient's ageing, the diagnosis' friction
    /// extension. T1 = μ·N·r is then 0 whatever N and μ would be
    /// ([`System::friction_torque_nm`]), so the motion is the plain model's
    /// and exact steps apply ([`System::region`]): e.g. the voltage steps of
    /// the motor-side refits of a model that carries N's modulation. Of the
    /// pad state only the extension's time since the last event moves (at
    /// the rate of time, [`System::exact_steps_age`]); the contact age
    /// stays, as there is no stick.
    open_contact_only: bool,
    /// Half the backlash gap b, rad (0: no backlash).
    half_gap_rad: f64,
    /// β of the cubic shaft, 1/rad² (0: linear).
    cubic_per_rad2: f64,
    /// No backlash and no cubic term: the shaft is Eq. 4-7's linear one.
    linear_shaft: bool,
    /// Whether the rotor carries an imbalance.
    imbalance: bool,
    /// Brake fade (C in J/K, τ in s, ϑ_fade in K), if any.
    fade: Option<(f64, f64, f64)>,
    /// Current limit I_max of the amplifier, A, if any.
    current_limit_a: Option<f64>,
    /// Static friction aging (B per e-fold, τ in s), if any; the contact age is `y[TEMP]`.
    aging: Option<(f64, f64)>,
    /// The diagnosis' friction extension, if any; the time since the last
    /// stick/slip event is `y[TEMP]` (crate::extension).
    extension: Option<Extension>,
    /// 1 / (ki T_t) of the anti-windup, inverted once instead of divided by
    /// on every right-hand side.
    inv_ki_tracking: f64,
}

impl<'a> System<'a> {
    pub fn new(p: &'a RigParams, drive: Drive, n0: f64) -> Self {
        let gear = p.motor.gear_ratio;
        let (mut half_gap_rad, mut cubic_per_rad2, mut imbalance, mut fade, mut current_limit_a, mut aging) =
            (0.0, 0.0, false, None, None, None);
        let (mut varying_n, mut cogging) = (matches!(p.harmonic, Some(HarmonicFriction::NormalForce { .. })), false);
        for e in &p.effects {
            match *e {
                Effect::NormalForceModulation { .. } | Effect::AnglePeriodicFriction { .. } => varying_n = true,
                Effect::MotorCogging { .. } => cogging = true,
                Effect::CouplingBacklash { gap_rad } => half_gap_rad += 0.5 * gap_rad,
                Effect::ShaftCubicStiffness { cubic_per_rad2: b } => cubic_per_rad2 += b,
                Effect::RotorImbalance { .. } => imbalance = true,
                Effect::BrakeFade { heat_capacity_j_k, cooling_time_s, fade_temperature_k } => {
                    varying_n = true;
                    fade = Some((heat_capacity_j_k, cooling_time_s, fade_temperature_k))
                }
                Effect::DriveCurrentLimit { current_limit_a: i } => current_limit_a = Some(i),
                Effect::StaticFrictionAging { aging_mu_per_efold, aging_time_s } => {
                    aging = Some((aging_mu_per_efold, aging_time_s))
                }
                _ => {}
            }
        }
        System {
            p,
            kind: p.kind,
            drive,
            n0,
            gear,
            inv_j_motor: 1.0 / (gear * gear * p.motor.inertia_kgm2),
            inv_j1: 1.0 / p.rotor_inertia_kgm2,
            inv_inductance: 1.0 / p.motor.inductance_h,
            ke_shaft: gear * p.motor.voltage_constant_v_s_rad,
            cm_shaft: gear * gear * p.motor.speed_regulation_nm_s_rad,
            plain: p.effects.is_empty() && p.harmonic.is_none(),
            varying_n,
            cogging,
            half_gap_rad,
            cubic_per_rad2,
            linear_shaft: half_gap_rad == 0.0 && cubic_per_rad2 == 0.0,
            imbalance,
            fade,
            current_limit_a,
            aging,
            extension: Extension::of(&p.effects),
            static_extension_only: p.harmonic.is_none()
                && !p.effects.is_empty()
                && p.effects.iter().all(|e| matches!(e, Effect::FrictionExtension { .. }))
                && Extension::of(&p.effects)
                    .is_some_and(|x| x.slip_speed_per_rad_s == 0.0 && x.breakaway_transient == 0.0),
            open_contact_only: n0 == 0.0
                && p.effects.iter().all(|e| {
                    matches!(
                        e,
                        Effect::NormalForceModulation { .. }
                            | Effect::AnglePeriodicFriction { .. }
                            | Effect::StaticFrictionAging { .. }
                            | Effect::FrictionExtension { .. }
                    )
                }),
            inv_ki_tracking: 1.0 / (p.drive.ki_v_rad * ANTI_WINDUP_TRACKING_S),
        }
    }

    /// Whether the state has the pad component (brake fade's temperature or
    /// static friction aging's contact age): the error norm then covers it.
    pub fn has_thermal_state(&self) -> bool {
        self.fade.is_some() || self.aging.is_some() || self.extension.is_some()
    }

    /// Whether the pad state is the stuck contact's age ([`Effect::StaticFrictionAging`]):
    /// it restarts at 0 whenever rotor 1 comes to rest.
    pub fn has_contact_age(&self) -> bool {
        self.aging.is_some() || self.extension.is_some()
    }

    /// Whether the pad state also restarts at break-away (the friction
    /// extension's time since break-away, crate::extension).
    pub fn has_slip_age(&self) -> bool {
        self.extension.is_some()
    }

    /// Whether exact steps must advance the pad state (the friction
    /// extension's time since the last event, dt/dt = 1 in both modes): a
    /// region exists with it only under [`System::static_extension_only`]'s
    /// or [`System::open_contact_only`]'s condition.
    pub fn exact_steps_age(&self) -> bool {
        self.static_extension_only || (self.open_contact_only && self.extension.is_some())
    }

    /// Whether friction can act at all (brake closed).
    pub fn brake_closed(&self) -> bool {
        self.n0 > 0.0
    }

    /// Speed reference at time t, rad/s at the shaft (motor side).
    #[inline]
    pub fn reference_rad_s(&self, t: f64) -> f64 {
        match self.drive {
            Drive::Voltage { .. } => 0.0,
            Drive::Pi { setpoint_rad_s, ramp_s, t_start_s } => {
                let elapsed = t - t_start_s;
                if ramp_s <= 0.0 || elapsed >= ramp_s {
                    setpoint_rad_s
                } else {
                    setpoint_rad_s * (elapsed / ramp_s).max(0.0)
                }
            }
        }
    }

    /// Armature voltage and the integrator rate d(∫e)/dt. PI with saturation
    /// and back-calculation anti-windup: the integral term I = ki·∫e obeys
    /// dI/dt = ki·e + (V − V_raw)/T_t, so while saturated it is pulled back to
    /// the limit with time constant T_t = [`ANTI_WINDUP_TRACKING_S`].
    /// Conditional integration (freeze ∫e while saturated) was tried first: it
    /// switches the right-hand side discontinuously on the saturation boundary,
    /// the integral then slides along it and the step size collapsed to
    /// round-off (20 million steps in 3.5 s of a saturated start-up).
    #[inline]
    pub fn voltage(&self, t: f64, y: &Vector) -> (f64, f64) {
        let (v, rate) = self.pi_voltage(t, y);
        match self.current_limit_a {
            None => (v, rate),
            // Effect::DriveCurrentLimit: the amplifier keeps the terminal voltage
            // within ±R·I_max of the back-EMF (Eq. 4-6a at di/dt = 0 and |i| = I_max).
            // The PI integral keeps its own rate: the loop does not see the limit.
            Some(i_max) => {
                let emf = self.ke_shaft * y[W2];
                let r_i = self.p.motor.resistance_ohm * i_max;
                (v.clamp(emf - r_i, emf + r_i), rate)
            }
        }
    }

    /// [`System::voltage`] inside `region`, where the clamp is decided and no
    /// current limit exists (regions require its absence): bit for bit the
    /// same values (test `affine_matrix_reproduces_rhs_and_output_shortcuts_are_exact`).
    #[inline]
    pub fn voltage_in(&self, region: &Region) -> VoltageIn {
        match self.drive {
            Drive::Voltage { voltage_v } => VoltageIn::Constant(voltage_v),
            Drive::Pi { .. } if region.saturation != 0 => {
                VoltageIn::Constant(f64::from(region.saturation) * self.p.drive.limit_v)
            }
            Drive::Pi { .. } => VoltageIn::Unclamped,
        }
    }

    /// The PI's unclamped voltage kp·e + ki·∫e, V, from the reference at t and
    /// the two states it reads, Ω2 and ∫e (the arithmetic of `pi_raw`).
    #[inline(always)]
    pub fn pi_unclamped_of_v(&self, reference_rad_s: f64, motor_speed_rad_s: f64, pi_integral_rad: f64) -> f64 {
        self.pi_law_v(reference_rad_s - motor_speed_rad_s, pi_integral_rad)
    }

    /// The PI law kp·e + ki·∫e, V: the one place it is written.
    #[inline(always)]
    fn pi_law_v(&self, error_rad_s: f64, pi_integral_rad: f64) -> f64 {
        let d = &self.p.drive;
        d.kp_v_s_rad * error_rad_s + d.ki_v_rad * pi_integral_rad
    }

    /// Whether [`System::friction_torque_nm`] takes one value at every state
    /// of `region`: the brake open, or rig-model slip (or the thesis lookup)
    /// on a segment whose coefficient does not depend on Ω1 (μ1 = 0: then
    /// μ0 + 0·|Ω1| is μ0 exactly).
    #[inline]
    pub fn friction_torque_constant_in(&self, region: &Region) -> bool {
        if !self.brake_closed() {
            return true;
        }
        let flat = |law: &FrictionLaw| match law {
            FrictionLaw::Coulomb { .. } => true,
            // Thesis lookup: the segments below zero (μneg) and above the dynamic set-point (μdyn).
            FrictionLaw::Thesis(_) => region.friction_segment == 0 || region.friction_segment == 3,
            FrictionLaw::Viscous { viscous_per_rad_s, .. } => *viscous_per_rad_s == 0.0,
            FrictionLaw::Stribeck { .. } => false,
        };
        match (self.kind, region.mode) {
            (ModelKind::Rig, Mode::Slip { .. }) => flat(&self.p.friction),
            (ModelKind::Rig, Mode::Continuous) => true,
            (ModelKind::Rig, Mode::Stick) => false,
            (ModelKind::Thesis, _) => matches!(self.p.friction, FrictionLaw::Thesis(_)) && flat(&self.p.friction),
        }
    }

    /// The speed error e and the unclamped voltage kp·e + ki·∫e of a PI drive.
    #[inline(always)]
    fn pi_raw(&self, t: f64, y: &Vector) -> (f64, f64) {
        let e = self.reference_rad_s(t) - y[W2];
        (e, self.pi_law_v(e, y[INT]))
    }

    #[inline]
    fn pi_voltage(&self, t: f64, y: &Vector) -> (f64, f64) {
        match self.drive {
            Drive::Voltage { voltage_v } => (voltage_v, 0.0),
            Drive::Pi { .. } => {
                let d = &self.p.drive;
                let (e, raw) = self.pi_raw(t, y);
                let v = raw.clamp(-d.limit_v, d.limit_v);
                let rate = if d.ki_v_rad == 0.0 { e } else { e + (v - raw) * self.inv_ki_tracking };
                (v, rate)
            }
        }
    }

    /// Torque the shaft applies to rotor 1 (and, reacted, to the motor side).
    /// Thesis (Eq. 4-7): k(φ2 − φ1); its damping C acts on Ω1 alone.
    /// Rig: k(φ2 − φ1) + C(Ω2 − Ω1): material damping of the twist rate.
    /// With backlash and/or a cubic shaft ([`Effect::CouplingBacklash`],
    /// [`Effect::ShaftCubicStiffness`]): K·δe(1 + β δe²) with δe the twist
    /// outside the dead zone, and the damping only in contact.
    #[inline]
    pub fn shaft_torque_nm(&self, y: &Vector) -> f64 {
        if !self.linear_shaft {
            return self.nonlinear_shaft_torque_nm(y);
        }
        let twist = self.p.shaft_stiffness_nm_rad * (y[PHI2] - y[PHI1]);
        match self.kind {
            ModelKind::Thesis => twist,
            ModelKind::Rig => twist + self.p.shaft_damping_nm_s_rad * (y[W2] - y[W1]),
        }
    }

    fn nonlinear_shaft_torque_nm(&self, y: &Vector) -> f64 {
        let delta = y[PHI2] - y[PHI1];
        let b = self.half_gap_rad;
        if delta.abs() <= b {
            return 0.0;
        }
        let de = delta - delta.clamp(-b, b);
        let elastic = self.p.shaft_stiffness_nm_rad * de * (1.0 + self.cubic_per_rad2 * de * de);
        match self.kind {
            ModelKind::Thesis => elastic,
            ModelKind::Rig => elastic + self.p.shaft_damping_nm_s_rad * (y[W2] - y[W1]),
        }
    }

    /// Net torque on rotor 1 other than brake friction: the shaft torque minus
    /// the gravity torque of an imbalance ([`Effect::RotorImbalance`]). Static
    /// friction must hold this torque in stick.
    #[inline]
    pub fn rotor_torque_nm(&self, y: &Vector) -> f64 {
        if self.imbalance {
            self.shaft_torque_nm(y) - imbalance_torque_nm(&self.p.effects, y[PHI1])
        } else {
            self.shaft_torque_nm(y)
        }
    }

    /// N(t, φ1) with its effects; under [`Effect::BrakeFade`] the fade factor
    /// 1/(1 + ϑ/ϑ_fade) is folded in here (it scales μs and μ alike).
    #[inline]
    pub fn normal_force_n(&self, t: f64, y: &Vector) -> f64 {
        // Without a modulation or fade the product below has no factor: N0 itself.
        if self.plain || !self.varying_n {
            return self.n0;
        }
        let n = normal_force_n(self.n0, &self.p.effects, self.p.harmonic.as_ref(), t, y[PHI1]);
        match self.fade {
            Some((_, _, fade_k)) => n / (1.0 + y[TEMP].max(0.0) / fade_k),
            None => n,
        }
    }

    #[inline]
    fn torque_factor(&self, t: f64) -> f64 {
        if self.plain || self.p.harmonic.is_none() { 1.0 } else { torque_factor(self.p.harmonic.as_ref(), t) }
    }

    /// Stick threshold μs·N·r (× |sin ω_p t| under Eq. 4-11 as published).
    #[inline]
    pub fn stick_limit_nm(&self, t: f64, y: &Vector) -> f64 {
        let factor = self.torque_factor(t).abs();
        let mu_s = match self.aging {
            // μs(t_stick) = μs + B ln(1 + t_stick/τ) (Effect::StaticFrictionAging).
            Some((b, tau_s)) => static_mu(&self.p.friction) + b * (y[TEMP].max(0.0) / tau_s).ln_1p(),
            None => static_mu(&self.p.friction),
        };
        let mu_s = match &self.extension {
            Some(x) => mu_s * x.static_factor(y[TEMP]),
            None => mu_s,
        };
        mu_s * self.normal_force_n(t, y) * self.p.brake_disc_radius_m * factor
    }

    /// Friction torque T1 on rotor 1 (positive opposes positive Ω1) in `mode`.
    #[inline]
    pub fn friction_torque_nm(&self, mode: Mode, t: f64, y: &Vector) -> f64 {
        if !self.brake_closed() {
            return 0.0;
        }
        let nr = self.normal_force_n(t, y) * self.p.brake_disc_radius_m * self.torque_factor(t);
        match (self.kind, mode) {
            // Eq. 4-10 (or 4-11) as published: a signed lookup, no stick phase.
            (ModelKind::Thesis, _) => match &self.p.friction {
                FrictionLaw::Thesis(f) => thesis_lookup(f, y[W1]) * nr,
                // A vocabulary law in the thesis model: symmetric slip law, no stick phase.
                law => slip_mu(law, y[W1]) * nr * sign_or_zero(y[W1]),
            },
            // Static friction balances the shaft (and gravity) exactly (Ω̇1 = 0).
            (ModelKind::Rig, Mode::Stick) => self.rotor_torque_nm(y),
            (ModelKind::Rig, Mode::Slip { sign }) => match &self.extension {
                Some(x) => sign * slip_mu(&self.p.friction, y[W1]) * x.slip_factor(y[W1].abs(), y[TEMP]) * nr,
                None => sign * slip_mu(&self.p.friction, y[W1]) * nr,
            },
            (ModelKind::Rig, Mode::Continuous) => 0.0,
        }
    }

    /// Motor-side internal friction at the armature: Eq. 4-6b's constant T_f
    /// for the thesis model; signed (regularised) for the rig model.
    fn motor_friction_nm(&self, w2: f64) -> f64 {
        let tf = self.p.motor.friction_torque_nm;
        match self.kind {
            ModelKind::Thesis => tf,
            ModelKind::Rig => tf * tanh_by_exp(self.gear * w2 / MOTOR_FRICTION_SPEED_RAD_S),
        }
    }

    /// Net motor torque delivered to the shaft end, before the shaft reaction:
    /// n·(k_T i − T_f − C_m·n·Ω2) + cogging (Eq. 4-6b with the gear made explicit).
    pub fn motor_drive_torque_nm(&self, y: &Vector) -> f64 {
        let m = &self.p.motor;
        let shaft =
            self.gear * (m.torque_constant_nm_a * y[CUR] - self.motor_friction_nm(y[W2])) - self.cm_shaft * y[W2];
        // Without cogging the sum below is +0.0, which changes only a shaft
        // torque of −0.0, i.e. a current of −0.0 exactly at Ω2 = +0.0: the
        // integration never makes −0.0 from a +0.0 start (x + y is −0.0 only
        // when both are), so the shortcut is the sum to the bit.
        if self.plain || !self.cogging { shaft } else { shaft + cogging_nm(&self.p.effects, y[PHI2]) }
    }

    /// dq/dt (Eq. 4-9 made consistent, q = [φ1 φ2 Ω1 Ω2 i ∫e]).
    pub fn rhs(&self, mode: Mode, t: f64, y: &Vector) -> Vector {
        let p = self.p;
        let m = &p.motor;
        let (v, int_rate) = self.voltage(t, y);
        let ts = self.shaft_torque_nm(y);
        let mut dy = [0.0; DIM];
        // Eq. 4-6a with the back-EMF of the armature speed n·Ω2.
        dy[CUR] = (v - m.resistance_ohm * y[CUR] - self.ke_shaft * y[W2]) * self.inv_inductance;
        dy[INT] = int_rate;
        // Eq. 4-7, second row, at the shaft: n² J_m Ω̇2 = n(k_T i − T_f − C_m n Ω2) − T_shaft.
        dy[PHI2] = y[W2];
        dy[W2] = (self.motor_drive_torque_nm(y) - ts) * self.inv_j_motor;
        if mode == Mode::Stick {
            if let Some((_, tau, _)) = self.fade {
                // Stuck: no friction power, the pad cools.
                dy[TEMP] = -y[TEMP] / tau;
            }
            if self.aging.is_some() || self.extension.is_some() {
                // Stuck: the contact ages at the rate of time.
                dy[TEMP] = 1.0;
            }
            return dy;
        }
        // Eq. 4-7, first row: J1 Ω̇1 = T_shaft − C Ω1 (thesis only) − C_r Ω1 − T1
        // (C_r: `rotor_damping_nm_s_rad`, 0 in the baseline).
        let absolute_damping = match self.kind {
            ModelKind::Thesis => (p.shaft_damping_nm_s_rad + p.rotor_damping_nm_s_rad) * y[W1],
            ModelKind::Rig => p.rotor_damping_nm_s_rad * y[W1],
        };
        let t1 = self.friction_torque_nm(mode, t, y);
        let gravity = if self.imbalance { imbalance_torque_nm(&p.effects, y[PHI1]) } else { 0.0 };
        dy[PHI1] = y[W1];
        dy[W1] = if self.imbalance {
            (ts - absolute_damping - t1 - gravity) * self.inv_j1
        } else {
            (ts - absolute_damping - t1) * self.inv_j1
        };
        if let Some((c, tau, _)) = self.fade {
            // C dϑ/dt = T1·Ω1 − C ϑ/τ: friction power heats the pad, Newton cooling.
            dy[TEMP] = t1 * y[W1] / c - y[TEMP] / tau;
        }
        if self.extension.is_some() {
            // Slipping: the time since break-away grows at the rate of time.
            dy[TEMP] = 1.0;
        }
        dy
    }

    /// Event function of `mode`: the mode ends where it crosses from ≤ 0 to > 0
    /// (stick) or from ≥ 0 to < 0 (slip). `None` for modes without events.
    #[inline(always)]
    pub fn event(&self, mode: Mode, t: f64, y: &Vector) -> Option<f64> {
        match mode {
            Mode::Continuous => None,
            Mode::Stick => Some(self.rotor_torque_nm(y).abs() - self.stick_limit_nm(t, y)),
            Mode::Slip { sign } => Some(sign * y[W1]),
        }
    }

    /// The mode the rotor takes at rest (Ω1 = 0) under the current shaft torque.
    pub fn mode_at_rest(&self, t: f64, y: &Vector) -> Mode {
        if self.kind == ModelKind::Thesis || !self.brake_closed() {
            return Mode::Continuous;
        }
        let ts = self.rotor_torque_nm(y);
        if ts.abs() <= self.stick_limit_nm(t, y) { Mode::Stick } else { Mode::Slip { sign: ts.signum() } }
    }

    /// The mode of an arbitrary state (start of a continuation).
    pub fn mode_of(&self, t: f64, y: &Vector, stuck: bool) -> Mode {
        if self.kind == ModelKind::Thesis || !self.brake_closed() {
            Mode::Continuous
        } else if stuck || y[W1] == 0.0 {
            self.mode_at_rest(t, y)
        } else {
            Mode::Slip { sign: y[W1].signum() }
        }
    }

    /// Whether t is inside the reference ramp.
    #[inline]
    pub fn ramping(&self, t: f64) -> bool {
        match self.drive {
            Drive::Voltage { .. } => false,
            Drive::Pi { ramp_s, t_start_s, .. } => ramp_s > 0.0 && t - t_start_s < ramp_s,
        }
    }
}

/// tanh x as ±(1 − e)/(1 + e) with e = e^{−2|x|}: one `exp` where the
/// library's `tanh` takes an `expm1` and more (the start-up of every run
/// evaluates it ~2000 times). The cancellation in 1 − e for small |x| costs
/// relative accuracy, not absolute: |error| < 4·10⁻¹⁶ everywhere (test
/// `tanh_by_exp_is_within_4e_16_of_tanh`), so T_f·tanh moves by < 10⁻¹⁶ N·m.
///
/// Past |x| = [`TANH_ONE_ABOVE`] it returns ±1 without the `exp`: there
/// e < e^{−38} < 2^{−54}, so 1 − e and 1 + e both round to 1 and the formula
/// gives ±1 exactly (test `tanh_by_exp_is_one_past_its_cut_to_the_bit`). The
/// motor of a steady operating point turns at |n Ω2| of tens of rad/s, so
/// most right-hand sides of a free run skip it.
#[inline]
pub(crate) fn tanh_by_exp(x: f64) -> f64 {
    if x.abs() > TANH_ONE_ABOVE {
        return 1f64.copysign(x);
    }
    let e = (-2.0 * x.abs()).exp();
    ((1.0 - e) / (1.0 + e)).copysign(x)
}

/// |x| above which [`tanh_by_exp`] is ±1 to the bit: 2^{−54} = e^{−37.4}.
const TANH_ONE_ABOVE: f64 = 19.0;

fn sign_or_zero(x: f64) -> f64 {
    if x == 0.0 { 0.0 } else { x.signum() }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn tanh_by_exp_is_within_4e_16_of_tanh() {
        let mut worst = 0.0f64;
        for k in -200_000..=200_000 {
            // Dense near 0 (|x| from 1e-12 up), then out to ±40.
            let x = f64::from(k) * 2e-4;
            for x in [x, x * 1e-7, x * x * x * 0.02] {
                worst = worst.max((tanh_by_exp(x) - x.tanh()).abs());
                assert_eq!(tanh_by_exp(x).signum(), x.tanh().signum(), "{x}");
            }
        }
        assert!(worst < 4e-16, "{worst:e}");
        assert_eq!(tanh_by_exp(1e300), 1.0);
        assert_eq!(tanh_by_exp(-1e300), -1.0);
    }

    #[test]
    fn tanh_by_exp_is_one_past_its_cut_to_the_bit() {
        // The formula without the cut, from its cut out to where e underflows:
        // ±1 exactly, so the cut returns what the formula did.
        let formula = |x: f64| {
            let e = (-2.0f64 * x.abs()).exp();
            ((1.0 - e) / (1.0 + e)).copysign(x)
        };
        for k in 0..=400_000 {
            let x = TANH_ONE_ABOVE + f64::from(k) * 2.5e-3;
            for x in [x, -x, x.next_up()] {
                assert_eq!(formula(x).to_bits(), tanh_by_exp(x).to_bits(), "{x}");
                assert_eq!(formula(x).abs(), 1.0, "{x}");
            }
        }
        // And the cut is not far above the first x whose formula gives 1 (18.72).
        assert!(formula(18.0) < 1.0 && formula(TANH_ONE_ABOVE) == 1.0);
    }
}
