//! The battery without the diagnosis: determinism, composition, expected
//! verdicts, the judge, the interval and that every effect outside the
//! vocabulary changes the recording beyond the noise.

use rig_types::{Campaign, RunData};
use rig_virtual_rig::battery::{
    Battery, Case, DiagnosisResult, Expected, Finding, Group, LADDER_STEPS, Outcome, clopper_pearson, confusion_table,
    detection_table, false_alarm_table, judge, wrong_table,
};
use rig_virtual_rig::{Hidden, Protocol, draw_hidden, draw_rig, draw_stick_slip_rig, generate, ids, stick_slip_runs};

fn tiny() -> Protocol {
    Protocol {
        op_points: vec![(20.0, 4.0), (85.0, 10.0), (130.0, 25.0)],
        op_duration_s: 12.0,
        step_voltages_v: vec![8.0],
        step_duration_s: 6.0,
        ..Protocol::small()
    }
}

#[test]
fn batteries_are_deterministic_and_cover_every_group() {
    let full = Battery::full();
    assert_eq!(full, Battery::full(), "same seed, same campaigns");
    let ids: std::collections::BTreeSet<&str> = full.cases.iter().map(|c| c.id.as_str()).collect();
    assert_eq!(ids.len(), full.cases.len(), "case ids are unique");
    let count = |g: Group| full.cases.iter().filter(|c| c.group == g).count();
    assert!(count(Group::Null) >= 20);
    assert!(count(Group::NullStickSlip) >= 20, "free-run thresholds need >= 20 stick-slipping nulls");
    for st in Hidden::STRUCTURAL {
        let n = full.cases.iter().filter(|c| c.group == Group::Structural && c.truth.hidden.class() == st).count();
        assert!(n >= 2, "{st}: {n} seeds");
        assert!(full.cases.iter().any(
            |c| c.group == Group::StructuralPlusVocabulary && c.truth.hidden_all().iter().any(|h| h.class() == st)
        ));
    }
    for e in Hidden::VOCABULARY {
        assert!(full.cases.iter().any(|c| c.group == Group::Single && c.expected_verdict() == e), "{e}");
        let ladder: Vec<f64> = full
            .cases
            .iter()
            .filter_map(|c| c.rung.as_ref().filter(|r| r.effect == e && c.id.ends_with("-0")).map(|r| r.size))
            .collect();
        assert_eq!(ladder.len(), LADDER_STEPS, "{e}");
        for step in 0..LADDER_STEPS {
            let draws =
                full.cases.iter().filter(|c| c.rung.as_ref().is_some_and(|r| r.effect == e && r.step == step)).count();
            assert!(draws >= 20, "{e} rung {step}: {draws} draws");
        }
        // Every rung's truth carries its size.
        for c in full.cases.iter().filter(|c| c.rung.as_ref().is_some_and(|r| r.effect == e)) {
            assert_eq!(c.truth.hidden.id(), e);
        }
    }
    // Every pair of vocabulary effects except the two friction laws.
    let pairs: std::collections::BTreeSet<String> =
        full.cases.iter().filter(|c| c.group == Group::Compound).map(|c| c.expected_verdict()).collect();
    assert_eq!(pairs.len(), 9, "{pairs:?}");
    for o in Hidden::OUTSIDE {
        let n = full.cases.iter().filter(|c| c.group == Group::Outside && c.truth.hidden.class() == o).count();
        assert!(n >= 2, "{o}: {n} seeds");
        assert!(full.cases.iter().any(|c| c.group == Group::VocabularyPlusOutside
            && c.truth.hidden_all().iter().any(|h| h.class() == o)));
    }
    // Null draws differ from each other (±8 % rig draws).
    let nulls: Vec<&Case> = full.cases.iter().filter(|c| c.group == Group::Null).collect();
    assert_ne!(nulls[0].truth.params, nulls[1].truth.params);
    let ci = Battery::ci();
    assert_eq!(ci, Battery::ci());
    assert_ne!(Battery::ci_seeded(1).cases[0].truth, ci.cases[0].truth, "another seed, other rigs");
    assert_eq!(Battery::full_seeded(rig_virtual_rig::battery::BATTERY_SEED), full);
    assert!((15..=20).contains(&ci.cases.len()), "{}", ci.cases.len());
    for g in [
        Group::Null,
        Group::NullStickSlip,
        Group::Single,
        Group::Compound,
        Group::VocabularyPlusOutside,
        Group::Outside,
        Group::Structural,
        Group::StructuralPlusVocabulary,
    ] {
        assert!(ci.cases.iter().any(|c| c.group == g), "{g:?}");
    }
    // The ci subset's generated campaign is the same twice (tiny protocol to stay fast).
    let c = &ci.cases[0];
    assert_eq!(c.generate(&tiny()).unwrap(), c.generate(&tiny()).unwrap());
    assert!(!c.generate(&tiny()).unwrap().description.contains("none"), "the description does not leak the truth");
}

#[test]
fn expected_verdicts_follow_the_groups() {
    for c in &Battery::full().cases {
        let v = c.expected_verdict();
        match c.group {
            Group::Null | Group::NullStickSlip => assert_eq!((v.as_str(), c.expected()), ("none", Expected::None)),
            Group::Single | Group::Ladder => {
                assert!(Hidden::VOCABULARY.contains(&v.as_str()), "{}: {v}", c.id);
                assert_eq!(c.truth.hidden_all().len(), 1);
            }
            Group::Compound => {
                let parts: Vec<&str> = v.split('+').collect();
                assert_eq!(parts.len(), 2, "{v}");
                assert!(parts.iter().all(|p| Hidden::VOCABULARY.contains(p)));
                assert!(c.truth_class().contains('+'));
            }
            Group::VocabularyPlusOutside => {
                assert_eq!(v, "unexplained");
                let Expected::Unexplained { partial } = c.expected() else { panic!("{}", c.id) };
                assert_eq!(partial.len(), 1);
                assert!(c.truth_class().contains("+outside:"), "{}", c.truth_class());
            }
            Group::Outside => {
                assert_eq!(v, "unexplained");
                assert_eq!(c.expected(), Expected::Unexplained { partial: vec![] });
                assert!(c.truth_class().starts_with("outside:"));
            }
            Group::Structural => {
                let id = c.truth.hidden.structural_id().expect("a structural fault");
                assert_eq!(c.expected(), Expected::Structural { id, partial: vec![] });
                assert_eq!(v, format!("{id}/unexplained"));
                assert!(c.truth_class().starts_with("structural:"));
            }
            Group::StructuralPlusVocabulary => {
                let Expected::Structural { partial, .. } = c.expected() else { panic!("{}", c.id) };
                assert_eq!(partial.len(), 1);
                assert!(c.truth_class().contains("+structural:"), "{}", c.truth_class());
            }
        }
    }
}

fn finding(effect: &str, params: &[(&str, f64)]) -> Finding {
    Finding { effect: effect.into(), params: params.iter().map(|(k, v)| (k.to_string(), *v)).collect() }
}

fn answer(verdict: &str, findings: Vec<Finding>) -> Result<DiagnosisResult, String> {
    Ok(DiagnosisResult { verdict: verdict.into(), findings, structure: None })
}

#[test]
fn judge_checks_verdict_every_effect_and_its_parameters() {
    let full = Battery::full();
    let find = |id: &str| full.cases.iter().find(|c| c.id == id).unwrap().clone();
    let null = find("null-00");
    assert!(judge(&null, &answer("none", vec![])).right);
    assert!(!judge(&null, &answer(ids::VISCOUS_BRAKE_FRICTION, vec![])).right);
    assert!(!judge(&null, &Err("boom".into())).right);

    let single = find("single-normal_force_modulation-0");
    let Hidden::NormalForceModulation { amplitude_ratio: a, frequency_hz: f } = single.truth.hidden else { panic!() };
    let nfm = |a, f| finding(ids::NORMAL_FORCE_MODULATION, &[("amplitude_ratio", a), ("frequency_hz", f)]);
    assert!(judge(&single, &answer(ids::NORMAL_FORCE_MODULATION, vec![nfm(a * 1.2, f * 1.04)])).right);
    let j = judge(&single, &answer(ids::NORMAL_FORCE_MODULATION, vec![nfm(a * 1.3, f)]));
    assert!(!j.right && j.reason.contains("amplitude_ratio"), "{}", j.reason);
    assert!(!judge(&single, &answer(ids::NORMAL_FORCE_MODULATION, vec![nfm(a, f * 1.06)])).right, "frequency 5 %");
    let spurious = answer(ids::NORMAL_FORCE_MODULATION, vec![nfm(a, f), finding(ids::DRIVE_VOLTAGE_LIMIT, &[])]);
    assert!(!judge(&single, &spurious).right);

    let comp = full.cases.iter().find(|c| c.group == Group::Compound).unwrap();
    let all: Vec<Finding> = comp
        .truth
        .hidden_all()
        .iter()
        .map(|h| Finding {
            effect: h.id().into(),
            params: h.params().into_iter().map(|(k, v)| (k.into(), v)).collect(),
        })
        .collect();
    let second = all[1].effect.clone();
    assert!(judge(comp, &answer(&second, all.clone())).right, "either effect may be the verdict");
    assert!(!judge(comp, &answer(&second, all[1..].to_vec())).right, "both must be found");

    let mixed = full.cases.iter().find(|c| c.group == Group::VocabularyPlusOutside).unwrap();
    let vocab = mixed.truth.hidden_all().into_iter().find(|h| !h.is_outside()).unwrap();
    let partial =
        Finding { effect: vocab.id().into(), params: vocab.params().into_iter().map(|(k, v)| (k.into(), v)).collect() };
    let unexplained = finding("unexplained", &[]);
    assert!(judge(mixed, &answer("unexplained", vec![partial.clone(), unexplained.clone()])).right);
    assert!(!judge(mixed, &answer(vocab.id(), vec![partial])).right, "naming only the vocabulary effect is wrong");
    let outside = full.cases.iter().find(|c| c.group == Group::Outside).unwrap();
    assert!(judge(outside, &answer("unexplained", vec![unexplained.clone()])).right);
    assert!(!judge(outside, &answer("none", vec![])).right);

    // A structural fault: `unexplained`, or its structure named; not `none`, not another structure.
    let st = find("structural-damping_rotor_absolute-0");
    assert!(judge(&st, &answer("unexplained", vec![unexplained.clone()])).right);
    assert!(judge(&st, &answer(ids::DAMPING_ROTOR_ABSOLUTE, vec![finding(ids::DAMPING_ROTOR_ABSOLUTE, &[])])).right);
    assert!(!judge(&st, &answer("none", vec![])).right);
    assert!(!judge(&st, &answer(ids::CHANNEL_DELAY, vec![finding(ids::CHANNEL_DELAY, &[])])).right);
    let j = judge(&st, &answer(ids::VISCOUS_BRAKE_FRICTION, vec![finding(ids::VISCOUS_BRAKE_FRICTION, &[])]));
    assert!(!j.right && j.reason.contains("spurious"), "a vocabulary effect compensating a structure: {}", j.reason);
    // With a vocabulary effect: that effect found, and the structure named or `unexplained`.
    let sv = full.cases.iter().find(|c| c.group == Group::StructuralPlusVocabulary).unwrap();
    let vocab = sv.truth.hidden_all().into_iter().find(|h| !h.is_outside()).unwrap();
    let Expected::Structural { id, .. } = sv.expected() else { panic!() };
    let found =
        Finding { effect: vocab.id().into(), params: vocab.params().into_iter().map(|(k, v)| (k.into(), v)).collect() };
    assert!(judge(sv, &answer("unexplained", vec![found.clone(), unexplained])).right);
    assert!(judge(sv, &answer(vocab.id(), vec![found.clone(), finding(id, &[])])).right);
    assert!(!judge(sv, &answer(vocab.id(), vec![found])).right, "the structure unnamed and not `unexplained`");
}

#[test]
fn clopper_pearson_matches_closed_forms() {
    // k = 0: upper = 1 − 0.025^(1/n); k = n: lower = 0.025^(1/n).
    let (lo, hi) = clopper_pearson(0, 20);
    assert_eq!(lo, 0.0);
    assert!((hi - (1.0 - 0.025f64.powf(1.0 / 20.0))).abs() < 1e-9, "{hi}");
    let (lo, hi) = clopper_pearson(20, 20);
    assert!((lo - 0.025f64.powf(1.0 / 20.0)).abs() < 1e-9 && hi == 1.0);
    // 1 of 20: the textbook interval (0.0013, 0.2487).
    let (lo, hi) = clopper_pearson(1, 20);
    assert!((lo - 0.00127).abs() < 1e-4 && (hi - 0.24873).abs() < 1e-4, "{lo} {hi}");
}

#[test]
fn tables_count_what_they_should() {
    let b = Battery::full();
    // A fake diagnosis: always `none`.
    let outcomes: Vec<Outcome> = b.cases.iter().map(|c| Outcome::new(c.clone(), answer("none", vec![]))).collect();
    let fa = false_alarm_table(&outcomes);
    let row = |g: &str, n: &str| vec![g.to_string(), n.to_string(), "0".to_string(), "0.000".to_string()];
    assert_eq!(fa.rows.len(), 3);
    assert_eq!(fa.rows[0][..4], row("null", "20"));
    assert_eq!(fa.rows[1][..4], row("null_stick_slip", "20"));
    assert_eq!(fa.rows[2][..4], row("all", "40"));
    let cm = confusion_table(&outcomes);
    let none_row = cm.rows.iter().find(|r| r[0] == "none").unwrap();
    assert_eq!(none_row[cm.columns.iter().position(|c| c == "right").unwrap()], "20");
    assert!(cm.rows.iter().all(|r| !r[0].starts_with("ladder")));
    let det = detection_table(&outcomes);
    assert_eq!(det.rows.len(), 5 * LADDER_STEPS);
    assert!(det.rows.iter().all(|r| r[6] == "0" && r[4] == "20"));
    assert_eq!(
        wrong_table(&outcomes).rows.len(),
        b.cases.iter().filter(|c| !matches!(c.group, Group::Null | Group::NullStickSlip)).count()
    );
    let md = rig_virtual_rig::battery::report_markdown(&b, &outcomes);
    assert!(md.contains("| null | 20 | 0 | 0.000 | 0.000 | 0.168 |"), "{md}");
    assert!(md.contains("| all | 40 | 0 | 0.000 | 0.000 | 0.088 |"), "{md}");
}

/// Largest change between two recordings of the same protocol, per channel
/// kind, on 1 s block means (so the sensor noise averages out): encoder
/// ticks, force-sensor mV, drive volts.
fn change(a: &Campaign, b: &Campaign) -> (f64, f64, f64) {
    let block = 500;
    let d = |x: &[f64], y: &[f64]| -> f64 {
        x.chunks(block)
            .zip(y.chunks(block))
            .map(|(p, q)| (p.iter().sum::<f64>() - q.iter().sum::<f64>()).abs() / p.len() as f64)
            .fold(0.0, f64::max)
    };
    let f = |v: &Option<Vec<i64>>| v.as_ref().map(|v| v.iter().map(|&x| x as f64).collect::<Vec<_>>());
    let (mut ticks, mut mv, mut volts) = (0.0f64, 0.0f64, 0.0f64);
    for (ra, rb) in a.runs.iter().zip(&b.runs) {
        let (x, y): (&RunData, &RunData) = (&ra.data, &rb.data);
        for (p, q) in [(f(&x.motor_ticks), f(&y.motor_ticks)), (f(&x.rotor_ticks), f(&y.rotor_ticks))] {
            if let (Some(p), Some(q)) = (p, q) {
                ticks = ticks.max(d(&p, &q));
            }
        }
        if let (Some(p), Some(q)) = (&x.brake_force_mv, &y.brake_force_mv) {
            mv = mv.max(d(p, q));
        }
        if let (Some(p), Some(q)) = (&x.motor_voltage_v, &y.motor_voltage_v) {
            volts = volts.max(d(p, q));
        }
    }
    (ticks, mv, volts)
}

#[test]
fn every_outside_effect_changes_the_recording_beyond_noise() {
    let proto = tiny();
    let seed = 424_242;
    let base = draw_rig(seed);
    let plain = generate("plain", &base, &proto, seed).unwrap();
    // The same rig and noise seed twice: nothing changes (the measure's zero).
    let again = generate("plain", &base, &proto, seed).unwrap();
    assert_eq!(change(&plain, &again), (0.0, 0.0, 0.0));
    let mut report = Vec::new();
    for class in Hidden::OUTSIDE {
        let h = draw_hidden(class, base.mu_kinetic(), 130.0, seed);
        assert_eq!(h.class(), class);
        let truth = base.clone().with_hidden(vec![h]);
        let c = generate(class, &truth, &proto, seed).unwrap();
        let (ticks, mv, volts) = change(&plain, &c);
        report.push(format!("{class}: {ticks:.1} ticks, {mv:.2} mV, {volts:.3} V"));
        // Beyond noise: 1 s means of the noise differ by < 0.5 mV and < 0.01 V
        // (σ ≤ 3 mV and 0.04 V over 500 samples); ticks carry no noise but the
        // twist runs' sub-tick wander.
        assert!(ticks >= 10.0 || mv >= 3.0 || volts >= 0.05, "{class} changes nothing measurable: {report:?}");
    }
    println!("{}", report.join("\n"));
}

/// Static friction aging and every structural fault change the recording of
/// a stick-slipping rig beyond the noise (small protocol: the stick-slip
/// draw needs its slow, loaded points).
#[test]
fn every_new_fault_changes_a_stick_slipping_recording_beyond_noise() {
    let proto = Protocol::small();
    let seed = 424_243;
    let base = draw_stick_slip_rig(seed, &proto).expect("a stick-slipping rig");
    let plain = generate("plain", &base, &proto, seed).unwrap();
    let mut report = Vec::new();
    for class in Hidden::STRUCTURAL.into_iter().chain([ids::STATIC_FRICTION_AGING]) {
        let h = draw_hidden(class, base.mu_kinetic(), 130.0, seed);
        assert_eq!(h.class(), class);
        let truth = base.clone().with_hidden(vec![h]);
        let c = generate(class, &truth, &proto, seed).unwrap();
        let (ticks, mv, volts) = change(&plain, &c);
        // Sensor dynamics ring at a few Hz and average out of 1 s means: the
        // encoders carry no noise, so their largest sample difference counts too.
        let sample_ticks = plain
            .runs
            .iter()
            .zip(&c.runs)
            .filter_map(|(a, b)| Some(a.data.rotor_ticks.as_ref()?.iter().zip(b.data.rotor_ticks.as_ref()?)))
            .flatten()
            .map(|(a, b)| (a - b).abs())
            .max()
            .unwrap_or(0);
        report.push(format!("{class}: {ticks:.1} ticks ({sample_ticks} per sample), {mv:.2} mV, {volts:.3} V"));
        assert!(
            ticks >= 10.0 || sample_ticks >= 10 || mv >= 3.0 || volts >= 0.05,
            "{class} changes nothing measurable: {report:?}"
        );
    }
    println!("{}", report.join("\n"));
}

/// The stick-slipping nulls do stick-slip: every one of the full battery's
/// has at least 3 operating points whose truth sticks repeatedly, and
/// fewer than all (steady sliding stays in the campaign).
#[test]
fn stick_slipping_nulls_stick_slip() {
    let full = Battery::full();
    let mut counts = Vec::new();
    for c in full.cases.iter().filter(|c| c.group == Group::NullStickSlip) {
        assert!(c.truth.hidden_all().is_empty());
        let runs = stick_slip_runs(&c.truth, &full.protocol).unwrap();
        let n = runs.iter().filter(|s| s.is_stick_slip()).count();
        assert!(n >= 3 && n < runs.len(), "{}: {n} of {} runs stick-slip", c.id, runs.len());
        counts.push(n);
    }
    assert_eq!(counts.len(), 20);
    // The plain nulls do not (issue 25: "today's nulls never stick-slip").
    let plain = full.cases.iter().find(|c| c.group == Group::Null).unwrap();
    let n = stick_slip_runs(&plain.truth, &full.protocol).unwrap().iter().filter(|s| s.is_stick_slip()).count();
    println!("stick-slipping runs per null: {counts:?}; a plain null: {n}");
}

/// The virtual rig's vocabulary (the confusion matrix's rows) is the
/// diagnosis' registry, in its order, every effect once: each id is the
/// effect file's own constant (`ids.rs` re-exports them), and no effect of
/// the registry is missing from the table.
#[test]
fn vocabulary_ids_are_the_diagnosis_ids() {
    let theirs: Vec<&str> = rig_diagnose::effects::REGISTRY.iter().map(|e| e.id()).collect();
    assert_eq!(theirs, ids::VOCABULARY.to_vec());
    // No id of the virtual rig is used twice.
    let mut all: Vec<&str> = [ids::NONE, ids::UNEXPLAINED].into_iter().chain(ids::VOCABULARY).collect();
    all.extend(ids::OUTSIDE);
    all.extend(ids::STRUCTURAL);
    let n = all.len();
    all.sort_unstable();
    all.dedup();
    assert_eq!(all.len(), n);
}

/// Every campaign of the full battery with an effect outside the vocabulary
/// or a compound simulates under the full protocol (no integrator failure).
/// Minutes in a debug build: `cargo test -p rig-virtual-rig --test battery -- --ignored`.
#[test]
#[ignore]
fn every_full_battery_campaign_with_new_physics_generates() {
    let b = Battery::full();
    let cases: Vec<&Case> = b.cases.iter().filter(|c| !matches!(c.group, Group::Null | Group::Ladder)).collect();
    let failures: Vec<String> =
        cases.iter().filter_map(|c| c.generate(&b.protocol).err().map(|e| format!("{}: {e}", c.id))).collect();
    assert!(failures.is_empty(), "{failures:#?}");
}

/// An oracle that answers from the truth is judged right on every case, through
/// both runners (in memory, and written folders read back by the closure).
#[test]
fn runners_hand_each_campaign_to_the_diagnosis_and_judge_it() {
    let mut b = Battery::ci();
    b.protocol = tiny();
    assert_eq!(Battery::full().cases.len(), 737);
    let oracle = |case: &Case| {
        let mut findings: Vec<Finding> = case
            .truth
            .hidden_all()
            .iter()
            .filter(|h| !h.is_outside())
            .map(|h| Finding {
                effect: h.id().into(),
                params: h.params().into_iter().map(|(k, v)| (k.into(), v)).collect(),
            })
            .collect();
        let verdict = match case.expected() {
            Expected::None => "none".to_string(),
            Expected::Effects(e) => e[0].to_string(),
            Expected::Unexplained { .. } => "unexplained".to_string(),
            Expected::Structural { id, .. } => {
                findings.insert(0, Finding { effect: id.into(), params: Default::default() });
                id.to_string()
            }
        };
        Ok(DiagnosisResult { verdict, findings, structure: None })
    };
    let out = b.run(|case, campaign| {
        assert_eq!(campaign.name, case.id);
        assert_eq!(campaign.runs.len(), 5 + 5 + 1 + 3);
        oracle(case)
    });
    assert_eq!(out.len(), b.cases.len());
    assert!(out.iter().all(|o| o.judgement.right), "{:?}", wrong_table(&out).rows);
    let root = tempfile::tempdir().unwrap();
    let out_dirs = b.run_dirs(root.path(), |case, dir| {
        assert!(dir.join("campaign.toml").is_file() && dir.ends_with(&case.id));
        oracle(case)
    });
    assert_eq!(out, out_dirs);
    // A diagnosis that fails is a wrong answer carrying its error.
    let failing = b.run(|_, _| Err("no".into()));
    assert!(failing.iter().all(|o| !o.judgement.right && o.verdict() == "error"));
}

/// Down each detection ladder the effect's mark on the recording shrinks:
/// the change against the same rig without it is larger on the first rung
/// than on the last (force mV for the friction effects, drive volts for the
/// voltage limit).
#[test]
fn ladders_shrink_the_effect_towards_the_noise() {
    let full = Battery::full();
    let proto = tiny();
    for effect in Hidden::VOCABULARY {
        let mark = |step: usize| {
            let case = full
                .cases
                .iter()
                .find(|c| c.rung.as_ref().is_some_and(|r| r.effect == effect && r.step == step))
                .unwrap();
            let with = generate("with", &case.truth, &proto, case.seed).unwrap();
            let without = generate("with", &draw_rig(case.seed), &proto, case.seed).unwrap();
            let (ticks, mv, volts) = change(&with, &without);
            if effect == ids::DRIVE_VOLTAGE_LIMIT { volts + ticks } else { mv }
        };
        let (first, last) = (mark(0), mark(LADDER_STEPS - 1));
        assert!(first > 2.0 * last && first > 1.0, "{effect}: first rung {first}, last {last}");
    }
}

/// The damping placements the judge reads from diagnosis.json's `structure`
/// are ids of the diagnosis' structure registry.
#[test]
fn damping_placements_are_the_diagnosis_structure_ids() {
    let theirs: Vec<&str> = rig_diagnose::structure::REGISTRY.iter().map(|c| c.id()).collect();
    assert_eq!(theirs.first(), Some(&ids::DAMPING_TWIST_RATE), "{theirs:?}");
    for fault in ids::STRUCTURAL {
        for p in ids::damping_placements(fault) {
            assert!(theirs.contains(p), "{fault} -> {p} not in {theirs:?}");
        }
    }
    // The judge accepts the placement named in `structure`, and flags one the truth lacks.
    let null = Battery::ci().cases.into_iter().find(|c| c.expected() == Expected::None).expect("a null case");
    let with = |damping: &str| {
        Ok(DiagnosisResult {
            verdict: ids::NONE.into(),
            findings: vec![],
            structure: Some(rig_virtual_rig::battery::StructureAnswer { damping: damping.into() }),
        })
    };
    assert!(judge(&null, &with(ids::DAMPING_TWIST_RATE)).right);
    assert!(!judge(&null, &with(ids::DAMPING_ROTOR_ABSOLUTE_PLACEMENT)).right);
    assert!(!judge(&null, &with(ids::DAMPING_BOTH_PLACEMENT)).right);
    // A drag on the rotor speed is named by either placement that carries it
    // (its truth keeps a small twist-rate damping beside the drag), with the
    // structural finding as the verdict; `none` with it is not right.
    let drag = Battery::ci()
        .cases
        .into_iter()
        .find(|c| c.id.starts_with("structural-damping_rotor_absolute"))
        .expect("a damping case");
    let answer = |verdict: &str, damping: &str| {
        Ok(DiagnosisResult {
            verdict: verdict.into(),
            findings: vec![rig_virtual_rig::battery::Finding {
                effect: ids::DAMPING_ROTOR_ABSOLUTE.into(),
                params: Default::default(),
            }],
            structure: Some(rig_virtual_rig::battery::StructureAnswer { damping: damping.into() }),
        })
    };
    for p in [ids::DAMPING_ROTOR_ABSOLUTE_PLACEMENT, ids::DAMPING_BOTH_PLACEMENT] {
        assert!(judge(&drag, &answer(ids::DAMPING_ROTOR_ABSOLUTE, p)).right, "{p}");
        assert!(!judge(&drag, &answer(ids::NONE, p)).right, "{p}");
    }
}
