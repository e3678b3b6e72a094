//! What the free-run checks read in a run: the stuck stretches, the
//! break-away peaks, each channel's values and their noise floors.

use super::*;

/// The steady-window signals of one side (measured or simulated) that the
/// channel features are computed from.
pub(super) struct Window<'a> {
    pub(super) w1: &'a [f64],
    pub(super) w2: &'a [f64],
    pub(super) voltage_v: Option<&'a [f64]>,
    /// Friction force, N, smoothed over the rotor-speed window.
    pub(super) force_n: Option<&'a [f64]>,
    /// The window's break-away peaks, N ([`breakaway_peaks`]; empty for a
    /// cycle's sub-window, whose floor does not use them).
    pub(super) peaks: &'a [f64],
}

/// Every stuck stretch (|Ω1| below the slip speed) that starts and ends
/// inside the window, as [first, end) sample ranges: the extension's
/// break-away rows. Not the free-run break-away feature any more: on a
/// record most such stretches are encoder chatter of a creeping rotor
/// ([`breakaway_peaks`] reads the estimation's stick episodes instead); the
/// extension's rows should move to those too (open).
pub fn stuck_stretches(w1: &[f64], slip_rad_s: f64) -> Vec<(usize, usize)> {
    let mut out = Vec::new();
    let mut start: Option<usize> = None;
    for k in 1..w1.len() {
        let (was, is) = (w1[k - 1].abs() < slip_rad_s, w1[k].abs() < slip_rad_s);
        if is && !was {
            start = Some(k);
        } else if was
            && !is
            && let Some(j) = start.take()
        {
            out.push((j, k));
        }
    }
    out
}

/// Break-aways a window needs to define its break-away level: the floor
/// carries their spread, which one or two do not measure (an angle-periodic
/// normal force sets each break-away by the angle the rotor stuck at: a
/// right model of seed 9313 broke away at 9.4 N in the record and 11.5 N in
/// the simulation, one episode each, 219× a floor of force noise alone).
pub const MIN_BREAKAWAYS: usize = 3;

/// The break-away peaks of one side over samples `from..` of a run: the
/// peak of the raw friction force `force_n`, N, over each stick episode that
/// starts in the window and ends in a break-away, by the estimation's rules
/// (`rig_estimate::friction::stick_episodes`, `[shared.stick_episodes]`: the
/// encoder did not move over the difference window, for at least
/// `min_stick_s`, and the rotor reaches slip right after). The estimation
/// reads μs as the median of the same peaks over N0, so the model's static
/// level and this feature are one reading of the record. `rotor_angle_rad`
/// is the encoder's (a simulated angle quantised first); no episode below
/// `min_normal_force_n`, where the estimation reads none either.
pub(super) fn breakaway_peaks(
    time_s: &[f64],
    rotor_angle_rad: &[f64],
    force_n: &[f64],
    from: usize,
    normal_force_n: f64,
    o: &rig_estimate::FrictionOptions,
) -> Vec<f64> {
    if normal_force_n < o.min_normal_force_n {
        return Vec::new();
    }
    rig_estimate::friction::stick_episodes(time_s, rotor_angle_rad, o)
        .into_iter()
        .filter(|r| r.start >= from)
        .map(|r| force_n[r].iter().copied().fold(f64::NEG_INFINITY, f64::max))
        .collect()
}

pub(super) fn mean(x: &[f64]) -> f64 {
    if x.is_empty() { f64::NAN } else { x.iter().sum::<f64>() / x.len() as f64 }
}

/// Sample standard deviation (NaN below two values).
pub(super) fn sd(x: &[f64]) -> f64 {
    if x.len() < 2 {
        return f64::NAN;
    }
    let m = mean(x);
    (x.iter().map(|v| (v - m).powi(2)).sum::<f64>() / (x.len() - 1) as f64).sqrt()
}

/// The channel features of one window (module docs); `sigma_v` is removed
/// from the voltage's SD (0 for a simulation).
pub(super) fn channel_values(w: &Window, slip_rad_s: f64, sigma_v: f64) -> [f64; ChannelFeatures::N] {
    let ext = |x: &[f64], max: bool| {
        x.iter()
            .copied()
            .fold(if max { f64::NEG_INFINITY } else { f64::INFINITY }, if max { f64::max } else { f64::min })
    };
    let (vm, vs) = match w.voltage_v {
        Some(v) => {
            let m = mean(v);
            let var = v.iter().map(|x| (x - m).powi(2)).sum::<f64>() / v.len() as f64;
            (m, (var - sigma_v * sigma_v).max(0.0).sqrt())
        }
        None => (f64::NAN, f64::NAN),
    };
    let (slip, breakaway) = match w.force_n {
        Some(f) => {
            let s: Vec<f64> = w.w1.iter().zip(f).filter(|(w, _)| w.abs() >= slip_rad_s).map(|(_, f)| *f).collect();
            let level = if w.peaks.len() >= MIN_BREAKAWAYS { mean(w.peaks) } else { f64::NAN };
            (mean(&s), level)
        }
        None => (f64::NAN, f64::NAN),
    };
    let stuck = w.w1.iter().filter(|x| x.abs() < slip_rad_s).count() as f64 / w.w1.len().max(1) as f64;
    [ext(w.w1, true), ext(w.w1, false), ext(w.w2, true), ext(w.w2, false), vm, vs, slip, breakaway, stuck]
}

/// The resolution and white noise a run's floors start from: the speed
/// resolutions of Ω1 and Ω2, rad/s, σ_V, V, and σ_F of the raw force, N.
pub(super) struct Noise {
    pub(super) res_rad_s: (f64, f64),
    pub(super) sigma_v: f64,
    pub(super) sigma_f: f64,
}

/// Each feature's floor in one run, from the record (module docs): the
/// sensor's resolution or noise ⊕ the feature's spread over cycles of
/// `cycle` samples.
pub(super) fn channel_floors(w: &Window, slip_rad_s: f64, noise: &Noise, h1: usize, cycle: usize) -> ChannelFeatures {
    let n = w.w1.len();
    let Noise { res_rad_s, sigma_v, sigma_f } = *noise;
    let cycles: Vec<[f64; ChannelFeatures::N]> = (0..n / cycle.max(1))
        .map(|i| {
            let r = i * cycle..(i + 1) * cycle;
            let sub = Window {
                w1: &w.w1[r.clone()],
                w2: &w.w2[r.clone()],
                voltage_v: w.voltage_v.map(|v| &v[r.clone()]),
                force_n: w.force_n.map(|f| &f[r.clone()]),
                peaks: &[],
            };
            channel_values(&sub, slip_rad_s, sigma_v.max(0.0))
        })
        .collect();
    // Spread over cycles (0 below two cycles that define it) and its count.
    let spread = |i: usize| {
        let v: Vec<f64> = cycles.iter().map(|c| c[i]).filter(|x| x.is_finite()).collect();
        let s = sd(&v);
        (if s.is_finite() { s } else { 0.0 }, v.len().max(1) as f64)
    };
    let q = |a: f64, b: f64| a.hypot(b);
    let nf = n.max(1) as f64;
    let n_slip = w.w1.iter().filter(|x| x.abs() >= slip_rad_s).count().max(1) as f64;
    let peaks = w.peaks;
    let sd_peaks = if peaks.len() >= 2 { sd(peaks) } else { 0.0 };
    let mut v = [0.0; ChannelFeatures::N];
    for (i, x) in v.iter_mut().enumerate() {
        let (s, nc) = spread(i);
        *x = match i {
            0 | 1 => q(res_rad_s.0, s),
            2 | 3 => q(res_rad_s.1, s),
            4 => q(sigma_v / nf.sqrt(), s / nc.sqrt()),
            5 => q(sigma_v / (2.0 * nf).sqrt(), s / nc.sqrt()),
            6 => q(sigma_f / n_slip.sqrt(), s / nc.sqrt()),
            7 => q(sigma_f, sd_peaks / (peaks.len().max(1) as f64).sqrt()),
            _ => q(2.0 * h1 as f64 / cycle.max(1) as f64, s / nc.sqrt()),
        };
    }
    ChannelFeatures { values: v }
}
