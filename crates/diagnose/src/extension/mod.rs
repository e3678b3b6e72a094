//! The extension of an `unexplained` answer (issue 25, item 6;
//! ../shared/spec/diagnosis.md, `extension`): the best data-driven friction
//! term from a library of state and history signals the simulator carries
//! (rig-model's `extension` module and `Effect::FrictionExtension`), chosen
//! by sparse forward selection on the cross-validated **free-run** misfit.
//!
//! # The library
//!
//! | signal | acts on | fitted on |
//! |---|---|---|
//! | `slip_speed_rad_s` (\|Ω1\|) | μ in slip | every 5th slip sample: μ_obs/μ̂ − 1 |
//! | `breakaway_transient` (exp(−t_slip/τ_b), t_slip the time since the rotor last stood) | μ in slip | the same |
//! | `static_level` (1) | μs at break-away | every break-away: F_peak/(μ̂s·N) − 1 |
//! | `log_dwell` (ln(1 + t_stick/τ_d), t_stick the length of the stick episode) | μs at break-away | **free run** (below), with `static_level` |
//!
//! μ̂ and μ̂s are the final model's (findings and structure, each run with its
//! own nuisance phases); the records give μ_obs = F/N0 in slip
//! ([`crate::prepare`]) and, for every stick episode that ends in a
//! break-away (the estimation's rules, `rig_estimate::friction::stick_episodes`,
//! `[shared.stick_episodes]`, as the free-run `breakaway_friction` feature
//! reads them; the stretches of |Ω1| below the slip speed this used before
//! are mostly encoder chatter of a creeping rotor), the raw peak of the
//! friction force and the episode's length. Heat (integrated friction power) and
//! slid distance would need more simulator states (rig-model's docs); the
//! teacher-forced residual signature still names them.
//!
//! # The ageing law (issue 25, item 5)
//!
//! `log_dwell` always enters with `static_level`: μs(t_stick) = μs_model·(1 +
//! c_0 + c_d·ln(1 + t_stick/τ_d)) = μs0 + β·ln(1 + t_stick/τ_d), contact
//! ageing (Dieterich 1972; Baumberger & Caroli, Adv. Phys. 55 (2006) 279),
//! simulated in the rig model by `Effect::FrictionExtension` (the pad state
//! is the contact's age, reset at every stick/slip event and 0 at the start
//! of a run, which starts at rest). Its signature is at break-away and in
//! the stick durations, where teacher-forcing in slip cannot see it, and a
//! teacher-forced fit on the break-aways alone made the free run of the CI
//! battery's ageing case 18× worse (misfit 2.86 → 52.5), so c_d is fitted
//! **by free-run simulation**: Brent's search ([`brent_min`], at most
//! [`DWELL_FIT_EVALS`] free runs of the training runs) over c_d ∈ [0,
//! [`DWELL_SLOPE_MAX`]] of the training runs' mean squared free-run misfit
//! (every channel), with c_0 at each c_d the least squares of the training
//! break-aways (the level the records fix at that slope). τ_d = 0.1 s is not
//! fitted: every dwell of the rig (0.3 s steady sticks to 2 s from rest) is
//! several τ_d, where β·ln(1 + t/τ) hardly tells τ from β (the CI case's
//! truth, β = 0.028 at τ = 0.187 s, and the fit, β = 0.022 at 0.1 s, rise by
//! 0.052 and 0.053 over 1 s). The law lives here, in the extension's library,
//! and not in the vocabulary's free-run hook
//! ([`crate::effects::VocabularyEffect::fit_free_run`]): ageing is outside
//! the spec's vocabulary, so an ageing campaign is `unexplained` with this
//! extension (the `operating_point.breakaway_dwell` check keeps it so).
//!
//! # Fit, selection and gain
//!
//! A set of signals is fitted teacher-forced by least squares (the workspace's
//! solver, no intercept: the signals' coefficients are relative changes of the
//! model's coefficients) on the training folds, and every held-out run is then
//! **simulated free** with the model fitted without it; its free-run misfit
//! ([`crate::channels::free_run_misfit_channels`], every channel) is compared with the
//! final model's on the same run by the selection's rule (gain ≥ the minimum
//! and paired run-level t ≥ `min_t`, [`crate::select`]'s comparison). Forward
//! selection adds the best signal while it passes; the reported extension is
//! the selected set, or, when no signal passes, the best single signal (its
//! gain then says it explains nothing). Coefficients are fitted on every run;
//! their standard errors are the jackknife over the folds (the run, not the
//! sample, is the independent unit).
//!
//! # Cost
//!
//! One free-run simulation of every operating point per candidate set: at
//! most 4 + 3 + 2 + 1 = 10 sets (the library has four signals), each one
//! rayon-parallel over runs (campaign order kept; deterministic), and the
//! teacher-forced rows are built once; a set with the ageing law adds its
//! free-run fit, (folds + 1) × at most [`DWELL_FIT_EVALS`] free runs of the
//! training runs (the CI ageing case: 2.4 → 14 s on a loaded 2-core
//! machine). Only an `unexplained` verdict with a baseline model pays it.

pub mod drift;
pub mod dwell;

use crate::channels::{
    ChannelCheck, FreeRunPair, FreeRunSettings, free_run_checks_of, free_run_misfit_channels, free_run_pairs_by,
    speed_floor_rad_s, with_run_phases,
};
use crate::prepare::RunSignals;
use crate::result::{Extension, ExtensionTerm, SpeedTraces, StepRow, round_sig};
use crate::select::compare_folds;
use rig_estimate::friction::stick_episodes;
use rig_model::extension::{BREAKAWAY_TIME_S, DWELL_TIME_S, slip_signals, static_signals};
use rig_model::friction::{normal_force_n, slip_mu, static_mu};
use rig_types::minimize::brent_min;
use rig_types::select::Comparison;
use rig_types::{Campaign, Effect, RigParams};
use std::collections::BTreeMap;

/// The library's signals, in the order of [`Effect::FrictionExtension`]'s
/// coefficients; the first two act in slip, the last two at break-away.
pub const SIGNALS: [&str; 4] = ["slip_speed_rad_s", "breakaway_transient", "static_level", "log_dwell"];

/// Index of `static_level` in [`SIGNALS`].
const LEVEL: usize = 2;
/// Index of `log_dwell` in [`SIGNALS`]: the ageing law, fitted in free run.
const DWELL: usize = 3;

/// Upper end of the ageing law's slope c_d = β/μs (relative growth of the
/// static level per e-fold of dwell; lower end 0: a contact strengthens with
/// its age, never weakens). Measured ageing of dry contacts is β/μ ≈ 0.01
/// (rocks, Dieterich 1972) to a few % (paper, polymers: Baumberger & Caroli
/// 2006); 0.15 leaves a factor of two above the largest.
pub const DWELL_SLOPE_MAX: f64 = 0.15;
/// Brent's tolerance on c_d (a tenth of the smallest slope the
/// `breakaway_dwell` check resolves, 0.006 ⊕ its standard error).
pub const DWELL_SLOPE_TOL: f64 = 5e-4;
/// Free-run simulations of the training runs per fit (Brent's evaluations).
pub const DWELL_FIT_EVALS: usize = 14;
/// A training run whose free run failed counts as this squared misfit (a
/// law that makes the integrator fail is no fit).
const FAILED_RUN_MISFIT: f64 = 1e6;

/// Teacher-forced rows of one run: (signals, relative error of the model).
#[derive(Debug, Default)]
struct RunRows {
    slip: Vec<([f64; 2], f64)>,
    breakaway: Vec<([f64; 2], f64)>,
}

/// The extension with its selection steps and the free runs of the
/// reported extension beside the record (held-out: each run simulated with
/// the coefficients fitted without its fold).
#[derive(Debug, Clone)]
pub struct ExtensionResult {
    pub extension: Extension,
    pub steps: Vec<StepRow>,
    pub traces: Vec<SpeedTraces>,
    /// The free-run checks of the extended model (held-out free runs).
    pub checks: Vec<ChannelCheck>,
}

/// What the extension is fitted and simulated from.
pub struct Inputs<'a> {
    pub c: &'a Campaign,
    /// The diagnosis' signals of every operating point (folds, slip samples, μ_obs).
    pub runs: &'a [RunSignals],
    /// The final model: baseline + findings + selected structure.
    pub model: &'a RigParams,
    /// `model`'s free runs (campaign order).
    pub before: &'a [FreeRunPair],
    /// Each run's nuisance phases (θ of the time and angle modulations).
    pub phases: &'a BTreeMap<String, (f64, f64)>,
    pub s: &'a FreeRunSettings,
    pub opts: &'a crate::DiagnoseOptions,
}

/// Fits, selects and simulates the extension on top of the final model
/// (module docs). `None` without operating points to fit.
pub fn extend(x: &Inputs) -> Option<ExtensionResult> {
    let Inputs { c, runs, model, before, phases, s, opts } = *x;
    let phase = |id: &str| phases.get(id).copied().unwrap_or_default();
    let rows: Vec<RunRows> = {
        use rayon::prelude::*;
        runs.par_iter().map(|r| run_rows(r, &with_run_phases(model, phase(&r.id)), s)).collect()
    };
    let fold_of: BTreeMap<&str, usize> = runs.iter().map(|r| (r.id.as_str(), r.fold)).collect();
    let folds = runs.iter().map(|r| r.fold + 1).max().unwrap_or(0);
    let floor = speed_floor_rad_s(c, s);
    let base: BTreeMap<&str, f64> =
        before.iter().filter_map(|q| free_run_misfit_channels(q, floor).map(|m| (q.id.as_str(), m))).collect();
    // Coefficients of a signal set fitted teacher-forced without fold `f` (None: every run).
    let teacher_forced = |set: &[usize], f: Option<usize>| -> Option<[f64; 4]> {
        let keep = |r: usize| f.is_none_or(|f| runs[r].fold != f);
        let mut coef = [0.0; 4];
        for (part, offset) in [(0usize, 0usize), (1, 2)] {
            let cols: Vec<usize> = set.iter().filter(|&&j| j / 2 == part).map(|&j| j - offset).collect();
            if cols.is_empty() {
                continue;
            }
            let (mut x, mut y) = (Vec::new(), Vec::new());
            for (_, rr) in rows.iter().enumerate().filter(|(r, _)| keep(*r)) {
                for (sig, e) in if part == 0 { &rr.slip } else { &rr.breakaway } {
                    x.push(cols.iter().map(|&j| sig[j]).collect::<Vec<f64>>());
                    y.push(*e);
                }
            }
            let b = rig_estimate::linear::ols(&x, &y, "friction extension").ok()?.beta;
            for (k, &j) in cols.iter().enumerate() {
                coef[j + offset] = b[k];
            }
        }
        Some(coef)
    };
    let with_ext = |coef: [f64; 4], id: &str| {
        let mut p = model.clone();
        p.effects.push(Effect::FrictionExtension {
            slip_speed_per_rad_s: coef[0],
            breakaway_transient: coef[1],
            static_level: coef[2],
            dwell_per_efold: coef[3],
        });
        with_run_phases(&p, phase(id))
    };
    // The ageing law (`log_dwell` with its `static_level`, module docs "The
    // ageing law"): the slope c_d fitted by free-run simulation of the
    // training runs, the level c_0 the break-aways' least squares at that slope.
    let fit = |set: &[usize], f: Option<usize>| -> Option<[f64; 4]> {
        let mut coef = teacher_forced(set, f)?;
        if !set.contains(&DWELL) {
            return Some(coef);
        }
        let train = |r: usize| f.is_none_or(|f| runs[r].fold != f);
        let rows_b: Vec<(f64, f64)> = rows
            .iter()
            .enumerate()
            .filter(|(r, _)| train(*r))
            .flat_map(|(_, rr)| rr.breakaway.iter().map(|(sig, e)| (sig[1], *e)))
            .collect();
        if rows_b.is_empty() {
            return Some(coef);
        }
        let n = rows_b.len() as f64;
        let level_at = |cd: f64| rows_b.iter().map(|(x, e)| e - cd * x).sum::<f64>() / n;
        let training: BTreeMap<&str, ()> =
            runs.iter().enumerate().filter(|(r, _)| train(*r)).map(|(_, r)| (r.id.as_str(), ())).collect();
        let misfit = |cd: f64| {
            let mut k = coef;
            (k[2], k[3]) = (level_at(cd), cd);
            let pairs = free_run_pairs_by(c, s, |id| training.contains_key(id).then(|| with_ext(k, id)));
            let m2: Vec<f64> =
                pairs.iter().map(|q| free_run_misfit_channels(q, floor).map_or(FAILED_RUN_MISFIT, |m| m * m)).collect();
            m2.iter().sum::<f64>() / m2.len().max(1) as f64
        };
        let cd = brent_min(0.0, DWELL_SLOPE_MAX, DWELL_SLOPE_TOL, DWELL_FIT_EVALS, misfit);
        (coef[2], coef[3]) = (level_at(cd), cd);
        Some(coef)
    };
    // Cross-validated free runs of a set: each run's misfit (runs order,
    // NaN where the run has no free-run misfit), its free runs and fits.
    let score = |set: &[usize]| {
        let fits: Vec<Option<[f64; 4]>> = (0..folds).map(|f| fit(set, Some(f))).collect();
        let pairs = free_run_pairs_by(c, s, |id| {
            let coef = (*fits.get(*fold_of.get(id)?)?)?;
            Some(with_ext(coef, id))
        });
        let misfits = runs
            .iter()
            .map(|r| {
                let q = pairs.iter().find(|q| q.id == r.id);
                q.and_then(|q| free_run_misfit_channels(q, floor)).unwrap_or(f64::NAN)
            })
            .collect();
        (misfits, (pairs, fits))
    };
    if folds == 0 || base.is_empty() {
        return None;
    }
    let base_ms: Vec<f64> = runs.iter().map(|r| base.get(r.id.as_str()).copied().unwrap_or(f64::NAN)).collect();
    let run_folds: Vec<usize> = runs.iter().map(|r| r.fold).collect();
    let passes = |k: &Comparison| k.gain >= opts.selection.min_relative_gain && k.t >= opts.selection.min_t;
    let (steps, found, selected) = forward_signals(&base_ms, &run_folds, folds, passes, score);
    let Tried { set, misfits, extra: (pairs, fits), .. } = found?;
    // The extension's gain over the final model (every step was judged
    // against the step before it).
    let cmp = compare_runs(&base_ms, &misfits, &run_folds, folds);
    let full = fit(&set, None)?;
    // The extended model's free-run checks (held-out runs, each simulated
    // with the coefficients fitted without its fold): does it now match?
    let checks = free_run_checks_of(c, &pairs, s, &opts.channels);
    let free_run_flagged = checks
        .iter()
        .filter(|k| k.flagged)
        .map(|k| format!("{} {:.1}× (threshold {:.1})", k.channel, k.ratio, k.threshold))
        .collect();
    let terms = set
        .iter()
        .map(|&j| {
            let v: Vec<f64> = fits.iter().flatten().map(|c| c[j]).collect();
            let k = v.len() as f64;
            let m = v.iter().sum::<f64>() / k.max(1.0);
            let se = if v.len() == folds && folds > 1 {
                ((k - 1.0) / k * v.iter().map(|x| (x - m).powi(2)).sum::<f64>()).sqrt()
            } else {
                f64::NAN
            };
            ExtensionTerm { signal: SIGNALS[j].into(), coefficient: round_sig(full[j], 4), stderr: round_sig(se, 2) }
        })
        .collect();
    let traces = before
        .iter()
        .map(|b| SpeedTraces {
            id: b.id.clone(),
            time_s: b.trace.time_s.clone(),
            measured_rad_s: b.trace.measured_rad_s.clone(),
            baseline_rad_s: b.trace.simulated_rad_s.clone(),
            extended_rad_s: pairs.iter().find(|e| e.id == b.id).and_then(|e| e.trace.simulated_rad_s.clone()),
        })
        .collect();
    Some(ExtensionResult {
        extension: Extension {
            formula: formula(&set, &full, static_mu(&model.friction), selected),
            terms,
            free_run_misfit_before: round_sig(cmp.before, 4),
            free_run_misfit_after: round_sig(cmp.after, 4),
            relative_gain: round_sig(cmp.gain, 3),
            relative_gain_sd: round_sig(cmp.gain_fold_sd, 2),
            free_run_flagged,
        },
        steps,
        traces,
        checks,
    })
}

/// A signal set tried at a step: its runs' held-out misfits (runs order,
/// NaN where a run has no free-run misfit), their comparison with the step's
/// starting model, and what the caller keeps of it.
struct Tried<T> {
    set: Vec<usize>,
    misfits: Vec<f64>,
    cmp: Comparison,
    extra: T,
}

/// The comparison of per-run misfits over the runs both score (a NaN on
/// either side, a free run with no misfit, leaves the run out).
fn compare_runs(before: &[f64], after: &[f64], fold_of: &[usize], folds: usize) -> Comparison {
    let (mut b, mut a, mut fv) = (Vec::new(), Vec::new(), Vec::new());
    for ((x, y), f) in before.iter().zip(after).zip(fold_of) {
        if !x.is_nan() && !y.is_nan() {
            b.push(*x);
            a.push(*y);
            fv.push(*f);
        }
    }
    compare_folds(&b, &a, &fv, folds)
}

/// Forward selection over the library's signals (module docs): at each step
/// every signal not yet chosen is added to the chosen set (`log_dwell` with
/// its `static_level`), `score`d, and compared with the set the step starts
/// from (the final model at step 1, then the last accepted set); the best
/// is accepted while it `passes`. Returns the step rows, the selected set or
/// else the best single signal, and whether it was selected.
fn forward_signals<T: Clone>(
    base: &[f64],
    fold_of: &[usize],
    folds: usize,
    passes: impl Fn(&Comparison) -> bool,
    score: impl Fn(&[usize]) -> (Vec<f64>, T),
) -> (Vec<StepRow>, Option<Tried<T>>, bool) {
    let mut chosen: Vec<usize> = Vec::new();
    let mut current = base.to_vec();
    let mut steps = Vec::new();
    let mut best_single = None;
    let mut kept = None;
    for step in 1..=SIGNALS.len() {
        let mut tried = Vec::new();
        for j in (0..SIGNALS.len()).filter(|j| !chosen.contains(j)) {
            let mut set: Vec<usize> = chosen.iter().copied().chain([j]).collect();
            // The ageing law carries its own level (μs0 of module docs).
            if j == DWELL && !set.contains(&LEVEL) {
                set.push(LEVEL);
                set.sort_unstable();
            }
            let (misfits, extra) = score(&set);
            let cmp = compare_runs(&current, &misfits, fold_of, folds);
            tried.push((j, Tried { set, misfits, cmp, extra }));
        }
        let key = |i: usize| if tried[i].1.cmp.gain.is_finite() { tried[i].1.cmp.gain } else { f64::NEG_INFINITY };
        let Some(bi) = (0..tried.len()).max_by(|&a, &b| key(a).total_cmp(&key(b))) else { break };
        let ok = passes(&tried[bi].1.cmp);
        for (i, (j, t)) in tried.iter().enumerate() {
            steps.push(StepRow {
                step,
                effect: SIGNALS[*j].into(),
                misfit_before: t.cmp.before,
                misfit_after: t.cmp.after,
                gain: t.cmp.gain,
                gain_fold_sd: t.cmp.gain_fold_sd,
                t: t.cmp.t,
                accepted: i == bi && ok,
                inadmissible: None,
            });
        }
        let (_, t) = tried.swap_remove(bi);
        if step == 1 {
            best_single =
                Some(Tried { set: t.set.clone(), misfits: t.misfits.clone(), cmp: t.cmp, extra: t.extra.clone() });
        }
        if !ok {
            break;
        }
        chosen = t.set.clone();
        current = t.misfits.clone();
        kept = Some(t);
    }
    let selected = kept.is_some();
    (steps, kept.or(best_single), selected)
}

/// The extended law in words and symbols, with the coefficients fitted on
/// every run; `mu_s` the model's static coefficient (the ageing law's μs0
/// and β in its units).
fn formula(set: &[usize], coef: &[f64; 4], mu_s: f64, selected: bool) -> String {
    let has = |j: usize| set.contains(&j);
    let mut slip = Vec::new();
    if has(0) {
        slip.push(format!("{:+.4}·|Ω1|", coef[0]));
    }
    if has(1) {
        slip.push(format!("{:+.4}·exp(−t_slip/{BREAKAWAY_TIME_S} s)", coef[1]));
    }
    let mut stat = Vec::new();
    if has(LEVEL) {
        stat.push(format!("{:+.4}", coef[LEVEL]));
    }
    if has(DWELL) {
        stat.push(format!("{:+.4}·ln(1 + t_stick/{DWELL_TIME_S} s)", coef[DWELL]));
    }
    let mut parts = Vec::new();
    if !slip.is_empty() {
        parts.push(format!("μ = μ_model·(1 {})", slip.join(" ")));
    }
    if !stat.is_empty() {
        parts.push(format!("μs = μs_model·(1 {})", stat.join(" ")));
    }
    if has(DWELL) {
        parts.push(format!(
            "contact ageing μs(t_stick) = μs0 + β·ln(1 + t_stick/{DWELL_TIME_S} s) with μs0 = {:.4}, β = {:.4} per \
             e-fold of dwell (Dieterich 1972; Baumberger & Caroli 2006; β fitted by free-run simulation)",
            mu_s * (1.0 + coef[LEVEL]),
            mu_s * coef[DWELL]
        ));
    }
    let note = if selected {
        "selected on the cross-validated free-run misfit"
    } else {
        "the best single signal; it does not pass the selection rule"
    };
    format!(
        "{} (t_slip: time since the rotor last stood, t_stick: time stuck, rad/s for |Ω1|; {note})",
        parts.join("; ")
    )
}

/// The teacher-forced rows of one run against model `p` (its phases set).
fn run_rows(r: &RunSignals, p: &RigParams, s: &FreeRunSettings) -> RunRows {
    let mut out = RunRows::default();
    let n0 = r.normal_force_n;
    if n0 <= 0.0 || r.time_s.len() < 3 {
        return out;
    }
    let slip = s.slip_speed_rad_s;
    let n_of = |k: usize| normal_force_n(n0, &p.effects, p.harmonic.as_ref(), r.time_s[k], r.rotor_angle_rad[k]);
    // Time since the rotor last stood (|Ω1| below the slip speed); the run starts at rest.
    let mut since = vec![0.0; r.time_s.len()];
    let mut last = r.time_s[0];
    for (k, w) in r.rotor_speed_rad_s.iter().enumerate() {
        if w.abs() < slip {
            last = r.time_s[k];
        }
        since[k] = r.time_s[k] - last;
    }
    for (j, &k) in r.slip_idx.iter().enumerate().step_by(5) {
        let w = r.rotor_speed_rad_s[k].abs();
        let mu = slip_mu(&p.friction, w) * n_of(k) / n0;
        if mu.abs() > 1e-9 && j < r.mu_obs.len() {
            out.slip.push((slip_signals(w, since[k]), r.mu_obs[j] / mu - 1.0));
        }
    }
    // Every stick episode that ends in a break-away, by the estimation's
    // rules (`[shared.stick_episodes]`, the free-run `breakaway_friction`
    // feature's reading): its raw peak force against the model's static
    // level at that instant, and its length as the contact's age.
    if n0 >= s.stick_episodes.min_normal_force_n {
        let mu_s = static_mu(&p.friction);
        for e in stick_episodes(&r.time_s, &r.rotor_angle_rad, &s.stick_episodes) {
            let Some(kp) = e.clone().max_by(|&a, &b| r.friction_force_n[a].total_cmp(&r.friction_force_n[b])) else {
                continue;
            };
            let level = mu_s * n_of(kp);
            if level > 0.0 {
                let dwell = r.time_s[e.end - 1] - r.time_s[e.start];
                out.breakaway.push((static_signals(dwell), r.friction_force_n[kp] / level - 1.0));
            }
        }
    }
    out
}

/// Puts the extension into an `unexplained` diagnosis (its finding's
/// `extension`, the selection steps and the free runs for the report);
/// nothing for any other verdict. The one call from [`crate::diagnose`].
pub fn attach(d: &mut crate::Diagnosis, inputs: &Inputs) {
    if d.verdict != "unexplained" {
        return;
    }
    let Some(x) = extend(inputs) else { return };
    if let Some(f) = d.findings.iter_mut().find(|f| f.effect == "unexplained") {
        f.extension = Some(x.extension);
    }
    d.detail.extension_steps = x.steps;
    d.detail.extension_traces = x.traces;
    d.detail.extension_free_run = x.checks;
}

/// Parameters of the vocabulary findings that the extended model
/// ([`crate::channels::extended_params`]) or the simulator can only use at a
/// bound (issue 25, item 4: reported, never silently fixed): the extension's
/// ageing slope at an end of its bracket, the break-away
/// coefficient of a slip law that fits μk but not μs (the viscous law), held
/// at max(μs of the baseline, μk), and a
/// modulation depth outside [0, 1] (N would change sign; rig-model refuses it).
pub fn vocabulary_bounds(baseline: &RigParams, findings: &[crate::Finding]) -> Vec<crate::ParamAtBound> {
    let mut out = Vec::new();
    let mu_s0 = static_mu(&baseline.friction);
    for f in findings {
        let g = |k: &str| f.params.get(k).copied();
        // A slip law that fits its own μk but not its own μs (the viscous law)
        // keeps the baseline's break-away coefficient, held at μk when below it.
        if g("mu_static").is_none()
            && let Some(mu_k) = g("mu_kinetic").filter(|&m| m > mu_s0)
        {
            out.push(crate::ParamAtBound {
                parameter: format!("{}.mu_static", f.effect),
                bound: round_sig(mu_k, 4),
                unconstrained: round_sig(mu_s0, 4),
                meaning: format!(
                    "the slip law's μk {mu_k:.4} exceeds the baseline's break-away coefficient μs {mu_s0:.4}; the \
                     extended model holds μs at μk (no break-away below the slip level): the break-away level is \
                     not measured by the slip channel, see the free-run breakaway_friction check"
                ),
            });
        }
        // The ageing law's slope where its free-run fit stopped at an end of
        // its bracket [0, DWELL_SLOPE_MAX] (module docs, "The ageing law").
        let dwell = f.extension.iter().flat_map(|x| &x.terms).find(|t| t.signal == SIGNALS[DWELL]);
        if let Some(t) = dwell.filter(|t| {
            t.coefficient <= 2.0 * DWELL_SLOPE_TOL || t.coefficient >= DWELL_SLOPE_MAX - 2.0 * DWELL_SLOPE_TOL
        }) {
            let at_upper = t.coefficient > 0.5 * DWELL_SLOPE_MAX;
            out.push(crate::ParamAtBound {
                parameter: "extension.log_dwell".into(),
                bound: if at_upper { DWELL_SLOPE_MAX } else { 0.0 },
                unconstrained: t.coefficient,
                meaning: if at_upper {
                    "the ageing law's free-run fit wants a static level that grows faster with the dwell than any \
                     dry contact ages (bracket end): the break-aways follow something else than contact ageing"
                } else {
                    "the ageing law's free-run fit puts its slope at 0: the free run wants no contact ageing"
                }
                .into(),
            });
        }
        if let Some(a) = g("amplitude_ratio").filter(|a| !(0.0..=1.0).contains(a)) {
            out.push(crate::ParamAtBound {
                parameter: format!("{}.amplitude_ratio", f.effect),
                bound: if a < 0.0 { 0.0 } else { 1.0 },
                unconstrained: round_sig(a, 4),
                meaning: "a modulation depth outside [0, 1] makes the normal force change sign: the simulator \
                          refuses it, so the extended model's free run fails"
                    .into(),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Six runs in two folds; the final model misfits 10 on each. Either
    /// slip signal alone brings every run to about 5 and the two together
    /// to the same 5 (the second explains what the first already did); the
    /// break-away signals change nothing.
    fn score(set: &[usize]) -> (Vec<f64>, ()) {
        let ms = (0..6)
            .map(|r| {
                let r = r as f64;
                match set {
                    [0] => 5.0 + 0.1 * r,
                    [1] => 6.0 + 0.1 * r,
                    [0, 1] => 4.99 + 0.1 * r,
                    _ => 10.0 + 0.01 * r,
                }
            })
            .collect();
        (ms, ())
    }

    #[test]
    fn a_second_signal_is_judged_against_the_first() {
        let base = vec![10.0; 6];
        let fold_of = [0, 1, 0, 1, 0, 1];
        let passes = |k: &Comparison| k.gain >= 0.05 && k.t >= 2.0;
        let (steps, found, selected) = forward_signals(&base, &fold_of, 2, passes, score);
        let found = found.expect("a set");
        assert!(selected);
        // Step 1 takes `slip_speed_rad_s` (gain ≈ 0.48 over the final model) ...
        let first: Vec<&StepRow> = steps.iter().filter(|s| s.step == 1 && s.accepted).collect();
        assert_eq!(first.len(), 1);
        assert_eq!(first[0].effect, SIGNALS[0]);
        // ... and step 2 judges `breakaway_transient` on top of it against it,
        // not against the final model (where it would gain 0.48 again): refused.
        let second = steps.iter().find(|s| s.step == 2 && s.effect == SIGNALS[1]).expect("step 2");
        assert!(second.gain.abs() < 0.01 && !second.accepted, "{second:?}");
        assert!((second.misfit_before - first[0].misfit_after).abs() < 1e-12);
        assert_eq!(found.set, [0]);
    }
}
