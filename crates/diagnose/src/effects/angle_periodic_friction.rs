//! Vocabulary effect `angle_periodic_friction`: the normal force varies with
//! the rotor angle, N(φ1) = N0 (1 + a sin(n φ1 + θ_r)), n a whole order per
//! revolution, θ free per run (diagnosis.md's table; F = μ N, Eq. 4-10).

use super::{ParamSpec, Params, Term, VocabularyEffect};
use crate::composite::{self, Composite, Phases};
use rig_types::{Effect, RigParams};

/// The id of diagnosis.json.
pub const ID: &str = "angle_periodic_friction";

pub struct AnglePeriodicFriction;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "amplitude_ratio",
        unit: "1",
        lower: 0.0,
        upper: 1.0,
        meaning: "relative amplitude a of the normal force's variation with the rotor angle",
    },
    ParamSpec {
        name: "order",
        unit: "1/rev",
        lower: 1.0,
        upper: f64::INFINITY,
        meaning: "order n, per rotor revolution (scanned up to pipeline.toml's max_order)",
    },
];

impl VocabularyEffect for AnglePeriodicFriction {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    /// The composite's angle sine (order scan, own phase per run).
    fn term(&self) -> Term {
        Term::Friction(composite::Term::AngleSine)
    }
    fn apply(&self, model: &mut RigParams, _baseline: &RigParams, p: Params) {
        model.effects.push(Effect::AnglePeriodicFriction {
            amplitude_ratio: p("amplitude_ratio"),
            order: p("order").round().max(1.0) as u32,
            phase_rad: 0.0,
        });
    }
    /// θ_φ: φ1 is the run's own (it starts at 0 with the record).
    fn set_phases(&self, e: &mut Effect, phases: Phases) {
        if let Effect::AnglePeriodicFriction { phase_rad, .. } = e {
            *phase_rad = phases.1;
        }
    }
    fn evidence(&self, p: Params) -> String {
        format!(
            "The friction coefficient in slip varies {} times per rotor revolution with relative amplitude {:.3}",
            p("order"),
            p("amplitude_ratio")
        )
    }
    /// A friction of order n drives the rotor speed at order n and its
    /// harmonics, and the shaft carries that torque to the motor side, whose
    /// angle φ2 = φ1 + twist turns at the rotor's mean rate: those lines, in
    /// either speed, are explained, not left over.
    fn explained_order(&self, m: &Composite) -> Option<u32> {
        m.angle_mod.map(|(_, n)| n)
    }
}
