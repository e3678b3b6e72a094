//! The free-run second look at the vocabulary (issue 25, items 1 and 5):
//! an effect the teacher-forced rule saw but refused is judged where the
//! model is used, in free run, when the final model's free run is flagged.
//!
//! Teacher-forcing in slip weighs an effect by how much of the slip
//! friction's scatter it explains. A small velocity weakening (μs − μk of
//! 1 % of μ, one of the battery's detection rungs) explains 3 % of it, below
//! the selection's minimum gain of 5 %, while its paired run-level t is 5.6:
//! the effect is there, but too small to earn its place on that channel.
//! Yet the free run sees it: the slip friction level the motion settles at
//! misses the record's by 5× its floor, and the answer, without a cause, was
//! `unexplained` although the vocabulary names the cause.
//!
//! # The rule
//!
//! Only when a free-run check of the final model (twist-rate structure) is
//! flagged while the model is otherwise adequate — the teacher-forced misfit
//! within its threshold, no order line, no other check flagged: the mismatch
//! shows only in the motion —, each effect of the last selection step with
//! - a paired run-level t ≥ `min_t` and a positive gain teacher-forced
//!   ([`crate::select::Selection::near_misses`]),
//! - an admissible fit on every run (its sign defines it),
//!
//! is added to the final model with its parameters fitted teacher-forced
//! **without each fold**, every run is simulated free with its own fold's
//! model (and its phases under it), and its free-run misfit (every channel,
//! [`crate::channels::free_run_misfit_channels`]) is compared with the final
//! model's on the same run by the selection's rule (gain ≥ the minimum and
//! paired t ≥ `min_t`). It is admitted only if, in addition, **none** of the
//! free-run checks is flagged with it: an effect admitted in free run must
//! explain the free-run gap that called for it, not only shrink it. Of the
//! effects that pass, the largest free-run gain is admitted (one per
//! diagnosis); the selection is then concluded with it
//! ([`crate::select::Selection::admit`]) and the whole chain (structure,
//! free-run checks, extension) runs again on the new final model.
//!
//! The baseline of the comparison is the final model fitted on every run,
//! so the candidate, fitted without each run's fold, is compared against an
//! in-sample model: the comparison leans against the candidate.
//!
//! Why it cannot raise false alarms where the first look could not: it runs
//! only when the final model's free run is already flagged (the nulls' free
//! runs are calibrated to 0 flags in 40, `free_run_calibration.rs`), and it
//! can only replace an `unexplained` answer by a vocabulary effect that
//! leaves no free-run check flagged. Where another check fails too (a force
//! sensor's bend, say), it does not run: on the full battery's
//! `outside-force_sensor_nonlinearity-1` an angle-periodic friction cleared
//! the free run while compensating the sensor's bend, a spurious finding.

use crate::channels::{
    ChannelCheck, FreeRunPair, FreeRunSettings, free_run_checks_of, free_run_misfit_channels, free_run_pairs_by,
    speed_floor_rad_s, with_run_phases,
};
use crate::prepare::{RunSignals, SensorLaw};
use crate::select::{Comparison, NearMiss, compare_folds};
use crate::{ChannelOptions, DiagnoseOptions, breakaway, extended_params};
use rig_types::{Campaign, RigParams};
use serde::Serialize;
use std::collections::BTreeMap;

/// One candidate of the second look, as the report lists it.
#[derive(Debug, Clone, Default, PartialEq, Serialize)]
pub struct SecondLookRow {
    pub effect: String,
    /// Teacher-forced, at the selection's last step.
    pub teacher_forced_gain: f64,
    pub teacher_forced_t: f64,
    /// Free run: the final model's misfit, with the effect, gain, its fold
    /// spread and the paired run-level t.
    pub free_run_before: f64,
    pub free_run_after: f64,
    pub free_run_gain: f64,
    pub free_run_gain_fold_sd: f64,
    pub free_run_t: f64,
    /// The free-run checks still flagged with the effect.
    pub still_flagged: Vec<String>,
    pub admitted: bool,
}

/// What the second look needs from the diagnosis.
pub struct Inputs<'a> {
    pub c: &'a Campaign,
    /// The prepared operating points, in the order of the selection's runs.
    pub runs: &'a [RunSignals],
    pub law: &'a SensorLaw,
    pub baseline: &'a RigParams,
    /// The final model's free runs (campaign order), fitted on every run.
    pub before: &'a [FreeRunPair],
    pub s: &'a FreeRunSettings,
    pub o: &'a ChannelOptions,
    pub opts: &'a DiagnoseOptions,
}

/// The second look at `near` (module docs): every candidate's row, and the
/// index of the one admitted, if any.
pub fn second_look(x: &Inputs, near: &[NearMiss]) -> (Vec<SecondLookRow>, Option<usize>) {
    let floor = speed_floor_rad_s(x.c, x.s);
    let ids: Vec<&str> = x.runs.iter().map(|r| r.id.as_str()).collect();
    let base: BTreeMap<&str, f64> =
        x.before.iter().filter_map(|q| free_run_misfit_channels(q, floor).map(|m| (q.id.as_str(), m))).collect();
    let mut rows = Vec::new();
    let mut best: Option<(usize, f64)> = None;
    for (k, m) in near.iter().enumerate() {
        let (cmp, checks) = judge(x, m, &ids, &base, floor);
        let still: Vec<String> = checks.iter().filter(|c| c.flagged).map(|c| c.channel.clone()).collect();
        let admitted = x.opts.selection.admits(&cmp) && still.is_empty();
        if admitted && best.is_none_or(|(_, g)| cmp.gain > g) {
            best = Some((k, cmp.gain));
        }
        rows.push(SecondLookRow {
            effect: m.effect.id().into(),
            teacher_forced_gain: m.teacher_forced.gain,
            teacher_forced_t: m.teacher_forced.t,
            free_run_before: cmp.before,
            free_run_after: cmp.after,
            free_run_gain: cmp.gain,
            free_run_gain_fold_sd: cmp.gain_fold_sd,
            free_run_t: cmp.t,
            still_flagged: still,
            admitted: false,
        });
    }
    if let Some((k, _)) = best {
        rows[k].admitted = true;
    }
    (rows, best.map(|b| b.0))
}

/// The free-run comparison of one near miss against the final model, and
/// the free-run checks with it.
fn judge(
    x: &Inputs,
    m: &NearMiss,
    ids: &[&str],
    base: &BTreeMap<&str, f64>,
    floor: f64,
) -> (Comparison, Vec<ChannelCheck>) {
    // Each run's phases under its own fold's model, by run id.
    let phases: BTreeMap<String, (f64, f64)> =
        ids.iter().zip(&m.per_run).filter_map(|(id, r)| r.map(|(_, ph)| (id.to_string(), ph))).collect();
    // Per fold, the extended model with the effect, at the static level it
    // breaks away at under its own normal force (as the final model's).
    let models: Vec<Option<RigParams>> = m
        .per_fold
        .iter()
        .map(|v| {
            let p = extended_params(x.baseline, v.as_ref()?);
            Some(breakaway::at_own_level(x.c, x.law, &p, &phases, &x.opts.stick_episodes).0)
        })
        .collect();
    let run_of: BTreeMap<&str, (usize, (f64, f64))> =
        ids.iter().zip(&m.per_run).filter_map(|(id, r)| r.map(|r| (*id, r))).collect();
    let pairs = free_run_pairs_by(x.c, x.s, |id| {
        let (f, ph) = run_of.get(id)?;
        Some(with_run_phases(models.get(*f)?.as_ref()?, *ph))
    });
    let folds = m.per_fold.len();
    let (mut b, mut a, mut fv) = (Vec::new(), Vec::new(), Vec::new());
    for q in &pairs {
        if let (Some(y0), Some(y1), Some((f, _))) =
            (base.get(q.id.as_str()), free_run_misfit_channels(q, floor), run_of.get(q.id.as_str()))
        {
            b.push(*y0);
            a.push(y1);
            fv.push(*f);
        }
    }
    let cmp = compare_folds(&b, &a, &fv, folds);
    (cmp, free_run_checks_of(x.c, &pairs, x.s, x.o))
}

/// Records the second look's rows in the report's detail and, for the
/// effect it admitted, says so in the finding's evidence.
pub fn attach(d: &mut crate::Diagnosis, rows: Vec<SecondLookRow>) {
    if let Some(r) = rows.iter().find(|r| r.admitted)
        && let Some(f) = d.findings.iter_mut().find(|f| f.effect == r.effect)
    {
        f.evidence.push_str(&format!(
            " Refused teacher-forced (gain {:.1} %, below the minimum; paired t {:.1}), it was admitted in free run \
             (the final model's free run was flagged): free-run misfit {:.3} → {:.3}, gain {:.1} % ± {:.1} % across \
             folds, paired t {:.2}, and no free-run check is left flagged with it.",
            100.0 * r.teacher_forced_gain,
            r.teacher_forced_t,
            r.free_run_before,
            r.free_run_after,
            100.0 * r.free_run_gain,
            100.0 * r.free_run_gain_fold_sd,
            r.free_run_t
        ));
    }
    d.detail.second_look = rows;
}
