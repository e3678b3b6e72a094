//! Structural candidate `twist_rate`: the rig model's own placement of the
//! shaft damping, C(Ω2 − Ω1) (rig-model docs: a departure from Eq. 4-7, whose
//! damping matrix diag(C, Cm) acts on Ω1 and Ω2). It is the baseline: C is
//! the estimation's (voltage-step fit), nothing is refitted in the model;
//! the rotor balance the other candidates are compared with fits C on the
//! twist rate and no drag.

use super::{Fitted, ParamSpec, StructureCandidate, StructureData};
use rig_types::RigParams;

pub struct TwistRate;

/// Its id (diagnosis.json's `structure.damping` of the rig model's placement).
pub const ID: &str = "twist_rate";

const PARAMS: &[ParamSpec] = &[ParamSpec {
    name: "shaft_damping_nm_s_rad",
    unit: "N·m·s/rad",
    lower: 0.0,
    meaning: "damping on the twist rate Ω2 − Ω1 (estimated on the voltage steps)",
}];

impl StructureCandidate for TwistRate {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    /// The estimation's C (the model is not changed: this is the baseline);
    /// the balance the others are compared with has C on the twist rate
    /// refitted on the same runs (no drag).
    fn fit(&self, model: &RigParams, data: &StructureData, include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
        let balance = data.balance.fit(include, true, false)?;
        Some(Fitted {
            values: vec![model.shaft_damping_nm_s_rad],
            balance,
            aligned: None,
            sensor: None,
            footprint: None,
        })
    }
    fn apply(&self, model: &RigParams, _fitted: &Fitted) -> RigParams {
        model.clone()
    }
    fn describe(&self, fitted: &Fitted) -> String {
        format!(
            "damping on the twist rate only, C = {:.2e} N·m·s/rad (the rig model's placement, the estimation's C)",
            fitted.values[0]
        )
    }
}
