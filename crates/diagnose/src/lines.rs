//! Line analysis used for `unexplained`: components of a speed locked to a
//! shaft angle (order n per revolution), tested against the local floor of the
//! order spectrum. An effect outside the vocabulary (cogging, an eccentric
//! coupling, …) leaves such a line where neither the baseline nor any
//! friction candidate puts one.

use crate::prepare::RunSignals;
use std::f64::consts::PI;

/// One order line in one run.
#[derive(Debug, Clone, PartialEq)]
pub struct OrderLine {
    pub run: String,
    /// "motor" (motor speed vs motor angle) or "rotor" (rotor speed vs rotor angle).
    pub channel: &'static str,
    pub order: u32,
    /// Amplitude of the speed component, rad/s.
    pub amplitude_rad_s: f64,
    /// Power at the order over the median power of the surrounding fractional orders.
    pub ratio: f64,
}

/// Order power of `x` (mean removed) against angle `phi` at fractional order `q`.
fn order_power(phi: &[f64], x: &[f64], q: f64) -> f64 {
    let (mut re, mut im) = (0.0, 0.0);
    for (p, v) in phi.iter().zip(x) {
        let (s, c) = (q * p).sin_cos();
        re += v * c;
        im += v * s;
    }
    (re * re + im * im) / x.len() as f64
}

/// [`order_power`] at each order of `qs`, a grid q0 + 0.04·j: sin/cos of
/// q·φ start exactly at q0 and advance by rotation through `step` (sin/cos of
/// 0.04·φ per sample), one sin_cos per sample for the whole grid instead of
/// one per order (the 41 sin_cos per sample were 4 % of a diagnosis). Over 40
/// rotations the rounding grows to ~10⁻¹⁴, far below the power differences
/// the median floor ranks.
fn floor_powers(phi: &[f64], x: &[f64], qs: &[f64], step: &[(f64, f64)]) -> Vec<f64> {
    let Some(&q0) = qs.first() else { return vec![] };
    let mut sc: Vec<(f64, f64)> = phi.iter().map(|p| (q0 * p).sin_cos()).collect();
    let mut out = Vec::with_capacity(qs.len());
    // Grid points in blocks of BLOCK per pass over the samples: each sample's
    // rotations and each point's sums are the one-point-per-pass loop's, in
    // its order (re_j, im_j summed over the samples in sample order), so the
    // same powers to the bit; the block's independent sums overlap instead
    // of one chain of additions waiting on the last.
    // The blocks share the grid evenly (25 points: 9, 9, 7, not 8, 8, 8, 1:
    // a pass over the samples for one point costs nearly a full block's).
    const BLOCK: usize = 9;
    let size = qs.len().div_ceil(qs.len().div_ceil(BLOCK));
    let mut j0 = 0;
    while j0 < qs.len() {
        let k = size.min(qs.len() - j0);
        let mut acc = [(0.0f64, 0.0f64); BLOCK];
        // Two samples a step: their rotations are independent chains that
        // overlap, each point's sums still taken in sample order (the
        // first sample's term, then the second's).
        let rot = |v: (f64, f64), r: &(f64, f64)| (v.0 * r.1 + v.1 * r.0, v.1 * r.1 - v.0 * r.0);
        let mut pairs = sc.chunks_exact_mut(2).zip(step.chunks_exact(2)).zip(x.chunks_exact(2));
        for ((v, r), xv) in &mut pairs {
            let (mut u0, mut u1) = (v[0], v[1]);
            for (j, a) in acc[..k].iter_mut().enumerate() {
                if j0 + j > 0 {
                    u0 = rot(u0, &r[0]);
                    u1 = rot(u1, &r[1]);
                }
                a.0 += xv[0] * u0.1;
                a.0 += xv[1] * u1.1;
                a.1 += xv[0] * u0.0;
                a.1 += xv[1] * u1.0;
            }
            (v[0], v[1]) = (u0, u1);
        }
        let tail = sc.len().min(step.len()).min(x.len()) / 2 * 2;
        for ((v, r), xv) in sc[tail..].iter_mut().zip(&step[tail..]).zip(&x[tail..]) {
            for (j, a) in acc[..k].iter_mut().enumerate() {
                if j0 + j > 0 {
                    *v = rot(*v, r);
                }
                a.0 += xv * v.1;
                a.1 += xv * v.0;
            }
        }
        out.extend(acc[..k].iter().map(|(re, im)| (re * re + im * im) / x.len() as f64));
        j0 += k;
    }
    out
}

/// The floor grid's powers of every order 1..=`max_order`: order n's at q =
/// n − 0.8 + 0.04·j, j = 0..=40 ([`floor_powers`]). Order n + 1's grid starts
/// at n + 0.2, order n's j = 25: consecutive grids share 16 points. Each
/// order's first 25 points are computed from its own start (as when each
/// order had its whole grid: the same powers to the bit), its last 16 are the
/// next order's first 16 (the last order computes its own), so 25·N + 16
/// points instead of 41·N (216 for 8 orders, not 328). A shared point's q
/// differs from the order's own by rounding (10⁻¹⁶), and it is fewer
/// rotations from an exact start (0–15 instead of 25–40).
fn order_floors(phi: &[f64], x: &[f64], max_order: u32, step: &[(f64, f64)]) -> Vec<Vec<f64>> {
    const OWN: usize = 25;
    let heads: Vec<Vec<f64>> = (1..=max_order)
        .map(|n| {
            let len = if n == max_order { 41 } else { OWN };
            let qs: Vec<f64> = (0..len).map(|j| n as f64 - 0.8 + 0.04 * j as f64).collect();
            floor_powers(phi, x, &qs, step)
        })
        .collect();
    (0..heads.len())
        .map(|i| {
            let own = &heads[i];
            let tail = heads.get(i + 1).map_or(&own[OWN..], |next| &next[..41 - OWN]);
            own[..OWN].iter().chain(tail).copied().collect()
        })
        .collect()
}

/// Order lines of one run and channel, for orders 1..=max_order, over the
/// steady state. Decimation by 8 (62.5 Hz at 500 Hz; the speeds are already
/// smoothed over ±8 samples or more, and order 8 at the fastest set-point is
/// below 20 Hz) keeps the scan cheap.
pub fn order_lines(s: &RunSignals, motor: bool, max_order: u32) -> Vec<OrderLine> {
    let (phi, w) =
        if motor { (&s.motor_angle_rad, &s.motor_speed_rad_s) } else { (&s.rotor_angle_rad, &s.rotor_speed_rad_s) };
    let idx: Vec<usize> = (s.steady_from..phi.len()).step_by(8).collect();
    if idx.len() < 64 {
        return vec![];
    }
    let revs = (phi[*idx.last().expect("non-empty")] - phi[idx[0]]).abs() / (2.0 * PI);
    if revs < 3.0 {
        return vec![];
    }
    let p: Vec<f64> = idx.iter().map(|&k| phi[k]).collect();
    let mean = idx.iter().map(|&k| w[k]).sum::<f64>() / idx.len() as f64;
    let x: Vec<f64> = idx.iter().map(|&k| w[k] - mean).collect();
    // Main lobe half-width in orders is ~1/revs; exclude two of them around the line.
    let excl = (2.0 / revs).clamp(0.1, 0.35);
    // sin/cos of the 0.04-order step of the floor's grid, per sample (see floor_powers).
    let step: Vec<(f64, f64)> = p.iter().map(|a| (0.04 * a).sin_cos()).collect();
    let floors = order_floors(&p, &x, max_order, &step);
    let mut out = Vec::new();
    for (n, grid) in (1..=max_order).zip(floors) {
        let nf = n as f64;
        let pn = order_power(&p, &x, nf);
        let qs: Vec<f64> = (0..=40).map(|j| nf - 0.8 + 0.04 * j as f64).collect();
        let mut floor: Vec<f64> =
            grid.into_iter().zip(&qs).filter(|(_, q)| (*q - nf).abs() > excl && **q > 0.2).map(|(pw, _)| pw).collect();
        floor.sort_by(|a, b| a.total_cmp(b));
        let med = floor.get(floor.len() / 2).copied().unwrap_or(0.0).max(f64::MIN_POSITIVE);
        out.push(OrderLine {
            run: s.id.clone(),
            channel: if motor { "motor" } else { "rotor" },
            order: n,
            amplitude_rad_s: 2.0 * (pn / x.len() as f64).sqrt(),
            ratio: pn / med,
        });
    }
    out
}

/// An order line that is significant in a majority of the runs that can show it.
#[derive(Debug, Clone, PartialEq)]
pub struct ConsistentLine {
    pub channel: &'static str,
    pub order: u32,
    pub runs_significant: usize,
    pub runs_tested: usize,
    pub median_ratio: f64,
}

/// Lines significant (ratio ≥ `min_ratio`) in at least half of the tested
/// runs (and at least two). A stick-slip harmonic can fall on an integer order
/// in one run by chance, not at the same order in most runs with different
/// set-points.
pub fn consistent_lines(lines: &[OrderLine], min_ratio: f64) -> Vec<ConsistentLine> {
    let mut out = Vec::new();
    for channel in ["motor", "rotor"] {
        let orders: std::collections::BTreeSet<u32> =
            lines.iter().filter(|l| l.channel == channel).map(|l| l.order).collect();
        for n in orders {
            let mut ratios: Vec<f64> =
                lines.iter().filter(|l| l.channel == channel && l.order == n).map(|l| l.ratio).collect();
            let tested = ratios.len();
            let sig = ratios.iter().filter(|&&r| r >= min_ratio).count();
            ratios.sort_by(|a, b| a.total_cmp(b));
            if sig >= 2 && 2 * sig >= tested {
                out.push(ConsistentLine {
                    channel,
                    order: n,
                    runs_significant: sig,
                    runs_tested: tested,
                    median_ratio: ratios[tested / 2],
                });
            }
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The rotated grid gives each fractional order's power as a sin_cos per
    /// sample does (to 10⁻⁹ of the largest power), including the peak of a
    /// line sitting on the grid.
    /// One grid point per pass over the samples (the loop [`floor_powers`]
    /// replaced): rotate every sample's (sin, cos), then sum.
    fn floor_powers_one_per_pass(phi: &[f64], x: &[f64], qs: &[f64], step: &[(f64, f64)]) -> Vec<f64> {
        let Some(&q0) = qs.first() else { return vec![] };
        let mut sc: Vec<(f64, f64)> = phi.iter().map(|p| (q0 * p).sin_cos()).collect();
        let mut out = Vec::with_capacity(qs.len());
        for j in 0..qs.len() {
            if j > 0 {
                for (v, r) in sc.iter_mut().zip(step) {
                    *v = (v.0 * r.1 + v.1 * r.0, v.1 * r.1 - v.0 * r.0);
                }
            }
            let (mut re, mut im) = (0.0, 0.0);
            for ((s, c), v) in sc.iter().zip(x) {
                re += v * c;
                im += v * s;
            }
            out.push((re * re + im * im) / x.len() as f64);
        }
        out
    }

    /// The blocked passes give every power of the one-per-pass loop to the
    /// bit, for grids that fill the last block and grids that do not.
    #[test]
    fn blocked_floor_powers_are_the_one_per_pass_loop_bit_for_bit() {
        let phi: Vec<f64> = (0..3001).map(|k| 0.011 * k as f64 + 0.3 * (0.002 * k as f64).sin()).collect();
        let x: Vec<f64> = phi.iter().map(|p| (5.0 * p + 0.1).sin() + 0.2 * (2.3 * p).cos() - 0.05).collect();
        let step: Vec<(f64, f64)> = phi.iter().map(|a| (0.04 * a).sin_cos()).collect();
        for n in [1, 7, 8, 9, 16, 41] {
            let qs: Vec<f64> = (0..n).map(|j| 4.2 + 0.04 * j as f64).collect();
            let a: Vec<u64> = floor_powers(&phi, &x, &qs, &step).iter().map(|v| v.to_bits()).collect();
            let b: Vec<u64> = floor_powers_one_per_pass(&phi, &x, &qs, &step).iter().map(|v| v.to_bits()).collect();
            assert_eq!(a.len(), n);
            assert_eq!(a, b, "{n} grid points");
        }
        assert!(floor_powers(&phi, &x, &[], &step).is_empty());
    }

    #[test]
    fn floor_powers_match_order_power_on_the_grid() {
        let phi: Vec<f64> = (0..4000).map(|k| 0.013 * k as f64 + 0.2 * (0.001 * k as f64).sin()).collect();
        let x: Vec<f64> = phi.iter().map(|p| (3.0 * p + 0.4).sin() + 0.3 * (1.7 * p).cos()).collect();
        let qs: Vec<f64> = (0..=40).map(|j| 2.2 + 0.04 * j as f64).collect();
        let step: Vec<(f64, f64)> = phi.iter().map(|a| (0.04 * a).sin_cos()).collect();
        let fast = floor_powers(&phi, &x, &qs, &step);
        let direct: Vec<f64> = qs.iter().map(|&q| order_power(&phi, &x, q)).collect();
        let top = direct.iter().cloned().fold(0.0, f64::max);
        assert!(top > 100.0, "the line at order 3 is on the grid: {top}");
        for ((q, a), b) in qs.iter().zip(&fast).zip(&direct) {
            assert!((a - b).abs() <= 1e-9 * top, "q = {q}: {a} vs {b}");
        }
    }

    /// The shared floor grids ([`order_floors`]): each order's 41 powers,
    /// its first 25 the order's own grid's to the bit, the 16 it shares
    /// with the next order within 10⁻¹² of the largest power of its own
    /// grid (a line at order 3 and one between orders).
    #[test]
    fn shared_floor_grids_are_each_orders_own() {
        let phi: Vec<f64> = (0..2500).map(|k| 0.021 * k as f64 + 0.3 * (0.003 * k as f64).sin()).collect();
        let x: Vec<f64> = phi.iter().map(|p| (3.0 * p + 0.4).sin() + 0.3 * (4.62 * p).cos() - 0.1).collect();
        let step: Vec<(f64, f64)> = phi.iter().map(|a| (0.04 * a).sin_cos()).collect();
        let floors = order_floors(&phi, &x, 8, &step);
        assert_eq!(floors.len(), 8);
        for (n, shared) in (1..=8u32).zip(&floors) {
            let qs: Vec<f64> = (0..=40).map(|j| n as f64 - 0.8 + 0.04 * j as f64).collect();
            let own = floor_powers(&phi, &x, &qs, &step);
            assert_eq!(shared.len(), 41);
            let bits = |v: &[f64]| v.iter().map(|p| p.to_bits()).collect::<Vec<u64>>();
            assert_eq!(bits(&shared[..25]), bits(&own[..25]), "order {n}");
            let top = own.iter().cloned().fold(0.0, f64::max);
            for j in 25..41 {
                assert!((shared[j] - own[j]).abs() <= 1e-12 * top, "order {n}, j {j}: {} vs {}", shared[j], own[j]);
            }
        }
        assert!(order_floors(&phi, &x, 0, &step).is_empty());
    }
}
