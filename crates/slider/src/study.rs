//! The study ([`run_study`]): measure every run, fit the Coulomb baseline on
//! the calibration stiffnesses, predict the held-out runs, then forward
//! selection on the workspace's one engine
//! ([`rig_types::select::forward_select_from`]: the Coulomb baseline fitted
//! on each training set, the pair step on): each step fits the current
//! model's extensions (a memory law in place of Coulomb, a set-up in place of
//! the README's m and k) fold by fold and keeps the best when its held-out
//! gain passes `[shared.selection]`; when none does, the best law and the
//! best set-up are tried together once.
//!
//! Held-out runs are the runs at a stiffness not in
//! `calibration_stiffnesses_n_m`. When there is none (the shipped folder with
//! the default list), every stiffness is held out in turn and the laws are
//! fitted on the others (leave one stiffness out); the study says which.

use crate::SliderError;
use crate::features::{FeatureOptions, Features, Regime, RunConstants, Spread, features, spectral_period_s};
use crate::fit::{
    CANDIDATES, Candidate, FitResult, FitTolerance, Model, SETUPS, SetupCandidate, StartHints,
    critical_stiffness_guess_n_m, fit, run_misfit,
};
use crate::sim::{Setup, simulate_more};
use rayon::prelude::*;
use rig_ingest::slider::{SliderRun, read_slider_folder};
use rig_model::one_dof::OneDofState;
use rig_types::select::{self as engine, Comparison, Fold};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// pipeline.toml's `[stage.params]` of the `slider` stage.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct StudyParams {
    /// The folder (`runs/k<k>-v<V>.csv`); `{shared}` is the shared folder.
    pub folder: String,
    /// Slider mass, kg (the data's README: 30.7 g).
    pub mass_kg: f64,
    pub gravity_m_s2: f64,
    /// Runs at these stiffnesses calibrate; every other run is held out.
    pub calibration_stiffnesses_n_m: Vec<f64>,
    /// Simulated time kept for the features: `sim_periods` measured periods,
    /// at least `sim_min_window_s`, at most `sim_max_window_s` and the record's length, s.
    pub sim_periods: f64,
    pub sim_min_window_s: f64,
    pub sim_max_window_s: f64,
    /// Periods a simulated stretch holds at least when its events do not
    /// repeat one cycle (the misfit reads their spread; [`predict`]).
    pub spread_periods: usize,
    /// Simulated time discarded before it, as a fraction of the window (the start from rest).
    pub warmup_fraction: f64,
    /// Integration steps per natural period.
    pub steps_per_period: f64,
    /// A fit runs Nelder–Mead from this many starts (the best-scored of the
    /// candidate's starts), the best result kept...
    pub fit_starts: usize,
    /// ...each for `fit_evals` evaluations when `fit_tolerance` is 0 (a
    /// fixed count: not converged, docs/findings.md); when it is above 0,
    /// each to convergence ([`crate::fit::FitTolerance`]: the simplex's
    /// misfits within `fit_tolerance`, the misfit's units, and its vertices
    /// within `fit_tolerance` of the bound widths, restarted until a restart
    /// gains at most `fit_tolerance`; `fit_evals` a safeguard per start),
    /// and from more starts in the order of their scores while the last one
    /// lowered the best misfit by more than `fit_tolerance`.
    pub fit_tolerance: f64,
    pub fit_evals: usize,
    /// Above 0 (and `fit_tolerance` 0): the `fit_starts` best-scored starts
    /// are raced ([`crate::fit::fit_race`]): each runs `fit_evals`
    /// evaluations, then the `fit_race_keep` best run on to `fit_race_evals`.
    pub fit_race_keep: usize,
    pub fit_race_evals: usize,
    /// An extension must pass the workspace's step rule (pipeline.toml's
    /// `[shared.selection]`, `rig_types::select::compare`: the campaign
    /// diagnosis' and the LAVI study's rule too)...
    pub selection: rig_types::contract::SelectionRule,
    /// ...and the model is adequate when its mean held-out misfit is at most
    /// this and it gets the regime of every held-out run right.
    pub adequacy_threshold: f64,
    /// The mains frequency of the lab, Hz: its line (the sensor's pick-up) is
    /// skipped where the spectrum reads an inertial period ([`spectral_period_s`]); 0: none.
    pub mains_hz: f64,
    pub features: FeatureOptions,
}

impl StudyParams {
    /// The `slider` stage's `[stage.params]` of a pipeline.toml text (for the
    /// examples and tests, which run the study outside the pipeline with the
    /// same settings); `Err` names what is missing or mistyped.
    pub fn from_pipeline_toml(text: &str) -> Result<StudyParams, String> {
        let doc: toml::Table = text.parse().map_err(|e| format!("pipeline.toml: {e}"))?;
        let stage = doc
            .get("stage")
            .and_then(|s| s.as_array())
            .and_then(|a| a.iter().find(|s| s.get("name").and_then(|n| n.as_str()) == Some("slider")))
            .ok_or("pipeline.toml: no [[stage]] named slider")?;
        let mut params = stage.get("params").cloned().ok_or("pipeline.toml: stage slider has no [stage.params]")?;
        // The runner hands each listed [shared.<name>] table to the stage as [stage.params.<name>].
        if let (Some(table), Some(sel)) =
            (params.as_table_mut(), doc.get("shared").and_then(|s| s.get("selection")).cloned())
        {
            table.insert("selection".into(), sel);
        }
        params.try_into().map_err(|e| format!("pipeline.toml: stage slider: {e}"))
    }
}

/// One run's measurement.
#[derive(Debug, Clone)]
pub struct Measured {
    pub name: String,
    pub stiffness_n_m: f64,
    pub drive_speed_um_s: f64,
    pub duration_s: f64,
    pub sample_rate_hz: f64,
    pub features: Features,
    /// An inertial oscillation's period read from the force's spectrum
    /// ([`spectral_period_s`]: the check of the turning points' median), s;
    /// NaN for the other regimes.
    pub spectral_period_s: f64,
    /// The channel's resolution, F/(m g) ([`crate::features::channel_step`]).
    pub force_step: f64,
}

/// A model fitted on some runs.
#[derive(Debug, Clone)]
pub struct Fitted {
    pub model: Model,
    /// The runs it was fitted on.
    pub train: Vec<usize>,
    pub params: Vec<f64>,
    /// Mean misfit on the runs it was fitted on.
    pub calibration_misfit: f64,
    /// Parameters at (within 1 % of the log or linear range of) a bound.
    pub at_bounds: Vec<&'static str>,
    /// Cost evaluations of the fit (every start scored, every search).
    pub evals: usize,
    /// Whether every start's search met the convergence criterion.
    pub converged: bool,
}

/// A model's record.
#[derive(Debug, Clone)]
pub struct CandidateResult {
    pub model: Model,
    /// Fitted on every calibration run: always with held-out stiffnesses
    /// (it is the fold's fit); with leave one stiffness out only for the
    /// baseline and each step's best (the selection uses the folds alone).
    pub fitted: Option<Fitted>,
    /// Its features at every run under `fitted` (empty without it).
    pub predicted: Vec<Features>,
    /// One fit per fold (leave one stiffness out: one per stiffness).
    pub fold_fits: Vec<Fitted>,
    /// Per held-out run: (run index, misfit, predicted features) under the fold that held it out.
    pub heldout: Vec<(usize, f64, Features)>,
    pub heldout_mean: f64,
}

impl CandidateResult {
    /// Every fit made of the model once: the folds', and the one on every
    /// calibration run when it is not a fold's.
    pub fn fits(&self) -> impl Iterator<Item = &Fitted> {
        let own = self.fitted.as_ref().filter(|f| !self.fold_fits.iter().any(|g| g.train == f.train));
        self.fold_fits.iter().chain(own)
    }
}

/// One forward step: from a model, the extensions tried and the one kept.
#[derive(Debug, Clone)]
pub struct Step {
    /// The engine's step number (from 1; a pair step is a step of its own).
    pub step: usize,
    /// Index into `Study::candidates` of the model the step starts from.
    pub from: usize,
    /// Indices of the models tried.
    pub tried: Vec<usize>,
    /// Each one's comparison with `from` by the workspace's step rule
    /// ([`rig_types::select::compare`]), in the order of `tried`.
    pub compared: Vec<Comparison>,
    /// The best of them (largest gain) and its comparison.
    pub best: usize,
    pub gain: Comparison,
    /// Whether it earned its place (`[shared.selection]`: relative gain and paired t).
    pub kept: bool,
}

/// The study's result.
#[derive(Debug, Clone)]
pub struct Study {
    pub params: StudyParams,
    pub runs: Vec<Measured>,
    /// True when held-out = leave one stiffness out (no run outside the calibration list).
    pub leave_one_out: bool,
    /// Calibration stiffnesses present in the folder.
    pub calibration_stiffnesses: Vec<f64>,
    /// Every model evaluated, the Coulomb baseline first, in the order of the steps.
    pub candidates: Vec<CandidateResult>,
    /// The forward selection, step by step.
    pub steps: Vec<Step>,
    /// The folds every held-out misfit was scored over.
    pub folds: Vec<Fold>,
    /// Index into `candidates` of the final model, when an extension earned its place.
    pub chosen: Option<usize>,
    /// The folder's name (`campaign` of slider-diagnosis.json).
    pub folder_name: String,
    /// Per run: the measured force after the running median over the figure's
    /// stretch (time from its start, s; thinned to at most [`TRACE_POINTS`]).
    pub traces: Vec<(Vec<f64>, Vec<f64>)>,
    /// Per creeping run, whether rate and state creeps across its stability
    /// boundary ([`boundary_scan`]).
    pub boundary_scans: Vec<BoundaryScan>,
    /// Per creeping run, the Coulomb baseline of the fold that held it out,
    /// simulated there and read through the run's channel ([`through_channel`]).
    pub channel_checks: Vec<ChannelCheck>,
    /// The friction level against V and k ([`crate::level::friction_level`]).
    pub level: crate::level::Level,
}

/// Whether a model's slips would show in a run's record ([`through_channel`]).
#[derive(Debug, Clone)]
pub struct ChannelCheck {
    /// Index into `Study::runs`.
    pub run: usize,
    pub model: Model,
    pub params: Vec<f64>,
    /// Its features read noiseless, and through the run's channel.
    pub clean: Features,
    pub channel: Features,
    /// Simulated seconds read.
    pub seconds: f64,
}

/// Simulated seconds a channel check reads (what the record's noise is
/// taken from: its first `CHANNEL_S` s).
pub const CHANNEL_S: f64 = 20.0;

/// The rate-and-state law (ageing law) simulated at one run while its
/// quasi-static critical stiffness k_c = m g (b − a)/Dc crosses the run's
/// stiffness, read by the one feature function: the regime at each k_c.
#[derive(Debug, Clone)]
pub struct BoundaryScan {
    /// Index into `Study::runs`.
    pub run: usize,
    /// One [`ScanCase`] per (a, Dc).
    pub scans: Vec<ScanCase>,
    /// The first law of the scans that creeps at the run (μ0, a, b − a, Dc:
    /// `rate_state_ageing`'s vector), with its features and misfit at every
    /// run of the same stiffness: what creeping there costs elsewhere.
    pub creeping_law: Option<CreepingLaw>,
}

/// A law's parameter vector and, per run, (run index, features, misfit).
pub type CreepingLaw = (Vec<f64>, Vec<(usize, Features, f64)>);

/// (a, Dc in m, [(k_c/k, regime)]), k_c/k from 0.85 to 1.15 in steps of 0.025.
pub type ScanCase = (f64, f64, Vec<(f64, Regime)>);

/// [`BoundaryScan`] of run `i`, at a = 0.003 and 0.01 and Dc = 0.3 and 1 µm
/// (the literature's range for paper: Heslot et al. 1994, Baumberger &
/// Caroli 2006; where the scan sits, not a fitted value), and at Dc = 1 µm
/// with the a of the run's own Hopf oscillation (`fit::hopf_starts`: the
/// a that puts the linearised law's period at the measured one when k_c is
/// the run's stiffness), μ0 at the run's mean force: whether the law has a
/// creep regime at that (k, V) at all, and where.
pub fn boundary_scan(runs: &[Measured], i: usize, p: &StudyParams) -> BoundaryScan {
    let m = &runs[i];
    let rs = Model { friction: Candidate::RateState, setup: SetupCandidate::Stated };
    let weight_n = p.mass_kg * p.gravity_m_s2;
    let mut cases: Vec<(f64, f64)> = [0.003, 0.01].iter().flat_map(|&a| [0.3e-6, 1e-6].map(|dc| (a, dc))).collect();
    let hints = StartHints {
        mu: m.features.mean_force,
        kc_over_weight_per_m: m.stiffness_n_m / weight_n,
        period_ratio: 1.0,
        stiffest_n_m: m.stiffness_n_m,
        creep: Some((m.stiffness_n_m / weight_n, m.drive_speed_um_s * 1e-6, m.features.period_s.median)),
    };
    // The first Hopf start: Dc = 1 µm, k_c at the run's stiffness.
    if let Some(x) = crate::fit::hopf_starts(&hints).first() {
        cases.push(((1e3 * x[1]).round() / 1e3, x[3]));
    }
    let scans: Vec<ScanCase> = cases
        .par_iter()
        .map(|&(a, dc)| {
            let regimes = (0..13)
                .map(|j| {
                    let ratio = 0.85 + 0.025 * j as f64;
                    let b_minus_a = ratio * m.stiffness_n_m * dc / weight_n;
                    (ratio, predict(rs, &[m.features.mean_force, a, b_minus_a, dc], m, p).regime)
                })
                .collect();
            (a, dc, regimes)
        })
        .collect();
    let creeping_law = scans.iter().find_map(|(a, dc, regimes)| {
        let ratio = regimes.iter().find(|x| x.1 == Regime::Creep)?.0;
        let x = vec![m.features.mean_force, *a, ratio * m.stiffness_n_m * dc / weight_n, *dc];
        let same_k: Vec<usize> = (0..runs.len()).filter(|&j| runs[j].stiffness_n_m == m.stiffness_n_m).collect();
        let at = same_k
            .par_iter()
            .map(|&j| {
                let f = predict(rs, &x, &runs[j], p);
                (j, f, run_misfit(&runs[j].features, &f))
            })
            .collect();
        Some((x, at))
    });
    BoundaryScan { run: i, scans, creeping_law }
}

/// Points of a figure's trace at most.
pub const TRACE_POINTS: usize = 400;

impl Measured {
    fn constants(&self, p: &StudyParams) -> RunConstants {
        RunConstants {
            stiffness_n_m: self.stiffness_n_m,
            drive_speed_m_s: self.drive_speed_um_s * 1e-6,
            mass_kg: p.mass_kg,
            gravity_m_s2: p.gravity_m_s2,
        }
    }
}

/// Measures one run.
pub fn measure(r: &SliderRun, p: &StudyParams) -> Measured {
    let n = r.time_s.len();
    let duration_s = r.time_s[n - 1] - r.time_s[0];
    let mut m = Measured {
        name: r.name.clone(),
        stiffness_n_m: r.stiffness_n_m,
        drive_speed_um_s: r.drive_speed_um_s,
        duration_s,
        sample_rate_hz: (n - 1) as f64 / duration_s,
        features: Features::default_steady(),
        spectral_period_s: f64::NAN,
        force_step: crate::features::channel_step(&r.force_over_weight),
    };
    m.features = features(&r.time_s, &r.force_over_weight, &m.constants(p), &p.features);
    if m.features.regime == Regime::InertialOscillation {
        let half = (p.features.median_window_s * m.sample_rate_hz / 2.0).round() as usize;
        let filtered = crate::features::running_median(&r.force_over_weight, half);
        m.spectral_period_s = spectral_period_s(&filtered, m.sample_rate_hz, m.features.natural_period_s, p.mains_hz);
    }
    m
}

/// A model's force at run `m` read through that run's channel, then by the
/// one feature function: `channel_s` s simulated (after the warm-up),
/// rounded onto the record's grid (its step, [`Measured::force_step`], at
/// the grid's offset) and with the record's own noise added sample by
/// sample (raw minus its running median: the spikes and the flicker between
/// steps the measurement carries). Whether the record could have shown what
/// the model does: a slip the channel resolves stays an event, one below
/// the hysteresis does not. Deterministic (the record's noise, no draw).
pub fn through_channel(
    model: Model,
    x: &[f64],
    m: &Measured,
    raw: &SliderRun,
    p: &StudyParams,
    channel_s: f64,
) -> Features {
    let mut q = p.clone();
    q.sim_min_window_s = channel_s;
    q.sim_max_window_s = channel_s;
    let (_, clean) = predict_trace(model, x, m, &q, usize::MAX);
    let half = (p.features.median_window_s * m.sample_rate_hz / 2.0).round() as usize;
    let median = crate::features::running_median(&raw.force_over_weight, half);
    let step = m.force_step;
    let offset = raw.force_over_weight[0] - step * (raw.force_over_weight[0] / step).round();
    let n = clean.len().min(raw.force_over_weight.len());
    let force: Vec<f64> = (0..n)
        .map(|i| {
            let on_grid = offset + step * ((clean[i] - offset) / step).round();
            on_grid + raw.force_over_weight[i] - median[i]
        })
        .collect();
    let time: Vec<f64> = (0..n).map(|i| i as f64 / m.sample_rate_hz).collect();
    features(&time, &force, &m.constants(p), &p.features)
}

/// The simulated (and the figures' measured) stretch of run `m`, s.
fn window_s(m: &Measured, p: &StudyParams) -> f64 {
    let periods = if m.features.period_s.n > 0 { p.sim_periods * m.features.period_s.median } else { 0.0 };
    periods.max(p.sim_min_window_s).min(p.sim_max_window_s).min(m.duration_s)
}

/// The features of `law` simulated at run `m`'s (k, V), through the same feature function.
///
/// The simulated stretch is [`window_s`] (set by the *measured* period).
/// It is lengthened, up to `sim_max_window_s` and the record's length, when
/// - the law's own slips are too slow to give `min_events` in it (a regime
///   of slips the window cannot hold, which the feature function would call
///   steady sliding): doubled, so a long period is measured as such;
/// - its events do not repeat one cycle ([`crate::fit::repeats`]) and it
///   holds fewer than `spread_periods` periods: to about that many, so the
///   misfit's spread term ([`crate::fit::spread_term`]) reads quartiles of
///   that many events (a cycle that repeats has its dispersion from two).
pub fn predict(model: Model, x: &[f64], m: &Measured, p: &StudyParams) -> Features {
    let cap = p.sim_max_window_s.min(m.duration_s);
    let mut window = window_s(m, p);
    // A law with a track covers enough of it for the events' statistics.
    if let (crate::sim::Law::Track(t), _) = model.law(x) {
        window = window.max(t.min_window_s(m.drive_speed_um_s * 1e-6)).min(cap);
    }
    // The first stretch from the start; a longer one continues it (bit for
    // bit the stretch simulated at once: `sim::simulate_more`).
    SCRATCH.with_borrow_mut(|(_, force, _)| force.clear());
    loop {
        let f = SCRATCH.with_borrow_mut(|(state, force, time)| {
            // A law whose simulation leaves the physical range predicts nothing: no slip.
            let Ok(skip) = simulate_window(model, x, m, p, window, state, force) else {
                return Features::default_steady();
            };
            time.clear();
            time.extend((skip..force.len()).map(|i| i as f64 / m.sample_rate_hz));
            features(time, &force[skip..], &m.constants(p), &p.features)
        });
        let slow_slips = f.regime == Regime::SteadySliding && f.events > 0;
        let periods = f.period_s.n;
        let few = f.events > 0 && periods < p.spread_periods && !crate::fit::repeats(&f);
        if !(slow_slips || few) || window >= cap {
            return f;
        }
        // Periods in a stretch grow with it: n + 1 maxima in the window.
        let grow =
            if slow_slips || periods < 2 { 2.0 } else { 1.1 * (p.spread_periods + 1) as f64 / (periods + 1) as f64 };
        window = (grow.max(1.25) * window).min(cap);
    }
}

thread_local! {
    /// Each thread's simulation buffers (the state at the last sample, force
    /// over weight, time), reused across evaluations.
    static SCRATCH: std::cell::RefCell<(OneDofState, Vec<f64>, Vec<f64>)> = Default::default();
}

/// The simulated force of `cand` at run `m` after its warm-up, thinned to about `points` (for figures).
pub fn predict_trace(model: Model, x: &[f64], m: &Measured, p: &StudyParams, points: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut state, mut f) = (OneDofState::default(), Vec::new());
    let Ok(skip) = simulate_window(model, x, m, p, window_s(m, p), &mut state, &mut f) else {
        return (Vec::new(), Vec::new());
    };
    let step = ((f.len() - skip) / points.max(1)).max(1);
    let t: Vec<f64> = (skip..f.len()).step_by(step).map(|i| (i - skip) as f64 / m.sample_rate_hz).collect();
    (t, f[skip..].iter().step_by(step).copied().collect())
}

/// Simulates `window` s of run `m` after a warm-up of `warmup_fraction` of it
/// into `force`; returns the number of warm-up samples at its start. An
/// empty `force` starts from rest; one a shorter call left (with `state`) is
/// continued ([`simulate_more`]).
fn simulate_window(
    model: Model,
    x: &[f64],
    m: &Measured,
    p: &StudyParams,
    window: f64,
    state: &mut OneDofState,
    force: &mut Vec<f64>,
) -> Result<usize, rig_model::ModelError> {
    let warmup_s = p.warmup_fraction * window;
    let (law, structure) = model.law(x);
    let setup = Setup {
        stiffness_n_m: m.stiffness_n_m,
        drive_speed_m_s: m.drive_speed_um_s * 1e-6,
        mass_kg: p.mass_kg,
        gravity_m_s2: p.gravity_m_s2,
        structure,
        duration_s: warmup_s + window,
        sample_rate_hz: m.sample_rate_hz,
        steps_per_period: p.steps_per_period,
        initial_force_over_weight: law.sliding_level(),
    };
    simulate_more(&law, &setup, state, force)?;
    Ok(((warmup_s * m.sample_rate_hz).round() as usize).min(force.len()))
}

/// Fits `model` on the runs `train` (indices into `runs`): Nelder–Mead from
/// the best-scored of its physical starts and of the starts `nested` (the
/// model the forward step extends, fitted on the same runs) gives
/// ([`warm_starts`]), the best result kept.
fn fit_on(model: Model, runs: &[Measured], train: &[usize], nested: Option<&Fitted>, p: &StudyParams) -> Fitted {
    let on: Vec<&Measured> = train.iter().map(|&i| &runs[i]).collect();
    let mu = on.iter().map(|r| r.features.mean_force).sum::<f64>() / on.len() as f64;
    // Each stiffness's slowest run: where the stability boundary shows.
    let mut slowest: Vec<(f64, Regime)> = Vec::new();
    for r in &on {
        let slower = on.iter().any(|q| q.stiffness_n_m == r.stiffness_n_m && q.drive_speed_um_s < r.drive_speed_um_s);
        if !slower {
            slowest.push((r.stiffness_n_m, r.features.regime));
        }
    }
    let kc = critical_stiffness_guess_n_m(&slowest) / (p.mass_kg * p.gravity_m_s2);
    // The measured inertial periods over the stated natural period (where a set-up's search starts).
    let ratios: Vec<f64> = on
        .iter()
        .filter(|r| r.features.regime == Regime::InertialOscillation && r.features.period_s.n > 0)
        .map(|r| r.features.period_s.median / r.features.natural_period_s)
        .collect();
    let period_ratio = if ratios.is_empty() { 1.0 } else { Spread::of(&ratios).median };
    let stiffest = on.iter().map(|r| r.stiffness_n_m).fold(0.0, f64::max);
    // The slowest creeping run (where the boundary's Hopf oscillation shows).
    let weight_n = p.mass_kg * p.gravity_m_s2;
    let creep = on
        .iter()
        .filter(|r| r.features.regime == Regime::Creep && r.features.period_s.n > 0)
        .min_by(|a, b| a.drive_speed_um_s.total_cmp(&b.drive_speed_um_s))
        .map(|r| (r.stiffness_n_m / weight_n, r.drive_speed_um_s * 1e-6, r.features.period_s.median));
    let hints = StartHints { mu, kc_over_weight_per_m: kc, period_ratio, stiffest_n_m: stiffest, creep };
    // Each point costed once per fit: Nelder–Mead re-evaluates its start
    // (scored among the starts) and, clamped at a bound, may step onto a
    // point it has costed (the same bits, the same simulations, the same value).
    let costed: std::cell::RefCell<Vec<(Vec<u64>, f64)>> = Default::default();
    let cost = |x: &[f64]| {
        let key: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
        if let Some(&(_, c)) = costed.borrow().iter().find(|(k, _)| *k == key) {
            return c;
        }
        let m: Vec<f64> = on.par_iter().map(|r| run_misfit(&r.features, &predict(model, x, r, p))).collect();
        let c = m.iter().sum::<f64>() / m.len() as f64;
        costed.borrow_mut().push((key, c));
        c
    };
    let specs = model.params();
    // Multi-start: every start scored, then Nelder–Mead from each in the
    // order of its score: `fit_starts` of them; converged fits
    // (`fit_tolerance` > 0) on while the last one lowered the best misfit by
    // more than the tolerance (the restart rule of `nelder_mead_converged`,
    // over starts). The best result kept (the first of equals).
    let mut starts = nested.map_or_else(Vec::new, |f| warm_starts(model, f, &hints));
    starts.extend(model.starts(&hints));
    let mut scored: Vec<(f64, Vec<f64>)> = starts.into_iter().map(|x| (cost(&x), x)).collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let tol = FitTolerance { tolerance: p.fit_tolerance, max_evals: p.fit_evals };
    let (mut evals, mut converged) = (scored.len(), true);
    let mut best: Option<FitResult> = None;
    // Raced (`fit_race_keep` > 0): the `fit_starts` best-scored starts side
    // by side for `fit_evals` evaluations, the `fit_race_keep` best on.
    let race = p.fit_race_keep > 0 && p.fit_tolerance <= 0.0;
    if race {
        let first: Vec<Vec<f64>> = scored.iter().take(p.fit_starts.max(1)).map(|(_, x)| x.clone()).collect();
        let r = crate::fit::fit_race(&specs, &first, p.fit_evals, p.fit_race_keep, p.fit_race_evals, cost);
        evals += r.evals;
        converged = false;
        best = Some(r);
    }
    for (k, (_, x)) in scored.iter().enumerate().take(if race { 0 } else { scored.len() }) {
        let r = fit(&specs, x, &tol, cost);
        evals += r.evals;
        converged &= r.converged;
        let before = best.as_ref().map_or(f64::INFINITY, |b| b.cost);
        let improved = r.cost < before - p.fit_tolerance;
        if r.cost < before {
            best = Some(r);
        }
        if k + 1 >= p.fit_starts.max(1) && (p.fit_tolerance <= 0.0 || !improved) {
            break;
        }
    }
    let best = best.expect("every model has a start");
    let (params, calibration_misfit) = (best.x, best.cost);
    let at_bounds = specs
        .iter()
        .zip(&params)
        .filter(|(s, v)| {
            let (lo, hi, v) = if s.log { (s.lo.ln(), s.hi.ln(), v.ln()) } else { (s.lo, s.hi, **v) };
            (v - lo) < 0.01 * (hi - lo) || (hi - v) < 0.01 * (hi - lo)
        })
        .map(|(s, _)| s.name)
        .collect();
    Fitted { model, train: train.to_vec(), params, calibration_misfit, at_bounds, evals, converged }
}

/// Starts from a nested fit: its law with each of `model`'s set-up starts
/// (a set-up added: the stated-like start reproduces the nested optimum), or
/// each of `model`'s law starts on the nested set-up (a memory law added on
/// a set-up). None when the law changes on the stated set-up (nothing of
/// the nested fit carries over).
fn warm_starts(model: Model, nested: &Fitted, hints: &StartHints) -> Vec<Vec<f64>> {
    let nf = nested.model.friction.params().len();
    let (law, setup) = nested.params.split_at(nf);
    let join = |a: &[f64], b: &[f64]| a.iter().chain(b).copied().collect::<Vec<f64>>();
    if nested.model.friction == model.friction && nested.model.setup != model.setup {
        model.setup.starts(hints).iter().map(|s| join(law, s)).collect()
    } else if nested.model.setup == model.setup && model.setup != SetupCandidate::Stated {
        model.friction.starts(&StartHints { mu: law[0], ..*hints }).iter().map(|l| join(l, setup)).collect()
    } else {
        Vec::new()
    }
}

/// The study's runs as the engine sees them ([`engine::Study`]): a unit is a
/// run, its misfit [`run_misfit`] of the model's simulated features.
struct OnRuns<'a> {
    runs: &'a [Measured],
    p: &'a StudyParams,
}

impl engine::Study<Fitted> for OnRuns<'_> {
    fn score(&self, m: &Fitted, run: usize) -> f64 {
        let r = &self.runs[run];
        run_misfit(&r.features, &predict(m.model, &m.params, r, self.p))
    }
}

/// One extension of a model ([`engine::Candidate`]): a memory law in place of
/// Coulomb, or a set-up in place of the README's m and k. Laws are one group
/// and set-ups another (alternatives: a model has one of each), so the engine
/// tries a law and a set-up together in its pair step.
#[derive(Debug, Clone, Copy)]
enum Extension {
    Law(Candidate),
    Setup(SetupCandidate),
}

impl Extension {
    /// Every extension of the Coulomb baseline on the stated set-up, in the report's order.
    fn all() -> Vec<Extension> {
        CANDIDATES[1..].iter().map(|&c| Extension::Law(c)).chain(SETUPS.iter().map(|&s| Extension::Setup(s))).collect()
    }
}

impl engine::Candidate<OnRuns<'_>, Fitted> for Extension {
    fn id(&self) -> &str {
        match self {
            Extension::Law(c) => c.id(),
            Extension::Setup(s) => s.id(),
        }
    }
    fn group(&self) -> Option<&str> {
        Some(match self {
            Extension::Law(_) => "friction_law",
            Extension::Setup(_) => "set_up",
        })
    }
    /// `current`'s model with this law or set-up, fitted on `train` from its
    /// physical starts and from `current`'s fit ([`warm_starts`]).
    fn fit(&self, s: &OnRuns<'_>, current: &Fitted, train: &[usize]) -> Result<Fitted, String> {
        let model = match *self {
            Extension::Law(friction) => Model { friction, ..current.model },
            Extension::Setup(setup) => Model { setup, ..current.model },
        };
        Ok(fit_on(model, s.runs, train, Some(current), s.p))
    }
}

/// A trial of the selection as the report's record: its fits (one per
/// training set, in the engine's order), its held-out misfits and the
/// held-out features under the fit of the fold that held each run out; with
/// held-out stiffnesses, the fit on every calibration run (the one fold's).
fn record(
    fits: &[Fitted],
    misfits: &[f64],
    sel: &engine::Selection<Fitted>,
    folds: &[Fold],
    runs: &[Measured],
    cal: &[usize],
    p: &StudyParams,
) -> CandidateResult {
    let model = fits[0].model;
    let fit_of = |i: usize| {
        let set = &folds[sel.fold_of[i]].train;
        fits.iter().find(|f| f.train == *set).expect("a fit per training set")
    };
    let mut heldout: Vec<(usize, f64, Features)> = (0..sel.units.len())
        .into_par_iter()
        .map(|i| {
            let f = fit_of(i);
            (sel.units[i], misfits[i], predict(model, &f.params, &runs[sel.units[i]], p))
        })
        .collect();
    heldout.sort_by_key(|h| h.0);
    let heldout_mean = heldout.iter().map(|h| h.1).sum::<f64>() / heldout.len().max(1) as f64;
    let mut c =
        CandidateResult { model, fitted: None, predicted: Vec::new(), fold_fits: fits.to_vec(), heldout, heldout_mean };
    if let Some(f) = c.fold_fits.iter().find(|f| f.train == cal) {
        c.fitted = Some(f.clone());
        c.predicted = runs.par_iter().map(|r| predict(model, &f.params, r, p)).collect();
    }
    c
}

/// Fits `c` on every calibration run (when not yet) and predicts every run with that fit.
fn complete(c: &mut CandidateResult, runs: &[Measured], cal: &[usize], p: &StudyParams) {
    if c.fitted.is_some() {
        return;
    }
    let f = fit_on(c.model, runs, cal, None, p);
    c.predicted = runs.par_iter().map(|r| predict(c.model, &f.params, r, p)).collect();
    c.fitted = Some(f);
}

/// Reads the folder and runs the study.
pub fn run_study(dir: &Path, p: &StudyParams) -> Result<Study, SliderError> {
    let raw = read_slider_folder(dir)?;
    let runs: Vec<Measured> = raw.par_iter().map(|r| measure(r, p)).collect();
    let is_cal = |k: f64| p.calibration_stiffnesses_n_m.iter().any(|&c| (c - k).abs() < 1e-9 * c.abs().max(1.0));
    let cal: Vec<usize> = (0..runs.len()).filter(|&i| is_cal(runs[i].stiffness_n_m)).collect();
    if cal.is_empty() {
        return Err(SliderError::NoCalibration {
            listed: p.calibration_stiffnesses_n_m.clone(),
            folder: dir.to_path_buf(),
        });
    }
    let mut calibration_stiffnesses: Vec<f64> = cal.iter().map(|&i| runs[i].stiffness_n_m).collect();
    calibration_stiffnesses.dedup();
    let leave_one_out = cal.len() == runs.len();
    let folds: Vec<Fold> = if leave_one_out {
        calibration_stiffnesses
            .iter()
            .map(|&k| {
                let (test, train): (Vec<usize>, Vec<usize>) =
                    (0..runs.len()).partition(|&i| runs[i].stiffness_n_m == k);
                Fold { train, held_out: test }
            })
            .filter(|f| !f.train.is_empty())
            .collect()
    } else {
        vec![Fold { train: cal.clone(), held_out: (0..runs.len()).filter(|i| !cal.contains(i)).collect() }]
    };
    // Forward selection on the workspace's one engine from the Coulomb
    // baseline fitted on each training set: each step tries the current
    // model's extensions (a memory law, a set-up) and keeps the best when the
    // step rule admits it (`[shared.selection]`); when none is admitted, the
    // pair step tries the best with each member of the other group (a law and
    // a set-up may each fail alone and gain together: the set-up moves the
    // inertial periods, the law the regimes).
    let sets = engine::train_sets(&folds);
    let baselines: Vec<Fitted> = sets.par_iter().map(|t| fit_on(Model::BASELINE, &runs, t, None, p)).collect();
    let extensions = Extension::all();
    let cands: Vec<&dyn engine::Candidate<OnRuns, Fitted>> =
        extensions.iter().map(|e| e as &dyn engine::Candidate<OnRuns, Fitted>).collect();
    let on = OnRuns { runs: &runs, p };
    let search = engine::Search { pair_step: true, ..engine::Search::default() };
    let sel = engine::forward_select_from(&on, &cands, &baselines, &folds, &p.selection, &search)
        .map_err(|e| SliderError::Selection(e.0))?;
    let mut candidates = vec![record(&baselines, &sel.baseline_misfits, &sel, &folds, &runs, &cal, p)];
    let mut steps: Vec<Step> = Vec::new();
    let mut current = 0;
    for (k, t) in sel.trials.iter().enumerate() {
        candidates.push(record(&t.fitted, &t.misfits, &sel, &folds, &runs, &cal, p));
        let idx = candidates.len() - 1;
        if steps.last().is_none_or(|st| st.step != t.step) {
            steps.push(Step {
                step: t.step,
                from: current,
                tried: Vec::new(),
                compared: Vec::new(),
                best: idx,
                gain: t.comparison,
                kept: false,
            });
        }
        let st = steps.last_mut().expect("a step");
        st.tried.push(idx);
        st.compared.push(t.comparison);
        if t.best {
            (st.best, st.gain) = (idx, t.comparison);
        }
        if t.accepted {
            st.kept = true;
            current = idx;
        }
        debug_assert!(sel.chosen.contains(&k) == t.accepted);
    }
    let chosen = (current != 0).then_some(current);
    // The models the report shows in full: the baseline and each step's best.
    let mut full: Vec<usize> = std::iter::once(0).chain(steps.iter().map(|st| st.best)).collect();
    full.sort_unstable();
    full.dedup();
    let completed: Vec<(usize, CandidateResult)> = full
        .par_iter()
        .map(|&i| {
            let mut c = candidates[i].clone();
            complete(&mut c, &runs, &cal, p);
            (i, c)
        })
        .collect();
    for (i, c) in completed {
        candidates[i] = c;
    }
    let traces = raw
        .iter()
        .zip(&runs)
        .map(|(r, m)| {
            let n = ((window_s(m, p) * m.sample_rate_hz) as usize).min(r.time_s.len());
            let half = (p.features.median_window_s * m.sample_rate_hz / 2.0).round() as usize;
            let f = crate::features::running_median(&r.force_over_weight[..n], half);
            let step = (n / TRACE_POINTS).max(1);
            let t: Vec<f64> = r.time_s[..n].iter().step_by(step).map(|t| t - r.time_s[0]).collect();
            (t, f.iter().step_by(step).copied().collect())
        })
        .collect();
    let folder_name = dir.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let creeping: Vec<usize> = (0..runs.len()).filter(|&i| runs[i].features.regime == Regime::Creep).collect();
    let boundary_scans = creeping.iter().map(|&i| boundary_scan(&runs, i, p)).collect();
    let channel_checks = creeping
        .par_iter()
        .filter_map(|&i| {
            let fold = folds.iter().find(|f| f.held_out.contains(&i))?;
            let base = baselines.iter().find(|b| b.train == fold.train)?;
            let seconds = CHANNEL_S.min(runs[i].duration_s);
            let clean = predict(base.model, &base.params, &runs[i], p);
            let channel = through_channel(base.model, &base.params, &runs[i], &raw[i], p, seconds);
            Some(ChannelCheck { run: i, model: base.model, params: base.params.clone(), clean, channel, seconds })
        })
        .collect();
    let level = crate::level::friction_level(&runs);
    Ok(Study {
        level,
        boundary_scans,
        channel_checks,
        params: p.clone(),
        runs,
        leave_one_out,
        calibration_stiffnesses,
        candidates,
        steps,
        folds,
        chosen,
        folder_name,
        traces,
    })
}
