//! Structural candidate `twist_rate`: the rig model's own placement of the
//! shaft damping, C(Ω2 − Ω1) (rig-model docs: a departure from Eq. 4-7, whose
//! damping matrix diag(C, Cm) acts on Ω1 and Ω2). It is the baseline: C is
//! the estimation's (voltage-step fit), nothing is refitted here.

use super::{Fitted, ParamSpec, StructureCandidate};
use crate::channels::BalanceData;
use rig_types::RigParams;

pub struct TwistRate;

const PARAMS: &[ParamSpec] = &[ParamSpec {
    name: "shaft_damping_nm_s_rad",
    unit: "N·m·s/rad",
    lower: 0.0,
    meaning: "damping on the twist rate Ω2 − Ω1 (estimated on the voltage steps)",
}];

impl StructureCandidate for TwistRate {
    fn id(&self) -> &'static str {
        "twist_rate"
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    /// The estimation's C (the balance is not refitted: this is the baseline).
    fn fit(&self, model: &RigParams, _data: &BalanceData, _include: &dyn Fn(&str) -> bool) -> Option<Fitted> {
        Some(Fitted { values: vec![model.shaft_damping_nm_s_rad] })
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
