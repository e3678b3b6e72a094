//! The composite's joint block: the speed law μ_speed(Ω) and the time
//! modulation 1 + a_t sin(2π f t + θ_t,r) refined together by Gauss–Newton
//! on all their parameters and the per-run phases (`refine_speed_time`; the
//! product law of Eq. 4-10 the module docs state), with its arrow-shaped
//! normal matrix and the parameters and standard errors it reports. Its own
//! file because it is the composite's one joint solve, with the test that it
//! reaches a stationary point where alternating the blocks did not.

use super::{Composite, Term};
use crate::friction::{self, SlipData};
use rig_estimate::linear::{ArrowNormal, Normal};
use std::f64::consts::PI;

/// The speed law and the time modulation refined together: Gauss–Newton on
/// every parameter of `μ_speed(Ω)·(1 + a sin(2π f t + θ_t,r))` at once — μk,
/// (Δ = μs − μk, vs) of the Stribeck term, c of the viscous one, a, f and one
/// phase per run — on `d` (the target already divided by the angle factor),
/// started from `m` and `phases` (the block fits' values). Alternating the two
/// blocks instead converged linearly: a time modulation shifts the mean μ of
/// the slip phases, which the speed law then re-absorbs, and five or six
/// passes of Brent's search for vs and a time-sine fit each were needed on
/// the emulated campaign (replacing them took the diagnosis stage from 17.4
/// to 12.3 s of CPU). The joint step
/// sees the coupling and converges in a few iterations to the same stationary
/// point. Returns the refined law, the phases, the weighted RSS, the normal
/// matrix at the end (joint covariance) and whether it converged; `None` if
/// the normal matrix is singular at the start.
pub(super) fn refine_speed_time(
    d: &SlipData,
    m: &Composite,
    phases: &[f64],
    stribeck: bool,
    viscous: bool,
) -> Option<(Composite, Vec<f64>, f64, Normal, bool)> {
    let (a0, f0) = m.time_mod?;
    if stribeck != m.stribeck.is_some() {
        return None;
    }
    // Parameter layout: μk, [Δ, vs], [c], a, f, θ_0..θ_{R−1}.
    let i_c = 1 + 2 * usize::from(stribeck);
    let i_a = i_c + usize::from(viscous);
    let (i_f, i_p) = (i_a + 1, i_a + 2);
    let mut theta = vec![m.mu_k];
    if let Some((mu_s, vs)) = m.stribeck {
        theta.extend([mu_s - m.mu_k, vs]);
    }
    if viscous {
        theta.push(m.viscous.unwrap_or(0.0));
    }
    theta.extend([a0, f0]);
    theta.extend_from_slice(phases);
    let speed = |th: &[f64], g: f64, w: f64| {
        let mut s = th[0];
        if stribeck {
            s += th[1] * g;
        }
        if viscous {
            s += th[i_c] * w;
        }
        s
    };
    // Per sample at `th`: g = exp(−(Ω/vs)²) and (sin, cos) of 2π f t + θ_r; returns the RSS.
    // sin/cos of 2π f t by the schedule's rotations (friction::SinCosSchedule),
    // visited in sample order in the same pass.
    let schedule = friction::SinCosSchedule::of(d);
    let eval = |th: &[f64], g: &mut Vec<f64>, sc: &mut Vec<(f64, f64)>| -> f64 {
        if stribeck && th[2] <= 0.0 {
            return f64::INFINITY;
        }
        let trig: Vec<(f64, f64)> = th[i_p..].iter().map(|t| t.sin_cos()).collect();
        g.resize(d.len(), 0.0);
        sc.resize(d.len(), (0.0, 0.0));
        let mut rss = 0.0;
        // A loop over the schedule's iterator, not a closure per sample: the sum stays in a register.
        for (i, (sx, cx)) in schedule.iter(&d.t, th[i_f]).enumerate() {
            let gi = if stribeck { rig_model::friction::stribeck_decay(d.omega[i], th[2]) } else { 0.0 };
            let (st, ct) = trig[d.run[i]];
            let v = (sx * ct + cx * st, cx * ct - sx * st);
            let e = d.mu[i] - speed(th, gi, d.omega[i]) * (1.0 + th[i_a] * v.0);
            rss += d.w(i) * e * e;
            g[i] = gi;
            sc[i] = v;
        }
        rss
    };
    let (mut g, mut sc) = (Vec::with_capacity(d.len()), Vec::with_capacity(d.len()));
    let (mut g_cand, mut sc_cand) = (Vec::with_capacity(d.len()), Vec::with_capacity(d.len()));
    let mut rss = eval(&theta, &mut g, &mut sc);
    let mut converged = false;
    let mut ne_last = None;
    let mut start = friction::LineStart::default();
    // Each accepted iteration's realised RSS decrease (the crawl rule, `friction::crawling`).
    let mut gains = Vec::new();
    for _ in 0..30 {
        // Columns 0..i_p shared, the sample's run's phase its block: an arrow
        // (ArrowNormal: the sums add_sparse would make, bit for bit).
        let row = |i: usize, row: &mut [f64; 6]| {
            let (w, t, gi, (s, c)) = (d.omega[i], d.t[i], g[i], sc[i]);
            let sp = speed(&theta, gi, w);
            let tf = 1.0 + theta[i_a] * s;
            let sw = d.w(i).sqrt();
            let e = d.mu[i] - sp * tf;
            let mut put = |j: usize, v: f64| row[j] = sw * v;
            put(0, tf);
            if stribeck {
                let vs = theta[2];
                put(1, gi * tf);
                put(2, theta[1] * gi * 2.0 * w * w / (vs * vs * vs) * tf);
            }
            if viscous {
                put(i_c, w * tf);
            }
            put(i_a, sp * s);
            let phase_rate = sp * theta[i_a] * c;
            put(i_f, phase_rate * 2.0 * PI * t);
            (d.run[i], sw * phase_rate, sw * e)
        };
        let ne = match i_p {
            3 => arrow_rows::<3>(d, &row),
            4 => arrow_rows::<4>(d, &row),
            5 => arrow_rows::<5>(d, &row),
            _ => arrow_rows::<6>(d, &row),
        };
        let Some(step) = ne.solve() else {
            // Singular at the start: no joint step (the caller keeps the block fits).
            ne_last.as_ref()?;
            break;
        };
        let near = friction::near_stationary(&step, &ne, rss, d.len());
        ne_last = Some(ne);
        let mut improved = false;
        let mut lambda = start.lambda;
        for _ in 0..12 {
            let cand: Vec<f64> = theta.iter().zip(&step).map(|(t, s)| t + lambda * s).collect();
            let r2 = eval(&cand, &mut g_cand, &mut sc_cand);
            if r2 <= rss {
                let rel = (rss - r2) / rss.max(f64::MIN_POSITIVE);
                gains.push(rss - r2);
                theta = cand;
                rss = r2;
                std::mem::swap(&mut g, &mut g_cand);
                std::mem::swap(&mut sc, &mut sc_cand);
                improved = true;
                start.accepted(lambda);
                converged = rel < 1e-10;
                break;
            }
            lambda *= 0.5;
        }
        if !improved || near || friction::crawling(&gains, rss, d.len(), theta.len()) {
            converged = true;
        }
        if converged {
            break;
        }
    }
    // Canonical sign: a ≥ 0 (a negative amplitude is a phase shift of π).
    if theta[i_a] < 0.0 {
        theta[i_a] = -theta[i_a];
        for th in theta[i_p..].iter_mut() {
            *th += PI;
        }
    }
    let phases = theta[i_p..].iter().map(|th| th.rem_euclid(2.0 * PI)).collect();
    let out = Composite {
        mu_k: theta[0],
        stribeck: stribeck.then(|| (theta[0] + theta[1], theta[2])),
        viscous: viscous.then(|| theta[i_c]),
        time_mod: Some((theta[i_a], theta[i_f])),
        angle_mod: m.angle_mod,
    };
    Some((out, phases, rss, ne_last?, converged))
}

/// The normal equations of [`refine_speed_time`]'s rows: `row(i, buf)` puts
/// sample i's `K` shared columns in `buf` and returns (its run, its phase
/// column, its target); an arrow with `K` a constant ([`ArrowNormal`]).
fn arrow_rows<const K: usize>(d: &SlipData, row: &impl Fn(usize, &mut [f64; 6]) -> (usize, f64, f64)) -> Normal {
    let mut arrow = ArrowNormal::<K, 1>::new(d.n_runs);
    let mut buf = [0.0; 6];
    for i in 0..d.len() {
        let (r, phase, y) = row(i, &mut buf);
        let shared: &[f64; K] = buf[..K].try_into().expect("K ≤ 6 shared columns");
        arrow.add(shared, r, &[phase], y);
    }
    arrow.into_normal()
}

/// The parameters of [`refine_speed_time`]'s fit with their joint standard
/// errors (σ²(JᵀJ)⁻¹ at the optimum, marginal over every other parameter of
/// the block, including the phases), in the order the block fits list them.
pub(super) fn joint_params(m: &Composite, ne: &Normal, rss: f64, n: usize) -> Vec<(Term, &'static str, f64, f64)> {
    let np = ne.n;
    let var = rss / (n.saturating_sub(np).max(1)) as f64;
    let inv = ne.inverse();
    let cov = |a: usize, b: usize| inv.as_ref().map(|v| v[a * np + b] * var).unwrap_or(f64::NAN);
    let se = |a: usize| cov(a, a).max(0.0).sqrt();
    let (vw, visc, nfm) = (Term::Stribeck, Term::Viscous, Term::TimeSine);
    let i_c = 1 + 2 * usize::from(m.stribeck.is_some());
    let i_a = i_c + usize::from(m.viscous.is_some());
    let mut out = Vec::new();
    if let Some((mu_s, vs)) = m.stribeck {
        out.push((vw, "mu_static", mu_s, (cov(0, 0) + cov(1, 1) + 2.0 * cov(0, 1)).max(0.0).sqrt()));
        out.push((vw, "mu_kinetic", m.mu_k, se(0)));
        out.push((vw, "stribeck_speed_rad_s", vs, se(2)));
        if let Some(c) = m.viscous {
            out.push((visc, "viscous_per_rad_s", c, se(i_c)));
            out.push((visc, "mu_kinetic", m.mu_k, se(0)));
        }
    } else if let Some(c) = m.viscous {
        out.push((visc, "mu_kinetic", m.mu_k, se(0)));
        out.push((visc, "viscous_per_rad_s", c, se(i_c)));
    }
    if let Some((a, f)) = m.time_mod {
        out.push((nfm, "amplitude_ratio", a, se(i_a)));
        out.push((nfm, "frequency_hz", f, se(i_a + 1)));
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::composite::tests::synth;
    use crate::composite::{FrictionSet, fit_composite, weighted_rss};

    /// A modulation at the frequency of the slip-speed cycle (0.5 Hz, the
    /// synthetic runs' sawtooth) is coupled to the speed law: each block
    /// re-absorbs what the other moved. The fit still ends at a stationary
    /// point of the full model's RSS: along every shared parameter the
    /// parabola through RSS(p − δ), RSS(p), RSS(p + δ) has its vertex within
    /// 2 % of δ of the fitted value, δ a tenth of the reported standard error
    /// (so within 0.002 standard errors; at δ = one standard error the
    /// Stribeck speed's cubic term alone moves the vertex by 2 %).
    #[test]
    fn coupled_speed_law_and_modulation_reach_a_stationary_point() {
        let d = synth(4, |r, t, _, w| {
            (0.4 + 0.2 * rig_model::friction::stribeck_decay(w, 2.0f64))
                * (1.0 + 0.1 * (2.0 * PI * 0.5 * t + 0.7 * r as f64).sin())
        });
        let freqs: Vec<f64> = (0..300).map(|j| 0.05 + 0.01 * j as f64).collect();
        let set = FrictionSet::default().with(Term::Stribeck).with(Term::TimeSine);
        let f = fit_composite(&d, set, &freqs, 8).unwrap();
        assert!(f.converged);
        let se = |key: &str| f.params.iter().find(|p| p.1 == key).map(|p| p.3).unwrap();
        let rss = |m: &Composite| weighted_rss(&d, m, &f.phases);
        let r0 = rss(&f.model);
        assert!((r0 - f.rss_w).abs() <= 1e-9 * r0, "{r0} vs {}", f.rss_w);
        type Shift = fn(&mut Composite, f64);
        let shifts: [(&str, Shift); 5] = [
            ("mu_kinetic", |m, x| m.mu_k += x),
            ("mu_static", |m, x| m.stribeck.as_mut().unwrap().0 += x),
            ("stribeck_speed_rad_s", |m, x| m.stribeck.as_mut().unwrap().1 += x),
            ("amplitude_ratio", |m, x| m.time_mod.as_mut().unwrap().0 += x),
            ("frequency_hz", |m, x| m.time_mod.as_mut().unwrap().1 += x),
        ];
        for (key, shift) in shifts {
            let delta = 0.1 * se(key);
            assert!(delta > 0.0 && delta.is_finite(), "{key}: se {delta}");
            let at = |x: f64| {
                let mut m = f.model.clone();
                shift(&mut m, x);
                rss(&m)
            };
            let (lo, hi) = (at(-delta), at(delta));
            let curvature = lo + hi - 2.0 * r0;
            assert!(curvature > 0.0, "{key}: not a minimum ({lo}, {r0}, {hi})");
            let vertex = 0.5 * (lo - hi) / curvature;
            assert!(vertex.abs() < 0.02, "{key}: vertex at {vertex:.3} δ ({lo}, {r0}, {hi})");
        }
    }
}
