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

mod boundary;
mod fitting;
mod predict;
mod roughness;
mod selection;

pub use boundary::boundary_scan;
pub use predict::{TRACE_POINTS, measure, predict, predict_trace, through_channel};
pub use roughness::{
    GainSpread, LocalMisfit, Roughness, ScanPoint, gain_spread, landscape, local_misfit, misfit_at, read_misfit,
    roughness,
};

use crate::SliderError;
use crate::features::{FeatureOptions, Features, Regime};
use crate::fit::Model;
use fitting::{fit_on, read_noise};
use predict::window_s;
use rayon::prelude::*;
use rig_ingest::slider::read_slider_folder;
use rig_types::select::{self as engine, Comparison, Fold};
use selection::{Extension, OnRuns, complete, record};
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
    /// The relative step at which the report reads the misfit's roughness
    /// about the baseline's and each step's best fit ([`roughness`]: every
    /// parameter scaled by 1 ± this).
    pub roughness_rel_step: f64,
    /// Which fits are noisy, and how a noisy fit's misfits are read (issue
    /// 26, the lead's decision of the twenty-first session: a law whose
    /// misfit is a noisy statistic is judged on its expected misfit, not on
    /// one draw). Every fit's calibration misfit is read over
    /// `local_moves` fixed random moves of relative size `local_rel_step`
    /// ([`local_misfit`]); a fit whose sd over them exceeds `noisy_sd` is
    /// noisy, and every misfit the selection reads of it — its held-out
    /// per-run misfits, hence the step's gain and paired t — is the local
    /// mean over the same moves ([`read_misfit`]); a smooth fit's is its
    /// point misfit. The search is unchanged. `local_moves` 0: every fit smooth.
    pub local_moves: usize,
    pub local_rel_step: f64,
    pub noisy_sd: f64,
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
    /// The calibration misfit read over the fixed moves ([`local_misfit`]
    /// on `train`; None when `local_moves` < 2 or the selection does not
    /// read the fit: the report's fit on every calibration run under leave
    /// one stiffness out)...
    pub local: Option<LocalMisfit>,
    /// ...and whether its sd exceeds `noisy_sd`: the selection then reads
    /// this fit's misfits as local means ([`read_misfit`]).
    pub noisy: bool,
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
    /// Per held-out run (the order of `heldout`), its misfit over
    /// the moves when its fold's fit is noisy (its misfit is then their
    /// local mean, [`read_misfit`], with its sd and values); None when the
    /// fit is smooth (its point misfit).
    pub heldout_local: Vec<Option<LocalMisfit>>,
    /// The calibration misfit's roughness about `fitted` ([`roughness`];
    /// the baseline and each step's best only).
    pub roughness: Option<Roughness>,
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
    /// The best's gain among its neighbouring fold fits ([`gain_spread`]).
    pub gain_spread: Option<GainSpread>,
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
    let baselines: Vec<Fitted> =
        sets.par_iter().map(|t| read_noise(fit_on(Model::BASELINE, &runs, t, None, p), &runs, p)).collect();
    let extensions = Extension::all();
    let cands: Vec<&dyn engine::Candidate<OnRuns, Fitted>> =
        extensions.iter().map(|e| e as &dyn engine::Candidate<OnRuns, Fitted>).collect();
    let on = OnRuns { runs: &runs, p, read: Default::default() };
    let search = engine::Search { pair_step: true, ..engine::Search::default() };
    let sel = engine::forward_select_from(&on, &cands, &baselines, &folds, &p.selection, &search)
        .map_err(|e| SliderError::Selection(e.0))?;
    let mut candidates = vec![record(&baselines, &sel.baseline_misfits, &sel, &folds, &on, &cal)];
    let mut steps: Vec<Step> = Vec::new();
    let mut current = 0;
    for (k, t) in sel.trials.iter().enumerate() {
        candidates.push(record(&t.fitted, &t.misfits, &sel, &folds, &on, &cal));
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
                gain_spread: None,
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
            let on: Vec<&Measured> = cal.iter().map(|&j| &runs[j]).collect();
            c.roughness = c.fitted.as_ref().map(|f| roughness(c.model, &f.params, &on, p));
            (i, c)
        })
        .collect();
    for (i, c) in completed {
        candidates[i] = c;
    }
    for st in &mut steps {
        st.gain_spread = gain_spread(&candidates[st.from], &candidates[st.best], &folds, &runs, p);
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
