//! A model's fit on some runs ([`fit_on`]): Nelder–Mead from its
//! best-scored starts, the nested model's among them.

use super::{Fitted, Measured, StudyParams, local_misfit, misfit_at};
use crate::features::{Regime, Spread};
use crate::fit::{FitResult, FitTolerance, Model, SetupCandidate, StartHints, critical_stiffness_guess_n_m, fit};

/// Fits `model` on the runs `train` (indices into `runs`): Nelder–Mead from
/// the best-scored of its physical starts and of the starts `nested` (the
/// model the forward step extends, fitted on the same runs) gives
/// ([`warm_starts`]), the best result kept.
pub(super) fn fit_on(
    model: Model,
    runs: &[Measured],
    train: &[usize],
    nested: Option<&Fitted>,
    p: &StudyParams,
) -> Fitted {
    let on: Vec<&Measured> = train.iter().map(|&i| &runs[i]).collect();
    let mu = on.iter().map(|r| r.features.mean_force).sum::<f64>() / on.len() as f64;
    // Each stiffness's slowest run: where the stability boundary shows.
    let mut slowest: Vec<(f64, Regime)> = Vec::new();
    for r in &on {
        let slower = on.iter().any(|q| q.stiffness_n_m == r.stiffness_n_m && q.drive_speed_um_s < r.drive_speed_um_s);
        if !slower {
            slowest.push((r.stiffness_n_m, r.features.regime));
        }
    }
    let kc = critical_stiffness_guess_n_m(&slowest) / (p.mass_kg * p.gravity_m_s2);
    // The measured inertial periods over the stated natural period (where a set-up's search starts).
    let ratios: Vec<f64> = on
        .iter()
        .filter(|r| r.features.regime == Regime::InertialOscillation && r.features.period_s.n > 0)
        .map(|r| r.features.period_s.median / r.features.natural_period_s)
        .collect();
    let period_ratio = if ratios.is_empty() { 1.0 } else { Spread::of(&ratios).median };
    let stiffest = on.iter().map(|r| r.stiffness_n_m).fold(0.0, f64::max);
    // The slowest creeping run (where the boundary's Hopf oscillation shows).
    let weight_n = p.mass_kg * p.gravity_m_s2;
    let creep = on
        .iter()
        .filter(|r| r.features.regime == Regime::Creep && r.features.period_s.n > 0)
        .min_by(|a, b| a.drive_speed_um_s.total_cmp(&b.drive_speed_um_s))
        .map(|r| (r.stiffness_n_m / weight_n, r.drive_speed_um_s * 1e-6, r.features.period_s.median));
    let hints = StartHints { mu, kc_over_weight_per_m: kc, period_ratio, stiffest_n_m: stiffest, creep };
    // Each point costed once per fit: Nelder–Mead re-evaluates its start
    // (scored among the starts) and, clamped at a bound, may step onto a
    // point it has costed (the same bits, the same simulations, the same value).
    let costed: std::cell::RefCell<Vec<(Vec<u64>, f64)>> = Default::default();
    let cost = |x: &[f64]| {
        let key: Vec<u64> = x.iter().map(|v| v.to_bits()).collect();
        if let Some(&(_, c)) = costed.borrow().iter().find(|(k, _)| *k == key) {
            return c;
        }
        let c = misfit_at(model, x, &on, p).0;
        costed.borrow_mut().push((key, c));
        c
    };
    let specs = model.params();
    // Multi-start: every start scored, then Nelder–Mead from each in the
    // order of its score: `fit_starts` of them; converged fits
    // (`fit_tolerance` > 0) on while the last one lowered the best misfit by
    // more than the tolerance (the restart rule of `nelder_mead_converged`,
    // over starts). The best result kept (the first of equals).
    let mut starts = nested.map_or_else(Vec::new, |f| warm_starts(model, f, &hints));
    starts.extend(model.starts(&hints));
    let mut scored: Vec<(f64, Vec<f64>)> = starts.into_iter().map(|x| (cost(&x), x)).collect();
    scored.sort_by(|a, b| a.0.total_cmp(&b.0));
    let tol = FitTolerance { tolerance: p.fit_tolerance, max_evals: p.fit_evals };
    let (mut evals, mut converged) = (scored.len(), true);
    let mut best: Option<FitResult> = None;
    // Raced (`fit_race_keep` > 0): the `fit_starts` best-scored starts side
    // by side for `fit_evals` evaluations, the `fit_race_keep` best on.
    let race = p.fit_race_keep > 0 && p.fit_tolerance <= 0.0;
    if race {
        let first: Vec<Vec<f64>> = scored.iter().take(p.fit_starts.max(1)).map(|(_, x)| x.clone()).collect();
        let r = crate::fit::fit_race(&specs, &first, p.fit_evals, p.fit_race_keep, p.fit_race_evals, cost);
        evals += r.evals;
        converged = false;
        best = Some(r);
    }
    for (k, (_, x)) in scored.iter().enumerate().take(if race { 0 } else { scored.len() }) {
        let r = fit(&specs, x, &tol, cost);
        evals += r.evals;
        converged &= r.converged;
        let before = best.as_ref().map_or(f64::INFINITY, |b| b.cost);
        let improved = r.cost < before - p.fit_tolerance;
        if r.cost < before {
            best = Some(r);
        }
        if k + 1 >= p.fit_starts.max(1) && (p.fit_tolerance <= 0.0 || !improved) {
            break;
        }
    }
    let best = best.expect("every model has a start");
    let (params, calibration_misfit) = (best.x, best.cost);
    let at_bounds = specs
        .iter()
        .zip(&params)
        .filter(|(s, v)| {
            let (lo, hi, v) = if s.log { (s.lo.ln(), s.hi.ln(), v.ln()) } else { (s.lo, s.hi, **v) };
            (v - lo) < 0.01 * (hi - lo) || (hi - v) < 0.01 * (hi - lo)
        })
        .map(|(s, _)| s.name)
        .collect();
    Fitted {
        model,
        train: train.to_vec(),
        params,
        calibration_misfit,
        at_bounds,
        evals,
        converged,
        local: None,
        noisy: false,
    }
}

/// A fit the selection reads, read for noise on its training runs alone
/// (the lead's decision, issue 26): its calibration misfit over the study's
/// fixed moves ([`local_misfit`]), noisy when their sd exceeds `noisy_sd`.
/// After the search (the search is unchanged, the judgement reads the fit's
/// neighbourhood), and only at the fits the selection reads: the engine's
/// trials and baselines, not the report's fits on every calibration run
/// under leave one stiffness out.
pub(super) fn read_noise(mut f: Fitted, runs: &[Measured], p: &StudyParams) -> Fitted {
    if p.local_moves > 1 {
        let on: Vec<&Measured> = f.train.iter().map(|&i| &runs[i]).collect();
        let l = local_misfit(f.model, &f.params, &on, p, p.local_moves, p.local_rel_step);
        f.noisy = l.sd > p.noisy_sd;
        f.local = Some(l);
    }
    f
}

/// Starts from a nested fit: its law with each of `model`'s set-up starts
/// (a set-up added: the stated-like start reproduces the nested optimum), or
/// each of `model`'s law starts on the nested set-up (a memory law added on
/// a set-up). None when the law changes on the stated set-up (nothing of
/// the nested fit carries over).
fn warm_starts(model: Model, nested: &Fitted, hints: &StartHints) -> Vec<Vec<f64>> {
    let nf = nested.model.friction.params().len();
    let (law, setup) = nested.params.split_at(nf);
    let join = |a: &[f64], b: &[f64]| a.iter().chain(b).copied().collect::<Vec<f64>>();
    if nested.model.friction == model.friction && nested.model.setup != model.setup {
        model.setup.starts(hints).iter().map(|s| join(law, s)).collect()
    } else if nested.model.setup == model.setup && model.setup != SetupCandidate::Stated {
        model.friction.starts(&StartHints { mu: law[0], ..*hints }).iter().map(|l| join(l, setup)).collect()
    } else {
        Vec::new()
    }
}
