//! Cross-validated forward selection of vocabulary effects, the adequacy test
//! of the final model and the residual signature (the rules are stated in the
//! crate docs).
//!
//! The selection runs on the workspace's one engine,
//! [`rig_types::select::forward_select_from`]: the campaign's runs are the
//! units (in campaign order, `Search::units_ascending`), fold f holds out the
//! runs of fold f and trains on the others, each [`VocabularyEffect`] of the
//! registry is a candidate (`Effect`: its id, its fit, its `inadmissible`
//! rule) and the model is one `FoldModel` per fold: its effects and each
//! channel's fit on the fold's training runs. The units are the friction
//! channel's runs (the brake applied); the drive channel's fits also read
//! the runs with the brake open, held out in folds of their own
//! ([`PreparedRuns`]: they inform the PI gains and the drive limit, and
//! are not scored by the step rule). What keeps it fast lives in the
//! study (`Vocabulary`): a channel's fit is shared by every model with the
//! same friction set or the same drive limit, and each friction fit is
//! warm-started from the current model's fit of the same fold. The engine
//! fits every (candidate, fold) as a task of its own, so a step's 3–4
//! friction sets × 5 folds keep two cores evenly busy. The engine's trace
//! is the report's (`StepRow`s).
//!
//! The module's files: this one the study, the candidates, the selection and
//! its near misses; `select/features.rs` a run's measured steady-state
//! features; `select/conclude.rs` the selection's conclusion (adequacy, the
//! `unexplained` finding's signature, the report's detail).

mod conclude;
mod features;

pub use features::{measured_features, steady_features, steady_fundamental_hz};

use crate::composite::{self, Composite, CompositeFit, FrictionSet, Phases};
use crate::drive::{self, Pi};
use crate::effects::{EffectId, REGISTRY, Term, VocabularyEffect};
use crate::friction::SlipData;
use crate::prepare::{PreparedRuns, RunSignals};
use crate::result::{Diagnosis, StepRow};
use crate::{DiagnoseError, DiagnoseOptions};
use rayon::prelude::*;
use rig_types::select::{self as engine, Fold};
use std::collections::BTreeMap;
use std::sync::{Arc, Mutex};

/// A model of both channels: which friction effects, whether the drive has its own limit.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Default)]
struct ModelSet {
    friction: FrictionSet,
    limit: bool,
}

impl ModelSet {
    fn with(self, e: EffectId) -> Self {
        match e.term() {
            Term::DriveLimit => ModelSet { limit: true, ..self },
            Term::Friction(t) => ModelSet { friction: self.friction.with(t), ..self },
        }
    }
}

/// Cross-validated friction channel of one friction set.
#[derive(Debug, Clone)]
struct FrictionCv {
    /// e_μ of every run, from the model fitted without the run's fold (None: no slip).
    e_mu: Vec<Option<f64>>,
    /// Per fold, the model fitted on the other folds.
    models: Vec<Option<Composite>>,
    /// Per run, its nuisance phases under its fold's model.
    phases: Vec<Phases>,
}

/// Cross-validated drive channel.
#[derive(Debug, Clone)]
struct DriveCv {
    e_v: Vec<f64>,
    pis: Vec<Option<Pi>>,
}

struct Cv<'a> {
    /// The selection's units: the friction channel's runs
    /// ([`crate::prepare::PreparedRuns::friction_units`]).
    runs: &'a [RunSignals],
    /// The drive channel's runs ([`crate::prepare::PreparedRuns::drive_units`]):
    /// `runs` first, then the operating points with the brake open, which
    /// the drive's fits read and the selection does not score.
    drive_runs: &'a [RunSignals],
    folds: usize,
    supply_v: f64,
    freqs: Vec<f64>,
    max_order: u32,
    /// Per fold, its training runs' slip samples (`fold_fit_spacing_s`
    /// apart, [`SlipData::from_runs_spaced`]) and each held-out run's
    /// (run index, every slip sample): built once and read by every friction set
    /// of every selection step (each fit built them anew: 4–5 % of a
    /// full-protocol diagnosis's CPU in `perf`, with their page faults).
    fold_data: Vec<(SlipData, Vec<(usize, SlipData)>)>,
    /// Per fold, what every friction set's fit of its training data
    /// computes alike ([`composite::DataMemo`]: the cold Stribeck fits, the
    /// angle modulation's sin and cos by order).
    cold: Vec<composite::DataMemo>,
    /// Per fold, its held-out runs' (in `fold_data`'s order) sin and cos of
    /// the modulations, shared by every friction set that predicts them
    /// ([`composite::HeldRuns`]).
    held_memos: Vec<composite::HeldRuns>,
}

/// One fold's friction fit: the model fitted on its training runs and, per
/// held-out run, (run index, relative μ error, phases fitted on that run).
type FoldFriction = (Option<Composite>, Vec<(usize, Option<f64>, Phases)>);

/// One fold's drive fit: the PI fitted on its training runs and, per
/// held-out run, (run index, relative voltage error).
type FoldDrive = (Option<Pi>, Vec<(usize, f64)>);

/// A model of both channels as the engine carries it, one per fold: which
/// effects, and each channel fitted on the fold's training runs with its
/// held-out runs' errors. A candidate refits only the channel its effect acts
/// on and shares the other's fit ([`Arc`]).
#[derive(Clone)]
struct FoldModel {
    set: ModelSet,
    fold: usize,
    friction: Arc<FoldFriction>,
    drive: Arc<FoldDrive>,
}

/// The diagnosis as [`rig_types::select`] sees it: the campaign's runs are
/// the units, a run's misfit M_r (crate docs) is read from its fold's
/// model. The channels' fits are kept by (friction set or limit, fold): a
/// friction set is fitted once per fold, whichever step and candidate reach
/// it (the drive limit accepted first leaves every friction set as it was),
/// and the drive with its own limit once per fold. The lock is held for
/// look-ups only, never during a fit.
struct Vocabulary<'c, 'a> {
    cv: &'c Cv<'a>,
    frictions: Mutex<BTreeMap<(FrictionSet, usize), Arc<FoldFriction>>>,
    drives: Mutex<BTreeMap<(bool, usize), Arc<FoldDrive>>>,
    /// Every run's slip samples and the joint fit of a friction set on them
    /// (the admissibility rule's and, for the retained set, the final one).
    d_all: &'c SlipData,
    all_fits: Mutex<BTreeMap<FrictionSet, Option<CompositeFit>>>,
}

/// `cache[key]`, computed by `fit` (outside the lock) when missing.
fn cached<K: Ord + Copy, V>(cache: &Mutex<BTreeMap<K, Arc<V>>>, key: K, fit: impl FnOnce() -> V) -> Arc<V> {
    if let Some(v) = cache.lock().expect("cache").get(&key) {
        return v.clone();
    }
    let v = Arc::new(fit());
    cache.lock().expect("cache").entry(key).or_insert(v).clone()
}

impl Vocabulary<'_, '_> {
    /// Fold `f`'s friction channel of `set`, warm-started from `start` when
    /// it is fitted here.
    fn friction(&self, set: FrictionSet, f: usize, start: Option<&Composite>) -> Arc<FoldFriction> {
        cached(&self.frictions, (set, f), || self.cv.fold_friction(set, f, start))
    }

    fn drive(&self, limit: bool, f: usize) -> Arc<FoldDrive> {
        cached(&self.drives, (limit, f), || self.cv.fold_drive(limit, f))
    }

    /// The joint fit of `set` on every run (memoised), its standard errors
    /// not yet inflated ([`composite::fit_composite_deferred`]: the
    /// admissibility rules read its model; the report's, the retained
    /// set's, is inflated once, [`composite::inflate_errors`]).
    fn fit_all(&self, set: FrictionSet) -> Option<CompositeFit> {
        if let Some(fit) = self.all_fits.lock().expect("joint fits").get(&set) {
            return fit.clone();
        }
        let fit = composite::fit_composite_deferred(self.d_all, set, &self.cv.freqs, self.cv.max_order);
        self.all_fits.lock().expect("joint fits").entry(set).or_insert(fit).clone()
    }
}

impl engine::Study<FoldModel> for Vocabulary<'_, '_> {
    /// M_r of run `r` under its fold's model ([`combine`]).
    fn score(&self, m: &FoldModel, r: usize) -> f64 {
        let e_mu = m.friction.1.iter().find(|h| h.0 == r).and_then(|h| h.1);
        let e_v = m.drive.1.iter().find(|h| h.0 == r).map_or(f64::INFINITY, |h| h.1);
        combine(e_mu, e_v)
    }
}

/// A vocabulary effect as the engine's candidate: its id the registry's,
/// its fit the current model with the effect's term added and that channel
/// refitted on the fold's training runs (the friction warm-started from the
/// current model's fit of the same fold), its admissibility rule its own.
struct Effect(EffectId);

impl engine::Candidate<Vocabulary<'_, '_>, FoldModel> for Effect {
    fn id(&self) -> &str {
        self.0.id()
    }

    fn fit(&self, v: &Vocabulary<'_, '_>, current: &FoldModel, _train: &[usize]) -> Result<FoldModel, String> {
        let set = current.set.with(self.0);
        let f = current.fold;
        Ok(match self.0.term() {
            Term::DriveLimit => FoldModel { set, drive: v.drive(set.limit, f), ..current.clone() },
            Term::Friction(_) => {
                FoldModel { set, friction: v.friction(set.friction, f, current.friction.0.as_ref()), ..current.clone() }
            }
        })
    }

    /// Whether the effect fitted on every run is the effect its name says:
    /// its own rule ([`VocabularyEffect::inadmissible`], e.g. viscous c > 0,
    /// velocity weakening μs > μk, diagnosis.md's table). A fit with the
    /// opposite sign is a shape outside the vocabulary (friction falling
    /// linearly with speed, or rising toward a plateau), so the effect is not
    /// accepted and selection stops: a second-best vocabulary effect would
    /// only paper over the mismatch, which the adequacy test then judges.
    fn inadmissible(&self, v: &Vocabulary<'_, '_>, current: &[FoldModel], _: &[FoldModel]) -> Option<String> {
        let set = current[0].set.with(self.0).friction;
        self.0.inadmissible(&mut || v.fit_all(set).map(|f| f.model))
    }
}

impl Cv<'_> {
    /// Fold `f`'s training runs of the drive channel: every drive run held
    /// out in another fold, the brake open or applied.
    fn drive_train(&self, f: usize) -> Vec<&RunSignals> {
        self.drive_runs.iter().filter(|r| r.fold != f).collect()
    }

    /// The runs with the brake open ([`Cv::drive_runs`] after the units).
    fn brake_open_runs(&self) -> &[RunSignals] {
        &self.drive_runs[self.runs.len()..]
    }

    /// Fold `f`'s friction fit: the model of `set` fitted on the other folds
    /// (warm-started from `start`, [`composite::fit_composite_model_from`]),
    /// and each held-out run's μ error and phases under it.
    fn fold_friction(&self, set: FrictionSet, f: usize, start: Option<&Composite>) -> FoldFriction {
        let (d, held_data) = &self.fold_data[f];
        let model =
            composite::fit_composite_model_from_cached(d, set, &self.freqs, self.max_order, start, &self.cold[f]);
        let held = match &model {
            Some(m) => {
                let runs: Vec<&SlipData> = held_data.iter().map(|(_, d)| d).collect();
                let fits = composite::heldout_fits(m, &runs, &self.held_memos[f]);
                held_data.iter().zip(fits).map(|((i, _), (e, ph))| (*i, e, ph)).collect()
            }
            None => held_data.iter().map(|(i, _)| (*i, None, (0.0, 0.0))).collect(),
        };
        (model, held)
    }

    /// [`Cv::fold_data`] of `runs` split into `folds`.
    fn fold_data(runs: &[RunSignals], folds: usize, spacing_s: f64) -> Vec<(SlipData, Vec<(usize, SlipData)>)> {
        (0..folds)
            .into_par_iter()
            .map(|f| {
                let train: Vec<&RunSignals> = runs.iter().filter(|r| r.fold != f).collect();
                let held = runs
                    .iter()
                    .enumerate()
                    .filter(|(_, s)| s.fold == f)
                    .map(|(i, s)| (i, SlipData::from_runs(&[s])))
                    .collect();
                (SlipData::from_runs_spaced(&train, spacing_s), held)
            })
            .collect()
    }

    fn assemble(&self, per_fold: Vec<FoldFriction>) -> FrictionCv {
        let mut out = FrictionCv {
            e_mu: vec![None; self.runs.len()],
            models: Vec::new(),
            phases: vec![(0.0, 0.0); self.runs.len()],
        };
        for (model, held) in per_fold {
            out.models.push(model);
            for (i, e, ph) in held {
                out.e_mu[i] = e;
                out.phases[i] = ph;
            }
        }
        out
    }

    /// Fold `f`'s drive fit: the PI (with its own limit when `limit`, else
    /// saturating at the supply) fitted on the other folds' drive runs (the
    /// brake open or applied), and each held-out unit's relative voltage
    /// error under it (∞ without a fit).
    fn fold_drive(&self, limit: bool, f: usize) -> FoldDrive {
        let train = self.drive_train(f);
        let pi =
            if limit { drive::fit_limit_gains(&train, self.supply_v) } else { drive::fit_gains(&train, self.supply_v) };
        let held = self
            .runs
            .iter()
            .enumerate()
            .filter(|(_, s)| s.fold == f)
            .map(|(i, s)| {
                (i, pi.as_ref().map_or(f64::INFINITY, |pi| drive::relative_voltage_error(pi, s, self.supply_v)))
            })
            .collect();
        (pi, held)
    }

    /// The drive channel of every run from its fold's fit (`per_fold[f]`).
    fn assemble_drive(&self, per_fold: &[&FoldDrive]) -> DriveCv {
        let mut e_v = vec![f64::INFINITY; self.runs.len()];
        for (_, held) in per_fold {
            for &(i, e) in held {
                e_v[i] = e;
            }
        }
        DriveCv { e_v, pis: per_fold.iter().map(|d| d.0).collect() }
    }
}

/// The parameters of effect `e` among a fit's (term, JSON key, value,
/// standard error), each key once, in the fit's order.
fn params_of(fitted: &[(Term, &'static str, f64, f64)], e: EffectId) -> Vec<(&'static str, f64, f64)> {
    let mut out: Vec<(&'static str, f64, f64)> = Vec::new();
    for &(term, k, v, s) in fitted {
        if term == e.term() && !out.iter().any(|p| p.0 == k) {
            out.push((k, v, s));
        }
    }
    out
}

/// M_r = sqrt((e_μ² + e_V²)/2), or e_V without slip samples (crate docs).
fn combine(e_mu: Option<f64>, e_v: f64) -> f64 {
    match e_mu {
        Some(m) => ((m * m + e_v * e_v) / 2.0).sqrt(),
        None => e_v,
    }
}

/// √(mean M²) of per-run misfits: the engine's ([`rig_types::select::overall`]).
pub(crate) use rig_types::select::overall;

fn noise_floor_parts(s: &RunSignals, supply_v: f64) -> (Option<f64>, f64) {
    let mean_mu = if s.mu_obs.is_empty() { 0.0 } else { s.mu_obs.iter().sum::<f64>() / s.mu_obs.len() as f64 };
    let e_v = s.voltage_noise_v / supply_v;
    if s.mu_obs.is_empty() || mean_mu.abs() < 1e-9 {
        (None, e_v)
    } else {
        (Some(s.force_noise_n / s.normal_force_n / mean_mu.abs()), e_v)
    }
}

/// The comparison of a model with the one before it (crate docs: the
/// criterion): the one step rule of every rig, [`rig_types::select`].
pub(crate) use rig_types::select::Comparison;

fn compare(before: &[f64], after: &[f64], runs: &[RunSignals], folds: usize) -> Comparison {
    let fold_of: Vec<usize> = runs.iter().map(|s| s.fold).collect();
    compare_folds(before, after, &fold_of, folds)
}

/// The comparison of per-run misfits `before` and `after` (same run order),
/// `fold_of[r]` the fold run r is held out in: overall misfits, relative
/// gain with its spread across folds, and the paired run-level t of
/// ln(M_before/M_after) (crate docs: the criterion), computed by the one
/// engine's [`rig_types::select::compare`]. The structural candidates'
/// free-run misfits are compared by the same rule.
pub(crate) fn compare_folds(before: &[f64], after: &[f64], fold_of: &[usize], folds: usize) -> Comparison {
    rig_types::select::compare(before, after, fold_of, folds)
}

/// The whole selection on prepared signals that every channel reads (no
/// run with the brake open: [`select_effects`] splits a campaign's). `thesis_mu_dynamic` (Table 4.7)
/// adds the thesis rung to the ladder; `channel_checks` are the significant
/// mismatches found in the other run kinds (static twist, voltage steps,
/// free-run operating points), each "run_kind: sentence". The candidates are
/// the vocabulary's [`REGISTRY`].
pub fn diagnose_signals(
    campaign: &str,
    runs: &[RunSignals],
    supply_v: f64,
    disc_radius_m: f64,
    thesis_mu_dynamic: Option<f64>,
    channel_checks: &[(String, String)],
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    Ok(select_over(REGISTRY, campaign, runs, supply_v, opts)?.conclude(
        campaign,
        disc_radius_m,
        thesis_mu_dynamic,
        channel_checks,
        opts,
    ))
}

/// The forward selection over the vocabulary's [`REGISTRY`]: what the
/// findings are, before any check of another run kind is known (the
/// findings do not depend on them: [`Selection::conclude`] turns the same
/// selection into a diagnosis for each set of flagged checks, so the
/// diagnosis that learns of a free-run flag after simulating the final
/// model does not select again). The units are the friction channel's runs
/// ([`PreparedRuns::friction_units`]); the drive channel's fits read its own
/// ([`PreparedRuns::drive_units`], the runs with the brake open too).
pub fn select_effects<'a>(
    campaign: &str,
    runs: &'a PreparedRuns,
    supply_v: f64,
    opts: &DiagnoseOptions,
) -> Result<Selection<'a>, DiagnoseError> {
    select_split(REGISTRY, campaign, runs.friction_units(), runs.drive_units(), supply_v, opts)
}

/// [`diagnose_signals`] with the candidates of `registry` (in its order),
/// on runs that every channel reads (built by hand: no brake open).
pub(crate) fn select_over<'a>(
    registry: &'static [&'static dyn VocabularyEffect],
    campaign: &str,
    runs: &'a [RunSignals],
    supply_v: f64,
    opts: &DiagnoseOptions,
) -> Result<Selection<'a>, DiagnoseError> {
    select_split(registry, campaign, runs, runs, supply_v, opts)
}

/// The selection with `runs` its units and the friction channel's runs,
/// and `drive_runs` the drive channel's (`runs` first: a prefix of it).
fn select_split<'a>(
    registry: &'static [&'static dyn VocabularyEffect],
    campaign: &str,
    runs: &'a [RunSignals],
    drive_runs: &'a [RunSignals],
    supply_v: f64,
    opts: &DiagnoseOptions,
) -> Result<Selection<'a>, DiagnoseError> {
    assert!(
        drive_runs.len() >= runs.len() && std::ptr::eq(drive_runs.as_ptr(), runs.as_ptr()),
        "the drive channel's runs start with the selection's units"
    );
    let folds = opts.folds.min(runs.len());
    if runs.len() < 3 || folds < 2 {
        return Err(DiagnoseError::TooFewRuns { campaign: campaign.into(), needed: 3, found: runs.len() });
    }
    // Every run's slip samples (the joint fits' and the check's).
    let all: Vec<&RunSignals> = runs.iter().collect();
    let d_all = SlipData::from_runs(&all);
    if d_all.len() < 10 {
        return Err(DiagnoseError::Singular("no slip samples in the operating points: μk cannot be fitted"));
    }
    let freqs: Vec<f64> = {
        let n = ((opts.freq_max_hz - opts.freq_min_hz) / opts.freq_step_hz).floor() as usize;
        (0..=n).map(|j| opts.freq_min_hz + opts.freq_step_hz * j as f64).collect()
    };
    let fold_data = Cv::fold_data(runs, folds, opts.fold_fit_spacing_s);
    let cold = (0..folds).map(|_| composite::DataMemo::default()).collect();
    let held_memos = fold_data.iter().map(|f| composite::HeldRuns::new(f.1.len())).collect();
    let cv = Cv { runs, drive_runs, folds, supply_v, freqs, max_order: opts.max_order, fold_data, cold, held_memos };

    // Forward selection on the one engine: the runs are the units, fold f
    // holds out the runs of fold f and trains on the others; the baseline
    // (Coulomb μk, the PI saturating at the supply) fitted on each.
    let engine_folds: Vec<Fold> = (0..folds)
        .map(|f| {
            let (held_out, train): (Vec<usize>, Vec<usize>) = (0..runs.len()).partition(|&r| runs[r].fold == f);
            Fold { train, held_out }
        })
        .collect();
    let study = Vocabulary {
        cv: &cv,
        frictions: Mutex::default(),
        drives: Mutex::default(),
        d_all: &d_all,
        all_fits: Mutex::default(),
    };
    let baselines: Vec<FoldModel> = (0..folds)
        .into_par_iter()
        .map(|f| {
            let set = ModelSet::default();
            let (friction, drive) = rayon::join(|| study.friction(set.friction, f, None), || study.drive(set.limit, f));
            FoldModel { set, fold: f, friction, drive }
        })
        .collect();
    let effects: Vec<Effect> = registry.iter().map(|e| Effect(EffectId(*e))).collect();
    let candidates: Vec<&dyn engine::Candidate<Vocabulary, FoldModel>> =
        effects.iter().map(|e| e as &dyn engine::Candidate<Vocabulary, FoldModel>).collect();
    // Runs in campaign order (the stratified folds interleave them).
    let search = engine::Search { units_ascending: true, ..engine::Search::default() };
    let sel = engine::forward_select_from(&study, &candidates, &baselines, &engine_folds, &opts.selection, &search)
        .map_err(|e| DiagnoseError::Selection(e.to_string()))?;

    // The trace, as the report prints it.
    let effect = |t: &engine::Trial<FoldModel>| EffectId(registry[t.candidate]);
    let steps: Vec<StepRow> = sel.trials.iter().map(StepRow::from).collect();
    let first_step: Vec<(EffectId, Comparison, Vec<f64>)> =
        sel.step(1).map(|t| (effect(t), t.comparison, t.misfits.clone())).collect();
    let accepted: Vec<(EffectId, Comparison)> =
        sel.chosen.iter().map(|&i| (effect(&sel.trials[i]), sel.trials[i].comparison)).collect();
    let current = sel.final_models[0].set;
    // Every channel the selection fitted, by friction set and by limit (the
    // conclusion, the second look and `admit` read them).
    let mut fr_cache: BTreeMap<FrictionSet, FrictionCv> = BTreeMap::new();
    let mut dr_cache: BTreeMap<bool, DriveCv> = BTreeMap::new();
    for models in std::iter::once(&baselines).chain(sel.trials.iter().map(|t| &t.fitted)) {
        let Some(m) = models.first() else { continue };
        fr_cache
            .entry(m.set.friction)
            .or_insert_with(|| cv.assemble(models.iter().map(|m| (*m.friction).clone()).collect()));
        dr_cache
            .entry(m.set.limit)
            .or_insert_with(|| cv.assemble_drive(&models.iter().map(|m| &*m.drive).collect::<Vec<_>>()));
    }
    let (base_ms, cur_ms) = (sel.baseline_misfits, sel.final_misfits);

    // Final joint fit on every run for the reported parameters.
    let mut full = study
        .fit_all(current.friction)
        .ok_or(DiagnoseError::Singular("the joint fit of the retained friction effects"))?;
    composite::inflate_errors(&d_all, &mut full);
    drop(study);
    // The drive's joint fits on every drive run (the brake open or applied).
    let all_drive: Vec<&RunSignals> = drive_runs.iter().collect();
    let limit_fit = if current.limit { drive::fit_limit(&all_drive, supply_v) } else { None };
    let pi_base =
        drive::fit_gains(&all_drive, supply_v).ok_or(DiagnoseError::Singular("PI gains of the baseline drive"))?;
    let coulomb = composite::fit_composite(&d_all, FrictionSet::default(), &[], opts.max_order)
        .ok_or(DiagnoseError::Singular("the Coulomb baseline"))?;
    Ok(Selection {
        registry,
        runs,
        supply_v,
        cv,
        fr_cache,
        dr_cache,
        current,
        base_ms,
        cur_ms,
        accepted,
        steps,
        first_step,
        full,
        limit_fit,
        pi_base,
        coulomb,
        d_all,
    })
}

/// What the forward selection found ([`select_effects`]), ready to be
/// concluded against the checks of the other run kinds.
pub struct Selection<'a> {
    registry: &'static [&'static dyn VocabularyEffect],
    runs: &'a [RunSignals],
    supply_v: f64,
    cv: Cv<'a>,
    fr_cache: BTreeMap<FrictionSet, FrictionCv>,
    dr_cache: BTreeMap<bool, DriveCv>,
    current: ModelSet,
    base_ms: Vec<f64>,
    cur_ms: Vec<f64>,
    accepted: Vec<(EffectId, Comparison)>,
    steps: Vec<StepRow>,
    first_step: Vec<(EffectId, Comparison, Vec<f64>)>,
    full: CompositeFit,
    limit_fit: Option<(Pi, f64, usize, f64)>,
    pi_base: Pi,
    coulomb: CompositeFit,
    d_all: SlipData,
}

/// Every effect of a fold's model with its parameters, fitted without that fold.
pub type FoldEffects = Vec<(EffectId, BTreeMap<String, f64>)>;

/// An effect the teacher-forced rule saw but did not admit, with what a
/// free run needs to judge it (the second look, [`crate::second_look`]):
/// the step's teacher-forced comparison, per fold every effect of the model
/// with it and their parameters fitted without that fold, and per run
/// (campaign order) its fold and its nuisance phases under that fold's model.
pub struct NearMiss {
    pub effect: EffectId,
    pub teacher_forced: Comparison,
    pub per_fold: Vec<Option<FoldEffects>>,
    pub per_run: Vec<Option<(usize, Phases)>>,
}

impl Selection<'_> {
    /// The effects the last selection step tried and refused although its
    /// paired run-level t passed `min_t` with a positive gain (below the
    /// minimum gain) and whose fit on every run is admissible: the
    /// candidates of the free-run second look (crate docs). Each with its
    /// fold fits (the model with it, fitted without each fold).
    pub fn near_misses(&self, opts: &DiagnoseOptions) -> Vec<NearMiss> {
        let last = self.steps.iter().map(|r| r.step).max().unwrap_or(0);
        let mut out = Vec::new();
        for row in self.steps.iter().filter(|r| r.step == last && !r.accepted) {
            let Some(e) = EffectId::from_id(&row.effect) else { continue };
            if !(row.t >= opts.selection.min_t && row.gain > 0.0 && row.misfit_after.is_finite()) {
                continue;
            }
            let set = self.current.with(e);
            // The rule reads the model alone (`fit_composite_model`: the same model to the bit).
            let mut fit_all =
                || composite::fit_composite_model(&self.d_all, set.friction, &self.cv.freqs, self.cv.max_order);
            if e.inadmissible(&mut fit_all).is_some() {
                continue;
            }
            let effects: Vec<EffectId> = self.accepted.iter().map(|a| a.0).chain([e]).collect();
            let mut per_run: Vec<Option<(usize, Phases)>> = vec![None; self.runs.len()];
            let mut per_fold = vec![None; self.cv.folds];
            let fits: Vec<_> = (0..self.cv.folds)
                .into_par_iter()
                .map(|f| {
                    let fit = composite::fit_composite(
                        &self.cv.fold_data[f].0,
                        set.friction,
                        &self.cv.freqs,
                        self.cv.max_order,
                    )?;
                    let limit = match set.limit {
                        true => Some(self.dr_cache.get(&true)?.pis.get(f).copied().flatten()?),
                        false => None,
                    };
                    Some((fit, limit))
                })
                .collect();
            for (f, fit) in fits.iter().enumerate() {
                let Some((fit, limit)) = fit else { continue };
                let fitted: Vec<(Term, &'static str, f64, f64)> = fit
                    .params
                    .iter()
                    .map(|&(t, k, v, s)| (Term::Friction(t), k, v, s))
                    .chain(limit.map(|pi| (Term::DriveLimit, drive::LIMIT_PARAM, pi.limit_v, 0.0)))
                    .collect();
                per_fold[f] = Some(
                    effects
                        .iter()
                        .map(|&x| (x, params_of(&fitted, x).into_iter().map(|(k, v, _)| (k.to_string(), v)).collect()))
                        .collect(),
                );
                for (i, d) in &self.cv.fold_data[f].1 {
                    per_run[*i] = Some((f, composite::heldout_phases(&fit.model, d)));
                }
            }
            let teacher_forced = Comparison {
                before: row.misfit_before,
                after: row.misfit_after,
                gain: row.gain,
                gain_fold_sd: row.gain_fold_sd,
                t: row.t,
            };
            out.push(NearMiss { effect: e, teacher_forced, per_fold, per_run });
        }
        out
    }

    /// Admits `e` (a [`NearMiss`] the free run passed, lib.rs) with its
    /// teacher-forced comparison: the selection as if its step had accepted
    /// it, the final joint fit refitted on every run.
    pub fn admit(&mut self, e: EffectId, teacher_forced: Comparison, opts: &DiagnoseOptions) {
        let set = self.current.with(e);
        let (Some(fr), Some(dr)) = (self.fr_cache.get(&set.friction), self.dr_cache.get(&set.limit)) else { return };
        let Some(full) = composite::fit_composite(&self.d_all, set.friction, &self.cv.freqs, opts.max_order) else {
            return;
        };
        self.cur_ms = fr.e_mu.iter().zip(&dr.e_v).map(|(a, b)| combine(*a, *b)).collect();
        if set.limit && !self.current.limit {
            let all_drive: Vec<&RunSignals> = self.cv.drive_runs.iter().collect();
            self.limit_fit = drive::fit_limit(&all_drive, self.supply_v);
        }
        self.current = set;
        self.full = full;
        self.accepted.push((e, teacher_forced));
    }
}
