//! The free-decay analysis (log decrement from successive extrema, Eqs.
//! 4-2a/b and 4-3). Encoder signals (angle from ticks, the speed
//! differentiator, the zero-phase moving average) are `rig_types::sensor`.

use crate::{CalibrateError, formulas};
pub use rig_types::contract::{DecayAnalysis, DecayPair, DecaySettings, Extremum};
use rig_types::sensor::{centred_moving_average, half_window_samples};
use std::f64::consts::PI;

/// Finds alternating extrema of `x` (after zero-phase smoothing) with hysteresis.
/// Each extremum time is refined by a parabola through its three samples.
pub fn find_extrema(time_s: &[f64], x: &[f64], s: &DecaySettings) -> Vec<Extremum> {
    let n = time_s.len().min(x.len());
    if n < 3 {
        return Vec::new();
    }
    let h = half_window_samples(&time_s[..n], s.smooth_half_s);
    let y = centred_moving_average(&x[..n], h);
    let fit = half_window_samples(&time_s[..n], s.peak_fit_half_s);
    let mut out = Vec::new();
    // Direction unknown at first: track both running max and min until one is confirmed.
    let (mut imax, mut imin) = (0usize, 0usize);
    let mut looking: Option<bool> = None; // Some(true): looking for a max
    for i in 1..n {
        match looking {
            None => {
                if y[i] > y[imax] {
                    imax = i;
                }
                if y[i] < y[imin] {
                    imin = i;
                }
                if y[imax] - y[i] > s.hysteresis && imax > 0 {
                    out.push(refine(time_s, &y, imax, fit, true));
                    looking = Some(false);
                    imin = i;
                } else if y[i] - y[imin] > s.hysteresis && imin > 0 {
                    out.push(refine(time_s, &y, imin, fit, false));
                    looking = Some(true);
                    imax = i;
                }
            }
            Some(true) => {
                if y[i] > y[imax] {
                    imax = i;
                } else if y[imax] - y[i] > s.hysteresis {
                    out.push(refine(time_s, &y, imax, fit, true));
                    looking = Some(false);
                    imin = i;
                }
            }
            Some(false) => {
                if y[i] < y[imin] {
                    imin = i;
                } else if y[i] - y[imin] > s.hysteresis {
                    out.push(refine(time_s, &y, imin, fit, false));
                    looking = Some(true);
                    imax = i;
                }
            }
        }
    }
    out
}

/// Refines extremum i by a least-squares parabola over ±`fit_half` samples of
/// the smoothed signal. Why a fitted parabola: encoder quantisation leaves flat
/// tops several samples wide, so a three-point vertex (or the arg-max) jitters
/// by milliseconds; the fit over a wider symmetric span does not. Falls back to
/// the sample when the fit is degenerate or its vertex leaves the span.
fn refine(t: &[f64], y: &[f64], i: usize, fit_half: usize, is_max: bool) -> Extremum {
    let lo = i.saturating_sub(fit_half);
    let hi = (i + fit_half).min(y.len() - 1);
    let fallback = Extremum { time_s: t[i], value: y[i], is_max };
    if hi - lo < 4 {
        return fallback;
    }
    // Least squares y = a + b u + c u², u = t − t_i (centred for conditioning),
    // solved by the workspace's one solver (a singular fit falls back).
    let mut ne = rig_types::linear::Normal::new(3);
    for k in lo..=hi {
        let u = t[k] - t[i];
        ne.add_row(&[1.0, u, u * u], y[k]);
    }
    let Some(abc) = ne.solve() else {
        return fallback;
    };
    let (a, b, c) = (abc[0], abc[1], abc[2]);
    if c == 0.0 || (c < 0.0) != is_max {
        return fallback;
    }
    let u = -b / (2.0 * c);
    if u < t[lo] - t[i] || u > t[hi] - t[i] {
        return fallback;
    }
    Extremum { time_s: t[i] + u, value: a + b * u + c * u * u, is_max }
}

/// Free-decay analysis of one record: extrema, then every pair (k, k+2)
/// with both swings above `min_swing`, each giving δ, ξ, ω_d, ω_n.
/// Returns `NoDecay` (data, not a panic) when fewer than one pair qualifies.
pub fn decay_analysis(
    label: &str,
    time_s: &[f64],
    x: &[f64],
    s: &DecaySettings,
) -> Result<DecayAnalysis, CalibrateError> {
    let extrema: Vec<Extremum> = find_extrema(time_s, x, s).into_iter().skip(s.skip_extrema).collect();
    let mut pairs = Vec::new();
    for k in 0..extrema.len().saturating_sub(3) {
        let x1 = (extrema[k + 1].value - extrema[k].value).abs();
        let x2 = (extrema[k + 3].value - extrema[k + 2].value).abs();
        if x2 < s.min_swing {
            break; // later swings are only smaller: the decay has reached the floor
        }
        let delta = formulas::log_decrement(x1, x2);
        let xi = formulas::damping_ratio(delta);
        let period = extrema[k + 2].time_s - extrema[k].time_s;
        let wd = 2.0 * PI / period;
        pairs.push(DecayPair {
            t1_s: extrema[k].time_s,
            t2_s: extrema[k + 2].time_s,
            x1,
            x2,
            log_decrement: delta,
            damping_ratio: xi,
            damped_rad_s: wd,
            natural_rad_s: formulas::natural_from_damped(wd, xi),
        });
    }
    if pairs.is_empty() {
        return Err(CalibrateError::NoDecay {
            what: label.to_string(),
            reason: format!("{} extrema found, no pair of swings above {}", extrema.len(), s.min_swing),
        });
    }
    let col = |f: fn(&DecayPair) -> f64| pairs.iter().map(f).collect::<Vec<f64>>();
    let ms = |v: Vec<f64>| (crate::stats::mean(&v).unwrap_or(f64::NAN), crate::stats::sample_std(&v).unwrap_or(0.0));
    let (dm, ds) = ms(col(|p| p.log_decrement));
    let (xm, xs) = ms(col(|p| p.damping_ratio));
    let (wdm, wds) = ms(col(|p| p.damped_rad_s));
    let (wnm, wns) = ms(col(|p| p.natural_rad_s));
    Ok(DecayAnalysis {
        extrema,
        pairs,
        log_decrement_mean: dm,
        log_decrement_std: ds,
        damping_ratio_mean: xm,
        damping_ratio_std: xs,
        damped_rad_s_mean: wdm,
        damped_rad_s_std: wds,
        natural_rad_s_mean: wnm,
        natural_rad_s_std: wns,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings() -> DecaySettings {
        DecaySettings { smooth_half_s: 0.02, peak_fit_half_s: 0.15, hysteresis: 0.02, min_swing: 0.05, skip_extrema: 0 }
    }

    /// A damped sinusoid with known δ = 0.55 and ω_d = 2.9 rad/s about an
    /// offset, sampled at 500 Hz and quantised to encoder ticks as the rig is.
    #[test]
    fn recovers_known_log_decrement_from_quantised_twist() {
        let (delta, wd) = (0.55_f64, 2.9_f64);
        let sigma = delta * wd / (2.0 * PI);
        let t: Vec<f64> = (0..10_000).map(|i| i as f64 * 0.002).collect();
        let ticks: Vec<i64> = t
            .iter()
            .map(|&t| {
                let phi = 0.4 + 3.0 * (-sigma * t).exp() * (wd * t).cos();
                (phi / (2.0 * PI / 1000.0)).round() as i64
            })
            .collect();
        let x = rig_types::sensor::ticks_to_rad(&ticks, 1000);
        let a = decay_analysis("synthetic", &t, &x, &settings()).unwrap();
        assert!(a.pairs.len() >= 8, "{} pairs", a.pairs.len());
        assert!((a.log_decrement_mean - delta).abs() < 0.01, "δ = {}", a.log_decrement_mean);
        assert!((a.damped_rad_s_mean - wd).abs() < 0.005, "ω_d = {}", a.damped_rad_s_mean);
        let xi = delta / (4.0 * PI * PI + delta * delta).sqrt();
        assert!((a.damping_ratio_mean - xi).abs() < 0.002);
        assert!((a.natural_rad_s_mean - wd / (1.0 - xi * xi).sqrt()).abs() < 0.01);
    }

    #[test]
    fn no_oscillation_is_reported_not_panicked() {
        let t: Vec<f64> = (0..1000).map(|i| i as f64 * 0.002).collect();
        let x = vec![1.0; 1000];
        assert!(matches!(decay_analysis("flat", &t, &x, &settings()), Err(CalibrateError::NoDecay { .. })));
    }
}
