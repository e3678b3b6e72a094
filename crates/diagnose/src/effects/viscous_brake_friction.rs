//! Vocabulary effect `viscous_brake_friction`: μ(Ω) = μk + c |Ω| in slip
//! (diagnosis.md's table), admissible only when friction grows with slip
//! speed (c > 0).

use super::{ParamSpec, Params, Term, VocabularyEffect};
use crate::composite::{self, Composite};
use rig_types::{FrictionLaw, RigParams};

/// The id of diagnosis.json.
pub const ID: &str = "viscous_brake_friction";

pub struct ViscousBrakeFriction;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mu_kinetic",
        unit: "1",
        lower: 0.0,
        upper: f64::INFINITY,
        meaning: "friction coefficient as the slip speed tends to zero",
    },
    ParamSpec {
        name: "viscous_per_rad_s",
        unit: "s/rad",
        lower: 0.0,
        upper: f64::INFINITY,
        meaning: "growth c of the friction coefficient per rad/s of slip speed",
    },
];

impl VocabularyEffect for ViscousBrakeFriction {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    /// The composite's linear speed term.
    fn term(&self) -> Term {
        Term::Friction(composite::Term::Viscous)
    }
    /// Replaces the friction law by the viscous law; the break-away
    /// coefficient stays the baseline's μs (at least μk).
    fn apply(&self, model: &mut RigParams, baseline: &RigParams, p: Params) {
        let mu_s0 = rig_model::friction::static_mu(&baseline.friction);
        model.friction = FrictionLaw::Viscous {
            mu_static: mu_s0.max(p("mu_kinetic")),
            mu_kinetic: p("mu_kinetic"),
            viscous_per_rad_s: p("viscous_per_rad_s"),
        }
    }
    /// Viscous friction grows with slip speed: a fit with c ≤ 0 (friction
    /// falling linearly with speed) is a shape outside the vocabulary.
    fn inadmissible(&self, fit_all: &mut dyn FnMut() -> Option<Composite>) -> Option<String> {
        fit_all()?.viscous.filter(|&c| c <= 0.0).map(|c| {
            format!(
                "fitted on every run c = {c:.3e} per rad/s ≤ 0: friction falls with slip speed, not viscous friction"
            )
        })
    }
    fn evidence(&self, p: Params) -> String {
        format!(
            "The friction coefficient grows with slip speed by {:.4} per rad/s from {:.3}",
            p("viscous_per_rad_s"),
            p("mu_kinetic")
        )
    }
}
