//! `slider-diagnosis.json` in the schema of ../shared/spec/diagnosis.md.

use super::*;

pub(super) fn heldout_names(s: &Study, c: &CandidateResult) -> Vec<String> {
    c.heldout.iter().map(|h| s.runs[h.0].name.clone()).collect()
}

/// The elements a forward step added: the memory law or the set-up that
/// differs, both (`law+set-up`) after the engine's pair step.
pub(super) fn added(from: Model, to: Model) -> String {
    match (from.friction != to.friction, from.setup != to.setup) {
        (true, true) => format!("{}+{}", to.friction.id(), to.setup.id()),
        (true, false) => to.friction.id().to_string(),
        _ => to.setup.id().to_string(),
    }
}

/// The parameters of the element `to` adds over `from`, by name.
pub(super) fn added_params(from: Model, c: &CandidateResult, values: Option<&[f64]>) -> Value {
    let n = c.model.friction.params().len();
    let all = c.model.params();
    let keep = |j: usize| if j < n { from.friction != c.model.friction } else { from.setup != c.model.setup };
    Value::Object(
        all.iter()
            .enumerate()
            .filter(|(j, _)| keep(*j))
            .map(|(j, p)| (p.name.to_string(), values.map_or(Value::Null, |v| json!(v[j]))))
            .collect(),
    )
}

/// A step's resolution: the larger relative roughness of the calibration
/// misfit at the fits of the model it starts from and of its best
/// ([`crate::study::roughness`]); None when either was not scanned.
pub(super) fn step_resolution(s: &Study, st: &Step) -> Option<f64> {
    let r = |i: usize| s.candidates[i].roughness.as_ref().map(crate::study::Roughness::relative);
    Some(r(st.from)?.max(r(st.best)?))
}

/// Whether a step's gain is within its resolution ([`step_resolution`]):
/// a difference the search that found the fits does not resolve.
pub(super) fn within_resolution(s: &Study, st: &Step) -> Option<bool> {
    step_resolution(s, st).map(|r| st.gain.gain.abs() <= r)
}

/// What a step's neighbouring readings of the gain are ([`crate::study::GainSpread`]).
pub(super) fn neighbours_text(s: &Study, g: &crate::study::GainSpread) -> String {
    if g.over_moves {
        format!(
            "at each of the {} fixed moves of {} % (its fits noisy: the one draws its local means average)",
            g.neighbours,
            (1e8 * s.params.local_rel_step).round() / 1e6
        )
    } else {
        format!(
            "among the {} neighbouring fold fits (one moved {} % along one parameter)",
            g.neighbours,
            (1e8 * s.params.roughness_rel_step).round() / 1e6
        )
    }
}

/// The sentence on a step's gain against its resolution, e.g. for the verdict.
pub(super) fn resolution_clause(s: &Study, st: &Step) -> String {
    let spread = st.gain_spread.as_ref().map_or(String::new(), |g| {
        format!(
            "; {} the gain runs {:.1}–{:.1} %, t {:.2}–{:.2}, {} admitted",
            neighbours_text(s, g),
            100.0 * g.gain_min,
            100.0 * g.gain_max,
            g.t_min,
            g.t_max,
            g.admitted
        )
    });
    let resolution = match (step_resolution(s, st), within_resolution(s, st)) {
        (Some(r), Some(true)) => format!(
            "; the gain is within the misfit's resolution at these fits (the calibration misfit moves by up to {:.1} % between points {} % apart): not resolved by the search",
            100.0 * r,
            (1e8 * s.params.roughness_rel_step).round() / 1e6
        ),
        (Some(r), _) => format!(
            "; the gain is beyond the misfit's resolution at these fits (up to {:.1} % between points {} % apart)",
            100.0 * r,
            (1e8 * s.params.roughness_rel_step).round() / 1e6
        ),
        _ => String::new(),
    };
    resolution + &spread
}

/// The kept steps, in order.
pub(super) fn kept_steps(s: &Study) -> impl Iterator<Item = &Step> {
    s.steps.iter().filter(|st| st.kept)
}

pub(super) fn diagnosis_json(s: &Study) -> Value {
    let base = &s.candidates[0];
    let mut findings = Vec::new();
    for st in kept_steps(s) {
        let (from, to) = (&s.candidates[st.from], &s.candidates[st.best]);
        findings.push(json!({
            "effect": added(from.model, to.model),
            "model": to.model.id(),
            "params": added_params(from.model, to, Some(&full_fit(to).params)),
            "params_stderr": added_params(from.model, to, None),
            "evidence": evidence(s, st),
            "heldout_runs": heldout_names(s, to),
            "heldout_misfit_baseline": from.heldout_mean,
            "heldout_misfit_extended": to.heldout_mean,
            "heldout_misfit_rms_baseline": st.gain.before,
            "heldout_misfit_rms_extended": st.gain.after,
            "relative_gain": st.gain.gain,
            "relative_gain_fold_sd": st.gain.gain_fold_sd,
            "paired_t": st.gain.t,
        }));
    }
    let final_c = s.chosen.map(|c| &s.candidates[c]).unwrap_or(base);
    let adequate = adequate(s, final_c);
    if !adequate {
        let where_: Vec<String> = final_c
            .heldout
            .iter()
            .filter(|h| h.1 > s.params.adequacy_threshold || misses_resolved(s, h))
            .map(|h| s.runs[h.0].name.clone())
            .collect();
        let ext = extension(s);
        findings.push(json!({
            "effect": "unexplained",
            "evidence": format!(
                "the final model ({1}) has a mean held-out misfit of {0:.2} (adequacy threshold {2}) and misses the regime, a check it resolves or the threshold at: {3}",
                final_c.heldout_mean, final_c.model.id(), s.params.adequacy_threshold, where_.join(", ")),
            "residual_over_noise": final_c.heldout_mean / s.params.adequacy_threshold,
            "where": where_,
            "signature": [],
            "heldout_misfit_baseline": base.heldout_mean,
            "heldout_misfit_extended": ext.heldout_mean,
        }));
    }
    let verdict = match (kept_steps(s).next(), adequate) {
        (_, false) => "unexplained".to_string(),
        (Some(st), true) => added(s.candidates[st.from].model, s.candidates[st.best].model),
        (None, true) => "none".to_string(),
    };
    // Every fit that pressed a parameter against its bound (on every calibration run, or on a fold: which runs it saw).
    let at_bounds: Vec<Value> = s
        .candidates
        .iter()
        .flat_map(|c| {
            let specs = c.model.params();
            c.fitted.iter().chain(&c.fold_fits).flat_map(move |f| {
                let specs = specs.clone();
                f.at_bounds.iter().map(move |p| {
                    let j = specs.iter().position(|q| q.name == *p).expect("a parameter of the model");
                    let (spec, v) = (specs[j], f.params[j]);
                    let ks = distinct(f.train.iter().map(|&i| s.runs[i].stiffness_n_m));
                    json!({
                        "parameter": format!("{}.{}", c.model.id(), p),
                        "fitted_on_stiffnesses_n_m": ks,
                        "bound": if (v - spec.lo).abs() < (v - spec.hi).abs() { spec.lo } else { spec.hi },
                        "unconstrained": Value::Null,
                        "meaning": "the fit pressed this parameter against its bound: the model cannot reach what these runs want there",
                    })
                })
            })
        })
        .collect();
    json!({
        "campaign": s.folder_name,
        "verdict": verdict,
        "findings": findings,
        "candidates": s.candidates.iter().skip(1).map(|c| json!({
            "effect": c.model.id(),
            "heldout_misfit_extended": c.heldout_mean,
            // The calibration misfit on every calibration run, else the mean of the folds' own.
            "criterion": c.fitted.as_ref().map_or_else(
                || c.fold_fits.iter().map(|f| f.calibration_misfit).sum::<f64>() / c.fold_fits.len().max(1) as f64,
                |f| f.calibration_misfit,
            ),
            // How far the criterion moves one `roughness_rel_step` from the fit (null: not scanned).
            "criterion_roughness": c.roughness.as_ref().map(|r| r.max_change),
            // How the selection read its held-out misfits: "local_mean" when a fold's fit is noisy
            // (`crate::study::read_misfit`: the mean over `local_moves` fixed moves of `local_rel_step`),
            // with each run's sd over them (null: that run's fit is smooth, its point misfit).
            "misfits_read": if c.fold_fits.iter().any(|f| f.noisy) { "local_mean" } else { "point" },
            "heldout_misfit_sd": c.heldout_local.iter().map(|l| l.as_ref().map(|l| l.sd)).collect::<Vec<_>>(),
            // Each fit's calibration misfit over the moves (the noise classification, `noisy_sd`).
            "calibration_local": c.fits().map(|f| json!({
                "fitted_on_stiffnesses_n_m": distinct(f.train.iter().map(|&i| s.runs[i].stiffness_n_m)),
                "at": f.calibration_misfit,
                "local_mean": f.local.as_ref().map(|l| l.mean),
                "local_sd": f.local.as_ref().map(|l| l.sd),
                "noisy": f.noisy,
            })).collect::<Vec<_>>(),
        })).collect::<Vec<_>>(),
        "structure": {
            "notes": "one mass on one spring with an imposed drive speed; a model is a friction law on a set-up (the README's m and k, or an effective mass, a compliance in series, a scaled spring)",
            "final_model": final_c.model.id(),
        },
        "parameters_at_bounds": at_bounds,
        // Per step: its best's gain against the misfit's roughness at the fits (`crate::study::roughness`).
        "misfit_resolution": s.steps.iter().map(|st| json!({
            "step": st.step,
            "from": s.candidates[st.from].model.id(),
            "best": s.candidates[st.best].model.id(),
            "relative_gain": st.gain.gain,
            "relative_step": s.params.roughness_rel_step,
            "resolution": step_resolution(s, st),
            "gain_within_resolution": within_resolution(s, st),
            // The gain among the best's neighbouring fold fits (`crate::study::gain_spread`).
            "neighbour_fits": st.gain_spread.as_ref().map(|g| json!({
                "count": g.neighbours,
                // true: the best's fits are noisy, the neighbours are the fixed moves (`local_rel_step`).
                "over_moves": g.over_moves,
                "relative_gain_min": g.gain_min,
                "relative_gain_max": g.gain_max,
                "paired_t_min": g.t_min,
                "paired_t_max": g.t_max,
                "admitted": g.admitted,
            })),
        })).collect::<Vec<_>>(),
    })
}

pub(super) fn evidence(s: &Study, st: &Step) -> String {
    let (from, to) = (&s.candidates[st.from], &s.candidates[st.best]);
    format!(
        "held out ({}), {} lowers the RMS misfit of {} from {:.2} to {:.2} (gain {:.1} %, paired t {:.2} over {} runs) and gets {}/{} regimes right against {}/{} (tables/slider-heldout.csv){}",
        if s.leave_one_out { "leave one stiffness out" } else { "runs at stiffnesses outside the calibration list" },
        added(from.model, to.model),
        from.model.id(),
        st.gain.before,
        st.gain.after,
        100.0 * st.gain.gain,
        st.gain.t,
        to.heldout.len(),
        regimes_heldout(s, to),
        to.heldout.len(),
        regimes_heldout(s, from),
        from.heldout.len(),
        resolution_clause(s, st),
    )
}
