//! Forward selection, one engine for every rig: candidates behind a small
//! trait, folds given by the caller, one step rule, and a trace of every
//! candidate at every step.
//!
//! # The procedure
//!
//! The caller names the *units* a misfit is measured on (runs of a campaign,
//! windows of one record, stiffnesses of a slider), and the *folds*: each fold
//! is a set of training units a candidate is fitted on and the held-out units
//! its fit is then scored on. Every held-out unit belongs to exactly one fold
//! (k-fold cross-validation over runs; or one calibration window and one fold
//! per held-out window, all folds sharing the training set: a candidate is then
//! fitted once per distinct training set, never once per fold).
//!
//! From the baseline, at each step every remaining candidate is fitted on top
//! of the current model (per distinct training set) and each held-out unit is
//! scored with the fit of its fold. The candidate with the largest gain (ties:
//! candidate order) is added when the rule admits it ([`SelectionRule::admits`])
//! and it is admissible ([`Candidate::inadmissible`]: the fitted candidate is
//! the effect its name says, asked only of the step's best); otherwise
//! selection stops. Candidates and units are fitted and scored in parallel and
//! collected in order, so the result is the same on any number of threads.
//!
//! Two options ([`forward_select_from`]; [`forward_select`] uses neither): a
//! baseline fitted on each training set (a baseline with parameters of its
//! own, like the slider's Coulomb law), and a *pair step* ([`Search`]): when
//! a step's best is not admitted, each applicable candidate of another group
//! ([`Candidate::group`]: candidates of one group are alternatives, one per
//! model) is fitted on top of it and judged once more by the same rule
//! against the model the step started from; the best of these pairs
//! ([`best_of`]), admitted, adds both.
//! [`Search::units_ascending`] orders the held-out units ascending in every
//! misfit vector instead of fold by fold (a campaign's runs in campaign order
//! under interleaved folds). A candidate whose fit brings a companion term
//! (the ageing law its static level) makes the candidate of that term no
//! longer apply ([`Candidate::applies`]): it leaves the selection.
//!
//! Who runs on it: the thesis rig's diagnosis (runs as units, k folds over
//! runs, the vocabulary's effects as candidates: `rig_diagnose::select`), the
//! LAVI study (held-out windows, one calibration window), the slider study
//! (stiffnesses) and the thesis rig's extension of an `unexplained` answer
//! (runs, the library's signals as candidates, scored in free run:
//! `rig_diagnose::extension`). A crate writes no selection loop of its own (tidy test
//! `forward_selection_has_one_engine`).
//!
//! # The step rule ([`compare`], the thesis rig's since issue 19)
//!
//! With M_u the misfit of unit u and M = √(mean M_u²) the overall misfit, a
//! candidate's gain is g = 1 − M_after/M_before (the overall misfits of the
//! held-out units), its spread the standard deviation over folds of each
//! fold's own gain, and its paired statistic the one-sample t of
//! d_u = ln(M_u,before/M_u,after) over the units (units with a non-positive or
//! non-finite misfit left out). It is admitted when g ≥ `min_relative_gain`,
//! t ≥ `min_t` and M_after is finite (pipeline.toml's `[shared.selection]`).
//! A unit the study scores NaN on either side (no misfit: a free run that
//! gives no features) is left out of that comparison
//! ([`compare_where_scored`]); a failed fit scores ∞ on every unit and is
//! never admitted.
//!
//! # Example: the slider's stiffnesses as folds
//!
//! ```
//! use rig_types::contract::SelectionRule;
//! use rig_types::select::{Candidate, Fold, Study, forward_select};
//! struct Slider { measured: Vec<f64> }                     // one feature per stiffness
//! impl Study<f64> for Slider {                             // the model: one friction level
//!     fn score(&self, m: &f64, unit: usize) -> f64 { (m - self.measured[unit]).abs() + 0.01 }
//! }
//! struct Refit;                                            // a candidate: the level fitted on the training units
//! impl Candidate<Slider, f64> for Refit {
//!     fn id(&self) -> &str { "refit" }
//!     fn fit(&self, s: &Slider, _: &f64, train: &[usize]) -> Result<f64, String> {
//!         Ok(train.iter().map(|&u| s.measured[u]).sum::<f64>() / train.len() as f64)
//!     }
//! }
//! let s = Slider { measured: vec![0.40, 0.42, 0.41] };
//! let folds = Fold::leave_one_out(3);                      // hold out each stiffness in turn
//! let rule = SelectionRule { min_relative_gain: 0.05, min_t: 2.0 };
//! let sel = forward_select(&s, &[&Refit as &dyn Candidate<Slider, f64>], &0.0, &folds, &rule).unwrap();
//! assert_eq!(sel.chosen_ids(), ["refit"]);
//! assert!(sel.trials[0].comparison.gain > 0.9);
//! ```

use crate::contract::SelectionRule;
use rayon::prelude::*;
use serde::Serialize;

mod views;

pub use views::*;

/// The training units a candidate is fitted on and the units it is then scored on.
#[derive(Debug, Clone, PartialEq, Eq, Serialize)]
pub struct Fold {
    pub train: Vec<usize>,
    pub held_out: Vec<usize>,
}

impl Fold {
    /// One fold per unit of `0..n`, fitted on all the others.
    pub fn leave_one_out(n: usize) -> Vec<Fold> {
        (0..n).map(|u| Fold { train: (0..n).filter(|&v| v != u).collect(), held_out: vec![u] }).collect()
    }

    /// One fold per held-out unit, every one fitted on the same `train` units
    /// (a calibration window and held-out windows of one record).
    pub fn shared_training(train: &[usize], held_out: &[usize]) -> Vec<Fold> {
        held_out.iter().map(|&u| Fold { train: train.to_vec(), held_out: vec![u] }).collect()
    }
}

/// What the engine asks of a study: the misfit of a model on one unit
/// (finite and ≥ 0; lower is better; a failed run should score a finite cap),
/// or NaN where the study has no misfit for the unit (a free run that gives
/// no features): the unit is then left out of that comparison
/// ([`compare_where_scored`]).
pub trait Study<M>: Sync {
    fn score(&self, model: &M, unit: usize) -> f64;
}

/// One candidate cause: its id, its fit on top of the current model, and its
/// admissibility rule.
pub trait Candidate<S: ?Sized, M>: Sync {
    /// The effect id (the `effect` field of a diagnosis).
    fn id(&self) -> &str;
    /// The current model extended by this candidate, fitted on the `train` units only.
    fn fit(&self, study: &S, current: &M, train: &[usize]) -> Result<M, String>;
    /// Why the fitted candidate is not the effect its name says (`None`:
    /// admissible). Asked only of a step's best candidate when the rule admits
    /// it; `fitted` holds one model per distinct training set, in the order of
    /// [`Selection::train_sets`].
    fn inadmissible(&self, _study: &S, _current: &[M], _fitted: &[M]) -> Option<String> {
        None
    }
    /// The group of alternatives this candidate belongs to (`None`: a group
    /// of its own). Candidates of one group replace each other (two
    /// friction laws, two set-ups): once one is chosen the others of its
    /// group are no longer tried, and a pair step pairs two groups.
    fn group(&self) -> Option<&str> {
        None
    }
    /// Whether this candidate is tried on top of the `current` models (one
    /// per training set). A candidate whose term the current model already
    /// holds — brought as a companion by another candidate's fit (the
    /// ageing law brings its static level) — does not apply, and leaves the
    /// selection (models only grow). Default: always.
    fn applies(&self, _study: &S, _current: &[M]) -> bool {
        true
    }
}

/// A model compared with the one before it (module docs: the step rule).
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Comparison {
    /// Overall misfit before and after, √(mean M_u²) over the held-out units.
    pub before: f64,
    pub after: f64,
    /// 1 − after/before.
    pub gain: f64,
    /// Standard deviation over folds of each fold's own gain (NaN with one fold).
    pub gain_fold_sd: f64,
    /// Paired t of ln(M_before/M_after) over the units.
    pub t: f64,
}

impl SelectionRule {
    /// The step rule: gain ≥ `min_relative_gain`, paired t ≥ `min_t`, a finite misfit after.
    pub fn admits(&self, c: &Comparison) -> bool {
        c.gain >= self.min_relative_gain && c.t >= self.min_t && c.after.is_finite()
    }
}

/// √(mean M²) of per-unit misfits (NaN for none).
pub fn overall(ms: &[f64]) -> f64 {
    if ms.is_empty() { f64::NAN } else { (ms.iter().map(|m| m * m).sum::<f64>() / ms.len() as f64).sqrt() }
}

/// The comparison of per-unit misfits `before` and `after` (same unit order),
/// `fold_of[u]` the fold unit u is held out in, `folds` the number of folds
/// (module docs: the step rule).
pub fn compare(before: &[f64], after: &[f64], fold_of: &[usize], folds: usize) -> Comparison {
    let (b, a) = (overall(before), overall(after));
    let gain = if b > 0.0 { 1.0 - a / b } else { 0.0 };
    let fold_gains: Vec<f64> = (0..folds)
        .filter_map(|f| {
            let idx: Vec<usize> = (0..fold_of.len()).filter(|&i| fold_of[i] == f).collect();
            let bf = overall(&idx.iter().map(|&i| before[i]).collect::<Vec<_>>());
            let af = overall(&idx.iter().map(|&i| after[i]).collect::<Vec<_>>());
            (bf > 0.0 && bf.is_finite() && af.is_finite()).then(|| 1.0 - af / bf)
        })
        .collect();
    let mg = fold_gains.iter().sum::<f64>() / fold_gains.len().max(1) as f64;
    let sd = if fold_gains.len() > 1 {
        (fold_gains.iter().map(|g| (g - mg).powi(2)).sum::<f64>() / (fold_gains.len() - 1) as f64).sqrt()
    } else {
        f64::NAN
    };
    let d: Vec<f64> = before
        .iter()
        .zip(after)
        .filter(|(x, y)| **x > 0.0 && **y > 0.0 && x.is_finite() && y.is_finite())
        .map(|(x, y)| (x / y).ln())
        .collect();
    let n = d.len() as f64;
    let t = if d.len() > 1 {
        let m = d.iter().sum::<f64>() / n;
        let v = d.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (n - 1.0);
        if v > 0.0 {
            m / (v / n).sqrt()
        } else if m > 0.0 {
            f64::INFINITY
        } else {
            0.0
        }
    } else {
        0.0
    };
    Comparison { before: b, after: a, gain, gain_fold_sd: sd, t }
}

/// A step's best candidate: the largest gain among finite misfits after
/// (ties: the first), the pick [`forward_select`] makes at every step.
pub fn best_of(comparisons: &[Comparison]) -> Option<usize> {
    (0..comparisons.len())
        .filter(|&i| comparisons[i].after.is_finite())
        .max_by(|&a, &b| comparisons[a].gain.total_cmp(&comparisons[b].gain).then(b.cmp(&a)))
}

/// One candidate tried at one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial<M> {
    pub step: usize,
    /// Index into the candidates passed to [`forward_select`].
    pub candidate: usize,
    /// In a pair step ([`Search::pair_step`]), the candidate this one was
    /// fitted on top of (the id is then `on+candidate`).
    pub on: Option<usize>,
    pub id: String,
    /// The fitted models, one per distinct training set ([`Selection::train_sets`]);
    /// empty when the fit failed.
    pub fitted: Vec<M>,
    /// Why the fit failed, if it did (the trial then scores an infinite misfit).
    pub error: Option<String>,
    /// Misfit of every held-out unit ([`Selection::units`] order).
    pub misfits: Vec<f64>,
    pub comparison: Comparison,
    /// Units where the candidate is better than the current model.
    pub wins: usize,
    /// Admitted by the rule ([`SelectionRule::admits`]).
    pub significant: bool,
    /// The step's largest gain.
    pub best: bool,
    /// The best's admissibility verdict, when it was asked.
    pub inadmissible: Option<String>,
    pub accepted: bool,
}

/// The selection's outcome: the trace of every trial, the chosen ones, and the final model.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Selection<M> {
    /// The held-out units, in the order of every misfit vector.
    pub units: Vec<usize>,
    /// Fold of each unit (index into the caller's folds).
    pub fold_of: Vec<usize>,
    /// The distinct training sets, in order of first appearance among the folds.
    pub train_sets: Vec<Vec<usize>>,
    pub baseline_misfits: Vec<f64>,
    pub trials: Vec<Trial<M>>,
    /// Indices into `trials` of the accepted ones, in the order added.
    pub chosen: Vec<usize>,
    /// The final model per training set, and its per-unit misfits.
    pub final_models: Vec<M>,
    pub final_misfits: Vec<f64>,
}

impl<M> Selection<M> {
    /// Ids of the chosen candidates, in the order added.
    pub fn chosen_ids(&self) -> Vec<&str> {
        self.chosen.iter().map(|&i| self.trials[i].id.as_str()).collect()
    }

    /// The trials of one step.
    pub fn step(&self, step: usize) -> impl Iterator<Item = &Trial<M>> {
        self.trials.iter().filter(move |t| t.step == step)
    }
}

/// Why a selection could not start.
#[derive(Debug, Clone, PartialEq, Eq)]
pub struct SelectError(pub String);

impl std::fmt::Display for SelectError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "forward selection: {}", self.0)
    }
}

impl std::error::Error for SelectError {}

/// How far a selection searches beyond one candidate per step.
#[derive(Debug, Clone, Copy, Default, PartialEq, Eq, Serialize)]
pub struct Search {
    /// When a step's best is not admitted, try once more pairs: each
    /// candidate of another group ([`Candidate::group`]) that applies on top
    /// of the step's best ([`Candidate::applies`]; one whose own fit failed
    /// too) fitted on top of it (each fit on its training set), every pair
    /// compared by the same rule with the model the step started from. Two
    /// causes may each fail alone and gain together (a set-up that moves one
    /// feature and a law that moves another), and the partner that gains
    /// together need not be the one that gains most alone, so every partner
    /// is tried, not only the best-scoring one. The pairs are trials of a
    /// step of their own, every one in the trace; the best of them
    /// ([`best_of`]: largest gain, ties the first in candidate order) is the
    /// step's best and is added, with the step's best under it, when the rule
    /// admits it (and it is admissible) — never a way round the rule.
    pub pair_step: bool,
    /// The held-out units in ascending order in every misfit vector
    /// ([`Selection::units`]) rather than fold by fold: a campaign's runs in
    /// campaign order, the order its per-run misfits are reported in, when
    /// its folds interleave the runs (the thesis rig's stratified folds). The
    /// comparisons sum over the units in that order.
    pub units_ascending: bool,
}

/// The training sets of `folds`, distinct, in order of first appearance: the
/// order of [`Selection::train_sets`] and of the baselines [`forward_select_from`] takes.
pub fn train_sets(folds: &[Fold]) -> Vec<Vec<usize>> {
    let mut sets: Vec<Vec<usize>> = Vec::new();
    for f in folds {
        if !sets.contains(&f.train) {
            sets.push(f.train.clone());
        }
    }
    sets
}

/// Forward selection from `baseline` over `candidates` (module docs). The
/// baseline is the same model for every training set.
pub fn forward_select<S, M>(
    study: &S,
    candidates: &[&dyn Candidate<S, M>],
    baseline: &M,
    folds: &[Fold],
    rule: &SelectionRule,
) -> Result<Selection<M>, SelectError>
where
    S: Study<M>,
    M: Clone + Send + Sync,
{
    let baselines = vec![baseline.clone(); train_sets(folds).len()];
    forward_select_from(study, candidates, &baselines, folds, rule, &Search::default())
}

/// Forward selection from a baseline fitted on each training set
/// (`baselines[s]` on [`train_sets`]`(folds)[s]`: a baseline with parameters
/// of its own, fitted like any model on the training units only), with the
/// search `search` (module docs; [`forward_select`] is this with one baseline
/// for every set and no pair step).
pub fn forward_select_from<S, M>(
    study: &S,
    candidates: &[&dyn Candidate<S, M>],
    baselines: &[M],
    folds: &[Fold],
    rule: &SelectionRule,
    search: &Search,
) -> Result<Selection<M>, SelectError>
where
    S: Study<M>,
    M: Clone + Send + Sync,
{
    let Layout { units, fold_of, train_sets, set_of_fold } = Layout::of(folds, search, baselines.len())?;
    // Each held-out unit scored with the model of its fold's training set.
    let score_all = |models: &[M]| -> Vec<f64> {
        (0..units.len()).into_par_iter().map(|i| study.score(&models[set_of_fold[fold_of[i]]], units[i])).collect()
    };
    let group = |c: usize| candidates[c].group();
    let mut current: Vec<M> = baselines.to_vec();
    let baseline_misfits = score_all(&current);
    let mut cur_ms = baseline_misfits.clone();
    let mut trials: Vec<Trial<M>> = Vec::new();
    let mut chosen = Vec::new();
    let mut left: Vec<usize> = (0..candidates.len()).collect();
    let mut step = 1;
    // A trial from its fits (one per training set, or the first error) against the current model.
    let trial = |step: usize, c: usize, on: Option<usize>, fits: &[Result<M, String>], cur_ms: &[f64]| {
        let (fitted, error, misfits) = match fits.iter().cloned().collect::<Result<Vec<M>, String>>() {
            Ok(models) => {
                let ms = score_all(&models);
                (models, None, ms)
            }
            Err(e) => (Vec::new(), Some(e), vec![f64::INFINITY; units.len()]),
        };
        let comparison = compare_where_scored(cur_ms, &misfits, &fold_of, folds.len());
        Trial {
            step,
            candidate: c,
            on,
            id: on.map_or_else(
                || candidates[c].id().to_string(),
                |b| format!("{}+{}", candidates[b].id(), candidates[c].id()),
            ),
            fitted,
            error,
            wins: cur_ms.iter().zip(&misfits).filter(|(b, a)| a < b).count(),
            misfits,
            significant: rule.admits(&comparison),
            comparison,
            best: false,
            inadmissible: None,
            accepted: false,
        }
    };
    // Every (candidate, training set) fit on `base` is a task of its own,
    // collected in order; one trial per candidate, `under` the step's best in a pair.
    let trials_of = |step: usize, cands: &[usize], under: Option<usize>, base: &[M], cur_ms: &[f64]| {
        let n = train_sets.len();
        let tasks: Vec<(usize, usize)> = cands.iter().flat_map(|&c| (0..n).map(move |s| (c, s))).collect();
        let fits: Vec<Result<M, String>> =
            tasks.par_iter().map(|&(c, s)| candidates[c].fit(study, &base[s], &train_sets[s])).collect();
        cands
            .iter()
            .enumerate()
            .map(|(k, &c)| trial(step, c, under, &fits[k * n..(k + 1) * n], cur_ms))
            .collect::<Vec<_>>()
    };
    loop {
        // A candidate the current model already holds leaves ([`Candidate::applies`]).
        left.retain(|&c| candidates[c].applies(study, &current));
        if left.is_empty() {
            break;
        }
        let first = trials.len();
        trials.extend(trials_of(step, &left, None, &current, &cur_ms));
        let step_comparisons: Vec<Comparison> = trials[first..].iter().map(|t| t.comparison).collect();
        let best = best_of(&step_comparisons).map(|i| first + i);
        let Some(mut best) = best else { break };
        trials[best].best = true;
        if !trials[best].significant {
            if !search.pair_step {
                break;
            }
            // The pair step: each applicable candidate of another group fitted
            // on top of the step's best, every pair a trial of the next step;
            // the best of them ([`best_of`]) is that step's pair.
            let (b, on) = (trials[best].candidate, trials[best].fitted.clone());
            let partners: Vec<usize> = left
                .iter()
                .copied()
                .filter(|&c| {
                    c != b && (group(c).is_none() || group(c) != group(b)) && candidates[c].applies(study, &on)
                })
                .collect();
            if partners.is_empty() {
                break;
            }
            step += 1;
            let first_pair = trials.len();
            trials.extend(trials_of(step, &partners, Some(b), &on, &cur_ms));
            let pair_comparisons: Vec<Comparison> = trials[first_pair..].iter().map(|t| t.comparison).collect();
            let Some(pair) = best_of(&pair_comparisons).map(|i| first_pair + i) else { break };
            trials[pair].best = true;
            best = pair;
            if !trials[best].significant {
                break;
            }
        }
        let why = candidates[trials[best].candidate].inadmissible(study, &current, &trials[best].fitted);
        if why.is_some() {
            trials[best].inadmissible = why;
            break;
        }
        trials[best].accepted = true;
        current = trials[best].fitted.clone();
        cur_ms = trials[best].misfits.clone();
        // The chosen candidates and the alternatives of their groups leave.
        for c in std::iter::once(trials[best].candidate).chain(trials[best].on) {
            left.retain(|&l| l != c && (group(c).is_none() || group(l) != group(c)));
        }
        chosen.push(best);
        step += 1;
    }
    Ok(Selection {
        units,
        fold_of,
        train_sets,
        baseline_misfits,
        trials,
        chosen,
        final_models: current,
        final_misfits: cur_ms,
    })
}

/// The held-out units of `folds` in the order of every misfit vector, the
/// fold of each, the distinct training sets and each fold's set (the folds
/// checked: every held-out unit in exactly one fold, never trained on there).
struct Layout {
    units: Vec<usize>,
    fold_of: Vec<usize>,
    train_sets: Vec<Vec<usize>>,
    set_of_fold: Vec<usize>,
}

impl Layout {
    fn of(folds: &[Fold], search: &Search, baselines: usize) -> Result<Layout, SelectError> {
        let mut units = Vec::new();
        let mut fold_of = Vec::new();
        let train_sets = train_sets(folds);
        let mut set_of_fold = Vec::new();
        for (f, fold) in folds.iter().enumerate() {
            if fold.train.is_empty() || fold.held_out.is_empty() {
                return Err(SelectError(format!("fold {f} needs training and held-out units")));
            }
            for &u in &fold.held_out {
                if units.contains(&u) {
                    return Err(SelectError(format!("unit {u} is held out in two folds")));
                }
                if fold.train.contains(&u) {
                    return Err(SelectError(format!("unit {u} of fold {f} is both trained on and held out")));
                }
                units.push(u);
                fold_of.push(f);
            }
            set_of_fold.push(train_sets.iter().position(|t| *t == fold.train).expect("every fold's set is listed"));
        }
        if search.units_ascending {
            let mut order: Vec<(usize, usize)> = units.iter().copied().zip(fold_of.iter().copied()).collect();
            order.sort_unstable();
            (units, fold_of) = order.into_iter().unzip();
        }
        if baselines != train_sets.len() {
            return Err(SelectError(format!("{baselines} baselines for {} distinct training sets", train_sets.len())));
        }
        Ok(Layout { units, fold_of, train_sets, set_of_fold })
    }
}

// # One step judged on several views ([`select_on_views`])
//
// Added for the thesis rig's structural candidates (issue 26, item 3): a
// candidate is scored on each held-out unit under several views (the rotor
// balance teacher-forced, the free run, the balance at the stick↔slip
// transitions), each view compared with the baseline by [`compare`], and a
// caller's [`ViewRule`] says from those comparisons whether it is admitted
// and how it ranks. One step: at most one candidate is chosen.

/// A study that scores a model on several views of each unit; a unit may
/// have no misfit in a view (`None`: left out of that view's comparison).
pub trait ViewStudy<M>: Sync {
    /// The number of views (each misfit vector has one entry per view).
    fn views(&self) -> usize;
    /// The misfit of `model` on `unit` in `view` (finite and ≥ 0, lower is better).
    fn score_view(&self, model: &M, view: usize, unit: usize) -> Option<f64>;
}

#[cfg(test)]
mod tests;
