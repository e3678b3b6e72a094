//! `wob_level`: the contact's normal force is the weight on bit's slow level.
//!
//! Coulomb's law on the bit's face, T = r μ(Ω) N (the thesis' Eq. 4-11 idea of
//! a normal force that varies; the rig measures it as the weight on bit W):
//! with the law T(Ω) fitted on the calibration window, where the normal force
//! is W̄ and averages W_ref, T(Ω, t) = T(Ω) · W̄(t) / W_ref, W̄ the measured WOB's centred
//! moving mean over `window_s` (rig_types::sensor::centred_moving_average: zero
//! phase, the window shrinking symmetrically at the record's ends).
//!
//! Why the slow level and not W(t) (`wob_normal_force`): the WOB's fast part
//! (std 9–18 % of its mean within a window, at the stick-slip frequency) is
//! in the record's phase of the cycle, which a free run does not keep; driven
//! into a free run it scales the friction at the wrong phase. Its level moves
//! between the windows (526–598 N against 554 N in the calibration window)
//! and, within 52–56 s, from 480–510 N to 550–610 N. What the record shows:
//! the `top_delay` model's errors over tolerance on the held-out windows
//! follow the window's mean WOB (stick fraction r = −0.70, loop area −0.63,
//! slip torque −0.57; docs/findings.md): a friction level fitted at 554 N,
//! too low where the WOB is above it, too high where it is below.
//!
//! Fit (calibration window only): the law is kept (its level is the
//! calibration window's; W_ref the mean of W̄ at that span over the window's
//! samples, so the scale averages 1 where the law was fitted: the raw WOB's
//! mean, as first built, left W̄'s centred mean reaching outside the window
//! and the scale ≈ 1 % above 1 there at 4 s); the span is chosen among
//! [`SPANS_S`] by the calibration misfit (ties: the shorter), each at least
//! a stick-slip cycle (0.3–0.45 s) so that the cycle's own WOB swing is
//! averaged out.
//!
//! On run 175 (docs/findings.md, eleventh and fourteenth sessions): with
//! W_ref the raw WOB's mean (554.3 N) every span scored worse on the
//! calibration window than no level (0.208 against 0.195 at 4 s), refused;
//! with W_ref W̄'s own mean (559.6 N at 4 s) the 4 s span scores 0.194, the
//! rule admits it at step 2 (held out 1.496 → 1.396, paired t 2.06), by a
//! calibration difference the window does not resolve over the free run's
//! start (the section's resolution paragraph): landed in the fifteenth
//! session as a fix of construction, the rule unchanged.

use crate::score::Evaluator;
use crate::select::{Selection, TrialReport, mean, trial_report, trial_section};
use crate::sim::Model;
use crate::{Candidate, LaviError, StudyParams};
use rayon::prelude::*;
use rig_types::sensor::centred_moving_average;
use serde::Serialize;
use std::collections::BTreeMap;

/// The spans the fit chooses among, s.
pub const SPANS_S: [f64; 4] = [0.5, 1.0, 2.0, 4.0];

/// The normal force's slow level: W̄ over `window_s`, relative to `reference_n`.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct WobLevel {
    pub window_s: f64,
    pub reference_n: f64,
}

impl WobLevel {
    /// The half-width of the centred mean in samples at `fs_hz` (at least 1).
    pub fn half_samples(&self, fs_hz: f64) -> usize {
        ((self.window_s * fs_hz).round() as usize / 2).max(1)
    }

    /// W̄ over the whole record `wob_n`, N: the workspace's centred moving
    /// average (rig_types::sensor; zero phase, the window shrinking
    /// symmetrically at the record's ends).
    pub fn level_n(&self, wob_n: &[f64], fs_hz: f64) -> Vec<f64> {
        centred_moving_average(wob_n, self.half_samples(fs_hz))
    }
}

/// W̄ over the whole record for every span of [`SPANS_S`] (made once per study, [`Evaluator`]).
pub fn levels(wob_n: &[f64], fs_hz: f64) -> Vec<(f64, Vec<f64>)> {
    SPANS_S.iter().map(|&window_s| (window_s, WobLevel { window_s, reference_n: 1.0 }.level_n(wob_n, fs_hz))).collect()
}

/// The level over `window_s` with its reference W_ref: the level's own mean over the
/// calibration window's samples, N (where the law was fitted, the normal force the candidate
/// states is W̄(t), so the law's level is W̄'s there: the scale W̄/W_ref averages 1 over that window).
pub fn level_at(ev: &Evaluator, window_s: f64) -> WobLevel {
    let cal = &ev.windows[ev.calibration()];
    let lv = ev.wob_level_n(&WobLevel { window_s, reference_n: 1.0 });
    let w = &lv[cal.span.start + cal.window.start..cal.span.start + cal.window.end];
    WobLevel { window_s, reference_n: w.iter().sum::<f64>() / w.len() as f64 }
}

/// Fits `wob_level` on top of `current` (module docs); fills the candidate's parameters.
pub fn fit(current: &Model, ev: &Evaluator, params: &mut BTreeMap<String, f64>) -> Result<(Model, usize), LaviError> {
    if current.wob_ref_n.is_some() {
        return Err(LaviError::Refused {
            candidate: "wob_level",
            reason: "the instantaneous weight on bit is the model's normal force already (`wob_normal_force`)".into(),
        });
    }
    let cal = ev.calibration();
    // The spans' free runs as one batch, in order; the first of equal misfits (the shorter span) kept.
    let models: Vec<Model> =
        SPANS_S.iter().map(|&window_s| Model { wob_level: Some(level_at(ev, window_s)), ..*current }).collect();
    let misfits = ev.misfits(&models.iter().map(|m| (m, cal)).collect::<Vec<_>>());
    let best = misfits.into_iter().zip(models).reduce(|a, b| if b.0 < a.0 { b } else { a }).expect("spans");
    params.insert("wob_level_window_s".into(), best.1.wob_level.map_or(f64::NAN, |l| l.window_s));
    params.insert("reference_wob_n".into(), best.1.wob_level.map_or(f64::NAN, |l| l.reference_n));
    Ok((best.1, SPANS_S.len()))
}

/// What the study reports of `wob_level`: its last trial against the model
/// of that step and its rivals ([`TrialReport`]), the spans and the level per window.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WobLevelReport {
    pub trial: TrialReport,
    pub level: WobLevel,
    /// The calibration misfit at each span of [`SPANS_S`] (the fit's choice).
    pub span_misfits: Vec<f64>,
    /// Per window: the weight on bit's mean over the window and its slow level's least and largest value there, N.
    pub wob_n: Vec<[f64; 3]>,
    /// What the calibration window resolves: per warm-up of [`START_WARMUPS_S`] (the free run
    /// started from the measured state that long before the window), the calibration misfit of
    /// the model the trial extends and of the trial.
    pub start_resolution: Vec<[f64; 3]>,
    /// The kept level's mean over the calibration window's samples, N (against `level.reference_n`).
    pub calibration_level_mean_n: f64,
}

/// Warm-ups the calibration misfit is recomputed at to judge the admissibility difference
/// against the free run's start, s (the study's own is `warmup_s`, 3 s).
pub const START_WARMUPS_S: [f64; 9] = [2.0, 2.25, 2.5, 2.75, 3.0, 3.25, 3.5, 3.75, 4.0];

/// The calibration misfits of `before` and `after` with the free run started at each warm-up of
/// [`START_WARMUPS_S`]: the spread a model's calibration misfit has over where its free run
/// starts, against which the admissibility rule's difference is read.
fn start_resolution(
    ev: &Evaluator,
    p: &StudyParams,
    before: &Model,
    after: &Model,
) -> Result<Vec<[f64; 3]>, LaviError> {
    START_WARMUPS_S
        .par_iter()
        .map(|&warmup_s| {
            let q = StudyParams { warmup_s, heldout_starts_s: Vec::new(), ..p.clone() };
            let wins = crate::data::windows(ev.data, &q)?;
            let e = Evaluator::new(ev.data, wins, ev.fopts, ev.substeps, ev.slip_speed_rpm, p.drive_ref_window_s)?;
            let m = e.misfits(&[(before, 0), (after, 0)]);
            Ok([warmup_s, m[0], m[1]])
        })
        .collect()
}

/// [`WobLevelReport`] of the selection (None: `wob_level` refused at its last step, or not tried).
pub fn report(
    ev: &Evaluator,
    sel: &Selection,
    baseline: &Model,
    p: &StudyParams,
) -> Result<Option<WobLevelReport>, LaviError> {
    let Some((trial, before_model, t)) = trial_report(ev, sel, baseline, Candidate::WobLevel) else { return Ok(None) };
    let Some(level) = t.fitted.model.wob_level else { return Ok(None) };
    let cal = ev.calibration();
    let spans: Vec<Model> =
        SPANS_S.iter().map(|&window_s| Model { wob_level: Some(level_at(ev, window_s)), ..before_model }).collect();
    let span_misfits = ev.misfits(&spans.iter().map(|m| (m, cal)).collect::<Vec<_>>());
    let d = ev.data;
    let wob_n = ev
        .windows
        .iter()
        .map(|w| {
            let s = w.span.start + w.window.start..w.span.start + w.window.end;
            let lv = &ev.wob_level_n(&level)[s.clone()];
            let lo = lv.iter().cloned().fold(f64::INFINITY, f64::min);
            let hi = lv.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
            [mean(&d.wob_n[s]), lo, hi]
        })
        .collect();
    let start_resolution = start_resolution(ev, p, &before_model, &t.fitted.model)?;
    let c = &ev.windows[cal];
    let calibration_level_mean_n =
        mean(&ev.wob_level_n(&level)[c.span.start + c.window.start..c.span.start + c.window.end]);
    Ok(Some(WobLevelReport { trial, level, span_misfits, wob_n, start_resolution, calibration_level_mean_n }))
}

/// The `lavi.md` section of `wob_level`: the spans, the verdict of the
/// calibration window and the rule, per window before → after, side by side.
pub fn section(s: &crate::study::Study) -> String {
    use std::fmt::Write as _;
    let Some(w) = &s.wob_level else { return String::new() };
    let r = &w.trial;
    let nh = s.windows.len() - 1;
    let step_model = step_model(s, r.step);
    let mut md = String::from("## The weight on bit's slow level (`wob_level`)\n\n");
    let _ = writeln!(
        md,
        "Coulomb's law on the bit's face, T = r μ(Ω) N, with the normal force N the weight on bit's slow level: the law kept at the \
         calibration window and scaled by W̄(t)/W_ref, W̄ the measured WOB's centred moving mean over a span chosen on the calibration \
         window, W_ref = {:.1} N its mean over the calibration window (where the law was fitted: the scale averages 1 there; \
         rig_lavi::wob_level). Why: the targets the model misses follow each window's mean WOB \
         (docs/findings.md), and the WOB's fast part is in the record's phase of the cycle, not the free run's (`wob_normal_force`). \
         Tried at step {} on {step_model}.\n",
        w.level.reference_n, r.step
    );
    md.push_str("| window | mean WOB [N] | W̄ over the window at the kept span [N] |\n|---|---|---|\n");
    for (win, x) in s.windows.iter().zip(&w.wob_n) {
        let _ = writeln!(md, "| {} | {:.0} | {:.0}–{:.0} |", win.label, x[0], x[1], x[2]);
    }
    let spans: Vec<String> = SPANS_S.iter().zip(&w.span_misfits).map(|(sp, m)| format!("{sp} s {m:.3}")).collect();
    let _ = writeln!(
        md,
        "\n**The fit and the verdict.** Calibration misfit per span: {} (without the level: {:.3}); kept: {} s, {:.3}. {}\n",
        spans.join(", "),
        r.calibration_before,
        w.level.window_s,
        r.calibration_after,
        verdict(s, r, nh),
    );
    let diff: Vec<f64> = w.start_resolution.iter().map(|x| x[2] - x[1]).collect();
    let (lo, hi) = diff.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), d| (a.min(*d), b.max(*d)));
    let m = mean(&diff);
    let _ = writeln!(
        md,
        "**What the calibration window resolves.** The free run started from the measured state {:.2}–{:.2} s before the window \
         (the study's {} s; {} starts): the model of that step scores {:.3}–{:.3} there, `wob_level` {:.3}–{:.3}; the difference \
         `wob_level` minus the model it extends is {m:+.4} ± {:.4} (mean ± sd over the starts), {lo:+.4} to {hi:+.4}: {}. At the \
         kept span W̄ averages {:.1} N over the calibration window's samples, W_ref by construction; the raw WOB's mean there, \
         {:.1} N, the reference as first built, would scale the window's own law by {:+.1} % on average (the centred mean reaches \
         {} s beyond the window's ends; docs/findings.md, fourteenth and fifteenth sessions).\n",
        START_WARMUPS_S[0],
        START_WARMUPS_S[START_WARMUPS_S.len() - 1],
        s.params.warmup_s,
        START_WARMUPS_S.len(),
        w.start_resolution.iter().map(|x| x[1]).fold(f64::INFINITY, f64::min),
        w.start_resolution.iter().map(|x| x[1]).fold(f64::NEG_INFINITY, f64::max),
        w.start_resolution.iter().map(|x| x[2]).fold(f64::INFINITY, f64::min),
        w.start_resolution.iter().map(|x| x[2]).fold(f64::NEG_INFINITY, f64::max),
        crate::select::std(&diff),
        if lo > 0.0 {
            "of one sign at every start, so the window's refusal is no accident of where the free run starts (the rule is \
             applied as it stands)"
        } else if hi < 0.0 {
            "of one sign at every start: the window prefers `wob_level` at every start"
        } else {
            "of either sign over the starts: the window does not resolve the difference (the rule reads it at the study's \
             start, as it stands)"
        },
        w.calibration_level_mean_n,
        w.wob_n[0][0],
        100.0 * (w.calibration_level_mean_n / w.wob_n[0][0] - 1.0), // window order: the calibration first
        w.level.window_s / 2.0,
    );
    md.push_str(&trial_section(s, r, "wob_level"));
    md
}

/// "baseline + …" of the model that step `step` extends.
pub(crate) fn step_model(s: &crate::study::Study, step: usize) -> String {
    if step == 1 {
        "the baseline".to_string()
    } else {
        let ids: Vec<&str> =
            s.selection.chosen[..step - 1].iter().map(|&i| s.selection.trials[i].candidate.id()).collect();
        format!("baseline + {}", ids.join(" + "))
    }
}

/// The held-out comparison of a [`TrialReport`] and what the rule and the calibration window say of it.
pub(crate) fn verdict(s: &crate::study::Study, r: &TrialReport, nh: usize) -> String {
    let (admitted, admissible) =
        (s.selection.rule.admits(&r.comparison), r.calibration_after <= r.calibration_before + 1e-12);
    format!(
        "Held out: {:.3} → {:.3} (gain {:.3}, paired t {:.2}, better on {}/{} windows; per window {}). The rule (gain ≥ {:.0} %, t ≥ \
         {}) {} it; the calibration window {}: {}.",
        r.comparison.before,
        r.comparison.after,
        r.comparison.gain,
        r.comparison.t,
        r.wins,
        nh,
        r.heldout_before
            .iter()
            .zip(&r.heldout_after)
            .map(|(b, a)| format!("{b:.3} → {a:.3}"))
            .collect::<Vec<_>>()
            .join(", "),
        100.0 * s.selection.rule.min_relative_gain,
        s.selection.rule.min_t,
        if admitted { "admits" } else { "does not admit" },
        if admissible { "accepts it (no worse there)" } else { "refuses it (worse there than the model it extends)" },
        if r.earns_place { "**earns its place**" } else { "**not kept**" },
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::data::RPM_TO_RAD_S;
    use crate::fit::tests::{prepared, window_4_8};

    /// Steady slip at 20 rad/s (20 v_s: the law at its kinetic 1 N m) under a weight on bit that
    /// steps from 500 to 600 N at 6 s: with W_ref 500 N and a 1 s span the friction reads 1 N m a
    /// second before the step (its centred mean all 500 N) and 1.2 N m 1.9 s after it; without
    /// the level, 1 N m throughout.
    #[test]
    fn the_friction_follows_the_weight_on_bits_slow_level() {
        let n = 12_000;
        let rpm = 20.0 / RPM_TO_RAD_S;
        let bit: Vec<f64> = (0..n).map(|i| rpm + (std::f64::consts::TAU * 2.0 * i as f64 / 1000.0).sin()).collect();
        let mut d = prepared((0..n).map(|i| i as f64 / 1000.0).collect(), vec![rpm; n], bit, vec![1.0; n]);
        d.wob_n = (0..n).map(|i| if i < 6000 { 500.0 } else { 600.0 }).collect();
        let fopts = crate::FeatureOptions { fs_hz: 1000.0, cutoff_hz: 10.0, transition_hz: 2.0, stick_speed_rpm: 5.0 };
        let ev = Evaluator::new(&d, vec![window_4_8()], fopts, 5, 5.0, 1.0).unwrap();
        let plain = crate::sim::tests::base();
        let m = Model { wob_level: Some(WobLevel { window_s: 1.0, reference_n: 500.0 }), ..plain };
        // The span 1000..8000: sample 5000 is index 4000, sample 7900 index 6900.
        let (r, r0) = (ev.simulate(&m, 0).unwrap(), ev.simulate(&plain, 0).unwrap());
        assert!(
            (r.torque_nm[4000] - 1.0).abs() < 1e-6 && (r0.torque_nm[4000] - 1.0).abs() < 1e-6,
            "{}",
            r.torque_nm[4000]
        );
        assert!(
            (r.torque_nm[6900] - 1.2).abs() < 1e-6 && (r0.torque_nm[6900] - 1.0).abs() < 1e-6,
            "{}",
            r.torque_nm[6900]
        );
        // The level is the workspace's centred mean: 550 N at the step, 500 and 600 N half a span away.
        let w = ev.wob_level_n(&m.wob_level.unwrap());
        assert!((w[6000] - 550.0).abs() < 0.1 && w[5499] == 500.0 && (w[6500] - 600.0).abs() < 1e-9, "{}", w[6000]);
    }

    /// The reference is the level's own mean over the calibration window's samples, not the raw
    /// WOB's: a WOB of 500 N stepping to 600 N at 8 s, the window's end, has a raw mean of 500 N
    /// over 4-8 s, while its 4 s centred mean (±2000 samples) rises from 6 s on, by 100 (i − 5999)/4001
    /// at sample i: over the window's 4000 samples it averages 500 + 100 · (Σ_{j=1}^{2000} j/4001)/4000
    /// = 512.5025 N.
    #[test]
    fn the_reference_is_the_levels_mean_where_the_law_was_fitted() {
        let n = 12_000;
        let mut d = prepared((0..n).map(|i| i as f64 / 1000.0).collect(), vec![60.0; n], vec![60.0; n], vec![1.0; n]);
        d.wob_n = (0..n).map(|i| if i < 8000 { 500.0 } else { 600.0 }).collect();
        let fopts = crate::FeatureOptions { fs_hz: 1000.0, cutoff_hz: 10.0, transition_hz: 2.0, stick_speed_rpm: 5.0 };
        let ev = Evaluator::new(&d, vec![window_4_8()], fopts, 5, 5.0, 1.0).unwrap();
        let expected = 500.0 + 100.0 * (2000.0 * 2001.0 / 2.0 / 4001.0) / 4000.0;
        let l = level_at(&ev, 4.0);
        assert!((l.reference_n - expected).abs() < 1e-9, "{} {expected}", l.reference_n);
        // At 0.5 s (±250 samples) only the window's last 250 samples rise, by 100 (i − 7749)/501.
        let short = 500.0 + 100.0 * (250.0 * 251.0 / 2.0 / 501.0) / 4000.0;
        assert!((level_at(&ev, 0.5).reference_n - short).abs() < 1e-9, "{}", level_at(&ev, 0.5).reference_n);
    }
}
