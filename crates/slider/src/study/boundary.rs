//! The creep boundary of rate and state at a creeping run ([`boundary_scan`]):
//! where the law's critical stiffness crosses the run's, read by the one
//! feature function.

use super::{BoundaryScan, Measured, ScanCase, StudyParams, predict};
use crate::features::Regime;
use crate::fit::{Candidate, Model, SetupCandidate, StartHints, run_misfit};
use rayon::prelude::*;

/// [`BoundaryScan`] of run `i`, at a = 0.003 and 0.01 and Dc = 0.3 and 1 µm
/// (the literature's range for paper: Heslot et al. 1994, Baumberger &
/// Caroli 2006; where the scan sits, not a fitted value), and at Dc = 1 µm
/// with the a of the run's own Hopf oscillation (`fit::hopf_starts`: the
/// a that puts the linearised law's period at the measured one when k_c is
/// the run's stiffness), μ0 at the run's mean force: whether the law has a
/// creep regime at that (k, V) at all, and where.
pub fn boundary_scan(runs: &[Measured], i: usize, p: &StudyParams) -> BoundaryScan {
    let m = &runs[i];
    let rs = Model { friction: Candidate::RateState, setup: SetupCandidate::Stated };
    let weight_n = p.mass_kg * p.gravity_m_s2;
    let mut cases: Vec<(f64, f64)> = [0.003, 0.01].iter().flat_map(|&a| [0.3e-6, 1e-6].map(|dc| (a, dc))).collect();
    let hints = StartHints {
        mu: m.features.mean_force,
        kc_over_weight_per_m: m.stiffness_n_m / weight_n,
        period_ratio: 1.0,
        stiffest_n_m: m.stiffness_n_m,
        creep: Some((m.stiffness_n_m / weight_n, m.drive_speed_um_s * 1e-6, m.features.period_s.median)),
    };
    // The first Hopf start: Dc = 1 µm, k_c at the run's stiffness.
    if let Some(x) = crate::fit::hopf_starts(&hints).first() {
        cases.push(((1e3 * x[1]).round() / 1e3, x[3]));
    }
    let scans: Vec<ScanCase> = cases
        .par_iter()
        .map(|&(a, dc)| {
            let regimes = (0..13)
                .map(|j| {
                    let ratio = 0.85 + 0.025 * j as f64;
                    let b_minus_a = ratio * m.stiffness_n_m * dc / weight_n;
                    (ratio, predict(rs, &[m.features.mean_force, a, b_minus_a, dc], m, p).regime)
                })
                .collect();
            (a, dc, regimes)
        })
        .collect();
    let creeping_law = scans.iter().find_map(|(a, dc, regimes)| {
        let ratio = regimes.iter().find(|x| x.1 == Regime::Creep)?.0;
        let x = vec![m.features.mean_force, *a, ratio * m.stiffness_n_m * dc / weight_n, *dc];
        let same_k: Vec<usize> = (0..runs.len()).filter(|&j| runs[j].stiffness_n_m == m.stiffness_n_m).collect();
        let at = same_k
            .par_iter()
            .map(|&j| {
                let f = predict(rs, &x, &runs[j], p);
                (j, f, run_misfit(&runs[j].features, &f))
            })
            .collect();
        Some((x, at))
    });
    BoundaryScan { run: i, scans, creeping_law }
}
