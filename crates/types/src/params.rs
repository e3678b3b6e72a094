//! Parameters of the rig models (thesis Eqs. 4-6 to 4-11) and the inputs of one run.
//! Owned by the `rig-model` crate's author: fields may be added, never renamed
//! silently. Units are in the names.

use serde::{Deserialize, Serialize};

/// DC motor constants (Eq. 4-6, Tables 4.4/4.5). Electrical constants refer
/// to the armature; `gear_ratio` n maps them to the shaft: armature speed =
/// n · Ω2, torque at the shaft = n · (k_T i − losses). n = 1 is the thesis
/// model as published (the chapter says the 8:1 gearbox "was not considered").
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct MotorParams {
    pub inertia_kgm2: f64,
    pub inductance_h: f64,
    pub resistance_ohm: f64,
    pub torque_constant_nm_a: f64,
    pub voltage_constant_v_s_rad: f64,
    pub friction_torque_nm: f64,
    pub speed_regulation_nm_s_rad: f64,
    pub gear_ratio: f64,
}

/// PI speed loop on the motor-side shaft speed Ω2 (the spec's "PI loop on
/// motor speed"): V = clamp(kp·e + ki·∫e, −limit_v, +limit_v), e = Ω_ref − Ω2.
/// rig-model adds back-calculation anti-windup (tracking time constant
/// `rig_model::ANTI_WINDUP_TRACKING_S`); see its crate docs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DriveParams {
    pub kp_v_s_rad: f64,
    pub ki_v_rad: f64,
    /// Saturation of the drive; `supply_voltage_v` of campaign.toml unless an
    /// effect lowers it.
    pub limit_v: f64,
}

/// Eq. 4-10 / Table 4.7 as published: a lookup over rotor speed.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThesisFriction {
    pub mu_static: f64,
    pub mu_dynamic: f64,
    pub mu_negative: f64,
    /// Tol of Eq. 4-10 (the chapter gives 0.001 without a unit).
    pub tolerance: f64,
    /// Set-points of Table 4.7, rpm.
    pub static_setpoint_rpm: f64,
    pub dynamic_setpoint_rpm: f64,
}

/// Friction coefficient law μ(Ω1) of the brake; friction torque = μ · N · r.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "law", rename_all = "snake_case")]
pub enum FrictionLaw {
    /// The chapter's modified Coulomb lookup (thesis model only).
    Thesis(ThesisFriction),
    /// Static break-away μs, constant slip coefficient μk, symmetric in sign.
    Coulomb { mu_static: f64, mu_kinetic: f64 },
    /// μ(Ω) = μk + (μs − μk) exp(−(Ω/vs)²) in slip (vocabulary `velocity_weakening_friction`).
    Stribeck { mu_static: f64, mu_kinetic: f64, stribeck_speed_rad_s: f64 },
    /// μ(Ω) = μk + c |Ω| in slip (vocabulary `viscous_brake_friction`).
    Viscous { mu_static: f64, mu_kinetic: f64, viscous_per_rad_s: f64 },
}

/// Effects added to the baseline (../shared/spec/diagnosis.md), plus effects
/// outside the vocabulary that the virtual rig may hide in test campaigns.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "effect", rename_all = "snake_case")]
pub enum Effect {
    /// N(t) = N0 (1 + a sin(2π f t + θ)).
    NormalForceModulation { amplitude_ratio: f64, frequency_hz: f64, phase_rad: f64 },
    /// N(φ1) = N0 (1 + a sin(n φ1 + θ)).
    AnglePeriodicFriction { amplitude_ratio: f64, order: u32, phase_rad: f64 },
    /// Not in the vocabulary: motor-side cogging torque τ sin(n φ2 + θ) at the shaft.
    MotorCogging { amplitude_nm: f64, order: u32, phase_rad: f64 },
    /// Not in the vocabulary (mechanics): backlash of total width `gap_rad` in
    /// the coupling of the string to the rotor, a dead zone in the twist
    /// δ = φ2 − φ1: with b = gap/2, δe = δ − clamp(δ, −b, b) and the shaft
    /// transmits K·δe + C·(Ω2 − Ω1) in contact (|δ| > b), nothing in the gap
    /// (the standard dead-zone backlash model, e.g. Nordin & Gutman,
    /// Automatica 38 (2002) 1633, "dead-zone model").
    CouplingBacklash { gap_rad: f64 },
    /// Not in the vocabulary (mechanics): a non-linear shaft, elastic torque
    /// K·δe·(1 + β·δe²) (Duffing spring; β > 0 hardening, β < 0 softening),
    /// β = `cubic_per_rad2` in 1/rad².
    ShaftCubicStiffness { cubic_per_rad2: f64 },
    /// Not in the vocabulary (mechanics): static imbalance of rotor 1 on a
    /// horizontal axis, gravity torque −m·e·g·sin(φ1 + θ) on the rotor
    /// (m·e = `imbalance_kg_m`, g = 9.80665 m/s²; a mass m at radius e).
    RotorImbalance { imbalance_kg_m: f64, phase_rad: f64 },
    /// Not in the vocabulary (tribology): friction fade with frictional
    /// heating. A lumped pad temperature rise ϑ (K) obeys
    /// C·dϑ/dt = T1·Ω1 − C·ϑ/τ (friction power in, Newton cooling out) and
    /// both coefficients fall as μ(ϑ) = μ / (1 + ϑ/ϑ_fade): fade grows with
    /// accumulated friction work and recovers when slip stops (Newcomb &
    /// Spurr, "Braking of road vehicles", ch. 5: μ falls with lining
    /// temperature). Each run starts cold (ϑ = 0).
    BrakeFade { heat_capacity_j_k: f64, cooling_time_s: f64, fade_temperature_k: f64 },
    /// Not in the vocabulary (drive): a current-limited amplifier. The
    /// terminal voltage is held in [n·k_e·Ω2 − R·I_max, n·k_e·Ω2 + R·I_max],
    /// the voltage that drives the steady armature current I_max (Eq. 4-6a
    /// with di/dt = 0); the PI loop does not know and winds up. Applies to
    /// voltage steps too (the amplifier is always in the path).
    DriveCurrentLimit { current_limit_a: f64 },
    /// Not in the vocabulary (tribology), seen only where the rotor sticks:
    /// the static coefficient grows with the age of the stuck contact,
    /// μs(t_stick) = μs + B·ln(1 + t_stick/τ) (B = `aging_mu_per_efold`,
    /// τ = `aging_time_s`; Dieterich, J. Geophys. Res. 77 (1972) 3690, and
    /// Rabinowicz, Proc. Phys. Soc. 71 (1958) 668: the real contact area
    /// creeps under load, so break-away after a longer stick needs a larger
    /// torque). The slip law is unchanged. The contact age restarts at 0 each
    /// time rotor 1 comes to rest (and at the start of a run).
    StaticFrictionAging { aging_mu_per_efold: f64, aging_time_s: f64 },
    /// The diagnosis' data-driven extension of an `unexplained` answer
    /// (rig-model `extension` module: the signal library, its physics and
    /// its state). The slip coefficient is multiplied by
    /// 1 + a_v·|Ω1| + a_b·exp(−t_slip/τ_b) and the break-away coefficient by
    /// 1 + c_0 + c_d·ln(1 + t_stick/τ_d), with t_slip the time since the last
    /// break-away and t_stick the age of the stuck contact (τ_b, τ_d fixed by
    /// rig-model). Every coefficient 0 is the model without it.
    FrictionExtension {
        /// a_v, per rad/s of slip speed.
        slip_speed_per_rad_s: f64,
        /// a_b, relative friction excess just after break-away.
        breakaway_transient: f64,
        /// c_0, relative change of the static (break-away) level.
        static_level: f64,
        /// c_d, relative growth of the static level per e-fold of dwell time.
        dwell_per_efold: f64,
    },
}

/// Eq. 4-11 and its physically consistent alternative (issue 4).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "variant", rename_all = "snake_case")]
pub enum HarmonicFriction {
    /// Eq. 4-11 as published: T1 · sin(ω_p t).
    MultiplyTorque { omega_p_rad_s: f64 },
    /// N(t) = N0 (1 + a sin(ω_p t)).
    NormalForce { omega_p_rad_s: f64, amplitude_ratio: f64 },
}

#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum ModelKind {
    /// Eqs. 4-6 to 4-10 as published, made consistent (see rig-model docs).
    Thesis,
    /// Same physics done properly: stick phase, symmetric friction, gear, PI with anti-windup.
    Rig,
}

#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct RigParams {
    pub kind: ModelKind,
    /// J1 (Eq. 4-4/4-5, Table 4.5).
    pub rotor_inertia_kgm2: f64,
    /// K_s (Eq. 4-1, Table 4.3/4.5).
    pub shaft_stiffness_nm_rad: f64,
    /// C of Eq. 4-7 (C = 2 ξ √(J1 K)). The thesis model applies it to the
    /// rotor speed Ω1 (Eq. 4-7 as published), the rig model to the twist rate
    /// Ω2 − Ω1 (material damping of the shaft).
    pub shaft_damping_nm_s_rad: f64,
    /// C_r: a drag on the absolute rotor speed Ω1 (bearings, air, seals), in
    /// addition to C: torque −C_r·Ω1 on rotor 1. Eq. 4-7's damping matrix acts
    /// on absolute speeds; the rig model's C acts on the twist rate, so this
    /// is the structural term that places damping where Eq. 4-7 puts it.
    /// 0 in the baseline; absent from JSON when 0 (files written before it
    /// existed read as 0 and are rewritten byte-identical).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub rotor_damping_nm_s_rad: f64,
    pub motor: MotorParams,
    pub drive: DriveParams,
    pub friction: FrictionLaw,
    /// r of Eq. 4-10.
    pub brake_disc_radius_m: f64,
    pub effects: Vec<Effect>,
    pub harmonic: Option<HarmonicFriction>,
}

fn is_zero(x: &f64) -> bool {
    *x == 0.0
}

/// What is imposed in one run, mirroring `RunKind` (the spec's protocol).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(tag = "input", rename_all = "snake_case")]
pub enum RunInput {
    /// Constant armature voltage from rest at t = 0, brake open.
    VoltageStep { voltage_v: f64 },
    /// PI speed loop following a ramp 0 → setpoint over ramp_s, brake pressed with N0.
    OperatingPoint { motor_rpm_setpoint: f64, normal_force_n: f64, ramp_s: f64 },
}
