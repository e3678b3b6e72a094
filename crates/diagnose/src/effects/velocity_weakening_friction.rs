//! Vocabulary effect `velocity_weakening_friction`: the Stribeck law
//! μ(Ω) = μk + (μs − μk) exp(−(Ω/vs)²) in slip (diagnosis.md's table; the
//! law is `rig_model::friction::stribeck_mu`), admissible only when it
//! weakens (μs > μk).

use super::{ParamSpec, Params, Term, VocabularyEffect};
use crate::composite::{self, Composite};
use rig_types::{FrictionLaw, RigParams};

/// The id of diagnosis.json.
pub const ID: &str = "velocity_weakening_friction";

pub struct VelocityWeakeningFriction;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "mu_static",
        unit: "1",
        lower: 0.0,
        upper: f64::INFINITY,
        meaning: "friction coefficient at zero slip speed (the law's peak and the break-away coefficient)",
    },
    ParamSpec {
        name: "mu_kinetic",
        unit: "1",
        lower: 0.0,
        upper: f64::INFINITY,
        meaning: "friction coefficient at high slip speed",
    },
    ParamSpec {
        name: "stribeck_speed_rad_s",
        unit: "rad/s",
        lower: 0.0,
        upper: f64::INFINITY,
        meaning: "Stribeck speed vs of the fall from μs to μk",
    },
];

impl VocabularyEffect for VelocityWeakeningFriction {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    /// The composite's Stribeck term (Brent's search for vs in its basin).
    fn term(&self) -> Term {
        Term::Friction(composite::Term::Stribeck)
    }
    /// Replaces the friction law by the Stribeck law: its μs is both the
    /// law's peak and the break-away coefficient, as in rig-model.
    fn apply(&self, model: &mut RigParams, _baseline: &RigParams, p: Params) {
        model.friction = FrictionLaw::Stribeck {
            mu_static: p("mu_static"),
            mu_kinetic: p("mu_kinetic"),
            stribeck_speed_rad_s: p("stribeck_speed_rad_s"),
        }
    }
    /// Velocity weakening is friction that falls from a higher static value:
    /// a fit with μs ≤ μk (friction rising toward a plateau) is a shape
    /// outside the vocabulary.
    fn inadmissible(&self, fit_all: &mut dyn FnMut() -> Option<Composite>) -> Option<String> {
        let m = fit_all()?;
        m.stribeck.filter(|&(mu_s, _)| mu_s <= m.mu_k).map(|(mu_s, _)| {
            format!(
                "fitted on every run μs = {mu_s:.4} ≤ μk = {:.4}: friction rises with slip speed, not velocity weakening",
                m.mu_k
            )
        })
    }
    fn evidence(&self, p: Params) -> String {
        format!(
            "The friction coefficient falls from {:.3} at low slip speed to {:.3} over {:.2} rad/s",
            p("mu_static"),
            p("mu_kinetic"),
            p("stribeck_speed_rad_s")
        )
    }
}
