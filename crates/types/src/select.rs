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

/// Where an admitted candidate ranks: a higher `tier` wins; within a tier,
/// the larger gain on the view `by_view` (ties: candidate order).
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize)]
pub struct Standing {
    pub tier: u32,
    pub by_view: usize,
}

/// The criterion of a one-step selection on views: from candidate
/// `candidate`'s comparisons with the baseline (one per view, in view order),
/// whether it is admitted (`Some`) and where it ranks.
pub trait ViewRule: Sync {
    fn standing(&self, candidate: usize, comparisons: &[Comparison]) -> Option<Standing>;
}

/// One candidate of a one-step selection on views.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewTrial<M> {
    /// Index into the candidates passed to [`select_on_views`].
    pub candidate: usize,
    pub id: String,
    /// The fitted models, one per distinct training set; empty when a fit failed.
    pub fitted: Vec<M>,
    pub error: Option<String>,
    /// `misfits[view][i]`: the held-out unit `units[i]`'s misfit in that view.
    pub misfits: Vec<Vec<Option<f64>>>,
    /// Each view's comparison with the baseline over the units both score.
    pub comparisons: Vec<Comparison>,
    /// The candidate's admissibility verdict ([`Candidate::inadmissible`],
    /// asked of every candidate that fitted).
    pub inadmissible: Option<String>,
    /// The rule's standing (`None`: not admitted by the rule).
    pub standing: Option<Standing>,
    pub accepted: bool,
}

/// The outcome of [`select_on_views`].
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ViewSelection<M> {
    pub units: Vec<usize>,
    pub fold_of: Vec<usize>,
    pub train_sets: Vec<Vec<usize>>,
    /// `baseline_misfits[view][i]`, as a trial's misfits.
    pub baseline_misfits: Vec<Vec<Option<f64>>>,
    /// One trial per candidate, in candidate order.
    pub trials: Vec<ViewTrial<M>>,
    /// Index into `trials` of the chosen candidate, if any.
    pub chosen: Option<usize>,
}

/// The comparison of two views' misfit vectors over the units both score,
/// in unit order (the step rule, [`compare`]).
pub fn compare_scored(before: &[Option<f64>], after: &[Option<f64>], fold_of: &[usize], folds: usize) -> Comparison {
    let (mut b, mut a, mut f) = (Vec::new(), Vec::new(), Vec::new());
    for ((x, y), g) in before.iter().zip(after).zip(fold_of) {
        if let (Some(x), Some(y)) = (x, y) {
            b.push(*x);
            a.push(*y);
            f.push(*g);
        }
    }
    compare(&b, &a, &f, folds)
}

/// [`compare`] over the units scored on both sides: a unit whose misfit is
/// NaN in `before` or `after` (the study has none for it, [`Study::score`])
/// is left out, as [`compare_scored`] leaves out a view's unscored units.
/// The comparison [`forward_select_from`] makes at every step; with no NaN it
/// is [`compare`] itself.
pub fn compare_where_scored(before: &[f64], after: &[f64], fold_of: &[usize], folds: usize) -> Comparison {
    let scored = |v: &[f64]| v.iter().map(|m| (!m.is_nan()).then_some(*m)).collect::<Vec<_>>();
    compare_scored(&scored(before), &scored(after), fold_of, folds)
}

/// One step of selection judged on several views: every candidate is fitted
/// on each distinct training set on top of that set's baseline
/// (`baselines[s]` on [`train_sets`]`(folds)[s]`), every held-out unit is
/// scored in every view with the fit of its fold, each view compared with the
/// baseline's ([`compare_scored`]); the rule gives each candidate its
/// standing, every candidate that fitted is asked its admissibility, and the
/// admissible admitted candidate of the highest standing is chosen (within a
/// tier the larger gain on the tier's view; ties: candidate order). Fits and
/// scores run in parallel and are collected in order: the result is the
/// same on any number of threads. `search.units_ascending` orders the units
/// as in [`forward_select_from`]; the pair step does not apply.
pub fn select_on_views<S, M>(
    study: &S,
    candidates: &[&dyn Candidate<S, M>],
    baselines: &[M],
    folds: &[Fold],
    rule: &dyn ViewRule,
    search: &Search,
) -> Result<ViewSelection<M>, SelectError>
where
    S: ViewStudy<M>,
    M: Clone + Send + Sync,
{
    let Layout { units, fold_of, train_sets, set_of_fold } = Layout::of(folds, search, baselines.len())?;
    let views = study.views();
    let score_all = |models: &[M]| -> Vec<Vec<Option<f64>>> {
        let cells: Vec<Option<f64>> = (0..views * units.len())
            .into_par_iter()
            .map(|k| {
                let (v, i) = (k / units.len(), k % units.len());
                study.score_view(&models[set_of_fold[fold_of[i]]], v, units[i])
            })
            .collect();
        cells.chunks(units.len().max(1)).map(<[Option<f64>]>::to_vec).collect()
    };
    let baseline_misfits = score_all(baselines);
    let tasks: Vec<(usize, usize)> =
        (0..candidates.len()).flat_map(|c| (0..train_sets.len()).map(move |s| (c, s))).collect();
    let fits: Vec<Result<M, String>> =
        tasks.par_iter().map(|&(c, s)| candidates[c].fit(study, &baselines[s], &train_sets[s])).collect();
    let mut trials: Vec<ViewTrial<M>> = (0..candidates.len())
        .map(|c| {
            let set = &fits[c * train_sets.len()..(c + 1) * train_sets.len()];
            let (fitted, error, misfits) = match set.iter().cloned().collect::<Result<Vec<M>, String>>() {
                Ok(models) => {
                    let ms = score_all(&models);
                    (models, None, ms)
                }
                // A failed fit scores an infinite misfit wherever the baseline scores.
                Err(e) => (
                    Vec::new(),
                    Some(e),
                    baseline_misfits.iter().map(|v| v.iter().map(|m| m.map(|_| f64::INFINITY)).collect()).collect(),
                ),
            };
            let comparisons: Vec<Comparison> =
                (0..views).map(|v| compare_scored(&baseline_misfits[v], &misfits[v], &fold_of, folds.len())).collect();
            let inadmissible = match error {
                None => candidates[c].inadmissible(study, baselines, &fitted),
                Some(_) => None,
            };
            let standing = if error.is_none() { rule.standing(c, &comparisons) } else { None };
            ViewTrial {
                candidate: c,
                id: candidates[c].id().to_string(),
                fitted,
                error,
                misfits,
                comparisons,
                inadmissible,
                standing,
                accepted: false,
            }
        })
        .collect();
    let rank = |t: &ViewTrial<M>| t.standing.map(|s| (s.tier, t.comparisons[s.by_view].gain));
    let mut chosen: Option<usize> = None;
    for (k, t) in trials.iter().enumerate() {
        let (Some(r), None) = (rank(t), &t.inadmissible) else { continue };
        let better = chosen.and_then(|c| rank(&trials[c])).is_none_or(|b| r.0 > b.0 || (r.0 == b.0 && r.1 > b.1));
        if better {
            chosen = Some(k);
        }
    }
    if let Some(k) = chosen {
        trials[k].accepted = true;
    }
    Ok(ViewSelection { units, fold_of, train_sets, baseline_misfits, trials, chosen })
}

#[cfg(test)]
mod tests {
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
        let c1 =
            compare(&[m(0.0, 1.0), m(0.0, 1.0), m(0.0, 0.9)], &[m(1.0, 1.0), m(1.0, 1.0), m(1.0, 0.9)], &[0, 2, 4], 6);
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
}
