//! Structural candidates: where the model's damping acts, selected like the
//! vocabulary effects (issue 25; ../shared/spec/diagnosis.md, `structure`).
//!
//! Each candidate is one file with its id, its parameters (units, bounds,
//! meaning), how it enters the model ([`StructureCandidate::apply`] on a
//! `RigParams`), how it is fitted ([`StructureCandidate::fit`]: teacher-forced
//! through the rotor torque balance, [`crate::channels::BalanceData`]), its
//! admissibility rule (every parameter at or above its lower bound) and its
//! sentence; [`REGISTRY`] lists them, the baseline first.
//!
//! | id | damping | parameters |
//! |---|---|---|
//! | `twist_rate` | C(Ω2 − Ω1), the rig model's (baseline) | C, the estimation's |
//! | `rotor_absolute` | −C_r·Ω1, C = 0 | C_r |
//! | `twist_rate_and_rotor` | both (contains Eq. 4-7 as published) | C, C_r |
//!
//! # Selection (one step of forward selection, on the free run)
//!
//! The vocabulary effects are selected on the teacher-forced channels (μ in
//! slip, the PI's voltage), which are driven by the measured speeds and
//! contain no damping term: where the damping acts cannot change them, so
//! the effects are selected first and the structure is selected on top of
//! the extended model (baseline + findings) — the order changes neither
//! choice. The damping shows in the motion, so the structure is scored by
//! the cross-validated **free-run misfit** ([`crate::channels::free_run_misfit`]):
//! for each fold, the candidate is fitted on the other folds' runs and the
//! held-out runs are simulated free from rest; the per-run misfits are
//! compared with the extended model's by the crate's criterion (relative
//! gain ≥ `min_relative_gain` and paired run-level t ≥ `min_t`,
//! [`crate::select`]), and the candidate must be admissible on its fit to
//! every run, with every term it fits at least `min_t` fold-jackknife
//! standard errors above its bound in the balance (a term the records put at
//! ≈ 0 is the baseline again, and the free-run extrema of stick-slip are
//! sensitive enough to reward such a copy by chance). The placements exclude
//! each other, so at most one wins. A
//! structure is never a finding: it is reported in diagnosis.json's
//! `structure` and the verdict stays the first vocabulary finding (spec).

mod both;
mod rotor_absolute;
mod twist_rate;

use crate::DiagnoseOptions;
use crate::channels::{BalanceData, FreeRunPair, FreeRunSettings, free_run_misfit, free_run_pairs_by, with_run_phases};
use crate::result::{ParamAtBound, StructureScore, round_sig};
use crate::select::{compare_folds, overall};
use rig_types::{Campaign, RigParams};
use std::collections::BTreeMap;

/// One parameter of a structural candidate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ParamSpec {
    pub name: &'static str,
    pub unit: &'static str,
    /// The physical lower bound (damping ≥ 0).
    pub lower: f64,
    pub meaning: &'static str,
}

/// A candidate's fitted values, in the order of its [`ParamSpec`]s,
/// unconstrained (the bound is applied by `apply` and reported).
#[derive(Debug, Clone, PartialEq)]
pub struct Fitted {
    pub values: Vec<f64>,
}

/// A structural candidate (one file each; [`REGISTRY`]).
pub trait StructureCandidate: Sync {
    fn id(&self) -> &'static str;
    fn params(&self) -> &'static [ParamSpec];
    /// Fit on the runs `include` accepts; `model` is the model it extends.
    fn fit(&self, model: &RigParams, data: &BalanceData, include: &dyn Fn(&str) -> bool) -> Option<Fitted>;
    /// The model with this structure (parameters clamped at their bounds).
    fn apply(&self, model: &RigParams, fitted: &Fitted) -> RigParams;
    /// The structure in words and numbers.
    fn describe(&self, fitted: &Fitted) -> String;
    /// Admissible: every fitted parameter at or above its bound; else the
    /// parameters pinned there, as data.
    fn pinned(&self, fitted: &Fitted) -> Vec<(&'static ParamSpec, f64)> {
        self.params().iter().zip(&fitted.values).filter(|(p, v)| **v < p.lower).map(|(p, v)| (p, *v)).collect()
    }
}

/// Every structural candidate, the baseline (`twist_rate`) first.
pub static REGISTRY: &[&dyn StructureCandidate] =
    &[&twist_rate::TwistRate, &rotor_absolute::RotorAbsolute, &both::TwistRateAndRotor];

/// What the structure selection found.
#[derive(Clone)]
pub struct StructureSelection {
    /// The winning candidate's id (`twist_rate` when none beats the baseline).
    pub damping: &'static str,
    /// The extended model with the winning structure, fitted on every run.
    pub model: RigParams,
    /// The winner and its fit to every run (to apply it to another model,
    /// e.g. the bare baseline for the voltage steps).
    pub candidate: &'static dyn StructureCandidate,
    pub fitted: Fitted,
    /// Every candidate with its cross-validated free-run misfit.
    pub scores: Vec<StructureScore>,
    /// Parameters some candidate's fit to every run pins at a bound.
    pub at_bounds: Vec<ParamAtBound>,
    /// One sentence: which structure won and its free-run gain.
    pub notes: String,
}

/// Selects the damping structure on top of `ext` (module docs). `ext_pairs`
/// are the extended model's free runs (campaign order), `runs` the
/// diagnosis' rows: each run's cross-validation fold (numbered from 0) and
/// its nuisance phases, with which its free runs are simulated.
pub fn select_structure(
    c: &Campaign,
    data: &BalanceData,
    ext: &RigParams,
    ext_pairs: &[FreeRunPair],
    runs: &[crate::RunRow],
    s: &FreeRunSettings,
    opts: &DiagnoseOptions,
) -> StructureSelection {
    let fold_of: BTreeMap<&str, usize> = runs.iter().map(|r| (r.id.as_str(), r.fold)).collect();
    let phases: BTreeMap<&str, (f64, f64)> = runs.iter().map(|r| (r.id.as_str(), r.phases_rad)).collect();
    let folds = fold_of.values().max().map_or(0, |m| m + 1);
    let floor = crate::channels::speed_floor_rad_s(c, s);
    let base_ms: BTreeMap<&str, f64> =
        ext_pairs.iter().filter_map(|q| free_run_misfit(q, floor).map(|m| (q.id.as_str(), m))).collect();
    let base = REGISTRY[0];
    let base_fit = base.fit(ext, data, &|_| true).expect("the baseline's structure needs no fit");
    let mut scores = vec![StructureScore {
        id: base.id().into(),
        description: base.describe(&base_fit),
        free_run_misfit: overall(&base_ms.values().copied().collect::<Vec<_>>()),
        relative_gain: 0.0,
        relative_gain_fold_sd: 0.0,
        t: 0.0,
        admissible: true,
        accepted: false,
    }];
    let mut at_bounds = Vec::new();
    let mut best: Option<(usize, Fitted, f64)> = None;
    for (k, cand) in REGISTRY.iter().enumerate().skip(1) {
        let Some(full) = cand.fit(ext, data, &|_| true) else { continue };
        let fits: Vec<Option<Fitted>> =
            (0..folds).map(|f| cand.fit(ext, data, &|id| fold_of.get(id).is_some_and(|&g| g != f))).collect();
        let pairs: Vec<FreeRunPair> = free_run_pairs_by(c, s, |id| {
            let f = fits.get(*fold_of.get(id)?)?.as_ref()?;
            Some(with_run_phases(&cand.apply(ext, f), phases.get(id).copied().unwrap_or_default()))
        });
        let (mut before, mut after, mut fold_v) = (Vec::new(), Vec::new(), Vec::new());
        for q in &pairs {
            if let (Some(b), Some(a)) = (base_ms.get(q.id.as_str()), free_run_misfit(q, floor)) {
                before.push(*b);
                after.push(a);
                fold_v.push(fold_of[q.id.as_str()]);
            }
        }
        let cmp = compare_folds(&before, &after, &fold_v, folds);
        // Each term must be supported by the balance itself: its fit to every
        // run at least `min_t` fold-jackknife standard errors above its bound
        // (a placement whose new term the records put at ≈ 0 is the baseline
        // again, and its free-run "gain" is the chaos of stick-slip extrema).
        let se = jackknife_se(&fits, cand.params().len());
        let weak: Vec<String> = cand
            .params()
            .iter()
            .zip(&full.values)
            .zip(&se)
            .filter(|((p, v), se)| {
                matches!(
                    (**v - p.lower).partial_cmp(&(opts.selection.min_t * **se)),
                    Some(std::cmp::Ordering::Less) | None
                )
            })
            .map(|((p, v), se)| format!("{} = {v:.2e} ± {se:.1e} {}", p.name, p.unit))
            .collect();
        let pinned = cand.pinned(&full);
        for (p, v) in &pinned {
            at_bounds.push(ParamAtBound {
                parameter: p.name.into(),
                bound: p.lower,
                unconstrained: round_sig(*v, 3),
                meaning: format!(
                    "structure `{}`'s rotor-balance fit wants {} below its bound ({}): the records do not support \
                     that term; the candidate is inadmissible",
                    cand.id(),
                    p.meaning,
                    p.unit
                ),
            });
        }
        let admissible = pinned.is_empty() && weak.is_empty();
        let significant = cmp.gain >= opts.selection.min_relative_gain && cmp.t >= opts.selection.min_t;
        scores.push(StructureScore {
            id: cand.id().into(),
            description: if weak.is_empty() {
                cand.describe(&full)
            } else {
                format!("{}; not supported by the balance: {}", cand.describe(&full), weak.join(", "))
            },
            free_run_misfit: cmp.after,
            relative_gain: cmp.gain,
            relative_gain_fold_sd: cmp.gain_fold_sd,
            t: cmp.t,
            admissible,
            accepted: false,
        });
        if admissible && significant && best.as_ref().is_none_or(|b| cmp.gain > b.2) {
            best = Some((k, full, cmp.gain));
        }
    }
    let (k, fitted) = match best {
        Some((k, f, _)) => (k, f),
        None => (0, base_fit),
    };
    scores[k].accepted = true;
    let winner = REGISTRY[k];
    let sc = &scores[k];
    let notes = if k == 0 {
        let runner = scores.iter().skip(1).max_by(|a, b| a.relative_gain.total_cmp(&b.relative_gain));
        format!(
            "The rig model's damping on the twist rate stays: {}; no other placement lowers the cross-validated \
             free-run misfit ({:.3}) by the criterion{}.",
            winner.describe(&fitted),
            sc.free_run_misfit,
            runner.map_or(String::new(), |r| format!(
                " (best: {} with gain {:.1} %, t = {:.2}{})",
                r.id,
                100.0 * r.relative_gain,
                r.t,
                if r.admissible { "" } else { ", inadmissible" }
            ))
        )
    } else {
        format!(
            "{} (fitted through the rotor torque balance) lowers the extended model's cross-validated free-run misfit \
             from {:.3} to {:.3} (gain {:.1} % ± {:.1} % across folds, paired t = {:.2}).",
            capitalise(&winner.describe(&fitted)),
            scores[0].free_run_misfit,
            sc.free_run_misfit,
            100.0 * sc.relative_gain,
            100.0 * sc.relative_gain_fold_sd,
            sc.t
        )
    };
    StructureSelection {
        damping: winner.id(),
        model: winner.apply(ext, &fitted),
        candidate: winner,
        fitted,
        scores,
        at_bounds,
        notes,
    }
}

/// Fold-jackknife standard error of each parameter from the K fits that
/// each leave one fold out: sqrt((K − 1)/K · Σ (θ_k − θ̄)²) (∞ when a fold's
/// fit failed or K < 2).
fn jackknife_se(fits: &[Option<Fitted>], n: usize) -> Vec<f64> {
    let k = fits.len();
    if k < 2 || fits.iter().any(Option::is_none) {
        return vec![f64::INFINITY; n];
    }
    (0..n)
        .map(|i| {
            let v: Vec<f64> = fits.iter().flatten().map(|f| f.values[i]).collect();
            let m = v.iter().sum::<f64>() / k as f64;
            ((k as f64 - 1.0) / k as f64 * v.iter().map(|x| (x - m).powi(2)).sum::<f64>()).sqrt()
        })
        .collect()
}

fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or(String::new(), |f| f.to_uppercase().chain(c).collect())
}
