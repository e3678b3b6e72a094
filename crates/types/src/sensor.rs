//! The sensor chain, defined once: encoder quantisation (angle → cumulative
//! ticks), ticks → angle, the speed differentiators and the force sensor's
//! mV → N line. Measured recordings
//! and simulated angles go through these same functions (calibration,
//! estimation, simulation, sweeps, spectra, diagnosis, the virtual rig), so
//! measurement and model see the same quantisation and filter.

use std::f64::consts::PI;

/// Half-width of the documented speed differentiator, seconds.
///
/// Why 20 ms: one encoder tick is 2π/1000 rad; a plain first difference at
/// 500 Hz turns one tick into 3.14 rad/s of noise. A central difference over
/// ±20 ms (a 40 ms baseline) shrinks that to 0.157 rad/s, and its frequency
/// response (a 40 ms boxcar of the true speed) still passes 0.5 Hz torsional
/// oscillations with 0.05 % loss and stick-slip harmonics up to ≈ 10 Hz with
/// < 10 % loss. Followed by the same-width centred moving average, the total
/// kernel is a triangle (side lobes −27 dB instead of −13 dB), still zero phase.
pub const SPEED_HALF_WINDOW_S: f64 = 0.020;

/// One encoder tick, rad: 2π / `ticks_per_rev`.
pub fn tick_rad(ticks_per_rev: u32) -> f64 {
    2.0 * PI / f64::from(ticks_per_rev)
}

/// Encoder model: the cumulative count of an incremental encoder with
/// `ticks_per_rev` ticks per revolution, floor(angle / (2π / ticks_per_rev)).
pub fn encoder_ticks(angle_rad: &[f64], ticks_per_rev: u32) -> Vec<i64> {
    let tick = tick_rad(ticks_per_rev);
    angle_rad.iter().map(|a| (a / tick).floor() as i64).collect()
}

/// Cumulative ticks → angle in rad.
pub fn ticks_to_rad(ticks: &[i64], ticks_per_rev: u32) -> Vec<f64> {
    let k = tick_rad(ticks_per_rev);
    ticks.iter().map(|&t| t as f64 * k).collect()
}

/// Speed resolution of a difference over `w` samples at `dt_s`: one tick per
/// `w · dt_s` seconds, rad/s.
pub fn speed_resolution_rad_s(ticks_per_rev: u32, w: usize, dt_s: f64) -> f64 {
    tick_rad(ticks_per_rev) / (w as f64 * dt_s)
}

/// Samples in a half window of `half_s` seconds, from the record's measured
/// step ([`window_samples`]; the time column is authoritative, the nominal
/// rate is not trusted).
pub fn half_window_samples(time_s: &[f64], half_s: f64) -> usize {
    window_samples(time_s, half_s)
}

/// Samples in a window of `window_s` seconds (at least 1), from the
/// record's measured step ([`measured_step_s`] about its mean step); 0 when
/// the record has fewer than two samples or no positive step. Every window
/// of the analysis is declared in seconds and counted in samples here, so a
/// campaign at another sample rate keeps its windows' length. The step is the
/// one [`clock_rate_hz`] reads, so a window counted here and one counted at
/// the records' clock agree: the median step would not (1/510 s written at
/// 0.1 ms gives steps of 1.9 and 2.0 ms, whose median is 2.0 ms).
pub fn window_samples(time_s: &[f64], window_s: f64) -> usize {
    let n = time_s.len();
    if n < 2 {
        return 0;
    }
    let mean_step_s = (time_s[n - 1] - time_s[0]) / (n - 1) as f64;
    match measured_step_s(&[time_s], mean_step_s) {
        Some(step_s) => ((window_s / step_s).round() as usize).max(1),
        None => 0,
    }
}

/// Σ and count of the steps of `records` within [½, 3/2]× `reference_s`,
/// and the count of every step. Four partial sums, step k into sum k mod 4
/// (a fixed order: the same bits on every call), so the additions do not
/// wait on each other: the pass runs once per window count of every free
/// run and each time a floor asks for a campaign's clock.
fn steps_in_band(records: &[&[f64]], reference_s: f64) -> (f64, usize, usize) {
    let (lo, hi) = (0.5 * reference_s, 1.5 * reference_s);
    let (mut sum, mut n, mut all) = ([0.0f64; 4], 0usize, 0usize);
    for t in records {
        let steps = t.len().saturating_sub(1);
        all += steps;
        let mut step = |lane: usize, k: usize| {
            let d = t[k + 1] - t[k];
            let inside = d >= lo && d <= hi;
            sum[lane] += if inside { d } else { 0.0 };
            n += usize::from(inside);
        };
        let quads = steps / 4 * 4;
        for k in (0..quads).step_by(4) {
            for lane in 0..4 {
                step(lane, k + lane);
            }
        }
        for k in quads..steps {
            step(k - quads, k);
        }
    }
    ((sum[0] + sum[1]) + (sum[2] + sum[3]), n, all)
}

/// The sample step of `records` (one recorder's time columns), s, measured:
/// the mean of their steps within [½, 3/2]× `reference_s` (gaps, dropped
/// samples and repeated stamps left out; jitter up to half a step and the
/// column's rounding average out). When fewer than half the steps fall in
/// that band (a reference off by 2× or more, gaps over half the record), the
/// band is taken about the median step. `None`: no step, or no positive
/// median step. One linear pass without allocation when the reference holds
/// (the record's mean step for [`window_samples`], the declared step for
/// [`clock_rate_hz`]).
pub fn measured_step_s(records: &[&[f64]], reference_s: f64) -> Option<f64> {
    let (sum, n, all) = steps_in_band(records, reference_s);
    if all == 0 {
        return None;
    }
    if 2 * n >= all && reference_s > 0.0 {
        return Some(sum / n as f64);
    }
    let mut d: Vec<f64> = records.iter().flat_map(|t| t.windows(2).map(|w| w[1] - w[0])).collect();
    let mid = d.len() / 2;
    let (_, &mut med, _) = d.select_nth_unstable_by(mid, f64::total_cmp);
    if med <= 0.0 {
        return None;
    }
    let (sum, n, _) = steps_in_band(records, med);
    Some(sum / n as f64)
}

/// Samples in a window of `window_s` seconds at `sample_rate_hz` (at least
/// 1): for a statistic of the whole campaign (a noise floor, a resolution)
/// where no one run's time column speaks for all. The analysis passes the
/// records' clock (`Campaign::clock_rate_hz`), not the declared rate.
pub fn nominal_window_samples(window_s: f64, sample_rate_hz: f64) -> usize {
    ((window_s * sample_rate_hz).round() as usize).max(1)
}

/// The window count of records one recorder made with one window of
/// `window_s` seconds: the median of their per-record counts (`counts`,
/// each [`window_samples`] of a record), or, with no record, the window at
/// `rate_hz` ([`nominal_window_samples`]). For a statistic whose rows were
/// made with those windows (a noise correction, a timing floor): its window
/// is the count the rows were made of.
pub fn median_window_samples(mut counts: Vec<usize>, window_s: f64, rate_hz: f64) -> usize {
    counts.sort_unstable();
    counts.get(counts.len() / 2).copied().unwrap_or_else(|| nominal_window_samples(window_s, rate_hz))
}

/// How far, relative, a record's measured sample step may sit from the
/// declared one (`sample_rate_hz`) and still be read as the declared rate.
///
/// Why 10⁻³: a data-acquisition card's sample clock is a quartz crystal a
/// lab states to ±50–100 ppm (10⁻⁴); the time column written at 0.1 ms adds
/// below 10⁻⁵ over a record of 10 s or more ([`clock_rate_hz`] reads the
/// mean step). A tenth of a percent is ten times the crystal's statement:
/// within it the time column says the declared rate, and a derivative over
/// the declared step is off by less than 0.1 %, far below one encoder
/// tick's noise. Beyond it the declaration is wrong (a clock 2 % off, a rate
/// written for another recorder) and the time column is read.
pub const CLOCK_TOLERANCE: f64 = 1e-3;

/// The sample rate a derivative should divide by, Hz: the records' own clock.
///
/// The time column is the measurement of the time that elapsed;
/// `declared_rate_hz` (campaign.toml's `sample_rate_hz`) is a declaration.
/// The measured step is [`measured_step_s`] about the declared step: the
/// mean of the records' steps within [½, 3/2]× it (gaps, dropped samples and
/// repeated stamps left out; jitter up to half a step and the time column's
/// rounding average out), pooled over `records` (one recorder, one clock). Within [`CLOCK_TOLERANCE`] of the declared step the declared rate
/// is returned, bit for bit (the shipped campaign's outputs stay what they
/// were); otherwise 1 / the measured step. When fewer than half the steps
/// fall within [½, 3/2]× the declared step (a declaration off by a factor of
/// two or more), the band is taken about the median step instead. No step
/// at all (records of fewer than two samples): the declared rate.
pub fn clock_rate_hz(records: &[&[f64]], declared_rate_hz: f64) -> f64 {
    let declared_step_s = declared_rate_hz.recip();
    match measured_step_s(records, declared_step_s) {
        Some(step_s) if ((step_s - declared_step_s) / declared_step_s).abs() > CLOCK_TOLERANCE => step_s.recip(),
        _ => declared_rate_hz,
    }
}

/// Centred moving average over ±`half` samples; the window shrinks
/// symmetrically near the ends so the filter stays zero-phase everywhere.
pub fn centred_moving_average(x: &[f64], half: usize) -> Vec<f64> {
    let n = x.len();
    let mut prefix = Vec::with_capacity(n + 1);
    prefix.push(0.0);
    for v in x {
        prefix.push(prefix.last().copied().unwrap_or(0.0) + v);
    }
    (0..n)
        .map(|i| {
            let h = half.min(i).min(n - 1 - i);
            (prefix[i + h + 1] - prefix[i - h]) / (2 * h + 1) as f64
        })
        .collect()
}

/// Shaft speed from cumulative encoder ticks, rad/s (rotor 1 or motor side):
/// the documented differentiator (see [`SPEED_HALF_WINDOW_S`]).
///
/// Central difference (θ[i+h] − θ[i−h]) / (t[i+h] − t[i−h]) with h ≈ 20 ms of
/// samples, shrunk symmetrically at the ends (one-sided at the very first and
/// last sample), then a centred moving average of the same half-width. Zero
/// phase, so speed peaks keep their times. Returns one value per sample.
pub fn encoder_speed_rad_s(time_s: &[f64], ticks: &[i64], ticks_per_rev: u32) -> Vec<f64> {
    let n = time_s.len().min(ticks.len());
    if n < 2 {
        return vec![0.0; n];
    }
    let angle = ticks_to_rad(&ticks[..n], ticks_per_rev);
    let h = half_window_samples(&time_s[..n], SPEED_HALF_WINDOW_S);
    let raw: Vec<f64> = (0..n)
        .map(|i| {
            let k = h.min(i).min(n - 1 - i);
            let (a, b) = if k == 0 { if i == 0 { (0, 1) } else { (n - 2, n - 1) } } else { (i - k, i + k) };
            (angle[b] - angle[a]) / (time_s[b] - time_s[a])
        })
        .collect();
    centred_moving_average(&raw, h)
}

/// A simulated angle seen as the rig sees it: [`encoder_ticks`], then
/// [`encoder_speed_rad_s`].
pub fn quantised_speed_rad_s(time_s: &[f64], angle_rad: &[f64], ticks_per_rev: u32) -> Vec<f64> {
    encoder_speed_rad_s(time_s, &encoder_ticks(angle_rad, ticks_per_rev), ticks_per_rev)
}

/// Plain centred difference at every sample over ±`half` samples (at least
/// 1), the window cut at the ends (one-sided there):
/// Ω_i = (φ[i+h] − φ[i−h]) / (t[i+h] − t[i−h]). No smoothing, so it is a
/// linear operator on the angle that a fit can apply to measurement and model
/// alike; one tick gives a resolution of 2π/(ticks · 2·half·dt).
pub fn central_difference_rad_s(time_s: &[f64], angle_rad: &[f64], half: usize) -> Vec<f64> {
    let n = time_s.len().min(angle_rad.len());
    let half = half.max(1);
    (0..n)
        .map(|i| {
            let a = i.saturating_sub(half);
            let b = (i + half).min(n.saturating_sub(1));
            if b > a { (angle_rad[b] - angle_rad[a]) / (time_s[b] - time_s[a]) } else { 0.0 }
        })
        .collect()
}

/// The force sensor's calibration line, mV = offset + factor · N (Table
/// 4.6's procedure with an offset; `rig_calibrate` fits it).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ForceCal {
    pub factor_mv_per_n: f64,
    pub offset_mv: f64,
}

/// Force-sensor output → force on the pads, N: (mV − offset) / factor.
pub fn force_n(mv: &[f64], cal: ForceCal) -> Vec<f64> {
    mv.iter().map(|m| (m - cal.offset_mv) / cal.factor_mv_per_n).collect()
}

/// Force-sensor output → force, N, for a sensor that is not linear:
/// mV = a + b·F + c·F² (`abc`), F the root on the branch through the origin
/// of the load axis, written so that it tends to [`force_n`]'s (mV − a)/b as c → 0.
pub fn force_n_parabola(mv: &[f64], abc: [f64; 3]) -> Vec<f64> {
    let [a, b, c] = abc;
    mv.iter()
        .map(|m| {
            // c F² + b F + (a − mV) = 0.
            let disc = (b * b + 4.0 * c * (m - a)).max(0.0);
            2.0 * (m - a) / (b + disc.sqrt())
        })
        .collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn parabola_inverts_its_law_and_is_the_line_without_curvature() {
        let abc = [3.0, 210.0, 0.6];
        let f = [0.0, 1.5, 8.0, 25.0];
        let mv: Vec<f64> = f.iter().map(|x| abc[0] + abc[1] * x + abc[2] * x * x).collect();
        for (got, want) in force_n_parabola(&mv, abc).iter().zip(f) {
            assert!((got - want).abs() < 1e-12 * want.max(1.0), "{got} vs {want}");
        }
        let line = force_n(&mv, ForceCal { factor_mv_per_n: 210.0, offset_mv: 3.0 });
        for (p, l) in force_n_parabola(&mv, [3.0, 210.0, 0.0]).iter().zip(&line) {
            assert!((p - l).abs() < 1e-12 * l.abs().max(1.0));
        }
    }

    /// A constant speed of 16 rad/s quantised to 1000-tick encoder counts:
    /// the differentiator's noise must stay far below one tick per sample (3.14 rad/s).
    #[test]
    fn differentiator_on_constant_speed() {
        let t: Vec<f64> = (0..5000).map(|i| i as f64 * 0.002).collect();
        let angle: Vec<f64> = t.iter().map(|&t| 16.0 * t).collect();
        let w = quantised_speed_rad_s(&t, &angle, 1000);
        let worst = w[20..4980].iter().map(|v| (v - 16.0).abs()).fold(0.0, f64::max);
        assert!(worst < 0.16, "worst error {worst} rad/s");
    }

    /// A sinusoidal speed 10 + 5 sin(2π·0.5 t): zero phase, amplitude kept to 0.5 %.
    #[test]
    fn differentiator_keeps_phase_and_amplitude() {
        let t: Vec<f64> = (0..5000).map(|i| i as f64 * 0.002).collect();
        let w0 = 2.0 * PI * 0.5;
        let theta = |t: f64| 10.0 * t - 5.0 / w0 * (w0 * t).cos();
        let ticks: Vec<i64> = t.iter().map(|&t| (theta(t) / (2.0 * PI / 1000.0)).round() as i64).collect();
        let w = encoder_speed_rad_s(&t, &ticks, 1000);
        // Peak of 10 + 5 sin at t = 0.5 + 2k s.
        let i = 2250; // t = 4.5 s
        assert!((w[i] - 15.0).abs() < 0.1, "{}", w[i]);
        assert!((w[i - 25] - w[i + 25]).abs() < 0.1, "asymmetric about the peak");
    }

    /// Floor, not round: an angle just under one tick is count 0, one just
    /// over is count 1; negative angles count down; ticks → angle inverts it.
    #[test]
    fn encoder_floors_to_ticks() {
        let tick = 2.0 * PI / 1000.0;
        let n = encoder_ticks(&[0.0, 0.999 * tick, 1.001 * tick, -0.5 * tick, 2.0 * PI + 0.5 * tick], 1000);
        assert_eq!(n, vec![0, 0, 1, -1, 1000]);
        let back = ticks_to_rad(&n, 1000);
        assert!((back[4] - 2.0 * PI).abs() < 1e-12);
    }

    /// The window counts the grid's step: on an irregular grid (jitter, a
    /// gap, dropped samples) the mean of the steps about the grid's, the
    /// gap and the doubled steps left out (the median, 2 ms, would count 500
    /// samples in 1 s); on a 510 Hz column written at 0.1 ms, 510 Hz (the
    /// median, 2.0 ms, would count 50 in 0.1 s).
    #[test]
    fn window_samples_counts_the_grids_step() {
        let mut t = vec![0.0];
        for k in 1..4001 {
            let dt = match k % 7 {
                0 => 0.004,
                3 => 0.0019,
                _ => 0.002 + 1e-9 * (k % 5) as f64,
            };
            t.push(t[k - 1] + if k == 2000 { 1.5 } else { dt });
        }
        let on_grid: Vec<f64> = t.windows(2).map(|w| w[1] - w[0]).filter(|d| (d - 0.00195).abs() < 1e-4).collect();
        let mean = on_grid.iter().sum::<f64>() / on_grid.len() as f64;
        assert_eq!(window_samples(&t, 1.0), (1.0 / mean).round() as usize);
        assert_eq!(window_samples(&t, 1.0), 504);
        let rounded: Vec<f64> = (0..10_000).map(|k| (k as f64 / 510.0 * 1e4).round() / 1e4).collect();
        assert_eq!(window_samples(&rounded, 0.1), 51);
        assert_eq!(window_samples(&[0.0, 0.002, 0.004], 0.04), 20);
        assert_eq!(window_samples(&[0.0], 0.04), 0);
        assert_eq!(window_samples(&[0.0, 0.0, 0.0], 0.04), 0);
    }

    /// The clock a derivative divides by: the declared rate, bit for bit,
    /// on its grid (the time column written at 0.1 ms; jittered, with a
    /// gap); the time column's rate when the clock runs 2 % fast of the
    /// declaration, even written at 0.1 ms (where the median step, 2.0 ms,
    /// would say the declared rate), and when the declaration is off by 2×.
    #[test]
    fn clock_rate_reads_the_time_column_beyond_the_clock_tolerance() {
        let round4 = |x: f64| (x * 1e4).round() / 1e4;
        let grid = |rate: f64, n: usize| (0..n).map(|k| round4(k as f64 / rate)).collect::<Vec<f64>>();
        let on_grid = grid(500.0, 10_000);
        assert_eq!(clock_rate_hz(&[&on_grid[..]], 500.0).to_bits(), 500f64.to_bits());
        // Jitter ±0.4 ms about the 2 ms grid and a 0.5 s gap: still the declared rate.
        let mut jittered: Vec<f64> =
            (0..10_000).map(|k| k as f64 * 0.002 + 4e-4 * ((k * 7 % 3) as f64 - 1.0)).collect();
        for t in &mut jittered[6_000..] {
            *t += 0.5;
        }
        assert_eq!(clock_rate_hz(&[&jittered[..]], 500.0), 500.0);
        // A clock 2 % fast: 510 samples a second, declared 500.
        let fast = grid(510.0, 10_000);
        let mut d: Vec<f64> = fast.windows(2).map(|w| w[1] - w[0]).collect();
        d.sort_by(f64::total_cmp);
        assert!((d[d.len() / 2] - 0.002).abs() < 1e-12, "the rounded column's median step is the declared one");
        let r = clock_rate_hz(&[&fast[..]], 500.0);
        assert!((r / 510.0 - 1.0).abs() < 1e-5, "{r} Hz");
        // Pooled over records, one with a gap; a record of one sample adds nothing.
        let mut gapped = grid(510.0, 4_000);
        for t in &mut gapped[2_000..] {
            *t += 0.5;
        }
        let r = clock_rate_hz(&[&fast[..], &gapped[..], &[0.0][..]], 500.0);
        assert!((r / 510.0 - 1.0).abs() < 1e-5, "{r} Hz");
        // Declared 500 Hz, recorded at 1.2 kHz: the band about the median step.
        let r = clock_rate_hz(&[&grid(1200.0, 10_000)[..]], 500.0);
        assert!((r / 1200.0 - 1.0).abs() < 1e-4, "{r} Hz");
        // Within the tolerance (0.05 % off): the declaration stands.
        assert_eq!(clock_rate_hz(&[&grid(500.25, 10_000)[..]], 500.0), 500.0);
        assert_eq!(clock_rate_hz(&[&[0.0][..]], 500.0), 500.0);
        assert_eq!(clock_rate_hz(&[], 500.0), 500.0);
    }

    #[test]
    fn central_difference_is_exact_on_a_ramp() {
        let t: Vec<f64> = (0..100).map(|k| k as f64 * 0.002).collect();
        let a: Vec<f64> = t.iter().map(|x| 3.0 * x).collect();
        for half in [0, 1, 5] {
            let w = central_difference_rad_s(&t, &a, half);
            assert!(w.iter().all(|v| (v - 3.0).abs() < 1e-9), "half {half}");
        }
    }
}
