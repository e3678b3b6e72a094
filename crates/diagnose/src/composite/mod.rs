//! Several friction effects at once: the slip coefficient as a speed law
//! times the two modulations of the vocabulary,
//!
//! `μ(t, φ1, Ω) = μ_speed(Ω) · (1 + a_t sin(2π f t + θ_t,r)) · (1 + a_φ sin(n φ1 + θ_φ,r))`,
//!
//! with `μ_speed(Ω) = μk + (μs − μk) exp(−(Ω/vs)²) + c Ω` (the Stribeck and
//! viscous terms present only when their effect is in the model). The product
//! form is the spec's: both modulations act on the normal force N, and
//! F = μ(Ω)·N (Eq. 4-10) scales the whole speed law.
//!
//! The first pass fits blocks — speed law on μ_obs divided by the
//! modulations, each modulation on μ_obs divided by everything else — by the
//! single-effect fitters of [`crate::friction`] (their tests prove recovery;
//! they scan the modulation frequency or order and the Stribeck speed's basin).
//! From the second pass on, the speed law and the time modulation are one
//! block refined by Gauss–Newton on all their parameters at once
//! ([`refine_speed_time`]): alternating them converged only linearly where the
//! modulation is coupled to the slip-speed cycle, and six passes did not reach
//! a stationary point (test `coupled_speed_law_and_modulation_reach_a_stationary_point`).
//! The angle modulation stays its own block (its fitter's Newton steps handle
//! runs that differ in amplitude), alternated with that one until the weighted
//! RSS stops falling; a set whose first pass already fitted everything jointly
//! (one modulation, no speed law) ends there. Standard errors are the joint
//! block's (marginal over the speed law, the time modulation and its phases)
//! and the angle block's conditional on the rest, inflated for correlated
//! residuals (effective sample size).
//!
//! The module's files: this one the composite ([`Term`], [`FrictionSet`],
//! [`Composite`]), its entry points and the alternation of the blocks;
//! `joint.rs` the joint Gauss–Newton block of the speed law and the time
//! modulation ([`refine_speed_time`]) and its reported parameters;
//! `heldout.rs` a held-out run's phases and error under a fitted composite.

mod heldout;
mod joint;

pub(crate) use heldout::{HeldRuns, heldout_fits};
pub use heldout::{heldout_fit, heldout_phases, relative_mu_error};
use joint::{joint_params, refine_speed_time};

use crate::friction::{self, FrictionFit, FrictionModel, SlipData};
use std::f64::consts::PI;

/// A term of the composite law: what a friction effect of the vocabulary
/// contributes to the joint fit ([`crate::effects::VocabularyEffect::term`]).
/// The fit knows each term's regressors and searches; it never names an effect.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub enum Term {
    /// (μs − μk) exp(−(Ω/vs)²) in the speed law (Brent's search for vs).
    Stribeck,
    /// c Ω in the speed law (a linear column).
    Viscous,
    /// The factor 1 + a sin(2π f t + θ_r) (frequency scan, phase per run).
    TimeSine,
    /// The factor 1 + a sin(n φ1 + θ_r) (order scan, phase per run).
    AngleSine,
}

/// Which terms a composite law has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct FrictionSet {
    pub time_mod: bool,
    pub angle_mod: bool,
    pub stribeck: bool,
    pub viscous: bool,
}

impl FrictionSet {
    pub fn with(mut self, t: Term) -> Self {
        match t {
            Term::TimeSine => self.time_mod = true,
            Term::AngleSine => self.angle_mod = true,
            Term::Stribeck => self.stribeck = true,
            Term::Viscous => self.viscous = true,
        }
        self
    }
}

/// A fitted composite law.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Composite {
    pub mu_k: f64,
    /// (μs, vs) of the Stribeck term.
    pub stribeck: Option<(f64, f64)>,
    /// c of the viscous term, per rad/s.
    pub viscous: Option<f64>,
    /// (a, f Hz) of the normal-force modulation.
    pub time_mod: Option<(f64, f64)>,
    /// (a, n) of the angle-periodic friction.
    pub angle_mod: Option<(f64, u32)>,
}

/// Per-run nuisance phases (θ_t, θ_φ).
pub type Phases = (f64, f64);

impl Composite {
    pub fn coulomb(mu_k: f64) -> Self {
        Composite { mu_k, ..Default::default() }
    }

    pub fn speed_mu(&self, omega: f64) -> f64 {
        let mut m = self.mu_k;
        if let Some((mu_s, vs)) = self.stribeck {
            m += (mu_s - self.mu_k) * rig_model::friction::stribeck_decay(omega, vs);
        }
        if let Some(c) = self.viscous {
            m += c * omega;
        }
        m
    }

    pub fn time_factor(&self, t: f64, th: f64) -> f64 {
        self.time_mod.map_or(1.0, |(a, f)| 1.0 + a * (2.0 * PI * f * t + th).sin())
    }

    pub fn angle_factor(&self, phi: f64, th: f64) -> f64 {
        self.angle_mod.map_or(1.0, |(a, n)| 1.0 + a * (n as f64 * phi + th).sin())
    }

    pub fn mu(&self, t: f64, phi: f64, omega: f64, ph: Phases) -> f64 {
        self.speed_mu(omega) * self.time_factor(t, ph.0) * self.angle_factor(phi, ph.1)
    }

    /// Scales the speed law (a modulation fit returns its mean level as a factor).
    fn scale(&mut self, s: f64) {
        self.mu_k *= s;
        if let Some((mu_s, _)) = self.stribeck.as_mut() {
            *mu_s *= s;
        }
        if let Some(c) = self.viscous.as_mut() {
            *c *= s;
        }
    }
}

/// A composite fit on the training runs.
#[derive(Debug, Clone)]
pub struct CompositeFit {
    pub model: Composite,
    /// Per training run.
    pub phases: Vec<Phases>,
    /// (term, JSON key, value, standard error).
    pub params: Vec<(Term, &'static str, f64, f64)>,
    /// The weighted RSS (NaN in a fit asked for its model alone: it is not computed).
    pub rss_w: f64,
    pub converged: bool,
    /// Frequency scan of the time modulation on the first pass: (Hz, weighted RSS).
    pub scan: Vec<(f64, f64)>,
}

fn with_mu(d: &SlipData, f: impl Fn(usize) -> f64) -> SlipData {
    let mut e = d.clone();
    set_mu(&mut e, f);
    e
}

/// Replaces the target μ of `work` (a copy of the data being fitted) in
/// place: the composite's blocks refit the same samples against a new target
/// up to three times per pass, without a fresh copy of ≈ 400 000 samples
/// (16 MB) each time (its page faults were 6 % of a diagnosis's samples in
/// `perf`; the bench's wall time did not move measurably).
fn set_mu(work: &mut SlipData, f: impl Fn(usize) -> f64) {
    for i in 0..work.len() {
        work.mu[i] = f(i);
    }
}

/// Weighted RSS of a composite on slip data with per-run phases.
pub fn weighted_rss(d: &SlipData, m: &Composite, phases: &[Phases]) -> f64 {
    (0..d.len())
        .map(|i| {
            let ph = phases.get(d.run[i]).copied().unwrap_or((0.0, 0.0));
            let e = d.mu[i] - m.mu(d.t[i], d.phi[i], d.omega[i], ph);
            d.w(i) * e * e
        })
        .sum()
}

/// Fits the composite of `set` on `d` (the frequency grid and the highest
/// order are the scans of the modulations). `None` when a block is singular.
pub fn fit_composite(d: &SlipData, set: FrictionSet, freqs_hz: &[f64], max_order: u32) -> Option<CompositeFit> {
    fit_composite_with(d, set, freqs_hz, max_order, true, None, None)
}

/// The model of [`fit_composite`] alone, as a cross-validation fold uses it
/// (its held-out runs are predicted by the model; the parameters' standard
/// errors are never read): the same fit without the residuals' autocorrelation
/// pass that inflates the errors (6.6 % of a full-protocol ladder rung's CPU
/// in `perf`), so the same model to the bit.
pub fn fit_composite_model(d: &SlipData, set: FrictionSet, freqs_hz: &[f64], max_order: u32) -> Option<Composite> {
    fit_composite_model_from(d, set, freqs_hz, max_order, None)
}

/// [`fit_composite_model`] warm-started from `start`, a model fitted on the
/// same data with a subset of `set`'s terms (the previous selection step's
/// model of the same fold: same training runs, so nothing of a held-out run
/// enters). The first pass then searches only the basin `start` found for
/// each term it has — the time modulation's frequency (Gauss–Newton from
/// it, no frequency scan), the angle modulation's order, the Stribeck
/// speed's bracket ([`friction::fit_stribeck_near`]) — as the cold fit's
/// later passes do; a term `start` lacks is searched cold. The stop rules
/// are the cold fit's: Gauss–Newton until the step is within a tenth of a
/// standard error ([`friction::near_stationary`]), the passes until the
/// weighted RSS moves by less than 10⁻⁷ of itself.
pub fn fit_composite_model_from(
    d: &SlipData,
    set: FrictionSet,
    freqs_hz: &[f64],
    max_order: u32,
    start: Option<&Composite>,
) -> Option<Composite> {
    fit_composite_with(d, set, freqs_hz, max_order, false, start, None).map(|f| f.model)
}

/// What every composite fit of one data set computes alike, computed once
/// on first use (each a fold's training runs, shared by every friction set
/// of every selection step):
///
/// - The cold Stribeck fits, [`friction::fit_stribeck`] of `d` itself
///   without and with the viscous column. A composite's first pass fits
///   its speed law before any modulation, on μ/(1·1) = μ to the bit, so
///   every set with the Stribeck term and no warm-started speed
///   (`{stribeck}` of the first selection step, `{time, stribeck}` and
///   `{angle, stribeck}` of the second) starts from the same fit of the
///   same fold: bit-identical to fitting it again (a cold fit is a
///   41-point grid and Brent's search).
/// - The warm-started Stribeck fits of the first pass,
///   [`friction::fit_stribeck_near`] of `d` itself at the start's speed:
///   the first pass's target is μ/(1·1) = μ there too, and the sets a
///   step adds to a model with the Stribeck term start from the same
///   model's vs (`{stribeck, time}` and `{stribeck, angle}` after
///   `{stribeck}`: the same search on the same numbers, ≈ 20 passes of an
///   `exp` per sample each; issue 23).
/// - The sin and cos of n·φ1 of every sample at each order the angle
///   block fits ([`friction::AngleTrig`]).
#[derive(Debug, Default)]
pub struct DataMemo {
    fits: [std::sync::OnceLock<Option<FrictionFit>>; 2],
    /// By (with_viscous, the start's vs as bits); each filled once, outside the map's lock.
    near: std::sync::Mutex<NearFits>,
    angles: friction::AngleTrig,
}

/// [`DataMemo`]'s warm-started Stribeck fits by (with_viscous, bits of vs).
type NearFits = std::collections::BTreeMap<(bool, u64), std::sync::Arc<std::sync::OnceLock<Option<FrictionFit>>>>;

impl DataMemo {
    /// `friction::fit_stribeck(d, with_viscous)`, the first time for this `d`.
    fn get(&self, d: &SlipData, with_viscous: bool) -> Option<FrictionFit> {
        self.fits[usize::from(with_viscous)].get_or_init(|| friction::fit_stribeck(d, with_viscous)).clone()
    }

    /// `friction::fit_stribeck_near(d, with_viscous, vs)`, the first time for this `d` and vs.
    fn near(&self, d: &SlipData, with_viscous: bool, vs: f64) -> Option<FrictionFit> {
        let cell = self.near.lock().expect("near fits").entry((with_viscous, vs.to_bits())).or_default().clone();
        cell.get_or_init(|| friction::fit_stribeck_near(d, with_viscous, vs)).clone()
    }
}

/// [`fit_composite_model_from`] with `cold`, the memo of what every fit of
/// `d` computes alike ([`DataMemo`]: the same `d` on every call that
/// shares it), so the same model to the bit.
pub fn fit_composite_model_from_cached(
    d: &SlipData,
    set: FrictionSet,
    freqs_hz: &[f64],
    max_order: u32,
    start: Option<&Composite>,
    cold: &DataMemo,
) -> Option<Composite> {
    fit_composite_with(d, set, freqs_hz, max_order, false, start, Some(cold)).map(|f| f.model)
}

/// The time modulation's frequency scan of [`fit_composite`] for the set
/// `{TimeSine}` alone (the report's evidence figure), without the fit at the
/// scan's best frequency: the same numbers to the bit (the first pass's
/// Coulomb level, the target divided by it, [`friction::time_scan`]).
pub fn coulomb_time_scan(d: &SlipData, freqs_hz: &[f64]) -> Option<Vec<(f64, f64)>> {
    if d.is_empty() {
        return None;
    }
    let mu_k = friction::fit_coulomb(d).params[0].1;
    let m = Composite::coulomb(mu_k);
    let dt = with_mu(d, |i| d.mu[i] / m.speed_mu(d.omega[i]));
    Some(friction::time_scan(&dt, freqs_hz))
}

fn fit_composite_with(
    d: &SlipData,
    set: FrictionSet,
    freqs_hz: &[f64],
    max_order: u32,
    errors: bool,
    start: Option<&Composite>,
    cold: Option<&DataMemo>,
) -> Option<CompositeFit> {
    if d.is_empty() {
        return None;
    }
    // The basins a warm start hands the first pass (fit_composite_model_from).
    let start_vs = start.and_then(|s| s.stribeck).map(|s| s.1).filter(|_| set.stribeck);
    let start_f = start.and_then(|s| s.time_mod).map(|s| s.1).filter(|_| set.time_mod);
    let start_order = start.and_then(|s| s.angle_mod).map(|s| s.1).filter(|_| set.angle_mod);
    let base = friction::fit_coulomb(d);
    let mut m = Composite::coulomb(base.params[0].1);
    let mut phases = vec![(0.0, 0.0); d.n_runs];
    let mut params: Vec<(Term, &'static str, f64, f64)> = Vec::new();
    let mut scan = Vec::new();
    let mut rss = weighted_rss(d, &m, &phases);
    let mut converged = set == FrictionSet::default();
    // Without a modulation there is one block, the speed law, fitted exactly
    // once: a second pass would refit it to the same data (the same numbers)
    // only to find the RSS unchanged.
    let modulated = set.time_mod || set.angle_mod;
    let passes = if set == FrictionSet::default() {
        0
    } else if modulated {
        6
    } else {
        1
    };
    // The two modulation factors of every sample under the current model,
    // recomputed only when their block changes them (the same values
    // Composite::time_factor / angle_factor give, each evaluated once).
    let factors = |f: &dyn Fn(usize) -> f64| -> Vec<f64> { (0..d.len()).map(f).collect() };
    let mut tf = vec![1.0; d.len()];
    let mut af = vec![1.0; d.len()];
    let mut work = d.clone();
    let speed_law = set.stribeck || set.viscous;
    for pass in 0..passes {
        params.clear();
        // From the second pass on, the speed law and the time modulation are one
        // block ([`refine_speed_time`]); the first pass's block fits find its start
        // (the frequency scan, the Stribeck speed's basin).
        let joint = if pass > 0 && set.time_mod && speed_law {
            set_mu(&mut work, |i| d.mu[i] / af[i]);
            let th: Vec<f64> = phases.iter().map(|p| p.0).collect();
            refine_speed_time(&work, &m, &th, set.stribeck, set.viscous)
        } else {
            None
        };
        let joint_converged = joint.as_ref().map(|j| j.4);
        // A pass that fitted every parameter of the set jointly ends the fit: a
        // single modulation without a speed law (fit_sine fits its level, amplitude,
        // frequency or order and phases together), or the joint block without an
        // angle modulation. Otherwise the blocks alternate until the RSS settles.
        let one_block =
            if set.angle_mod { !set.time_mod && !speed_law } else { !speed_law || joint_converged.is_some() };
        // Where this pass ends the fit whatever its RSS, a fit asked for its
        // model alone (a fold's, `errors` false) needs neither the last
        // block's modulation factors nor the closing RSS (`rss_w` is NaN
        // then): each a `sin` or an `exp` per sample, and the model the same
        // to the bit (issue 23).
        let model_only_end = !errors && (!modulated || one_block);
        if let Some((jm, th, jrss, ne, _)) = joint {
            m = jm;
            for (r, t) in th.iter().enumerate() {
                phases[r].0 = *t;
            }
            params.extend(joint_params(&m, &ne, jrss, d.len()));
            if !model_only_end {
                tf = factors(&|i| m.time_factor(d.t[i], phases[d.run[i]].0));
            }
        } else {
            // Speed block on μ / (modulations).
            set_mu(&mut work, |i| d.mu[i] / (tf[i] * af[i]));
            let ds = &work;
            if set.stribeck {
                // From the second pass on, Brent's search starts in the basin the
                // first pass's grid found (friction::fit_stribeck_near).
                let f = match (m.stribeck, start_vs) {
                    (Some((_, vs)), _) if pass > 0 => friction::fit_stribeck_near(ds, set.viscous, vs)?,
                    // The first pass's target is μ/(1·1) = μ: the fits of `d` itself.
                    (_, Some(vs)) if pass == 0 => match cold {
                        Some(cold) => cold.near(d, set.viscous, vs)?,
                        None => friction::fit_stribeck_near(ds, set.viscous, vs)?,
                    },
                    _ => match cold.filter(|_| pass == 0) {
                        Some(cold) => cold.get(d, set.viscous)?,
                        None => friction::fit_stribeck(ds, set.viscous)?,
                    },
                };
                let FrictionModel::Stribeck { mu_k, mu_s, vs, c } = f.model else { unreachable!() };
                m.mu_k = mu_k;
                m.stribeck = Some((mu_s, vs));
                m.viscous = set.viscous.then_some(c);
                for (k, v, e) in f.params {
                    let eff = if k == "viscous_per_rad_s" { Term::Viscous } else { Term::Stribeck };
                    params.push((eff, k, v, e));
                }
                if set.viscous {
                    let mk = params.iter().find(|p| p.1 == "mu_kinetic").copied().expect("fitted");
                    params.push((Term::Viscous, "mu_kinetic", mk.2, mk.3));
                }
            } else if set.viscous {
                let f = friction::fit_viscous(ds)?;
                let FrictionModel::Viscous { mu_k, c } = f.model else { unreachable!() };
                m.mu_k = mu_k;
                m.viscous = Some(c);
                for (k, v, e) in f.params {
                    params.push((Term::Viscous, k, v, e));
                }
            } else {
                m.mu_k = friction::fit_coulomb(ds).params[0].1;
            }
            // Time modulation on μ / (speed law · angle factor).
            if set.time_mod {
                set_mu(&mut work, |i| d.mu[i] / (m.speed_mu(d.omega[i]) * af[i]));
                let dt = &work;
                let grid: Vec<f64> = match (pass, m.time_mod, start_f) {
                    (0, _, Some(f)) => vec![f],
                    (0, _, None) | (_, None, _) => freqs_hz.to_vec(),
                    (_, Some((_, f)), _) => vec![f],
                };
                let f = friction::fit_sine(dt, true, &grid, 1..=max_order)?;
                let FrictionModel::TimeSine { mu_k: s, a, f_hz } = f.model else { unreachable!() };
                if pass == 0 {
                    scan = f.scan.clone();
                }
                m.time_mod = Some((a, f_hz));
                m.scale(s);
                for (r, th) in f.phases.iter().enumerate() {
                    phases[r].0 = *th;
                }
                for (k, v, e) in f.params {
                    params.push((Term::TimeSine, k, v, e));
                }
                if !model_only_end {
                    tf = factors(&|i| m.time_factor(d.t[i], phases[d.run[i]].0));
                }
            }
        }
        // Angle modulation on μ / (speed law · time factor).
        if set.angle_mod {
            set_mu(&mut work, |i| d.mu[i] / (m.speed_mu(d.omega[i]) * tf[i]));
            let da = &work;
            // Later passes refine the order the first chose (as the time block keeps its frequency).
            let orders = match (m.angle_mod, start_order) {
                (Some((_, n)), _) if pass > 0 => n..=n,
                (_, Some(n)) if pass == 0 => n..=n,
                _ => 1..=max_order,
            };
            let f = friction::fit_sine_with(da, false, &[], orders, cold.map(|c| &c.angles))?;
            let FrictionModel::AngleSine { mu_k: s, a, order } = f.model else { unreachable!() };
            m.angle_mod = Some((a, order));
            m.scale(s);
            for (r, th) in f.phases.iter().enumerate() {
                phases[r].1 = *th;
            }
            for (k, v, e) in f.params {
                params.push((Term::AngleSine, k, v, e));
            }
            if !model_only_end {
                af = factors(&|i| m.angle_factor(d.phi[i], phases[d.run[i]].1));
            }
        }
        if model_only_end {
            rss = f64::NAN;
            converged = joint_converged.unwrap_or(true);
            break;
        }
        // weighted_rss(d, &m, &phases) with the cached factors (same products, same order).
        let next: f64 = (0..d.len())
            .map(|i| {
                let e = d.mu[i] - m.speed_mu(d.omega[i]) * tf[i] * af[i];
                d.w(i) * e * e
            })
            .sum();
        let done = !modulated || one_block || (pass > 0 && (rss - next).abs() <= 1e-7 * rss.max(f64::MIN_POSITIVE));
        rss = next;
        if done {
            converged = joint_converged.unwrap_or(true);
            break;
        }
    }
    // The speed law's coefficients are reported after the modulations rescaled
    // them (Composite::scale multiplies μk, μs and c alike).
    for p in params.iter_mut() {
        if p.1 == "mu_kinetic" {
            p.2 = m.mu_k;
        }
        if p.1 == "mu_static" {
            p.2 = m.stribeck.map_or(p.2, |s| s.0);
        }
        if p.1 == "viscous_per_rad_s" {
            p.2 = m.viscous.unwrap_or(p.2);
        }
    }
    // Correlated residuals: standard errors × √τ (effective sample size).
    let mut fit = CompositeFit { model: m, phases, params, rss_w: rss, converged, scan };
    if errors {
        inflate_errors(d, &mut fit);
    }
    Some(fit)
}

/// [`fit_composite`] with the standard errors not yet inflated for
/// correlated residuals and, where a pass ends the fit anyway, without the
/// closing RSS (`rss_w` NaN): what the selection's fits on every run
/// compute for the admissibility rules, which read the model alone; the
/// one the report reads then gets [`inflate_errors`] (the same fit to the
/// bit as [`fit_composite`]'s, test `a_deferred_fit_inflated_is_the_full_fit`).
/// The autocorrelation pass and the closing RSS over every slip sample
/// (each a `sin` or `exp` per sample) were made for every admissibility
/// check's set (issue 23).
pub fn fit_composite_deferred(
    d: &SlipData,
    set: FrictionSet,
    freqs_hz: &[f64],
    max_order: u32,
) -> Option<CompositeFit> {
    fit_composite_with(d, set, freqs_hz, max_order, false, None, None)
}

/// Correlated residuals: the standard errors of `fit` (fitted on `d`) × √τ,
/// τ the effective-sample-size factor of its weighted residuals
/// ([`autocorr_inflation`]); the order, an integer, has none.
pub fn inflate_errors(d: &SlipData, fit: &mut CompositeFit) {
    let tau = autocorr_inflation(d, &fit.model, &fit.phases).sqrt();
    for p in fit.params.iter_mut() {
        if p.1 != "order" {
            p.3 *= tau;
        }
    }
}

/// τ = 1 + 2 Σ ρ_k of the weighted residuals within runs (see
/// [`friction::autocorr_inflation`], which this mirrors for the composite).
fn autocorr_inflation(d: &SlipData, m: &Composite, phases: &[Phases]) -> f64 {
    let r: Vec<f64> = (0..d.len())
        .map(|i| {
            let ph = phases.get(d.run[i]).copied().unwrap_or((0.0, 0.0));
            d.w(i).sqrt() * (d.mu[i] - m.mu(d.t[i], d.phi[i], d.omega[i], ph))
        })
        .collect();
    friction::inflation_of(&r, &d.run)
}

#[cfg(test)]
mod tests;
