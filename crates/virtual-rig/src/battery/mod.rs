//! The battery: a deterministic, seeded list of hidden-effect campaigns that
//! tests the open-world diagnosis (issue 9, item 7), the successor of
//! [`crate::confusion`]. Each [`Case`] carries its truth and the answer a
//! right diagnosis gives ([`Case::expected`]); [`Battery::run`] generates each
//! campaign and hands it to a caller-supplied diagnosis (this crate does not
//! depend on the diagnosis), [`judge`] scores the answer, and three tables
//! summarise it: the confusion matrix ([`confusion_table`]), the false-alarm
//! rate on effect-free rigs with its binomial 95 % interval
//! ([`false_alarm_table`]) and the detection limit of each vocabulary effect
//! ([`detection_table`]).
//!
//! Groups of cases ([`Group`]):
//! - `null`: the rig drawn (±8–10 % around Table 4.5, as [`crate::draw_rig`]) with nothing hidden: `none`;
//! - `null_stick_slip`: an effect-free rig whose campaign stick-slips in at
//!   least [`crate::MIN_STICK_SLIP_RUNS`] operating points
//!   ([`crate::draw_stick_slip_rig`]): `none` (what free-run thresholds are
//!   calibrated on);
//! - `single`: each vocabulary effect alone, drawn as [`crate::draw_hidden`]: that effect;
//! - `compound`: two vocabulary effects at once (every pair except
//!   velocity weakening + viscous brake, which are two friction laws and
//!   cannot both be the brake's law): both must be found, the verdict is either;
//! - `vocabulary_plus_outside`: a vocabulary effect and one outside the
//!   vocabulary: `unexplained`, with the vocabulary effect found as a partial explanation;
//! - `outside`: one effect outside the vocabulary ([`Hidden::OUTSIDE`]): `unexplained`
//!   (static friction aging, which only a stick shows, on a stick-slipping rig);
//! - `structural`: one structural fault ([`Hidden::STRUCTURAL`]) on a
//!   stick-slipping rig: its structural id or `unexplained` ([`Expected::Structural`]);
//! - `structural_plus_vocabulary`: a structural fault and a vocabulary effect:
//!   the vocabulary effect found, and the structure named or the verdict `unexplained`;
//! - `ladder`: each vocabulary effect at six sizes down to where it should
//!   be lost in the noise ([`LADDER_STEPS`]): the effect, or a miss.
//!
//! Confounds to expect (physics, to be checked with numbers once the
//! diagnosis runs on the battery): brake fade lowers μ most where friction
//! power T1·Ω1 is largest, i.e. at high slip speed, and can pass for
//! velocity weakening; rotor imbalance is periodic in φ1 like
//! `angle_periodic_friction` of order 1, but additive (not ∝ N) and present
//! with the brake open; force-offset drift is slow like a low-frequency
//! `normal_force_modulation`; the force sensor's q F² makes the measured μ
//! grow with N; motor warm-up changes R and k_e between runs, which no
//! vocabulary effect does; the current limit only shows where the current
//! would exceed I_max (start-up, break-away).

use crate::{Hidden, Protocol, Truth, VirtualRigError, draw_hidden, draw_rig, generate, ids, write_campaign};
use rig_types::Campaign;
use std::collections::BTreeMap;
use std::path::Path;

mod judge;
mod render;
mod shard;
mod truths;
pub use judge::{Judgement, Outcome, battery_tolerance, judge};
pub use render::{
    battery_outputs, clopper_pearson, confusion_table, detection_sheet, detection_table, false_alarm_table,
    markdown_table, report_markdown, wrong_table,
};
pub use shard::{BatterySlice, CaseResult, ExactResult, merge_slices};
use truths::{alone, base_rig, compound, ladder_hidden, max_rpm};

/// One finding of a diagnosis, as diagnosis.md's `findings[]` (effect id and
/// its parameters under their JSON keys).
#[derive(Debug, Clone, PartialEq, Default, serde::Deserialize, serde::Serialize)]
pub struct Finding {
    pub effect: String,
    /// Absent in the JSON of an `unexplained` finding (it has no parameters).
    #[serde(default)]
    pub params: BTreeMap<String, f64>,
}

/// What a blind diagnosis returned for one campaign: `verdict` and every
/// finding in order, read from diagnosis.json's schema
/// (../shared/spec/diagnosis.md; other fields ignored), so any diagnosis that
/// writes the spec's JSON converts with `serde_json::from_value`.
#[derive(Debug, Clone, PartialEq, Default, serde::Deserialize, serde::Serialize)]
pub struct DiagnosisResult {
    pub verdict: String,
    pub findings: Vec<Finding>,
    /// The spec's top-level `structure` (where the diagnosis puts the
    /// damping), absent in older files.
    #[serde(default)]
    pub structure: Option<StructureAnswer>,
}

/// diagnosis.json's `structure` object: the damping placement the diagnosis
/// selected (its other fields ignored).
#[derive(Debug, Clone, PartialEq, Default, serde::Deserialize, serde::Serialize)]
pub struct StructureAnswer {
    pub damping: String,
}

/// The kind of a case.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord)]
pub enum Group {
    Null,
    NullStickSlip,
    Single,
    Compound,
    VocabularyPlusOutside,
    Outside,
    Structural,
    StructuralPlusVocabulary,
    Ladder,
}

impl Group {
    pub fn name(self) -> &'static str {
        match self {
            Group::Null => "null",
            Group::NullStickSlip => "null_stick_slip",
            Group::Single => "single",
            Group::Compound => "compound",
            Group::VocabularyPlusOutside => "vocabulary_plus_outside",
            Group::Outside => "outside",
            Group::Structural => "structural",
            Group::StructuralPlusVocabulary => "structural_plus_vocabulary",
            Group::Ladder => "ladder",
        }
    }
}

/// The rung of a detection-limit ladder a case stands on.
#[derive(Debug, Clone, PartialEq)]
pub struct Rung {
    pub effect: &'static str,
    /// 0 = largest effect.
    pub step: usize,
    /// What `size` measures (see [`LADDER_STEPS`]).
    pub size_name: &'static str,
    pub size: f64,
}

/// Number of rungs of each detection ladder.
pub const LADDER_STEPS: usize = 6;

/// The ladder of one vocabulary effect: what its size measures and the sizes,
/// largest effect first, halving down to where the effect should be lost in
/// the sensor noise. Sizes:
/// - `normal_force_modulation`, `angle_periodic_friction`: the modulation depth a;
/// - `velocity_weakening_friction`: (μs − μk)/μk, the friction excess at rest;
/// - `viscous_brake_friction`: c·(10 rad/s)/μk, the friction excess at 10 rad/s of slip;
/// - `drive_voltage_limit`: the limit over the back-EMF n·k_e·Ω at the
///   highest set-point (above 1 the limit only bites under load, at 1.15 hardly).
pub fn ladder(effect: &str) -> (&'static str, [f64; LADDER_STEPS]) {
    match effect {
        ids::NORMAL_FORCE_MODULATION | ids::ANGLE_PERIODIC_FRICTION => {
            ("amplitude_ratio", [0.16, 0.08, 0.04, 0.02, 0.01, 0.005])
        }
        ids::VELOCITY_WEAKENING_FRICTION => ("static_excess_ratio", [0.4, 0.2, 0.1, 0.05, 0.025, 0.0125]),
        ids::VISCOUS_BRAKE_FRICTION => ("excess_at_10_rad_s_ratio", [0.3, 0.15, 0.075, 0.0375, 0.019, 0.0094]),
        ids::DRIVE_VOLTAGE_LIMIT => ("limit_over_back_emf", [0.55, 0.7, 0.8, 0.9, 1.0, 1.15]),
        _ => ("", [0.0; LADDER_STEPS]),
    }
}

/// What a right diagnosis answers.
#[derive(Debug, Clone, PartialEq)]
pub enum Expected {
    /// `none`: the baseline explains the data.
    None,
    /// Every listed vocabulary effect among the findings (with its parameters),
    /// no other, and the verdict one of them.
    Effects(Vec<&'static str>),
    /// `unexplained`, with the listed vocabulary effects found as a partial explanation.
    Unexplained { partial: Vec<&'static str> },
    /// A structural fault (diagnosis.md: "Structure is a candidate like an
    /// effect"): the structure `id` among the findings, or the verdict
    /// `unexplained`; the listed vocabulary effects found either way.
    Structural { id: &'static str, partial: Vec<&'static str> },
}

/// One campaign of the battery.
#[derive(Debug, Clone, PartialEq)]
pub struct Case {
    /// Unique, also the campaign's name.
    pub id: String,
    pub group: Group,
    /// Seed of the rig draw and of the campaign's noise.
    pub seed: u64,
    pub truth: Truth,
    pub rung: Option<Rung>,
}

impl Case {
    /// The answer a right diagnosis gives.
    pub fn expected(&self) -> Expected {
        let hidden = self.truth.hidden_all();
        let vocab: Vec<&'static str> = hidden.iter().filter(|h| !h.is_outside()).map(|h| h.id()).collect();
        if hidden.is_empty() {
            Expected::None
        } else if hidden.iter().any(|h| h.is_outside() && !h.is_structural()) {
            Expected::Unexplained { partial: vocab }
        } else if let Some(id) = hidden.iter().find_map(|h| h.structural_id()) {
            Expected::Structural { id, partial: vocab }
        } else {
            Expected::Effects(vocab)
        }
    }

    /// The expected verdict as one string: `none`, the effect id, the ids of a
    /// compound joined by `+` (any of them is a right verdict), `unexplained`,
    /// or `<structural id>/unexplained` for a structural fault (either is right).
    pub fn expected_verdict(&self) -> String {
        match self.expected() {
            Expected::None => ids::NONE.into(),
            Expected::Effects(e) => e.join("+"),
            Expected::Unexplained { .. } => ids::UNEXPLAINED.into(),
            Expected::Structural { id, .. } => format!("{id}/{}", ids::UNEXPLAINED),
        }
    }

    /// Row of the confusion matrix: `none`, `none:stick_slip`, the effect,
    /// `a+b`, `a+outside:x`, `outside:x`, `structural:s`, `a+structural:s` or `ladder:a`.
    pub fn truth_class(&self) -> String {
        let names: Vec<String> = self
            .truth
            .hidden_all()
            .iter()
            .map(|h| {
                if h.is_structural() {
                    format!("structural:{}", h.class())
                } else if h.is_outside() {
                    format!("outside:{}", h.class())
                } else {
                    h.class().to_string()
                }
            })
            .collect();
        match (self.group, &self.rung) {
            (_, Some(r)) => format!("ladder:{}", r.effect),
            (Group::NullStickSlip, _) => "none:stick_slip".into(),
            _ if names.is_empty() => "none".into(),
            _ => names.join("+"),
        }
    }

    /// The case's campaign under `protocol`. The description says nothing of
    /// what is hidden (a blind diagnosis must not read it there).
    pub fn generate(&self, protocol: &Protocol) -> Result<Campaign, VirtualRigError> {
        let mut c = generate(&self.id, &self.truth, protocol, self.seed)?;
        c.description = "virtual rig battery campaign".into();
        Ok(c)
    }
}

/// A list of cases under one protocol.
#[derive(Debug, Clone, PartialEq)]
pub struct Battery {
    pub name: &'static str,
    /// The first case seed it was built from.
    pub seed: u64,
    pub protocol: Protocol,
    pub cases: Vec<Case>,
}

/// Seed of [`Battery::full`] and [`Battery::ci`].
pub const BATTERY_SEED: u64 = 90_000;

/// How many cases of each group a battery has.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Sizes {
    pub nulls: usize,
    /// Effect-free rigs that stick-slip ([`crate::draw_stick_slip_rig`]).
    pub stick_slip_nulls: usize,
    pub singles_per_effect: usize,
    /// Seeds per compound pair (0: no compounds).
    pub compound_seeds: usize,
    /// Outside effects paired with a vocabulary effect (at most 11).
    pub vocabulary_plus_outside: usize,
    pub outside_seeds: usize,
    /// Seeds per structural fault.
    pub structural_seeds: usize,
    /// Vocabulary effects paired with each structural fault (at most 5).
    pub structural_plus_vocabulary: usize,
    pub ladder_seeds: usize,
}

impl Battery {
    /// The full battery under [`Protocol::full`]: 20 nulls, 20 stick-slipping
    /// nulls, 3 draws of each vocabulary effect, every compound pair twice,
    /// each outside effect once with a vocabulary effect and 3 times alone,
    /// each structural fault 3 times alone and with 2 vocabulary effects,
    /// each ladder rung 20 times (737 campaigns;
    /// 20 draws per rung put the 95 % band of P(right) = 1 at 0.83–1).
    pub fn full() -> Battery {
        Battery::full_seeded(BATTERY_SEED)
    }

    /// [`Battery::full`] with its case seeds starting at `seed`.
    pub fn full_seeded(seed: u64) -> Battery {
        let sizes = Sizes {
            nulls: 20,
            stick_slip_nulls: 20,
            singles_per_effect: 3,
            compound_seeds: 2,
            vocabulary_plus_outside: 11,
            outside_seeds: 3,
            structural_seeds: 3,
            structural_plus_vocabulary: 2,
            ladder_seeds: 20,
        };
        Battery::build("full", Protocol::full(), sizes, seed, &Hidden::OUTSIDE, &Hidden::STRUCTURAL)
    }

    /// The seeded CI subset under [`Protocol::small`] (18 campaigns): 3 nulls
    /// and a stick-slipping one, each vocabulary effect once, one compound,
    /// one vocabulary + outside, four outside effects (a tribological, a
    /// mechanical, a sensor fault and static friction aging, which only free
    /// run sees), two structural faults (damping on the rotor speed, a
    /// channel delay) and one structural fault with a vocabulary effect.
    pub fn ci() -> Battery {
        Battery::ci_seeded(BATTERY_SEED)
    }

    /// [`Battery::ci`] with its case seeds starting at `seed`.
    pub fn ci_seeded(seed: u64) -> Battery {
        let sizes = Sizes {
            nulls: 3,
            stick_slip_nulls: 1,
            singles_per_effect: 1,
            compound_seeds: 0,
            vocabulary_plus_outside: 0,
            outside_seeds: 1,
            structural_seeds: 1,
            structural_plus_vocabulary: 0,
            ladder_seeds: 0,
        };
        let mut b = Battery::build(
            "ci",
            Protocol::small(),
            sizes,
            seed,
            &[ids::BRAKE_FADE, ids::COUPLING_BACKLASH, ids::ENCODER_MISSING_TICKS, ids::STATIC_FRICTION_AGING],
            &[ids::DAMPING_ROTOR_ABSOLUTE, ids::CHANNEL_DELAY],
        );
        let max_rpm = max_rpm(&b.protocol);
        let seed = seed + 20_000;
        let proto = b.protocol.clone();
        b.cases.push(compound(
            "compound-normal_force_modulation+viscous_brake_friction-0",
            Group::Compound,
            seed,
            [ids::NORMAL_FORCE_MODULATION, ids::VISCOUS_BRAKE_FRICTION],
            max_rpm,
            &proto,
        ));
        b.cases.push(compound(
            "mixed-angle_periodic_friction+brake_fade-0",
            Group::VocabularyPlusOutside,
            seed + 1,
            [ids::ANGLE_PERIODIC_FRICTION, ids::BRAKE_FADE],
            max_rpm,
            &proto,
        ));
        b.cases.push(compound(
            "structural-viscous_brake_friction+damping_rotor_absolute-0",
            Group::StructuralPlusVocabulary,
            seed + 2,
            [ids::VISCOUS_BRAKE_FRICTION, ids::DAMPING_ROTOR_ABSOLUTE],
            max_rpm,
            &proto,
        ));
        b.cases.sort_by(|a, b| a.group.cmp(&b.group).then(a.id.cmp(&b.id)));
        b
    }

    /// Four cases of [`Battery::ci_seeded`] (a null, a vocabulary effect, an
    /// outside effect and a structural fault) under [`Protocol::small`]: the
    /// battery the shard tests run through the real diagnosis in seconds.
    pub fn smoke_seeded(seed: u64) -> Battery {
        let mut b = Battery::ci_seeded(seed);
        let keep = [
            "null-00",
            "single-normal_force_modulation-0",
            "outside-coupling_backlash-0",
            "structural-channel_delay-0",
        ];
        b.cases.retain(|c| keep.contains(&c.id.as_str()));
        b.name = "smoke";
        b
    }

    /// A battery of the given sizes with the listed outside effects and
    /// structural faults; case seeds are `seed + 10 000·group + index`.
    pub fn build(
        name: &'static str,
        protocol: Protocol,
        sizes: Sizes,
        seed: u64,
        outside: &[&'static str],
        structural: &[&'static str],
    ) -> Battery {
        let max_rpm = max_rpm(&protocol);
        let mut cases = Vec::new();
        for j in 0..sizes.nulls {
            let s = seed + j as u64;
            cases.push(Case {
                id: format!("null-{j:02}"),
                group: Group::Null,
                seed: s,
                truth: draw_rig(s),
                rung: None,
            });
        }
        for j in 0..sizes.stick_slip_nulls {
            let s = seed + 60_000 + j as u64;
            cases.push(Case {
                id: format!("null_stick_slip-{j:02}"),
                group: Group::NullStickSlip,
                seed: s,
                truth: base_rig(ids::NONE, s, &protocol),
                rung: None,
            });
        }
        let mut k = 0u64;
        for effect in Hidden::VOCABULARY {
            for j in 0..sizes.singles_per_effect {
                let s = seed + 10_000 + k;
                k += 1;
                let base = draw_rig(s);
                let h = draw_hidden(effect, base.mu_kinetic(), max_rpm, s);
                cases.push(Case {
                    id: format!("single-{effect}-{j}"),
                    group: Group::Single,
                    seed: s,
                    truth: base.with_hidden(vec![h]),
                    rung: None,
                });
            }
        }
        k = 0;
        for (a, ea) in Hidden::VOCABULARY.iter().enumerate() {
            for eb in &Hidden::VOCABULARY[a + 1..] {
                if *ea == ids::VELOCITY_WEAKENING_FRICTION && *eb == ids::VISCOUS_BRAKE_FRICTION {
                    continue;
                }
                for j in 0..sizes.compound_seeds {
                    let s = seed + 20_000 + k;
                    k += 1;
                    cases.push(compound(
                        &format!("compound-{ea}+{eb}-{j}"),
                        Group::Compound,
                        s,
                        [ea, eb],
                        max_rpm,
                        &protocol,
                    ));
                }
            }
        }
        for (i, out) in outside.iter().take(sizes.vocabulary_plus_outside).enumerate() {
            let ea = Hidden::VOCABULARY[i % Hidden::VOCABULARY.len()];
            let s = seed + 30_000 + i as u64;
            cases.push(compound(
                &format!("mixed-{ea}+{out}-0"),
                Group::VocabularyPlusOutside,
                s,
                [ea, out],
                max_rpm,
                &protocol,
            ));
        }
        cases.extend(alone(outside, Group::Outside, "outside", sizes.outside_seeds, seed + 40_000, &protocol));
        cases.extend(alone(
            structural,
            Group::Structural,
            "structural",
            sizes.structural_seeds,
            seed + 70_000,
            &protocol,
        ));
        k = 0;
        for (i, st) in structural.iter().enumerate() {
            for j in 0..sizes.structural_plus_vocabulary.min(Hidden::VOCABULARY.len()) {
                // Each fault with a different pair of effects (i + 2j mod 5).
                let ea = Hidden::VOCABULARY[(i + 2 * j) % Hidden::VOCABULARY.len()];
                let s = seed + 80_000 + k;
                k += 1;
                cases.push(compound(
                    &format!("structural-{ea}+{st}-0"),
                    Group::StructuralPlusVocabulary,
                    s,
                    [ea, st],
                    max_rpm,
                    &protocol,
                ));
            }
        }
        k = 0;
        for effect in Hidden::VOCABULARY {
            let (size_name, sizes_of) = ladder(effect);
            for (step, &size) in sizes_of.iter().enumerate() {
                for j in 0..sizes.ladder_seeds {
                    let s = seed + 50_000 + k;
                    k += 1;
                    let base = draw_rig(s);
                    let h = ladder_hidden(effect, size, &base, max_rpm, s);
                    cases.push(Case {
                        id: format!("ladder-{effect}-{step}-{j}"),
                        group: Group::Ladder,
                        seed: s,
                        truth: base.with_hidden(vec![h]),
                        rung: Some(Rung { effect, step, size_name, size }),
                    });
                }
            }
        }
        Battery { name, seed, protocol, cases }
    }

    /// The battery `name` (`smoke`, `ci` or `full`) with its case seeds starting at `seed`.
    pub fn named(name: &str, seed: u64) -> Option<Battery> {
        match name {
            "smoke" => Some(Battery::smoke_seeded(seed)),
            "ci" => Some(Battery::ci_seeded(seed)),
            "full" => Some(Battery::full_seeded(seed)),
            _ => None,
        }
    }

    /// Generates each campaign in memory and diagnoses it with `diagnose`,
    /// the cases in parallel (rayon) and the outcomes in the battery's order;
    /// a generation error is a wrong answer with its text.
    pub fn run(&self, diagnose: impl Fn(&Case, &Campaign) -> Result<DiagnosisResult, String> + Sync) -> Vec<Outcome> {
        self.run_indices(0..self.cases.len(), diagnose).into_iter().map(|(_, o)| o).collect()
    }

    /// As [`Battery::run`] for the cases at `indices` only (a shard), each with its index.
    pub fn run_indices(
        &self,
        indices: impl IntoIterator<Item = usize>,
        diagnose: impl Fn(&Case, &Campaign) -> Result<DiagnosisResult, String> + Sync,
    ) -> Vec<(usize, Outcome)> {
        use rayon::prelude::*;
        let indices: Vec<usize> = indices.into_iter().filter(|&k| k < self.cases.len()).collect();
        indices
            .into_par_iter()
            .map(|k| {
                let case = &self.cases[k];
                let result = case.generate(&self.protocol).map_err(|e| e.to_string()).and_then(|c| diagnose(case, &c));
                (k, Outcome::new(case.clone(), result))
            })
            .collect()
    }

    /// The case indices of shard `index` of `count` (1 ≤ index ≤ count):
    /// interleaved, case k in shard k mod count + 1. The battery is in group
    /// order with its costly groups together (the ladders, 600 of the full
    /// battery's 737 cases, at its end; an angle-periodic rung costs four
    /// nulls), so contiguous shards would differ in cost several-fold; an
    /// interleaved shard samples every group in proportion and a job array's
    /// tasks end together. The shards together cover every case once.
    pub fn shard_indices(&self, index: usize, count: usize) -> Vec<usize> {
        let count = count.max(1);
        (index.saturating_sub(1)..self.cases.len()).step_by(count).collect()
    }

    /// The diagnoses of shard `index` of `count` ([`Battery::shard_indices`])
    /// as a mergeable slice; [`merge_slices`] joins a job array's slices.
    pub fn run_slice(
        &self,
        index: usize,
        count: usize,
        diagnose: impl Fn(&Case, &Campaign) -> Result<DiagnosisResult, String> + Sync,
    ) -> BatterySlice {
        let results = self
            .run_indices(self.shard_indices(index, count), diagnose)
            .into_iter()
            .map(|(k, o)| CaseResult { index: k, id: o.case.id.clone(), result: o.result.map(ExactResult::from) })
            .collect();
        BatterySlice {
            battery: self.name.to_string(),
            seed: self.seed,
            total_cases: self.cases.len(),
            shard_index: index,
            shard_count: count,
            results,
        }
    }

    /// As [`Battery::run`] (in parallel, in order), but each campaign is written to `root/<case id>`
    /// (rig-campaign/1, read back like a user's data) and `diagnose` gets that
    /// folder. The folders are left in place.
    pub fn run_dirs(
        &self,
        root: &Path,
        diagnose: impl Fn(&Case, &Path) -> Result<DiagnosisResult, String> + Sync,
    ) -> Vec<Outcome> {
        use rayon::prelude::*;
        self.cases
            .par_iter()
            .map(|case| {
                let dir = root.join(&case.id);
                let result = case
                    .generate(&self.protocol)
                    .and_then(|c| write_campaign(&dir, &c))
                    .map_err(|e| e.to_string())
                    .and_then(|()| diagnose(case, &dir));
                Outcome::new(case.clone(), result)
            })
            .collect()
    }
}
