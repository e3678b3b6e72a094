//! The torque balance's window rows: triangle-weighted means around each
//! window boundary, from running box sums, for several channel sets at once.

use super::Row;

/// Triangle-weighted means around the boundary b (weights w − |k − b|),
/// the kernel for which (mean speed of the next window − of the previous) / T
/// is exactly the weighted mean of the acceleration, so no derivative of a
/// quantised angle is taken. `None` when the kernel leaves the record.
pub(super) fn row_at(
    phi1: &[f64],
    phi2: &[f64],
    force_n: &[f64],
    dt: f64,
    w: usize,
    r_m: f64,
    b: usize,
) -> Option<Row> {
    let n = phi1.len().min(phi2.len()).min(force_n.len());
    if b < w || b + w >= n {
        return None;
    }
    let tw = |k: usize| phi2[k] - phi1[k];
    let big_t = w as f64 * dt;
    let (mut s_tw, mut s_f, mut s_k) = (0.0, 0.0, 0.0);
    for (k, &f) in force_n.iter().enumerate().take(b + w + 1).skip(b - w) {
        let wt = (w - k.abs_diff(b)) as f64;
        s_tw += wt * tw(k);
        s_f += wt * f;
        s_k += wt;
    }
    let w1_prev = (phi1[b] - phi1[b - w]) / big_t;
    let w1_next = (phi1[b + w] - phi1[b]) / big_t;
    let tw_prev = (tw(b) - tw(b - w)) / big_t;
    let tw_next = (tw(b + w) - tw(b)) / big_t;
    Some((
        [(w1_next - w1_prev) / big_t, s_tw / s_k, 0.5 * (tw_prev + tw_next), 0.5 * (w1_prev + w1_next), 1.0],
        r_m * s_f / s_k,
    ))
}

/// [`row_at`] every `w` samples from `from` on (the steady state's grid),
/// for `L` channel sets of one run at once (a sensor grid's points,
/// [`Recorded::balance_lanes`]; one set is `L = 1`). The triangle-weighted
/// means come from running box sums: the triangle w − |k − b| (|k − b| < w)
/// is a box of w samples convolved with itself, so its weighted sum at b is
/// the sum of the w box sums B(s) = Σ x[s..s+w] for s = b − w + 1 … b, and B
/// is updated by one sample in and one out (the same rows as [`row_at`]'s
/// to rounding, without its 2w + 1 products per boundary; a campaign's
/// structural grids build ≈ 100 balances of every run). The running sums
/// are additions each waiting for its last (latency-bound) and the lanes'
/// are independent, so one pass with the lanes interleaved lets the
/// processor overlap them; each lane performs the same operations in the
/// same order as it would alone (`L = 1`), so it is its own rows to the
/// bit. Lanes of unequal length are built one after the other. Lanes that
/// read the same angles (the same slices: a force sensor's points, which
/// change the force alone) share their twist's running sums, computed once
/// by the same operations in the same order, so each lane's rows are still
/// its own to the bit.
pub(super) fn rows_lanes<const L: usize>(
    lanes: [(&[f64], &[f64], &[f64]); L],
    dt: f64,
    w: usize,
    r_m: f64,
    from: usize,
) -> [Vec<Row>; L] {
    let len = |(phi1, phi2, force_n): (&[f64], &[f64], &[f64])| phi1.len().min(phi2.len()).min(force_n.len());
    let n = len(lanes[0]);
    if L > 1 && lanes.iter().any(|&c| len(c) != n) {
        return lanes.map(|c| {
            let [out] = rows_lanes([c], dt, w, r_m, from);
            out
        });
    }
    let same = |a: &[f64], b: &[f64]| std::ptr::eq(a, b);
    if L > 1 && lanes.iter().all(|c| same(c.0, lanes[0].0) && same(c.1, lanes[0].1)) {
        rows_lanes_of::<L, true>(lanes, n, dt, w, r_m, from)
    } else {
        rows_lanes_of::<L, false>(lanes, n, dt, w, r_m, from)
    }
}

/// [`rows_lanes`] of `L` lanes of `n` samples each; with `SHARED_ANGLES`
/// every lane reads lane 0's angles and the twist's sums are lane 0's.
fn rows_lanes_of<const L: usize, const SHARED_ANGLES: bool>(
    lanes: [(&[f64], &[f64], &[f64]); L],
    n: usize,
    dt: f64,
    w: usize,
    r_m: f64,
    from: usize,
) -> [Vec<Row>; L] {
    let tw_lanes = if SHARED_ANGLES { 1 } else { L };
    let first = from.max(w);
    if first + w >= n {
        return std::array::from_fn(|_| Vec::new());
    }
    let tw = |l: usize, k: usize| lanes[l].1[k] - lanes[l].0[k];
    let big_t = w as f64 * dt;
    let s_k = (w * w) as f64;
    // Box sums starting at s = first − w + 1, advanced along the boundaries.
    let mut s = first + 1 - w;
    let mut b_tw: [f64; L] =
        std::array::from_fn(|l| if l < tw_lanes { (s..s + w).map(|k| tw(l, k)).sum::<f64>() } else { 0.0 });
    let mut b_f: [f64; L] = std::array::from_fn(|l| lanes[l].2[s..s + w].iter().sum::<f64>());
    let mut out: [Vec<Row>; L] = std::array::from_fn(|_| Vec::with_capacity((n - first) / w + 1));
    let mut b = first;
    while b + w < n {
        let (mut t_tw, mut t_f) = ([0.0; L], [0.0; L]);
        // Σ over s = b − w + 1 … b of B(s); on leaving, s = b + 1.
        while s <= b {
            for l in 0..tw_lanes {
                t_tw[l] += b_tw[l];
                b_tw[l] += tw(l, s + w) - tw(l, s);
            }
            for l in 0..L {
                t_f[l] += b_f[l];
                b_f[l] += lanes[l].2[s + w] - lanes[l].2[s];
            }
            s += 1;
        }
        for l in 0..L {
            let t_tw_l = t_tw[if SHARED_ANGLES { 0 } else { l }];
            let phi1 = lanes[l].0;
            let w1_prev = (phi1[b] - phi1[b - w]) / big_t;
            let w1_next = (phi1[b + w] - phi1[b]) / big_t;
            let tw_prev = (tw(l, b) - tw(l, b - w)) / big_t;
            let tw_next = (tw(l, b + w) - tw(l, b)) / big_t;
            out[l].push((
                [(w1_next - w1_prev) / big_t, t_tw_l / s_k, 0.5 * (tw_prev + tw_next), 0.5 * (w1_prev + w1_next), 1.0],
                r_m * t_f[l] / s_k,
            ));
        }
        b += w;
    }
    out
}
