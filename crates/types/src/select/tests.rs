//! The engine's tests.

use super::*;

/// Units carry a measured level; the model is a level; misfit |m − x_u| + floor.
struct Levels(Vec<f64>);

impl Study<f64> for Levels {
    fn score(&self, m: &f64, u: usize) -> f64 {
        (m - self.0[u]).abs() + 0.01
    }
}

/// Adds `shift` to the current level (fitted: the training units' mean offset when `shift` is NaN).
struct Shift(&'static str, f64);

impl Candidate<Levels, f64> for Shift {
    fn id(&self) -> &str {
        self.0
    }
    fn fit(&self, s: &Levels, cur: &f64, train: &[usize]) -> Result<f64, String> {
        if self.1.is_nan() {
            Ok(train.iter().map(|&u| s.0[u]).sum::<f64>() / train.len() as f64)
        } else if self.1.is_infinite() {
            Err("no fit".into())
        } else {
            Ok(cur + self.1)
        }
    }
    fn inadmissible(&self, _: &Levels, _: &[f64], fitted: &[f64]) -> Option<String> {
        (self.0 == "negative_forbidden" && fitted.iter().any(|m| *m < 0.0)).then(|| "level below 0".into())
    }
}

fn rule() -> SelectionRule {
    SelectionRule { min_relative_gain: 0.05, min_t: 2.0 }
}

#[test]
fn the_comparison_is_the_thesis_rigs_rule() {
    // Halving every unit's misfit: gain 0.5, every log ratio ln 2, zero spread: t infinite.
    let c = compare(&[2.0, 4.0, 6.0, 8.0], &[1.0, 2.0, 3.0, 4.0], &[0, 0, 1, 1], 2);
    assert!((c.gain - 0.5).abs() < 1e-12 && c.t.is_infinite() && c.gain_fold_sd.abs() < 1e-12, "{c:?}");
    // Overall misfit is the RMS: √((1 + 9)/2).
    assert!((overall(&[1.0, 3.0]) - 5.0_f64.sqrt()).abs() < 1e-12);
    // Mixed signs: d = ln 2, ln 0.5, ln 2 → mean ln2/3, sd 0.8004: t = 0.5.
    let c = compare(&[2.0, 1.0, 2.0], &[1.0, 2.0, 1.0], &[0, 1, 2], 3);
    assert!((c.t - 0.5).abs() < 1e-9, "{c:?}");
    assert!(!rule().admits(&c));
}

#[test]
fn selection_takes_the_best_admitted_candidate_then_stops() {
    let s = Levels(vec![1.0, 1.1, 0.9, 1.05, 0.95]);
    let fit_level = Shift("fit_level", f64::NAN);
    let useless = Shift("useless", 0.0);
    let broken = Shift("broken", f64::INFINITY);
    let cands: [&dyn Candidate<Levels, f64>; 3] = [&useless, &broken, &fit_level];
    let sel = forward_select(&s, &cands, &0.0, &Fold::leave_one_out(5), &rule()).unwrap();
    assert_eq!(sel.chosen_ids(), ["fit_level"]);
    assert_eq!(sel.train_sets.len(), 5);
    // Step 1 traces all three, step 2 the two left, and stops (no gain).
    assert_eq!(sel.step(1).count(), 3);
    assert_eq!(sel.step(2).count(), 2);
    let broken1 = sel.step(1).find(|t| t.id == "broken").unwrap();
    assert!(broken1.error.is_some() && !broken1.significant && broken1.comparison.after.is_infinite());
    assert!(sel.step(2).all(|t| !t.accepted));
    assert!(overall(&sel.final_misfits) < 0.1 * overall(&sel.baseline_misfits));
}

#[test]
fn a_shared_training_set_is_fitted_once_and_an_inadmissible_best_stops() {
    let s = Levels(vec![-1.0, -1.0, -1.1, -0.9]);
    let neg = Shift("negative_forbidden", f64::NAN);
    let folds = Fold::shared_training(&[0], &[1, 2, 3]);
    let sel = forward_select(&s, &[&neg as &dyn Candidate<Levels, f64>], &0.0, &folds, &rule()).unwrap();
    assert_eq!(sel.train_sets, vec![vec![0]]);
    let t = &sel.trials[0];
    assert_eq!(t.fitted, vec![-1.0]);
    assert!(t.significant && t.best && !t.accepted && t.inadmissible.as_deref() == Some("level below 0"));
    assert!(sel.chosen.is_empty() && sel.final_models == vec![0.0]);
}

/// A model of two switches and a level: it predicts the level only when both are on.
#[derive(Debug, Clone, Copy, PartialEq)]
struct Gate {
    a: bool,
    b: bool,
    level: f64,
}

struct Gated(Vec<f64>);

impl Study<Gate> for Gated {
    fn score(&self, m: &Gate, u: usize) -> f64 {
        let pred = if m.a && m.b { m.level } else { 0.0 };
        (pred - self.0[u]).abs() + 0.01
    }
}

/// Switches `a` (group "law") or `b` (group "setup") on and fits the level on the training units.
struct Switch(&'static str, &'static str);

impl Candidate<Gated, Gate> for Switch {
    fn id(&self) -> &str {
        self.0
    }
    fn group(&self) -> Option<&str> {
        Some(self.1)
    }
    fn fit(&self, s: &Gated, cur: &Gate, train: &[usize]) -> Result<Gate, String> {
        let level = train.iter().map(|&u| s.0[u]).sum::<f64>() / train.len() as f64;
        Ok(match self.1 {
            "law" => Gate { a: true, level, ..*cur },
            _ => Gate { b: true, level, ..*cur },
        })
    }
}

#[test]
fn a_pair_step_adds_two_causes_that_gain_only_together() {
    let s = Gated(vec![1.0, 1.1, 0.9, 1.05, 0.95]);
    let (law, law2, setup) = (Switch("law", "law"), Switch("law2", "law"), Switch("setup", "setup"));
    let cands: [&dyn Candidate<Gated, Gate>; 3] = [&law, &law2, &setup];
    let folds = Fold::leave_one_out(5);
    let base = Gate { a: false, b: false, level: 0.0 };
    // Alone, each switch changes no prediction: no gain, nothing chosen (the plain engine).
    let plain = forward_select(&s, &cands, &base, &folds, &rule()).unwrap();
    assert!(plain.chosen.is_empty() && plain.trials.len() == 3, "{:?}", plain.chosen_ids());
    // With the pair step: the step's best (ties: the first, `law`) with each
    // candidate of another group (`setup`; not its alternative `law2`), fitted on top of it.
    let search = Search { pair_step: true, ..Search::default() };
    let bases = vec![base; train_sets(&folds).len()];
    let sel = forward_select_from(&s, &cands, &bases, &folds, &rule(), &search).unwrap();
    assert_eq!(sel.chosen_ids(), ["law+setup"]);
    let pair = &sel.trials[sel.chosen[0]];
    assert_eq!((pair.step, pair.candidate, pair.on), (2, 2, Some(0)));
    assert!(pair.best && pair.accepted && pair.comparison.gain > 0.9 && pair.fitted.iter().all(|m| m.a && m.b));
    // Both groups are used up: no step after it.
    assert_eq!(sel.trials.len(), 4);
    assert!(overall(&sel.final_misfits) < 0.1 * overall(&sel.baseline_misfits));
    // A baseline per training set: one per distinct set, or refused.
    assert!(forward_select_from(&s, &cands, &bases[..2], &folds, &rule(), &search).is_err());
}

/// A law and two set-ups: the prediction is the fitted level only with
/// the law and the `right` set-up; otherwise each switch on nudges it a
/// little (the law most, the `decoy` set-up less, `right` not at all).
#[derive(Debug, Clone, Copy, PartialEq)]
struct Trio {
    law: bool,
    right: bool,
    decoy: bool,
    level: f64,
}

struct Trios(Vec<f64>);

impl Study<Trio> for Trios {
    fn score(&self, m: &Trio, u: usize) -> f64 {
        let pred = if m.law && m.right {
            m.level
        } else {
            0.02 * f64::from(u8::from(m.law)) + 0.01 * f64::from(u8::from(m.decoy))
        };
        (pred - self.0[u]).abs() + 0.01
    }
}

/// Switches one of the trio on (`law`: group "law"; `right`, `decoy`: group
/// "setup") and fits the level on the training units.
struct Turn(&'static str);

impl Candidate<Trios, Trio> for Turn {
    fn id(&self) -> &str {
        self.0
    }
    fn group(&self) -> Option<&str> {
        Some(if self.0 == "law" { "law" } else { "setup" })
    }
    fn fit(&self, s: &Trios, cur: &Trio, train: &[usize]) -> Result<Trio, String> {
        let level = train.iter().map(|&u| s.0[u]).sum::<f64>() / train.len() as f64;
        Ok(match self.0 {
            "law" => Trio { law: true, level, ..*cur },
            "right" => Trio { right: true, level, ..*cur },
            _ => Trio { decoy: true, level, ..*cur },
        })
    }
}

#[test]
fn a_pair_step_tries_every_partner_not_only_the_best_scoring_one() {
    let s = Trios(vec![1.0, 1.1, 0.9, 1.05, 0.95]);
    let (decoy, law, right) = (Turn("decoy"), Turn("law"), Turn("right"));
    let cands: [&dyn Candidate<Trios, Trio>; 3] = [&decoy, &law, &right];
    let folds = Fold::leave_one_out(5);
    let base = Trio { law: false, right: false, decoy: false, level: 0.0 };
    let bases = vec![base; train_sets(&folds).len()];
    let search = Search { pair_step: true, ..Search::default() };
    let sel = forward_select_from(&s, &cands, &bases, &folds, &rule(), &search).unwrap();
    // Step 1: the law gains most alone (2 %), the decoy less (1 %), `right` nothing: none admitted.
    let one: Vec<&Trial<Trio>> = sel.step(1).collect();
    assert_eq!(one.iter().map(|t| t.id.as_str()).collect::<Vec<_>>(), ["decoy", "law", "right"]);
    assert!(one.iter().all(|t| !t.significant));
    assert!(one[1].best && one[1].comparison.gain > one[0].comparison.gain);
    assert!(one[0].comparison.gain > one[2].comparison.gain);
    // Step 2: the law with each set-up, both in the trace. With the
    // best-scoring set-up alone (the decoy) the pair gains too little;
    // with the second (`right`) it gains together, and is chosen.
    let two: Vec<&Trial<Trio>> = sel.step(2).collect();
    assert_eq!(two.iter().map(|t| t.id.as_str()).collect::<Vec<_>>(), ["law+decoy", "law+right"]);
    assert!(two.iter().all(|t| t.on == Some(1) && t.fitted.iter().all(|m| m.law)));
    assert!(!two[0].significant && !two[0].best && two[0].comparison.gain < 0.05);
    assert!(two[1].best && two[1].accepted && two[1].comparison.gain > 0.9);
    assert_eq!(sel.chosen_ids(), ["law+right"]);
    // Both groups used up: nothing after it.
    assert_eq!(sel.trials.len(), 5);
}

#[test]
fn a_chosen_candidate_retires_its_group() {
    // The level is the only thing to fit: `law` alone now predicts it (b already on).
    let s = Gated(vec![1.0, 1.1, 0.9, 1.05, 0.95]);
    let (law, law2, setup) = (Switch("law", "law"), Switch("law2", "law"), Switch("setup", "setup"));
    let cands: [&dyn Candidate<Gated, Gate>; 3] = [&law, &law2, &setup];
    let base = Gate { a: false, b: true, level: 0.0 };
    let sel = forward_select(&s, &cands, &base, &Fold::leave_one_out(5), &rule()).unwrap();
    assert_eq!(sel.chosen_ids(), ["law"]);
    // Step 2 tries `setup` only: `law2` left with its group.
    assert_eq!(sel.step(2).map(|t| t.id.as_str()).collect::<Vec<_>>(), ["setup"]);
}

#[test]
fn units_in_ascending_order_keep_their_folds_and_the_comparisons() {
    // Interleaved folds (unit u in fold u mod 2), as a campaign's stratified folds.
    let s = Levels(vec![1.0, 1.3, 0.8, 1.2, 0.9, 1.25]);
    let folds = [
        Fold { train: vec![1, 3, 5], held_out: vec![0, 2, 4] },
        Fold { train: vec![0, 2, 4], held_out: vec![1, 3, 5] },
    ];
    let fit_level = Shift("fit_level", f64::NAN);
    let cands: [&dyn Candidate<Levels, f64>; 1] = [&fit_level];
    let by_fold = forward_select(&s, &cands, &0.0, &folds, &rule()).unwrap();
    assert_eq!(by_fold.units, [0, 2, 4, 1, 3, 5]);
    let search = Search { units_ascending: true, ..Search::default() };
    let sel = forward_select_from(&s, &cands, &[0.0, 0.0], &folds, &rule(), &search).unwrap();
    assert_eq!(sel.units, [0, 1, 2, 3, 4, 5]);
    assert_eq!(sel.fold_of, [0, 1, 0, 1, 0, 1]);
    // Each unit scored with its own fold's fit, wherever it sits.
    let t = &sel.trials[0];
    let level = |f: usize| folds[f].train.iter().map(|&u| s.0[u]).sum::<f64>() / 3.0;
    for (i, &u) in sel.units.iter().enumerate() {
        assert_eq!(t.misfits[i], (level(sel.fold_of[i]) - s.0[u]).abs() + 0.01);
    }
    // The same misfits, the same comparison up to the order of the sums.
    let c = compare(&sel.baseline_misfits, &t.misfits, &sel.fold_of, 2);
    assert_eq!(t.comparison, c);
    let b = &by_fold.trials[0].comparison;
    assert!((b.gain - c.gain).abs() < 1e-12 && (b.t - c.t).abs() < 1e-9 && sel.chosen_ids() == ["fit_level"]);
}

/// Two views of a level: view 0 every unit, view 1 only the even units.
struct TwoViews(Vec<f64>, Vec<f64>);

impl ViewStudy<f64> for TwoViews {
    fn views(&self) -> usize {
        2
    }
    fn score_view(&self, m: &f64, view: usize, u: usize) -> Option<f64> {
        match view {
            0 => Some((m - self.0[u]).abs() + 0.01),
            _ => u.is_multiple_of(2).then(|| (m - self.1[u]).abs() + 0.01),
        }
    }
}

impl Candidate<TwoViews, f64> for Shift {
    fn id(&self) -> &str {
        self.0
    }
    fn fit(&self, _: &TwoViews, cur: &f64, _: &[usize]) -> Result<f64, String> {
        if self.1.is_infinite() { Err("no fit".into()) } else { Ok(cur + self.1) }
    }
    fn inadmissible(&self, _: &TwoViews, _: &[f64], _: &[f64]) -> Option<String> {
        (self.0 == "inadmissible").then(|| "ruled out".into())
    }
}

/// Admitted when view 0 passes the step rule; tier 1 (ranked by view 1)
/// when view 1 passes too, else tier 0 (ranked by view 0).
struct Tiered(SelectionRule);

impl ViewRule for Tiered {
    fn standing(&self, _: usize, c: &[Comparison]) -> Option<Standing> {
        let both = self.0.admits(&c[1]);
        self.0.admits(&c[0]).then_some(if both {
            Standing { tier: 1, by_view: 1 }
        } else {
            Standing { tier: 0, by_view: 0 }
        })
    }
}

#[test]
fn one_step_on_views_ranks_by_the_rules_tier_then_its_views_gain() {
    // View 0 measures 1.0 everywhere; view 1 (even units only) measures 1.0 too, except unit 4 at 0.9.
    let s = TwoViews(vec![1.0; 6], vec![1.0, 9.0, 1.0, 9.0, 0.9, 9.0]);
    let folds = Fold::leave_one_out(6);
    let (to_one, near, bad, broken) =
        (Shift("to_one", 1.0), Shift("near", 0.9), Shift("inadmissible", 1.0), Shift("broken", f64::INFINITY));
    let cands: [&dyn Candidate<TwoViews, f64>; 4] = [&near, &bad, &broken, &to_one];
    let bases = vec![0.0; 6];
    let rule = Tiered(rule());
    let sel = select_on_views(&s, &cands, &bases, &folds, &rule, &Search::default()).unwrap();
    // View 1 is compared over the even units only: the odd ones have no misfit there.
    let t = &sel.trials[3];
    assert_eq!(t.misfits[1].iter().filter(|m| m.is_some()).count(), 3);
    let m = |p: f64, x: f64| (p - x).abs() + 0.01;
    let c1 = compare(&[m(0.0, 1.0), m(0.0, 1.0), m(0.0, 0.9)], &[m(1.0, 1.0), m(1.0, 1.0), m(1.0, 0.9)], &[0, 2, 4], 6);
    assert_eq!(t.comparisons[1], c1);
    // `near` (0.9) gains less on view 0 than `to_one` (1.0), and both pass view 0 ...
    assert!(sel.trials[0].comparisons[0].gain < t.comparisons[0].gain);
    // ... and view 1 by the rule: both tier 1, so view 1's gain decides; `to_one` wins.
    assert_eq!(sel.trials[0].standing, Some(Standing { tier: 1, by_view: 1 }));
    assert_eq!(sel.chosen, Some(3));
    assert!(t.accepted && !sel.trials[0].accepted);
    // The inadmissible one is admitted by the rule and still not chosen; the broken one scores ∞.
    assert!(sel.trials[1].standing.is_some() && sel.trials[1].inadmissible.as_deref() == Some("ruled out"));
    assert!(sel.trials[2].error.is_some() && sel.trials[2].standing.is_none());
    assert!(sel.trials[2].comparisons[0].after.is_infinite());
    // A higher tier wins over a larger gain: with view 1 measuring 0.5 on the even units
    // `to_one` gains nothing there (tier 0) and `near` passes it (tier 1): `near` wins.
    let s = TwoViews(vec![1.0; 6], vec![0.5, 9.0, 0.5, 9.0, 0.5, 9.0]);
    let sel = select_on_views(&s, &cands, &bases, &folds, &rule, &Search::default()).unwrap();
    assert_eq!(sel.trials[3].standing, Some(Standing { tier: 0, by_view: 0 }));
    assert_eq!(sel.chosen, Some(0));
    // No admitted candidate: nothing chosen.
    let none = TwoViews(vec![0.0; 6], vec![0.0; 6]);
    assert_eq!(select_on_views(&none, &cands, &bases, &folds, &rule, &Search::default()).unwrap().chosen, None);
}

/// A level whose free run fails (NaN) on unit 2 once it moves above 1.05.
struct FailsHigh(Vec<f64>);

impl Study<f64> for FailsHigh {
    fn score(&self, m: &f64, u: usize) -> f64 {
        if u == 2 && *m > 1.05 { f64::NAN } else { (m - self.0[u]).abs() + 0.01 }
    }
}

impl Candidate<FailsHigh, f64> for Shift {
    fn id(&self) -> &str {
        self.0
    }
    fn fit(&self, _: &FailsHigh, cur: &f64, _: &[usize]) -> Result<f64, String> {
        Ok(cur + self.1)
    }
}

#[test]
fn a_unit_scored_nan_is_left_out_of_the_comparison() {
    let s = FailsHigh(vec![1.1, 1.1, 1.1, 1.1, 1.1]);
    let to_high = Shift("to_high", 1.1);
    let cands: [&dyn Candidate<FailsHigh, f64>; 1] = [&to_high];
    let sel = forward_select(&s, &cands, &0.0, &Fold::leave_one_out(5), &rule()).unwrap();
    let t = &sel.trials[0];
    assert!(t.misfits[2].is_nan());
    // Compared over the four units it scores: NaN no longer poisons the
    // overall misfit, the step is admitted, the comparison is `compare`'s over them.
    let keep = [0, 1, 3, 4];
    let pick = |v: &[f64]| keep.iter().map(|&i| v[i]).collect::<Vec<f64>>();
    let plain = compare(&pick(&sel.baseline_misfits), &pick(&t.misfits), &keep, 5);
    assert_eq!(t.comparison, plain);
    assert!(t.comparison.after.is_finite() && t.accepted, "{:?}", t.comparison);
    assert_eq!(sel.chosen_ids(), ["to_high"]);
    // `compare` itself would have no overall misfit after.
    assert!(compare(&sel.baseline_misfits, &t.misfits, &[0, 1, 2, 3, 4], 5).after.is_nan());
    // With no NaN, the two comparisons are the same bits.
    let (b, a) = ([2.0, 4.0, 6.0, 8.0], [1.0, 2.5, 3.0, 4.5]);
    assert_eq!(compare_where_scored(&b, &a, &[0, 0, 1, 1], 2), compare(&b, &a, &[0, 0, 1, 1], 2));
}

/// Switches both `a` and `b` on: a candidate that brings a companion term.
struct Both;

impl Candidate<Gated, Gate> for Both {
    fn id(&self) -> &str {
        "both"
    }
    fn fit(&self, s: &Gated, _: &Gate, train: &[usize]) -> Result<Gate, String> {
        let level = train.iter().map(|&u| s.0[u]).sum::<f64>() / train.len() as f64;
        Ok(Gate { a: true, b: true, level })
    }
}

/// Switches `b` on (fits the level); applies only to a model without `b`.
struct OnlyB;

impl Candidate<Gated, Gate> for OnlyB {
    fn id(&self) -> &str {
        "only_b"
    }
    fn fit(&self, s: &Gated, cur: &Gate, train: &[usize]) -> Result<Gate, String> {
        let level = train.iter().map(|&u| s.0[u]).sum::<f64>() / train.len() as f64;
        Ok(Gate { b: true, level, ..*cur })
    }
    fn applies(&self, _: &Gated, current: &[Gate]) -> bool {
        !current.iter().any(|m| m.b)
    }
}

#[test]
fn a_candidate_the_model_already_holds_no_longer_applies() {
    let s = Gated(vec![1.0, 1.1, 0.9, 1.05, 0.95]);
    let cands: [&dyn Candidate<Gated, Gate>; 2] = [&OnlyB, &Both];
    let base = Gate { a: false, b: false, level: 0.0 };
    let sel = forward_select(&s, &cands, &base, &Fold::leave_one_out(5), &rule()).unwrap();
    // Step 1: `only_b` alone predicts nothing, `both` brings `b` with `a` and is chosen ...
    assert_eq!(sel.chosen_ids(), ["both"]);
    assert_eq!(sel.step(1).count(), 2);
    // ... and `only_b` no longer applies: no step 2 (without the hook it would be tried again).
    assert_eq!(sel.trials.len(), 2, "{:?}", sel.trials.iter().map(|t| &t.id).collect::<Vec<_>>());
    // From a model that already holds `b`, it is never tried.
    let with_b = Gate { b: true, ..base };
    let sel = forward_select(&s, &cands, &with_b, &Fold::leave_one_out(5), &rule()).unwrap();
    assert!(sel.trials.iter().all(|t| t.id == "both"));
}

#[test]
fn bad_folds_are_refused() {
    let s = Levels(vec![0.0; 3]);
    let c = Shift("x", 0.0);
    let cands: [&dyn Candidate<Levels, f64>; 1] = [&c];
    let twice = [Fold { train: vec![0], held_out: vec![1] }, Fold { train: vec![0], held_out: vec![1] }];
    assert!(forward_select(&s, &cands, &0.0, &twice, &rule()).is_err());
    let both = [Fold { train: vec![0, 1], held_out: vec![1] }];
    assert!(forward_select(&s, &cands, &0.0, &both, &rule()).is_err());
}
