//! Structural candidate `rotor_absolute`: the damping acts on the absolute
//! rotor speed only, a drag −C_r·Ω1 on rotor 1 (`RigParams::rotor_damping_nm_s_rad`,
//! simulated by rig-model) and no damping on the twist rate (C = 0): the
//! rotor row of Eq. 4-7's diag(C, Cm) acting on Ω1, with the shaft itself
//! undamped.
//!
//! Fitted teacher-forced through the rotor torque balance
//! ([`crate::channels::BalanceData::fit`], Eq. 4-7 first row with the
//! measured r·F, J1 held at the calibration's): r·F = −J1 Ω̇1 + K tw − C_r Ω1 + c0
//! over the training runs' steady states. Admissible when C_r ≥ 0 (a
//! negative drag would feed energy into the rotor).

use super::{Fitted, ParamSpec, StructureCandidate, StructureData};
use rig_types::RigParams;

pub struct RotorAbsolute;

/// The finding's id when a drag on Ω1 wins (alone or beside a twist-rate
/// damping, [`super::both`]): the structural fault it names.
pub const FINDING: &str = "damping_rotor_absolute";

const PARAMS: &[ParamSpec] = &[ParamSpec {
    name: "rotor_damping_nm_s_rad",
    unit: "N·m·s/rad",
    lower: 0.0,
    meaning: "drag on the absolute rotor speed Ω1 (bearings, air, brake viscous share)",
}];

impl StructureCandidate for RotorAbsolute {
    fn id(&self) -> &'static str {
        "rotor_absolute"
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn fit(&self, _model: &RigParams, data: &StructureData, include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
        let f = data.balance.fit(include, false, true)?;
        Some(Fitted { values: vec![f.rotor_drag_nm_s_rad], balance: f, aligned: None, sensor: None, footprint: None })
    }
    /// The damping moves off the twist rate: the motor side is re-estimated under it.
    fn refits_motor_side(&self) -> bool {
        true
    }
    fn finding_id(&self) -> Option<&'static str> {
        Some(FINDING)
    }
    /// C = 0 on the twist rate, C_r on Ω1 (clamped at its bound 0; an
    /// unconstrained negative value is reported, not simulated).
    fn apply(&self, model: &RigParams, fitted: &Fitted) -> RigParams {
        let mut p = model.clone();
        p.shaft_damping_nm_s_rad = 0.0;
        p.rotor_damping_nm_s_rad = fitted.values[0].max(0.0);
        p
    }
    fn describe(&self, fitted: &Fitted) -> String {
        format!(
            "damping on the absolute rotor speed only, C_r = {:.2e} N·m·s/rad on Ω1, C = 0 on the twist rate",
            fitted.values[0]
        )
    }
}
