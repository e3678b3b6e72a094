//! Vocabulary effect `drive_voltage_limit`: the PI drive saturates at its own
//! limit below the supply voltage (diagnosis.md's table), fitted on the
//! recorded voltage ([`crate::drive::fit_limit`]).

use super::{ParamSpec, Params, Term, VocabularyEffect};
use rig_types::RigParams;

/// The id of diagnosis.json.
pub const ID: &str = "drive_voltage_limit";

pub struct DriveVoltageLimit;

const PARAMS: &[ParamSpec] = &[ParamSpec {
    name: crate::drive::LIMIT_PARAM,
    unit: "V",
    lower: 0.0,
    upper: f64::INFINITY,
    meaning: "the drive's output voltage limit (at most the supply)",
}];

impl VocabularyEffect for DriveVoltageLimit {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    fn term(&self) -> Term {
        Term::DriveLimit
    }
    fn apply(&self, model: &mut RigParams, _baseline: &RigParams, p: Params) {
        model.drive.limit_v = p(crate::drive::LIMIT_PARAM);
    }
    fn evidence(&self, p: Params) -> String {
        format!("The recorded drive voltage saturates at {:.2} V, below the supply", p(crate::drive::LIMIT_PARAM))
    }
}
