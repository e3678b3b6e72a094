//! A held-out run under a fixed composite: its own phases of the modulations
//! (a phase is per run, so a held-out run's is fitted on that run alone,
//! [`heldout_phases`]) and its relative error e_μ (crate docs;
//! [`heldout_fit`], [`relative_mu_error`]), from per-sample values computed
//! once per run (`HeldOut`).

use super::{Composite, Phases};
use crate::friction::{self, AngleTrig, SlipData};
use std::f64::consts::PI;
use std::sync::Arc;

/// A held-out run's samples as its phase fits and its error read them under
/// a fixed composite: per sample the speed law μ_speed(Ω) and the sin and cos
/// of each modulation's argument without its phase (2πf·t, n·φ1). None of
/// them depends on the run's phases, so each is computed once per run and a
/// factor at phase θ is 1 + a(sin x cos θ + cos x sin θ) (angle addition),
/// one sin_cos per run and factor: the alternation of [`heldout_phases`]
/// took a `sin` per sample for each factor in each of its three rounds, and
/// a `sin_cos` per sample in each phase fit, and [`relative_mu_error`] a
/// `sin` per factor and an `exp` of the Stribeck term per sample again
/// (with the error, 9.6 % of a ladder rung's CPU in `perf`, issue 23). The
/// factors differ from `Composite::time_factor` / `angle_factor` by the
/// rounding of the angle addition (≈ 10⁻¹⁶).
/// The angle part does not depend on the model beyond its order, so a run
/// held out under several models reads it from the run's memo when given
/// one ([`friction::AngleTrig`]: the same numbers).
struct HeldOut {
    speed: Vec<f64>,
    time: Vec<(f64, f64)>,
    angle: Arc<Vec<(f64, f64)>>,
}

impl HeldOut {
    fn of(m: &Composite, d: &SlipData, angles: Option<&AngleTrig>) -> Self {
        HeldOut {
            speed: d.omega.iter().map(|&w| m.speed_mu(w)).collect(),
            time: m.time_mod.map_or(Vec::new(), |(_, f)| d.t.iter().map(|t| (2.0 * PI * f * t).sin_cos()).collect()),
            angle: match (m.angle_mod, angles) {
                (None, _) => Arc::default(),
                (Some((_, n)), Some(memo)) => memo.get(d, n),
                (Some((_, n)), None) => Arc::new(d.phi.iter().map(|p| (n as f64 * p).sin_cos()).collect()),
            },
        }
    }

    /// The factor 1 + a sin(x + θ) of every sample (1 without the modulation).
    fn factors(trig: &[(f64, f64)], modulation: Option<f64>, th: f64, n: usize) -> Vec<f64> {
        match modulation {
            Some(a) => {
                let (st, ct) = th.sin_cos();
                trig.iter().map(|&(sx, cx)| 1.0 + a * (sx * ct + cx * st)).collect()
            }
            None => vec![1.0; n],
        }
    }

    /// Both factors of every sample at phases `ph`.
    fn both(&self, m: &Composite, ph: Phases) -> (Vec<f64>, Vec<f64>) {
        let n = self.speed.len();
        (
            Self::factors(&self.time, m.time_mod.map(|t| t.0), ph.0, n),
            Self::factors(&self.angle, m.angle_mod.map(|t| t.0), ph.1, n),
        )
    }
}

/// The nuisance phases of one held-out run with the shared parameters fixed
/// (the vocabulary frees θ per run, nothing else): alternating single-phase
/// fits, each exact for its factor.
pub fn heldout_phases(m: &Composite, d: &SlipData) -> Phases {
    phases_on(m, d, &HeldOut::of(m, d, None))
}

/// [`heldout_phases`] on the run's [`HeldOut`] values.
fn phases_on(m: &Composite, d: &SlipData, h: &HeldOut) -> Phases {
    let mut ph = (0.0, 0.0);
    if d.is_empty() || (m.time_mod.is_none() && m.angle_mod.is_none()) {
        return ph;
    }
    let n = d.len();
    let mut target = vec![0.0; n];
    for _ in 0..3 {
        if let Some((a, _)) = m.time_mod {
            let af = HeldOut::factors(&h.angle, m.angle_mod.map(|t| t.0), ph.1, n);
            for (i, y) in target.iter_mut().enumerate() {
                *y = d.mu[i] / (h.speed[i] * af[i]);
            }
            ph.0 = friction::heldout_phase(&target, &h.time, a);
        }
        if let Some((a, _)) = m.angle_mod {
            let tf = HeldOut::factors(&h.time, m.time_mod.map(|t| t.0), ph.0, n);
            for (i, y) in target.iter_mut().enumerate() {
                *y = d.mu[i] / (h.speed[i] * tf[i]);
            }
            ph.1 = friction::heldout_phase(&target, &h.angle, a);
        }
        if m.time_mod.is_none() || m.angle_mod.is_none() {
            break;
        }
    }
    ph
}

/// A held-out run's phases under `m` ([`heldout_phases`]) and its relative
/// μ error at them ([`relative_mu_error`]), from one [`HeldOut`]: what a
/// cross-validation fold computes for each run it holds out.
pub fn heldout_fit(m: &Composite, d: &SlipData) -> (Option<f64>, Phases) {
    heldout_fit_with(m, d, None)
}

/// [`heldout_fit`] reading the angle modulation's sin and cos from `angles`,
/// the run's memo (the same numbers, so the same phases and error).
pub(crate) fn heldout_fit_with(m: &Composite, d: &SlipData, angles: Option<&AngleTrig>) -> (Option<f64>, Phases) {
    let h = HeldOut::of(m, d, angles);
    let ph = phases_on(m, d, &h);
    let (tf, af) = h.both(m, ph);
    (friction::relative_rms(&d.mu, |i| h.speed[i] * tf[i] * af[i]), ph)
}

/// Relative RMS error of μ̂ on one run's slip samples (crate docs: e_μ).
pub fn relative_mu_error(m: &Composite, d: &SlipData, ph: Phases) -> Option<f64> {
    friction::relative_rms(&d.mu, |i| m.mu(d.t[i], d.phi[i], d.omega[i], ph))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::composite::set_mu;
    use crate::composite::tests::synth;

    /// A fold's held-out fit from the run's values computed once (angle
    /// addition) is the per-sample one — the alternation of single-phase
    /// fits on `Composite::time_factor` / `angle_factor` and the error on
    /// `Composite::mu` — up to rounding, on a run with both modulations and
    /// the Stribeck term (the three rounds of the alternation all run).
    #[test]
    fn the_heldout_fit_from_values_computed_once_is_the_per_sample_one() {
        let law = |_: usize, t: f64, phi: f64, w: f64| {
            (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64))
                * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 2.5).sin())
                * (1.0 + 0.08 * (3.0 * phi + 1.1).sin())
        };
        let held = synth(1, law);
        let m = Composite {
            mu_k: 0.41,
            stribeck: Some((0.59, 2.1)),
            viscous: None,
            time_mod: Some((0.11, 1.3004)),
            angle_mod: Some((0.07, 3)),
        };
        // The reference: the same alternation, every factor by `sin` of its whole argument.
        let mut reference = (0.0, 0.0);
        let mut target = held.clone();
        let trig = |x: &dyn Fn(usize) -> f64| -> Vec<(f64, f64)> { (0..held.len()).map(|i| x(i).sin_cos()).collect() };
        let time_trig = trig(&|i| 2.0 * PI * 1.3004 * held.t[i]);
        let angle_trig = trig(&|i| 3.0 * held.phi[i]);
        for _ in 0..3 {
            set_mu(&mut target, |i| {
                held.mu[i] / (m.speed_mu(held.omega[i]) * m.angle_factor(held.phi[i], reference.1))
            });
            reference.0 = friction::heldout_phase(&target.mu, &time_trig, 0.11);
            set_mu(&mut target, |i| held.mu[i] / (m.speed_mu(held.omega[i]) * m.time_factor(held.t[i], reference.0)));
            reference.1 = friction::heldout_phase(&target.mu, &angle_trig, 0.07);
        }
        let e_reference = relative_mu_error(&m, &held, reference).unwrap();
        let (e, ph) = heldout_fit(&m, &held);
        let close = |a: f64, b: f64| (a - b).abs() <= 1e-12 * b.abs().max(1.0);
        assert!(close(ph.0, reference.0) && close(ph.1, reference.1), "{ph:?} vs {reference:?}");
        assert!(close(e.unwrap(), e_reference), "{e:?} vs {e_reference}");
        assert_eq!(heldout_phases(&m, &held), ph);
        // The phases are the run's own (2.5 and 1.1) and the error is the noise's.
        let off = |x: f64, y: f64| {
            let d = (x - y).rem_euclid(2.0 * PI);
            d.min(2.0 * PI - d)
        };
        assert!(off(ph.0, 2.5) < 0.05 && off(ph.1, 1.1) < 0.1, "{ph:?}");
        assert!(e.unwrap() < 0.05, "{e:?}");
        // Read from the run's memo (filled by the first model, read by a
        // second of the same order): each the fit computed alone, to the bit.
        let memo = AngleTrig::default();
        let other = Composite { time_mod: None, angle_mod: Some((0.05, 3)), ..m.clone() };
        let bits = |(e, ph): (Option<f64>, Phases)| (e.map(f64::to_bits), ph.0.to_bits(), ph.1.to_bits());
        for model in [&m, &other, &m] {
            assert_eq!(bits(heldout_fit_with(model, &held, Some(&memo))), bits(heldout_fit(model, &held)));
        }
        assert_eq!(memo.get(&held, 3).as_slice(), angle_trig.as_slice(), "the memo's values are sin_cos(3·φ)");
    }
}
