//! A held-out run under a fixed composite: its own phases of the modulations
//! (a phase is per run, so a held-out run's is fitted on that run alone,
//! [`heldout_phases`]) and its relative error e_μ (crate docs;
//! [`heldout_fit`], [`relative_mu_error`]), from per-sample values computed
//! once per run (`HeldOut`).

use super::{Composite, Phases};
use crate::friction::{self, AngleTrig, SlipData};
use std::f64::consts::PI;
use std::sync::{Arc, OnceLock};

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
        Self::with_times(m, d, angles, None)
    }

    /// [`HeldOut::of`] reading sin and cos of 2πf·t from `times`, the
    /// fold's [`TimeGrid`] table at the model's f and this run's slots.
    fn with_times(m: &Composite, d: &SlipData, angles: Option<&AngleTrig>, times: Option<GridTrig>) -> Self {
        let time_trig = |f: f64, t: &f64| (2.0 * PI * f * t).sin_cos();
        HeldOut {
            speed: d.omega.iter().map(|&w| m.speed_mu(w)).collect(),
            time: match (m.time_mod, times) {
                (None, _) => Vec::new(),
                (Some((_, f)), None) => d.t.iter().map(|t| time_trig(f, t)).collect(),
                (Some((_, f)), Some((table, slots))) => slots
                    .iter()
                    .zip(d.t.iter())
                    .map(|(&k, t)| if k == OWN { time_trig(f, t) } else { table[k as usize] })
                    .collect(),
            },
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
    fit_on(m, d, &HeldOut::of(m, d, None))
}

/// [`heldout_fit`] reading the angle modulation's sin and cos from `angles`,
/// the run's memo (the same numbers, so the same phases and error; what
/// [`heldout_fits`] does for each run of a fold).
#[cfg(test)]
fn heldout_fit_with(m: &Composite, d: &SlipData, angles: Option<&AngleTrig>) -> (Option<f64>, Phases) {
    fit_on(m, d, &HeldOut::of(m, d, angles))
}

/// The phases and error of [`heldout_fit`] from the run's [`HeldOut`] values.
fn fit_on(m: &Composite, d: &SlipData, h: &HeldOut) -> (Option<f64>, Phases) {
    let ph = phases_on(m, d, h);
    let (tf, af) = h.both(m, ph);
    (friction::relative_rms(&d.mu, |i| h.speed[i] * tf[i] * af[i]), ph)
}

/// A run's view of its fold's [`TimeGrid`] at one f: the table of sin and
/// cos of 2πf·t by slot, and each of the run's samples' slot.
type GridTrig<'a> = (&'a [(f64, f64)], &'a [u32]);

/// A sample of [`TimeGrid`] that takes its own `sin_cos` (off the grid, or
/// another run's time at its slot has other bits).
const OWN: u32 = u32::MAX;

/// Where the held-out runs of one fold sample time: the slots of their
/// common grid t0 + k·dt (dt the smallest step within a run) that some
/// sample falls on, each slot holding the time (its bits) of the first run
/// that has it, and per run each sample's slot. The runs are recorded on
/// one clock, so the runs a fold holds out pass through the same times, and
/// the time modulation's sin and cos of 2πf·t at a slot serve every run
/// that has that time: a table per model over the slots, read in each
/// run's sample order. On the battery's campaigns a fold's ≈ 116 000
/// held-out slip samples sit on ≈ 20 000 slots, and each friction set with
/// the time modulation took a `sin_cos` of every sample (1.1 % of the full
/// battery's CPU in `perf`, issue 23). A sample is read from a slot only
/// when its time has the slot's bits, so its value is the same product
/// 2π·f·t and the same `sin_cos`: the same phases and errors to the bit.
#[derive(Debug)]
struct TimeGrid {
    /// Per slot, the bits of its time (`u64::MAX`: no sample falls on it).
    slots: Vec<u64>,
    /// Per held-out run, each sample's slot ([`OWN`]: its own `sin_cos`).
    at: Vec<Vec<u32>>,
}

impl TimeGrid {
    /// The grid of `runs` (their t in sample order); `None` when they have
    /// no step, or the grid would be longer than 2²⁶ slots.
    fn of(runs: &[&SlipData]) -> Option<Self> {
        let ts = || runs.iter().flat_map(|d| d.t.iter().copied());
        let t0 = ts().fold(f64::INFINITY, f64::min);
        let dt = runs
            .iter()
            .flat_map(|d| (1..d.len()).filter(|&i| d.run[i] == d.run[i - 1]).map(|i| d.t[i] - d.t[i - 1]))
            .filter(|s| *s > 0.0)
            .fold(f64::INFINITY, f64::min);
        let span = (ts().fold(f64::NEG_INFINITY, f64::max) - t0) / dt;
        if !(t0.is_finite() && dt.is_finite() && span.is_finite() && span < (1u64 << 26) as f64) {
            return None;
        }
        let mut slots = vec![u64::MAX; span.round() as usize + 1];
        let at = runs
            .iter()
            .map(|d| {
                d.t.iter()
                    .map(|t| {
                        let x = (t - t0) / dt;
                        let k = x.round();
                        if (x - k).abs() > 1e-6 || !(0.0..slots.len() as f64).contains(&k) {
                            return OWN;
                        }
                        let slot = &mut slots[k as usize];
                        if *slot == u64::MAX {
                            *slot = t.to_bits();
                        }
                        if *slot == t.to_bits() { k as u32 } else { OWN }
                    })
                    .collect()
            })
            .collect();
        Some(TimeGrid { slots, at })
    }

    /// sin and cos of 2πf·t at every occupied slot (the same expression as
    /// [`HeldOut::with_times`]'s own; an empty slot is never read).
    fn table(&self, f: f64) -> Vec<(f64, f64)> {
        self.slots
            .iter()
            .map(|&b| if b == u64::MAX { (0.0, 0.0) } else { (2.0 * PI * f * f64::from_bits(b)).sin_cos() })
            .collect()
    }
}

/// The runs one cross-validation fold holds out, as every friction set's
/// model predicts them ([`heldout_fits`]): each run's angle memo
/// ([`friction::AngleTrig`]) and the fold's [`TimeGrid`], built the first
/// time a model with the time modulation is held out.
#[derive(Debug, Default)]
pub(crate) struct HeldRuns {
    angles: Vec<AngleTrig>,
    times: OnceLock<Option<TimeGrid>>,
}

impl HeldRuns {
    /// The memos of `n` held-out runs.
    pub(crate) fn new(n: usize) -> Self {
        HeldRuns { angles: (0..n).map(|_| AngleTrig::default()).collect(), times: OnceLock::new() }
    }
}

/// [`heldout_fit_with`] of every run of `held` (one fold's held-out runs,
/// in `memo`'s order) under `m`, in order: the time modulation's sin and
/// cos from one table of the fold's time grid at the model's f ([`TimeGrid`]),
/// the angle modulation's from each run's memo; the same phases and errors
/// to the bit as each run fitted alone.
pub(crate) fn heldout_fits(m: &Composite, held: &[&SlipData], memo: &HeldRuns) -> Vec<(Option<f64>, Phases)> {
    let grid = m.time_mod.and_then(|_| memo.times.get_or_init(|| TimeGrid::of(held)).as_ref());
    let table = grid.zip(m.time_mod).map(|(g, (_, f))| g.table(f));
    held.iter()
        .enumerate()
        .map(|(r, d)| {
            let times = grid.zip(table.as_deref()).map(|(g, tab)| (tab, g.at[r].as_slice()));
            fit_on(m, d, &HeldOut::with_times(m, d, memo.angles.get(r), times))
        })
        .collect()
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
    /// A Stribeck law with both modulations, near the synthetic law the tests draw from.
    fn modulated_model() -> Composite {
        Composite {
            mu_k: 0.41,
            stribeck: Some((0.59, 2.1)),
            viscous: None,
            time_mod: Some((0.11, 1.3004)),
            angle_mod: Some((0.07, 3)),
        }
    }

    #[test]
    fn the_heldout_fit_from_values_computed_once_is_the_per_sample_one() {
        let law = |_: usize, t: f64, phi: f64, w: f64| {
            (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64))
                * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 2.5).sin())
                * (1.0 + 0.08 * (3.0 * phi + 1.1).sin())
        };
        let held = synth(1, law);
        let m = modulated_model();
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

    /// A fold's held-out runs read from one table of their time grid get
    /// each run's own phases and error to the bit: runs on one clock, one
    /// whose times are a hair off the grid, one whose times at the grid's
    /// slots have other bits than the first run's, an empty run; and the
    /// grid shares slots between runs.
    #[test]
    fn held_out_runs_read_from_the_folds_time_grid_are_each_run_alone() {
        let law = |r: usize, t: f64, phi: f64, w: f64| {
            (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64))
                * (1.0 + 0.12 * (2.0 * PI * 1.3 * t + 2.5 + r as f64).sin())
                * (1.0 + 0.08 * (3.0 * phi + 1.1).sin())
        };
        let all = synth(5, law);
        let mut held: Vec<SlipData> = (0..5)
            .map(|r| {
                let keep: Vec<usize> =
                    (0..all.len()).filter(|&i| all.run[i] == r && (all.t[i] * 7.0 + r as f64) % 3.0 < 2.0).collect();
                SlipData {
                    run: Arc::new(vec![0; keep.len()]),
                    t: Arc::new(keep.iter().map(|&i| all.t[i]).collect()),
                    phi: Arc::new(keep.iter().map(|&i| all.phi[i]).collect()),
                    omega: Arc::new(keep.iter().map(|&i| all.omega[i]).collect()),
                    mu: keep.iter().map(|&i| all.mu[i]).collect(),
                    run_weight: vec![all.run_weight[r]],
                    n_runs: 1,
                }
            })
            .collect();
        // Run 2 a hair off the grid, run 3's times through another rounding, run 4 empty.
        Arc::make_mut(&mut held[2].t).iter_mut().for_each(|t| *t += 1e-5);
        Arc::make_mut(&mut held[3].t).iter_mut().for_each(|t| *t = f64::from_bits(t.to_bits() + 1));
        held[4] = SlipData { run_weight: vec![1.0], n_runs: 1, ..Default::default() };
        let refs: Vec<&SlipData> = held.iter().collect();
        let grid = TimeGrid::of(&refs).expect("a grid");
        let on_grid = grid.at[1].iter().filter(|&&k| k != OWN).count();
        assert!(on_grid > 0 && grid.at[2].iter().all(|&k| k == OWN), "run 2 is off the grid");
        assert!(grid.at[3].contains(&OWN), "run 3's times have other bits than run 0's");
        let occupied = grid.slots.iter().filter(|&&b| b != u64::MAX).count();
        let samples: usize = held.iter().map(SlipData::len).sum();
        assert!(occupied < samples / 2, "the runs share slots: {occupied} of {samples}");
        let m = modulated_model();
        let bits = |(e, ph): (Option<f64>, Phases)| (e.map(f64::to_bits), ph.0.to_bits(), ph.1.to_bits());
        let memo = HeldRuns::new(held.len());
        for model in
            [&m, &Composite { time_mod: Some((0.05, 0.77)), ..m.clone() }, &Composite { time_mod: None, ..m.clone() }]
        {
            let shared: Vec<_> = heldout_fits(model, &refs, &memo).into_iter().map(bits).collect();
            let own: Vec<_> = held.iter().map(|d| bits(heldout_fit(model, d))).collect();
            assert_eq!(shared, own);
        }
    }
}
