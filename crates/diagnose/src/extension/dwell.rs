//! Does the break-away level follow the time the contact stood? The
//! extension library's `log_dwell` signal ([`rig_model::extension`]: μs ×
//! (1 + c_d ln(1 + t_stick/τ_d)), contact ageing, Dieterich 1972) tested on
//! the records' break-aways, where teacher-forcing in slip cannot see it
//! (issue 25, item 5).
//!
//! No model of the vocabulary has a static level that depends on the dwell
//! (the rig model's μs is one number), so a dependence in the records is a
//! mismatch of every model the diagnosis can build. The longest dwell of a
//! run is its first: the rotor stands from rest until the drive has wound
//! the shaft up (seconds), where a steady stick-slip stick lasts a fraction
//! of its period. Compared **within a run** (same normal force, same
//! sensor, same smoothing), the first break-away's level against the run's
//! steady ones removes what differs between runs (force level, rise rate).
//!
//! For every operating point with a first break-away and at least two
//! steady sticks (a stuck stretch of at least [`MIN_DWELL_S`] that starts and
//! ends inside the run, [`crate::channels::stuck_stretches`], whose peak
//! force exceeds the run's mean slip force by [`STICK_EXCESS`]: a dip of
//! |Ω1| below the slip speed in which the force stays at its slip level is
//! no stick, and its "break-away" would read as a huge dwell effect): peak
//! of the friction force smoothed over the rotor-speed window in each stuck
//! stretch (as [`crate::extension`] reads break-aways), d_r = first peak /
//! mean steady peak − 1 and x_r = ln(1 + t_first/τ_d) − mean ln(1 + t/τ_d)
//! of the steady ones. The slope through the origin b = Σ d x / Σ x² (the
//! relative change of μs per unit of log dwell, the library's c_d) with its
//! standard error (residual variance over n − 1 runs ⊕ each run's spread
//! of one break-away, [`slope`]; at least [`MIN_RUNS`] runs): the
//! check's statistic is b, one-sided (contact ageing strengthens a contact
//! with its age, Dieterich 1972; a first break-away *below* the steady ones
//! is what a modulated normal force does: the first break-away falls where
//! N dips — a right `normal_force_modulation` model of
//! `free_run_right_models`, seed 9300, reads −3.95 % ± 1.07 %), its floor the standard error ⊕ [`MIN_SLOPE`]
//! (a consistent but small slope is the smoothing's bias, not ageing: the
//! force rises more slowly before the first break-away, during the ramp),
//! and it is flagged above `breakaway_dwell_ratio` (pipeline.toml).
//!
//! # Calibration (`breakaway_dwell_probe` in crates/virtual-rig/tests/hidden_effects.rs)
//!
//! The stick-slipping null and the static-friction-ageing case of the CI
//! battery drawn with 20 battery seeds (7000 + 1000 k): nulls b = +0.001 to
//! +0.006 (the smoothing's bias, always positive), ageing +0.03 to +0.06
//! (B = 4–10 % of μk per e-fold); before the stick filter a null run whose
//! slow dips never stuck read +0.69.

use crate::channels::{ChannelCheck, stuck_stretches};
use crate::prepare::RunSignals;
use rig_model::extension::DWELL_TIME_S;
use rig_types::sensor::{centred_moving_average, half_window_samples};

/// The check's name (run kind `operating_point`).
pub const CHECK: &str = "operating_point.breakaway_dwell";

/// A stuck stretch shorter than this is the speed's chatter around the slip
/// threshold, not a stick (the real sticks of the rig last 0.3–1 s).
pub const MIN_DWELL_S: f64 = 0.1;

/// The floor of the slope b: the smoothing's bias (module docs: the
/// stick-slipping nulls' slopes reach +0.006).
pub const MIN_SLOPE: f64 = 0.006;

/// A steady stuck stretch is a stick when its peak force exceeds the run's
/// mean slip force by this fraction (the rig's μs/μk is 1.3–1.8).
pub const STICK_EXCESS: f64 = 0.1;

/// One run's comparison: (run id, x_r, d_r, first dwell s, first peak N,
/// mean steady peak N, relative SD of the steady peaks: the spread one
/// break-away of the run has without any dwell effect).
pub type DwellRow = (String, f64, f64, f64, f64, f64, f64);

/// Each run's first and steady break-aways (module docs).
pub fn dwell_rows(runs: &[RunSignals], slip_rad_s: f64, half_window_s: f64) -> Vec<DwellRow> {
    let log_dwell = |t: f64| (t.max(0.0) / DWELL_TIME_S).ln_1p();
    let mut out = Vec::new();
    for r in runs {
        let w = &r.rotor_speed_rad_s;
        let Some(k0) = w.iter().position(|x| x.abs() >= slip_rad_s) else { continue };
        if k0 == 0 || r.normal_force_n <= 0.0 {
            continue;
        }
        let f = centred_moving_average(&r.friction_force_n, half_window_samples(&r.time_s, half_window_s));
        let peak = |a: usize, b: usize| f[a..b].iter().copied().fold(f64::NEG_INFINITY, f64::max);
        let slip: Vec<f64> = r.slip_idx.iter().filter_map(|&k| r.friction_force_n.get(k).copied()).collect();
        let slip_force = slip.iter().sum::<f64>() / slip.len().max(1) as f64;
        let steady: Vec<(f64, f64)> = stuck_stretches(w, slip_rad_s)
            .into_iter()
            .filter(|&(j, k)| j > k0 && r.time_s[k] - r.time_s[j] >= MIN_DWELL_S)
            .map(|(j, k)| (log_dwell(r.time_s[k] - r.time_s[j]), peak(j, k)))
            .filter(|&(_, p)| p > (1.0 + STICK_EXCESS) * slip_force)
            .collect();
        // Two steady sticks at least: their spread is the scatter of one break-away.
        if steady.len() < 2 {
            continue;
        }
        let n = steady.len() as f64;
        let (xs, ps) = (steady.iter().map(|s| s.0).sum::<f64>() / n, steady.iter().map(|s| s.1).sum::<f64>() / n);
        let (t0, p0) = (r.time_s[k0] - r.time_s[0], peak(0, k0));
        let sd = (steady.iter().map(|s| (s.1 - ps).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / ps;
        if ps > 0.0 && p0.is_finite() {
            out.push((r.id.clone(), log_dwell(t0) - xs, p0 / ps - 1.0, t0, p0, ps, sd));
        }
    }
    out
}

/// The slope b through the origin of d on x over the rows, its standard
/// error and the degrees of freedom (module docs): the run-level residual
/// variance over n − 1 runs ⊕ each run's spread of one break-away (its
/// steady peaks' relative SD: a modulated normal force scatters every
/// break-away, the first included), propagated as Σ x² σ² / (Σ x²)².
/// `None` below [`MIN_RUNS`] runs.
pub fn slope(rows: &[DwellRow]) -> Option<(f64, f64, usize)> {
    let sxx: f64 = rows.iter().map(|r| r.1 * r.1).sum();
    if rows.len() < MIN_RUNS || sxx <= 0.0 {
        return None;
    }
    let b = rows.iter().map(|r| r.1 * r.2).sum::<f64>() / sxx;
    let dof = rows.len() - 1;
    let s2 = rows.iter().map(|r| (r.2 - b * r.1).powi(2)).sum::<f64>() / dof as f64;
    let within = rows.iter().map(|r| (r.1 * r.6).powi(2)).sum::<f64>() / (sxx * sxx);
    Some((b, (s2 / sxx + within).sqrt(), dof))
}

/// Runs the slope needs (two residual degrees of freedom: one run's
/// residual says nothing of the scatter).
pub const MIN_RUNS: usize = 3;

/// The check (module docs): flagged when b over its floor (standard error
/// ⊕ [`MIN_SLOPE`]) exceeds `threshold` (one-sided).
pub fn breakaway_dwell_check(runs: &[RunSignals], slip_rad_s: f64, half_window_s: f64, threshold: f64) -> ChannelCheck {
    let rows = dwell_rows(runs, slip_rad_s, half_window_s);
    let ids: Vec<String> = rows.iter().map(|r| r.0.clone()).collect();
    let Some((b, se, dof)) = slope(&rows) else {
        return ChannelCheck {
            channel: CHECK.into(),
            run_kind: "operating_point".into(),
            runs: ids,
            statistic: 0.0,
            noise_floor: 0.0,
            ratio: 0.0,
            threshold: f64::INFINITY,
            flagged: false,
            detail: format!(
                "fewer than {MIN_RUNS} runs both break away from rest and stick and slip: the dwell cannot be compared"
            ),
        };
    };
    let floor = se.hypot(MIN_SLOPE);
    // One-sided (module docs): only a level that grows with the dwell is ageing.
    let ratio = b / floor;
    let per_run: Vec<String> = rows
        .iter()
        .map(|r| format!("{} first {:.2} s {:.3} N vs steady {:.3} N ({:+.2} %)", r.0, r.3, r.4, r.5, 100.0 * r.2))
        .collect();
    ChannelCheck {
        channel: CHECK.into(),
        run_kind: "operating_point".into(),
        runs: ids,
        statistic: b,
        noise_floor: floor,
        ratio,
        threshold,
        flagged: ratio > threshold,
        detail: format!(
            "the break-away level changes by {:+.2} % ± {:.2} % ({dof} dof) per unit of ln(1 + t_stick/{DWELL_TIME_S} \
             s) within the runs (first break-away from rest against the steady sticks; floor ⊕ {:.1} %): {}",
            100.0 * b,
            100.0 * se,
            100.0 * MIN_SLOPE,
            per_run.join("; ")
        ),
    }
}
