//! The effect vocabulary of ../shared/spec/diagnosis.md: one file per effect
//! and one [`REGISTRY`] (issue 26, item 1), in the style of [`crate::structure`].
//!
//! Each effect's file carries everything the diagnosis knows about it: its id
//! (`ID`, the one spelling of diagnosis.json's `effect`), its parameters
//! (JSON keys, units, bounds, meaning), the teacher-forced channel it acts on,
//! how it is fitted ([`VocabularyEffect::term`]: the term it switches on in the
//! joint fit of its channel), how it enters the simulated model
//! ([`VocabularyEffect::apply`], [`VocabularyEffect::set_phases`]), its
//! admissibility rule and its evidence sentence. Every other module iterates
//! the registry and never names an effect: forward selection
//! ([`crate::select`]) tries the registry's effects in order, the extended
//! model ([`crate::channels::extended_params`]) and the per-run phases
//! ([`crate::channels::with_run_phases`]) ask each effect, and the virtual rig
//! names effects through the `ID` constants. A tidy test
//! (`crates/pipeline/tests/tidy.rs`, `vocabulary_ids_are_spelt_in_their_effect_file`)
//! fails where an id is spelt as a string literal outside its effect file.
//!
//! | id | channel | term (fit) | parameters |
//! |---|---|---|---|
//! | `normal_force_modulation` | friction | time sine, own phase per run | amplitude_ratio, frequency_hz |
//! | `angle_periodic_friction` | friction | angle sine, own phase per run | amplitude_ratio, order |
//! | `velocity_weakening_friction` | friction | Stribeck speed law | mu_static, mu_kinetic, stribeck_speed_rad_s |
//! | `viscous_brake_friction` | friction | linear speed law | mu_kinetic, viscous_per_rad_s |
//! | `drive_voltage_limit` | drive | the PI's own saturation | limit_v |
//!
//! # The joint fit stays joint
//!
//! The effects of one channel are fitted together, in one least squares
//! ([`crate::composite`]: the friction coefficient in slip as a speed law times
//! a time and an angle modulation; [`crate::drive`]: the PI voltage with its
//! limit). An effect contributes its term ([`Term`]) to that fit; the fit knows
//! the term's regressors and searches (the frequency scan, the order scan, the
//! Stribeck speed's basin), not the effect. Adding an effect whose law is one of
//! these terms is one new file and one line in [`REGISTRY`] (test
//! `an_effect_is_one_file_and_one_registry_line`); an effect with a law of a new
//! shape adds its term to the fit of its channel as well.
//!
//! The verdicts `none` and `unexplained` are not effects; their one home is
//! here ([`NONE`], [`UNEXPLAINED`]).

pub mod angle_periodic_friction;
pub mod drive_voltage_limit;
pub mod normal_force_modulation;
pub mod velocity_weakening_friction;
pub mod viscous_brake_friction;

use crate::composite::{Composite, Phases};
use rig_types::{Campaign, RigParams};
use std::collections::BTreeMap;

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

/// The term an effect contributes to the joint fit of its channel.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Term {
    /// A term of the composite friction law ([`crate::composite::Term`]).
    Friction(crate::composite::Term),
    /// The drive's own voltage limit below the supply ([`crate::drive::fit_limit`]).
    DriveLimit,
}

impl Term {
    pub fn channel(self) -> Channel {
        match self {
            Term::Friction(_) => Channel::Friction,
            Term::DriveLimit => Channel::Drive,
        }
    }
}

/// One parameter of a vocabulary effect (a JSON key of a finding's `params`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    /// The JSON key, the name the fit of the effect's term reports it under.
    pub name: &'static str,
    pub unit: &'static str,
    /// The physical range [lower, upper] (the fit's search range where it has one).
    pub lower: f64,
    pub upper: f64,
    pub meaning: &'static str,
}

/// A finding's parameters by JSON key (0 when missing).
pub type Params<'a> = &'a dyn Fn(&str) -> f64;

/// A vocabulary effect (one file each; [`REGISTRY`]).
pub trait VocabularyEffect: Sync {
    /// The id of diagnosis.json (the file's `ID`).
    fn id(&self) -> &'static str;
    /// Its parameters, in the spec's order.
    fn params(&self) -> &'static [ParamSpec];
    /// What it contributes to the joint fit of its channel.
    fn term(&self) -> Term;
    /// The teacher-forced channel it acts on.
    fn channel(&self) -> Channel {
        self.term().channel()
    }
    /// How it enters the simulated model: `model` (the extended model being
    /// built from `baseline`) with this effect at the finding's parameters
    /// `p`, each phase θ at 0 (per-run phases: [`VocabularyEffect::set_phases`]).
    fn apply(&self, model: &mut RigParams, baseline: &RigParams, p: Params);
    /// One run's nuisance phases (θ_t, θ_φ) in the simulator's effect `e`,
    /// when `e` is this effect's (the phases are free per run, spec).
    fn set_phases(&self, _e: &mut rig_types::Effect, _phases: Phases) {}
    /// The admissibility rule: `Some(why)` when the fit of the current model
    /// plus this effect on every run (`fit_all`, called only by effects with a
    /// rule: it is a joint fit of its own) does not have the sign that defines
    /// the effect (diagnosis.md's table; crate docs, "admissible").
    fn inadmissible(&self, _fit_all: &mut dyn FnMut() -> Option<Composite>) -> Option<String> {
        None
    }
    /// The evidence sentence's first clause: what the fitted effect does, in
    /// numbers (`p`, the fit's parameters by JSON key).
    fn evidence(&self, p: Params) -> String;
    /// The shaft order whose lines the fitted final law `m` explains in
    /// either speed (an angle-locked friction drives them), if any.
    fn explained_order(&self, _m: &Composite) -> Option<u32> {
        None
    }
    /// A fit in free run, for an effect only the motion can show (none of the
    /// vocabulary's five: each is seen teacher-forced). Defaulted: `None`
    /// means the teacher-forced fit of [`VocabularyEffect::term`] is the fit.
    /// The one law the diagnosis fits in free run, contact ageing, is outside
    /// the spec's vocabulary: its fit is the extension's ([`crate::extension`],
    /// "The ageing law").
    fn fit_free_run(&self, _c: &Campaign, _model: &RigParams) -> Option<BTreeMap<String, f64>> {
        None
    }
}

/// Every vocabulary effect, in the order candidates are tried and listed.
pub static REGISTRY: &[&dyn VocabularyEffect] = &[
    &normal_force_modulation::NormalForceModulation,
    &angle_periodic_friction::AnglePeriodicFriction,
    &velocity_weakening_friction::VelocityWeakeningFriction,
    &viscous_brake_friction::ViscousBrakeFriction,
    &drive_voltage_limit::DriveVoltageLimit,
];

/// A vocabulary effect of the [`REGISTRY`], as the diagnosis passes it
/// around: compared, ordered and hashed by its id.
#[derive(Clone, Copy)]
pub struct EffectId(pub &'static dyn VocabularyEffect);

impl EffectId {
    /// Every effect of the registry, in its order.
    pub fn all() -> impl Iterator<Item = EffectId> {
        REGISTRY.iter().map(|e| EffectId(*e))
    }

    /// The registry's effect with this id (`None` for a verdict or an unknown id).
    pub fn from_id(id: &str) -> Option<EffectId> {
        EffectId::all().find(|e| e.id() == id)
    }
}

impl std::ops::Deref for EffectId {
    type Target = dyn VocabularyEffect;
    fn deref(&self) -> &Self::Target {
        self.0
    }
}

impl std::fmt::Debug for EffectId {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.id())
    }
}

impl PartialEq for EffectId {
    fn eq(&self, other: &Self) -> bool {
        self.id() == other.id()
    }
}

impl Eq for EffectId {}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::composite::{self, FrictionSet};
    use crate::friction::tests::synth_noisy;
    use std::f64::consts::PI;

    #[test]
    fn ids_round_trip_and_are_distinct() {
        for e in EffectId::all() {
            assert_eq!(EffectId::from_id(e.id()).map(|x| x.id()), Some(e.id()));
            assert_eq!(EffectId::all().filter(|x| x.id() == e.id()).count(), 1, "{} twice", e.id());
        }
        assert!(EffectId::from_id(NONE).is_none());
        assert!(EffectId::from_id(UNEXPLAINED).is_none());
    }

    /// Every effect's term is its own (the joint fit attributes each fitted
    /// parameter to a term, so two effects on one term could not be told apart),
    /// and its parameters are well formed: distinct keys, lower ≤ upper, a unit
    /// and a meaning.
    #[test]
    fn every_effect_has_its_own_term_and_well_formed_params() {
        for e in EffectId::all() {
            assert_eq!(EffectId::all().filter(|x| x.term() == e.term()).count(), 1, "{}: term shared", e.id());
            let ps = e.params();
            assert!(!ps.is_empty(), "{}", e.id());
            for (i, p) in ps.iter().enumerate() {
                assert!(p.lower <= p.upper && !p.unit.is_empty() && !p.meaning.is_empty(), "{}: {p:?}", e.id());
                assert!(ps[..i].iter().all(|q| q.name != p.name), "{}: {} twice", e.id(), p.name);
            }
        }
    }

    /// The keys each friction effect declares are exactly the keys the joint
    /// fit reports for its term (alone, and with every other friction term at
    /// once), each within the bounds the effect declares on data generated
    /// with every effect at once.
    #[test]
    fn the_joint_fit_reports_every_declared_parameter_within_its_bounds() {
        let d = synth_noisy(5, 7, 0.003, |r, t, phi, w| {
            (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64) + 0.01 * w)
                * (1.0 + 0.1 * (2.0 * PI * 1.3 * t + 0.9 * r as f64).sin())
                * (1.0 + 0.08 * (3.0 * phi + 0.4 * r as f64).sin())
        });
        let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
        let friction: Vec<EffectId> = EffectId::all().filter(|e| e.channel() == Channel::Friction).collect();
        let term = |e: &EffectId| match e.term() {
            Term::Friction(t) => t,
            Term::DriveLimit => unreachable!("a friction effect"),
        };
        let every = friction.iter().fold(FrictionSet::default(), |s, e| s.with(term(e)));
        let full = composite::fit_composite(&d, every, &freqs, 8).expect("joint fit");
        for e in &friction {
            let t = term(e);
            let alone = composite::fit_composite(&d, FrictionSet::default().with(t), &freqs, 8).expect("fit");
            for fit in [&alone, &full] {
                let mut keys: Vec<&str> = fit.params.iter().filter(|p| p.0 == t).map(|p| p.1).collect();
                keys.sort();
                keys.dedup();
                let mut declared: Vec<&str> = e.params().iter().map(|p| p.name).collect();
                declared.sort();
                assert_eq!(keys, declared, "{}", e.id());
            }
            for p in e.params() {
                let v = full.params.iter().find(|q| q.0 == t && q.1 == p.name).map(|q| q.2).unwrap();
                assert!((p.lower..=p.upper).contains(&v), "{}.{} = {v} outside {p:?}", e.id(), p.name);
            }
        }
    }

    /// Adding an effect is one new file and one registry line: a test-only
    /// effect, declared here as its own file would declare it (an id, its
    /// parameters, its term, how it applies, its sentence), goes through the
    /// same code as the vocabulary's: forward selection over a registry of
    /// its own finds it, reports its parameters and its sentence, and the
    /// extended model and the per-run phases apply it. Nothing else names it.
    mod an_effect_is_one_file_and_one_registry_line {
        use super::super::*;
        use crate::drive::{Pi, predict_voltage};
        use crate::prepare::RunSignals;

        /// The test effect: a limit of the drive under an id of its own.
        struct TestLimit;
        const ID: &str = "test_drive_limit";
        const PARAMS: &[ParamSpec] =
            &[ParamSpec { name: "limit_v", unit: "V", lower: 0.0, upper: 1e3, meaning: "test limit" }];
        impl VocabularyEffect for TestLimit {
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
                model.drive.limit_v = p("limit_v") - 1.0;
            }
            fn evidence(&self, p: Params) -> String {
                format!("test limit at {:.1} V", p("limit_v"))
            }
        }
        /// The test's registry: the test effect's one line, and a vocabulary effect.
        static TEST_REGISTRY: &[&dyn VocabularyEffect] =
            &[&super::super::normal_force_modulation::NormalForceModulation, &TestLimit];

        /// Six runs whose drive saturates at 5 V (PI kp = 2 V·s/rad, ki = 10 V/rad
        /// on a motor speed that lags the ramp and wobbles), Coulomb friction
        /// μ = 0.4 in slip, small deterministic noise on both channels.
        fn runs() -> Vec<RunSignals> {
            let truth = Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 };
            (0..6)
                .map(|r| {
                    let sp = [1.0, 2.0, 3.0][r % 3];
                    let n = 4000;
                    let time_s: Vec<f64> = (0..n).map(|k| k as f64 * 0.002).collect();
                    let wobble = |t: f64, f: f64| (2.0 * std::f64::consts::PI * f * t + r as f64).sin();
                    let motor_speed_rad_s: Vec<f64> =
                        time_s.iter().map(|&t| sp * (1.0 - (-t / 0.8).exp()) * (1.0 + 0.1 * wobble(t, 0.7))).collect();
                    let rotor_speed_rad_s: Vec<f64> = time_s.iter().map(|&t| 5.0 + 0.3 * wobble(t, 0.37)).collect();
                    let integral = |w: &[f64]| {
                        w.iter()
                            .scan(0.0, |a, x| {
                                *a += x * 0.002;
                                Some(*a)
                            })
                            .collect::<Vec<f64>>()
                    };
                    let noise = |k: usize, m: usize| (k * m % 101) as f64 / 50.0 - 1.0;
                    let mu_obs: Vec<f64> = (0..n).map(|k| 0.4 + 0.002 * noise(k, 7919)).collect();
                    let mut s = RunSignals {
                        id: format!("r{r}"),
                        fold: r % 3,
                        setpoint_rad_s: sp,
                        normal_force_n: 10.0,
                        ramp_s: 2.0,
                        rotor_angle_rad: integral(&rotor_speed_rad_s),
                        motor_angle_rad: integral(&motor_speed_rad_s),
                        time_s,
                        rotor_speed_rad_s,
                        motor_speed_rad_s,
                        voltage_v: vec![],
                        friction_force_n: mu_obs.iter().map(|m| m * 10.0).collect(),
                        slip_idx: (0..n).collect(),
                        mu_obs,
                        force_noise_n: 0.002 * 10.0 * 0.58,
                        voltage_noise_v: 0.01 * 0.58,
                        steady_from: n - 400,
                        drive: Default::default(),
                    };
                    let (v, _, _) = predict_voltage(&truth, &s);
                    s.voltage_v = v.iter().enumerate().map(|(k, v)| v + 0.01 * noise(k, 104_729)).collect();
                    s
                })
                .collect()
        }

        #[test]
        fn selection_over_a_registry_finds_its_test_effect() {
            let mut opts = crate::DiagnoseOptions::from_pipeline_toml(include_str!("../../../../pipeline.toml"))
                .expect("pipeline.toml");
            opts.folds = 3;
            let runs = runs();
            let d = crate::select::select_over(TEST_REGISTRY, "test", &runs, 24.0, &opts).expect("selection").conclude(
                "test",
                0.06,
                None,
                &[],
                &opts,
            );
            assert_eq!(d.verdict, ID, "{:?}", d.findings);
            let f = &d.findings[0];
            assert!((f.params["limit_v"] - 5.0).abs() < 0.25, "{:?}", f.params);
            assert!(f.evidence.starts_with("test limit at ") && f.evidence.contains("paired t"), "{}", f.evidence);
            let tried: Vec<&str> = d.candidates.iter().map(|c| c.effect.as_str()).collect();
            assert_eq!(tried, [super::super::normal_force_modulation::ID, ID]);
            // The vocabulary's own registry finds the vocabulary's effect on the same runs.
            let v = crate::diagnose_signals("test", &runs, 24.0, 0.06, None, &[], &opts).expect("selection");
            assert_eq!(v.verdict, super::super::drive_voltage_limit::ID);
            assert_eq!(v.findings[0].params, f.params);
        }

        #[test]
        fn the_extended_model_and_the_phases_apply_a_test_effect() {
            let base = crate::channels::tests::base_params();
            let (nfm, e) = (EffectId(TEST_REGISTRY[0]), EffectId(TEST_REGISTRY[1]));
            assert_eq!(e.channel(), Channel::Drive);
            let m = |kv: &[(&str, f64)]| kv.iter().map(|(k, v)| (k.to_string(), *v)).collect::<BTreeMap<_, _>>();
            let p = crate::channels::extended_params(
                &base,
                &[(e, m(&[("limit_v", 12.0)])), (nfm, m(&[("amplitude_ratio", 0.1), ("frequency_hz", 1.5)]))],
            );
            assert_eq!(p.drive.limit_v, 11.0);
            let q = crate::channels::with_run_phases_of(TEST_REGISTRY, &p, (0.5, 0.0));
            assert_eq!(
                q.effects,
                vec![rig_types::Effect::NormalForceModulation {
                    amplitude_ratio: 0.1,
                    frequency_hz: 1.5,
                    phase_rad: 0.5
                }]
            );
        }
    }
}
