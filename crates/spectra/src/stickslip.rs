//! Stick-slip measures on recordings: glitch repair, severity, friction torque
//! binned against speed, and the velocity-weakening fit μ(v) = a + b·exp(−v/vs).

use crate::error::{SpectraError, check_finite};
use rig_types::minimize::brent_min;
use serde::{Deserialize, Serialize};

/// Running median over an odd window (shrunk at the ends): element
/// len/2 of the window x[i−h ..= i+h] (clipped to the record) sorted by
/// `f64::total_cmp`. Where the window is monotone (a smooth signal between
/// its turning points: most of a simulated record) that element is the
/// window's middle one in its own order, read without sorting (the
/// window's falling and rising adjacent pairs counted, without a branch, as
/// it slides). Elsewhere the window is kept sorted as it slides: one sample
/// in and one out, the entering one takes the leaving one's place and moves
/// to its own by swaps; after a monotone stretch, the samples that entered
/// and left since are inserted and removed by binary search, or the window
/// is sorted afresh when none of it is left — O(n·w) moves instead of a
/// sort per sample (O(n·w log w) comparisons: 23 % of the LAVI stage with
/// its 1 kHz record). Samples are compared as `total_cmp`'s integer keys
/// (the same order; equal keys are equal bits). The same order statistic of
/// the same samples, so the same values, bit for bit.
pub fn running_median(x: &[f64], window: usize) -> Vec<f64> {
    let key = rig_types::order::total_key;
    let h = window / 2;
    let n = x.len();
    let position = |buf: &[i64], v: i64| buf.partition_point(|&b| b < v);
    // The window is x[lo..hi]; of its adjacent pairs, `falls` fall and `rises` rise.
    let (mut lo, mut hi, mut falls, mut rises) = (0usize, 0usize, 0usize, 0usize);
    let mut buf: Vec<i64> = Vec::with_capacity(2 * h + 1);
    // The samples in `buf`: x[from..to], sorted by key.
    let (mut from, mut to) = (0usize, 0usize);
    let mut out = Vec::with_capacity(n);
    for i in 0..n {
        while hi < (i + h + 1).min(n) {
            if hi > lo {
                let (a, b) = (key(x[hi - 1]), key(x[hi]));
                falls += usize::from(a > b);
                rises += usize::from(a < b);
            }
            hi += 1;
        }
        while lo < i.saturating_sub(h) {
            if lo + 1 < hi {
                let (a, b) = (key(x[lo]), key(x[lo + 1]));
                falls -= usize::from(a > b);
                rises -= usize::from(a < b);
            }
            lo += 1;
        }
        let len = hi - lo;
        out.push(if falls == 0 {
            x[lo + len / 2]
        } else if rises == 0 {
            x[hi - 1 - len / 2]
        } else {
            if lo >= to {
                buf.clear();
                buf.extend(x[lo..hi].iter().map(|&v| key(v)));
                buf.sort_unstable();
            } else if lo == from + 1 && hi == to + 1 {
                // One sample in, one out: the entering one takes the leaving one's
                // place and moves to its own by swaps (a short window: few).
                let out_key = key(x[from]);
                let mut k = buf.iter().position(|&b| b == out_key).expect("a sample of the window");
                buf[k] = key(x[to]);
                while k > 0 && buf[k - 1] > buf[k] {
                    buf.swap(k - 1, k);
                    k -= 1;
                }
                while k + 1 < buf.len() && buf[k] > buf[k + 1] {
                    buf.swap(k, k + 1);
                    k += 1;
                }
            } else {
                for &v in &x[to..hi] {
                    let k = key(v);
                    buf.insert(position(&buf, k), k);
                }
                for &v in &x[from..lo] {
                    let at = position(&buf, key(v));
                    buf.remove(at);
                }
            }
            (from, to) = (lo, hi);
            rig_types::order::from_total_key(buf[len / 2])
        });
    }
    out
}

/// How isolated sensor glitches are found and bridged.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GlitchOptions {
    /// Running-median window, samples (must exceed the longest glitch ×2).
    pub median_window: usize,
    /// A sample is a glitch when it is this far from the running median.
    pub threshold: f64,
    /// Samples below this are glitches too (a drive that never reverses).
    pub floor: f64,
    /// Flagged runs are widened by this many samples each side (the slopes
    /// into and out of a dip are below the threshold but still corrupted).
    pub dilate: usize,
}

/// What the repair did.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct GlitchReport {
    pub runs: usize,
    pub samples: usize,
    pub longest_run: usize,
}

/// Replaces glitch runs by the straight line between the good samples around
/// them (held constant at the record's ends).
pub fn repair_glitches(x: &[f64], o: &GlitchOptions) -> Result<(Vec<f64>, GlitchReport), SpectraError> {
    check_finite("x", x)?;
    if o.median_window < 3 || o.median_window.is_multiple_of(2) {
        return Err(SpectraError::InvalidParameter {
            name: "median_window",
            value: o.median_window as f64,
            rule: "an odd number >= 3",
        });
    }
    let med = running_median(x, o.median_window);
    let n = x.len();
    let mut bad = vec![false; n];
    for i in 0..n {
        if (x[i] - med[i]).abs() > o.threshold || x[i] < o.floor {
            for b in &mut bad[i.saturating_sub(o.dilate)..(i + o.dilate + 1).min(n)] {
                *b = true;
            }
        }
    }
    let mut y = x.to_vec();
    let mut rep = GlitchReport { runs: 0, samples: 0, longest_run: 0 };
    let mut i = 0;
    while i < n {
        if !bad[i] {
            i += 1;
            continue;
        }
        let start = i;
        while i < n && bad[i] {
            i += 1;
        }
        let (left, right) = (start.checked_sub(1), (i < n).then_some(i));
        for (j, yj) in y.iter_mut().enumerate().take(i).skip(start) {
            *yj = match (left, right) {
                (Some(l), Some(r)) => x[l] + (x[r] - x[l]) * (j - l) as f64 / (r - l) as f64,
                (Some(l), None) => x[l],
                (None, Some(r)) => x[r],
                (None, None) => 0.0,
            };
        }
        rep.runs += 1;
        rep.samples += i - start;
        rep.longest_run = rep.longest_run.max(i - start);
    }
    Ok((y, rep))
}

/// Severity of a speed record: the two conventions in use.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Severity {
    pub min: f64,
    pub max: f64,
    pub mean: f64,
    /// (max − min) / (2 · mean): 1 when the minimum touches zero symmetrically.
    pub half_range_over_mean: f64,
    /// (max − min) / mean.
    pub range_over_mean: f64,
}

pub fn severity(x: &[f64]) -> Severity {
    let min = x.iter().cloned().fold(f64::INFINITY, f64::min);
    let max = x.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
    let mean = x.iter().sum::<f64>() / x.len().max(1) as f64;
    Severity { min, max, mean, half_range_over_mean: (max - min) / (2.0 * mean), range_over_mean: (max - min) / mean }
}

/// One speed bin of y against x.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct Bin {
    pub x_lo: f64,
    pub x_hi: f64,
    pub count: usize,
    pub mean: f64,
    pub std: f64,
}

/// Means of `y` in equal-width bins of `x` over [lo, hi) (empty bins are kept with count 0).
pub fn bin_means(x: &[f64], y: &[f64], lo: f64, hi: f64, bins: usize) -> Vec<Bin> {
    let w = (hi - lo) / bins as f64;
    let mut acc = vec![(0usize, 0.0f64, 0.0f64); bins];
    for (xi, yi) in x.iter().zip(y) {
        if *xi >= lo && *xi < hi {
            let b = (((xi - lo) / w) as usize).min(bins - 1);
            acc[b].0 += 1;
            acc[b].1 += yi;
            acc[b].2 += yi * yi;
        }
    }
    acc.iter()
        .enumerate()
        .map(|(b, (c, s, s2))| {
            let mean = if *c > 0 { s / *c as f64 } else { f64::NAN };
            let var = if *c > 1 { ((s2 - s * s / *c as f64) / (*c - 1) as f64).max(0.0) } else { 0.0 };
            Bin { x_lo: lo + b as f64 * w, x_hi: lo + (b + 1) as f64 * w, count: *c, mean, std: var.sqrt() }
        })
        .collect()
}

/// y(v) = a + b·exp(−(v / vs)^δ), fitted in slip (v > 0).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
pub struct WeakeningFit {
    /// δ: 1 exponential, 2 Gaussian (Stribeck).
    pub shape_exponent: f64,
    pub a: f64,
    pub b: f64,
    pub vs: f64,
    pub rmse: f64,
    /// rmse of the best constant (Coulomb) fit, for comparison.
    pub rmse_constant: f64,
    pub points: usize,
    /// False when the best vs sits on the edge of the scanned range (no interior optimum).
    pub converged: bool,
    /// True when the unconstrained optimum had a < 0 and a was held at 0.
    pub a_at_bound: bool,
}

/// The weakening shape e^{−x^δ} of x = |v|/v_s (δ = 1 exponential, 2
/// Gaussian Stribeck). δ = 1 and 2 are computed as x and x·x instead of
/// `powf` (pow(x, 1) is x exactly; x·x is the correctly rounded square, which
/// glibc's pow matches to its stated 0.52 ulp), the rest by `powf`: the
/// friction loops of the LAVI simulation spend a third of their time in pow.
#[inline]
pub fn weakening_shape(x: f64, shape_exponent: f64) -> f64 {
    let p = if shape_exponent == 1.0 {
        x
    } else if shape_exponent == 2.0 {
        x * x
    } else {
        x.powf(shape_exponent)
    };
    (-p).exp()
}

impl WeakeningFit {
    /// y at v → 0⁺ over y at v → ∞: (a + b) / a.
    pub fn static_over_kinetic(&self) -> f64 {
        (self.a + self.b) / self.a
    }

    pub fn eval(&self, v: f64) -> f64 {
        self.a + self.b * weakening_shape(v.abs() / self.vs, self.shape_exponent)
    }
}

/// For fixed vs the model is linear in (a, b): least squares in closed form,
/// with a ≥ 0 enforced (a negative kinetic level would make friction drive the
/// rotor at high speed); vs is scanned on a log grid over [vs_min, vs_max] and
/// refined by Brent's method (`rig_types::minimize`).
pub fn fit_weakening(
    v: &[f64],
    y: &[f64],
    shape_exponent: f64,
    vs_min: f64,
    vs_max: f64,
) -> Result<WeakeningFit, SpectraError> {
    if v.len() != y.len() {
        return Err(SpectraError::LengthMismatch { a: "v", len_a: v.len(), b: "y", len_b: y.len() });
    }
    if v.len() < 4 {
        return Err(SpectraError::TooShort { name: "v", len: v.len(), min: 4, rule: "a 3-parameter fit" });
    }
    if !(vs_min > 0.0 && vs_max > vs_min) {
        return Err(SpectraError::InvalidParameter { name: "vs_min", value: vs_min, rule: "0 < vs_min < vs_max" });
    }
    check_finite("v", v)?;
    check_finite("y", y)?;
    let linear = |vs: f64| -> (f64, f64, f64) {
        let n = v.len() as f64;
        let e: Vec<f64> = v.iter().map(|vi| weakening_shape(vi.abs() / vs, shape_exponent)).collect();
        let (se, see) = (e.iter().sum::<f64>(), e.iter().map(|x| x * x).sum::<f64>());
        let (sy, sey) = (y.iter().sum::<f64>(), e.iter().zip(y).map(|(a, b)| a * b).sum::<f64>());
        let det = n * see - se * se;
        let (mut a, mut b) =
            if det.abs() > 1e-300 { ((see * sy - se * sey) / det, (n * sey - se * sy) / det) } else { (sy / n, 0.0) };
        if a < 0.0 {
            // Constrained optimum on the boundary a = 0: y ≈ b e.
            (a, b) = (0.0, sey / see.max(1e-300));
        }
        let sse: f64 = e.iter().zip(y).map(|(ei, yi)| (yi - a - b * ei).powi(2)).sum();
        (a, b, (sse / n).sqrt())
    };
    let grid = 60;
    let ratio = (vs_max / vs_min).ln();
    let at = |i: usize| vs_min * (ratio * i as f64 / grid as f64).exp();
    let (mut ib, mut best) = (0, f64::INFINITY);
    for i in 0..=grid {
        let r = linear(at(i)).2;
        if r < best {
            best = r;
            ib = i;
        }
    }
    // Brent's method on ln vs between the grid neighbours, to 10⁻⁹ (golden section's
    // 60 steps of two evaluations each went to 10⁻¹³, far below what the RMSE's
    // flat minimum resolves; a third of the LAVI stage's time).
    let (lo, hi) = (at(ib.saturating_sub(1)).ln(), at((ib + 1).min(grid)).ln());
    let vs = brent_min(lo, hi, 1e-9, 60, |lv| linear(lv.exp()).2).exp();
    let (a, b, rmse) = linear(vs);
    let a_at_bound = a == 0.0;
    let mean = y.iter().sum::<f64>() / y.len() as f64;
    let rmse_constant = (y.iter().map(|yi| (yi - mean).powi(2)).sum::<f64>() / y.len() as f64).sqrt();
    Ok(WeakeningFit {
        shape_exponent,
        a,
        b,
        vs,
        rmse,
        rmse_constant,
        points: v.len(),
        converged: ib > 0 && ib < grid,
        a_at_bound,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The sliding sorted window gives exactly a sort per sample, with ties,
    /// signed zeros, windows wider than the record and a window of one.
    #[test]
    fn running_median_equals_a_sort_per_window() {
        let reference = |x: &[f64], window: usize| -> Vec<f64> {
            let h = window / 2;
            (0..x.len())
                .map(|i| {
                    let mut b = x[i.saturating_sub(h)..(i + h + 1).min(x.len())].to_vec();
                    b.sort_by(f64::total_cmp);
                    b[b.len() / 2]
                })
                .collect()
        };
        let mut seed = 7u64;
        let x: Vec<f64> = (0..500)
            .map(|i| {
                seed = seed.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
                match i % 7 {
                    0 => 0.0,
                    1 => -0.0,
                    2 => 1.5,
                    _ => ((seed >> 11) as f64 / (1u64 << 53) as f64 - 0.5) * 10.0,
                }
            })
            .collect();
        for window in [1, 3, 5, 21, 101, 999, 1001] {
            let (got, want) = (running_median(&x, window), reference(&x, window));
            assert!(got.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()), "window {window}");
        }
        assert!(running_median(&[], 5).is_empty());
        // Monotone stretches (a sampled sine, a ramp, plateaus of ties) broken
        // by spikes and signed zeros: the read-off and the sorted window
        // hand over in both directions, after short and long monotone runs.
        let y: Vec<f64> = (0..3000)
            .map(|i| match i {
                _ if i % 311 == 0 => -0.0,
                _ if i % 157 == 0 => 0.0,
                _ if i % 97 == 0 => 5.0,
                _ if (1200..1400).contains(&i) => ((i / 9) as f64 * 0.25).floor(),
                _ if (2000..2100).contains(&i) => -1e-3 * i as f64,
                _ => (i as f64 * 0.013).sin() + if i % 13 < 2 { 0.3 } else { 0.0 },
            })
            .collect();
        for window in [1, 3, 5, 7, 21, 101, 4001] {
            let (got, want) = (running_median(&y, window), reference(&y, window));
            assert!(got.iter().zip(&want).all(|(a, b)| a.to_bits() == b.to_bits()), "window {window} on stretches");
        }
    }
}
