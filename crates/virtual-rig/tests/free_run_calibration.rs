//! Calibration of the free-run checks that enter the diagnosis' adequacy test
//! (issue 25): effect-free virtual-rig campaigns whose protocol includes
//! low-speed, high-force operating points where the rig sticks and slips,
//! diagnosed blind end to end (`diagnose_campaign`: calibrate, estimate,
//! select, structure, free run). Every null must stick-slip in some runs (or
//! it calibrates nothing), and the campaign-level rate of flagged free-run
//! checks is printed with its Clopper–Pearson interval.
//!
//! And the diagnosis' structural candidates (rig_diagnose::structure) on
//! campaigns whose damping placement is known: the rig's shaft damping moved
//! from the twist rate onto the absolute rotor speed (a drag on Ω1, the
//! rotor row of Eq. 4-7's diag(C, Cm), simulated by rig-model's
//! `rotor_damping_nm_s_rad`) is named `rotor_absolute` (or the placement that
//! contains it) with a free-run gain; the rig model's own placement keeps
//! `twist_rate`.
//!
//! Slow (a blind estimate and diagnosis per campaign): `cargo nextest run
//! --workspace -E 'test(free_run_nulls)' --run-ignored all --nocapture`,
//! `NULLS` campaigns (default 24).

use rig_virtual_rig::{Protocol, draw_truth, generate};
use std::collections::BTreeMap;
use std::path::Path;

/// The blind chain with pipeline.toml's options (their one home).
fn chain() -> rig_diagnose::BlindChain {
    rig_diagnose::BlindChain::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml")
}

fn thesis() -> rig_calibrate::ThesisData {
    let t = rig_ingest::thesis::read_thesis_tables(Path::new("../../data/thesis")).expect("data/thesis");
    rig_calibrate::thesis_data(&t).expect("thesis data")
}

/// The small protocol with most points moved into the stick-slip region of
/// the severity map (low set-point, high normal force), so that every null
/// has runs that stick and slip and runs that slide steadily.
fn stick_slip_protocol() -> Protocol {
    let op = vec![
        (10.0, 10.0),
        (10.0, 25.0),
        (15.0, 10.0),
        (15.0, 25.0),
        (20.0, 25.0),
        (20.0, 13.0),
        (25.0, 18.0),
        (32.0, 25.0),
        (45.0, 10.0),
        (45.0, 25.0),
        (85.0, 10.0),
        (130.0, 25.0),
    ];
    Protocol { op_points: op, ..Protocol::small() }
}

/// An effect-free rig that sticks and slips: the virtual rig's draw with its
/// shaft damping scaled by 0.3. `draw_rig` damps the shaft at ξ = 0.06–0.12,
/// where no point of these protocols sticks and slips (seed 9100: 0 of 12
/// runs); × 0.3 gives ξ = 0.018–0.036, the shipped rig's range (its
/// estimate: C = 5.25e-3 N·m·s/rad, ξ ≈ 0.03). Still the rig model's own
/// structure (damping on the twist rate) and no effect: a null.
fn stick_slip_null(seed: u64) -> rig_virtual_rig::Truth {
    let mut truth = draw_truth("none", 130.0, seed);
    truth.params.shaft_damping_nm_s_rad *= 0.3;
    truth
}

/// Two-sided 95 % Clopper–Pearson interval of a binomial rate k/n (bisection
/// on the binomial tail sums).
fn clopper_pearson(k: usize, n: usize) -> (f64, f64) {
    let tail_le = |p: f64, k: usize| -> f64 {
        let mut s = 0.0;
        let mut term = (1.0 - p).powi(n as i32);
        for i in 0..=k {
            s += term;
            term *= (n - i) as f64 / (i + 1) as f64 * p / (1.0 - p);
        }
        s
    };
    let solve = |f: &dyn Fn(f64) -> bool| {
        let (mut lo, mut hi) = (0.0, 1.0);
        for _ in 0..60 {
            let mid = 0.5 * (lo + hi);
            if f(mid) { lo = mid } else { hi = mid }
        }
        0.5 * (lo + hi)
    };
    let lower = if k == 0 { 0.0 } else { solve(&|p| 1.0 - tail_le(p, k - 1) < 0.025) };
    let upper = if k == n { 1.0 } else { solve(&|p| tail_le(p, k) > 0.025) };
    (lower, upper)
}

#[test]
fn clopper_pearson_matches_known_values() {
    // 0 of 24: upper 1 − 0.025^(1/24) = 0.1425; 1 of 24: (0.00105, 0.2112).
    let (l, u) = clopper_pearson(0, 24);
    assert!(l == 0.0 && (u - 0.1425).abs() < 5e-4, "{l} {u}");
    let (l, u) = clopper_pearson(1, 24);
    assert!((l - 0.00105).abs() < 5e-5 && (u - 0.2112).abs() < 5e-4, "{l} {u}");
}

#[test]
#[ignore]
fn free_run_nulls() {
    let n: u64 = std::env::var("NULLS").ok().and_then(|s| s.parse().ok()).unwrap_or(24);
    let th = thesis();
    let o = chain();
    let mut by_check: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let (mut flagged, mut not_none, mut structure_moved) = (Vec::new(), Vec::new(), Vec::new());
    for seed in 0..n {
        let seed = 9100 + seed;
        let truth = stick_slip_null(seed);
        let c = generate("null-ss", &truth, &stick_slip_protocol(), seed).expect("generate");
        let d = rig_diagnose::diagnose_campaign(&c, Some(&th), &o).expect("diagnosis");
        let ss = d.detail.runs.iter().filter(|r| r.measured.stick_slip).count();
        let line: Vec<String> =
            d.detail.free_run_extended.iter().map(|k| format!("{} {:.2}", k.channel, k.ratio)).collect();
        println!(
            "seed {seed}: {ss}/{} runs stick-slip; verdict {}; structure {}; {}",
            d.detail.runs.len(),
            d.verdict,
            d.structure.damping,
            line.join(", ")
        );
        assert!(ss >= 1, "null seed {seed} never sticks and slips: it calibrates nothing");
        for k in &d.detail.free_run_extended {
            by_check.entry(k.channel.clone()).or_default().push(k.ratio);
        }
        if d.detail.free_run_extended.iter().any(|k| k.flagged) {
            flagged.push(seed);
        }
        if d.verdict != "none" {
            not_none.push((seed, d.verdict.clone()));
        }
        if d.structure.damping != "twist_rate" {
            structure_moved.push((seed, d.structure.damping.clone()));
        }
    }
    println!("free-run ratios of the final model over {n} stick-slipping nulls (min / median / 90 % / max):");
    for (k, mut r) in by_check {
        r.sort_by(f64::total_cmp);
        let q = |p: f64| r[((r.len() - 1) as f64 * p).round() as usize];
        println!("  {k:<36} {:.2} / {:.2} / {:.2} / {:.2}", q(0.0), q(0.5), q(0.9), q(1.0));
    }
    let (lo, hi) = clopper_pearson(flagged.len(), n as usize);
    println!(
        "campaigns with a flagged free-run check: {}/{n} (95 % Clopper–Pearson {lo:.3}–{hi:.3}): {flagged:?}",
        flagged.len()
    );
    println!("verdict not `none`: {not_none:?}; structure not twist_rate: {structure_moved:?}");
    assert!(flagged.len() as f64 <= 0.05 * n as f64 + 1e-9, "free-run false alarms {}/{n}", flagged.len());
}

/// The free-run checks on RIGHT models (issue 25: a right in-vocabulary
/// model must pass them): each vocabulary effect drawn on a stick-slipping
/// rig (the nulls' draw with the effect hidden), diagnosed blind; among the
/// campaigns whose findings contain the hidden effect, the rate with a
/// flagged free-run check of the final model, with its Clopper–Pearson
/// interval. `RIGHT` draws per effect (default 4: 20 campaigns).
#[test]
#[ignore]
fn free_run_right_models() {
    let n: u64 = std::env::var("RIGHT").ok().and_then(|s| s.parse().ok()).unwrap_or(4);
    let th = thesis();
    let o = chain();
    let classes = rig_virtual_rig::ids::VOCABULARY;
    // ONLY="9312,9313": those seeds, with the detail of every flagged check.
    let only: Option<Vec<u64>> =
        std::env::var("ONLY").ok().map(|v| v.split(',').filter_map(|x| x.trim().parse().ok()).collect());
    let mut by_check: BTreeMap<String, Vec<f64>> = BTreeMap::new();
    let (mut right, mut flagged, mut missed) = (0usize, Vec::new(), Vec::new());
    for (ci, class) in classes.iter().enumerate() {
        for i in 0..n {
            let seed = 9300 + 10 * ci as u64 + i;
            if only.as_ref().is_some_and(|o| !o.contains(&seed)) {
                continue;
            }
            let mut truth = draw_truth(class, 130.0, seed);
            truth.params.shaft_damping_nm_s_rad *= 0.3;
            let c = generate("right-ss", &truth, &stick_slip_protocol(), seed).expect("generate");
            let d = rig_diagnose::diagnose_campaign(&c, Some(&th), &o).expect("diagnosis");
            let found = d.findings.iter().any(|f| f.effect == *class);
            let line: Vec<String> = d
                .detail
                .free_run_extended
                .iter()
                .filter(|k| k.flagged)
                .map(|k| format!("{} {:.2}", k.channel, k.ratio))
                .collect();
            let effects: Vec<&str> = d.findings.iter().map(|f| f.effect.as_str()).collect();
            if let Some(u) = d.findings.iter().find(|f| f.effect == "unexplained") {
                println!("  unexplained: {}", u.evidence);
            }
            println!(
                "{class} seed {seed}: verdict {}; findings {effects:?}; structure {}; found {found}; flagged: {}",
                d.verdict,
                d.structure.damping,
                line.join(", ")
            );
            if only.is_some() {
                for k in d.detail.free_run_extended.iter().filter(|k| k.flagged || k.channel.ends_with("regime")) {
                    println!("  {}: {}", k.channel, k.detail);
                }
                println!("  adequacy: {:?}", d.adequacy);
                for k in &d.detail.structure_scores {
                    println!(
                        "  structure {}: balance gain {:.3} (t {:.2}), free-run gain {:.3} ± {:.3} (t {:.2}), accepted {}",
                        k.id, k.balance_gain, k.balance_t, k.relative_gain, k.relative_gain_fold_sd, k.t, k.accepted
                    );
                }
            }
            if !found {
                missed.push((seed, class.to_string(), d.verdict.clone()));
                continue;
            }
            right += 1;
            for k in &d.detail.free_run_extended {
                by_check.entry(k.channel.clone()).or_default().push(k.ratio);
            }
            if d.detail.free_run_extended.iter().any(|k| k.flagged) {
                flagged.push((seed, class.to_string()));
            }
        }
    }
    println!("free-run ratios of right final models over {right} campaigns (min / median / 90 % / max):");
    for (k, mut r) in by_check {
        r.sort_by(f64::total_cmp);
        let q = |p: f64| r[((r.len() - 1) as f64 * p).round() as usize];
        println!("  {k:<36} {:.2} / {:.2} / {:.2} / {:.2}", q(0.0), q(0.5), q(0.9), q(1.0));
    }
    let (lo, hi) = clopper_pearson(flagged.len(), right);
    println!(
        "right models with a flagged free-run check: {}/{right} (95 % Clopper–Pearson {lo:.3}–{hi:.3}): {flagged:?}",
        flagged.len()
    );
    println!("effect not found: {missed:?}");
    assert!(right > 0, "no campaign was diagnosed right");
}

/// The small protocol with two slow, heavily braked points (stick-slip).
fn structure_protocol() -> Protocol {
    let mut p = Protocol::small();
    p.op_points[0] = (10.0, 10.0);
    p.op_points[4] = (20.0, 25.0);
    p
}

#[test]
fn damping_on_the_rotor_speed_is_named_with_its_free_run_gain() {
    let mut truth = draw_truth("none", 130.0, 4242);
    let c_nm_s_rad = truth.params.shaft_damping_nm_s_rad;
    truth.params.shaft_damping_nm_s_rad = 0.0;
    truth.params.rotor_damping_nm_s_rad = c_nm_s_rad;
    let c = generate("rotor-drag", &truth, &structure_protocol(), 4242).expect("generate");
    let d = rig_diagnose::diagnose_campaign(&c, Some(&thesis()), &chain()).expect("diagnosis");
    println!("{}\n{:#?}", d.structure.notes, d.detail.structure_scores);
    assert!(
        d.structure.damping == "rotor_absolute" || d.structure.damping == "twist_rate_and_rotor",
        "structure {} ({})",
        d.structure.damping,
        d.structure.notes
    );
    let won = d.detail.structure_scores.iter().find(|s| s.accepted).expect("a winner");
    assert!(won.relative_gain >= 0.05 && won.t >= 2.0, "{won:?}");
    // The final model's free run is within its thresholds; what is left (if
    // anything) is the estimate's voltage-step fit, made in the twist-rate
    // placement, not the motion.
    let left: Vec<&str> = d.detail.free_run_extended.iter().filter(|k| k.flagged).map(|k| k.channel.as_str()).collect();
    assert!(left.is_empty(), "final model's free run flagged: {left:?}");
    assert!(d.findings.iter().all(|f| !f.where_.iter().any(|w| w == "free_run")), "{:?}", d.findings);
    // The baseline's free run misses the drag by the structure's criterion
    // (the gain above). Its adequacy checks no longer flag it: since the
    // per-run floors carry the spread of the extremes over cycles (issue 25's
    // rotor_max regression), the drag's rotor-extreme error is within them,
    // and the voltage mean that the drag moves is reported, not in the
    // adequacy test (ChannelOptions' docs). Printed, not asserted.
    for k in &d.detail.free_run_baseline {
        println!("baseline {} {:.2} (threshold {:.1})", k.channel, k.ratio, k.threshold);
    }
}

#[test]
fn the_rig_models_own_placement_keeps_twist_rate() {
    let truth = draw_truth("none", 130.0, 4243);
    let c = generate("twist-rate", &truth, &structure_protocol(), 4243).expect("generate");
    let d = rig_diagnose::diagnose_campaign(&c, Some(&thesis()), &chain()).expect("diagnosis");
    println!("{}\n{:#?}", d.structure.notes, d.detail.structure_scores);
    assert_eq!(d.structure.damping, "twist_rate", "{}", d.structure.notes);
    assert_eq!(d.verdict, "none", "{:?}", d.findings.last().map(|f| &f.evidence));
}
