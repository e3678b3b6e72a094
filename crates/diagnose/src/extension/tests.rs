//! The extension module's tests (split from `mod.rs`, which passed 700 lines).

use super::*;

/// Six runs in two folds; the final model misfits 10 on each. Either
/// slip signal alone brings every run to about 5 and the two together
/// to the same 5 (the second explains what the first already did); the
/// break-away signals change nothing. A set's "fit" marks its signals.
struct Table;

impl Study<Terms> for Table {
    fn score(&self, m: &Terms, r: usize) -> f64 {
        let r = r as f64;
        match m.set.as_slice() {
            [] => 10.0,
            [0] => 5.0 + 0.1 * r,
            [1] => 6.0 + 0.1 * r,
            [0, 1] => 4.99 + 0.1 * r,
            _ => 10.0 + 0.01 * r,
        }
    }
}

impl SignalFits for Table {
    fn fit_set(&self, set: &[usize], _: &[usize]) -> Option<[f64; 4]> {
        let mut coef = [0.0; 4];
        set.iter().for_each(|&j| coef[j] = 1.0);
        Some(coef)
    }
}

fn folds() -> Vec<Fold> {
    vec![Fold { train: vec![1, 3, 5], held_out: vec![0, 2, 4] }, Fold { train: vec![0, 2, 4], held_out: vec![1, 3, 5] }]
}

fn rule() -> SelectionRule {
    SelectionRule { min_relative_gain: 0.05, min_t: 2.0 }
}

#[test]
fn a_second_signal_is_judged_against_the_first() {
    let sel = select_signals(&Table, &folds(), &rule()).unwrap();
    // Step 1 takes `slip_speed_rad_s` (gain ≈ 0.48 over the final model) ...
    assert_eq!(sel.chosen_ids(), [SIGNALS[0]]);
    let first = &sel.trials[sel.chosen[0]];
    // ... and step 2 judges `breakaway_transient` on top of it against it,
    // not against the final model (where it would gain 0.48 again): refused.
    let second = sel.step(2).find(|t| t.id == SIGNALS[1]).expect("step 2");
    assert!(second.comparison.gain.abs() < 0.01 && !second.accepted, "{:?}", second.comparison);
    assert_eq!(second.comparison.before, first.comparison.after);
    assert_eq!(second.fitted[0].set, [0, 1]);
}

#[test]
fn the_ageing_law_brings_its_level_and_the_level_then_leaves() {
    let sel = select_signals(&Aged, &folds(), &rule()).unwrap();
    // `log_dwell` is fitted with `static_level` and chosen ...
    assert_eq!(sel.chosen_ids(), [SIGNALS[DWELL]]);
    assert_eq!(sel.trials[sel.chosen[0]].fitted[0].set, [LEVEL, DWELL]);
    // ... and step 2 tries the two slip signals only: the level is held.
    let step2: Vec<&str> = sel.step(2).map(|t| t.id.as_str()).collect();
    assert_eq!(step2, [SIGNALS[0], SIGNALS[1]]);
}

/// Only the ageing law (with its level) gains; a run whose free run
/// fails under the level alone scores NaN and is left out.
struct Aged;

impl Study<Terms> for Aged {
    fn score(&self, m: &Terms, r: usize) -> f64 {
        match m.set.as_slice() {
            [LEVEL] if r == 3 => f64::NAN,
            s if s.contains(&DWELL) => 3.0 + 0.1 * r as f64,
            _ => 10.0 + 0.01 * r as f64,
        }
    }
}

impl SignalFits for Aged {
    fn fit_set(&self, set: &[usize], train: &[usize]) -> Option<[f64; 4]> {
        Table.fit_set(set, train)
    }
}
