//! The effect vocabulary of ../shared/spec/diagnosis.md, defined once: ids,
//! parameter names (JSON keys) and the channel each effect acts on.

/// A vocabulary effect (`none` and `unexplained` are verdicts, not effects).
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum EffectId {
    NormalForceModulation,
    AnglePeriodicFriction,
    VelocityWeakeningFriction,
    ViscousBrakeFriction,
    DriveVoltageLimit,
}

/// The verdict when the baseline explains the data within its noise.
pub const NONE: &str = "none";
/// The verdict (and the finding) when a significant mismatch is left.
pub const UNEXPLAINED: &str = "unexplained";

/// Which teacher-forced channel an effect changes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Channel {
    /// The friction coefficient in slip, μ = F/N0.
    Friction,
    /// The armature voltage of the PI drive.
    Drive,
}

impl EffectId {
    /// Every effect, in the order candidates are listed.
    pub const ALL: [EffectId; 5] = [
        EffectId::NormalForceModulation,
        EffectId::AnglePeriodicFriction,
        EffectId::VelocityWeakeningFriction,
        EffectId::ViscousBrakeFriction,
        EffectId::DriveVoltageLimit,
    ];

    /// The id of diagnosis.json.
    pub fn id(self) -> &'static str {
        match self {
            EffectId::NormalForceModulation => "normal_force_modulation",
            EffectId::AnglePeriodicFriction => "angle_periodic_friction",
            EffectId::VelocityWeakeningFriction => "velocity_weakening_friction",
            EffectId::ViscousBrakeFriction => "viscous_brake_friction",
            EffectId::DriveVoltageLimit => "drive_voltage_limit",
        }
    }

    pub fn from_id(id: &str) -> Option<EffectId> {
        EffectId::ALL.into_iter().find(|e| e.id() == id)
    }

    /// Parameter names (JSON keys of `params`), in the spec's order.
    pub fn param_names(self) -> &'static [&'static str] {
        match self {
            EffectId::NormalForceModulation => &["amplitude_ratio", "frequency_hz"],
            EffectId::AnglePeriodicFriction => &["amplitude_ratio", "order"],
            EffectId::VelocityWeakeningFriction => &["mu_static", "mu_kinetic", "stribeck_speed_rad_s"],
            EffectId::ViscousBrakeFriction => &["mu_kinetic", "viscous_per_rad_s"],
            EffectId::DriveVoltageLimit => &["limit_v"],
        }
    }

    pub fn channel(self) -> Channel {
        match self {
            EffectId::DriveVoltageLimit => Channel::Drive,
            _ => Channel::Friction,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ids_round_trip_and_are_distinct() {
        for e in EffectId::ALL {
            assert_eq!(EffectId::from_id(e.id()), Some(e));
        }
        assert_eq!(EffectId::from_id(NONE), None);
        assert_eq!(EffectId::from_id(UNEXPLAINED), None);
    }
}
