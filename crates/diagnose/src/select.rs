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
//! channel's fit on the fold's training runs. What keeps it fast lives in the
//! study (`Vocabulary`): a channel's fit is shared by every model with the
//! same friction set or the same drive limit, and each friction fit is
//! warm-started from the current model's fit of the same fold. The engine
//! fits every (candidate, fold) as a task of its own, so a step's 3–4
//! friction sets × 5 folds keep two cores evenly busy. The engine's trace
//! is the report's (`StepRow`s).

use crate::composite::{self, Composite, CompositeFit, FrictionSet, Phases};
use crate::drive::{self, Pi};
use crate::effects::{EffectId, NONE, REGISTRY, Term, UNEXPLAINED, VocabularyEffect};
use crate::friction::SlipData;
use crate::lines;
use crate::prepare::RunSignals;
use crate::result::MuBin;
use crate::result::{
    Adequacy, CandidateScore, Detail, Diagnosis, Features, Finding, RunRow, SignatureEntry, StepRow, round_sig,
};
use crate::signature::{self, Library, Samples};
use crate::{DiagnoseError, DiagnoseOptions};
use rayon::prelude::*;
use rig_spectra::{LineAnalysisOptions, line_analysis};
use rig_sweep::ClassifyOptions;
use rig_types::select::{self as engine, Fold};
use std::collections::BTreeMap;
use std::f64::consts::PI;
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
    runs: &'a [RunSignals],
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
    /// Per fold, the cold Stribeck fits of its training data, shared by
    /// every friction set whose first pass starts from them
    /// ([`composite::ColdStribeck`]).
    cold: Vec<composite::ColdStribeck>,
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

    /// The joint fit of `set` on every run (memoised).
    fn fit_all(&self, set: FrictionSet) -> Option<CompositeFit> {
        if let Some(fit) = self.all_fits.lock().expect("joint fits").get(&set) {
            return fit.clone();
        }
        let fit = composite::fit_composite(self.d_all, set, &self.cv.freqs, self.cv.max_order);
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
    fn train(&self, f: usize) -> Vec<&RunSignals> {
        self.runs.iter().filter(|r| r.fold != f).collect()
    }

    /// Fold `f`'s friction fit: the model of `set` fitted on the other folds
    /// (warm-started from `start`, [`composite::fit_composite_model_from`]),
    /// and each held-out run's μ error and phases under it.
    fn fold_friction(&self, set: FrictionSet, f: usize, start: Option<&Composite>) -> FoldFriction {
        let (d, held_data) = &self.fold_data[f];
        let model =
            composite::fit_composite_model_from_cached(d, set, &self.freqs, self.max_order, start, &self.cold[f]);
        let mut held = Vec::new();
        for (i, dr) in held_data {
            let (e, ph) = match &model {
                Some(m) => composite::heldout_fit(m, dr),
                None => (None, (0.0, 0.0)),
            };
            held.push((*i, e, ph));
        }
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
    /// saturating at the supply) fitted on the other folds, and each held-out
    /// run's relative voltage error under it (∞ without a fit).
    fn fold_drive(&self, limit: bool, f: usize) -> FoldDrive {
        let train = self.train(f);
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

/// Measured features of one run's steady state.
pub fn measured_features(s: &RunSignals, slip_speed_rad_s: f64, classify: &ClassifyOptions) -> Features {
    steady_features(
        &s.time_s[s.steady_from..],
        &s.rotor_speed_rad_s[s.steady_from..],
        &s.motor_speed_rad_s[s.steady_from..],
        s.setpoint_rad_s,
        slip_speed_rad_s,
        classify,
    )
}

/// The line analysis of a steady window's rotor speed (`rig_spectra::line_analysis`):
/// 0.05 Hz (above the drift of a window of ≥ 20 s, below the slowest stick-slip
/// of the rig, ≈ 0.3 Hz) to 5 Hz (the stick-slip fundamentals and their first
/// harmonics; the differentiator smooths above); 0.1 bin, as the `spectra`
/// stage for the same signals: the tolerance is then the peak's own 3σ_f.
const STEADY_LINES: LineAnalysisOptions =
    LineAnalysisOptions { min_freq_hz: 0.05, max_freq_hz: 5.0, tolerance_bins: 0.1 };

/// Features of a steady-state record (shared by measured and simulated runs).
pub fn steady_features(
    t: &[f64],
    w1: &[f64],
    w2: &[f64],
    setpoint_rad_s: f64,
    slip_speed_rad_s: f64,
    classify: &ClassifyOptions,
) -> Features {
    if t.len() < 16 {
        return Features::default();
    }
    let fs_hz = (t.len() - 1) as f64 / (t[t.len() - 1] - t[0]);
    let stick_slip = rig_sweep::classify(w1, fs_hz, classify).regime.stick_slip();
    let stuck = w1.iter().filter(|w| w.abs() < slip_speed_rad_s).count() as f64 / w1.len() as f64;
    let min = w1.iter().copied().fold(f64::INFINITY, f64::min);
    let max = w1.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let dip = w2.iter().map(|w| setpoint_rad_s - w).fold(0.0_f64, f64::max);
    // Fundamental: f0 of the line analysis of Ω1 when Ω1 swings more than the slip speed.
    let n = w1.len() as f64;
    let mean = w1.iter().sum::<f64>() / n;
    let var = w1.iter().map(|w| (w - mean).powi(2)).sum::<f64>() / n;
    let fundamental_hz = if var.sqrt() > slip_speed_rad_s {
        line_analysis(w1, fs_hz, &STEADY_LINES).ok().and_then(|sl| sl.lines.f0_hz).unwrap_or(0.0)
    } else {
        0.0
    };
    Features {
        stuck_fraction: stuck,
        stick_slip,
        rotor_min_rad_s: min,
        rotor_max_rad_s: max,
        fundamental_hz,
        motor_dip_rad_s: dip,
    }
}

/// Residual samples of the final model in both channels, for the signature.
fn residual_samples(cv: &Cv, fr: &FrictionCv, dr: &DriveCv, disc_radius_m: f64) -> (Samples, Samples) {
    let per_run: Vec<(Samples, Samples)> = cv
        .runs
        .par_iter()
        .enumerate()
        .map(|(r, s)| {
            let lib = Library::of(s, disc_radius_m);
            let mut mu = Samples::default();
            if let Some(m) = fr.models[s.fold].as_ref() {
                for (j, &k) in s.slip_idx.iter().enumerate().step_by(5) {
                    let mh = m.mu(s.time_s[k], s.rotor_angle_rad[k], s.rotor_speed_rad_s[k].abs(), fr.phases[r]);
                    if mh.abs() < 1e-9 {
                        continue;
                    }
                    mu.run.push(r);
                    mu.fold.push(s.fold);
                    mu.x.push(lib.row(k));
                    mu.y.push(s.mu_obs[j] / mh - 1.0);
                    mu.scale.push(mh);
                }
            }
            let mut v = Samples::default();
            if let Some(pi) = dr.pis[s.fold].as_ref() {
                let (vh, _, _) = drive::predict_voltage(pi, s);
                for k in (0..s.time_s.len()).step_by(10) {
                    v.run.push(r);
                    v.fold.push(s.fold);
                    v.x.push(lib.row(k));
                    v.y.push((s.voltage_v[k] - vh[k]) / cv.supply_v);
                    v.scale.push(1.0);
                }
            }
            (mu, v)
        })
        .collect();
    let mut mu = Samples::default();
    let mut v = Samples::default();
    for (a, b) in per_run {
        for (dst, src) in [(&mut mu, a), (&mut v, b)] {
            dst.run.extend(src.run);
            dst.fold.extend(src.fold);
            dst.x.extend(src.x);
            dst.y.extend(src.y);
            dst.scale.extend(src.scale);
        }
    }
    (mu, v)
}

/// Binned mean residual against the best signal, training folds and the held-out fold 0 apart.
fn signature_curve(s: &Samples, col: usize) -> Vec<(f64, f64, bool)> {
    if s.y.is_empty() {
        return vec![];
    }
    let lo = s.x.iter().map(|r| r[col]).fold(f64::INFINITY, f64::min);
    let hi = s.x.iter().map(|r| r[col]).fold(f64::NEG_INFINITY, f64::max);
    if hi <= lo {
        return vec![];
    }
    let nb = 24;
    let mut out = Vec::new();
    for held in [false, true] {
        let mut acc = vec![(0.0, 0usize); nb];
        for i in 0..s.y.len() {
            if (s.fold[i] == 0) != held {
                continue;
            }
            let b = (((s.x[i][col] - lo) / (hi - lo) * nb as f64) as usize).min(nb - 1);
            acc[b].0 += s.y[i];
            acc[b].1 += 1;
        }
        for (b, a) in acc.iter().enumerate() {
            if a.1 >= 10 {
                out.push((lo + (b as f64 + 0.5) * (hi - lo) / nb as f64, a.0 / a.1 as f64, held));
            }
        }
    }
    out
}

/// The whole selection on prepared signals. `thesis_mu_dynamic` (Table 4.7)
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
    Ok(select_effects(campaign, runs, supply_v, opts)?.conclude(
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
/// model does not select again).
pub fn select_effects<'a>(
    campaign: &str,
    runs: &'a [RunSignals],
    supply_v: f64,
    opts: &DiagnoseOptions,
) -> Result<Selection<'a>, DiagnoseError> {
    select_over(REGISTRY, campaign, runs, supply_v, opts)
}

/// [`diagnose_signals`] with the candidates of `registry` (in its order).
pub(crate) fn select_over<'a>(
    registry: &'static [&'static dyn VocabularyEffect],
    campaign: &str,
    runs: &'a [RunSignals],
    supply_v: f64,
    opts: &DiagnoseOptions,
) -> Result<Selection<'a>, DiagnoseError> {
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
    let cold = (0..folds).map(|_| composite::ColdStribeck::default()).collect();
    let cv = Cv { runs, folds, supply_v, freqs, max_order: opts.max_order, fold_data, cold };

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
    let full = study
        .fit_all(current.friction)
        .ok_or(DiagnoseError::Singular("the joint fit of the retained friction effects"))?;
    drop(study);
    let limit_fit = if current.limit { drive::fit_limit(&all, supply_v) } else { None };
    let pi_base = drive::fit_gains(&all, supply_v).ok_or(DiagnoseError::Singular("PI gains of the baseline drive"))?;
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
            let fit_all = || composite::fit_composite(&self.d_all, set.friction, &self.cv.freqs, self.cv.max_order);
            if e.inadmissible(&mut || fit_all().map(|f| f.model)).is_some() {
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
            let all: Vec<&RunSignals> = self.runs.iter().collect();
            self.limit_fit = drive::fit_limit(&all, self.supply_v);
        }
        self.current = set;
        self.full = full;
        self.accepted.push((e, teacher_forced));
    }
}

impl Selection<'_> {
    /// The diagnosis of this selection given the significant checks of the
    /// other run kinds (`channel_checks`: (run kind, text)): adequacy, the
    /// `unexplained` finding and its signature, the report's detail.
    pub fn conclude(
        &self,
        campaign: &str,
        disc_radius_m: f64,
        thesis_mu_dynamic: Option<f64>,
        channel_checks: &[(String, String)],
        opts: &DiagnoseOptions,
    ) -> Diagnosis {
        let Selection {
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
        } = self;
        let (registry, runs, supply_v, current) = (*registry, *runs, *supply_v, *current);
        let folds = cv.folds;
        let all: Vec<&RunSignals> = runs.iter().collect();
        let significant = |c: &Comparison| opts.selection.admits(c);

        // Adequacy: the final model against noise, and the other run kinds.
        let floor_parts: Vec<(Option<f64>, f64)> = runs.iter().map(|s| noise_floor_parts(s, supply_v)).collect();
        let floor_ms: Vec<f64> = floor_parts.iter().map(|(a, b)| combine(*a, *b)).collect();
        let floor_m = overall(&floor_ms);
        let final_m = overall(cur_ms);
        let ratio = final_m / floor_m;
        let fr_final = fr_cache.get(&current.friction).expect("evaluated").clone();
        let dr_final = dr_cache.get(&current.limit).expect("evaluated").clone();
        let ch_mu = {
            let e: Vec<f64> = fr_final.e_mu.iter().flatten().copied().collect();
            let f: Vec<f64> = floor_parts.iter().filter_map(|p| p.0).collect();
            overall(&e) / overall(&f)
        };
        let ch_v = overall(&dr_final.e_v) / overall(&floor_parts.iter().map(|p| p.1).collect::<Vec<_>>());
        let all_lines: Vec<lines::OrderLine> = runs
            .par_iter()
            .map(|s| {
                let mut v = lines::order_lines(s, true, opts.max_order);
                v.extend(lines::order_lines(s, false, opts.max_order));
                v
            })
            .collect::<Vec<_>>()
            .into_iter()
            .flatten()
            .collect();
        // Lines a fitted effect drives (an angle-locked friction of order n: order
        // n and its harmonics, in either speed) are explained, not left over.
        let explained_order = registry.iter().find_map(|e| e.explained_order(&full.model));
        let consistent: Vec<lines::ConsistentLine> = lines::consistent_lines(&all_lines, opts.line_ratio)
            .into_iter()
            .filter(|l| explained_order.is_none_or(|n| l.order % n != 0))
            .collect();
        let line_text: Vec<String> = consistent
            .iter()
            .map(|l| {
                format!(
                    "{} speed has an order-{} line (per {} revolution) in {}/{} runs, median {:.0}× the local floor",
                    l.channel, l.order, l.channel, l.runs_significant, l.runs_tested, l.median_ratio
                )
            })
            .collect();
        let adequate = ratio <= opts.adequacy_ratio && consistent.is_empty() && channel_checks.is_empty();
        let adequacy = Adequacy {
            residual_over_noise: round_sig(ratio, 3),
            threshold: opts.adequacy_ratio,
            order_lines: consistent.len(),
            channel_checks: channel_checks.iter().filter(|(k, _)| k != "free_run").count(),
            free_run_checks: channel_checks.iter().filter(|(k, _)| k == "free_run").count(),
            adequate,
        };

        let run_ids: Vec<String> = runs.iter().map(|s| s.id.clone()).collect();
        // Every fitted parameter of the final model, by the term that fitted it.
        let fitted: Vec<(Term, &str, f64, f64)> = full
            .params
            .iter()
            .map(|&(t, k, v, s)| (Term::Friction(t), k, v, s))
            .chain(limit_fit.map(|(pi, _, _, s)| (Term::DriveLimit, drive::LIMIT_PARAM, pi.limit_v, s)))
            .collect();
        let mut findings = Vec::new();
        for (e, c) in accepted {
            let mut params = BTreeMap::new();
            let mut se = BTreeMap::new();
            let mut ptext = Vec::new();
            for (k, v, s) in params_of(&fitted, *e) {
                params.insert(k.to_string(), round_sig(v, 4));
                se.insert(k.to_string(), round_sig(s, 2));
                ptext.push((k, v));
            }
            findings.push(Finding {
                effect: e.id().into(),
                params,
                params_stderr: se,
                evidence: evidence(e.0, &ptext, c),
                heldout_runs: run_ids.clone(),
                heldout_misfit_baseline: round_sig(c.before, 4),
                heldout_misfit_extended: round_sig(c.after, 4),
                relative_gain: round_sig(c.gain, 4),
                relative_gain_fold_sd: round_sig(c.gain_fold_sd, 2),
                criterion: Some(round_sig(-c.t, 4)),
                ..Default::default()
            });
        }

        // What is left: the signature of the final model's residual.
        let mut detail = Detail { folds, ..Default::default() };
        let mut verdict = accepted.first().map(|a| a.0.id().to_string()).unwrap_or_else(|| NONE.into());
        let mut ext_ms = cur_ms.clone();
        if !adequate {
            let (mu_s, v_s) = residual_samples(cv, &fr_final, &dr_final, disc_radius_m);
            let sig_mu = signature::channel_signature(&mu_s, "friction", folds, runs.len(), opts.signature_threshold);
            let sig_v = signature::channel_signature(&v_s, "drive", folds, runs.len(), opts.signature_threshold);
            // Best data-driven extension: each channel corrected by its sparse model, per run.
            ext_ms = (0..runs.len())
                .map(|r| {
                    let e_mu = fr_final.e_mu[r].map(|e| e * sig_mu.run_factor[r].max(0.0).sqrt());
                    combine(e_mu, dr_final.e_v[r] * sig_v.run_factor[r].max(0.0).sqrt())
                })
                .collect();
            let mut terms: Vec<signature::Term> =
                sig_mu.terms.iter().chain(sig_v.terms.iter()).filter(|t| t.heldout_gain > 0.0).cloned().collect();
            terms.sort_by(|a, b| b.heldout_gain.total_cmp(&a.heldout_gain).then(a.signal.cmp(b.signal)));
            if let Some(t0) = terms.first() {
                let (s, _) = if t0.channel == "friction" { (&mu_s, ()) } else { (&v_s, ()) };
                let col = signature::SIGNALS.iter().position(|x| *x == t0.signal).expect("library signal");
                detail.signature_curve = signature_curve(s, col);
            }
            detail.signature_gain = sig_mu.combined_gain.max(sig_v.combined_gain);
            let mut where_: Vec<String> = Vec::new();
            if ratio > opts.adequacy_ratio || !consistent.is_empty() {
                where_.push("operating_point".into());
            }
            for (kind, _) in channel_checks {
                if !where_.contains(kind) {
                    where_.push(kind.clone());
                }
            }
            let mut what = Vec::new();
            if ratio > opts.adequacy_ratio {
                what.push(format!(
                "the final model's cross-validated misfit is {:.1}× the noise floor (threshold {:.1}; friction channel \
                 {:.1}×, drive channel {:.1}×)",
                ratio, opts.adequacy_ratio, ch_mu, ch_v
            ));
            }
            what.extend(line_text.iter().take(2).cloned());
            what.extend(channel_checks.iter().take(3).map(|(k, t)| format!("{k}: {t}")));
            let signature_entries: Vec<SignatureEntry> = terms
            .iter()
            .take(4)
            .map(|t| SignatureEntry {
                signal: t.signal.into(),
                heldout_gain: round_sig(t.heldout_gain, 3),
                description: format!(
                    "{} residual changes by {:.3e} per unit of {} (±1 sd of the signal moves it by {:.3e}); a term in \
                     it removes {:.0} % of the held-out residual. Causes that leave this: {}.",
                    if t.channel == "friction" { "the relative friction-coefficient" } else { "the relative voltage" },
                    t.slope,
                    t.signal,
                    t.residual_sd,
                    100.0 * t.heldout_gain,
                    signature::causes(t.signal)
                ),
            })
            .collect();
            let explained = if findings.is_empty() {
                "No vocabulary effect earns its place".to_string()
            } else {
                format!(
                    "The vocabulary explains part of the mismatch ({})",
                    findings.iter().map(|f| f.effect.as_str()).collect::<Vec<_>>().join(", ")
                )
            };
            // A mismatch seen only in the free run, with the teacher-forced
            // channels within their noise: the residual signature describes
            // noise-level structure of those channels, not the motion's gap.
            let motion_only = ratio <= opts.adequacy_ratio
                && consistent.is_empty()
                && channel_checks.iter().all(|(k, _)| k == "free_run");
            let follows = match terms.first() {
                _ if motion_only => format!(
                    " The teacher-forced channels are within their noise ({ratio:.1}× the floor): the mismatch shows only \
                 in the motion, where the residual signature of those channels (listed, best {}) cannot see it.",
                    terms.first().map_or("none", |t| t.signal)
                ),
                Some(t) => format!(
                    " The leftover follows {} (held-out gain {:.0} %), pointing to {}.",
                    t.signal,
                    100.0 * t.heldout_gain,
                    signature::causes(t.signal)
                ),
                None => " No signal of the library explains the leftover on held-out runs.".into(),
            };
            findings.push(Finding {
                effect: UNEXPLAINED.into(),
                evidence: format!("{explained}, but {}.{follows}", what.join("; ")),
                residual_over_noise: Some(round_sig(ratio, 3)),
                where_,
                signature: signature_entries,
                heldout_runs: run_ids.clone(),
                heldout_misfit_baseline: round_sig(final_m, 4),
                heldout_misfit_extended: round_sig(overall(&ext_ms), 4),
                relative_gain: round_sig(1.0 - overall(&ext_ms) / final_m, 4),
                relative_gain_fold_sd: round_sig(compare(cur_ms, &ext_ms, runs, folds).gain_fold_sd, 2),
                criterion: None,
                ..Default::default()
            });
            detail.signature = terms;
            verdict = UNEXPLAINED.into();
        }

        let base_m = overall(base_ms);
        let mut candidates = Vec::new();
        for (e, c, _) in first_step {
            candidates.push(CandidateScore {
                effect: e.id().into(),
                heldout_misfit_extended: round_sig(c.after, 4),
                relative_gain: round_sig(c.gain, 4),
                relative_gain_fold_sd: round_sig(c.gain_fold_sd, 2),
                criterion: round_sig(-c.t, 4),
            });
            detail.scores.push((e.id().into(), -c.t, c.after, c.gain, significant(c), String::new()));
        }

        // Detail for the report.
        detail.steps = steps.clone();
        detail.heldout_misfit_baseline = base_m;
        detail.heldout_misfit_noise_floor = floor_m;
        detail.lines = line_text;
        detail.channel_over_noise = (ch_mu, ch_v);
        detail.baseline_text = format!(
            "μk = {:.4} (Coulomb, all slip samples); voltage predictor kp = {:.3} V·s/rad, ki = {:.3} V/rad, limit {:.1} V \
         (supply). These gains are the best teacher-forced predictor of the recorded voltage from the measured, \
         differentiated motor speed: speed noise biases kp low (errors in variables), so they are not the drive's \
         physical gains, which estimation.md gives with that bias corrected",
            coulomb.model.mu_k, pi_base.kp_v_s_rad, pi_base.ki_v_rad, supply_v
        );
        if let Some(c) = full.scan.first().map(|_| &full.scan) {
            let worst = c.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
            detail.freq_scan = c.iter().map(|&(f, r)| (f, 1.0 - r / worst)).collect();
        } else if let Some(scan) = composite::coulomb_time_scan(d_all, &cv.freqs) {
            // The scan of the set {normal_force_modulation} alone, without its
            // fit at the best frequency (only the scan is drawn).
            let worst = scan.iter().map(|x| x.1).fold(f64::NEG_INFINITY, f64::max);
            detail.freq_scan = scan.iter().map(|&(f, r)| (f, 1.0 - r / worst)).collect();
        }
        for (r, s) in runs.iter().enumerate() {
            detail.runs.push(RunRow {
                id: s.id.clone(),
                fold: s.fold,
                normal_force_n: s.normal_force_n,
                motor_rpm_setpoint: rig_types::units::rad_s_to_rpm(s.setpoint_rad_s),
                slip_samples: s.slip_idx.len(),
                misfit_baseline: base_ms[r],
                misfit_extended: cur_ms[r],
                misfit_noise_floor: floor_ms[r],
                force_noise_n: s.force_noise_n,
                voltage_noise_v: s.voltage_noise_v,
                measured: measured_features(s, opts.slip_speed_rad_s, &opts.classify),
                simulated: None,
                extended: None,
                phases_rad: full.phases.get(r).copied().unwrap_or((0.0, 0.0)),
            });
        }
        detail.mu_vs_speed = mu_vs_speed(d_all, &coulomb.model, &full.model, &full.phases);
        detail.residual_vs_angle = residual_vs_angle(&all, coulomb.model.mu_k);
        if let Some(mu_dyn) = thesis_mu_dynamic {
            let thesis = Composite::coulomb(mu_dyn);
            let tm: Vec<f64> = runs
                .iter()
                .enumerate()
                .map(|(r, s)| {
                    let dr = SlipData::from_runs(&[s]);
                    combine(composite::relative_mu_error(&thesis, &dr, (0.0, 0.0)), dr_cache[&false].e_v[r])
                })
                .collect();
            detail.rungs.push((
                "thesis model as published".into(),
                overall(&tm),
                format!("Table 4.7 μ_dyn = {mu_dyn} in slip, drive saturating at the supply"),
            ));
        }
        detail.rungs.push((
            "rig model recalibrated".into(),
            base_m,
            format!("μk = {:.4} fitted on the campaign's slip samples", coulomb.model.mu_k),
        ));
        let mut names = Vec::new();
        for (e, c) in accepted {
            names.push(e.id());
            detail.rungs.push(("extended model".into(), c.after, format!("+ {}", names.join(" + "))));
        }
        if verdict == UNEXPLAINED {
            detail.rungs.push((
                "data-driven extension".into(),
                overall(&ext_ms),
                format!(
                    "+ sparse regression of the residual on {}",
                    detail.signature.iter().take(2).map(|t| t.signal).collect::<Vec<_>>().join(", ")
                ),
            ));
        }
        Diagnosis {
            campaign: campaign.into(),
            verdict,
            findings,
            candidates,
            adequacy,
            structure: Default::default(),
            parameters_at_bounds: Vec::new(),
            detail,
        }
    }
}

/// The evidence sentence: what the effect does in numbers (its own clause,
/// [`VocabularyEffect::evidence`]) and the criterion's numbers.
fn evidence(effect: &dyn VocabularyEffect, params: &[(&str, f64)], c: &Comparison) -> String {
    let p = |k: &str| params.iter().find(|x| x.0 == k).map(|x| x.1).unwrap_or(f64::NAN);
    let what = effect.evidence(&p);
    format!(
        "{what}; cross-validated misfit {:.4} → {:.4} (gain {:.1} % ± {:.1} % across folds, paired t = {:.1}).",
        c.before,
        c.after,
        100.0 * c.gain,
        100.0 * c.gain_fold_sd,
        c.t
    )
}

fn mu_vs_speed(d: &SlipData, base: &Composite, ext: &Composite, phases: &[Phases]) -> Vec<MuBin> {
    let wmax = d.omega.iter().copied().fold(0.0_f64, f64::max);
    if wmax <= 0.0 {
        return vec![];
    }
    let nb = 30;
    let mut acc = vec![(0.0, 0.0, 0.0, 0usize); nb];
    // Per bin and run: (Σμ, n), for the run-level spread of the bin mean.
    let mut per_run = vec![vec![(0.0, 0usize); d.n_runs]; nb];
    for i in 0..d.len() {
        let b = ((d.omega[i] / wmax * nb as f64) as usize).min(nb - 1);
        let ph = phases.get(d.run[i]).copied().unwrap_or((0.0, 0.0));
        acc[b].0 += d.mu[i];
        acc[b].1 += base.mu(d.t[i], d.phi[i], d.omega[i], (0.0, 0.0));
        acc[b].2 += ext.mu(d.t[i], d.phi[i], d.omega[i], ph);
        acc[b].3 += 1;
        per_run[b][d.run[i]].0 += d.mu[i];
        per_run[b][d.run[i]].1 += 1;
    }
    acc.iter()
        .zip(&per_run)
        .enumerate()
        .filter(|(_, (a, _))| a.3 >= 20)
        .map(|(b, (a, runs))| {
            // 95 % half-width with the run as the independent unit (samples of
            // one run are correlated): Student t over the runs' own bin means.
            let means: Vec<f64> = runs.iter().filter(|r| r.1 >= 5).map(|r| r.0 / r.1 as f64).collect();
            let k = means.len();
            let half = if k >= 2 {
                let m = means.iter().sum::<f64>() / k as f64;
                let sd = (means.iter().map(|x| (x - m).powi(2)).sum::<f64>() / (k - 1) as f64).sqrt();
                rig_calibrate::stats::student_t_quantile(0.975, (k - 1) as f64)
                    .map_or(f64::NAN, |t| t * sd / (k as f64).sqrt())
            } else {
                f64::NAN
            };
            MuBin {
                speed_rad_s: (b as f64 + 0.5) * wmax / nb as f64,
                measured: a.0 / a.3 as f64,
                baseline: a.1 / a.3 as f64,
                extended: a.2 / a.3 as f64,
                measured_half_width_95: half,
            }
        })
        .collect()
}

/// μ_obs − μk of the run with most slip in 72 bins of φ1 mod 2π, with the
/// interval the data support: the independent unit is one pass of the disc
/// through a bin (samples inside one pass are correlated), so each bin gives
/// the mean over revolutions of the per-revolution mean and ±1.96 standard
/// errors over those revolutions; bins seen on fewer than 3 revolutions are
/// left out. Rows: (bin centre rad, mean, lower, upper, revolutions).
fn residual_vs_angle(runs: &[&RunSignals], mu_k: f64) -> Vec<(f64, f64, f64, f64, usize)> {
    let Some(s) = runs.iter().max_by_key(|s| s.slip_idx.len()) else { return vec![] };
    let nb = 72;
    // (revolution, bin) -> (sum, count), in a fixed order.
    let mut per_pass: std::collections::BTreeMap<(i64, usize), (f64, usize)> = std::collections::BTreeMap::new();
    for (j, &k) in s.slip_idx.iter().enumerate() {
        let phi = s.rotor_angle_rad[k];
        let rev = (phi / (2.0 * PI)).floor() as i64;
        let a = phi.rem_euclid(2.0 * PI);
        let b = ((a / (2.0 * PI) * nb as f64) as usize).min(nb - 1);
        let e = per_pass.entry((rev, b)).or_insert((0.0, 0));
        e.0 += s.mu_obs[j] - mu_k;
        e.1 += 1;
    }
    let mut bins: Vec<Vec<f64>> = vec![Vec::new(); nb];
    for ((_, b), (sum, n)) in per_pass {
        bins[b].push(sum / n as f64);
    }
    bins.iter()
        .enumerate()
        .filter(|(_, v)| v.len() >= 3)
        .map(|(b, v)| {
            let n = v.len() as f64;
            let mean = v.iter().sum::<f64>() / n;
            let sd = (v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
            let half = 1.96 * sd / n.sqrt();
            ((b as f64 + 0.5) * 2.0 * PI / nb as f64, mean, mean - half, mean + half, v.len())
        })
        .collect()
}
