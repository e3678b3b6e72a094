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
//! # Against the model's free run
//!
//! The records alone confuse a modulated normal force with ageing: the
//! full battery's strongest modulations (`ladder-normal_force_modulation-0-19`,
//! a = 0.16 at 2.89 Hz) put the first break-away from rest 6–12 % above
//! the steady ones (op-04 +6.33 %, op-17 +9.23 %, op-30 +12.03 %; slope
//! +4.71 % ± 1.01 %, 4.0× its floor), because the "steady sticks" of those
//! runs are the rotor's dips at the modulation's high N, not break-aways at
//! μs. Any model with the modulation does the same, so when the diagnosis
//! has a model the check reads the same rows on the final model's free run
//! (every operating point from rest with its fitted phases,
//! [`crate::channels::FreeRunPair`]'s `dwell`, one rule for both sides:
//! [`dwell_row`]) and tests the record's d minus the free run's on the
//! record's x ([`breakaway_dwell_model_check`], [`difference_rows`]; the
//! spread of one break-away is both sides' ⊕). There: free run +6.47 %,
//! +9.46 %, +12.17 %; difference slope −0.09 % ± 0.67 %, ratio −0.10. The
//! floor and threshold are the records-alone check's; the smoothing's bias
//! now cancels between the sides, so [`MIN_SLOPE`] is a margin.
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
    runs.iter()
        .filter(|r| r.normal_force_n > 0.0)
        .filter_map(|r| {
            let slip: Vec<f64> = r.slip_idx.iter().filter_map(|&k| r.friction_force_n.get(k).copied()).collect();
            let slip_force = slip.iter().sum::<f64>() / slip.len().max(1) as f64;
            let f = centred_moving_average(&r.friction_force_n, half_window_samples(&r.time_s, half_window_s));
            dwell_row(&r.id, &r.time_s, &r.rotor_speed_rad_s, &f, slip_force, slip_rad_s)
        })
        .collect()
}

/// One run's first and steady break-aways (module docs) from its rotor
/// speed `w1`, rad/s, and its friction force `smoothed_force_n`, N, already
/// smoothed over the rotor-speed window; `slip_force_n` the run's mean slip
/// force (the stick filter's reference). The record's rows
/// ([`dwell_rows`]) and a free run's ([`crate::channels::FreeRunPair`]'s
/// `dwell`) come from here, so both sides are read by one rule.
pub fn dwell_row(
    id: &str,
    time_s: &[f64],
    w1: &[f64],
    smoothed_force_n: &[f64],
    slip_force_n: f64,
    slip_rad_s: f64,
) -> Option<DwellRow> {
    let log_dwell = |t: f64| (t.max(0.0) / DWELL_TIME_S).ln_1p();
    let k0 = w1.iter().position(|x| x.abs() >= slip_rad_s)?;
    if k0 == 0 {
        return None;
    }
    let f = smoothed_force_n;
    let peak = |a: usize, b: usize| f[a..b].iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let steady: Vec<(f64, f64)> = stuck_stretches(w1, slip_rad_s)
        .into_iter()
        .filter(|&(j, k)| j > k0 && time_s[k] - time_s[j] >= MIN_DWELL_S)
        .map(|(j, k)| (log_dwell(time_s[k] - time_s[j]), peak(j, k)))
        .filter(|&(_, p)| p > (1.0 + STICK_EXCESS) * slip_force_n)
        .collect();
    // Two steady sticks at least: their spread is the scatter of one break-away.
    if steady.len() < 2 {
        return None;
    }
    let n = steady.len() as f64;
    let (xs, ps) = (steady.iter().map(|s| s.0).sum::<f64>() / n, steady.iter().map(|s| s.1).sum::<f64>() / n);
    let (t0, p0) = (time_s[k0] - time_s[0], peak(0, k0));
    let sd = (steady.iter().map(|s| (s.1 - ps).powi(2)).sum::<f64>() / (n - 1.0)).sqrt() / ps;
    (ps > 0.0 && p0.is_finite()).then(|| (id.to_string(), log_dwell(t0) - xs, p0 / ps - 1.0, t0, p0, ps, sd))
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

/// Each run's record row against the model's free-run row (module docs,
/// "Against the model's free run"): x the record's, d the record's d minus
/// the free run's, the spread of one break-away the root sum of both sides'.
/// Runs where either side has no row are left out.
pub fn difference_rows(pairs: &[(DwellRow, DwellRow)]) -> Vec<DwellRow> {
    pairs.iter().map(|(m, s)| (m.0.clone(), m.1, m.2 - s.2, m.3, m.4, s.4, m.6.hypot(s.6))).collect()
}

/// The check against a model's free run (module docs, "Against the model's
/// free run"): the slope b of [`difference_rows`] over its floor (standard
/// error ⊕ [`MIN_SLOPE`]), flagged above `threshold` (one-sided).
pub fn breakaway_dwell_model_check(pairs: &[(DwellRow, DwellRow)], threshold: f64) -> ChannelCheck {
    let rows = difference_rows(pairs);
    let per_run = pairs
        .iter()
        .map(|(m, s)| {
            format!(
                "{} first {:.2} s {:+.2} % over steady, free run {:.2} s {:+.2} %",
                m.0,
                m.3,
                100.0 * m.2,
                s.3,
                100.0 * s.2
            )
        })
        .collect::<Vec<_>>()
        .join("; ");
    let what = "record minus the final model's free run (first break-away from rest against the steady sticks, \
                each side within its runs";
    check_of(&rows, threshold, what, per_run)
}

/// The check (module docs): flagged when b over its floor (standard error
/// ⊕ [`MIN_SLOPE`]) exceeds `threshold` (one-sided). The records alone:
/// what the diagnosis judges when it has no model to simulate.
pub fn breakaway_dwell_check(runs: &[RunSignals], slip_rad_s: f64, half_window_s: f64, threshold: f64) -> ChannelCheck {
    let rows = dwell_rows(runs, slip_rad_s, half_window_s);
    let per_run: Vec<String> = rows
        .iter()
        .map(|r| format!("{} first {:.2} s {:.3} N vs steady {:.3} N ({:+.2} %)", r.0, r.3, r.4, r.5, 100.0 * r.2))
        .collect();
    check_of(
        &rows,
        threshold,
        "within the runs (first break-away from rest against the steady sticks",
        per_run.join("; "),
    )
}

/// The check of rows (either reading): slope, floor, flag and sentence.
fn check_of(rows: &[DwellRow], threshold: f64, what: &str, per_run: String) -> ChannelCheck {
    let ids: Vec<String> = rows.iter().map(|r| r.0.clone()).collect();
    let Some((b, se, dof)) = slope(rows) else {
        return ChannelCheck::not_testable(
            CHECK,
            ids,
            format!(
                "fewer than {MIN_RUNS} runs both break away from rest and stick and slip: the dwell cannot be compared"
            ),
        );
    };
    let floor = se.hypot(MIN_SLOPE);
    // One-sided (module docs): only a level that grows with the dwell is ageing.
    let ratio = b / floor;
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
             s) {what}; floor ⊕ {:.1} %): {per_run}",
            100.0 * b,
            100.0 * se,
            100.0 * MIN_SLOPE,
        ),
    }
}
