//! Forward selection with the campaign diagnosis' logic: at each step every
//! remaining candidate is fitted on the calibration window on top of the
//! current model and scored on the held-out windows; the one with the largest
//! held-out gain is added while it earns its place (relative gain of the mean
//! held-out misfit ≥ `min_relative_gain` **and** a one-sided paired t-test over
//! the held-out windows at level `significance`, **and** no worse on the
//! calibration window). Then the adequacy verdict.

use crate::fit::{Fitted, fit_candidate};
use crate::score::Evaluator;
use crate::sim::Model;
use crate::{Candidate, LaviError};
use rayon::prelude::*;
use serde::Serialize;

/// One candidate tried at one step.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct Trial {
    pub step: usize,
    pub candidate: Candidate,
    pub fitted: Fitted,
    /// Held-out misfit per window (window order), of the extended model.
    pub heldout: Vec<f64>,
    pub heldout_mean: f64,
    /// 1 − mean(extended)/mean(current).
    pub relative_gain: f64,
    /// Paired t of (current − extended) over the held-out windows.
    pub paired_t: f64,
    /// Held-out windows where the candidate is better than the current model.
    pub wins: usize,
    pub earns_place: bool,
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
    pub t_critical: f64,
}

/// Runs the forward selection from `baseline`.
pub fn forward_select(
    ev: &Evaluator,
    baseline: &Model,
    candidates: &[Candidate],
    max_evals: usize,
    min_relative_gain: f64,
    significance: f64,
) -> Result<Selection, LaviError> {
    let mut current = *baseline;
    let mut current_held = ev.heldout_misfits(&current);
    let mut current_cal = ev.misfit(&current, ev.calibration());
    let n = current_held.len();
    let t_critical = t_quantile_one_sided(significance, n.saturating_sub(1));
    let mut sel = Selection {
        baseline_heldout: current_held.clone(),
        baseline_calibration: current_cal,
        trials: Vec::new(),
        chosen: Vec::new(),
        final_model: current,
        final_heldout: current_held.clone(),
        t_critical,
    };
    let mut left: Vec<Candidate> = candidates.to_vec();
    let mut step = 1;
    while !left.is_empty() {
        let first = sel.trials.len();
        // Each candidate's fit and held-out scores are independent: fitted in
        // parallel, kept in candidate order (the same numbers on any thread count).
        let fits: Vec<Result<(Fitted, Vec<f64>), LaviError>> = left
            .par_iter()
            .map(|c| {
                let fitted = fit_candidate(*c, &current, ev, max_evals)?;
                let heldout = ev.heldout_misfits(&fitted.model);
                Ok((fitted, heldout))
            })
            .collect();
        for (c, fit) in left.iter().zip(fits) {
            let (fitted, heldout) = fit?;
            let heldout_mean = mean(&heldout);
            let d: Vec<f64> = current_held.iter().zip(&heldout).map(|(a, b)| a - b).collect();
            let (md, sd) = (mean(&d), std(&d));
            let paired_t = if sd > 0.0 {
                md / (sd / (n as f64).sqrt())
            } else if md > 0.0 {
                f64::INFINITY
            } else {
                0.0
            };
            let relative_gain = 1.0 - heldout_mean / mean(&current_held);
            let wins = d.iter().filter(|x| **x > 0.0).count();
            let earns_place = relative_gain >= min_relative_gain
                && paired_t > t_critical
                && fitted.calibration_misfit <= current_cal + 1e-12;
            sel.trials.push(Trial {
                step,
                candidate: *c,
                fitted,
                heldout,
                heldout_mean,
                relative_gain,
                paired_t,
                wins,
                earns_place,
            });
        }
        // Largest held-out gain of this step (ties: candidate order).
        let best = (first..sel.trials.len())
            .max_by(|&a, &b| sel.trials[a].relative_gain.total_cmp(&sel.trials[b].relative_gain).then(b.cmp(&a)))
            .expect("at least one candidate left");
        if !sel.trials[best].earns_place {
            break;
        }
        let t = &sel.trials[best];
        current = t.fitted.model;
        current_held = t.heldout.clone();
        current_cal = t.fitted.calibration_misfit;
        left.retain(|c| *c != t.candidate);
        sel.chosen.push(best);
        step += 1;
    }
    sel.final_model = current;
    sel.final_heldout = current_held;
    Ok(sel)
}

pub(crate) fn mean(x: &[f64]) -> f64 {
    x.iter().sum::<f64>() / x.len().max(1) as f64
}

pub(crate) fn std(x: &[f64]) -> f64 {
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len().max(2) - 1) as f64).sqrt()
}

/// One-sided Student t quantile t_{1−α, df} for α = 0.05 or 0.01 (table,
/// Abramowitz & Stegun 26.10); df > 30 uses the normal quantile.
#[allow(clippy::approx_constant)] // 2.718 is t_{0.99, 11}, not e
pub fn t_quantile_one_sided(alpha: f64, df: usize) -> f64 {
    const T05: [f64; 30] = [
        6.314, 2.920, 2.353, 2.132, 2.015, 1.943, 1.895, 1.860, 1.833, 1.812, 1.796, 1.782, 1.771, 1.761, 1.753, 1.746,
        1.740, 1.734, 1.729, 1.725, 1.721, 1.717, 1.714, 1.711, 1.708, 1.706, 1.703, 1.701, 1.699, 1.697,
    ];
    const T01: [f64; 30] = [
        31.821, 6.965, 4.541, 3.747, 3.365, 3.143, 2.998, 2.896, 2.821, 2.764, 2.718, 2.681, 2.650, 2.624, 2.602,
        2.583, 2.567, 2.552, 2.539, 2.528, 2.518, 2.508, 2.500, 2.492, 2.485, 2.479, 2.473, 2.467, 2.462, 2.457,
    ];
    let (table, z) = if alpha <= 0.01 { (&T01, 2.326) } else { (&T05, 1.645) };
    match df {
        0 => f64::INFINITY,
        1..=30 => table[df - 1],
        _ => z,
    }
}
