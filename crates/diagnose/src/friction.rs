//! Teacher-forced friction candidates: during slip the force sensor gives the
//! friction coefficient μ_obs = sign(Ω1)·F/N0 directly (Eq. 4-10: T1 = μ·N·r,
//! so F = T1/r = μ·N), and each vocabulary law is a regression of μ_obs on the
//! MEASURED time, rotor angle and rotor speed. Shared parameters across runs,
//! one phase per run where the vocabulary frees it (diagnosis.md table).

use crate::prepare::RunSignals;
use rig_estimate::linear::{ArrowNormal, Normal};
use rig_types::minimize::brent_min;
use std::f64::consts::PI;
use std::ops::RangeInclusive;
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

/// The weighted RSS of the Stribeck regression μ = μk + Δ g(Ω; vs) [+ c Ω]
/// at a given vs, as [`linear_solve`] computes it (the same products summed
/// in the same order, so the same bits), without its per-call row storage
/// and general sparse accumulation: the sums that do not involve g (Σw,
/// ΣwΩ, ΣwΩ², Σwμ, ΣwΩμ) are made once, and each vs costs one exp and a
/// few products per sample. The Stribeck speed search evaluates it ~70
/// times per fit.
struct StribeckRss<'a> {
    d: &'a SlipData,
    viscous: bool,
    /// √w and μ√w per sample.
    sw: Vec<f64>,
    y: Vec<f64>,
    /// Σ sw², Σ sw·(Ω sw), Σ (Ω sw)², Σ sw·y, Σ (Ω sw)·y.
    fixed: [f64; 5],
    /// g of every sample at the last vs (the residual pass reuses it).
    g: Vec<f64>,
}

impl<'a> StribeckRss<'a> {
    fn new(d: &'a SlipData, viscous: bool) -> Self {
        let sw: Vec<f64> = (0..d.len()).map(|i| d.w(i).sqrt()).collect();
        let y: Vec<f64> = (0..d.len()).map(|i| d.mu[i] * sw[i]).collect();
        let mut fixed = [0.0; 5];
        for i in 0..d.len() {
            let (v0, v2) = (1.0 * sw[i], d.omega[i] * sw[i]);
            fixed[0] += v0 * v0;
            fixed[1] += v0 * v2;
            fixed[2] += v2 * v2;
            fixed[3] += v0 * y[i];
            fixed[4] += v2 * y[i];
        }
        StribeckRss { d, viscous, sw, y, fixed, g: vec![0.0; d.len()] }
    }

    /// The RSS at `vs` (∞ when the normal equations are singular).
    fn at(&mut self, vs: f64) -> f64 {
        let d = self.d;
        let (mut a01, mut a11, mut a12, mut b1) = (0.0, 0.0, 0.0, 0.0);
        for i in 0..d.len() {
            let g = rig_model::friction::stribeck_decay(d.omega[i], vs);
            self.g[i] = g;
            let (v0, v1, v2) = (1.0 * self.sw[i], g * self.sw[i], d.omega[i] * self.sw[i]);
            a01 += v0 * v1;
            a11 += v1 * v1;
            a12 += v1 * v2;
            b1 += v1 * self.y[i];
        }
        let [a00, a02, a22, b0, b2] = self.fixed;
        let ne = if self.viscous {
            Normal::from_row_major(3, &[a00, a01, a02, a01, a11, a12, a02, a12, a22], vec![b0, b1, b2])
        } else {
            Normal::from_row_major(2, &[a00, a01, a01, a11], vec![b0, b1])
        };
        let Some(p) = ne.solve() else { return f64::INFINITY };
        let mut rss = 0.0;
        for i in 0..d.len() {
            let fit = if self.viscous {
                1.0 * p[0] + self.g[i] * p[1] + d.omega[i] * p[2]
            } else {
                1.0 * p[0] + self.g[i] * p[1]
            };
            let e = d.mu[i] - fit;
            rss += d.w(i) * e * e;
        }
        rss
    }
}

/// μ = μk + Δ exp(−(Ω/vs)²) [+ c|Ω| when `with_viscous`]: linear in (μk, Δ[, c])
/// for fixed vs; vs by a log grid then Brent's refinement; covariance
/// from the numerical Jacobian.
pub fn fit_stribeck(d: &SlipData, with_viscous: bool) -> Option<FrictionFit> {
    let grid: Vec<f64> = (0..41).map(|j| 0.05 * 10f64.powf(j as f64 * 3.0 / 40.0)).collect();
    // The grid on a subsample locates the basin; Brent's method on every sample.
    let ds = d.subsample(SEARCH_EVERY);
    let mut coarse = StribeckRss::new(&ds, with_viscous);
    let (best, _) = grid.iter().enumerate().map(|(j, &v)| (j, coarse.at(v))).min_by(|a, b| a.1.total_cmp(&b.1))?;
    let lo = grid[best.saturating_sub(1)].ln();
    let hi = grid[(best + 1).min(grid.len() - 1)].ln();
    stribeck_in(d, with_viscous, lo, hi)
}

/// Decades per step of [`fit_stribeck`]'s log grid of vs (41 points over 0.05–50 rad/s, 3/40 decade apart).
const STRIBECK_GRID_STEP_LN10: f64 = 3.0 / 40.0;

/// [`fit_stribeck`] started in a known basin: Brent's search on the bracket
/// of the same width the grid gives (one grid step either side) around
/// `vs_near`, without the grid. The composite's later passes refit the speed
/// law on a target that only the modulations' re-estimation changed (by a
/// fraction of a percent per pass), so the basin its first pass's grid found
/// is the one to refine; the grid's 41 subsample evaluations (≈ 10 passes
/// over every sample, a third of the fit) are saved. The search is the same
/// (ln vs to 10⁻⁶); where the optimum lies inside both brackets it is found
/// to that tolerance either way. Off the grid's 0.05–50 rad/s range the
/// cold fit runs instead.
pub fn fit_stribeck_near(d: &SlipData, with_viscous: bool, vs_near: f64) -> Option<FrictionFit> {
    let h = STRIBECK_GRID_STEP_LN10 * std::f64::consts::LN_10;
    let lv = vs_near.ln();
    if !lv.is_finite() || lv - h < 0.05f64.ln() || lv + h > 50f64.ln() {
        return fit_stribeck(d, with_viscous);
    }
    stribeck_in(d, with_viscous, lv - h, lv + h)
}

/// Brent's search for ln vs on [lo, hi], then the linear fit and the covariance at it.
fn stribeck_in(d: &SlipData, with_viscous: bool, lo: f64, hi: f64) -> Option<FrictionFit> {
    let ncol = if with_viscous { 3 } else { 2 };
    let lin = |vs: f64| {
        linear_fit(d, ncol, |i, r| {
            r[0] = 1.0;
            r[1] = rig_model::friction::stribeck_decay(d.omega[i], vs);
            if with_viscous {
                r[2] = d.omega[i];
            }
        })
    };
    let mut fine = StribeckRss::new(d, with_viscous);
    // ln vs to 10⁻⁶ (golden section's 25 steps on this bracket reached 2·10⁻⁶).
    let lv = brent_min(lo, hi, 1e-6, 27, |lv| fine.at(lv.exp()));
    let vs = lv.exp();
    let (p, _, rss) = lin(vs)?;
    let (mu_k, dmu) = (p[0], p[1]);
    let c = if with_viscous { p[2] } else { 0.0 };
    // Gauss–Newton covariance over (μk, Δ, vs[, c]).
    let np = ncol + 1;
    let mut ne = Normal::new(np);
    for i in 0..d.len() {
        let g = rig_model::friction::stribeck_decay(d.omega[i], vs);
        let dg_dvs = g * 2.0 * d.omega[i].powi(2) / vs.powi(3);
        let sw = d.w(i).sqrt();
        if with_viscous {
            ne.add_sparse(&[(0, sw), (1, sw * g), (2, sw * dmu * dg_dvs), (3, sw * d.omega[i])], 0.0);
        } else {
            ne.add_sparse(&[(0, sw), (1, sw * g), (2, sw * dmu * dg_dvs)], 0.0);
        }
    }
    let var = rss / (d.len().saturating_sub(np).max(1)) as f64;
    let inv = ne.inverse();
    let se = |a: usize, b: usize| inv.as_ref().map(|m| m[a * np + b] * var).unwrap_or(f64::NAN);
    let se_mu_s = (se(0, 0) + se(1, 1) + 2.0 * se(0, 1)).max(0.0).sqrt();
    let mut params = vec![
        ("mu_static", mu_k + dmu, se_mu_s),
        ("mu_kinetic", mu_k, se(0, 0).max(0.0).sqrt()),
        ("stribeck_speed_rad_s", vs, se(2, 2).max(0.0).sqrt()),
    ];
    if with_viscous {
        params.push(("viscous_per_rad_s", c, se(3, 3).max(0.0).sqrt()));
    }
    Some(FrictionFit {
        model: FrictionModel::Stribeck { mu_k, mu_s: mu_k + dmu, vs, c },
        phases: vec![],
        params,
        rss_w: rss,
        n: d.len(),
        k: np,
        converged: inv.is_some(),
        scan: vec![],
    })
}

/// Per-run sine regression μ = μk + A_r sin x + B_r cos x (shared μk) for
/// given (sin x, cos x) per sample: (weighted RSS, solution). Linear, so the
/// scan is exact at each x. RSS = yᵀWy − pᵀJᵀWy at the solution.
fn sine_rss_from(d: &SlipData, sc: &[(f64, f64)], ywy: f64) -> Option<(f64, Vec<f64>)> {
    // μk shared, (A_r, B_r) the sample's run's block: an arrow (ArrowNormal).
    let mut arrow = ArrowNormal::<1, 2>::new(d.n_runs);
    for (i, &(s, c)) in sc.iter().enumerate().take(d.len()) {
        let r = d.run[i];
        let sw = d.w(i).sqrt();
        arrow.add(&[sw], r, &[sw * s, sw * c], sw * d.mu[i]);
    }
    let ne = arrow.into_normal();
    let p = ne.solve()?;
    let rss = ywy - p.iter().zip(&ne.atb).map(|(a, b)| a * b).sum::<f64>();
    Some((rss.max(0.0), p))
}

/// RSS only of the same regression, for the scans: the normal matrix is an
/// arrow (μk couples every run, runs only their own 2×2 block), so it is
/// solved by eliminating each run's block (Schur complement on μk), O(runs)
/// per trial instead of a dense O(runs³) solve, with per-run sums instead of
/// a rank-one update per sample. Same solution as [`sine_rss_from`] (a test
/// checks); a run whose block is singular (no slip samples) drops out of the
/// elimination as it would be a zero row of the dense system.
fn sine_rss_scan(d: &SlipData, sc: &[(f64, f64)], sums: &ScanSums) -> f64 {
    // Per run: Σs, Σc, Σs², Σc², Σsc, Σys, Σyc (unweighted; w is per run).
    let mut acc = vec![[0.0f64; 7]; d.n_runs];
    let add = |a: &mut [f64; 7], (s, c): (f64, f64), y: f64| {
        a[0] += s;
        a[1] += c;
        a[2] += s * s;
        a[3] += c * c;
        a[4] += s * c;
        a[5] += y * s;
        a[6] += y * c;
    };
    match &sums.runs {
        // Contiguous runs: one local accumulator per run (same order of sums).
        Some(ranges) => {
            for (a, range) in acc.iter_mut().zip(ranges) {
                let mut local = [0.0f64; 7];
                for i in range.clone() {
                    add(&mut local, sc[i], d.mu[i]);
                }
                *a = local;
            }
        }
        None => {
            for (i, &v) in sc.iter().enumerate().take(d.len()) {
                add(&mut acc[d.run[i]], v, d.mu[i]);
            }
        }
    }
    sine_rss_of_sums(d, &acc, sums)
}

/// The RSS of [`sine_rss_scan`] from the per-run sums Σs, Σc, Σs², Σc², Σsc,
/// Σys, Σyc (unweighted; w is per run), however they were made.
fn sine_rss_of_sums(d: &SlipData, acc: &[[f64; 7]], sums: &ScanSums) -> f64 {
    let (a00, g0, ywy) = (sums.a00, sums.g0, sums.ywy);
    // Eliminate the run blocks: S = a00 − Σ bᵀB⁻¹b, h = g0 − Σ bᵀB⁻¹g.
    let mut blocks = Vec::with_capacity(d.n_runs);
    let (mut schur, mut h) = (a00, g0);
    for (r, a) in acc.iter().enumerate() {
        let w = d.run_weight[r];
        let (b11, b22, b12) = (w * a[2], w * a[3], w * a[4]);
        let det = b11 * b22 - b12 * b12;
        if det <= 1e-12 * (b11 * b22).max(f64::MIN_POSITIVE) {
            blocks.push(None);
            continue;
        }
        let (c1, c2, g1, g2) = (w * a[0], w * a[1], w * a[5], w * a[6]);
        // B⁻¹ = [b22, −b12; −b12, b11]/det.
        let bi = move |x1: f64, x2: f64| ((b22 * x1 - b12 * x2) / det, (b11 * x2 - b12 * x1) / det);
        let (u1, u2) = bi(c1, c2);
        schur -= c1 * u1 + c2 * u2;
        let (v1, v2) = bi(g1, g2);
        h -= c1 * v1 + c2 * v2;
        blocks.push(Some((c1, c2, g1, g2, bi)));
    }
    if schur.abs() < 1e-300 {
        return f64::INFINITY;
    }
    let mu_k = h / schur;
    let mut fitted = mu_k * g0;
    for (c1, c2, g1, g2, bi) in blocks.into_iter().flatten() {
        let (x1, x2) = bi(g1 - c1 * mu_k, g2 - c2 * mu_k);
        fitted += x1 * g1 + x2 * g2;
    }
    (ywy - fitted).max(0.0)
}

/// What [`sine_rss_scan`] needs besides the regressors, computed once per
/// data set: yᵀWy, Σw, Σwy and the sample range of each run when runs are
/// contiguous (as [`SlipData::from_runs`] and `subsample` build them).
struct ScanSums {
    ywy: f64,
    a00: f64,
    g0: f64,
    runs: Option<Vec<std::ops::Range<usize>>>,
}

impl ScanSums {
    fn of(d: &SlipData) -> Self {
        let (mut a00, mut g0) = (0.0, 0.0);
        for i in 0..d.len() {
            a00 += d.w(i);
            g0 += d.w(i) * d.mu[i];
        }
        let mut ranges: Vec<std::ops::Range<usize>> = (0..d.n_runs).map(|_| 0..0).collect();
        let mut contiguous = true;
        let mut i = 0;
        while i < d.len() {
            let r = d.run[i];
            let start = i;
            while i < d.len() && d.run[i] == r {
                i += 1;
            }
            contiguous &= ranges[r].is_empty();
            ranges[r] = start..i;
        }
        ScanSums { ywy: ywy(d), a00, g0, runs: contiguous.then_some(ranges) }
    }
}

fn ywy(d: &SlipData) -> f64 {
    (0..d.len()).map(|i| d.w(i) * d.mu[i] * d.mu[i]).sum()
}

/// RSS of the time-sine regression at every frequency of `freqs_hz`, in
/// frequency order (the evidence figure draws them): by FFT on every sample
/// where the samples lie on a uniform time grid and the frequencies on the
/// FFT's bins ([`time_scan_fft`]), else sample by sample on every
/// [`SEARCH_EVERY`]-th sample, coarse to fine ([`time_scan_direct`]).
pub(crate) fn time_scan(d: &SlipData, freqs_hz: &[f64]) -> Vec<(f64, f64)> {
    time_scan_fft(d, freqs_hz).unwrap_or_else(|| time_scan_direct(&d.subsample(SEARCH_EVERY), freqs_hz))
}

/// Largest FFT of [`time_scan_fft`] (2²² samples: 2.3 h at 500 Hz).
const MAX_SCAN_FFT: usize = 1 << 22;

/// The scan's per-run sums at every frequency at once. Slip samples are a
/// subset of each run's uniform recording grid t_k = t_ref + k·dt, so every
/// sum over them is a DFT of a zero-filled series on that grid:
/// Σ_i a_i e^{−j2πf t_i} = e^{−j2πf t_ref} · Σ_k x_k e^{−j2π m k/N} with
/// x_k = a_i at the samples' k and 0 elsewhere, m = f·N·dt. With N a multiple
/// of 1/(Δf·dt) no shorter than the run, every grid frequency f_j = f0 + jΔf
/// (f0 a multiple of Δf) is bin m_j and nothing wraps around, so two real
/// FFTs per run (the sample indicator, and μ at the samples) give Σs, Σc,
/// Σys, Σyc at f_j and, at bin 2m_j, Σcos 2x and Σsin 2x, whence
/// Σs² = (n − Σcos 2x)/2, Σc² = (n + Σcos 2x)/2, Σsc = Σsin 2x/2. The same
/// sums as [`sine_rss_scan`] up to rounding, on every sample and every grid
/// frequency for ≈ 2·(runs) FFTs instead of (frequencies × samples) rotations
/// (the direct scan, on a quarter of the samples and half the grid plus the
/// best minima's neighbours, was 18 % of the diagnosis; test
/// `fft_scan_matches_the_direct_sums`). `None` (the caller scans directly)
/// when the runs are not contiguous, a sample is off its run's grid by more
/// than 10⁻⁶ of a step, the grid is not uniform or not on the bins, or N
/// would exceed [`MAX_SCAN_FFT`].
fn time_scan_fft(d: &SlipData, freqs_hz: &[f64]) -> Option<Vec<(f64, f64)>> {
    use rayon::prelude::*;
    if freqs_hz.len() < 2 || d.is_empty() {
        return None;
    }
    let sums = ScanSums::of(d);
    let ranges = sums.runs.as_ref()?;
    let df = freqs_hz[1] - freqs_hz[0];
    let on_grid = |x: f64, tol: f64| (x - x.round()).abs() <= tol;
    if df.is_nan() || df <= 0.0 || !freqs_hz.windows(2).all(|w| ((w[1] - w[0]) - df).abs() <= 1e-9 * df) {
        return None;
    }
    // The recording step: the smallest step between consecutive samples of a run.
    let dt =
        (1..d.len()).filter(|&i| d.run[i] == d.run[i - 1]).map(|i| d.t[i] - d.t[i - 1]).fold(f64::INFINITY, f64::min);
    if !(dt > 0.0 && dt.is_finite()) {
        return None;
    }
    let mut span = 0usize;
    for range in ranges.iter().filter(|r| !r.is_empty()) {
        let t_ref = d.t[range.start];
        for i in range.clone() {
            let k = (d.t[i] - t_ref) / dt;
            if !on_grid(k, 1e-6) {
                return None;
            }
            span = span.max(k.round() as usize + 1);
        }
    }
    // N = q·n0 with n0 = 1/(Δf·dt) samples per bin step Δf.
    let n0 = 1.0 / (df * dt);
    if !on_grid(n0, 1e-6 * n0) || !on_grid(freqs_hz[0] / df, 1e-6) || n0 < 1.0 {
        return None;
    }
    let n0 = n0.round() as usize;
    let n = n0 * span.div_ceil(n0).max(1);
    let bin = |f: f64| (f * n as f64 * dt).round() as usize;
    let top = 2 * bin(*freqs_hz.last()?);
    if n > MAX_SCAN_FFT || top > n / 2 {
        return None;
    }
    let fft = rig_spectra::forward_plan(n);
    // Per run: the seven sums at every frequency.
    let per_run: Vec<Vec<[f64; 7]>> = ranges
        .par_iter()
        .map(|range| {
            if range.is_empty() {
                return vec![[0.0; 7]; freqs_hz.len()];
            }
            let t_ref = d.t[range.start];
            let mut ind = fft.make_input_vec();
            let mut val = fft.make_input_vec();
            for i in range.clone() {
                let k = ((d.t[i] - t_ref) / dt).round() as usize;
                ind[k] = 1.0;
                val[k] = d.mu[i];
            }
            let (mut ind_f, mut val_f) = (fft.make_output_vec(), fft.make_output_vec());
            fft.process(&mut ind, &mut ind_f).expect("sizes from the plan");
            fft.process(&mut val, &mut val_f).expect("sizes from the plan");
            let count = range.len() as f64;
            freqs_hz
                .iter()
                .map(|&f| {
                    let m = bin(f);
                    // Σ a e^{−jx} = e^{−j2πf t_ref}·X[m]: real part Σ a cos x, imaginary −Σ a sin x.
                    let at = |x: realfft::num_complex::Complex<f64>, f: f64| {
                        let (s, c) = (2.0 * PI * f * t_ref).sin_cos();
                        let re = x.re * c + x.im * s;
                        let im = x.im * c - x.re * s;
                        (-im, re)
                    };
                    let (s1, c1) = at(ind_f[m], f);
                    let (s2, c2) = at(ind_f[2 * m], 2.0 * f);
                    let (ys, yc) = at(val_f[m], f);
                    [s1, c1, 0.5 * (count - c2), 0.5 * (count + c2), 0.5 * s2, ys, yc]
                })
                .collect()
        })
        .collect();
    Some(
        freqs_hz
            .iter()
            .enumerate()
            .map(|(j, &f)| {
                let acc: Vec<[f64; 7]> = per_run.iter().map(|r| r[j]).collect();
                (f, sine_rss_of_sums(d, &acc, &sums))
            })
            .collect(),
    )
}

/// RSS of the time-sine regression on a frequency grid, coarse to fine: every
/// second grid point first, then every grid point within ±2 steps of the five
/// best coarse minima. With runs of T ≥ 30 s the main lobe of a modulation is
/// ±1/T ≤ ±0.033 Hz wide, so a coarse step of 2 × 0.01 Hz leaves a true line at
/// most 0.01 Hz from a coarse point, where it keeps sinc²(π·0.01·40) ≈ 58 %
/// of its RSS drop: the peak ranks among the best five, and its fine
/// neighbourhood is then scanned exactly. Returns the scored points in
/// frequency order (the evidence figure draws them).
fn time_scan_direct(d: &SlipData, freqs_hz: &[f64]) -> Vec<(f64, f64)> {
    if freqs_hz.len() < 16 {
        return time_scan_at(d, freqs_hz);
    }
    let coarse: Vec<f64> = freqs_hz.iter().step_by(2).copied().collect();
    let scored = time_scan_at(d, &coarse);
    let mut minima: Vec<usize> = (0..scored.len())
        .filter(|&j| {
            let l = if j > 0 { scored[j - 1].1 } else { f64::INFINITY };
            let r = scored.get(j + 1).map_or(f64::INFINITY, |x| x.1);
            scored[j].1 <= l && scored[j].1 <= r
        })
        .collect();
    minima.sort_by(|&a, &b| scored[a].1.total_cmp(&scored[b].1).then(a.cmp(&b)));
    let mut fine_idx: Vec<usize> = minima
        .iter()
        .take(5)
        .flat_map(|&j| (2 * j).saturating_sub(2)..=(2 * j + 2).min(freqs_hz.len() - 1))
        .filter(|k| k % 2 == 1)
        .collect();
    fine_idx.sort_unstable();
    fine_idx.dedup();
    let fine: Vec<f64> = fine_idx.iter().map(|&k| freqs_hz[k]).collect();
    let mut out = scored;
    out.extend(time_scan_at(d, &fine));
    out.sort_by(|a, b| a.0.total_cmp(&b.0));
    out
}

/// RSS of the time-sine regression at each frequency of `freqs_hz`. On a
/// uniform grid, chunks of 64 frequencies run in parallel and inside a chunk
/// sin/cos advance by rotation (angle 2πΔf·t per sample), re-synchronised
/// exactly at each chunk start.
fn time_scan_at(d: &SlipData, freqs_hz: &[f64]) -> Vec<(f64, f64)> {
    use rayon::prelude::*;
    let sums = ScanSums::of(d);
    let uniform =
        freqs_hz.len() > 1 && freqs_hz.windows(2).all(|w| ((w[1] - w[0]) - (freqs_hz[1] - freqs_hz[0])).abs() < 1e-9);
    if !uniform {
        return freqs_hz
            .par_iter()
            .map(|&f| {
                let sc: Vec<(f64, f64)> = d.t.iter().map(|t| (2.0 * PI * f * t).sin_cos()).collect();
                (f, sine_rss_scan(d, &sc, &sums))
            })
            .collect();
    }
    let df = freqs_hz[1] - freqs_hz[0];
    let rot: Vec<(f64, f64)> = d.t.iter().map(|t| (2.0 * PI * df * t).sin_cos()).collect();
    let chunks: Vec<&[f64]> = freqs_hz.chunks(64).collect();
    chunks
        .par_iter()
        .map(|chunk| {
            let mut sc: Vec<(f64, f64)> = d.t.iter().map(|t| (2.0 * PI * chunk[0] * t).sin_cos()).collect();
            let mut out = Vec::with_capacity(chunk.len());
            for &f in chunk.iter() {
                out.push((f, sine_rss_scan(d, &sc, &sums)));
                for (v, r) in sc.iter_mut().zip(&rot) {
                    *v = (v.0 * r.1 + v.1 * r.0, v.1 * r.1 - v.0 * r.0);
                }
            }
            out
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// RSS of the angle-sine regression at every order 1..=`max_order`, in
/// parallel over orders; sin/cos of n·φ by the multiple-angle recurrence from
/// sin/cos φ (rounding grows by about one unit per order, far below the RSS
/// differences the scan ranks).
fn order_scan(d: &SlipData, orders: &RangeInclusive<u32>) -> Vec<(f64, f64)> {
    let sums = ScanSums::of(d);
    let base: Vec<(f64, f64)> = d.phi.iter().map(|p| p.sin_cos()).collect();
    let mut sc = base.clone();
    let mut out = Vec::with_capacity(orders.clone().count());
    for n in 1..=*orders.end() {
        if n > 1 {
            for (v, b) in sc.iter_mut().zip(&base) {
                *v = (v.0 * b.1 + v.1 * b.0, v.1 * b.1 - v.0 * b.0);
            }
        }
        if orders.contains(&n) {
            out.push((f64::from(n), sine_rss_scan(d, &sc, &sums)));
        }
    }
    out
}

/// Samples between exact re-synchronisations of [`SinCosSchedule`].
const RESYNC_EVERY: usize = 64;

/// The samples of [`SinCosSchedule::visit`] in a vector (the tests' view);
/// returns how many took the exact `sin_cos`.
#[cfg(test)]
fn time_sin_cos(d: &SlipData, f_hz: f64, out: &mut Vec<(f64, f64)>) -> usize {
    let schedule = SinCosSchedule::of(d);
    out.clear();
    schedule.visit(&d.t, f_hz, |_, v| out.push(v));
    schedule.segments.len()
}

/// sin and cos of 2π f t_i for every sample: exact `sin_cos` at each run's
/// first sample, after a gap and every [`RESYNC_EVERY`] samples; between, a
/// rotation by 2π f Δt of the step the last re-sync saw (steps that agree to
/// 1e-12 s count as equal). The sample times are rounded (an ulp of t,
/// 7·10⁻¹⁵ s at 60 s), so a step differs from the cached one by up to two
/// ulps and the phase drifts by ≤ 2π f · 2 ulp(t) per step: at 10 Hz and
/// 60 s, ≤ 6·10⁻¹¹ after 64 steps (the test derives this bound), far below
/// any amplitude the fits resolve (~10⁻⁴). The Gauss–Newton of the time sine
/// evaluates this once per trial; a `sin_cos` per sample instead cost 4 % of
/// the diagnosis bench (10.2 against 9.8 s).
///
/// Where the exact `sin_cos` falls and which step rotates in between depend
/// on the sample times and runs only, not on the frequency: a fit that tries
/// many frequencies on the same samples builds the schedule once
/// ([`SinCosSchedule::of`]) and [`SinCosSchedule::visit`]s it per frequency,
/// in the pass that uses the values, without the per-sample step tests or a
/// vector of them (the same operations on the same numbers as testing each
/// sample's step in turn).
pub(crate) struct SinCosSchedule {
    /// (first sample, samples, step): an exact `sin_cos` at the first
    /// sample, then rotations by `steps_s[step]` (a segment of one sample
    /// rotates by nothing).
    segments: Vec<(usize, usize, usize)>,
    /// Each step length the samples set, in order (a step equal to the last
    /// within 1e-12 s is not a new one).
    steps_s: Vec<f64>,
}

impl SinCosSchedule {
    pub(crate) fn of(d: &SlipData) -> Self {
        let (mut segments, mut steps_s) = (Vec::new(), Vec::new());
        let mut step = f64::NAN;
        let mut since = 0;
        for i in 0..d.len() {
            let dt = if i > 0 && d.run[i] == d.run[i - 1] { d.t[i] - d.t[i - 1] } else { f64::NAN };
            let same_step = (dt - step).abs() <= 1e-12;
            match segments.last_mut() {
                Some((_, len, _)) if since + 1 < RESYNC_EVERY && same_step => {
                    since += 1;
                    *len += 1;
                }
                _ => {
                    since = 0;
                    // A new step length (the first step is one: its predecessor is NaN).
                    if dt.is_finite() && !same_step {
                        step = dt;
                        steps_s.push(dt);
                    }
                    segments.push((i, 1, steps_s.len().saturating_sub(1)));
                }
            }
        }
        SinCosSchedule { segments, steps_s }
    }

    /// Calls `f(i, (sin, cos) of 2π f t_i)` for every sample in order.
    #[inline]
    pub(crate) fn visit(&self, t: &[f64], f_hz: f64, mut f: impl FnMut(usize, (f64, f64))) {
        let w = 2.0 * PI * f_hz;
        let rot: Vec<(f64, f64)> = self.steps_s.iter().map(|dt| (w * dt).sin_cos()).collect();
        for &(start, len, step) in &self.segments {
            let mut v = (w * t[start]).sin_cos();
            f(start, v);
            if len > 1 {
                let (sr, cr) = rot[step];
                for i in start + 1..start + len {
                    v = (v.0 * cr + v.1 * sr, v.1 * cr - v.0 * sr);
                    f(i, v);
                }
            }
        }
    }
}

/// Sine models: scan the frequency (time kind, grid of `freqs_hz`) or the
/// order (angle kind, `orders`, usually 1..=max_order), then Gauss–Newton on
/// the shared (μk, a[, f]) and per-run θ_r. Returns the best fit.
///
/// Both kinds take full Newton steps where they are descent steps: the runs
/// share one amplitude, so on data whose runs differ in amplitude (or that
/// carry no such modulation at all) the residual stays correlated with each
/// run's sine, the curvature Gauss–Newton leaves out (Σ w r ∂²f) is as large
/// as the one it keeps, and its phase steps overshoot: a quarter step
/// accepted per iteration, the phases creeping by ~3 % of their distance per
/// iteration, 30 iterations without convergence on the emulated campaign.
/// With the exact Hessian the same optimum is reached in a few iterations.
/// The time kind's frequency zig-zagged the same way (issue 23: a time sine
/// fitted to an angle-periodic rung's runs, whose angle modulation shows in
/// time at a frequency near n·Ω/2π with run-to-run amplitudes, moved f by
/// ±10⁻⁴ Hz per iteration, the predicted decrease shrinking by ≈ 15 % per
/// iteration and still 0.3 σ² after the 30th; with the exact Hessian,
/// including f's terms, 2–4 iterations reach the stop rule).
pub fn fit_sine(d: &SlipData, time_kind: bool, freqs_hz: &[f64], orders: RangeInclusive<u32>) -> Option<FrictionFit> {
    if d.is_empty() {
        return None;
    }
    // Frequency parameters before the per-run phases: f (time kind) or none.
    let nf = usize::from(time_kind);
    let xarg = |psi: f64, i: usize| if time_kind { 2.0 * PI * psi * d.t[i] } else { psi * d.phi[i] };
    // A single candidate — a warm start's frequency or order, or the one a
    // composite's later pass refines (`composite::fit_composite_with`) — is
    // the scan's best whatever its RSS, so it is not scanned: the scan of one
    // frequency was a `sin_cos` of every fourth sample and the order scan's
    // one of every sample with n − 1 rotations, each only to be the minimum
    // of one (the same ψ0 to the bit; issue 23). Its one scan point is the
    // RSS of the per-run regression at ψ0 below (the same regression, solved
    // directly rather than by the scan's elimination).
    let single = if time_kind {
        (freqs_hz.len() == 1).then(|| freqs_hz[0])
    } else {
        (orders.start() == orders.end() && *orders.start() >= 1).then(|| f64::from(*orders.start()))
    };
    let mut scored: Vec<(f64, f64)> = match single {
        Some(_) => Vec::new(),
        None if time_kind => time_scan(d, freqs_hz),
        None => order_scan(d, &orders),
    };
    let psi0 = match single {
        Some(psi) => psi,
        None => scored.iter().copied().min_by(|a, b| a.1.total_cmp(&b.1).then(a.0.total_cmp(&b.0)))?.0,
    };
    // sin/cos of the scan's best argument: the start of Gauss–Newton (per-run
    // linear fit) and, for the angle kind, its regressor throughout — n·φ does
    // not move during Gauss–Newton, so each run's phase enters by angle
    // addition, sin(x + θ) = sin x cos θ + cos x sin θ (no trigonometry per
    // sample). Time kind: sin/cos of 2πf·t by rotation along each run's
    // uniform sample steps ([`SinCosSchedule`]), recomputed for each trial f.
    let schedule = time_kind.then(|| SinCosSchedule::of(d));
    let sc0: Vec<(f64, f64)> = match &schedule {
        Some(sch) => {
            let mut base = Vec::with_capacity(d.len());
            sch.visit(&d.t, psi0, |_, v| base.push(v));
            base
        }
        None => (0..d.len()).map(|i| xarg(psi0, i).sin_cos()).collect(),
    };
    let (rss0, p) = sine_rss_from(d, &sc0, ywy(d))?;
    if single.is_some() {
        scored.push((psi0, rss0));
    }
    // Each sample's weight and its square root, once (the loops below read them every pass).
    let w: Vec<f64> = (0..d.len()).map(|i| d.w(i)).collect();
    let sw: Vec<f64> = w.iter().map(|w| w.sqrt()).collect();
    let run_trig = |th: &[f64]| -> Vec<(f64, f64)> { th[2 + nf..].iter().map(|t| t.sin_cos()).collect() };
    let mu_k0 = p[0];
    // Shared amplitude: weighted mean of per-run amplitudes (start of GN).
    let mut amp_sum = 0.0;
    let mut phases = vec![0.0; d.n_runs];
    for r in 0..d.n_runs {
        let (a, b) = (p[1 + 2 * r], p[2 + 2 * r]);
        amp_sum += (a * a + b * b).sqrt();
        phases[r] = b.atan2(a);
    }
    let a0 = amp_sum / d.n_runs as f64 / mu_k0.abs().max(1e-9);
    // Gauss–Newton: params [μk, a, (f), θ_0..θ_{R−1}].
    let np = 2 + nf + d.n_runs;
    let mut theta = vec![mu_k0, a0];
    if time_kind {
        theta.push(psi0);
    }
    theta.extend(phases);
    let model_of = |th: &[f64]| {
        if time_kind {
            FrictionModel::TimeSine { mu_k: th[0], a: th[1], f_hz: th[2] }
        } else {
            FrictionModel::AngleSine { mu_k: th[0], a: th[1], order: psi0 as u32 }
        }
    };
    // The weighted RSS at `th`, leaving sin and cos of each sample's argument
    // in `sc`: an accepted line-search candidate hands them to the next
    // iteration's normal equations, so each iteration evaluates them once.
    // Time kind: sin/cos of 2πf·t by the schedule's rotations, visited in
    // sample order in the same pass (the angle kind reads sc0).
    let rss_of = |th: &[f64], sc: &mut Vec<(f64, f64)>| -> f64 {
        let trig = run_trig(th);
        sc.resize(d.len(), (0.0, 0.0));
        let mut rss = 0.0;
        let mut at = |i: usize, (sx, cx): (f64, f64)| {
            let (st, ct) = trig[d.run[i]];
            let v = (sx * ct + cx * st, cx * ct - sx * st);
            sc[i] = v;
            let e = d.mu[i] - th[0] * (1.0 + th[1] * v.0);
            rss += w[i] * e * e;
        };
        match &schedule {
            Some(sch) => sch.visit(&d.t, th[2], at),
            None => sc0.iter().enumerate().for_each(|(i, &v)| at(i, v)),
        }
        rss
    };
    let (mut sc, mut sc_cand) = (Vec::with_capacity(d.len()), Vec::with_capacity(d.len()));
    let mut rss = rss_of(&theta, &mut sc);
    let mut converged = false;
    let mut ne_last = None;
    // Where each step's line search starts ([`LineStart`]): Newton's, Gauss–Newton's.
    let mut starts = [LineStart::default(); 2];
    for _ in 0..30 {
        // −Σ w r ∂²f/∂p∂q of f = μk(1 + a sin(x + θ_r)) (the terms
        // Gauss–Newton drops), x = 2πf·t (time kind) or n·φ (angle kind):
        // over the shared (μk, a[, f]) and per run (μk, θ_r), (a, θ_r),
        // [(f, θ_r),] (θ_r, θ_r). With the time kind's f, ∂x/∂f = 2πt:
        // ∂²f/∂μk∂f = a c 2πt, ∂²f/∂a∂f = μk c 2πt, ∂²f/∂f² = −μk a s (2πt)²,
        // ∂²f/∂f∂θ = −μk a s 2πt.
        let mut h_shared = [[0.0f64; 3]; 3];
        let mut h_th = vec![[0.0f64; 4]; d.n_runs];
        // Rows (μk, a[, f]) shared and θ_r of the sample's run: an arrow
        // (ArrowNormal: the sums add_sparse would make, bit for bit).
        let (mk, a) = (theta[0], theta[1]);
        let ne = if time_kind {
            let mut arrow = ArrowNormal::<3, 1>::new(d.n_runs);
            for (i, &(s, c)) in sc.iter().enumerate() {
                let r = d.run[i];
                let sw = sw[i];
                let e = d.mu[i] - mk * (1.0 + a * s);
                let tt = 2.0 * PI * d.t[i];
                let we = w[i] * e;
                h_shared[0][1] -= we * s;
                h_shared[0][2] -= we * a * c * tt;
                h_shared[1][2] -= we * mk * c * tt;
                h_shared[2][2] += we * mk * a * s * tt * tt;
                let h = &mut h_th[r];
                h[0] -= we * a * c;
                h[1] -= we * mk * c;
                h[2] += we * mk * a * s * tt;
                h[3] += we * mk * a * s;
                let shared = [sw * (1.0 + a * s), sw * mk * s, sw * mk * a * c * tt];
                arrow.add(&shared, r, &[sw * mk * a * c], sw * e);
            }
            arrow.into_normal()
        } else {
            let mut arrow = ArrowNormal::<2, 1>::new(d.n_runs);
            for (i, &(s, c)) in sc.iter().enumerate() {
                let r = d.run[i];
                let sw = sw[i];
                let e = d.mu[i] - mk * (1.0 + a * s);
                let we = w[i] * e;
                h_shared[0][1] -= we * s;
                let h = &mut h_th[r];
                h[0] -= we * a * c;
                h[1] -= we * mk * c;
                h[3] += we * mk * a * s;
                arrow.add(&[sw * (1.0 + a * s), sw * mk * s], r, &[sw * mk * a * c], sw * e);
            }
            arrow.into_normal()
        };
        // The Newton step where the Hessian is positive definite (Cholesky).
        let newton = {
            let k = 2 + nf;
            let mut h = ne.clone();
            for (p, row) in h_shared.iter().enumerate().take(k) {
                for (q, &v) in row.iter().enumerate().take(k).skip(p) {
                    h.ata[(p, q)] += v;
                    if p != q {
                        h.ata[(q, p)] += v;
                    }
                }
            }
            for (r, x) in h_th.iter().enumerate() {
                let j = k + r;
                for (p, v) in [(0, x[0]), (1, x[1]), (2, x[2])].into_iter().take(k) {
                    h.ata[(p, j)] += v;
                    h.ata[(j, p)] += v;
                }
                h.ata[(j, j)] += x[3];
            }
            h.solve()
        };
        let gauss_newton = ne.solve();
        if newton.is_none() && gauss_newton.is_none() {
            break;
        }
        let near = gauss_newton.as_ref().is_some_and(|step| near_stationary(step, &ne, rss, d.len()));
        let mut improved = false;
        // The Newton step (where the Hessian is positive definite), then the Gauss–Newton step.
        for (kind, step) in [(0, &newton), (1, &gauss_newton)] {
            let Some(step) = step else { continue };
            let mut lambda = starts[kind].lambda;
            for _ in 0..12 {
                let cand: Vec<f64> = theta.iter().zip(step).map(|(t, s)| t + lambda * s).collect();
                let r2 = rss_of(&cand, &mut sc_cand);
                if r2 <= rss {
                    let rel = (rss - r2) / rss.max(f64::MIN_POSITIVE);
                    theta = cand;
                    rss = r2;
                    std::mem::swap(&mut sc, &mut sc_cand);
                    improved = true;
                    starts[kind].accepted(lambda);
                    if rel < 1e-10 {
                        converged = true;
                    }
                    break;
                }
                lambda *= 0.5;
            }
            if improved {
                break;
            }
        }
        ne_last = Some(ne);
        if !improved || near {
            converged = true;
        }
        if converged {
            break;
        }
    }
    // Canonical sign: a ≥ 0 (a negative amplitude is a phase shift of π).
    if theta[1] < 0.0 {
        theta[1] = -theta[1];
        for th in theta[2 + nf..].iter_mut() {
            *th += PI;
        }
    }
    for th in theta[2 + nf..].iter_mut() {
        *th = th.rem_euclid(2.0 * PI);
    }
    let var = rss / (d.len().saturating_sub(np).max(1)) as f64;
    let inv = ne_last.as_ref().and_then(Normal::inverse);
    let se = |j: usize| inv.as_ref().map(|m| (m[j * np + j] * var).max(0.0).sqrt()).unwrap_or(f64::NAN);
    let model = model_of(&theta);
    let params = if time_kind {
        vec![("amplitude_ratio", theta[1], se(1)), ("frequency_hz", theta[2], se(2))]
    } else {
        vec![("amplitude_ratio", theta[1], se(1)), ("order", psi0, 0.0)]
    };
    Some(FrictionFit {
        model,
        phases: theta[2 + nf..].to_vec(),
        params,
        rss_w: rss,
        n: d.len(),
        // μk, a, and f (time) or the scanned integer order (angle), plus one phase per run.
        k: 3 + d.n_runs,
        converged,
        scan: scored,
    })
}

/// Stop rule of the sine fits' Gauss–Newton ([`fit_sine`],
/// `composite::refine_speed_time`): the step δ = (JᵀJ)⁻¹Jᵀr predicts an RSS
/// decrease δᵀJᵀr = (θ* − θ)ᵀ JᵀJ (θ* − θ) to the stationary point θ* of the
/// local quadratic model, i.e. σ² times the squared distance to it in the
/// parameters' own standard errors (the covariance is σ²(JᵀJ)⁻¹, σ² =
/// RSS/(n − p)). Once that distance is below [`GN_STOP_SE`] standard errors
/// the step is taken and the iteration ends: what is left moves every
/// parameter, and every combination of them, by less than a tenth of its
/// standard error (less still in the correlated-residual errors reported,
/// which are √τ ≥ 1 times these), far inside what any comparison of the
/// selection resolves. The relative-RSS rule (10⁻¹⁰) kept iterating where
/// Gauss–Newton converges only linearly — a modulation far below the noise
/// (large residuals) or absent, whose frequency and phases the data do not
/// pin: up to 30 iterations over ≈ 400 000 slip samples per fit on every
/// unmodulated set of a full-protocol campaign, each step a few 10⁻⁴
/// standard errors.
pub(crate) fn near_stationary(step: &[f64], ne: &Normal, rss: f64, n: usize) -> bool {
    let predicted = step.iter().zip(&ne.atb).map(|(s, g)| s * g).sum::<f64>();
    let var = rss / n.saturating_sub(step.len()).max(1) as f64;
    predicted <= GN_STOP_SE * GN_STOP_SE * var
}

/// [`near_stationary`]'s distance, in standard errors.
pub(crate) const GN_STOP_SE: f64 = 0.1;

/// Where a Gauss–Newton (or Newton) line search starts: the full step, or
/// twice the fraction of it the last accepted step of the same kind took,
/// whichever is smaller (the search then halves as before, up to 12 times,
/// and accepts the first fraction that does not raise the RSS). A fit
/// whose steps are accepted whole, or at half, starts every search at the
/// full step, as before; one that needed a quarter of its step or less
/// (a modulation the data barely pin, whose quadratic model overshoots on
/// every iteration: 30 iterations of 4–9 trials each on the 37-case
/// sample's worst fits, 42 % of the sine fits' RSS passes over 5 % of the
/// calls) starts the next search near the fraction that worked, and grows
/// back by doubling. The directions and the stop rules
/// ([`near_stationary`], the relative RSS) are unchanged; where the
/// search starts lower it accepts a shorter step than the first trial
/// that would have passed, so such fits follow another path to the same
/// stop rule (issue 23).
#[derive(Debug, Clone, Copy)]
pub(crate) struct LineStart {
    pub(crate) lambda: f64,
}

impl Default for LineStart {
    fn default() -> Self {
        LineStart { lambda: 1.0 }
    }
}

impl LineStart {
    /// The search accepted `lambda` of its step.
    pub(crate) fn accepted(&mut self, lambda: f64) {
        self.lambda = (2.0 * lambda).min(1.0);
    }
}

/// Variance inflation for correlated residuals: τ = 1 + 2 Σ_{k=1..K} ρ_k of the
/// weighted residuals, consecutive slip samples of one run (K = 50 samples,
/// 0.1 s at 500 Hz; the sum stops at the first negative ρ). Standard errors
/// from σ²(JᵀJ)⁻¹ assume white residuals; multiplying them by √τ uses the
/// effective sample size instead. τ ≥ 1.
pub fn autocorr_inflation(d: &SlipData, m: &FrictionModel, phases: &[f64]) -> f64 {
    let r: Vec<f64> = (0..d.len())
        .map(|i| {
            let th = phases.get(d.run[i]).copied().unwrap_or(0.0);
            d.w(i).sqrt() * (d.mu[i] - m.mu(d.t[i], d.phi[i], d.omega[i], th))
        })
        .collect();
    inflation_of(&r, &d.run)
}

/// τ of residuals `r` whose sample i belongs to run `run[i]` (lags never
/// cross runs). The definition is [`autocorr_inflation`]'s.
pub fn inflation_of(r: &[f64], run: &[usize]) -> f64 {
    let var = r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64;
    if var <= 0.0 {
        return 1.0;
    }
    // Runs of equal `run` (consecutive samples of one run): pairs never cross them.
    let mut segs = Vec::new();
    let mut start = 0;
    for i in 1..=r.len() {
        if i == r.len() || run[i] != run[i - 1] {
            segs.push(start..i);
            start = i;
        }
    }
    // Lags in groups of four, summed in one pass so the four dependency chains
    // overlap (one chain per lag was 4 % of a diagnosis). Each lag's sum still
    // adds its products in increasing i, segment by segment, as one lag at a
    // time did, so the sums are the same bits.
    const LAGS: usize = 50;
    let mut tau = 1.0;
    let mut k0 = 1;
    while k0 <= LAGS {
        let lanes = (LAGS + 1 - k0).min(4);
        let (mut s, mut n) = ([0.0f64; 4], [0usize; 4]);
        let k_max = k0 + lanes - 1;
        for seg in &segs {
            let main = (seg.start + k_max).min(seg.end);
            for l in 0..lanes {
                let k = k0 + l;
                for i in (seg.start + k).min(main)..main {
                    s[l] += r[i] * r[i - k];
                }
                n[l] += seg.len().saturating_sub(k);
            }
            if lanes == 4 {
                for i in main..seg.end {
                    s[0] += r[i] * r[i - k0];
                    s[1] += r[i] * r[i - k0 - 1];
                    s[2] += r[i] * r[i - k0 - 2];
                    s[3] += r[i] * r[i - k0 - 3];
                }
            } else {
                for i in main..seg.end {
                    for l in 0..lanes {
                        s[l] += r[i] * r[i - k0 - l];
                    }
                }
            }
        }
        for l in 0..lanes {
            if n[l] == 0 {
                return tau;
            }
            let rho = s[l] / n[l] as f64 / var;
            if rho <= 0.0 {
                return tau;
            }
            tau += 2.0 * rho;
        }
        k0 += lanes;
    }
    tau
}

/// Per-run fit of the nuisance phase with the shared parameters fixed, for a
/// held-out run: the phase is free per run in the vocabulary, the rest is
/// not. The model is 1 + `amp`·sin(x_i + θ) of a target already divided by
/// every other factor of the law (level 1), `trig` the sin and cos of each
/// sample's argument x_i without the phase (2πf·t or n·φ1), computed once
/// by the caller: the Newton steps below add the phase by angle addition,
/// sin(x + θ) = sin x cos θ + cos x sin θ (a sin_cos per sample and step was
/// 3 % of a diagnosis), and the composite's alternation reuses them in
/// every round (`composite::heldout_phases`).
pub fn heldout_phase(target: &[f64], trig: &[(f64, f64)], amp: f64) -> f64 {
    if target.is_empty() {
        return 0.0;
    }
    let (mut ss, mut sc, mut cc, mut ys, mut yc) = (0.0, 0.0, 0.0, 0.0, 0.0);
    for (&mu, &(s, c)) in target.iter().zip(trig) {
        let y = mu - 1.0;
        ss += s * s;
        sc += s * c;
        cc += c * c;
        ys += y * s;
        yc += y * c;
    }
    let det = ss * cc - sc * sc;
    if det.abs() < 1e-12 {
        return 0.0;
    }
    let a = (ys * cc - yc * sc) / det;
    let b = (yc * ss - ys * sc) / det;
    let mut th = b.atan2(a);
    // A few Newton steps on the exact fixed-amplitude problem.
    for _ in 0..5 {
        let (mut g, mut h) = (0.0, 0.0);
        let (st, ct) = th.sin_cos();
        for (&mu, &(sx, cx)) in target.iter().zip(trig) {
            let (s, c) = (sx * ct + cx * st, cx * ct - sx * st);
            let e = mu - (1.0 + amp * s);
            let j = amp * c;
            g += j * e;
            h += j * j;
        }
        if h <= 0.0 {
            break;
        }
        th += g / h;
    }
    th.rem_euclid(2.0 * PI)
}

/// Relative RMS error of μ̂ against μ_obs on one run's slip samples:
/// sqrt(mean((μ̂ − μ_obs)²)) / mean(μ_obs). Dimensionless.
pub fn relative_mu_error(m: &FrictionModel, d: &SlipData, theta: f64) -> Option<f64> {
    relative_rms(&d.mu, |i| m.mu(d.t[i], d.phi[i], d.omega[i], theta))
}

/// The relative RMS error of `predicted(i)` against `mu[i]`:
/// sqrt(mean((μ̂ − μ_obs)²)) / |mean(μ_obs)| (floored at 1e-9); None for no
/// samples. The one home of e_μ (crate docs) for every law form.
pub fn relative_rms(mu: &[f64], predicted: impl Fn(usize) -> f64) -> Option<f64> {
    if mu.is_empty() {
        return None;
    }
    let n = mu.len() as f64;
    let mean = mu.iter().sum::<f64>() / n;
    let ms = (0..mu.len()).map(|i| (mu[i] - predicted(i)).powi(2)).sum::<f64>() / n;
    Some(ms.sqrt() / mean.abs().max(1e-9))
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
    fn synth(runs: usize, law: impl Fn(usize, f64, f64, f64) -> f64) -> SlipData {
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

    /// The folds' thinned slip samples (`fold_fit_spacing_s`): of each run
    /// the slip samples whose record index is a multiple of the spacing in
    /// samples, so they stay on a uniform grid and the frequency scan's FFT
    /// still takes them (the campaign's 0.05–10 Hz grid by 0.01 Hz at
    /// 16 ms); spacing 0 keeps every sample.
    #[test]
    fn thinned_slip_samples_stay_on_a_grid_the_fft_scan_takes() {
        let run = |r: usize| {
            let time_s: Vec<f64> = (0..20000).map(|k| k as f64 * 0.002).collect();
            // Slip 60 % of every second, starting at a different sample per run.
            let slip_idx: Vec<usize> = (0..time_s.len()).filter(|&k| ((k + 37 * r) % 500) < 300).collect();
            let mu_obs = slip_idx.iter().map(|&k| 0.4 + 0.01 * (k as f64 * 0.01).sin()).collect();
            RunSignals {
                id: format!("r{r}"),
                fold: r,
                setpoint_rad_s: 5.0,
                normal_force_n: 10.0,
                ramp_s: 2.0,
                rotor_angle_rad: time_s.clone(),
                rotor_speed_rad_s: vec![1.0; time_s.len()],
                motor_angle_rad: vec![],
                motor_speed_rad_s: vec![],
                voltage_v: vec![],
                friction_force_n: vec![],
                time_s,
                slip_idx,
                mu_obs,
                force_noise_n: 0.1,
                voltage_noise_v: 0.01,
                steady_from: 0,
                drive: Default::default(),
            }
        };
        let runs: Vec<RunSignals> = (0..3).map(run).collect();
        let refs: Vec<&RunSignals> = runs.iter().collect();
        let all = SlipData::from_runs(&refs);
        let none_dropped = SlipData::from_runs_spaced(&refs, 0.0);
        assert_eq!((all.t.clone(), all.mu.clone()), (none_dropped.t, none_dropped.mu));
        let thin = SlipData::from_runs_spaced(&refs, 0.016);
        let expected: usize = runs.iter().map(|s| s.slip_idx.iter().filter(|&&k| k % 8 == 0).count()).sum();
        assert_eq!(thin.len(), expected);
        assert!(thin.t.iter().all(|t| ((t / 0.016) - (t / 0.016).round()).abs() < 1e-9));
        let freqs: Vec<f64> = (0..=995).map(|j| 0.05 + 0.01 * j as f64).collect();
        assert!(time_scan_fft(&thin, &freqs).is_some(), "the thinned samples left the FFT's grid");
    }

    #[test]
    fn arrow_elimination_matches_the_dense_solve() {
        let mut d = synth(5, |r, t, _, _| 0.45 * (1.0 + 0.08 * (2.0 * PI * 0.9 * t + r as f64).sin()));
        for (r, w) in d.run_weight.iter_mut().enumerate() {
            *w = 1.0 + r as f64; // unequal run weights
        }
        let yy = ywy(&d);
        for f in [0.3, 0.9, 2.71] {
            let sc: Vec<(f64, f64)> = d.t.iter().map(|t| (2.0 * PI * f * t).sin_cos()).collect();
            let dense = sine_rss_from(&d, &sc, yy).unwrap().0;
            let fast = sine_rss_scan(&d, &sc, &ScanSums::of(&d));
            assert!((dense - fast).abs() <= 1e-9 * yy, "f = {f}: dense {dense} fast {fast}");
        }
    }

    /// The FFT scan gives the direct scan's RSS at every grid frequency, on
    /// slip samples with gaps (stick phases removed), runs that start at
    /// different times and weigh differently; and declines grids it cannot
    /// put on its bins or samples off a uniform time grid.
    #[test]
    fn fft_scan_matches_the_direct_sums() {
        let full = synth(3, |r, t, _, _| 0.45 * (1.0 + 0.08 * (2.0 * PI * 0.9 * t + r as f64).sin()));
        // Keep 60 % of each 1 s (slip phases), shift run r by 7.3·r s, weigh it 1 + r.
        let keep: Vec<usize> = (0..full.len()).filter(|&i| (full.t[i] % 1.0) < 0.6).collect();
        let mut d = SlipData {
            run: Arc::new(keep.iter().map(|&i| full.run[i]).collect()),
            t: Arc::new(keep.iter().map(|&i| full.t[i] + 7.3 * full.run[i] as f64).collect()),
            phi: Arc::new(keep.iter().map(|&i| full.phi[i]).collect()),
            omega: Arc::new(keep.iter().map(|&i| full.omega[i]).collect()),
            mu: keep.iter().map(|&i| full.mu[i]).collect(),
            run_weight: vec![1.0, 2.0, 3.0],
            n_runs: 3,
        };
        let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
        let fft = time_scan_fft(&d, &freqs).expect("uniform grid on the bins");
        let sums = ScanSums::of(&d);
        assert_eq!(fft.len(), freqs.len());
        for &(f, rss) in &fft {
            let sc: Vec<(f64, f64)> = d.t.iter().map(|t| (2.0 * PI * f * t).sin_cos()).collect();
            let direct = sine_rss_scan(&d, &sc, &sums);
            assert!((rss - direct).abs() <= 1e-12 * sums.ywy, "f = {f}: fft {rss} direct {direct}");
        }
        // The minimum is the modulation's frequency.
        let best = fft.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap().0;
        assert!((best - 0.9).abs() < 1e-9, "{best}");
        // A grid whose start is not a multiple of its step, and samples off the grid, are declined.
        let shifted: Vec<f64> = freqs.iter().map(|f| f + 0.003).collect();
        assert!(time_scan_fft(&d, &shifted).is_none());
        Arc::make_mut(&mut d.t)[5] += 0.3e-3;
        assert!(time_scan_fft(&d, &freqs).is_none());
    }

    #[test]
    fn stribeck_law_is_recovered() {
        let d = synth(4, |_, _, _, w| 0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64));
        let f = fit_stribeck(&d, false).unwrap();
        let FrictionModel::Stribeck { mu_k, mu_s, vs, .. } = f.model else { panic!() };
        assert!((mu_k - 0.4).abs() < 1e-3 && (mu_s - 0.6).abs() < 5e-3 && (vs - 2.0).abs() < 0.05, "{:?}", f.model);
        // The Coulomb baseline is much worse on the same data.
        assert!(fit_coulomb(&d).rss_w > 10.0 * f.rss_w);
    }

    #[test]
    fn viscous_law_is_recovered() {
        let d = synth(3, |_, _, _, w| 0.5 + 0.01 * w);
        let f = fit_viscous(&d).unwrap();
        let FrictionModel::Viscous { mu_k, c } = f.model else { panic!() };
        assert!((mu_k - 0.5).abs() < 1e-3 && (c - 0.01).abs() < 2e-4, "{:?}", f.model);
    }

    #[test]
    fn time_modulation_is_recovered_with_per_run_phases() {
        let d = synth(4, |r, t, _, _| 0.5 * (1.0 + 0.1 * (2.0 * PI * 1.37 * t + r as f64).sin()));
        let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
        let f = fit_sine(&d, true, &freqs, 1..=8).unwrap();
        let FrictionModel::TimeSine { mu_k, a, f_hz } = f.model else { panic!() };
        assert!((mu_k - 0.5).abs() < 1e-3 && (a - 0.1).abs() < 3e-3 && (f_hz - 1.37).abs() < 1e-3, "{:?}", f.model);
        for (r, th) in f.phases.iter().enumerate() {
            let e = (th - r as f64).rem_euclid(2.0 * PI);
            assert!(e.min(2.0 * PI - e) < 0.05, "run {r}: phase {th}");
        }
    }

    /// The rotation recurrence against `sin_cos` of every sample: two runs of
    /// 500 Hz samples with a stick gap, 60 s long, at the highest scanned
    /// frequency; and the recurrence is what computes them.
    #[test]
    fn time_sin_cos_matches_sin_cos_of_every_sample() {
        let mut d = SlipData { n_runs: 2, run_weight: vec![1.0, 1.0], ..Default::default() };
        for r in 0..2 {
            for k in 0..30_000 {
                if (10_000..10_400).contains(&k) {
                    continue; // stuck
                }
                Arc::make_mut(&mut d.run).push(r);
                Arc::make_mut(&mut d.t).push(3.0 + k as f64 / 500.0);
                Arc::make_mut(&mut d.phi).push(0.0);
                Arc::make_mut(&mut d.omega).push(1.0);
                d.mu.push(1.0);
            }
        }
        let mut out = Vec::new();
        for f_hz in [0.05, 1.9, 10.0] {
            let exact = time_sin_cos(&d, f_hz, &mut out);
            assert_eq!(out.len(), d.len());
            // The recurrence is taken: exact values only at re-syncs (the
            // step length of a NaN predecessor once never matched, so every
            // sample took sin_cos). 4 segments of ~15 000 samples.
            assert!(exact <= d.len() / RESYNC_EVERY + 8, "{exact} exact of {}", d.len());
            let worst = (0..d.len())
                .map(|i| {
                    let (s, c) = (2.0 * PI * f_hz * d.t[i]).sin_cos();
                    (out[i].0 - s).abs().max((out[i].1 - c).abs())
                })
                .fold(0.0, f64::max);
            // The drift bound of SinCosSchedule's docs, plus the rounding of sin_cos itself.
            let t_max = d.t.iter().copied().fold(0.0, f64::max);
            let bound = RESYNC_EVERY as f64 * 2.0 * PI * f_hz * 2.0 * t_max * f64::EPSILON + 1e-13;
            assert!(worst < bound, "f = {f_hz} Hz: worst |Δ| = {worst:e} against {bound:e}");
        }
    }

    /// The schedule, built once, visits the very numbers of the recurrence
    /// that tests each sample's step in turn (the loop it replaced, kept
    /// here as the reference): runs, a gap, jittered and changing steps.
    #[test]
    fn the_schedule_is_the_per_sample_recurrence_bit_for_bit() {
        let mut d = SlipData { n_runs: 3, run_weight: vec![1.0; 3], ..Default::default() };
        let mut t = 1.0;
        for r in 0..3 {
            for k in 0..3000 {
                let dt = if k > 2000 { 0.004 } else { 0.002 };
                t += if k == 700 { 0.3 } else { dt } + if k % 3 == 0 { 4e-16 } else { 0.0 };
                if (1200..1250).contains(&k) {
                    continue;
                }
                Arc::make_mut(&mut d.run).push(r);
                Arc::make_mut(&mut d.t).push(t);
                Arc::make_mut(&mut d.phi).push(0.0);
                Arc::make_mut(&mut d.omega).push(1.0);
                d.mu.push(1.0);
            }
        }
        let reference = |f_hz: f64| {
            let w = 2.0 * PI * f_hz;
            let (mut out, mut step, mut since) = (Vec::<(f64, f64)>::new(), (f64::NAN, (0.0, 1.0)), 0);
            for i in 0..d.len() {
                let dt = if i > 0 && d.run[i] == d.run[i - 1] { d.t[i] - d.t[i - 1] } else { f64::NAN };
                let same_step = (dt - step.0).abs() <= 1e-12;
                let v = if since + 1 < RESYNC_EVERY && same_step {
                    since += 1;
                    let (p, (sr, cr)) = (out[i - 1], step.1);
                    (p.0 * cr + p.1 * sr, p.1 * cr - p.0 * sr)
                } else {
                    since = 0;
                    if dt.is_finite() && !same_step {
                        step = (dt, (w * dt).sin_cos());
                    }
                    (w * d.t[i]).sin_cos()
                };
                out.push(v);
            }
            out
        };
        let schedule = SinCosSchedule::of(&d);
        assert!(schedule.steps_s.len() >= 2, "the steps change");
        for f_hz in [0.05, 1.37, 9.99] {
            let mut got = Vec::new();
            schedule.visit(&d.t, f_hz, |i, v| {
                assert_eq!(i, got.len(), "in sample order");
                got.push(v);
            });
            let bits = |v: &[(f64, f64)]| v.iter().map(|x| (x.0.to_bits(), x.1.to_bits())).collect::<Vec<_>>();
            assert_eq!(bits(&got), bits(&reference(f_hz)), "f = {f_hz} Hz");
        }
    }

    /// A single frequency or order (a warm start's, a later pass's) is not
    /// scanned: the fit is the one the scan reaches when it picks that
    /// candidate, bit for bit, and its one scan point is the RSS there.
    #[test]
    fn a_single_candidate_is_the_scanned_fit_at_it() {
        let bits = |f: &FrictionFit| {
            let mut v: Vec<u64> =
                f.phases.iter().chain(f.params.iter().flat_map(|p| [&p.1, &p.2])).map(|x| x.to_bits()).collect();
            v.push(f.rss_w.to_bits());
            (format!("{:?}", f.model), v, f.converged)
        };
        let d = synth(4, |r, t, _, _| 0.5 * (1.0 + 0.1 * (2.0 * PI * 1.37 * t + r as f64).sin()));
        let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
        let scanned = fit_sine(&d, true, &freqs, 1..=8).unwrap();
        let FrictionModel::TimeSine { .. } = scanned.model else { panic!() };
        let at = freqs[scanned.scan.iter().enumerate().min_by(|a, b| a.1.1.total_cmp(&b.1.1)).unwrap().0];
        assert!((at - 1.37).abs() < 0.006, "the scan's best {at}");
        let single = fit_sine(&d, true, &[at], 1..=8).unwrap();
        assert_eq!(bits(&single), bits(&scanned));
        let rss_scan = scanned.scan.iter().find(|p| p.0 == at).unwrap().1;
        assert!(single.scan.len() == 1 && (single.scan[0].1 - rss_scan).abs() <= 1e-9 * rss_scan, "{:?}", single.scan);

        let d = synth(3, |r, _, phi, _| 0.5 * (1.0 + 0.15 * (3.0 * phi + 0.5 * r as f64).sin()));
        let scanned = fit_sine(&d, false, &[], 1..=8).unwrap();
        let single = fit_sine(&d, false, &[], 3..=3).unwrap();
        assert_eq!(bits(&single), bits(&scanned));
        assert!(fit_sine(&d, false, &[], 0..=0).is_none(), "no order 0");
    }

    #[test]
    fn angle_order_is_recovered() {
        let d = synth(3, |r, _, phi, _| 0.5 * (1.0 + 0.15 * (3.0 * phi + 0.5 * r as f64).sin()));
        let f = fit_sine(&d, false, &[], 1..=8).unwrap();
        let FrictionModel::AngleSine { a, order, .. } = f.model else { panic!() };
        assert_eq!(order, 3);
        assert!((a - 0.15).abs() < 3e-3);
    }

    /// Runs whose angle amplitudes differ (0.02 … 0.48, 24 runs) against the one shared
    /// amplitude of the vocabulary: the residual keeps each run's sine, and
    /// Gauss–Newton alone crept along the phases for all 30 iterations. The
    /// fit converges, to a stationary point: no phase, amplitude or level
    /// moved by a small step (either sign) lowers the weighted RSS.
    #[test]
    fn unequal_run_amplitudes_converge_to_a_stationary_point() {
        let d = synth(24, |r, _, phi, _| 0.5 * (1.0 + 0.02 * (1 + r) as f64 * (3.0 * phi + 0.9 * r as f64).sin()));
        let f = fit_sine(&d, false, &[], 3..=3).unwrap();
        assert!(f.converged, "{:?}", f.params);
        let FrictionModel::AngleSine { mu_k, a, order } = f.model else { panic!() };
        let rss = |mk: f64, a: f64, ph: &[f64]| -> f64 {
            (0..d.len())
                .map(|i| {
                    let e = d.mu[i] - mk * (1.0 + a * (f64::from(order) * d.phi[i] + ph[d.run[i]]).sin());
                    d.w(i) * e * e
                })
                .sum()
        };
        let best = rss(mu_k, a, &f.phases);
        assert!((best - f.rss_w).abs() <= 1e-9 * best, "{best} vs {}", f.rss_w);
        for h in [1e-4, -1e-4] {
            assert!(rss(mu_k * (1.0 + h), a, &f.phases) >= best);
            assert!(rss(mu_k, a * (1.0 + h), &f.phases) >= best);
            for r in 0..d.n_runs {
                let mut ph = f.phases.clone();
                ph[r] += h;
                assert!(rss(mu_k, a, &ph) >= best, "run {r}, phase step {h}");
            }
        }
    }

    /// The grouped lags give the same bits as one lag at a time over every pair
    /// of samples of one run, on runs of different lengths (one shorter than
    /// the 50 lags) with correlated residuals.
    #[test]
    fn inflation_of_matches_one_lag_at_a_time() {
        let reference = |r: &[f64], run: &[usize]| -> f64 {
            let var = r.iter().map(|x| x * x).sum::<f64>() / r.len().max(1) as f64;
            let mut tau = 1.0;
            for k in 1..=50 {
                let (mut s, mut n) = (0.0, 0usize);
                for i in k..r.len() {
                    if run[i] == run[i - k] {
                        s += r[i] * r[i - k];
                        n += 1;
                    }
                }
                if n == 0 {
                    break;
                }
                let rho = s / n as f64 / var;
                if rho <= 0.0 {
                    break;
                }
                tau += 2.0 * rho;
            }
            tau
        };
        let mut seed = 3u64;
        for (lens, memory) in [(vec![700usize, 30, 1200], 0.97), (vec![400, 400], 0.5), (vec![20, 25], 0.99)] {
            let (mut r, mut run) = (Vec::new(), Vec::new());
            for (k, &len) in lens.iter().enumerate() {
                let mut x = 0.0;
                for _ in 0..len {
                    x = memory * x + noise(&mut seed);
                    r.push(x);
                    run.push(k);
                }
            }
            let (got, want) = (inflation_of(&r, &run), reference(&r, &run));
            assert_eq!(got.to_bits(), want.to_bits(), "{lens:?}: {got} vs {want}");
            assert!(got > 1.0);
        }
    }

    #[test]
    fn white_residuals_do_not_inflate() {
        let d = synth(2, |_, _, _, _| 0.5);
        let f = fit_coulomb(&d);
        let tau = autocorr_inflation(&d, &f.model, &[]);
        assert!(tau < 1.2, "τ = {tau}");
    }
}
