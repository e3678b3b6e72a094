//! The study ([`run_study`]): measure every run, fit the Coulomb baseline and
//! every candidate on the calibration stiffnesses, predict the held-out
//! runs, choose the extension by its held-out gain.
//!
//! Held-out runs are the runs at a stiffness not in
//! `calibration_stiffnesses_n_m`. When there is none (the shipped folder with
//! the default list), every stiffness is held out in turn and the laws are
//! fitted on the others (leave one stiffness out); the study says which.

use crate::SliderError;
use crate::features::Regime;
use crate::features::{FeatureOptions, Features, RunConstants, features};
use crate::fit::{CANDIDATES, Candidate, critical_stiffness_guess_n_m, fit, run_misfit};
use crate::sim::{Setup, simulate_into};
use rayon::prelude::*;
use rig_ingest::slider::{SliderRun, read_slider_folder};
use rig_model::one_dof::OneDofRun;
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
    /// Simulated time discarded before it, as a fraction of the window (the start from rest).
    pub warmup_fraction: f64,
    /// Integration steps per natural period.
    pub steps_per_period: f64,
    /// Nelder–Mead evaluations per start...
    pub fit_evals: usize,
    /// ...from this many starts (the best-scored of the candidate's starts), the best result kept.
    pub fit_starts: usize,
    /// An extension must lower the mean held-out misfit by
    /// `selection.min_relative_gain` (pipeline.toml's `[shared.selection]`,
    /// the campaign diagnosis' and the LAVI study's rule too)...
    pub selection: rig_types::contract::SelectionRule,
    /// ...and the model is adequate when its mean held-out misfit is at most
    /// this and it gets the regime of every held-out run right.
    pub adequacy_threshold: f64,
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
}

/// A law fitted on some runs.
#[derive(Debug, Clone)]
pub struct Fitted {
    pub candidate: Candidate,
    pub params: Vec<f64>,
    /// Mean misfit on the runs it was fitted on.
    pub calibration_misfit: f64,
    /// Parameters at (within 1 % of the log or linear range of) a bound.
    pub at_bounds: Vec<&'static str>,
}

/// A candidate's held-out record.
#[derive(Debug, Clone)]
pub struct CandidateResult {
    /// Fitted on every calibration run.
    pub fitted: Fitted,
    /// Its features at every run (fitted on all calibration runs).
    pub predicted: Vec<Features>,
    /// Per held-out run: (run index, misfit, predicted features) under the split that held it out.
    pub heldout: Vec<(usize, f64, Features)>,
    pub heldout_mean: f64,
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
    pub candidates: Vec<CandidateResult>,
    /// Index into `candidates` of the chosen extension, when one earns its place.
    pub chosen: Option<usize>,
    /// The folder's name (`campaign` of slider-diagnosis.json).
    pub folder_name: String,
    /// Per run: the measured force after the running median over the figure's
    /// stretch (time from its start, s; thinned to at most [`TRACE_POINTS`]).
    pub traces: Vec<(Vec<f64>, Vec<f64>)>,
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
    };
    m.features = features(&r.time_s, &r.force_over_weight, &m.constants(p), &p.features);
    m
}

/// The simulated (and the figures' measured) stretch of run `m`, s.
fn window_s(m: &Measured, p: &StudyParams) -> f64 {
    let periods = if m.features.period_s.n > 0 { p.sim_periods * m.features.period_s.median } else { 0.0 };
    periods.max(p.sim_min_window_s).min(p.sim_max_window_s).min(m.duration_s)
}

/// The features of `law` simulated at run `m`'s (k, V), through the same feature function.
///
/// The simulated stretch is [`window_s`] (set by the *measured* period);
/// when the law's own slips are too slow to give `min_events` in it (a
/// regime of slips the window cannot hold, which the feature function would
/// call steady sliding) the stretch is doubled, up to `sim_max_window_s`,
/// so a long period is measured as such.
pub fn predict(cand: Candidate, x: &[f64], m: &Measured, p: &StudyParams) -> Features {
    let mut window = window_s(m, p);
    loop {
        let f = SCRATCH.with_borrow_mut(|(run, force, time)| {
            // A law whose simulation leaves the physical range predicts nothing: no slip.
            let Ok(skip) = simulate_window(cand, x, m, p, window, run, force) else {
                return Features::default_steady();
            };
            time.clear();
            time.extend((skip..force.len()).map(|i| i as f64 / m.sample_rate_hz));
            features(time, &force[skip..], &m.constants(p), &p.features)
        });
        let slow_slips = f.regime == Regime::SteadySliding && f.events > 0;
        if !slow_slips || window >= p.sim_max_window_s {
            return f;
        }
        window = (2.0 * window).min(p.sim_max_window_s);
    }
}

thread_local! {
    /// Each thread's simulation buffers (one_dof run, force over weight, time), reused across evaluations.
    static SCRATCH: std::cell::RefCell<(OneDofRun, Vec<f64>, Vec<f64>)> = Default::default();
}

/// The simulated force of `cand` at run `m` after its warm-up, thinned to about `points` (for figures).
pub fn predict_trace(cand: Candidate, x: &[f64], m: &Measured, p: &StudyParams, points: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut run, mut f) = (OneDofRun::default(), Vec::new());
    let Ok(skip) = simulate_window(cand, x, m, p, window_s(m, p), &mut run, &mut f) else {
        return (Vec::new(), Vec::new());
    };
    let step = ((f.len() - skip) / points.max(1)).max(1);
    let t: Vec<f64> = (skip..f.len()).step_by(step).map(|i| (i - skip) as f64 / m.sample_rate_hz).collect();
    (t, f[skip..].iter().step_by(step).copied().collect())
}

/// Simulates `window` s of run `m` after a warm-up of `warmup_fraction` of it
/// into `force`; returns the number of warm-up samples at its start.
fn simulate_window(
    cand: Candidate,
    x: &[f64],
    m: &Measured,
    p: &StudyParams,
    window: f64,
    run: &mut OneDofRun,
    force: &mut Vec<f64>,
) -> Result<usize, rig_model::ModelError> {
    let warmup_s = p.warmup_fraction * window;
    let law = cand.law(x);
    let setup = Setup {
        stiffness_n_m: m.stiffness_n_m,
        drive_speed_m_s: m.drive_speed_um_s * 1e-6,
        mass_kg: p.mass_kg,
        gravity_m_s2: p.gravity_m_s2,
        duration_s: warmup_s + window,
        sample_rate_hz: m.sample_rate_hz,
        steps_per_period: p.steps_per_period,
        initial_force_over_weight: law.sliding_level(),
    };
    simulate_into(&law, &setup, run, force)?;
    Ok(((warmup_s * m.sample_rate_hz).round() as usize).min(force.len()))
}

fn fit_on(cand: Candidate, runs: &[&Measured], p: &StudyParams) -> Fitted {
    let mu = runs.iter().map(|r| r.features.mean_force).sum::<f64>() / runs.len() as f64;
    // Each stiffness's slowest run: where the stability boundary shows.
    let mut slowest: Vec<(f64, Regime)> = Vec::new();
    for r in runs {
        let slower = runs.iter().any(|q| q.stiffness_n_m == r.stiffness_n_m && q.drive_speed_um_s < r.drive_speed_um_s);
        if !slower {
            slowest.push((r.stiffness_n_m, r.features.regime));
        }
    }
    let kc = critical_stiffness_guess_n_m(&slowest) / (p.mass_kg * p.gravity_m_s2);
    let cost = |x: &[f64]| {
        let m: Vec<f64> = runs.par_iter().map(|r| run_misfit(&r.features, &predict(cand, x, r, p))).collect();
        m.iter().sum::<f64>() / m.len() as f64
    };
    // Multi-start: every start scored, Nelder–Mead from the best
    // `fit_starts`, the best result kept.
    let mut scored: Vec<(f64, Vec<f64>)> = cand.starts(mu, kc).into_iter().map(|x| (cost(&x), x)).collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let (params, calibration_misfit) = scored
        .iter()
        .take(p.fit_starts.max(1))
        .map(|(_, x)| fit(cand, x, p.fit_evals, cost))
        .min_by(|a, b| a.1.total_cmp(&b.1))
        .expect("every candidate has a start");
    let at_bounds = cand
        .params()
        .iter()
        .zip(&params)
        .filter(|(s, v)| {
            let (lo, hi, v) = if s.log { (s.lo.ln(), s.hi.ln(), v.ln()) } else { (s.lo, s.hi, **v) };
            (v - lo) < 0.01 * (hi - lo) || (hi - v) < 0.01 * (hi - lo)
        })
        .map(|(s, _)| s.name)
        .collect();
    Fitted { candidate: cand, params, calibration_misfit, at_bounds }
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
    // Splits: (fitted on, held out).
    let splits: Vec<(Vec<usize>, Vec<usize>)> = if leave_one_out {
        calibration_stiffnesses
            .iter()
            .map(|&k| {
                let (out, inn): (Vec<usize>, Vec<usize>) = (0..runs.len()).partition(|&i| runs[i].stiffness_n_m == k);
                (inn, out)
            })
            .filter(|(inn, _)| !inn.is_empty())
            .collect()
    } else {
        vec![(cal.clone(), (0..runs.len()).filter(|i| !cal.contains(i)).collect())]
    };
    let candidates: Vec<CandidateResult> = CANDIDATES
        .par_iter()
        .map(|&cand| {
            let all: Vec<&Measured> = cal.iter().map(|&i| &runs[i]).collect();
            let fitted = fit_on(cand, &all, p);
            let predicted: Vec<Features> = runs.par_iter().map(|r| predict(cand, &fitted.params, r, p)).collect();
            let mut heldout = Vec::new();
            for (inn, out) in &splits {
                let refs: Vec<&Measured> = inn.iter().map(|&i| &runs[i]).collect();
                let f = if inn == &cal { fitted.clone() } else { fit_on(cand, &refs, p) };
                let pred: Vec<(usize, f64, Features)> = out
                    .par_iter()
                    .map(|&i| {
                        let s = predict(cand, &f.params, &runs[i], p);
                        (i, run_misfit(&runs[i].features, &s), s)
                    })
                    .collect();
                heldout.extend(pred);
            }
            heldout.sort_by_key(|h| h.0);
            let heldout_mean = heldout.iter().map(|h| h.1).sum::<f64>() / heldout.len().max(1) as f64;
            CandidateResult { fitted, predicted, heldout, heldout_mean }
        })
        .collect();
    let base = candidates[0].heldout_mean;
    let chosen = (1..candidates.len())
        .filter(|&c| !candidates[c].heldout.is_empty())
        .min_by(|&a, &b| candidates[a].heldout_mean.total_cmp(&candidates[b].heldout_mean))
        .filter(|&c| candidates[c].heldout_mean <= (1.0 - p.selection.min_relative_gain) * base);
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
    Ok(Study {
        params: p.clone(),
        runs,
        leave_one_out,
        calibration_stiffnesses,
        candidates,
        chosen,
        folder_name,
        traces,
    })
}
