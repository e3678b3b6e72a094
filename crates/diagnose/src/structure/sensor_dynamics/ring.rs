//! The force's ring after a break-away (module docs of [`super`], "The
//! ring after a break-away"): every run's average of its break-aways and
//! its misfit with the true force's basis through each force-sensor point.

use super::{Biquad, Sensor, SensorPoint, filtered};
use crate::channels::{MIN_EVENTS, Recorded, RecordedRun};
use rayon::prelude::*;
use rig_types::sensor::{centred_moving_average, nominal_window_samples};

/// Seconds of the ring average before the aligned drop.
pub const RING_PRE_S: f64 = 0.05;
/// Seconds of the ring average after it: 1.6 periods at 8 Hz, 3.5 decay
/// times 1/(ζω) at 8 Hz, ζ 0.25.
pub const RING_POST_S: f64 = 0.2;
/// The drop is looked for within ± this of the encoder's transition, s
/// (the documented differentiator smooths over ±40 ms in all).
pub const RING_SEARCH_S: f64 = 0.08;
/// Half-width of the smoothing the drop is located on, s.
pub const RING_LOCATE_HALF_S: f64 = 0.005;
/// The true drop's time τ relative to the aligned one: from −this, s (a
/// step through a sensor is steepest up to a quarter period later: 50 ms at
/// 5 Hz) …
pub const RING_STEP_LEAD_S: f64 = 0.06;
/// … to +this, s.
pub const RING_STEP_LAG_S: f64 = 0.01;
/// Widths of the true drop's raised-cosine ramp, s (a Stribeck decay
/// passed in a few to tens of milliseconds as the rotor speeds up).
pub const RING_RAMPS_S: [f64; 3] = [0.0, 0.01, 0.03];
/// Seconds of lead-in before the window over which the model's basis is
/// filtered (so the sensor's response to the line before the drop has
/// settled: 6 decay times at 2 Hz, ζ 0.4).
const RING_LEAD_IN_S: f64 = 0.2;

/// Every run's ring misfit after its break-aways (module docs), as
/// recorded and through every force-sensor point of the grid.
#[derive(Debug, Clone, Default)]
pub struct Ring {
    /// The runs with a ring average, campaign order.
    ids: Vec<String>,
    /// Their ring misfits as recorded, N·m (the force's times the disc radius).
    recorded: Vec<f64>,
    /// Per point of [`super::super::StructureData::sensors`]: the runs' misfits through
    /// it (`None` for a point that leaves the force as recorded).
    through: Vec<Option<Vec<f64>>>,
}

impl Ring {
    /// Each run's ring misfit, N·m, through grid point `point` (`None`: as
    /// recorded), over the runs `include` accepts that have a ring average.
    pub fn run_rms(&self, point: Option<usize>, include: &dyn Fn(&str) -> bool) -> Vec<(String, f64)> {
        let v = point.and_then(|i| self.through.get(i)?.as_ref()).unwrap_or(&self.recorded);
        self.ids.iter().zip(v).filter(|(id, _)| include(id)).map(|(id, r)| (id.clone(), *r)).collect()
    }
}

/// The ring of every run of `rec` (module docs) for the grid `sensors`.
pub(in crate::structure) fn ring(rec: &Recorded, rate_hz: f64, sensors: &[SensorPoint]) -> Ring {
    let avgs: Vec<(String, Vec<f64>)> =
        rec.runs.iter().filter_map(|r| Some((r.id.clone(), ring_average(r, rate_hz)?))).collect();
    if avgs.is_empty() {
        return Ring { through: vec![None; sensors.len()], ..Ring::default() };
    }
    let y: Vec<&[f64]> = avgs.iter().map(|a| a.1.as_slice()).collect();
    let r_m = rec.disc_radius_m();
    let torque = |v: Vec<f64>| v.into_iter().map(|x| r_m * x).collect::<Vec<f64>>();
    let recorded = torque(ring_misfits(&y, None, rate_hz));
    let through = sensors
        .par_iter()
        .map(|p| {
            (p.sensor == Sensor::Force).then(|| {
                torque(ring_misfits(
                    &y,
                    Some(Biquad::new(rate_hz, p.natural_frequency_hz, p.damping_ratio, false)),
                    rate_hz,
                ))
            })
        })
        .collect();
    Ring { ids: avgs.into_iter().map(|a| a.0).collect(), recorded, through }
}

/// The run's recorded force averaged over its break-aways, aligned on the
/// force's steepest change (module docs); `None` with fewer than
/// [`MIN_EVENTS`] in the record.
fn ring_average(run: &RecordedRun, rate_hz: f64) -> Option<Vec<f64>> {
    let f = &run.force_n;
    let n = f.len();
    let (pre, post) = (nominal_window_samples(RING_PRE_S, rate_hz), nominal_window_samples(RING_POST_S, rate_hz));
    let search = nominal_window_samples(RING_SEARCH_S, rate_hz);
    let sm = centred_moving_average(f, nominal_window_samples(RING_LOCATE_HALF_S, rate_hz));
    let slope = |k: usize| (sm[k + 1] - sm[k]).abs();
    let (mut sum, mut count) = (vec![0.0; pre + post + 1], 0usize);
    for (e, next) in run.breakaways() {
        let (lo, hi) = (e.saturating_sub(search), (e + search).min(n.saturating_sub(1)));
        let Some(a) = (lo..hi).max_by(|&i, &j| slope(i).total_cmp(&slope(j))) else { continue };
        if a < pre || a + post >= n.min(next) {
            continue;
        }
        for (s, x) in sum.iter_mut().zip(&f[a - pre..=a + post]) {
            *s += x;
        }
        count += 1;
    }
    (count >= MIN_EVENTS).then(|| sum.into_iter().map(|s| s / count as f64).collect())
}

/// Each ring average's misfit, N (module docs): the smallest RMS residual
/// over the drop's time τ and width of the least-squares fit of the five
/// amplitudes with the basis through `q` (`None`: as recorded).
///
/// The basis 1 does not depend on τ or the width and t (time from the drop)
/// not on the width, so each is put through `q` once (and its products with
/// the records summed once), the drop's three columns once per width, every
/// τ reading them shifted (below), and X'X's lower triangle is its upper
/// one's mirror: the same
/// operations on the same values as every point building its own five
/// columns and 25 sums, so the same misfits to the bit (test
/// `ring_misfits_are_each_points_own_fit_to_the_bit`).
fn ring_misfits(y: &[&[f64]], q: Option<Biquad>, rate_hz: f64) -> Vec<f64> {
    let len = y.first().map_or(0, |v| v.len());
    let (pre, lead) = (nominal_window_samples(RING_PRE_S, rate_hz), nominal_window_samples(RING_LEAD_IN_S, rate_hz));
    let dt = 1.0 / rate_hz;
    let mut best = vec![f64::INFINITY; y.len()];
    // A column of the true force's basis on the lead-in and the window, through `q`.
    let through = |u: Vec<f64>| -> Vec<f64> {
        let v = q.map_or(u.clone(), |q| filtered(&u, q));
        v[lead..].to_vec()
    };
    let dot = |a: &[f64], b: &[f64]| -> f64 { a.iter().zip(b).map(|(a, v)| a * v).sum() };
    let one = through(vec![1.0; lead + len]);
    let one_y: Vec<f64> = y.iter().map(|yr| dot(&one, yr)).collect();
    let yty: Vec<f64> = y.iter().map(|yr| yr.iter().map(|v| v * v).sum()).collect();
    let (tau_lo, tau_hi) = (
        -(nominal_window_samples(RING_STEP_LEAD_S, rate_hz) as i64),
        nominal_window_samples(RING_STEP_LAG_S, rate_hz) as i64,
    );
    let span = (tau_hi - tau_lo) as usize;
    // The drop's columns s, s·t', s·t'² are 0 before it and functions of the
    // samples since it after it (t' = k − at), and the filter starts from
    // rest at sample 0, so it stays at rest until the drop: the columns of
    // a drop `o` samples earlier than the last τ's are the last τ's columns
    // read `o` samples on — the same operations on the same values. So each
    // width's three columns are put through `q` once, with the drop at the
    // last τ and `span` samples longer, and every τ reads its slice.
    let at_hi = pre as i64 + lead as i64 + tau_hi;
    let drop_cols: Vec<[Vec<f64>; 3]> = RING_RAMPS_S
        .iter()
        .map(|&width_s| {
            let m = (width_s * rate_hz).round() as i64;
            // After the drop (ramp s from `at_hi` over m samples): s, s·t', s·t'².
            let mut cols = [(); 3].map(|_| Vec::with_capacity(lead + len + span));
            for k in 0..(lead + len + span) as i64 {
                let t = (k - at_hi) as f64 * dt;
                let s = if k < at_hi {
                    0.0
                } else if k >= at_hi + m {
                    1.0
                } else {
                    0.5 - 0.5 * (std::f64::consts::PI * (k - at_hi) as f64 / m as f64).cos()
                };
                cols[0].push(s);
                cols[1].push(s * t);
                cols[2].push(s * t * t);
            }
            cols.map(|u| q.map_or(u.clone(), |q| filtered(&u, q)))
        })
        .collect();
    for tau in tau_lo..=tau_hi {
        let at = pre as i64 + lead as i64 + tau;
        let times: Vec<f64> = (0..(lead + len) as i64).map(|k| (k - at) as f64 * dt).collect();
        let t_col = through(times);
        let t_y: Vec<f64> = y.iter().map(|yr| dot(&t_col, yr)).collect();
        // The window's first sample in the columns of the drop at `at_hi`.
        let from = lead + (at_hi - at) as usize;
        for cols in &drop_cols {
            let [s_col, st_col, stt_col] = [0, 1, 2].map(|c| &cols[c][from..from + len]);
            let basis: [&[f64]; 5] = [&one, &t_col, s_col, st_col, stt_col];
            const UPPER: [(usize, usize); 15] = [
                (0, 0),
                (0, 1),
                (0, 2),
                (0, 3),
                (0, 4),
                (1, 1),
                (1, 2),
                (1, 3),
                (1, 4),
                (2, 2),
                (2, 3),
                (2, 4),
                (3, 3),
                (3, 4),
                (4, 4),
            ];
            let mut xtx = [0.0; 25];
            for ((i, j), v) in UPPER.into_iter().zip(dots(UPPER.map(|(i, j)| (basis[i], basis[j])))) {
                (xtx[5 * i + j], xtx[5 * j + i]) = (v, v);
            }
            let Some(inv) = rig_estimate::linear::Normal::from_row_major(5, &xtx, vec![0.0; 5]).inverse() else {
                continue;
            };
            for (r, yr) in y.iter().enumerate() {
                let [sy, sty, stty] = dots([(s_col, yr), (st_col, yr), (stt_col, yr)]);
                let xty = [one_y[r], t_y[r], sy, sty, stty];
                let fitted: f64 = (0..5).map(|i| xty[i] * (0..5).map(|j| inv[5 * i + j] * xty[j]).sum::<f64>()).sum();
                let rms = ((yty[r] - fitted).max(0.0) / len as f64).sqrt();
                if rms < best[r] {
                    best[r] = rms;
                }
            }
        }
    }
    best
}

/// Σ_k a[k]·b[k] of each of the `M` pairs (k up to the shortest slice's
/// length: the ring's columns and averages all have the window's), each summed in k's order from −0.0 as `Iterator::sum` folds it, so each
/// is `a.iter().zip(b).map(|(a, b)| a * b).sum()` to the bit; the `M` sums
/// in one pass: each addition waits for its sum's last, the sums are
/// independent, so the processor overlaps them (the latency-bound
/// recursions' lanes, [`super::corrected_pairs`]).
fn dots<const M: usize>(pairs: [(&[f64], &[f64]); M]) -> [f64; M] {
    let n = pairs.iter().map(|(a, b)| a.len().min(b.len())).min().unwrap_or(0);
    let pairs = pairs.map(|(a, b)| (&a[..n], &b[..n]));
    let mut acc = [-0.0f64; M];
    for k in 0..n {
        for (s, (a, b)) in acc.iter_mut().zip(&pairs) {
            *s += a[k] * b[k];
        }
    }
    acc
}

#[cfg(test)]
mod tests {
    use super::{
        Biquad, RING_LEAD_IN_S, RING_POST_S, RING_PRE_S, RING_RAMPS_S, RING_STEP_LAG_S, RING_STEP_LEAD_S, filtered,
        ring_misfits,
    };
    use rig_types::sensor::nominal_window_samples;

    /// [`ring_misfits`] as it was before its shared columns: every point
    /// builds its own five columns and 25 sums.
    fn each_points_own(y: &[&[f64]], q: Option<Biquad>, rate_hz: f64) -> Vec<f64> {
        let len = y.first().map_or(0, |v| v.len());
        let (pre, lead) =
            (nominal_window_samples(RING_PRE_S, rate_hz), nominal_window_samples(RING_LEAD_IN_S, rate_hz));
        let dt = 1.0 / rate_hz;
        let mut best = vec![f64::INFINITY; y.len()];
        let taus = -(nominal_window_samples(RING_STEP_LEAD_S, rate_hz) as i64)
            ..=nominal_window_samples(RING_STEP_LAG_S, rate_hz) as i64;
        for tau in taus {
            let at = pre as i64 + lead as i64 + tau;
            for width_s in RING_RAMPS_S {
                let m = (width_s * rate_hz).round() as i64;
                // The true force's basis on the lead-in and the window: 1, t, and
                // after the drop (ramp s from `at` over m samples) s, s·t', s·t'².
                let basis: Vec<Vec<f64>> = (0..5)
                    .map(|j| {
                        let u: Vec<f64> = (0..(lead + len) as i64)
                            .map(|k| {
                                let t = (k - at) as f64 * dt;
                                let s = if k < at {
                                    0.0
                                } else if k >= at + m {
                                    1.0
                                } else {
                                    0.5 - 0.5 * (std::f64::consts::PI * (k - at) as f64 / m as f64).cos()
                                };
                                [1.0, t, s, s * t, s * t * t][j]
                            })
                            .collect();
                        let v = q.map_or(u.clone(), |q| filtered(&u, q));
                        v[lead..].to_vec()
                    })
                    .collect();
                let mut xtx = [0.0; 25];
                for i in 0..5 {
                    for j in 0..5 {
                        xtx[5 * i + j] = basis[i].iter().zip(&basis[j]).map(|(a, b)| a * b).sum();
                    }
                }
                let Some(inv) = rig_estimate::linear::Normal::from_row_major(5, &xtx, vec![0.0; 5]).inverse() else {
                    continue;
                };
                for (r, yr) in y.iter().enumerate() {
                    let xty: Vec<f64> = basis.iter().map(|b| b.iter().zip(*yr).map(|(a, v)| a * v).sum()).collect();
                    let yty: f64 = yr.iter().map(|v| v * v).sum();
                    let fitted: f64 =
                        (0..5).map(|i| xty[i] * (0..5).map(|j| inv[5 * i + j] * xty[j]).sum::<f64>()).sum();
                    let rms = ((yty - fitted).max(0.0) / len as f64).sqrt();
                    if rms < best[r] {
                        best[r] = rms;
                    }
                }
            }
        }
        best
    }

    /// The shared columns change no misfit's bit: synthetic averages (a
    /// drop through a sensor, a late drop, a ramp with a slow swing, a flat
    /// line), as recorded and through sensors of the grid's range, at
    /// 500 and 1000 Hz.
    #[test]
    fn ring_misfits_are_each_points_own_fit_to_the_bit() {
        for rate in [500.0, 1000.0] {
            let (pre, post) = (nominal_window_samples(RING_PRE_S, rate), nominal_window_samples(RING_POST_S, rate));
            let lead = nominal_window_samples(RING_LEAD_IN_S, rate);
            let n = pre + post + 1;
            let drop = |shift: f64, width_s: f64| -> Vec<f64> {
                (0..lead + n)
                    .map(|k| {
                        let t = (k as f64 - (lead + pre) as f64) / rate - shift;
                        let s = if t < 0.0 {
                            0.0
                        } else if t >= width_s {
                            1.0
                        } else {
                            0.5 - 0.5 * (std::f64::consts::PI * t / width_s).cos()
                        };
                        40.0 + 5.0 * t - s * (10.0 + 2.0 * t) + 0.3 * (2.0 * std::f64::consts::PI * 1.3 * t).sin()
                    })
                    .collect()
            };
            let sensor = Biquad::new(rate, 8.0, 0.25, false);
            let ys: Vec<Vec<f64>> = vec![
                filtered(&drop(0.0, 0.0), sensor)[lead..].to_vec(),
                drop(0.01, 0.0)[lead..].to_vec(),
                drop(-0.02, 0.02)[lead..].to_vec(),
                vec![12.5; n],
            ];
            let y: Vec<&[f64]> = ys.iter().map(|v| v.as_slice()).collect();
            for q in [
                None,
                Some(sensor),
                Some(Biquad::new(rate, 2.0, 0.05, false)),
                Some(Biquad::new(rate, 20.0, 0.4, false)),
            ] {
                let (a, b) = (ring_misfits(&y, q, rate), each_points_own(&y, q, rate));
                assert_eq!(a.len(), 4);
                for (x, r) in a.iter().zip(&b) {
                    assert_eq!(x.to_bits(), r.to_bits(), "{rate} Hz: {a:?} vs {b:?}");
                }
            }
        }
    }

    /// The ring's fit (module docs) on synthetic averages: a friction drop
    /// of 10 N with a slow slip after it, recorded through a 8 Hz, ζ 0.25
    /// sensor, is fitted through that sensor to within the normal
    /// equations' rounding (1e-4 N of 40 N) and leaves
    /// a ring as recorded; the same drop 10 ms late through no sensor (a
    /// delay) fits as recorded, and through the sensor it does not.
    #[test]
    fn a_ring_is_fitted_by_its_sensor_and_a_delay_is_not() {
        let rate = 500.0;
        let (pre, post) = (25usize, 100usize);
        let lead = 100usize;
        let force = |shift: usize| -> Vec<f64> {
            (0..lead + pre + post + 1)
                .map(|k| {
                    let t = (k as f64 - (lead + pre + shift) as f64) / rate;
                    if t < 0.0 { 40.0 + 5.0 * t } else { 30.0 - 2.0 * t + 4.0 * t * t }
                })
                .collect()
        };
        let sensor = Biquad::new(rate, 8.0, 0.25, false);
        let rings = filtered(&force(0), sensor)[lead..].to_vec();
        let late = force(5)[lead..].to_vec();
        let m = |y: &[f64], q: Option<Biquad>| ring_misfits(&[y], q, rate)[0];
        assert!(m(&rings, Some(sensor)) < 1e-4, "{}", m(&rings, Some(sensor)));
        assert!(m(&rings, None) > 0.3, "{}", m(&rings, None));
        assert!(m(&late, None) < 1e-4, "{}", m(&late, None));
        assert!(m(&late, Some(sensor)) > 0.3, "{}", m(&late, Some(sensor)));
    }
}
