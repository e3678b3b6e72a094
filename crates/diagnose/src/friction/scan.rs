//! The sine models' linear scans: at each trial frequency (time kind) or
//! order (angle kind) the per-run regression μ = μk + A_r sin x + B_r cos x
//! (shared μk) is linear, so its weighted RSS is exact there — by an FFT of
//! the per-run sums where the slip samples lie on a uniform grid, else sample
//! by sample ([`time_scan`], `order_scan`) — and [`SinCosSchedule`], the sin
//! and cos of 2π f t by rotations between exact re-synchronisations, which the
//! Gauss–Newton of [`super::fit_sine`] and the composite evaluate per trial.
//! Split from `fit_sine` because the scan is the search's start and the
//! evidence figure's curve, with its own exactness tests.

use super::{SEARCH_EVERY, SlipData};
use rig_estimate::linear::ArrowNormal;
use std::f64::consts::PI;
use std::ops::RangeInclusive;

/// Per-run sine regression μ = μk + A_r sin x + B_r cos x (shared μk) for
/// given (sin x, cos x) per sample: (weighted RSS, solution). Linear, so the
/// scan is exact at each x. RSS = yᵀWy − pᵀJᵀWy at the solution.
pub(super) fn sine_rss_from(d: &SlipData, sc: &[(f64, f64)], ywy: f64) -> Option<(f64, Vec<f64>)> {
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

pub(super) fn ywy(d: &SlipData) -> f64 {
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
                    // Σ a e^{−jx} = e^{−j2πf t_ref}·X[m]: real part Σ a cos x, imaginary −Σ a sin x,
                    // (s, c) = sin and cos of 2πf·t_ref (the indicator's and μ's sums at f share them).
                    let at = |x: realfft::num_complex::Complex<f64>, (s, c): (f64, f64)| {
                        let re = x.re * c + x.im * s;
                        let im = x.im * c - x.re * s;
                        (-im, re)
                    };
                    let ref_at = |f: f64| (2.0 * PI * f * t_ref).sin_cos();
                    let at_f = ref_at(f);
                    let (s1, c1) = at(ind_f[m], at_f);
                    let (s2, c2) = at(ind_f[2 * m], ref_at(2.0 * f));
                    let (ys, yc) = at(val_f[m], at_f);
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
/// differences the scan ranks). sin/cos φ are order 1's of `angles`, the
/// memo of `d`'s, when given (1·φ is φ to the bit): every friction set with
/// a cold angle block scans the same fold's φ1 (a `sin_cos` of every sample
/// per scan, 0.44 % of the full battery's CPU in `perf`, issue 23).
pub(super) fn order_scan(d: &SlipData, orders: &RangeInclusive<u32>, angles: Option<&AngleTrig>) -> Vec<(f64, f64)> {
    let sums = ScanSums::of(d);
    let base: SinCos = match angles {
        Some(memo) => memo.get(d, 1),
        None => std::sync::Arc::new(d.phi.iter().map(|p| p.sin_cos()).collect()),
    };
    let mut sc = base.to_vec();
    let mut out = Vec::with_capacity(orders.clone().count());
    for n in 1..=*orders.end() {
        if n > 1 {
            for (v, b) in sc.iter_mut().zip(base.iter()) {
                *v = (v.0 * b.1 + v.1 * b.0, v.1 * b.1 - v.0 * b.0);
            }
        }
        if orders.contains(&n) {
            out.push((f64::from(n), sine_rss_scan(d, &sc, &sums)));
        }
    }
    out
}

/// sin and cos of n·φ1 of every sample of one data set, per order n, each
/// computed once: the angle sine's regressor at its order ([`super::fit_sine`]'s
/// start and Gauss–Newton, a held-out run's angle factor). A composite
/// with the angle modulation refits its angle block at the same order on
/// every pass (up to six) and in every friction set of a selection step
/// with it, on the same fold's training runs, and each fold's held-out runs
/// are refitted under every such set: each was a `sin_cos` of every sample
/// again (3.4 % of an angle-periodic ladder rung's CPU in `perf` in the
/// fits, 0.9 % in the held-out runs; issue 23). The same products
/// `f64::from(n) · φ1` and the same `sin_cos`, so the same bits. The memo
/// belongs to one data set: every `get` must pass the same `d` (or one
/// sharing its φ1).
#[derive(Debug, Default)]
pub(crate) struct AngleTrig {
    by_order: std::sync::Mutex<std::collections::BTreeMap<u32, SinCos>>,
}

/// (sin, cos) of every sample, shared.
type SinCos = std::sync::Arc<Vec<(f64, f64)>>;

impl AngleTrig {
    /// (sin, cos) of n·φ1 of every sample of `d`, computed the first time.
    pub(crate) fn get(&self, d: &SlipData, n: u32) -> SinCos {
        if let Some(v) = self.by_order.lock().expect("angle trig").get(&n) {
            return v.clone();
        }
        let v = std::sync::Arc::new(angle_sin_cos(d, f64::from(n)));
        self.by_order.lock().expect("angle trig").entry(n).or_insert(v).clone()
    }
}

/// (sin, cos) of ψ·φ1 of every sample of `d` (ψ an order).
pub(crate) fn angle_sin_cos(d: &SlipData, psi: f64) -> Vec<(f64, f64)> {
    d.phi.iter().map(|p| (psi * p).sin_cos()).collect()
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
        for (i, v) in self.iter(t, f_hz).enumerate() {
            f(i, v);
        }
    }

    /// (sin, cos) of 2π f t_i for every sample in order, as an iterator: the
    /// numbers [`SinCosSchedule::visit`] passes, for a loop that keeps its
    /// sums in registers (a closure `visit` does not inline sums through a
    /// captured `&mut` in memory, one store and reload per sample).
    pub(crate) fn iter<'a>(&'a self, t: &'a [f64], f_hz: f64) -> ScheduleIter<'a> {
        let w = 2.0 * PI * f_hz;
        let rot = self.steps_s.iter().map(|dt| (w * dt).sin_cos()).collect();
        ScheduleIter { segments: self.segments.iter(), t, w, rot, v: (0.0, 1.0), r: (0.0, 1.0), left: 0 }
    }
}

/// [`SinCosSchedule::iter`]: an exact `sin_cos` at each segment's first
/// sample, then `left` rotations by `r`, the segment's step.
pub(crate) struct ScheduleIter<'a> {
    segments: std::slice::Iter<'a, (usize, usize, usize)>,
    t: &'a [f64],
    w: f64,
    rot: Vec<(f64, f64)>,
    v: (f64, f64),
    r: (f64, f64),
    left: usize,
}

impl Iterator for ScheduleIter<'_> {
    type Item = (f64, f64);

    #[inline]
    fn next(&mut self) -> Option<(f64, f64)> {
        if self.left > 0 {
            self.left -= 1;
            let ((s, c), (sr, cr)) = (self.v, self.r);
            self.v = (s * cr + c * sr, c * cr - s * sr);
            return Some(self.v);
        }
        let &(start, len, step) = self.segments.next()?;
        self.v = (self.w * self.t[start]).sin_cos();
        self.left = len - 1;
        if len > 1 {
            self.r = self.rot[step];
        }
        Some(self.v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::friction::tests::synth;
    use crate::prepare::RunSignals;
    use std::sync::Arc;

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

    /// The order scan from the data's memo (its order 1, 1·φ1) is the scan
    /// by its own `sin_cos` of every φ1, to the bit, whether the memo is
    /// filled by the scan or before it.
    #[test]
    fn the_order_scan_from_the_memo_is_the_scan_alone() {
        let d = synth(3, |r, _, phi, _| 0.45 * (1.0 + 0.1 * (3.0 * phi + 0.5 * r as f64).sin()));
        let bits = |v: Vec<(f64, f64)>| v.iter().map(|x| (x.0.to_bits(), x.1.to_bits())).collect::<Vec<_>>();
        let alone = bits(order_scan(&d, &(1..=8), None));
        let memo = AngleTrig::default();
        assert_eq!(bits(order_scan(&d, &(1..=8), Some(&memo))), alone);
        assert_eq!(bits(order_scan(&d, &(2..=8), Some(&memo))), bits(order_scan(&d, &(2..=8), None)));
        assert_eq!(bits(order_scan(&d, &(1..=8), Some(&memo))), alone);
        let own: Vec<(f64, f64)> = d.phi.iter().map(|p| p.sin_cos()).collect();
        assert_eq!(bits(memo.get(&d, 1).to_vec()), bits(own));
        // The scan finds the order.
        let scan = order_scan(&d, &(1..=8), None);
        assert_eq!(scan.iter().min_by(|a, b| a.1.total_cmp(&b.1)).unwrap().0, 3.0, "{scan:?}");
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
}
