//! Seeded draws of the truth: rig parameters in plausible ranges around the
//! thesis' Table 4.5 (with the 8:1 gearbox), the sensor chain, and the hidden effect.

use crate::ids;
use rand::{Rng, SeedableRng};
use rand_chacha::ChaCha8Rng;
use rig_types::{DriveParams, Effect, FrictionLaw, ModelKind, MotorParams, RigParams};

/// A recorded channel of an operating point that a sensor fault can act on.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum SensorChannel {
    /// `rotor_ticks`, the rotor encoder.
    RotorEncoder,
    /// `brake_force_mv`, the force sensor.
    Force,
}

impl SensorChannel {
    /// The recording's column name.
    pub fn column(self) -> &'static str {
        match self {
            SensorChannel::RotorEncoder => "rotor_ticks",
            SensorChannel::Force => "brake_force_mv",
        }
    }
}

/// The effect hidden in a campaign, with the parameters the diagnosis must recover.
#[derive(Debug, Clone, PartialEq)]
pub enum Hidden {
    None,
    NormalForceModulation {
        amplitude_ratio: f64,
        frequency_hz: f64,
    },
    AnglePeriodicFriction {
        amplitude_ratio: f64,
        order: u32,
    },
    VelocityWeakening {
        mu_static: f64,
        mu_kinetic: f64,
        stribeck_speed_rad_s: f64,
    },
    ViscousBrake {
        mu_kinetic: f64,
        viscous_per_rad_s: f64,
    },
    DriveVoltageLimit {
        limit_v: f64,
    },
    /// Outside the vocabulary: the diagnosis must answer `unexplained`.
    MotorCogging {
        amplitude_nm: f64,
        order: u32,
    },
    /// Outside (tribology): [`Effect::BrakeFade`], μ/(1 + ϑ/ϑ_fade) with the
    /// pad heated by friction power and cooling with time constant τ.
    BrakeFade {
        heat_capacity_j_k: f64,
        cooling_time_s: f64,
        fade_temperature_k: f64,
    },
    /// Outside (mechanics): [`Effect::CouplingBacklash`], a dead zone of `gap_rad` in the twist.
    CouplingBacklash {
        gap_rad: f64,
    },
    /// Outside (mechanics): [`Effect::ShaftCubicStiffness`], K δ (1 + β δ²).
    ShaftCubicStiffness {
        cubic_per_rad2: f64,
    },
    /// Outside (mechanics): [`Effect::RotorImbalance`], gravity torque m e g sin(φ1 + θ).
    RotorImbalance {
        imbalance_kg_m: f64,
    },
    /// Outside (drive): [`Effect::DriveCurrentLimit`], terminal voltage within n k_e Ω2 ± R I_max.
    DriveCurrentLimit {
        current_limit_a: f64,
    },
    /// Outside (motor/drive): the motor warms up over the campaign. Before run
    /// j the winding is ΔT(1 − exp(−t_j/τ)) above its start (t_j: recorded
    /// time of the runs before it); R grows by α_Cu = 0.00393 1/K (annealed
    /// copper, IEC 60028) and k_T = k_e fall by α_B = 0.002 1/K (ferrite
    /// magnets, remanence −0.2 %/K), so the voltage constant drifts with
    /// temperature. Applied per run by the virtual rig.
    MotorWarmUp {
        temperature_rise_k: f64,
        time_constant_s: f64,
    },
    /// Outside (sensor): force-sensor gain nonlinearity, mV = offset + g F + q F²
    /// (bridge/load-cell nonlinearity, quadratic in the load), in every run
    /// that records `brake_force_mv`, calibration included.
    ForceSensorNonlinearity {
        quadratic_mv_per_n2: f64,
    },
    /// Outside (sensor): the force sensor's offset drifts from the start of
    /// each run, mV = offset + d·t + g F (thermal zero drift of the bridge amplifier).
    ForceOffsetDrift {
        drift_mv_per_s: f64,
    },
    /// Outside (sensor): the rotor encoder misses each tick with probability
    /// p (independently; dirt on the code disc), so its count falls behind.
    EncoderMissingTicks {
        miss_probability: f64,
    },
    /// Outside (tribology), seen only in free run: static friction that ages
    /// with the time the contact has been stuck,
    /// μs(t_stick) = μs0 + B ln(1 + t_stick/τ), slip friction unchanged
    /// ([`Effect::StaticFrictionAging`]; Dieterich 1972, Rabinowicz 1958).
    /// A longer stick needs a larger torque to break away, so stick-slip
    /// cycles lengthen and grow; teacher-forcing in slip never sees it.
    StaticFrictionAging {
        aging_mu_per_efold: f64,
        aging_time_s: f64,
    },
    /// Structural: the rig's damping acts on the absolute rotor speed (a drag
    /// −C_r Ω1: bearings, seals, air; Eq. 4-7's diag(C, Cm) placement), with
    /// only a small material damping C left on the twist rate, where the rig
    /// model puts all of it.
    RotorAbsoluteDamping {
        rotor_damping_nm_s_rad: f64,
        shaft_damping_nm_s_rad: f64,
    },
    /// Structural (sensor chain): one recorded channel of the operating
    /// points lags the others by a transport delay of whole samples (a FIFO
    /// or filter latency of the acquisition chain): x_rec[k] = x[k − d].
    ChannelDelay {
        channel: SensorChannel,
        delay_samples: u32,
    },
    /// Structural (sensor chain): the force sensor is a second-order system
    /// (load cell and caliper arm as mass–spring–damper, base-excited by the
    /// pad force): F̈m + 2ζω F̊m + ω² Fm = ω² F, ω = 2π f_n.
    ForceSensorDynamics {
        natural_frequency_hz: f64,
        damping_ratio: f64,
    },
    /// Structural (sensor chain): the rotor encoder's disc sits on a compliant
    /// coupling (its inertia between the sensor and rotor 1):
    /// φ̈e + 2ζω φ̇e + ω² φe = ω² φ1 + 2ζω Ω1 (coupling stiffness k_c and
    /// damping c_c over the disc's inertia J_e: ω² = k_c/J_e, 2ζω = c_c/J_e).
    EncoderCouplingCompliance {
        natural_frequency_hz: f64,
        damping_ratio: f64,
    },
}

impl Hidden {
    /// The verdict a correct diagnosis returns (a structural fault: see
    /// [`Hidden::structural_id`], `unexplained` is right too).
    pub fn id(&self) -> &'static str {
        match self {
            Hidden::None => ids::NONE,
            Hidden::NormalForceModulation { .. } => ids::NORMAL_FORCE_MODULATION,
            Hidden::AnglePeriodicFriction { .. } => ids::ANGLE_PERIODIC_FRICTION,
            Hidden::VelocityWeakening { .. } => ids::VELOCITY_WEAKENING_FRICTION,
            Hidden::ViscousBrake { .. } => ids::VISCOUS_BRAKE_FRICTION,
            Hidden::DriveVoltageLimit { .. } => ids::DRIVE_VOLTAGE_LIMIT,
            _ => ids::UNEXPLAINED,
        }
    }

    /// The structural id of a structural fault ([`ids::STRUCTURAL`]).
    pub fn structural_id(&self) -> Option<&'static str> {
        match self {
            Hidden::RotorAbsoluteDamping { .. } => Some(ids::DAMPING_ROTOR_ABSOLUTE),
            Hidden::ChannelDelay { .. } => Some(ids::CHANNEL_DELAY),
            Hidden::ForceSensorDynamics { .. } => Some(ids::FORCE_SENSOR_DYNAMICS),
            Hidden::EncoderCouplingCompliance { .. } => Some(ids::ENCODER_COUPLING_COMPLIANCE),
            _ => None,
        }
    }

    /// Whether this is a structural fault rather than an effect.
    pub fn is_structural(&self) -> bool {
        self.structural_id().is_some()
    }

    /// Name of the hidden class: the verdict id for a vocabulary effect and
    /// `none`, the effect's own name for one outside the vocabulary.
    pub fn class(&self) -> &'static str {
        match self {
            Hidden::MotorCogging { .. } => ids::MOTOR_COGGING,
            Hidden::BrakeFade { .. } => ids::BRAKE_FADE,
            Hidden::CouplingBacklash { .. } => ids::COUPLING_BACKLASH,
            Hidden::ShaftCubicStiffness { .. } => ids::SHAFT_CUBIC_STIFFNESS,
            Hidden::RotorImbalance { .. } => ids::ROTOR_IMBALANCE,
            Hidden::DriveCurrentLimit { .. } => ids::DRIVE_CURRENT_LIMIT,
            Hidden::MotorWarmUp { .. } => ids::MOTOR_WARM_UP,
            Hidden::ForceSensorNonlinearity { .. } => ids::FORCE_SENSOR_NONLINEARITY,
            Hidden::ForceOffsetDrift { .. } => ids::FORCE_OFFSET_DRIFT,
            Hidden::EncoderMissingTicks { .. } => ids::ENCODER_MISSING_TICKS,
            Hidden::StaticFrictionAging { .. } => ids::STATIC_FRICTION_AGING,
            other => other.structural_id().unwrap_or_else(|| other.id()),
        }
    }

    /// Whether this effect is outside the diagnosis vocabulary (structural
    /// faults included: no vocabulary effect explains them).
    pub fn is_outside(&self) -> bool {
        self.id() == ids::UNEXPLAINED
    }

    /// All parameters of the truth, outside effects included (for reports).
    pub fn truth_params(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Hidden::MotorCogging { amplitude_nm, order } => {
                vec![("amplitude_nm", amplitude_nm), ("order", f64::from(order))]
            }
            Hidden::BrakeFade { heat_capacity_j_k, cooling_time_s, fade_temperature_k } => vec![
                ("heat_capacity_j_k", heat_capacity_j_k),
                ("cooling_time_s", cooling_time_s),
                ("fade_temperature_k", fade_temperature_k),
            ],
            Hidden::CouplingBacklash { gap_rad } => vec![("gap_rad", gap_rad)],
            Hidden::ShaftCubicStiffness { cubic_per_rad2 } => vec![("cubic_per_rad2", cubic_per_rad2)],
            Hidden::RotorImbalance { imbalance_kg_m } => vec![("imbalance_kg_m", imbalance_kg_m)],
            Hidden::DriveCurrentLimit { current_limit_a } => vec![("current_limit_a", current_limit_a)],
            Hidden::MotorWarmUp { temperature_rise_k, time_constant_s } => {
                vec![("temperature_rise_k", temperature_rise_k), ("time_constant_s", time_constant_s)]
            }
            Hidden::ForceSensorNonlinearity { quadratic_mv_per_n2 } => {
                vec![("quadratic_mv_per_n2", quadratic_mv_per_n2)]
            }
            Hidden::ForceOffsetDrift { drift_mv_per_s } => vec![("drift_mv_per_s", drift_mv_per_s)],
            Hidden::EncoderMissingTicks { miss_probability } => vec![("miss_probability", miss_probability)],
            Hidden::StaticFrictionAging { aging_mu_per_efold, aging_time_s } => {
                vec![("aging_mu_per_efold", aging_mu_per_efold), ("aging_time_s", aging_time_s)]
            }
            Hidden::RotorAbsoluteDamping { rotor_damping_nm_s_rad, shaft_damping_nm_s_rad } => vec![
                ("rotor_damping_nm_s_rad", rotor_damping_nm_s_rad),
                ("shaft_damping_nm_s_rad", shaft_damping_nm_s_rad),
            ],
            Hidden::ChannelDelay { channel, delay_samples } => vec![
                ("delay_samples", f64::from(delay_samples)),
                ("force_channel", if channel == SensorChannel::Force { 1.0 } else { 0.0 }),
            ],
            Hidden::ForceSensorDynamics { natural_frequency_hz, damping_ratio }
            | Hidden::EncoderCouplingCompliance { natural_frequency_hz, damping_ratio } => {
                vec![("natural_frequency_hz", natural_frequency_hz), ("damping_ratio", damping_ratio)]
            }
            _ => self.params(),
        }
    }

    /// True parameters under the JSON keys of diagnosis.md.
    pub fn params(&self) -> Vec<(&'static str, f64)> {
        match *self {
            Hidden::None => vec![],
            Hidden::NormalForceModulation { amplitude_ratio, frequency_hz } => {
                vec![("amplitude_ratio", amplitude_ratio), ("frequency_hz", frequency_hz)]
            }
            Hidden::AnglePeriodicFriction { amplitude_ratio, order } => {
                vec![("amplitude_ratio", amplitude_ratio), ("order", order as f64)]
            }
            Hidden::VelocityWeakening { mu_static, mu_kinetic, stribeck_speed_rad_s } => vec![
                ("mu_static", mu_static),
                ("mu_kinetic", mu_kinetic),
                ("stribeck_speed_rad_s", stribeck_speed_rad_s),
            ],
            Hidden::ViscousBrake { mu_kinetic, viscous_per_rad_s } => {
                vec![("mu_kinetic", mu_kinetic), ("viscous_per_rad_s", viscous_per_rad_s)]
            }
            Hidden::DriveVoltageLimit { limit_v } => vec![("limit_v", limit_v)],
            // Outside the vocabulary: nothing the diagnosis must recover.
            _ => vec![],
        }
    }

    /// The classes in the order of the confusion matrix.
    pub const CLASSES: [&'static str; 7] = [
        ids::NONE,
        ids::NORMAL_FORCE_MODULATION,
        ids::ANGLE_PERIODIC_FRICTION,
        ids::VELOCITY_WEAKENING_FRICTION,
        ids::VISCOUS_BRAKE_FRICTION,
        ids::DRIVE_VOLTAGE_LIMIT,
        ids::MOTOR_COGGING,
    ];

    /// The vocabulary effects (diagnosis.md), in the matrix's order.
    pub const VOCABULARY: [&'static str; 5] = ids::VOCABULARY;

    /// The effects outside the vocabulary ([`Hidden::class`] names).
    pub const OUTSIDE: [&'static str; 11] = ids::OUTSIDE;

    /// The structural faults ([`Hidden::class`] names).
    pub const STRUCTURAL: [&'static str; 4] = ids::STRUCTURAL;
}

/// Everything the virtual rig knows and the diagnosis must not.
#[derive(Debug, Clone, PartialEq)]
pub struct Truth {
    pub params: RigParams,
    /// The (first) hidden effect; `Hidden::None` for an effect-free rig.
    pub hidden: Hidden,
    /// Further hidden effects of a compound campaign (empty for one effect).
    pub more_hidden: Vec<Hidden>,
    pub supply_voltage_v: f64,
    pub force_factor_mv_per_n: f64,
    pub force_offset_mv: f64,
    pub force_noise_mv: f64,
    pub voltage_noise_v: f64,
}

/// Draws a hidden effect of class `class` (one of [`Hidden::CLASSES`]) with
/// random parameters in ranges where it matters on this rig. `mu_kinetic` is
/// the rig's slip coefficient (the laws are built around it).
pub fn draw_hidden(class: &str, mu_kinetic: f64, max_setpoint_rpm: f64, seed: u64) -> Hidden {
    let mut r = ChaCha8Rng::seed_from_u64(seed ^ 0x005e_ed0f_4e55);
    match class {
        ids::NORMAL_FORCE_MODULATION => Hidden::NormalForceModulation {
            amplitude_ratio: r.random_range(0.08..0.3),
            frequency_hz: r.random_range(0.5..3.0),
        },
        ids::ANGLE_PERIODIC_FRICTION => {
            Hidden::AnglePeriodicFriction { amplitude_ratio: r.random_range(0.08..0.3), order: r.random_range(1..=6) }
        }
        ids::VELOCITY_WEAKENING_FRICTION => Hidden::VelocityWeakening {
            mu_static: mu_kinetic * r.random_range(1.3..1.8),
            mu_kinetic,
            stribeck_speed_rad_s: r.random_range(0.8..4.0),
        },
        ids::VISCOUS_BRAKE_FRICTION => Hidden::ViscousBrake {
            mu_kinetic,
            // 10–40 % more friction at 10 rad/s of slip.
            viscous_per_rad_s: mu_kinetic * r.random_range(0.01..0.04),
        },
        ids::DRIVE_VOLTAGE_LIMIT => {
            // Armature back-EMF at the highest set-point with the default motor (n = 8, k_e ≈ 0.0588):
            // a limit between 45 % and 80 % of it saturates the fast runs.
            let w_arm = rig_types::units::rpm_to_rad_s(8.0 * max_setpoint_rpm);
            Hidden::DriveVoltageLimit { limit_v: 0.0588 * w_arm * r.random_range(0.45..0.8) }
        }
        "motor_cogging" => {
            Hidden::MotorCogging { amplitude_nm: r.random_range(0.08..0.2), order: r.random_range(2..=6) }
        }
        // Outside the vocabulary, sizes where each matters on this rig (see the crate docs).
        "brake_fade" => Hidden::BrakeFade {
            heat_capacity_j_k: r.random_range(4.0..10.0),
            cooling_time_s: r.random_range(20.0..60.0),
            fade_temperature_k: r.random_range(30.0..80.0),
        },
        "coupling_backlash" => Hidden::CouplingBacklash { gap_rad: r.random_range(0.02..0.08) },
        "shaft_cubic_stiffness" => Hidden::ShaftCubicStiffness {
            // Twists reach ~3.5 rad: a softening shaft must still carry ~1.5 N·m,
            // (2K/3)/√(3|β|) > 1.5 N·m ⇒ |β| < 0.005 1/rad².
            cubic_per_rad2: if r.random_bool(0.5) { r.random_range(0.01..0.04) } else { -r.random_range(0.002..0.004) },
        },
        "rotor_imbalance" => Hidden::RotorImbalance { imbalance_kg_m: r.random_range(0.005..0.015) },
        "drive_current_limit" => Hidden::DriveCurrentLimit { current_limit_a: r.random_range(2.5..4.0) },
        "motor_warm_up" => Hidden::MotorWarmUp {
            temperature_rise_k: r.random_range(30.0..60.0),
            time_constant_s: r.random_range(200.0..600.0),
        },
        "force_sensor_nonlinearity" => {
            Hidden::ForceSensorNonlinearity { quadratic_mv_per_n2: r.random_range(0.3..0.8) }
        }
        "force_offset_drift" => Hidden::ForceOffsetDrift {
            drift_mv_per_s: if r.random_bool(0.5) { 1.0 } else { -1.0 } * r.random_range(0.5..1.5),
        },
        "encoder_missing_ticks" => Hidden::EncoderMissingTicks { miss_probability: r.random_range(0.002..0.01) },
        // B of 4–10 % of μk per e-fold of stick time, τ 20–200 ms: a 0.3 s stick
        // raises μs by 5–25 % of μk. Rocks give B ≈ 0.01 on μ ≈ 0.6 (Dieterich
        // 1972), polymer glasses 1–3 % of μ (Baumberger & Caroli, Adv. Phys. 55
        // (2006) 279); the range is the upper end, where it matters on this rig.
        "static_friction_aging" => Hidden::StaticFrictionAging {
            aging_mu_per_efold: mu_kinetic * r.random_range(0.04..0.10),
            aging_time_s: r.random_range(0.02..0.2),
        },
        // Bearing, seal and air drag on rotor 1 of 3–12 mN·m·s/rad (the torque
        // balance of emulated rigs finds 6.5–6.9 mN·m·s/rad, issue 25), and a
        // shaft's material damping of 0.5–2 % of critical on the nominal
        // √(J1 K) = √(0.0298 · 0.271) (steel: ≈ 0.1–1 %, couplings add).
        "damping_rotor_absolute" => Hidden::RotorAbsoluteDamping {
            rotor_damping_nm_s_rad: r.random_range(0.003..0.012),
            shaft_damping_nm_s_rad: 2.0 * r.random_range(0.005..0.02) * (0.0298f64 * 0.271).sqrt(),
        },
        // 2–5 samples (4–10 ms at 500 Hz), the rotor encoder or the force channel.
        "channel_delay" => Hidden::ChannelDelay {
            channel: if r.random_bool(0.5) { SensorChannel::RotorEncoder } else { SensorChannel::Force },
            delay_samples: r.random_range(2..=5),
        },
        // A force measured through a compliant lever arm: 6–15 Hz, ζ 0.05–0.3,
        // a few times the stick-slip fundamental, so the break-away rings.
        "force_sensor_dynamics" => Hidden::ForceSensorDynamics {
            natural_frequency_hz: r.random_range(6.0..15.0),
            damping_ratio: r.random_range(0.05..0.3),
        },
        // An encoder disc on a soft elastomer coupling or a long extension
        // shaft: 2–5 Hz, ζ 0.05–0.2. The disc lags by ≈ α/ω² under an
        // acceleration α; stick-slip swings Ω1 by a few rad/s in ≈ 0.1 s
        // (α ≈ 20–50 rad/s²), so at 3 Hz the lag is ≈ 0.05–0.14 rad (8–22
        // ticks), at 10 Hz below a tick (6.3 mrad): stiffer couplings are
        // invisible on this rig.
        "encoder_coupling_compliance" => Hidden::EncoderCouplingCompliance {
            natural_frequency_hz: r.random_range(2.0..5.0),
            damping_ratio: r.random_range(0.05..0.2),
        },
        _ => Hidden::None,
    }
}

/// Draws the rig (seeded, plausible ranges) and builds the truth model with `class` hidden.
pub fn draw_truth(class: &str, max_setpoint_rpm: f64, seed: u64) -> Truth {
    let base = draw_rig(seed);
    let hidden = draw_hidden(class, base.mu_kinetic(), max_setpoint_rpm, seed);
    base.with_hidden(vec![hidden])
}

/// Draws the rig alone (seeded; the same draw as [`draw_truth`] with the same
/// seed), with no hidden effect.
pub fn draw_rig(seed: u64) -> Truth {
    let mut r = ChaCha8Rng::seed_from_u64(seed);
    let mut u = |lo: f64, hi: f64| r.random_range(lo..hi);
    let j1 = 0.0298 * u(0.9, 1.1);
    let k = 0.271 * u(0.9, 1.1);
    let xi = u(0.06, 0.12);
    let mu_k = u(0.3, 0.6);
    let mu_s = mu_k * u(1.2, 1.5);
    let motor = MotorParams {
        inertia_kgm2: 4.698e-4 * u(0.9, 1.1),
        inductance_h: 8.437e-4 * u(0.9, 1.1),
        resistance_ohm: 0.526 * u(0.9, 1.1),
        torque_constant_nm_a: 0.126 * u(0.95, 1.05),
        voltage_constant_v_s_rad: 0.0588 * u(0.95, 1.05),
        friction_torque_nm: 0.1 * u(0.7, 1.3),
        speed_regulation_nm_s_rad: 1.784e-4 * u(0.8, 1.2),
        gear_ratio: 8.0,
    };
    let drive = DriveParams { kp_v_s_rad: u(1.5, 3.0), ki_v_rad: u(6.0, 15.0), limit_v: 24.0 };
    let truth_extra = (u(190.0, 240.0), u(-8.0, 8.0), u(1.0, 3.0), u(0.01, 0.04));
    let params = RigParams {
        kind: ModelKind::Rig,
        rotor_inertia_kgm2: j1,
        shaft_stiffness_nm_rad: k,
        shaft_damping_nm_s_rad: 2.0 * xi * (j1 * k).sqrt(),
        rotor_damping_nm_s_rad: 0.0,
        motor,
        drive,
        friction: FrictionLaw::Coulomb { mu_static: mu_s, mu_kinetic: mu_k },
        brake_disc_radius_m: 0.062,
        effects: vec![],
        harmonic: None,
    };
    Truth {
        params,
        hidden: Hidden::None,
        more_hidden: vec![],
        supply_voltage_v: 24.0,
        force_factor_mv_per_n: truth_extra.0,
        force_offset_mv: truth_extra.1,
        force_noise_mv: truth_extra.2,
        voltage_noise_v: truth_extra.3,
    }
}

impl Truth {
    /// Every hidden effect (the first, then the others), `Hidden::None` left out.
    pub fn hidden_all(&self) -> Vec<&Hidden> {
        std::iter::once(&self.hidden).chain(&self.more_hidden).filter(|h| **h != Hidden::None).collect()
    }

    /// The rig's slip coefficient μk (of its Coulomb law before any effect).
    pub fn mu_kinetic(&self) -> f64 {
        match self.params.friction {
            FrictionLaw::Coulomb { mu_kinetic, .. }
            | FrictionLaw::Stribeck { mu_kinetic, .. }
            | FrictionLaw::Viscous { mu_kinetic, .. } => mu_kinetic,
            FrictionLaw::Thesis(ref f) => f.mu_dynamic,
        }
    }

    /// This rig with `hidden` added to the truth model (in order; the first
    /// becomes [`Truth::hidden`]). Friction-law effects replace the Coulomb
    /// law, so `velocity_weakening_friction` and `viscous_brake_friction`
    /// cannot be combined (the later one wins).
    pub fn with_hidden(mut self, hidden: Vec<Hidden>) -> Truth {
        let mu_s = match self.params.friction {
            FrictionLaw::Coulomb { mu_static, .. }
            | FrictionLaw::Stribeck { mu_static, .. }
            | FrictionLaw::Viscous { mu_static, .. } => mu_static,
            FrictionLaw::Thesis(ref f) => f.mu_static,
        };
        let params = &mut self.params;
        for h in &hidden {
            match *h {
                Hidden::None => {}
                Hidden::NormalForceModulation { amplitude_ratio, frequency_hz } => {
                    params.effects.push(Effect::NormalForceModulation { amplitude_ratio, frequency_hz, phase_rad: 0.0 })
                }
                Hidden::AnglePeriodicFriction { amplitude_ratio, order } => {
                    params.effects.push(Effect::AnglePeriodicFriction { amplitude_ratio, order, phase_rad: 0.0 })
                }
                Hidden::VelocityWeakening { mu_static, mu_kinetic, stribeck_speed_rad_s } => {
                    params.friction = FrictionLaw::Stribeck { mu_static, mu_kinetic, stribeck_speed_rad_s }
                }
                Hidden::ViscousBrake { mu_kinetic, viscous_per_rad_s } => {
                    params.friction = FrictionLaw::Viscous { mu_static: mu_s, mu_kinetic, viscous_per_rad_s }
                }
                Hidden::DriveVoltageLimit { limit_v } => params.drive.limit_v = limit_v,
                Hidden::MotorCogging { amplitude_nm, order } => {
                    params.effects.push(Effect::MotorCogging { amplitude_nm, order, phase_rad: 0.0 })
                }
                Hidden::BrakeFade { heat_capacity_j_k, cooling_time_s, fade_temperature_k } => {
                    params.effects.push(Effect::BrakeFade { heat_capacity_j_k, cooling_time_s, fade_temperature_k })
                }
                Hidden::CouplingBacklash { gap_rad } => params.effects.push(Effect::CouplingBacklash { gap_rad }),
                Hidden::ShaftCubicStiffness { cubic_per_rad2 } => {
                    params.effects.push(Effect::ShaftCubicStiffness { cubic_per_rad2 })
                }
                Hidden::RotorImbalance { imbalance_kg_m } => {
                    params.effects.push(Effect::RotorImbalance { imbalance_kg_m, phase_rad: 0.0 })
                }
                Hidden::DriveCurrentLimit { current_limit_a } => {
                    params.effects.push(Effect::DriveCurrentLimit { current_limit_a })
                }
                Hidden::StaticFrictionAging { aging_mu_per_efold, aging_time_s } => {
                    params.effects.push(Effect::StaticFrictionAging { aging_mu_per_efold, aging_time_s })
                }
                Hidden::RotorAbsoluteDamping { rotor_damping_nm_s_rad, shaft_damping_nm_s_rad } => {
                    params.rotor_damping_nm_s_rad = rotor_damping_nm_s_rad;
                    params.shaft_damping_nm_s_rad = shaft_damping_nm_s_rad;
                }
                // Applied by the campaign generator (per run, or in the sensor chain).
                Hidden::MotorWarmUp { .. }
                | Hidden::ForceSensorNonlinearity { .. }
                | Hidden::ForceOffsetDrift { .. }
                | Hidden::EncoderMissingTicks { .. }
                | Hidden::ChannelDelay { .. }
                | Hidden::ForceSensorDynamics { .. }
                | Hidden::EncoderCouplingCompliance { .. } => {}
            }
        }
        let mut it = hidden.into_iter().filter(|h| *h != Hidden::None);
        self.hidden = it.next().unwrap_or(Hidden::None);
        self.more_hidden = it.collect();
        self
    }
}
