//! Every id the virtual rig names, in one table: the verdicts and the
//! vocabulary effects of the diagnosis (../shared/spec/diagnosis.md), taken
//! from the diagnosis' own effect files (`rig_diagnose::effects::<effect>::ID`,
//! the vocabulary's one home: the only use this crate makes of rig-diagnose,
//! its physics stays its own), the effects outside it and the structural
//! faults. Code names an id through these constants, so a misspelt id does
//! not compile.

pub use rig_diagnose::effects::angle_periodic_friction::ID as ANGLE_PERIODIC_FRICTION;
pub use rig_diagnose::effects::drive_voltage_limit::ID as DRIVE_VOLTAGE_LIMIT;
pub use rig_diagnose::effects::normal_force_modulation::ID as NORMAL_FORCE_MODULATION;
pub use rig_diagnose::effects::velocity_weakening_friction::ID as VELOCITY_WEAKENING_FRICTION;
pub use rig_diagnose::effects::viscous_brake_friction::ID as VISCOUS_BRAKE_FRICTION;
/// The verdicts `none` (the baseline explains the data within its noise) and
/// `unexplained` (a significant mismatch is left).
pub use rig_diagnose::effects::{NONE, UNEXPLAINED};

/// The vocabulary effects (diagnosis.md), in the confusion matrix's order.
pub const VOCABULARY: [&str; 5] = [
    NORMAL_FORCE_MODULATION,
    ANGLE_PERIODIC_FRICTION,
    VELOCITY_WEAKENING_FRICTION,
    VISCOUS_BRAKE_FRICTION,
    DRIVE_VOLTAGE_LIMIT,
];

pub const MOTOR_COGGING: &str = "motor_cogging";
pub const BRAKE_FADE: &str = "brake_fade";
pub const COUPLING_BACKLASH: &str = "coupling_backlash";
pub const SHAFT_CUBIC_STIFFNESS: &str = "shaft_cubic_stiffness";
pub const ROTOR_IMBALANCE: &str = "rotor_imbalance";
pub const DRIVE_CURRENT_LIMIT: &str = "drive_current_limit";
pub const MOTOR_WARM_UP: &str = "motor_warm_up";
pub const FORCE_SENSOR_NONLINEARITY: &str = "force_sensor_nonlinearity";
pub const FORCE_OFFSET_DRIFT: &str = "force_offset_drift";
pub const ENCODER_MISSING_TICKS: &str = "encoder_missing_ticks";
pub const STATIC_FRICTION_AGING: &str = "static_friction_aging";

/// Effects outside the vocabulary (the right verdict is `unexplained`).
pub const OUTSIDE: [&str; 11] = [
    MOTOR_COGGING,
    BRAKE_FADE,
    COUPLING_BACKLASH,
    SHAFT_CUBIC_STIFFNESS,
    ROTOR_IMBALANCE,
    DRIVE_CURRENT_LIMIT,
    MOTOR_WARM_UP,
    FORCE_SENSOR_NONLINEARITY,
    FORCE_OFFSET_DRIFT,
    ENCODER_MISSING_TICKS,
    STATIC_FRICTION_AGING,
];

/// Damping on the absolute rotor speed Ω1 instead of the twist rate (Eq. 4-7's placement).
pub const DAMPING_ROTOR_ABSOLUTE: &str = "damping_rotor_absolute";

/// diagnosis.json's `structure.damping` of the rig model's own placement
/// (damping on the twist rate): no structural finding.
pub const DAMPING_TWIST_RATE: &str = "twist_rate";
/// diagnosis.json's `structure.damping` that names [`DAMPING_ROTOR_ABSOLUTE`].
pub const DAMPING_ROTOR_ABSOLUTE_PLACEMENT: &str = "rotor_absolute";
/// diagnosis.json's `structure.damping` with damping on both the twist rate
/// and the absolute rotor speed: also names [`DAMPING_ROTOR_ABSOLUTE`], whose
/// truth keeps a small material damping on the twist rate beside the drag
/// (`Hidden::RotorAbsoluteDamping`: 0.5–2 % of critical), so "both" is its
/// exact structure and "rotor_absolute" the same within that small term.
pub const DAMPING_BOTH_PLACEMENT: &str = "twist_rate_and_rotor";

/// The `structure.damping` values a structural fault is named by, if it is
/// a damping placement (a test checks these against the diagnosis' registry).
pub fn damping_placements(fault: &str) -> &'static [&'static str] {
    if fault == DAMPING_ROTOR_ABSOLUTE { &[DAMPING_ROTOR_ABSOLUTE_PLACEMENT, DAMPING_BOTH_PLACEMENT] } else { &[] }
}
/// A recorded channel lagging the others by a transport delay.
pub const CHANNEL_DELAY: &str = "channel_delay";
/// The force sensor as a second-order system (a load cell with its own resonance).
pub const FORCE_SENSOR_DYNAMICS: &str = "force_sensor_dynamics";
/// The rotor encoder on a compliant coupling (an inertia between a sensor and what it measures).
pub const ENCODER_COUPLING_COMPLIANCE: &str = "encoder_coupling_compliance";

/// Structural faults: the model's structure, not an effect, is wrong. A right
/// answer names the structure (these ids, the diagnosis' own structural ids
/// once it has them) or says `unexplained` (diagnosis.md: "Structure is a
/// candidate like an effect … their ids are the project's to define").
pub const STRUCTURAL: [&str; 4] =
    [DAMPING_ROTOR_ABSOLUTE, CHANNEL_DELAY, FORCE_SENSOR_DYNAMICS, ENCODER_COUPLING_COMPLIANCE];
