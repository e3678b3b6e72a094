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
//! # Every stick, under the model's normal force
//!
//! The first break-away against the steady ones has little power behind a
//! modulated normal force: each break-away falls where μs·N(t) meets the
//! spring's load, so its level scatters by the modulation's amplitude and the
//! first one's excess is read against that scatter (the full battery's
//! `mixed-normal_force_modulation+static_friction_aging-0`, B = 0.025 per
//! e-fold behind a = 0.20: +0.77 % ± 3.44 %, ratio 0.22). With a model, the
//! modulation is known: its fitted amplitude, frequency and each run's phase.
//! [`breakaway_ageing_check`] reads **every** stick episode of every
//! operating point by the estimation's rule (`[shared.stick_episodes]`,
//! [`rig_estimate::friction::stick_episodes`], as [`crate::breakaway`] reads
//! μs), its dwell t (the episode's length) and its level μ_b, the peak of
//! F/N(t, φ1) over the episode with N the final model's normal force
//! ([`rig_model::friction::normal_force_n`], the run's fitted phases): the
//! modulation divided out of each break-away. Contact ageing is
//! μs(t) = μs0 + B ln(1 + t/τ) (Dieterich 1972; the library's `log_dwell`,
//! [`rig_model::extension`]), so ln μ_b rises by B/μs per unit of
//! x = ln(1 + t/τ_d) and a right model's F/N at break-away is μs whatever the
//! dwell. The statistic is the slope b of ln μ_b on x **within runs** (each
//! run's rows centred on its own means, so its level, normal force and sensor
//! cancel; [`pooled_slope`]) pooled over the runs with at least two
//! break-aways, its standard error cluster-robust with the runs as clusters
//! (CR1; the sticks of one run share its phase error and drift, so they are
//! not independent), at least [`MIN_STICK_RUNS`] runs. One-sided as the first
//! break-away's reading, floor se ⊕ [`MIN_STICK_SLOPE`], the same threshold
//! (`breakaway_dwell_ratio`). Raw peaks, not smoothed ones (the estimation's
//! rule): the smoothing's bias that the first-break-away reading needed a
//! floor for does not arise. Without a model the first-break-away reading of
//! the records alone stands (there is no normal force to divide out).
//!
//! Measured on the full battery (seed 7000, debug build; findings.md,
//! thirteenth session): the 20 stick-slipping nulls b = −0.0009 to +0.0005
//! (each within 2.2 of its own se; the 20 nulls that never stick-slip have
//! fewer than five runs with two break-aways: not testable),
//! `outside-static_friction_aging-0..2` +0.035, +0.044, +0.043 (se ≤ 0.0008),
//! the modulated case +0.0327 ± 0.0029 over its five stick-slipping runs
//! (ratio 7.8; the first break-away from rest, a dwell of ≈ 3 s, is 2.6–3.2 %
//! above the steady ones of ≈ 1 s).
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
    one_sided(
        CHECK,
        ids,
        b,
        se.hypot(MIN_SLOPE),
        threshold,
        format!(
            "the break-away level changes by {:+.2} % ± {:.2} % ({dof} dof) per unit of ln(1 + t_stick/{DWELL_TIME_S} \
             s) {what}; floor ⊕ {:.1} %): {per_run}",
            100.0 * b,
            100.0 * se,
            100.0 * MIN_SLOPE,
        ),
    )
}

/// A dwell slope judged one-sided (module docs: only a level that grows with
/// the dwell is ageing): flagged when b over its floor exceeds the threshold.
fn one_sided(channel: &str, runs: Vec<String>, b: f64, floor: f64, threshold: f64, detail: String) -> ChannelCheck {
    let ratio = b / floor;
    ChannelCheck {
        channel: channel.into(),
        run_kind: "operating_point".into(),
        runs,
        statistic: b,
        noise_floor: floor,
        ratio,
        threshold,
        flagged: ratio > threshold,
        detail,
    }
}

// ---------------------------------------------------------------------------
// Every stick, under the model's normal force (module docs, "Every stick").

/// The every-stick check's name (run kind `operating_point`).
pub const STICKS_CHECK: &str = "operating_point.breakaway_ageing";

/// Runs with at least two break-aways the pooled slope needs for its
/// cluster-robust standard error (fewer clusters make it unreliable).
pub const MIN_STICK_RUNS: usize = 5;

/// One run's break-aways: (run id, [(x = ln(1 + t_stick/τ_d), ln μ_b, first from rest)]).
pub type StickRows = (String, Vec<(f64, f64, bool)>);

/// Every break-away of one run (module docs, "Every stick"): the stick
/// episodes of the estimation's rule (`[shared.stick_episodes]`,
/// [`rig_estimate::friction::stick_episodes`]), each with its dwell (the
/// episode's length) and its level μ_b, the peak of F/N(t, φ1) over the
/// episode with N the model's normal force (`normal_n(i)`, N, at sample i).
pub fn stick_rows_of(
    id: &str,
    time_s: &[f64],
    rotor_angle_rad: &[f64],
    force_n: &[f64],
    normal_n: &dyn Fn(usize) -> f64,
    o: &rig_estimate::FrictionOptions,
) -> StickRows {
    let rows = rig_estimate::friction::stick_episodes(time_s, rotor_angle_rad, o)
        .into_iter()
        .enumerate()
        .filter_map(|(k, r)| {
            let dwell_s = time_s[r.end - 1] - time_s[r.start];
            let mu = r.clone().map(|i| force_n[i].abs() / normal_n(i)).fold(0.0_f64, f64::max);
            (mu > 0.0).then(|| ((dwell_s / DWELL_TIME_S).ln_1p(), mu.ln(), k == 0))
        })
        .collect();
    (id.to_string(), rows)
}

/// The pooled within-run slope of ln μ_b on x (module docs, "Every stick"):
/// each run's rows centred on their own means (a run's level, normal force
/// and sensor cancel), b = Σ x̃ ỹ / Σ x̃², its cluster-robust standard error
/// (runs as clusters, CR1: G/(G − 1) Σ_g (Σ x̃ e)² / (Σ x̃²)²) and G − 1.
/// `keep` selects the rows; runs with fewer than two kept rows add nothing.
pub fn pooled_slope(runs: &[StickRows], keep: impl Fn(&(f64, f64, bool)) -> bool) -> Option<(f64, f64, usize)> {
    let groups: Vec<Vec<(f64, f64)>> = runs
        .iter()
        .map(|(_, rows)| rows.iter().filter(|r| keep(r)).map(|r| (r.0, r.1)).collect::<Vec<_>>())
        .filter(|g| g.len() >= 2)
        .map(|g| {
            let n = g.len() as f64;
            let (mx, my) = (g.iter().map(|p| p.0).sum::<f64>() / n, g.iter().map(|p| p.1).sum::<f64>() / n);
            g.iter().map(|p| (p.0 - mx, p.1 - my)).collect()
        })
        .collect();
    let sxx: f64 = groups.iter().flatten().map(|p| p.0 * p.0).sum();
    if groups.len() < MIN_STICK_RUNS || sxx <= 0.0 {
        return None;
    }
    let b = groups.iter().flatten().map(|p| p.0 * p.1).sum::<f64>() / sxx;
    let g = groups.len() as f64;
    let scores: f64 = groups.iter().map(|grp| grp.iter().map(|p| p.0 * (p.1 - b * p.0)).sum::<f64>().powi(2)).sum();
    Some((b, (g / (g - 1.0) * scores).sqrt() / sxx, groups.len() - 1))
}

/// The floor of the every-stick slope: a margin over what a right model's
/// records give (module docs, "Every stick": the stick-slipping nulls'
/// |b| ≤ 0.0009).
pub const MIN_STICK_SLOPE: f64 = 0.003;

/// The every-stick check (module docs, "Every stick"): each operating point's
/// break-aways read under `model_of(run id)`'s normal force (the final model
/// with the run's fitted phases), the pooled within-run slope b over its
/// floor (cluster-robust standard error ⊕ [`MIN_STICK_SLOPE`]), flagged above
/// `threshold` (one-sided, as the first-break-away reading).
pub fn breakaway_ageing_check(
    runs: &[RunSignals],
    model_of: &dyn Fn(&str) -> rig_types::RigParams,
    o: &rig_estimate::FrictionOptions,
    threshold: f64,
) -> ChannelCheck {
    let rows: Vec<StickRows> = runs
        .iter()
        .filter(|r| r.normal_force_n > 0.0)
        .map(|r| {
            let p = model_of(&r.id);
            let n_of = |i: usize| {
                rig_model::friction::normal_force_n(
                    r.normal_force_n,
                    &p.effects,
                    None,
                    r.time_s[i],
                    r.rotor_angle_rad[i],
                )
            };
            stick_rows_of(&r.id, &r.time_s, &r.rotor_angle_rad, &r.friction_force_n, &n_of, o)
        })
        .filter(|(_, v)| v.len() >= 2)
        .collect();
    let ids: Vec<String> = rows.iter().map(|r| r.0.clone()).collect();
    let Some((b, se, dof)) = pooled_slope(&rows, |_| true) else {
        return ChannelCheck::not_testable(
            STICKS_CHECK,
            ids,
            format!("fewer than {MIN_STICK_RUNS} runs break away twice: the dwell cannot be compared within runs"),
        );
    };
    let sticks: usize = rows.iter().map(|r| r.1.len()).sum();
    one_sided(
        STICKS_CHECK,
        ids,
        b,
        se.hypot(MIN_STICK_SLOPE),
        threshold,
        format!(
            "every break-away's level F/N(t, φ1) under the final model's normal force changes by {:+.2} % ± {:.2} % \
             (cluster-robust over {} runs, {sticks} break-aways, {dof} dof) per unit of ln(1 + t_stick/{DWELL_TIME_S} \
             s) within the runs; floor ⊕ {:.1} %",
            100.0 * b,
            100.0 * se,
            rows.len(),
            100.0 * MIN_STICK_SLOPE,
        ),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A run built from an ageing law under a modulated normal force: the pad
    /// holds the rotor (F = spring load, rising at `rate_n_s`, slower during
    /// the first stick from rest as under the ramp) until F reaches
    /// μs(t_stick)·N(t), μs(t) = μs0 + B ln(1 + t/τ) (Dieterich 1972); the
    /// rotor then slips at 3 rad/s for 0.3 s at μk·N(t) while the spring
    /// unloads. Returns (time s, angle rad, force N, N(t) N).
    fn run(b_per_efold: f64, rate_n_s: f64, phase_rad: f64) -> (Vec<f64>, Vec<f64>, Vec<f64>, Vec<f64>) {
        let (mu_s0, mu_k, n0, a, f_hz, tau_s, dt) = (0.6, 0.5, 10.0, 0.2, 1.63, 0.035, 0.002);
        let n_of = |t: f64| n0 * (1.0 + a * (2.0 * std::f64::consts::PI * f_hz * t + phase_rad).sin());
        let (mut t, mut phi, mut load, mut stuck_since, mut slip_until) =
            (0.0_f64, 0.0_f64, 0.0_f64, 0.0_f64, -1.0_f64);
        let mut out = (vec![], vec![], vec![], vec![]);
        while t < 30.0 {
            let n = n_of(t);
            let f = if t < slip_until {
                phi += 3.0 * dt;
                load = (load - 40.0 * dt).max(0.0);
                if t + dt >= slip_until {
                    stuck_since = t + dt;
                }
                mu_k * n
            } else {
                load += if t < 2.0 { 0.4 * rate_n_s } else { rate_n_s } * dt;
                let mu_s = mu_s0 + b_per_efold * ((t - stuck_since) / tau_s).ln_1p();
                if load >= mu_s * n {
                    slip_until = t + 0.3;
                }
                load.min(mu_s * n)
            };
            out.0.push(t);
            out.1.push(phi);
            out.2.push(f);
            out.3.push(n);
            t += dt;
        }
        out
    }

    /// The pooled slope of campaigns of six runs (rise rates 4–9 N/s, so the
    /// steady dwells differ between runs and the first one is longest).
    fn slope_of(b_per_efold: f64) -> (f64, f64, usize) {
        let o = rig_estimate::FrictionOptions::default();
        let rows: Vec<StickRows> = (0..6)
            .map(|k| {
                let (t, phi, f, n) = run(b_per_efold, 4.0 + k as f64, 0.7 * k as f64);
                stick_rows_of(&format!("op-{k}"), &t, &phi, &f, &|i| n[i], &o)
            })
            .collect();
        assert!(rows.iter().all(|r| r.1.len() >= 3), "{rows:?}");
        pooled_slope(&rows, |_| true).expect("six runs")
    }

    /// Under the modulated force, F/N(t) at break-away follows the law: no
    /// slope without ageing, B/μs per unit of ln(1 + t/τ_d) with it (τ_d of
    /// the library differs from the law's τ; at dwells of 0.5–3 s the log
    /// slopes differ by a few %).
    #[test]
    fn every_stick_reads_the_ageing_behind_a_modulation() {
        let (b0, se0, _) = slope_of(0.0);
        assert!(b0.abs() < 0.002 && b0.abs() < 3.0 * se0.max(1e-4), "no ageing: b {b0} ± {se0}");
        let (b, se, dof) = slope_of(0.025);
        assert_eq!(dof, 5);
        // μs at a 1 s dwell: 0.6 + 0.025·ln(1 + 1/0.035) ≈ 0.685.
        assert!((b - 0.025 / 0.685).abs() < 0.008, "ageing: b {b} ± {se}");
        assert!(b / se.hypot(MIN_STICK_SLOPE) > 2.5, "ageing: b {b} ± {se}");
    }
}
