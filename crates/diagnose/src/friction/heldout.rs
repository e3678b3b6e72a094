//! What the held-out side of a fold needs: the variance inflation of
//! correlated residuals ([`autocorr_inflation`], [`inflation_of`]), a
//! held-out run's own phase of a fitted modulation ([`heldout_phase`], since a
//! phase is per run and cannot be carried over from training), and the
//! relative RMS error e_μ of a prediction ([`relative_mu_error`],
//! [`relative_rms`]; crate docs).

use super::{FrictionModel, SlipData};
use std::f64::consts::PI;

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
mod tests {
    use super::*;
    use crate::friction::fit_coulomb;
    use crate::friction::tests::{noise, synth};

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
