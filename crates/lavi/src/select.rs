//! The LAVI study's forward selection: a thin adapter onto the one engine,
//! `rig_types::select`. The units are the held-out windows; every fold is one
//! held-out window fitted on the calibration window (`Fold::shared_training`:
//! each candidate is fitted once per step); a unit's misfit is the free run's
//! phase-insensitive misfit ([`crate::score`]). The step rule is the engine's
//! (`[shared.selection]`: gain of the RMS held-out misfit ≥ `min_relative_gain`
//! and paired t of ln(M_before/M_after) over the windows ≥ `min_t`); the
//! candidates' admissibility rule is this study's: a candidate fitted on the
//! calibration window must be no worse there than the model it extends. Then
//! the adequacy verdict (crate docs).

use crate::fit::{Fitted, fit_candidate};
use crate::score::Evaluator;
use crate::sim::Model;
use crate::{Candidate, LaviError};
use rig_types::contract::SelectionRule;
use rig_types::select::{self as engine, Fold};
use serde::Serialize;
use std::collections::BTreeMap;

/// The study as the engine sees it.
struct Lavi<'a, 'b> {
    ev: &'a Evaluator<'b>,
    max_evals: usize,
}

impl engine::Study<Fitted> for Lavi<'_, '_> {
    fn score(&self, m: &Fitted, window: usize) -> f64 {
        self.ev.misfit(&m.model, window)
    }
}

impl engine::Candidate<Lavi<'_, '_>, Fitted> for Candidate {
    fn id(&self) -> &str {
        Candidate::id(*self)
    }

    fn fit(&self, s: &Lavi<'_, '_>, current: &Fitted, train: &[usize]) -> Result<Fitted, String> {
        if train != [s.ev.calibration()] {
            return Err(format!("fitted on the calibration window only, not on windows {train:?}"));
        }
        let fitted = fit_candidate(*self, &current.model, s.ev, s.max_evals).map_err(|e| e.to_string())?;
        // The engine scores the fitted model on every held-out window next: its free runs made
        // here as one batch (`Evaluator::outcomes`), the engine's scores then read them back.
        s.ev.heldout_misfits(&fitted.model);
        Ok(fitted)
    }

    fn inadmissible(&self, _: &Lavi<'_, '_>, current: &[Fitted], fitted: &[Fitted]) -> Option<String> {
        worse_on_calibration(&current[0], &fitted[0])
    }

    /// `top_delay` fits the torque channel's delay jointly with the top's (it is
    /// `channel_delay` at τ_top = 0): the two are alternatives, one per model.
    fn group(&self) -> Option<&str> {
        matches!(self, Candidate::ChannelDelay | Candidate::TopDelay).then_some("channel_clock")
    }
}

/// The admissibility rule: no worse on the window the candidate was fitted on.
fn worse_on_calibration(current: &Fitted, fitted: &Fitted) -> Option<String> {
    (fitted.calibration_misfit > current.calibration_misfit + 1e-12).then(|| {
        format!(
            "worse on the calibration window it was fitted on ({:.3} > {:.3})",
            fitted.calibration_misfit, current.calibration_misfit
        )
    })
}

/// One candidate tried at one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    pub step: usize,
    pub candidate: Candidate,
    pub fitted: Fitted,
    /// Held-out misfit per window (window order), of the extended model.
    pub heldout: Vec<f64>,
    /// The engine's overall held-out misfit: RMS over the windows.
    pub heldout_misfit: f64,
    /// 1 − M(extended)/M(current), M the overall held-out misfit.
    pub relative_gain: f64,
    /// Spread of the per-window gains (standard deviation over the windows).
    pub gain_spread: f64,
    /// Paired t of ln(M_current/M_extended) over the held-out windows.
    pub paired_t: f64,
    /// Held-out windows where the candidate is better than the current model.
    pub wins: usize,
    /// Admitted by the rule and no worse on the calibration window.
    pub earns_place: bool,
    /// Why the candidate could not be fitted at this step (its `fitted` is
    /// then the current model and its misfits infinite: never the best).
    pub refused: Option<String>,
}

/// The selection's outcome.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Selection {
    pub baseline_heldout: Vec<f64>,
    pub baseline_calibration: f64,
    /// Every trial of every step.
    pub trials: Vec<Trial>,
    /// Indices into `trials` of the chosen ones, in the order added.
    pub chosen: Vec<usize>,
    pub final_model: Model,
    pub final_heldout: Vec<f64>,
    pub rule: SelectionRule,
}

/// Runs the forward selection from `baseline` on the engine.
pub fn forward_select(
    ev: &Evaluator,
    baseline: &Model,
    candidates: &[Candidate],
    max_evals: usize,
    rule: &SelectionRule,
) -> Result<Selection, LaviError> {
    let base = Fitted {
        model: *baseline,
        at_bounds: Vec::new(),
        params: BTreeMap::new(),
        calibration_misfit: ev.misfit(baseline, ev.calibration()),
        evaluations: 0,
        top_scan: Vec::new(),
    };
    // The baseline's held-out free runs as one batch (the engine scores them first).
    ev.heldout_misfits(baseline);
    let study = Lavi { ev, max_evals };
    let cands: Vec<&dyn engine::Candidate<Lavi, Fitted>> =
        candidates.iter().map(|c| c as &dyn engine::Candidate<Lavi, Fitted>).collect();
    let folds = Fold::shared_training(&[ev.calibration()], &ev.heldout());
    let sel = engine::forward_select(&study, &cands, &base, &folds, rule)
        .map_err(|e| LaviError::Input { what: "forward selection", rule: e.0 })?;
    let mut current = base.clone();
    let mut trials = Vec::with_capacity(sel.trials.len());
    for t in &sel.trials {
        let fitted = match t.fitted.first() {
            Some(f) => f.clone(),
            None => Fitted {
                model: current.model,
                at_bounds: Vec::new(),
                params: BTreeMap::new(),
                calibration_misfit: f64::INFINITY,
                evaluations: 0,
                top_scan: Vec::new(),
            },
        };
        trials.push(Trial {
            refused: t.error.clone(),
            step: t.step,
            candidate: candidates[t.candidate],
            earns_place: t.significant && t.error.is_none() && worse_on_calibration(&current, &fitted).is_none(),
            fitted,
            heldout: t.misfits.clone(),
            heldout_misfit: t.comparison.after,
            relative_gain: t.comparison.gain,
            gain_spread: t.comparison.gain_fold_sd,
            paired_t: t.comparison.t,
            wins: t.wins,
        });
        if t.accepted {
            current = t.fitted[0].clone();
        }
    }
    Ok(Selection {
        baseline_heldout: sel.baseline_misfits,
        baseline_calibration: base.calibration_misfit,
        trials,
        chosen: sel.chosen,
        final_model: sel.final_models[0].model,
        final_heldout: sel.final_misfits,
        rule: rule.clone(),
    })
}

pub(crate) fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

pub(crate) fn std(x: &[f64]) -> f64 {
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len().max(2) - 1) as f64).sqrt()
}

/// The engine's overall misfit (RMS over the windows).
pub use rig_types::select::overall;

/// A candidate's last trial (the step the selection stopped at, or the one
/// that added it) against the model of that step, window by window, and
/// against every other candidate side by side: what the study reports of a
/// candidate whose own section says why it was or was not kept (`wob_level`,
/// `static_friction`).
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct TrialReport {
    pub step: usize,
    pub calibration_before: f64,
    pub calibration_after: f64,
    pub heldout_before: Vec<f64>,
    pub heldout_after: Vec<f64>,
    /// The engine's comparison of the trial with the model it extends.
    pub comparison: rig_types::select::Comparison,
    /// Held-out windows the trial improves.
    pub wins: usize,
    pub earns_place: bool,
    /// Per window (calibration first): features of the model it extends and of the trial.
    pub before: Vec<crate::Features>,
    pub after: Vec<crate::Features>,
    /// The trial against each other candidate of its step (paired t of ln(M_it/M_trial)), and the windows the trial is better.
    pub same_step: Vec<(Candidate, rig_types::select::Comparison, usize)>,
    /// The trial's model against each step-1 candidate, likewise (empty at step 1).
    pub step1: Vec<(Candidate, rig_types::select::Comparison, usize)>,
}

/// [`TrialReport`] of candidate `c`'s last trial, with the model that trial
/// extends and the trial itself (None: never tried, or refused at its last step).
pub fn trial_report<'s>(
    ev: &Evaluator,
    sel: &'s Selection,
    baseline: &Model,
    c: Candidate,
) -> Option<(TrialReport, Model, &'s Trial)> {
    use rig_types::select::compare;
    let t = sel.trials.iter().rev().find(|t| t.candidate == c)?;
    if t.refused.is_some() {
        return None;
    }
    let prior = (t.step >= 2).then(|| &sel.trials[sel.chosen[t.step - 2]]);
    let before_model = prior.map_or(*baseline, |p| p.fitted.model);
    let heldout_before = prior.map_or_else(|| sel.baseline_heldout.clone(), |p| p.heldout.clone());
    let calibration_before = prior.map_or(sel.baseline_calibration, |p| p.fitted.calibration_misfit);
    let n = t.heldout.len();
    let folds: Vec<usize> = (0..n).collect();
    let against = |r: &Trial| {
        let cmp = compare(&r.heldout, &t.heldout, &folds, n);
        (r.candidate, cmp, t.heldout.iter().zip(&r.heldout).filter(|(a, b)| a < b).count())
    };
    let rivals = |step: usize| -> Vec<(Candidate, rig_types::select::Comparison, usize)> {
        sel.trials.iter().filter(|r| r.step == step && r.candidate != c && r.refused.is_none()).map(against).collect()
    };
    let report = TrialReport {
        step: t.step,
        calibration_before,
        calibration_after: t.fitted.calibration_misfit,
        comparison: compare(&heldout_before, &t.heldout, &folds, n),
        heldout_before,
        heldout_after: t.heldout.clone(),
        wins: t.wins,
        earns_place: t.earns_place,
        before: ev.all_features(&before_model),
        after: ev.all_features(&t.fitted.model),
        same_step: rivals(t.step),
        step1: if t.step == 1 { Vec::new() } else { rivals(1) },
    };
    Some((report, before_model, t))
}

/// The `lavi.md` paragraphs every [`TrialReport`] shares: the targets per
/// held-out window before → after and the trial side by side with its rivals.
pub fn trial_section(s: &crate::study::Study, r: &TrialReport, id: &str) -> String {
    use std::fmt::Write as _;
    let nh = s.windows.len() - 1;
    let mut md = format!(
        "Per held-out window, the targets held (of 7) before (the model of that step) and after (`{id}` on it), and what the \
         latter misses (error over tolerance):\n\n| window | before: targets held | after: targets held | missed after |\n|---|---|---|---|\n"
    );
    md.push_str(&crate::drive::targets_before_after(s, &r.before, &r.after));
    let side = |list: &[(Candidate, rig_types::select::Comparison, usize)]| -> String {
        list.iter()
            .map(|(c, cmp, w)| {
                format!("`{}` {:.3}, gain {:.3}, t {:.2}, {w}/{nh}", c.id(), cmp.before, cmp.gain, cmp.t)
            })
            .collect::<Vec<_>>()
            .join("; ")
    };
    let _ = writeln!(
        md,
        "**Side by side** (held-out misfit of the rival, the gain of `{id}`'s model over it, the paired t of \
         ln(M_rival/M_{id}), the windows where `{id}`'s model is better): the other candidates of step {}: {}.{}\n",
        r.step,
        side(&r.same_step),
        if r.step1.is_empty() { String::new() } else { format!(" Every step-1 candidate: {}.", side(&r.step1)) }
    );
    // The rule's own test applied to each rival in place of the model the trial extends.
    let unbeaten: Vec<String> = r
        .same_step
        .iter()
        .chain(&r.step1)
        .filter(|(_, cmp, _)| !s.selection.rule.admits(cmp))
        .map(|(c, cmp, _)| format!("`{}` (gain {:.3}, t {:.2})", c.id(), cmp.gain, cmp.t))
        .collect();
    let _ = writeln!(
        md,
        "By the rule's own test (gain ≥ {:.0} %, t ≥ {}), `{id}`'s model does not beat, side by side: {}.\n",
        100.0 * s.selection.rule.min_relative_gain,
        s.selection.rule.min_t,
        if unbeaten.is_empty() { "none".to_string() } else { unbeaten.join(", ") }
    );
    md
}
