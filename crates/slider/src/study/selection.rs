//! The study's runs and extensions as the workspace's one selection engine
//! sees them ([`OnRuns`], [`Extension`]), and a trial's record for the report.

use super::{CandidateResult, Fitted, LocalMisfit, Measured, StudyParams, fit_on, predict, read_misfit, read_noise};
use crate::features::Features;
use crate::fit::{CANDIDATES, Candidate, Model, SETUPS, SetupCandidate};
use rayon::prelude::*;
use rig_types::select::{self as engine, Fold};
use std::collections::HashMap;
use std::sync::Mutex;

/// A noisy fit's reading at one run, kept for the report: (model id, the
/// parameters' bits, run) → the local misfit.
type Readings = HashMap<(String, Vec<u64>, usize), LocalMisfit>;

/// The study's runs as the engine sees them ([`engine::Study`]): a unit is a
/// run, its misfit [`read_misfit`] of the fit there (a noisy fit's local
/// mean over the fixed moves, a smooth fit's [`crate::fit::run_misfit`] of its simulated
/// features), the noisy fits' readings kept for the report (a value of the
/// parameters and the run alone, so the same whatever the order the
/// engine's threads fill it in).
pub(super) struct OnRuns<'a> {
    pub(super) runs: &'a [Measured],
    pub(super) p: &'a StudyParams,
    pub(super) read: Mutex<Readings>,
}

impl OnRuns<'_> {
    fn key(m: &Fitted, run: usize) -> (String, Vec<u64>, usize) {
        (m.model.id(), m.params.iter().map(|v| v.to_bits()).collect(), run)
    }
}

impl engine::Study<Fitted> for OnRuns<'_> {
    fn score(&self, m: &Fitted, run: usize) -> f64 {
        let (misfit, local) = read_misfit(m, &self.runs[run], self.p);
        if let Some(l) = local {
            self.read.lock().expect("no thread panicked holding it").insert(Self::key(m, run), l);
        }
        misfit
    }
}

/// One extension of a model ([`engine::Candidate`]): a memory law in place of
/// Coulomb, or a set-up in place of the README's m and k. Laws are one group
/// and set-ups another (alternatives: a model has one of each), so the engine
/// tries a law and a set-up together in its pair step.
#[derive(Debug, Clone, Copy)]
pub(super) enum Extension {
    Law(Candidate),
    Setup(SetupCandidate),
}

impl Extension {
    /// Every extension of the Coulomb baseline on the stated set-up, in the report's order.
    pub(super) fn all() -> Vec<Extension> {
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
        Ok(read_noise(fit_on(model, s.runs, train, Some(current), s.p), s.runs, s.p))
    }
}

/// A trial of the selection as the report's record: its fits (one per
/// training set, in the engine's order), its held-out misfits and the
/// held-out features under the fit of the fold that held each run out; with
/// held-out stiffnesses, the fit on every calibration run (the one fold's).
pub(super) fn record(
    fits: &[Fitted],
    misfits: &[f64],
    sel: &engine::Selection<Fitted>,
    folds: &[Fold],
    on: &OnRuns<'_>,
    cal: &[usize],
) -> CandidateResult {
    let (runs, p) = (on.runs, on.p);
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
    let read = on.read.lock().expect("no thread panicked holding it");
    let heldout_local: Vec<Option<LocalMisfit>> = heldout
        .iter()
        .map(|h| {
            let f = fit_of(sel.units.iter().position(|&u| u == h.0).expect("a held-out unit"));
            f.noisy.then(|| read.get(&OnRuns::key(f, h.0)).cloned().expect("the engine read every noisy fit"))
        })
        .collect();
    drop(read);
    let heldout_mean = heldout.iter().map(|h| h.1).sum::<f64>() / heldout.len().max(1) as f64;
    let mut c = CandidateResult {
        model,
        fitted: None,
        predicted: Vec::new(),
        fold_fits: fits.to_vec(),
        heldout,
        heldout_mean,
        heldout_local,
        roughness: None,
    };
    if let Some(f) = c.fold_fits.iter().find(|f| f.train == cal) {
        c.fitted = Some(f.clone());
        c.predicted = runs.par_iter().map(|r| predict(model, &f.params, r, p)).collect();
    }
    c
}

/// Fits `c` on every calibration run (when not yet) and predicts every run with that fit.
pub(super) fn complete(c: &mut CandidateResult, runs: &[Measured], cal: &[usize], p: &StudyParams) {
    if c.fitted.is_some() {
        return;
    }
    let f = fit_on(c.model, runs, cal, None, p);
    c.predicted = runs.par_iter().map(|r| predict(c.model, &f.params, r, p)).collect();
    c.fitted = Some(f);
}
