//! The PI gains at a fixed voltage limit: the (kp, ki) that minimise the
//! voltage RSS of the clamped, teacher-forced PI model ([`super::visit`])
//! over every sample, by Levenberg–Marquardt on the exact forward
//! sensitivities of the clamped recursion (issue 23).
//!
//! # The model and its sensitivities
//!
//! The thesis states the PI loop in words only (§4.1: "a PI control ... to
//! keep constant the angular velocity of the DC-motor"); the law is
//! rig-model's drive (its module docs, "Drive"): u_k = kp·e_k + ki·I_k,
//! V̂_k = clamp(u_k, ±Vmax), I_{k+1} = I_k + dt_k·(e_k + (V̂_k − u_k)/(ki·T_t)),
//! e = Ω_ref − Ω2 from the measured motor speed, T_t =
//! `rig_model::ANTI_WINDUP_TRACKING_S`. With s_k = ∂I_k/∂(kp, ki) (s_0 = 0):
//! ∂u_k = (e_k, I_k) + ki·s_k; where the clamp is idle ∂V̂_k = ∂u_k and
//! s_{k+1} = s_k (the rate is e, whatever the gains); where it acts ∂V̂_k = 0
//! and s_{k+1} = s_k − dt_k·(∂u_k/(ki·T_t) + (V̂_k − u_k)/(ki²·T_t)·(0, 1)).
//! One pass over a clamping run gives its SSE, JᵀJ and Jᵀr together; a run
//! the gains do not clamp is linear in them, and its JᵀJ and Jᵀr are its
//! closed form's totals ([`super::Prepared`]). The RSS is piecewise smooth
//! (a sample entering or leaving the clamp is a kink), and the
//! sensitivities are those of the piece the gains are on.
//!
//! # The solver and its stop rule
//!
//! Levenberg–Marquardt with Marquardt's scaling (the step solves
//! (JᵀJ + λ·diag JᵀJ)·δ = Jᵀr by `rig_types::linear`'s [`Normal`]; λ from
//! 10⁻³, Nielsen's update, `rig_estimate::lsq::Damping` (the one home of it): × max(1/3,
//! 1 − (2ρ − 1)³) on an accepted step, ρ the RSS decrease over the linear
//! model's, × ν on a rejected one, ν doubling). It stops when (1) the
//! undamped Gauss–Newton step is within a tenth of a standard error of the
//! local model's minimum (`crate::friction::near_stationary`, the
//! workspace's Gauss–Newton stop rule; RSS in noise units, σ² = RSS/(n −
//! 2)): that step is taken if it lowers the RSS, and the fit ends either
//! way (a step that raises it crossed a kink within that tenth); (2) an accepted step lowers the RSS by less than
//! [`FTOL`] of itself, or a step is below [`XTOL`] of the gains (MINPACK's
//! `ftol` and `xtol` tests, Moré, Garbow & Hillstrom, *User Guide for
//! MINPACK-1*, 1980, §2.3, as `rig_estimate::lsq::SolverOptions` states
//! them); (3) after [`MAX_ITERATIONS`] (`converged: false`, data). The
//! returned gains are the lowest-RSS point evaluated, so the fit's RSS is
//! never above its start's.

use super::{Pi, Recording, idle_sse, visit};
use crate::friction::near_stationary;
use rig_estimate::linear::Normal;
use rig_estimate::lsq::Damping;

/// Relative RSS decrease of an accepted step below which the fit stops.
pub(super) const FTOL: f64 = 1e-12;
/// Step size, relative to the gains' norm, below which the fit stops.
pub(super) const XTOL: f64 = 1e-12;
/// Iterations (accepted or rejected steps) after which the fit stops unconverged.
pub(super) const MAX_ITERATIONS: usize = 40;

/// A gains fit at one limit: the gains, their RSS (noise units, as
/// [`super::rss_of`]), the RSS evaluations it took and whether a stop rule met.
#[derive(Debug, Clone, Copy)]
pub(super) struct GainsFit {
    pub pi: Pi,
    pub rss: f64,
    /// Read by the tests.
    #[allow(dead_code)]
    pub evaluations: usize,
    #[allow(dead_code)]
    pub converged: bool,
}

/// The RSS, JᵀWJ (row-major 2 × 2) and JᵀWr (r = V − V̂) of every run at `pi`,
/// each run weighted by 1/σ_V², and the sample count.
pub(super) fn normal_at(pi: &Pi, runs: &[Recording]) -> (f64, Normal, usize) {
    let (mut rss, mut a, mut b, mut n) = (0.0, [0.0; 3], [0.0; 2], 0);
    let (kp, ki) = (pi.kp_v_s_rad, pi.ki_v_rad);
    for r in runs {
        let w = 1.0 / r.voltage_noise_v.max(1e-6).powi(2);
        n += r.p.e_rad_s.len();
        let (sse, ra, rb) = if r.p.idle(pi) {
            let s = r.p.cum.last().expect("cum[0]");
            (idle_sse(pi, s), [s[0], s[1], s[2]], [s[3] - kp * s[0] - ki * s[1], s[4] - kp * s[1] - ki * s[2]])
        } else {
            clamped_normal(pi, r)
        };
        rss += w * sse;
        for (x, y) in a.iter_mut().zip(ra) {
            *x += w * y;
        }
        for (x, y) in b.iter_mut().zip(rb) {
            *x += w * y;
        }
    }
    (rss, Normal::from_row_major(2, &[a[0], a[1], a[1], a[2]], b.to_vec()), n)
}

/// One clamping run's SSE, JᵀJ (upper triangle: kp·kp, kp·ki, ki·ki) and Jᵀr
/// by the recursion ([`visit`], so V̂ to the bit of [`super::run_sse`]) with
/// its sensitivities (module docs).
fn clamped_normal(pi: &Pi, r: &Recording) -> (f64, [f64; 3], [f64; 2]) {
    let (kp, ki) = (pi.kp_v_s_rad, pi.ki_v_rad);
    let tt = rig_model::ANTI_WINDUP_TRACKING_S;
    let no_windup = ki.abs() < 1e-9;
    let dt_s = &r.p.dt_s;
    let (mut sse, mut a, mut b) = (0.0, [0.0; 3], [0.0; 2]);
    let mut s = [0.0f64; 2];
    visit(pi, r, |k, e, v_hat, i, sat| {
        let res = r.voltage_v[k] - v_hat;
        sse += res * res;
        let du = [e + ki * s[0], i + ki * s[1]];
        if !sat {
            a[0] += du[0] * du[0];
            a[1] += du[0] * du[1];
            a[2] += du[1] * du[1];
            b[0] += du[0] * res;
            b[1] += du[1] * res;
        } else if !no_windup && k < dt_s.len() {
            let u = kp * e + ki * i;
            let c = dt_s[k] / (ki * tt);
            s[0] -= c * du[0];
            s[1] -= c * (du[1] + (v_hat - u) / ki);
        }
    });
    (sse, a, b)
}

/// The gains minimising the voltage RSS at `limit_v` from `start`'s gains
/// (its own limit replaced), calling `visited` with every gains pair
/// evaluated (accepted or not). `None` when the start's RSS is not finite.
pub(super) fn fit_gains_lm(
    runs: &[Recording],
    limit_v: f64,
    start: &Pi,
    mut visited: impl FnMut(&Pi),
) -> Option<GainsFit> {
    let mut pi = Pi { limit_v, ..*start };
    visited(&pi);
    let (mut rss, mut ne, n) = normal_at(&pi, runs);
    if !rss.is_finite() {
        return None;
    }
    let mut evaluations = 1;
    let mut damping = Damping::new(1e-3);
    let mut converged = false;
    while !converged && evaluations < MAX_ITERATIONS {
        let gn = ne.solve();
        let near = gn.as_ref().is_some_and(|step| near_stationary(step, &ne, rss, n));
        let step = if near {
            gn
        } else {
            let d = [ne.ata[(0, 0)], ne.ata[(1, 1)]].map(|x| damping.lambda * x.max(1e-12 * (1.0 + x)));
            let damped = [ne.ata[(0, 0)] + d[0], ne.ata[(0, 1)], ne.ata[(1, 0)], ne.ata[(1, 1)] + d[1]];
            Normal::from_row_major(2, &damped, ne.atb.clone()).solve()
        };
        let Some(step) = step else {
            damping.refuse();
            evaluations += 1;
            continue;
        };
        let norm = pi.kp_v_s_rad.hypot(pi.ki_v_rad);
        if step[0].hypot(step[1]) <= XTOL * (norm + XTOL) {
            converged = true;
            break;
        }
        let trial = Pi { kp_v_s_rad: pi.kp_v_s_rad + step[0], ki_v_rad: pi.ki_v_rad + step[1], limit_v };
        visited(&trial);
        let (t_rss, t_ne, _) = normal_at(&trial, runs);
        evaluations += 1;
        if t_rss < rss {
            // The gain ratio: the decrease against the linear model's,
            // 2δᵀJᵀr − δᵀJᵀJδ (RSS = Σ w r², not ½ of it).
            let a_step = [
                ne.ata[(0, 0)] * step[0] + ne.ata[(0, 1)] * step[1],
                ne.ata[(1, 0)] * step[0] + ne.ata[(1, 1)] * step[1],
            ];
            let pred = 2.0 * (step[0] * ne.atb[0] + step[1] * ne.atb[1]) - (step[0] * a_step[0] + step[1] * a_step[1]);
            let rho = if pred > 0.0 { (rss - t_rss) / pred } else { 0.0 };
            converged = near || (rss - t_rss) < FTOL * rss;
            (pi, rss, ne) = (trial, t_rss, t_ne);
            damping.accept(rho);
        } else if near {
            // The Gauss–Newton step to within a tenth of a standard error
            // crossed a kink (a sample entering or leaving the clamp) and
            // did not pay: the gains are already that close to the piece's
            // minimum, and the damped steps would crawl along the kink.
            converged = true;
        } else {
            damping.refuse();
        }
    }
    Some(GainsFit { pi, rss, evaluations, converged })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::drive::tests::runs;
    use crate::drive::{fit_gains, fit_gains_from, rss_of};
    use crate::prepare::RunSignals;

    /// The gradient in standard errors: |∂RSS/∂θ_j| · se_j / (2σ²), se_j =
    /// √(σ²·(JᵀJ)⁻¹_jj), σ² = RSS/(n − 2), the larger of the two (by central
    /// differences of the recursion's RSS, [`rss_of`], steps of 10⁻⁴ of a
    /// standard error): for a quadratic RSS, the distance to its minimum
    /// along θ_j in standard errors; ≈ 0 at a minimum.
    fn gradient_in_se(pi: &Pi, rec: &[Recording]) -> f64 {
        let (rss, ne, n) = normal_at(pi, rec);
        let var = rss / (n - 2) as f64;
        let inv = ne.inverse().expect("JᵀJ regular");
        (0..2)
            .map(|j| {
                let se = (var * inv[3 * j]).sqrt();
                let h = 1e-4 * se;
                let at = |d: f64| {
                    let mut p = *pi;
                    if j == 0 {
                        p.kp_v_s_rad += d;
                    } else {
                        p.ki_v_rad += d;
                    }
                    rss_of(&p, rec).0
                };
                ((at(h) - at(-h)) / (2.0 * h)).abs() * se / (2.0 * var)
            })
            .fold(0.0, f64::max)
    }

    /// At several trial limits of a record clipped at 5 V, below, at and
    /// above the clip, the fit from the unlimited gains reaches an RSS no
    /// higher than the eight alternation passes from the same start (the
    /// fit the limit search used before, [`fit_gains_from`]), and its
    /// gradient is ≈ 0 (below a tenth of the noise variance per standard
    /// error) where the passes' is not at one limit at least; its RSS
    /// is the recursion's ([`rss_of`]) to the bit.
    #[test]
    fn the_fit_is_stationary_and_no_worse_than_the_passes() {
        let limited = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 2.0, 3.0]);
        let r: Vec<&RunSignals> = limited.iter().collect();
        let rec = Recording::all(&r);
        let p0 = fit_gains(&r, 24.0).expect("unlimited fit");
        let mut passes_off = 0.0f64;
        for l in [4.2, 4.6, 4.8, 5.0, 5.2, 6.0, 24.0] {
            let fit = fit_gains_lm(&rec, l, &p0, |_| {}).expect("fit");
            let old = fit_gains_from(&rec, l, Some(&p0)).expect("passes");
            let old_rss = rss_of(&old, &rec).0;
            assert_eq!(fit.rss.to_bits(), rss_of(&fit.pi, &rec).0.to_bits(), "limit {l}");
            assert!(fit.rss <= old_rss, "limit {l}: {} > {old_rss} of the passes", fit.rss);
            assert!(fit.converged, "limit {l}: {fit:?}");
            let g = gradient_in_se(&fit.pi, &rec);
            assert!(g < 0.1, "limit {l}: gradient {g} se at {:?}", fit.pi);
            passes_off = passes_off.max(gradient_in_se(&old, &rec));
        }
        assert!(passes_off > 1.0, "the passes' largest gradient {passes_off}: the check cannot tell");
    }

    /// The sensitivities are the recursion's derivatives: JᵀJ and Jᵀr from
    /// [`normal_at`] at clamping gains (ki small enough for the windup
    /// term to matter) match those of the central differences of V̂ to 10⁻⁵.
    #[test]
    fn the_sensitivities_are_the_recursions_derivatives() {
        let limited = runs(Pi { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 5.0 }, &[1.0, 3.0]);
        for s in &limited {
            let rec = vec![Recording::of(s)];
            for pi in [
                Pi { kp_v_s_rad: 2.2, ki_v_rad: 9.0, limit_v: 4.5 },
                Pi { kp_v_s_rad: 1.5, ki_v_rad: 0.8, limit_v: 3.0 },
            ] {
                let (_, ne, _) = normal_at(&pi, &rec);
                let v_at = |dkp: f64, dki: f64| {
                    let p = Pi { kp_v_s_rad: pi.kp_v_s_rad + dkp, ki_v_rad: pi.ki_v_rad + dki, ..pi };
                    let mut v = Vec::new();
                    visit(&p, &rec[0], |_, _, vk, _, _| v.push(vk));
                    v
                };
                let h = 1e-6;
                let cols: Vec<Vec<f64>> = [(h, 0.0), (0.0, h)]
                    .iter()
                    .map(|&(a, b)| {
                        let (up, dn) = (v_at(a, b), v_at(-a, -b));
                        up.iter().zip(&dn).map(|(u, d)| (u - d) / (2.0 * h)).collect()
                    })
                    .collect();
                let v0 = v_at(0.0, 0.0);
                let res: Vec<f64> = s.voltage_v.iter().zip(&v0).map(|(v, vh)| v - vh).collect();
                let w = 1.0 / s.voltage_noise_v.powi(2);
                let dot = |a: &[f64], b: &[f64]| w * a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
                let fd_a = [dot(&cols[0], &cols[0]), dot(&cols[0], &cols[1]), dot(&cols[1], &cols[1])];
                let fd_b = [dot(&cols[0], &res), dot(&cols[1], &res)];
                let got_a = [ne.ata[(0, 0)], ne.ata[(0, 1)], ne.ata[(1, 1)]];
                for (g, f) in got_a.iter().zip(fd_a).chain(ne.atb.iter().zip(fd_b)) {
                    let scale = fd_a[0].abs().max(fd_a[2].abs()).sqrt() * res.iter().map(|x| x * x).sum::<f64>().sqrt();
                    assert!((g - f).abs() <= 1e-5 * f.abs().max(scale * w.sqrt()), "{pi:?}: {g} vs {f}");
                }
            }
        }
    }
}
