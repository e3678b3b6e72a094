//! The sine models' fit ([`fit_sine`]): μ = μk·(1 + a·sin(2π f t + θ_r))
//! (time kind) or μk·(1 + a·sin(n φ1 + θ_r)) (angle kind), the diagnosis
//! vocabulary's time- and angle-periodic modulations of Eq. 4-10's μ, with
//! shared (μk, a[, f]) and one phase θ_r per run: the scan (`scan.rs`) picks
//! the start, then Newton / Gauss–Newton steps with the stop rule and line
//! search of `line_search.rs`.

use super::line_search::{LineStart, near_stationary};
use super::scan::{AngleTrig, SinCosSchedule, angle_sin_cos, order_scan, sine_rss_from, time_scan, ywy};
use super::{FrictionFit, FrictionModel, SlipData};
use rig_estimate::linear::{ArrowNormal, Normal};
use std::f64::consts::PI;
use std::ops::RangeInclusive;
use std::sync::Arc;

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
    fit_sine_with(d, time_kind, freqs_hz, orders, None)
}

/// [`fit_sine`] reading the angle kind's sin and cos of n·φ1 from `angles`,
/// the memo of `d`'s ([`AngleTrig`]; the same numbers, so the same fit).
pub(crate) fn fit_sine_with(
    d: &SlipData,
    time_kind: bool,
    freqs_hz: &[f64],
    orders: RangeInclusive<u32>,
    angles: Option<&AngleTrig>,
) -> Option<FrictionFit> {
    if d.is_empty() {
        return None;
    }
    // Frequency parameters before the per-run phases: f (time kind) or none.
    let nf = usize::from(time_kind);
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
        None => order_scan(d, &orders, angles),
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
    let sc0: Arc<Vec<(f64, f64)>> = match (&schedule, angles) {
        (Some(sch), _) => {
            let mut base = Vec::with_capacity(d.len());
            sch.visit(&d.t, psi0, |_, v| base.push(v));
            Arc::new(base)
        }
        // ψ0 is an order (the scan's points and a single candidate are f64::from(n)).
        (None, Some(memo)) => memo.get(d, psi0 as u32),
        (None, None) => Arc::new(angle_sin_cos(d, psi0)),
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
        match &schedule {
            Some(sch) => phase_rss(sch.iter(&d.t, th[2]), d, &w, &trig, th, sc),
            None => phase_rss(sc0.iter().copied(), d, &w, &trig, th, sc),
        }
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

/// The weighted RSS of μk(1 + a sin(x + θ_r)) at `th` = [μk, a, …], given
/// (sin x, cos x) per sample in sample order (`base`) and (sin θ_r, cos θ_r)
/// per run (`trig`), leaving sin and cos of x + θ_r in `sc` (angle
/// addition). One loop with the sum in a register: the same operations in
/// the same order as a closure per sample, which did not inline and kept the
/// sum in memory (issue 23).
fn phase_rss(
    base: impl Iterator<Item = (f64, f64)>,
    d: &SlipData,
    w: &[f64],
    trig: &[(f64, f64)],
    th: &[f64],
    sc: &mut [(f64, f64)],
) -> f64 {
    let (mk, a) = (th[0], th[1]);
    let mut rss = 0.0;
    for ((((sx, cx), out), (&r, &mu)), &w) in base.zip(sc.iter_mut()).zip(d.run.iter().zip(&d.mu)).zip(w) {
        let (st, ct) = trig[r];
        let v = (sx * ct + cx * st, cx * ct - sx * st);
        *out = v;
        let e = mu - mk * (1.0 + a * v.0);
        rss += w * e * e;
    }
    rss
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::friction::tests::synth;

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
}
