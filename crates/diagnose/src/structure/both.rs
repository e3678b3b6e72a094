//! Structural candidate `twist_rate_and_rotor`: damping on both, C(Ω2 − Ω1)
//! on the twist rate and a drag −C_r·Ω1 on the absolute rotor speed, both
//! fitted teacher-forced through the rotor torque balance (Eq. 4-7 first row,
//! J1 held at the calibration's, [`crate::channels::BalanceData::fit`]):
//! r·F = −J1 Ω̇1 + K tw + C tẇ − C_r Ω1 + c0. It contains the other two
//! placements (C_r = 0, C = 0) and Eq. 4-7 as published, whose damping
//! matrix acts on Ω1. Admissible when C ≥ 0 and C_r ≥ 0.

use super::{Fitted, ParamSpec, StructureCandidate, StructureData};
use rig_types::RigParams;

pub struct TwistRateAndRotor;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "shaft_damping_nm_s_rad",
        unit: "N·m·s/rad",
        lower: 0.0,
        meaning: "damping on the twist rate Ω2 − Ω1 (shaft material, coupling)",
    },
    ParamSpec {
        name: "rotor_damping_nm_s_rad",
        unit: "N·m·s/rad",
        lower: 0.0,
        meaning: "drag on the absolute rotor speed Ω1 (bearings, air, brake viscous share)",
    },
];

impl StructureCandidate for TwistRateAndRotor {
    fn id(&self) -> &'static str {
        "twist_rate_and_rotor"
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn fit(&self, _model: &RigParams, data: &StructureData, include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
        let f = data.balance.fit(include, true, true)?;
        Some(Fitted {
            values: vec![f.twist_damping_nm_s_rad, f.rotor_drag_nm_s_rad],
            balance: f,
            aligned: None,
            sensor: None,
            footprint: None,
        })
    }
    /// The new term is the drag on Ω1: the finding names it.
    /// The damping moves off the twist rate: the motor side is re-estimated under it.
    fn refits_motor_side(&self) -> bool {
        true
    }
    fn finding_id(&self) -> Option<&'static str> {
        Some(super::rotor_absolute::FINDING)
    }
    /// Both clamped at their bound 0 (an unconstrained negative value is reported, not simulated).
    fn apply(&self, model: &RigParams, fitted: &Fitted) -> RigParams {
        let mut p = model.clone();
        p.shaft_damping_nm_s_rad = fitted.values[0].max(0.0);
        p.rotor_damping_nm_s_rad = fitted.values[1].max(0.0);
        p
    }
    fn describe(&self, fitted: &Fitted) -> String {
        format!(
            "damping on both, C = {:.2e} N·m·s/rad on the twist rate and C_r = {:.2e} N·m·s/rad on Ω1",
            fitted.values[0], fitted.values[1]
        )
    }
}
