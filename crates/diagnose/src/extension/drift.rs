//! Does the slip friction drift within a run? The extension library's
//! slow signals (the residual signature's `time_since_start_s`,
//! `friction_work_j`) tested on the records' slip force, where a fading
//! brake shows and the teacher-forced misfit, averaged over runs whose
//! friction power spans 100×, does not (issue 25; the full battery's
//! `mixed-angle_periodic_friction+brake_fade-0` was answered
//! `angle_periodic_friction`, adequate at 3.14× the noise floor).
//!
//! No model of the vocabulary has a slip force that trends within a run at
//! a constant set-point: its terms are a law of the speed, of the shaft
//! angle and a sine in time, all stationary over a steady run. A pad that
//! heats (brake fade), wears or a force channel whose zero wanders makes
//! one.
//!
//! For every operating point with at least [`MIN_SLIP_SAMPLES`] slip samples
//! (the diagnosis' slip samples, [`RunSignals::slip_idx`]) after ramp +
//! settle: the line F = a + b (t − t̄) through them, its relative drift
//! over the run b·(t_last − t_first)/a, and b's standard error from the
//! [`BLOCK_S`] block means around the line (a modulation, an angle-periodic
//! friction or a stick-slip cycle scatters the blocks, not the line, so it
//! raises the floor instead of the drift): z_r = drift / (its standard error
//! ⊕ [`MIN_DRIFT`]). The check's ratio is
//! the RMS of z_r over the runs, flagged above `slip_drift_ratio`
//! (pipeline.toml's `[stage.params.channels]`, as every check's threshold).
//!
//! # Calibration (seed 7000's full battery, docs/findings.md)
//!
//! A numpy probe of the same statistic (the force in mV, h = 8 samples):
//! nulls and stick-slipping nulls 0.83–1.23 (20 campaigns), campaigns of
//! one vocabulary effect (or two with a drive limit) 0.44–1.28 (14), brake
//! fade 14.1–51.3 (4), without [`MIN_DRIFT`]; in the diagnosis one right
//! modulation read 4.59 without it, hence the floor (which can only lower
//! a ratio). The threshold, 4, is about 3× the largest null.

use crate::channels::ChannelCheck;
use crate::prepare::RunSignals;

/// The check's name (run kind `operating_point`).
pub const CHECK: &str = "operating_point.slip_drift";

/// Length of the blocks whose means around the line give its floor, s.
pub const BLOCK_S: f64 = 1.0;

/// Slip samples a run needs after ramp + settle.
pub const MIN_SLIP_SAMPLES: usize = 500;

/// The floor of a run's relative drift (⊕ its standard error): a right
/// normal-force modulation (`ladder-normal_force_modulation-1-15`) drifted
/// by at most 0.12 % with block means so steady that z reached 6 (RMS 4.59,
/// flagged); brake fades drift by 5–26 % at high friction power.
pub const MIN_DRIFT: f64 = 0.005;

/// One run's relative drift over the run and its z (module docs), `None`
/// below [`MIN_SLIP_SAMPLES`] or four blocks.
pub fn run_drift(r: &RunSignals, settle_s: f64) -> Option<(f64, f64)> {
    let from = r.ramp_s + settle_s;
    let pts: Vec<(f64, f64)> =
        r.slip_idx.iter().filter(|&&k| r.time_s[k] >= from).map(|&k| (r.time_s[k], r.friction_force_n[k])).collect();
    if pts.len() < MIN_SLIP_SAMPLES {
        return None;
    }
    let n = pts.len() as f64;
    let tm = pts.iter().map(|p| p.0).sum::<f64>() / n;
    let fm = pts.iter().map(|p| p.1).sum::<f64>() / n;
    let sxx: f64 = pts.iter().map(|p| (p.0 - tm).powi(2)).sum();
    let b = pts.iter().map(|p| (p.0 - tm) * (p.1 - fm)).sum::<f64>() / sxx;
    // Block means of the residual around the line, and of t − t̄.
    let mut blocks: std::collections::BTreeMap<i64, (f64, f64, usize)> = std::collections::BTreeMap::new();
    for &(t, f) in &pts {
        let e = blocks.entry((t / BLOCK_S).floor() as i64).or_insert((0.0, 0.0, 0));
        e.0 += f - (fm + b * (t - tm));
        e.1 += t - tm;
        e.2 += 1;
    }
    if blocks.len() < 4 || fm.abs() <= 0.0 {
        return None;
    }
    let (mut s_e, mut s_t) = (0.0, 0.0);
    for (e, t, c) in blocks.values() {
        s_e += (e / *c as f64).powi(2);
        s_t += (t / *c as f64).powi(2);
    }
    let se = (s_e / (blocks.len() - 2) as f64 / s_t).sqrt();
    let span = pts[pts.len() - 1].0 - pts[0].0;
    let (drift, se_rel) = (b * span / fm, se * span / fm.abs());
    (se > 0.0).then(|| (drift, drift / se_rel.hypot(MIN_DRIFT)))
}

/// The check (module docs), flagged above `threshold` (`slip_drift_ratio`).
pub fn slip_drift_check(runs: &[RunSignals], settle_s: f64, threshold: f64) -> ChannelCheck {
    let rows: Vec<(&str, f64, f64)> =
        runs.iter().filter_map(|r| run_drift(r, settle_s).map(|(d, z)| (r.id.as_str(), d, z))).collect();
    let ids: Vec<String> = rows.iter().map(|r| r.0.to_string()).collect();
    if rows.is_empty() {
        return ChannelCheck::not_testable(
            CHECK,
            ids,
            format!("no run slips for {MIN_SLIP_SAMPLES} samples after the settle: no drift to read"),
        );
    }
    let ratio = (rows.iter().map(|r| r.2 * r.2).sum::<f64>() / rows.len() as f64).sqrt();
    let worst = rows.iter().max_by(|a, b| a.2.abs().total_cmp(&b.2.abs())).expect("rows");
    let mean = rows.iter().map(|r| r.1).sum::<f64>() / rows.len() as f64;
    ChannelCheck {
        channel: CHECK.into(),
        run_kind: "operating_point".into(),
        runs: ids,
        statistic: ratio,
        noise_floor: 1.0,
        ratio,
        threshold,
        flagged: ratio > threshold,
        detail: format!(
            "the slip force drifts within the runs by {:+.2} % on average over {} runs (a line through each run's \
             slip samples after the settle, its slope over the {BLOCK_S} s block means' scatter: RMS z {ratio:.2}); \
             worst {} {:+.2} % (z {:+.1})",
            100.0 * mean,
            rows.len(),
            worst.0,
            100.0 * worst.1,
            worst.2
        ),
    }
}
