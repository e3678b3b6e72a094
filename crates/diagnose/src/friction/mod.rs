//! Teacher-forced friction candidates: during slip the force sensor gives the
//! friction coefficient μ_obs = sign(Ω1)·F/N0 directly (Eq. 4-10: T1 = μ·N·r,
//! so F = T1/r = μ·N), and each vocabulary law is a regression of μ_obs on the
//! MEASURED time, rotor angle and rotor speed. Shared parameters across runs,
//! one phase per run where the vocabulary frees it (diagnosis.md table).
//!
//! The module's files: this one the data ([`SlipData`]), the laws
//! ([`FrictionModel`], [`FrictionFit`]) and the linear fits (Coulomb,
//! viscous); `stribeck.rs` the Stribeck fits; `scan.rs` the sine models'
//! frequency and order scans and the sin/cos schedule; `sine.rs` the sine
//! models' Gauss–Newton fit; `line_search.rs` its stop rule and line-search
//! start (shared with the composite); `heldout.rs` the held-out phase, the
//! residual inflation and the relative error.

mod heldout;
mod line_search;
mod scan;
mod sine;
mod stribeck;

pub use heldout::{autocorr_inflation, heldout_phase, inflation_of, relative_mu_error, relative_rms};
pub(crate) use line_search::{LineStart, crawling, near_stationary};
pub(crate) use scan::{AngleTrig, SinCosSchedule, time_scan};
pub use sine::fit_sine;
pub(crate) use sine::fit_sine_with;
pub use stribeck::{fit_stribeck, fit_stribeck_near};

use crate::prepare::RunSignals;
use rig_estimate::linear::Normal;
use std::f64::consts::PI;
use std::sync::Arc;

/// A friction law in slip, with its shared parameters.
#[derive(Debug, Clone, PartialEq)]
pub enum FrictionModel {
    /// Baseline: μ = μk in slip (Eq. 4-10 with a single kinetic coefficient).
    Coulomb { mu_k: f64 },
    /// μ = μk + c|Ω| (vocabulary `viscous_brake_friction`).
    Viscous { mu_k: f64, c: f64 },
    /// μ = μk + (μs − μk) exp(−(Ω/vs)²) + c|Ω| (vocabulary
    /// `velocity_weakening_friction`; c ≠ 0 only when `viscous_brake_friction`
    /// is in the model too).
    Stribeck { mu_k: f64, mu_s: f64, vs: f64, c: f64 },
    /// μ = μk (1 + a sin(2π f t + θ_r)) (vocabulary `normal_force_modulation`).
    TimeSine { mu_k: f64, a: f64, f_hz: f64 },
    /// μ = μk (1 + a sin(n φ1 + θ_r)) (vocabulary `angle_periodic_friction`).
    AngleSine { mu_k: f64, a: f64, order: u32 },
}

/// Slip samples of a set of runs, flattened, with per-run weights.
///
/// The regressors (run, t, φ1, |Ω1|) are shared ([`Arc`]) and the target μ
/// owned: the composite's blocks and the held-out phases refit the same
/// samples against a new target (`composite::fit_composite_with`'s `work`,
/// `composite::heldout_phases`), and a copy of the data copies one column, not five (the five columns' copy and
/// its page faults were ≈ 3 % of a ladder rung's CPU in `perf`, issue 23).
#[derive(Debug, Clone, Default)]
pub struct SlipData {
    pub run: Arc<Vec<usize>>,
    pub t: Arc<Vec<f64>>,
    pub phi: Arc<Vec<f64>>,
    pub omega: Arc<Vec<f64>>,
    pub mu: Vec<f64>,
    /// Weight of each run: (N0/σ_F)², so weighted residuals are in noise units.
    pub run_weight: Vec<f64>,
    pub n_runs: usize,
}

impl SlipData {
    pub fn from_runs(runs: &[&RunSignals]) -> Self {
        Self::from_runs_spaced(runs, 0.0)
    }

    /// The slip samples of `runs` on a grid `spacing_s` apart: of each run,
    /// the slip samples whose index in the record is a multiple of
    /// `spacing_s` counted in samples ([`rig_types::sensor::window_samples`]
    /// of the run's time column); 0 keeps every sample ([`SlipData::from_runs`]).
    /// The kept samples stay on a uniform time grid, so the frequency scan's
    /// FFT still applies. What a cross-validation fold fits its model on
    /// (`fold_fit_spacing_s`, [`crate::DiagnoseOptions`]: the residuals are
    /// correlated over more than the spacing, so the thinned fit keeps
    /// almost all of the information).
    pub fn from_runs_spaced(runs: &[&RunSignals], spacing_s: f64) -> Self {
        let mut d = SlipData { n_runs: runs.len(), ..Default::default() };
        let (mut run, mut t, mut phi, mut omega) = (Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for (r, s) in runs.iter().enumerate() {
            let sd = (s.force_noise_n / s.normal_force_n.max(1e-9)).max(1e-6);
            d.run_weight.push(1.0 / (sd * sd));
            let every =
                if spacing_s > 0.0 { rig_types::sensor::window_samples(&s.time_s, spacing_s).max(1) } else { 1 };
            for (j, &k) in s.slip_idx.iter().enumerate() {
                if k % every != 0 {
                    continue;
                }
                run.push(r);
                t.push(s.time_s[k]);
                phi.push(s.rotor_angle_rad[k]);
                omega.push(s.rotor_speed_rad_s[k].abs());
                d.mu.push(s.mu_obs[j]);
            }
        }
        (d.run, d.t, d.phi, d.omega) = (Arc::new(run), Arc::new(t), Arc::new(phi), Arc::new(omega));
        d
    }
    pub fn len(&self) -> usize {
        self.mu.len()
    }
    pub fn is_empty(&self) -> bool {
        self.mu.is_empty()
    }
    pub(crate) fn w(&self, i: usize) -> f64 {
        self.run_weight[self.run[i]]
    }

    /// Every `k`-th sample (runs and weights kept), for the searches over a
    /// nonlinear parameter (modulation frequency, Stribeck speed). At 500 Hz
    /// and k = 4 the subsample is still 125 Hz, far above the 10 Hz the scans
    /// reach; the search only locates the optimum, and the fit at it is then
    /// made on every sample.
    pub(crate) fn subsample(&self, k: usize) -> SlipData {
        let keep: Vec<usize> = (0..self.len()).step_by(k.max(1)).collect();
        SlipData {
            run: Arc::new(keep.iter().map(|&i| self.run[i]).collect()),
            t: Arc::new(keep.iter().map(|&i| self.t[i]).collect()),
            phi: Arc::new(keep.iter().map(|&i| self.phi[i]).collect()),
            omega: Arc::new(keep.iter().map(|&i| self.omega[i]).collect()),
            mu: keep.iter().map(|&i| self.mu[i]).collect(),
            run_weight: self.run_weight.clone(),
            n_runs: self.n_runs,
        }
    }
}

/// Subsampling factor of the searches ([`SlipData::subsample`]).
const SEARCH_EVERY: usize = 4;

/// A fitted friction candidate on the training runs.
#[derive(Debug, Clone)]
pub struct FrictionFit {
    pub model: FrictionModel,
    /// Per training run phase θ_r (sine models only).
    pub phases: Vec<f64>,
    /// (JSON key, value, standard error), in the vocabulary's order.
    pub params: Vec<(&'static str, f64, f64)>,
    /// Weighted residual sum of squares (noise units) and sample count.
    pub rss_w: f64,
    pub n: usize,
    /// Free parameters counted by the information criterion (shared + per-run).
    pub k: usize,
    pub converged: bool,
    /// Scan of the sine models: (frequency Hz or order, weighted RSS of the linear per-run fit).
    pub scan: Vec<(f64, f64)>,
}

impl FrictionModel {
    /// μ̂ at one sample with the run's phase θ (ignored by speed laws).
    pub fn mu(&self, t: f64, phi: f64, omega: f64, theta: f64) -> f64 {
        match *self {
            FrictionModel::Coulomb { mu_k } => mu_k,
            FrictionModel::Viscous { mu_k, c } => mu_k + c * omega,
            FrictionModel::Stribeck { mu_k, mu_s, vs, c } => {
                rig_model::friction::stribeck_mu(mu_s, mu_k, vs, omega) + c * omega
            }
            FrictionModel::TimeSine { mu_k, a, f_hz } => mu_k * (1.0 + a * (2.0 * PI * f_hz * t + theta).sin()),
            FrictionModel::AngleSine { mu_k, a, order } => mu_k * (1.0 + a * (order as f64 * phi + theta).sin()),
        }
    }
}

fn weighted_rss(d: &SlipData, m: &FrictionModel, phases: &[f64]) -> f64 {
    (0..d.len())
        .map(|i| {
            let th = phases.get(d.run[i]).copied().unwrap_or(0.0);
            let e = d.mu[i] - m.mu(d.t[i], d.phi[i], d.omega[i], th);
            d.w(i) * e * e
        })
        .sum()
}

/// Baseline: weighted mean coefficient.
pub fn fit_coulomb(d: &SlipData) -> FrictionFit {
    let (mut sw, mut swy) = (0.0, 0.0);
    for i in 0..d.len() {
        sw += d.w(i);
        swy += d.w(i) * d.mu[i];
    }
    let mu_k = swy / sw.max(f64::MIN_POSITIVE);
    let m = FrictionModel::Coulomb { mu_k };
    let rss = weighted_rss(d, &m, &[]);
    let var = rss / (d.len().max(2) - 1) as f64;
    FrictionFit {
        params: vec![("mu_kinetic", mu_k, (var / sw).sqrt())],
        model: m,
        phases: vec![],
        rss_w: rss,
        n: d.len(),
        k: 1,
        converged: sw > 0.0,
        scan: vec![],
    }
}

/// Linear least squares of μ on fixed columns; returns (solution, covariance, rss).
fn linear_fit(
    d: &SlipData,
    ncol: usize,
    /* ≤ 4 */ cols: impl Fn(usize, &mut [f64]),
) -> Option<(Vec<f64>, Vec<f64>, f64)> {
    let (p, rss, ne) = linear_solve(d, ncol, cols)?;
    let var = rss / (d.len().saturating_sub(ncol).max(1)) as f64;
    let cov = ne.inverse()?.into_iter().map(|x| x * var).collect();
    Some((p, cov, rss))
}

/// The solution and weighted RSS of [`linear_fit`] without the covariance
/// (the searches only need the RSS). Each sample's columns are evaluated once.
fn linear_solve(d: &SlipData, ncol: usize, cols: impl Fn(usize, &mut [f64])) -> Option<(Vec<f64>, f64, Normal)> {
    let mut ne = Normal::new(ncol);
    let mut rows = vec![[0.0f64; 4]; d.len()];
    for (i, row) in rows.iter_mut().enumerate() {
        cols(i, &mut row[..ncol]);
        let sw = d.w(i).sqrt();
        let mut sparse = [(0usize, 0.0f64); 4];
        for (j, &v) in row[..ncol].iter().enumerate() {
            sparse[j] = (j, v * sw);
        }
        ne.add_sparse(&sparse[..ncol], d.mu[i] * sw);
    }
    let p = ne.solve()?;
    let mut rss = 0.0;
    for (i, row) in rows.iter().enumerate() {
        let e = d.mu[i] - row[..ncol].iter().zip(&p).map(|(a, b)| a * b).sum::<f64>();
        rss += d.w(i) * e * e;
    }
    Some((p, rss, ne))
}

/// μ = μk + c|Ω|: linear.
pub fn fit_viscous(d: &SlipData) -> Option<FrictionFit> {
    let (p, cov, rss) = linear_fit(d, 2, |i, r| {
        r[0] = 1.0;
        r[1] = d.omega[i];
    })?;
    Some(FrictionFit {
        model: FrictionModel::Viscous { mu_k: p[0], c: p[1] },
        phases: vec![],
        params: vec![("mu_kinetic", p[0], cov[0].sqrt()), ("viscous_per_rad_s", p[1], cov[3].sqrt())],
        rss_w: rss,
        n: d.len(),
        k: 2,
        converged: true,
        scan: vec![],
    })
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;

    /// Deterministic Gaussian-ish noise (sum of 12 LCG uniforms).
    pub(crate) fn noise(seed: &mut u64) -> f64 {
        let mut acc = 0.0;
        for _ in 0..12 {
            *seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
            acc += (*seed >> 11) as f64 / (1u64 << 53) as f64;
        }
        acc - 6.0
    }

    /// Slip data of `runs` runs: a saw-tooth slip speed 0..15 rad/s (period 2 s),
    /// angle its integral, and μ from `law` plus noise of σ = 0.005.
    pub(crate) fn synth(runs: usize, law: impl Fn(usize, f64, f64, f64) -> f64) -> SlipData {
        synth_noisy(runs, 99, 0.005, law)
    }

    /// As [`synth`], with the noise seed and σ given (shared with composite's tests).
    pub(crate) fn synth_noisy(
        runs: usize,
        mut seed: u64,
        sigma: f64,
        law: impl Fn(usize, f64, f64, f64) -> f64,
    ) -> SlipData {
        let mut d = SlipData { n_runs: runs, ..Default::default() };
        for r in 0..runs {
            d.run_weight.push(1.0);
            let mut phi = 0.0;
            for k in 0..10000 {
                let t = k as f64 * 0.002;
                let w = 0.6 + 14.4 * ((t + 0.37 * r as f64) % 2.0) / 2.0;
                phi += w * 0.002;
                Arc::make_mut(&mut d.run).push(r);
                Arc::make_mut(&mut d.t).push(t);
                Arc::make_mut(&mut d.phi).push(phi);
                Arc::make_mut(&mut d.omega).push(w);
                d.mu.push(law(r, t, phi, w) + sigma * noise(&mut seed));
            }
        }
        d
    }

    #[test]
    fn viscous_law_is_recovered() {
        let d = synth(3, |_, _, _, w| 0.5 + 0.01 * w);
        let f = fit_viscous(&d).unwrap();
        let FrictionModel::Viscous { mu_k, c } = f.model else { panic!() };
        assert!((mu_k - 0.5).abs() < 1e-3 && (c - 0.01).abs() < 2e-4, "{:?}", f.model);
    }
}
