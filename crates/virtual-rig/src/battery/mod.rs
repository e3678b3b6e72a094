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

use crate::{
    Hidden, Protocol, Truth, VirtualRigError, draw_hidden, draw_rig, draw_stick_slip_rig, generate, ids, write_campaign,
};
use rig_types::{Campaign, fmt_fixed};
use std::collections::BTreeMap;
use std::path::Path;

mod render;
pub use render::{
    battery_outputs, clopper_pearson, confusion_table, detection_sheet, detection_table, false_alarm_table,
    markdown_table, report_markdown, wrong_table,
};

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

/// One shard's diagnoses of a battery: enough to rebuild the battery
/// ([`Battery::named`]) and judge every case again after a merge.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct BatterySlice {
    pub battery: String,
    pub seed: u64,
    pub total_cases: usize,
    pub shard_index: usize,
    pub shard_count: usize,
    pub results: Vec<CaseResult>,
}

/// The diagnosis of the case at `index` (its id, to check the rebuilt battery).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct CaseResult {
    pub index: usize,
    pub id: String,
    pub result: Result<ExactResult, String>,
}

/// A [`DiagnosisResult`] whose parameters are stored as their f64 bit
/// patterns, so a slice read back gives the very same numbers (JSON's
/// decimal text need not round-trip every f64 in serde_json's default parser).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct ExactResult {
    pub verdict: String,
    pub findings: Vec<(String, BTreeMap<String, u64>)>,
    #[serde(default)]
    pub structure: Option<String>,
}

impl From<DiagnosisResult> for ExactResult {
    fn from(d: DiagnosisResult) -> Self {
        let findings = d
            .findings
            .into_iter()
            .map(|f| (f.effect, f.params.into_iter().map(|(k, v)| (k, v.to_bits())).collect()))
            .collect();
        ExactResult { verdict: d.verdict, findings, structure: d.structure.map(|s| s.damping) }
    }
}

impl From<ExactResult> for DiagnosisResult {
    fn from(e: ExactResult) -> Self {
        let findings = e
            .findings
            .into_iter()
            .map(|(effect, p)| Finding { effect, params: p.into_iter().map(|(k, v)| (k, f64::from_bits(v))).collect() })
            .collect();
        DiagnosisResult {
            verdict: e.verdict,
            findings,
            structure: e.structure.map(|damping| StructureAnswer { damping }),
        }
    }
}

/// Joins the slices of one battery's job array: the battery rebuilt from
/// its name and seed, and every case's outcome judged again, in the
/// battery's order. Refuses slices of different batteries, a case id that is
/// not the rebuilt battery's, and a set that misses or repeats a case.
pub fn merge_slices(slices: Vec<BatterySlice>) -> Result<(Battery, Vec<Outcome>), String> {
    let first = slices.first().ok_or("no battery slice to merge")?;
    let (name, seed, total) = (first.battery.clone(), first.seed, first.total_cases);
    if slices.iter().any(|s| s.battery != name || s.seed != seed || s.total_cases != total) {
        return Err("slices come from different batteries (name, seed or size differ)".into());
    }
    let battery = Battery::named(&name, seed).ok_or_else(|| format!("unknown battery {name:?}"))?;
    if battery.cases.len() != total {
        return Err(format!("battery {name} has {} cases, the slices {total}", battery.cases.len()));
    }
    let mut results: Vec<CaseResult> = slices.into_iter().flat_map(|s| s.results).collect();
    results.sort_by_key(|r| r.index);
    if results.len() != total || results.iter().enumerate().any(|(k, r)| r.index != k) {
        return Err("slices must cover every case exactly once (missing or duplicate shard)".into());
    }
    let mut outcomes = Vec::with_capacity(total);
    for (r, case) in results.into_iter().zip(&battery.cases) {
        if r.id != case.id {
            return Err(format!("case {} of the slices is {}, the battery's is {}", r.index, r.id, case.id));
        }
        outcomes.push(Outcome::new(case.clone(), r.result.map(DiagnosisResult::from)));
    }
    Ok((battery, outcomes))
}

fn max_rpm(p: &Protocol) -> f64 {
    p.op_points.iter().map(|x| x.0).fold(0.0, f64::max)
}

/// The effect-free rig a case with `class` hidden is built on: a rig that
/// stick-slips ([`draw_stick_slip_rig`]) for the stick-slipping nulls, for
/// static friction aging (only a stick shows it) and for the structural
/// faults (their free-run signature is in the stick-slip cycle), else
/// [`draw_rig`]'s.
fn base_rig(class: &str, seed: u64, protocol: &Protocol) -> Truth {
    if class == ids::NONE || class == ids::STATIC_FRICTION_AGING || ids::STRUCTURAL.contains(&class) {
        draw_stick_slip_rig(seed, protocol).unwrap_or_else(|| {
            panic!("no rig drawn from seed {seed} stick-slips under this protocol: it needs slow, loaded points")
        })
    } else {
        draw_rig(seed)
    }
}

/// `per` cases of each class of `classes` hidden alone, on the rig it needs
/// ([`base_rig`]), ids `<prefix>-<class>-<j>`, seeds `seed0 + k` in order.
fn alone(classes: &[&str], group: Group, prefix: &str, per: usize, seed0: u64, protocol: &Protocol) -> Vec<Case> {
    let max_rpm = max_rpm(protocol);
    let mut cases = Vec::new();
    for class in classes {
        for j in 0..per {
            let s = seed0 + cases.len() as u64;
            let base = base_rig(class, s, protocol);
            let h = draw_hidden(class, base.mu_kinetic(), max_rpm, s);
            cases.push(Case {
                id: format!("{prefix}-{class}-{j}"),
                group,
                seed: s,
                truth: base.with_hidden(vec![h]),
                rung: None,
            });
        }
    }
    cases
}

/// A case with two hidden effects, the second drawn with its own seed, on
/// the rig the second needs ([`base_rig`]).
fn compound(id: &str, group: Group, seed: u64, effects: [&str; 2], max_rpm: f64, protocol: &Protocol) -> Case {
    let base = base_rig(effects[1], seed, protocol);
    let mu_k = base.mu_kinetic();
    let a = draw_hidden(effects[0], mu_k, max_rpm, seed);
    let b = draw_hidden(effects[1], mu_k, max_rpm, seed.wrapping_add(0x5151_5151));
    Case { id: id.to_string(), group, seed, truth: base.with_hidden(vec![a, b]), rung: None }
}

/// The vocabulary effect `effect` at ladder size `size` (see [`ladder`]);
/// its other parameters (frequency, order, Stribeck speed) drawn as usual.
fn ladder_hidden(effect: &str, size: f64, base: &Truth, max_rpm: f64, seed: u64) -> Hidden {
    let mu_k = base.mu_kinetic();
    match draw_hidden(effect, mu_k, max_rpm, seed) {
        Hidden::NormalForceModulation { frequency_hz, .. } => {
            Hidden::NormalForceModulation { amplitude_ratio: size, frequency_hz }
        }
        Hidden::AnglePeriodicFriction { order, .. } => Hidden::AnglePeriodicFriction { amplitude_ratio: size, order },
        Hidden::VelocityWeakening { stribeck_speed_rad_s, .. } => {
            Hidden::VelocityWeakening { mu_static: mu_k * (1.0 + size), mu_kinetic: mu_k, stribeck_speed_rad_s }
        }
        Hidden::ViscousBrake { .. } => Hidden::ViscousBrake { mu_kinetic: mu_k, viscous_per_rad_s: mu_k * size / 10.0 },
        Hidden::DriveVoltageLimit { .. } => {
            let m = &base.truth_motor();
            let back_emf_v = rig_types::units::rpm_to_rad_s(m.0 * m.1 * max_rpm);
            Hidden::DriveVoltageLimit { limit_v: size * back_emf_v }
        }
        other => other,
    }
}

impl Truth {
    /// (k_e in V·s/rad, gear ratio n) of the drawn motor.
    fn truth_motor(&self) -> (f64, f64) {
        (self.params.motor.voltage_constant_v_s_rad, self.params.motor.gear_ratio)
    }
}

/// Relative tolerance on a recovered parameter (issue 9: 25 %, frequencies
/// 5 %, the order exact).
pub fn battery_tolerance(param: &str) -> f64 {
    match param {
        "order" => 0.0,
        "frequency_hz" => 0.05,
        _ => 0.25,
    }
}

/// Whether the answer is right, and why not.
#[derive(Debug, Clone, PartialEq)]
pub struct Judgement {
    pub right: bool,
    /// Empty when right; otherwise every reason, `; `-separated.
    pub reason: String,
}

/// Scores a diagnosis of `case`: the verdict must be the expected one (any
/// effect of a compound; for a structural fault `unexplained`, or the
/// structure named among the findings with the verdict the structure or a
/// vocabulary effect of the truth), every vocabulary effect of the truth must
/// be among the findings with every parameter within [`battery_tolerance`],
/// and nothing that is not in the truth may be found (a structural finding
/// other than the truth's structure included).
pub fn judge(case: &Case, result: &Result<DiagnosisResult, String>) -> Judgement {
    let d = match result {
        Ok(d) => d,
        Err(e) => return Judgement { right: false, reason: format!("error: {e}") },
    };
    let mut why = Vec::new();
    // The truth's structural id, which a finding may name.
    let mut structure = None;
    let (required, verdict_ok) = match case.expected() {
        Expected::None => (vec![], d.verdict == "none"),
        Expected::Effects(e) => {
            let ok = e.iter().any(|x| *x == d.verdict);
            (e, ok)
        }
        Expected::Unexplained { partial } => (partial, d.verdict == ids::UNEXPLAINED),
        Expected::Structural { id, partial } => {
            let named = d.findings.iter().any(|f| f.effect == id)
                || d.structure.as_ref().is_some_and(|s| ids::damping_placements(id).contains(&s.damping.as_str()));
            let ok =
                d.verdict == ids::UNEXPLAINED || (named && (d.verdict == id || partial.contains(&d.verdict.as_str())));
            structure = Some(id);
            (partial, ok)
        }
    };
    if !verdict_ok {
        why.push(format!("verdict `{}`, expected `{}`", d.verdict, case.expected_verdict()));
    }
    for h in case.truth.hidden_all().into_iter().filter(|h| !h.is_outside()) {
        let Some(f) = d.findings.iter().find(|f| f.effect == h.id()) else {
            why.push(format!("{} not found", h.id()));
            continue;
        };
        for (k, truth) in h.params() {
            match f.params.get(k) {
                None => why.push(format!("{}.{k} missing", h.id())),
                Some(&est) => {
                    let rel = (est - truth).abs() / truth.abs();
                    let tol = battery_tolerance(k);
                    if rel.is_nan() || rel > tol + 1e-12 {
                        why.push(format!(
                            "{}.{k} = {} vs truth {} ({:.1} % off, tolerance {:.0} %)",
                            h.id(),
                            fmt_fixed(est, 4),
                            fmt_fixed(truth, 4),
                            100.0 * rel,
                            100.0 * tol
                        ));
                    }
                }
            }
        }
    }
    // A damping placement other than the rig model's, where the truth has none, is spurious.
    if let Some(s) = &d.structure {
        let truth_placements = structure.map_or(&[][..], ids::damping_placements);
        if s.damping != ids::DAMPING_TWIST_RATE && !truth_placements.contains(&s.damping.as_str()) {
            why.push(format!("spurious structure: damping on {}", s.damping));
        }
    }
    for f in &d.findings {
        if f.effect != ids::UNEXPLAINED
            && !required.contains(&f.effect.as_str())
            && Some(f.effect.as_str()) != structure
        {
            why.push(format!("spurious finding {}", f.effect));
        }
    }
    Judgement { right: why.is_empty(), reason: why.join("; ") }
}

/// One judged case.
#[derive(Debug, Clone, PartialEq)]
pub struct Outcome {
    pub case: Case,
    pub result: Result<DiagnosisResult, String>,
    pub judgement: Judgement,
}

impl Outcome {
    pub fn new(case: Case, result: Result<DiagnosisResult, String>) -> Outcome {
        let judgement = judge(&case, &result);
        Outcome { case, result, judgement }
    }

    /// The verdict, or `error`.
    pub fn verdict(&self) -> &str {
        match &self.result {
            Ok(d) => &d.verdict,
            Err(_) => "error",
        }
    }
}
