//! Vocabulary effect `normal_force_modulation`: the normal force oscillates in
//! time, N(t) = N0 (1 + a sin(2π f t + θ_r)), θ free per run (diagnosis.md's
//! table); in slip F = μ N (Eq. 4-10), so μ_obs = F/N0 carries the factor.

use super::{ParamSpec, Params, Term, VocabularyEffect};
use crate::composite::{self, Phases};
use rig_types::{Effect, RigParams};

/// The id of diagnosis.json.
pub const ID: &str = "normal_force_modulation";

pub struct NormalForceModulation;

const PARAMS: &[ParamSpec] = &[
    ParamSpec {
        name: "amplitude_ratio",
        unit: "1",
        lower: 0.0,
        upper: 1.0,
        meaning: "relative amplitude a of the normal force's oscillation",
    },
    ParamSpec {
        name: "frequency_hz",
        unit: "Hz",
        lower: 0.0,
        upper: f64::INFINITY,
        meaning: "frequency f of the oscillation (scanned over pipeline.toml's grid, then refined)",
    },
];

impl VocabularyEffect for NormalForceModulation {
    fn id(&self) -> &'static str {
        ID
    }
    fn params(&self) -> &'static [ParamSpec] {
        PARAMS
    }
    /// The composite's time sine (frequency scan, own phase per run).
    fn term(&self) -> Term {
        Term::Friction(composite::Term::TimeSine)
    }
    fn apply(&self, model: &mut RigParams, _baseline: &RigParams, p: Params) {
        model.effects.push(Effect::NormalForceModulation {
            amplitude_ratio: p("amplitude_ratio"),
            frequency_hz: p("frequency_hz"),
            phase_rad: 0.0,
        });
    }
    /// θ_t: t is the run's own (it starts at 0 with the record).
    fn set_phases(&self, e: &mut Effect, phases: Phases) {
        if let Effect::NormalForceModulation { phase_rad, .. } = e {
            *phase_rad = phases.0;
        }
    }
    fn evidence(&self, p: Params) -> String {
        format!(
            "The friction coefficient in slip oscillates in time at {:.3} Hz with relative amplitude {:.3} (own phase per run)",
            p("frequency_hz"),
            p("amplitude_ratio")
        )
    }
}
