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
//! The fit alternates blocks — speed law on μ_obs divided by the modulations,
//! each modulation on μ_obs divided by everything else — each block solved by
//! the single-effect fitters of [`crate::friction`] (their tests prove
//! recovery), until the weighted RSS stops falling. The blocks are nearly
//! separable (a modulation is a zero-mean factor), so three to five passes
//! converge. Standard errors are each block's, conditional on the others, and
//! inflated for correlated residuals (effective sample size).

use crate::friction::{self, FrictionModel, SlipData};
use crate::vocab::EffectId;
use std::f64::consts::PI;

/// Which friction effects a model has.
#[derive(Debug, Clone, Copy, PartialEq, Eq, PartialOrd, Ord, Hash, Default)]
pub struct FrictionSet {
    pub time_mod: bool,
    pub angle_mod: bool,
    pub stribeck: bool,
    pub viscous: bool,
}

impl FrictionSet {
    pub fn with(mut self, e: EffectId) -> Self {
        match e {
            EffectId::NormalForceModulation => self.time_mod = true,
            EffectId::AnglePeriodicFriction => self.angle_mod = true,
            EffectId::VelocityWeakeningFriction => self.stribeck = true,
            EffectId::ViscousBrakeFriction => self.viscous = true,
            EffectId::DriveVoltageLimit => {}
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
            m += (mu_s - self.mu_k) * (-(omega / vs).powi(2)).exp();
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
    /// (effect, JSON key, value, standard error).
    pub params: Vec<(EffectId, &'static str, f64, f64)>,
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
    if d.is_empty() {
        return None;
    }
    let base = friction::fit_coulomb(d);
    let mut m = Composite::coulomb(base.params[0].1);
    let mut phases = vec![(0.0, 0.0); d.n_runs];
    let mut params: Vec<(EffectId, &'static str, f64, f64)> = Vec::new();
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
    for pass in 0..passes {
        params.clear();
        // Speed block on μ / (modulations).
        set_mu(&mut work, |i| d.mu[i] / (tf[i] * af[i]));
        let ds = &work;
        if set.stribeck {
            let f = friction::fit_stribeck(ds, set.viscous)?;
            let FrictionModel::Stribeck { mu_k, mu_s, vs, c } = f.model else { unreachable!() };
            m.mu_k = mu_k;
            m.stribeck = Some((mu_s, vs));
            m.viscous = set.viscous.then_some(c);
            for (k, v, e) in f.params {
                let eff = if k == "viscous_per_rad_s" {
                    EffectId::ViscousBrakeFriction
                } else {
                    EffectId::VelocityWeakeningFriction
                };
                params.push((eff, k, v, e));
            }
            if set.viscous {
                let mk = params.iter().find(|p| p.1 == "mu_kinetic").copied().expect("fitted");
                params.push((EffectId::ViscousBrakeFriction, "mu_kinetic", mk.2, mk.3));
            }
        } else if set.viscous {
            let f = friction::fit_viscous(ds)?;
            let FrictionModel::Viscous { mu_k, c } = f.model else { unreachable!() };
            m.mu_k = mu_k;
            m.viscous = Some(c);
            for (k, v, e) in f.params {
                params.push((EffectId::ViscousBrakeFriction, k, v, e));
            }
        } else {
            m.mu_k = friction::fit_coulomb(ds).params[0].1;
        }
        // Time modulation on μ / (speed law · angle factor).
        if set.time_mod {
            set_mu(&mut work, |i| d.mu[i] / (m.speed_mu(d.omega[i]) * af[i]));
            let dt = &work;
            let grid: Vec<f64> = match (pass, m.time_mod) {
                (0, _) | (_, None) => freqs_hz.to_vec(),
                (_, Some((_, f))) => vec![f],
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
                params.push((EffectId::NormalForceModulation, k, v, e));
            }
            tf = factors(&|i| m.time_factor(d.t[i], phases[d.run[i]].0));
        }
        // Angle modulation on μ / (speed law · time factor).
        if set.angle_mod {
            set_mu(&mut work, |i| d.mu[i] / (m.speed_mu(d.omega[i]) * tf[i]));
            let da = &work;
            // Later passes refine the order the first chose (as the time block keeps its frequency).
            let orders = match m.angle_mod {
                Some((_, n)) if pass > 0 => n..=n,
                _ => 1..=max_order,
            };
            let f = friction::fit_sine(da, false, &[], orders)?;
            let FrictionModel::AngleSine { mu_k: s, a, order } = f.model else { unreachable!() };
            m.angle_mod = Some((a, order));
            m.scale(s);
            for (r, th) in f.phases.iter().enumerate() {
                phases[r].1 = *th;
            }
            for (k, v, e) in f.params {
                params.push((EffectId::AnglePeriodicFriction, k, v, e));
            }
            af = factors(&|i| m.angle_factor(d.phi[i], phases[d.run[i]].1));
        }
        // weighted_rss(d, &m, &phases) with the cached factors (same products, same order).
        let next: f64 = (0..d.len())
            .map(|i| {
                let e = d.mu[i] - m.speed_mu(d.omega[i]) * tf[i] * af[i];
                d.w(i) * e * e
            })
            .sum();
        let done = !modulated || (pass > 0 && (rss - next).abs() <= 1e-7 * rss.max(f64::MIN_POSITIVE));
        rss = next;
        if done {
            converged = true;
            break;
        }
    }
    // The speed law's μk is reported after the modulations rescaled it.
    for p in params.iter_mut() {
        if p.1 == "mu_kinetic" {
            p.2 = m.mu_k;
        }
        if p.1 == "mu_static" {
            p.2 = m.stribeck.map_or(p.2, |s| s.0);
        }
    }
    // Correlated residuals: standard errors × √τ (effective sample size).
    let tau = autocorr_inflation(d, &m, &phases).sqrt();
    for p in params.iter_mut() {
        if p.1 != "order" {
            p.3 *= tau;
        }
    }
    Some(CompositeFit { model: m, phases, params, rss_w: rss, converged, scan })
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

/// The nuisance phases of one held-out run with the shared parameters fixed
/// (the vocabulary frees θ per run, nothing else): alternating single-phase
/// fits, each exact for its factor.
pub fn heldout_phases(m: &Composite, d: &SlipData) -> Phases {
    let mut ph = (0.0, 0.0);
    if d.is_empty() || (m.time_mod.is_none() && m.angle_mod.is_none()) {
        return ph;
    }
    for _ in 0..3 {
        if let Some((a, f_hz)) = m.time_mod {
            let dt = with_mu(d, |i| d.mu[i] / (m.speed_mu(d.omega[i]) * m.angle_factor(d.phi[i], ph.1)));
            ph.0 = friction::heldout_phase(&FrictionModel::TimeSine { mu_k: 1.0, a, f_hz }, &dt);
        }
        if let Some((a, order)) = m.angle_mod {
            let da = with_mu(d, |i| d.mu[i] / (m.speed_mu(d.omega[i]) * m.time_factor(d.t[i], ph.0)));
            ph.1 = friction::heldout_phase(&FrictionModel::AngleSine { mu_k: 1.0, a, order }, &da);
        }
        if m.time_mod.is_none() || m.angle_mod.is_none() {
            break;
        }
    }
    ph
}

/// Relative RMS error of μ̂ on one run's slip samples (crate docs: e_μ).
pub fn relative_mu_error(m: &Composite, d: &SlipData, ph: Phases) -> Option<f64> {
    if d.is_empty() {
        return None;
    }
    let mean = d.mu.iter().sum::<f64>() / d.len() as f64;
    let ms =
        (0..d.len()).map(|i| (d.mu[i] - m.mu(d.t[i], d.phi[i], d.omega[i], ph)).powi(2)).sum::<f64>() / d.len() as f64;
    Some(ms.sqrt() / mean.abs().max(1e-9))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn synth(runs: usize, law: impl Fn(usize, f64, f64, f64) -> f64) -> SlipData {
        crate::friction::tests::synth_noisy(runs, 7, 0.003, law)
    }

    #[test]
    fn two_effects_at_once_are_recovered() {
        // Stribeck speed law × normal-force modulation at 1.3 Hz, own phase per run.
        let d = synth(5, |r, t, _, w| {
            (0.4 + 0.2 * (-(w / 2.0f64).powi(2)).exp()) * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 0.9 * r as f64).sin())
        });
        let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
        let set =
            FrictionSet::default().with(EffectId::VelocityWeakeningFriction).with(EffectId::NormalForceModulation);
        let f = fit_composite(&d, set, &freqs, 8).unwrap();
        let m = &f.model;
        let (mu_s, vs) = m.stribeck.unwrap();
        let (a, fr) = m.time_mod.unwrap();
        assert!((m.mu_k - 0.4).abs() < 4e-3 && (mu_s - 0.6).abs() < 1e-2 && (vs - 2.0).abs() < 0.1, "{m:?}");
        assert!((a - 0.12).abs() < 5e-3 && (fr - 1.3).abs() < 2e-3, "{m:?}");
        // Each single effect alone leaves far more.
        let one = fit_composite(&d, FrictionSet::default().with(EffectId::VelocityWeakeningFriction), &freqs, 8);
        assert!(one.unwrap().rss_w > 20.0 * f.rss_w);
        // A held-out run's phase is recovered from its own data with the shared parameters fixed.
        let held = synth(1, |_, t, _, w| {
            (0.4 + 0.2 * (-(w / 2.0f64).powi(2)).exp()) * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 2.5).sin())
        });
        let ph = heldout_phases(m, &held);
        let e = (ph.0 - 2.5).rem_euclid(2.0 * PI);
        assert!(e.min(2.0 * PI - e) < 0.05, "phase {}", ph.0);
    }

    #[test]
    fn the_empty_set_is_coulomb() {
        let d = synth(2, |_, _, _, _| 0.5);
        let f = fit_composite(&d, FrictionSet::default(), &[], 8).unwrap();
        assert!((f.model.mu_k - 0.5).abs() < 1e-3 && f.params.is_empty());
    }
}
