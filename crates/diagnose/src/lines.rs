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
    let mut out = Vec::new();
    for n in 1..=max_order {
        let nf = n as f64;
        let pn = order_power(&p, &x, nf);
        let mut floor: Vec<f64> = (0..=40)
            .map(|j| nf - 0.8 + 0.04 * j as f64)
            .filter(|q| (q - nf).abs() > excl && *q > 0.2)
            .map(|q| order_power(&p, &x, q))
            .collect();
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
