//! The structure selection itself ([`select_structure`]), the placebo
//! comparison, and the finding, notes and score rows it attaches to the
//! diagnosis.

use super::*;

/// Selects the structure on top of `ext` (module docs) on the one engine
/// ([`rig_types::select::select_on_views`]: the runs as units, each run's
/// fold as the folds, the baseline `twist_rate` fitted per training set, the
/// four views and [`FourViews`]). `ext_pairs` are the extended model's free
/// runs (campaign order), `runs` the diagnosis' rows: each run's
/// cross-validation fold (numbered from 0) and its nuisance phases, with
/// which its free runs are simulated; `measured` the records' side of every
/// free run ([`MeasuredRuns::of`] under `s`), so a candidate's held-out runs
/// only simulate.
#[allow(clippy::too_many_arguments)]
pub fn select_structure(
    c: &Campaign,
    data: &StructureData,
    ext: &RigParams,
    ext_pairs: &[FreeRunPair],
    runs: &[crate::RunRow],
    s: &FreeRunSettings,
    opts: &DiagnoseOptions,
    rec: &crate::channels::Recorded,
    measured: &MeasuredRuns,
) -> StructureSelection {
    use rig_types::select::{Candidate, Fold, Search, select_on_views};
    let floor_rad_s = crate::channels::speed_floor_rad_s(c, s);
    let ext_ms: BTreeMap<&str, f64> =
        ext_pairs.iter().filter_map(|q| free_run_misfit(q, floor_rad_s).map(|m| (q.id.as_str(), m))).collect();
    // The motor side re-estimated once under each candidate that moves the
    // damping, at its fit to every run (module docs), in REGISTRY order.
    let motor: Vec<Option<MotorSide>> = REGISTRY
        .par_iter()
        .map(|cand| {
            let full = cand.refits_motor_side().then(|| cand.fit(ext, data, &|_| true)).flatten()?;
            MotorSide::refit(c, &cand.apply(ext, &full), opts)
        })
        .collect();
    let study = Study {
        c,
        data,
        ext,
        models: motor.iter().map(|m| m.as_ref().map_or_else(|| ext.clone(), |m| m.model.clone())).collect(),
        runs,
        ext_free_run: runs.iter().map(|r| ext_ms.get(r.id.as_str()).copied()).collect(),
        floor_rad_s,
        s,
        measured,
        min_t: opts.selection.min_t,
    };
    // One fold per cross-validation fold of the diagnosis that holds out a run.
    let folds_n = runs.iter().map(|r| r.fold + 1).max().unwrap_or(0);
    let folds: Vec<Fold> = (0..folds_n)
        .map(|f| Fold {
            train: (0..runs.len()).filter(|&u| runs[u].fold != f).collect(),
            held_out: (0..runs.len()).filter(|&u| runs[u].fold == f).collect(),
        })
        .filter(|f| !f.held_out.is_empty())
        .collect();
    let base = REGISTRY[0];
    let base_fit = base.fit(ext, data, &|_| true).expect("the baseline's structure fits every balance");
    let baselines: Vec<Structured> = folds
        .iter()
        .map(|f| Structured {
            k: 0,
            fit: base.fit(ext, data, &study.include(&f.train)).unwrap_or_else(|| base_fit.clone()),
        })
        .collect();
    let cands: Vec<Cand> = (1..REGISTRY.len()).map(Cand).collect();
    let cand_refs: Vec<&dyn Candidate<Study<'_>, Structured>> = cands.iter().map(|c| c as _).collect();
    let search = Search { units_ascending: true, ..Search::default() };
    // Which candidates' fits to every run sit at their grid's edge (the rule's
    // admission, [`FourViews`]; reported below as parameters at bounds).
    let at_edge = cands
        .iter()
        .map(|c| REGISTRY[c.0].fit(ext, data, &|_| true).is_some_and(|f| REGISTRY[c.0].at_grid_edge(&f).is_some()))
        .collect();
    let rule = FourViews { rule: &opts.selection, at_edge };
    let sel = select_on_views(&study, &cand_refs, &baselines, &folds, &rule, &search);
    let Ok(sel) = sel else {
        // Fewer than two folds: nothing to hold out, the rig model's structure stays.
        let scores = vec![score_row(base, &base_fit, &[], [&no_gain(f64::NAN); 4], true)];
        return finish(ext, base, 0, base_fit, vec![f64::NAN], scores, Vec::new(), runs, (false, false));
    };
    let overall_view = |v: usize| overall(&sel.baseline_misfits[v].iter().flatten().copied().collect::<Vec<_>>());
    let mut scores = vec![score_row(
        base,
        &base_fit,
        &[],
        [
            &no_gain(overall_view(BALANCE)),
            &no_gain(overall_view(FREE_RUN)),
            &no_gain(overall_view(EVENTS)),
            &no_gain(overall_view(RING)),
        ],
        true,
    )];
    let mut at_bounds = Vec::new();
    let mut winner = None;
    for t in sel.trials.iter().filter(|t| t.error.is_none()) {
        let k = t.candidate + 1;
        let Some(a) = study.assess(k, &t.fitted) else { continue };
        for (p, v) in &a.pinned {
            at_bounds.push(ParamAtBound {
                parameter: p.name.into(),
                bound: p.lower,
                unconstrained: round_sig(*v, 3),
                meaning: format!(
                    "structure `{}`'s rotor-balance fit wants {} below its bound ({}): the records do not support \
                     that term; the candidate is inadmissible",
                    REGISTRY[k].id(),
                    p.meaning,
                    p.unit
                ),
            });
        }
        if let Some(e) = REGISTRY[k].at_grid_edge(&a.full) {
            at_bounds.push(ParamAtBound {
                parameter: e.param.name.into(),
                bound: e.edge,
                unconstrained: e.edge,
                meaning: format!(
                    "structure `{}`'s fit to every run is at the edge of its search grid ({}): the unconstrained \
                     optimum lies there or beyond, so {} is not estimated, and the steady balance alone does not \
                     admit the candidate (only its ring or its transitions can)",
                    REGISTRY[k].id(),
                    e.what,
                    e.param.meaning
                ),
            });
        }
        let cmp = &t.comparisons;
        let admissible = a.pinned.is_empty() && a.weak.is_empty();
        let mut row = score_row(
            REGISTRY[k],
            &a.full,
            &a.weak,
            [&cmp[BALANCE], &cmp[FREE_RUN], &cmp[EVENTS], &cmp[RING]],
            admissible,
        );
        if let Some(m) = &motor[k] {
            row.description = format!("{}; {}", row.description, m.describe(ext));
        }
        scores.push(row);
        if t.accepted {
            // Admitted on neither the balance nor the free run ([`FourViews`]
            // ranks those by the event-locked gain): on the ring where it
            // passes, else on the event-locked rows.
            let off_balance = t.standing.is_some_and(|s| s.by_view == EVENTS);
            let on_ring = off_balance && opts.selection.admits(&cmp[RING]);
            let on_events = off_balance && !on_ring;
            // Admitted on the transitions alone: it must beat its placebo there
            // by the same criterion (module docs, "A placebo at the transitions").
            let placebo = on_events
                .then(|| placebo_comparison(REGISTRY[k], t, &sel, &folds, &study, rec, rec.rate_hz()))
                .flatten();
            if let Some(p) = placebo.filter(|p| !opts.selection.admits(p)) {
                let row = scores.len() - 1;
                scores[row].description.push_str(&format!(
                    "; admitted on the event-locked rows alone, it does not beat its placebo there (the same \
                     correction in the direction no sensor makes: gain {:.1} %, paired t = {:.2}), so it is refused",
                    100.0 * p.gain,
                    p.t
                ));
                continue;
            }
            winner = Some((k, scores.len() - 1, a.full, a.se, (on_events, on_ring)));
        }
    }
    match winner {
        Some((k, row, full, se, on)) => {
            scores[row].accepted = true;
            finish(&study.models[k], REGISTRY[k], row, full, se, scores, at_bounds, runs, on)
        }
        None => {
            scores[0].accepted = true;
            finish(ext, base, 0, base_fit, vec![f64::NAN; base.params().len()], scores, at_bounds, runs, (false, false))
        }
    }
}

/// The candidate `cand` (trial `t` of `sel`) against its placebo on the
/// event-locked rows (module docs, "A placebo at the transitions"): each
/// held-out run's event-locked RMS through the placebo of its fold's fit,
/// the balance refitted on that fold's training runs, paired with the
/// candidate's; `None` when the candidate has no placebo.
pub(super) fn placebo_comparison(
    cand: &dyn StructureCandidate,
    t: &rig_types::select::ViewTrial<Structured>,
    sel: &rig_types::select::ViewSelection<Structured>,
    folds: &[rig_types::select::Fold],
    study: &Study<'_>,
    rec: &crate::channels::Recorded,
    rate_hz: f64,
) -> Option<Comparison> {
    let sorted = |v: &[usize]| {
        let mut v = v.to_vec();
        v.sort_unstable();
        v
    };
    // One placebo balance per distinct fitted point (the folds share most).
    let mut built: Vec<(Vec<u64>, BalanceData)> = Vec::new();
    let mut misfits = Vec::with_capacity(sel.units.len());
    for (i, &u) in sel.units.iter().enumerate() {
        let train = sorted(&folds[sel.fold_of[i]].train);
        let set = sel.train_sets.iter().position(|s| sorted(s) == train)?;
        let fit = &t.fitted.get(set)?.fit;
        let key: Vec<u64> = fit.values.iter().map(|v| v.to_bits()).collect();
        let at = match built.iter().position(|b| b.0 == key) {
            Some(j) => j,
            None => {
                built.push((key, cand.placebo(rec, rate_hz, fit)?));
                built.len() - 1
            }
        };
        let data = &built[at].1;
        let (_, balance) = channel_delay::training_cost(data, &study.include(&sel.train_sets[set]))?;
        let id = study.runs[u].id.as_str();
        misfits.push(data.run_event_rms(&balance, |r| r == id).first().map(|x| x.1));
    }
    Some(rig_types::select::compare_scored(&misfits, &t.misfits[EVENTS], &sel.fold_of, folds.len()))
}

/// A comparison of a model with itself (the baseline's row).
pub(super) fn no_gain(m: f64) -> Comparison {
    Comparison { before: m, after: m, gain: 0.0, gain_fold_sd: 0.0, t: 0.0 }
}

/// The selection from its winner (`row`: its row of `scores`), applied to
/// `model`, the model it extends (the extended model, with the motor side
/// re-estimated under a damping winner's structure).
#[allow(clippy::too_many_arguments)]
pub(super) fn finish(
    model: &RigParams,
    winner: &'static dyn StructureCandidate,
    row: usize,
    fitted: Fitted,
    stderr: Vec<f64>,
    mut scores: Vec<StructureScore>,
    at_bounds: Vec<ParamAtBound>,
    runs: &[crate::RunRow],
    (on_events, on_ring): (bool, bool),
) -> StructureSelection {
    scores[row].accepted = true;
    let notes = notes(winner, &fitted, row, &scores);
    StructureSelection {
        damping: winner.damping(),
        model: winner.apply(model, &fitted),
        candidate: winner,
        fitted,
        stderr,
        scores,
        at_bounds,
        notes,
        heldout_runs: runs.iter().map(|r| r.id.clone()).collect(),
        on_events,
        on_ring,
    }
}

/// One candidate's row; `cmp` is its balance, free-run and event-locked comparison.
pub(super) fn score_row(
    cand: &dyn StructureCandidate,
    full: &Fitted,
    weak: &[String],
    cmp: [&Comparison; 4],
    admissible: bool,
) -> StructureScore {
    let [balance, free_run, events, ring] = cmp;
    StructureScore {
        id: cand.id().into(),
        description: if weak.is_empty() {
            cand.describe(full)
        } else {
            format!("{}; not supported by the balance: {}", cand.describe(full), weak.join(", "))
        },
        free_run_misfit: free_run.after,
        relative_gain: free_run.gain,
        relative_gain_fold_sd: free_run.gain_fold_sd,
        t: free_run.t,
        balance_misfit: balance.after,
        balance_gain: balance.gain,
        balance_gain_fold_sd: balance.gain_fold_sd,
        balance_t: balance.t,
        event_misfit: events.after,
        event_gain: events.gain,
        event_gain_fold_sd: events.gain_fold_sd,
        event_t: events.t,
        ring_misfit: ring.after,
        ring_gain: ring.gain,
        ring_gain_fold_sd: ring.gain_fold_sd,
        ring_t: ring.t,
        admissible,
        accepted: false,
    }
}

/// The selection's sentence: the winner with its gains, or the baseline
/// with the best runner-up.
pub(super) fn notes(winner: &dyn StructureCandidate, fitted: &Fitted, k: usize, scores: &[StructureScore]) -> String {
    let sc = &scores[k];
    if k == 0 {
        let runner = scores.iter().skip(1).max_by(|a, b| a.balance_gain.total_cmp(&b.balance_gain));
        format!(
            "The rig model's structure stays: {}; no candidate lowers the cross-validated rotor-balance misfit \
             ({:.3e} N·m), its event-locked misfit or the free-run misfit ({:.3}) by the criterion without its free \
             run refuting it{}.",
            winner.describe(fitted),
            sc.balance_misfit,
            sc.free_run_misfit,
            runner.map_or(String::new(), |r| format!(
                " (best: {}, balance gain {:.1} %, t = {:.2}; event-locked gain {:.1} %, t = {:.2}; ring gain {:.1} \
                 %, t = {:.2}; free-run gain {:.1} %, t = {:.2}{})",
                r.id,
                100.0 * r.balance_gain,
                r.balance_t,
                100.0 * r.event_gain,
                r.event_t,
                100.0 * r.ring_gain,
                r.ring_t,
                100.0 * r.relative_gain,
                r.t,
                if r.admissible { "" } else { ", inadmissible" }
            ))
        )
    } else {
        format!(
            "{} (fitted through the rotor torque balance) lowers the cross-validated balance misfit from {:.3e} to \
             {:.3e} N·m (gain {:.1} %, paired t = {:.2}), at the stick↔slip transitions from {:.3e} to {:.3e} N·m \
             (event-locked rows: gain {:.1} %, paired t = {:.2}), the force's ring after the break-aways from {:.3e} \
             to {:.3e} N·m (gain {:.1} %, paired t = {:.2}); the extended model's free-run misfit goes from {:.3} to \
             {:.3} (gain {:.1} % ± {:.1} % across folds, paired t = {:.2}).",
            capitalise(&winner.describe(fitted)),
            scores[0].balance_misfit,
            sc.balance_misfit,
            100.0 * sc.balance_gain,
            sc.balance_t,
            scores[0].event_misfit,
            sc.event_misfit,
            100.0 * sc.event_gain,
            sc.event_t,
            scores[0].ring_misfit,
            sc.ring_misfit,
            100.0 * sc.ring_gain,
            sc.ring_t,
            scores[0].free_run_misfit,
            sc.free_run_misfit,
            100.0 * sc.relative_gain,
            100.0 * sc.relative_gain_fold_sd,
            sc.t
        )
    }
}

/// The winner as a finding (module docs), `None` for the baseline.
pub fn finding(sel: &StructureSelection) -> Option<Finding> {
    let id = sel.candidate.finding_id()?;
    let sc = sel.scores.iter().find(|s| s.accepted)?;
    let base = &sel.scores[0];
    let names = sel.candidate.params().iter().map(|p| p.name.to_string());
    // (baseline misfit, misfit, gain, its fold sd, t) of the statistic it was admitted on.
    let (before, after, gain, sd, t) = if sel.on_ring {
        (base.ring_misfit, sc.ring_misfit, sc.ring_gain, sc.ring_gain_fold_sd, sc.ring_t)
    } else if sel.on_events {
        (base.event_misfit, sc.event_misfit, sc.event_gain, sc.event_gain_fold_sd, sc.event_t)
    } else {
        (base.balance_misfit, sc.balance_misfit, sc.balance_gain, sc.balance_gain_fold_sd, sc.balance_t)
    };
    Some(Finding {
        effect: id.into(),
        params: names.clone().zip(&sel.fitted.values).map(|(n, v)| (n, round_sig(*v, 4))).collect(),
        params_stderr: names.zip(&sel.stderr).map(|(n, v)| (n, round_sig(*v, 2))).collect(),
        evidence: format!("Structure `{}`: {}", sel.candidate.id(), sel.notes),
        heldout_runs: sel.heldout_runs.clone(),
        heldout_misfit_baseline: round_sig(before, 4),
        heldout_misfit_extended: round_sig(after, 4),
        relative_gain: round_sig(gain, 3),
        relative_gain_fold_sd: round_sig(sd, 2),
        criterion: Some(round_sig(-t, 4)),
        ..Finding::default()
    })
}

/// Puts the selection into the diagnosis: `structure`, the scores, the
/// parameters at bounds, and the winner's finding (module docs: after the
/// vocabulary findings, before an `unexplained` one; the verdict becomes
/// the structure's when it was `none`). The one call from [`crate::diagnose`].
pub fn attach(d: &mut crate::Diagnosis, sel: StructureSelection) {
    if let Some(f) = finding(&sel) {
        let at = d.findings.iter().position(|f| f.effect == crate::effects::UNEXPLAINED).unwrap_or(d.findings.len());
        if d.verdict == crate::effects::NONE {
            d.verdict = f.effect.clone();
        }
        d.findings.insert(at, f);
    }
    d.detail.structure_scores = sel.scores;
    d.structure = crate::Structure { damping: sel.damping.into(), notes: sel.notes };
    d.parameters_at_bounds = sel.at_bounds;
}
/// Fold-jackknife standard error of each parameter from the K fits that
/// each leave one fold out: sqrt((K − 1)/K · Σ (θ_k − θ̄)²) (∞ when a fold's
/// fit failed or K < 2).
pub(super) fn jackknife_se(fits: &[Option<Fitted>], n: usize) -> Vec<f64> {
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

pub(super) fn capitalise(s: &str) -> String {
    let mut c = s.chars();
    c.next().map_or(String::new(), |f| f.to_uppercase().chain(c).collect())
}
