//! Candidate friction laws as parameter vectors with bounds, the misfit of a
//! law against measured features (defined once here), and the fit: coordinate
//! descent with `rig_types::minimize::brent_min` on each parameter in turn
//! (the workspace's one bracketed minimiser), on the calibration runs only.
//!
//! Misfit of one run (dimensionless, in units of the targets, RMS
//! over the terms both records carry):
//! - regime: 0 when the regimes agree, 2 when they differ;
//! - period: ln(P_sim/P_meas)/ln 2 (a factor 2 is 1) for stick-slip,
//!   ln(P_sim/P_meas)/ln 1.15 for an inertial oscillation;
//! - drop per slip: ln(D_sim/D_meas)/ln 2;
//! - force at slip onset: (F_sim − F_meas)/0.05.
//!
//! When one side has no slips only the regime term counts.

use crate::features::{Features, Regime};
use crate::sim::Law;
use rig_types::minimize::brent_min;
use serde::Serialize;

/// A candidate law family.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Serialize)]
#[serde(rename_all = "snake_case")]
pub enum Candidate {
    /// The baseline: μs, μk.
    Coulomb,
    /// Static threshold growing with stick time, velocity-strengthening kinetic friction.
    StaticAgeing,
    /// Dieterich–Ruina rate-and-state friction with the ageing law.
    RateState,
}

pub const CANDIDATES: [Candidate; 3] = [Candidate::Coulomb, Candidate::StaticAgeing, Candidate::RateState];

/// A fitted parameter's name (with unit), bounds and whether it is searched in log.
#[derive(Debug, Clone, Copy)]
pub struct ParamSpec {
    pub name: &'static str,
    pub lo: f64,
    pub hi: f64,
    pub log: bool,
}

const fn p(name: &'static str, lo: f64, hi: f64, log: bool) -> ParamSpec {
    ParamSpec { name, lo, hi, log }
}

/// Reference speed of the rate-and-state law, m/s (μ0 is the steady friction there).
pub const V_REF_M_S: f64 = 1e-4;
/// Speed scale of the velocity-strengthening kinetic law, m/s.
pub const V1_M_S: f64 = 1e-4;

impl Candidate {
    pub fn id(self) -> &'static str {
        match self {
            Candidate::Coulomb => "coulomb",
            Candidate::StaticAgeing => "static_ageing",
            Candidate::RateState => "rate_state_ageing",
        }
    }

    /// The fitted parameters, in the order of [`Candidate::law`]'s vector.
    pub fn params(self) -> &'static [ParamSpec] {
        const COULOMB: &[ParamSpec] = &[p("mu_static", 0.2, 0.8, false), p("mu_drop", 0.001, 0.3, true)];
        const AGEING: &[ParamSpec] = &[
            p("mu_static0", 0.2, 0.8, false),
            p("ageing_beta", 1e-4, 0.05, true),
            p("ageing_time_s", 1e-3, 10.0, true),
            p("mu_drop", 0.001, 0.3, true),
            p("alpha", 1e-4, 0.1, true),
        ];
        const RATE_STATE: &[ParamSpec] = &[
            p("mu0", 0.2, 0.8, false),
            p("a", 1e-3, 0.1, true),
            p("b_minus_a", 1e-4, 0.1, true),
            p("dc_m", 1e-7, 1e-4, true),
        ];
        match self {
            Candidate::Coulomb => COULOMB,
            Candidate::StaticAgeing => AGEING,
            Candidate::RateState => RATE_STATE,
        }
    }
    /// The law of parameter vector `x`.
    pub fn law(self, x: &[f64]) -> Law {
        match self {
            Candidate::Coulomb => Law::Coulomb { mu_static: x[0], mu_kinetic: x[0] - x[1] },
            Candidate::StaticAgeing => Law::StaticAgeing {
                mu_static0: x[0],
                ageing_beta: x[1],
                ageing_time_s: x[2],
                mu_kinetic0: x[0] - x[3],
                alpha: x[4],
                v1_m_s: V1_M_S,
            },
            Candidate::RateState => {
                Law::RateState { mu0: x[0], a: x[1], b: x[1] + x[2], dc_m: x[3], v_ref_m_s: V_REF_M_S }
            }
        }
    }

    /// Starting points inside the bounds (around the measured mean force
    /// `mu`); the fit starts from the one with the lowest calibration misfit.
    /// For the memory laws they span the literature's range for paper on
    /// paper (a, b − a of 0.003–0.01, Dc of 0.3–3 µm, ageing over 0.01–1 s;
    /// Heslot et al. 1994, Baumberger & Caroli 2006): where the search
    /// starts, not a value it keeps.
    pub fn starts(self, mu: f64) -> Vec<Vec<f64>> {
        match self {
            Candidate::Coulomb => vec![vec![mu + 0.02, 0.04], vec![mu + 0.01, 0.01], vec![mu + 0.05, 0.1]],
            Candidate::StaticAgeing => [(0.002, 0.01), (0.002, 1.0), (0.01, 0.01), (0.01, 1.0)]
                .iter()
                .map(|&(beta, tau)| vec![mu, beta, tau, 0.03, 0.005])
                .collect(),
            Candidate::RateState => {
                [0.003, 0.01].iter().flat_map(|&bma| [0.3e-6, 1e-6, 3e-6].map(|dc| vec![mu, 0.01, bma, dc])).collect()
            }
        }
    }
}

/// The misfit of simulated features `s` against measured `m` (module docs).
pub fn run_misfit(m: &Features, s: &Features) -> f64 {
    let mut terms = vec![if m.regime == s.regime { 0.0 } else { 2.0 }];
    let both = m.regime != Regime::SteadySliding && s.regime != Regime::SteadySliding;
    if both && m.period_s.n > 0 && s.period_s.n > 0 {
        let unit = if m.regime == Regime::InertialOscillation { 1.15f64.ln() } else { 2f64.ln() };
        terms.push((s.period_s.median / m.period_s.median).ln() / unit);
        terms.push((s.drop.median / m.drop.median).ln() / 2f64.ln());
        terms.push((s.onset.median - m.onset.median) / 0.05);
    }
    (terms.iter().map(|t| t * t).sum::<f64>() / terms.len() as f64).sqrt()
}

/// A map of a parameter onto the search axis and back.
type AxisMap = fn(f64) -> f64;
const LN: AxisMap = f64::ln;
const EXP: AxisMap = f64::exp;
const IDENTITY: AxisMap = |v| v;

/// Coordinate descent: `sweeps` passes of Brent over each parameter within
/// its bounds (in log where flagged), `evals` evaluations per line search.
/// Returns the best vector and its cost.
pub fn fit(
    cand: Candidate,
    start: &[f64],
    sweeps: usize,
    evals: usize,
    cost: impl Fn(&[f64]) -> f64,
) -> (Vec<f64>, f64) {
    let specs = cand.params();
    let mut x: Vec<f64> = start.iter().zip(specs).map(|(v, s)| v.clamp(s.lo, s.hi)).collect();
    let mut best = cost(&x);
    for _ in 0..sweeps {
        for (j, s) in specs.iter().enumerate() {
            let (to, from) = if s.log { (LN, EXP) } else { (IDENTITY, IDENTITY) };
            let mut trial = x.clone();
            let u = brent_min(to(s.lo), to(s.hi), 1e-3 * (to(s.hi) - to(s.lo)).abs(), evals, |u| {
                trial[j] = from(u);
                cost(&trial)
            });
            trial[j] = from(u);
            let c = cost(&trial);
            if c < best {
                best = c;
                x = trial;
            }
        }
    }
    (x, best)
}
