//! Steady-state balance of the drive over the operating points: do the
//! motor's constants stay put during the campaign?

use super::{ChannelCheck, ChannelOptions, ols};
use crate::DiagnoseOptions;
use rig_types::sensor::tick_rad;
use rig_types::{Campaign, RunKind};

/// One operating point's steady-state means: ⟨V⟩, ⟨φ2 − φ1⟩, ⟨Ω2⟩ over the
/// whole steady window and over each of its halves, and the recorded
/// campaign time before it, s.
struct Means {
    id: String,
    whole: [f64; 3],
    halves: [[f64; 3]; 2],
    clock_s: f64,
}

/// [⟨V⟩, ⟨φ2 − φ1⟩, ⟨Ω2⟩] over samples `from..=to`; Ω2 from the encoder
/// counts at the ends (no derivative of a quantised angle).
fn window_means(time_s: &[f64], v: &[f64], t1: &[i64], t2: &[i64], rad: f64, from: usize, to: usize) -> [f64; 3] {
    let k = (to - from + 1) as f64;
    [
        v[from..=to].iter().sum::<f64>() / k,
        (from..=to).map(|j| (t2[j] - t1[j]) as f64 * rad).sum::<f64>() / k,
        (t2[to] - t2[from]) as f64 * rad / (time_s[to] - time_s[from]),
    ]
}

/// The drive's mean balance over the steady state of every operating point:
/// do the motor's constants stay put over the campaign?
///
/// Eq. 4-6 (armature and motor rotor, gear made explicit as in rig-model)
/// averaged over a steady window of length T:
/// ⟨V⟩ = R⟨i⟩ + n k_e⟨Ω2⟩ + L Δi/T and
/// n k_T⟨i⟩ = K⟨φ2 − φ1⟩ + C Δ(φ2 − φ1)/T + J2 ΔΩ2/T + n T_f + n² C_m⟨Ω2⟩,
/// so ⟨V⟩ = a⟨φ2 − φ1⟩ + b⟨Ω2⟩ + c with a = RK/(n k_T),
/// b = n k_e + R n C_m/k_T and c = R T_f/k_T, up to boundary terms that
/// shrink as 1/T. With constant motor constants a, b, c are the same for
/// every run; they are fitted on the records themselves (no calibrated value
/// enters), so only a change of the constants between runs, or a drive that
/// is not linear in current and speed, leaves a residual.
///
/// Statistic: the residual standard deviation of that fit, √(RSS/(n − 3)), V.
/// Floor: what the means' own noise gives, from inside the runs: each run's
/// balance residual over the first half of its window minus over the second
/// half (same a, b, c) has twice the variance of a half-window mean, four
/// times that of the whole-window mean: floor = √(Σ d²/(4n)). It carries the
/// voltage noise, quantisation and the partial stick-slip cycles at the
/// window ends, without a model of any of them.
///
/// The detail says whether the residual follows the recorded time before the
/// run (runs in campaign.toml order, each run's duration counted; the format
/// states no wall-clock time): the fit with a and b drifting linearly in it,
/// and the correlation of the residual with it. A winding that warms raises R
/// (a grows), warm magnets lower k_T = k_e (b falls).
pub fn drive_balance_check(c: &Campaign, opts: &DiagnoseOptions, o: &ChannelOptions) -> ChannelCheck {
    let name = "operating_point.drive_balance";
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    let mut clock_s = 0.0;
    let mut means = Vec::new();
    for run in &c.runs {
        let before_s = clock_s;
        clock_s += run.data.time_s.last().copied().unwrap_or(0.0);
        let RunKind::OperatingPoint { ramp_s, .. } = run.kind else { continue };
        let d = &run.data;
        let (Some(t1), Some(t2), Some(v)) = (&d.rotor_ticks, &d.motor_ticks, &d.motor_voltage_v) else { continue };
        let from = d.time_s.partition_point(|&x| x < ramp_s + opts.settle_s);
        let to = d.time_s.len().saturating_sub(1);
        if to < from + 8 {
            continue;
        }
        let mid = from + (to - from) / 2;
        let w = |a: usize, b: usize| window_means(&d.time_s, v, t1, t2, rad, a, b);
        means.push(Means {
            id: run.id.clone(),
            whole: w(from, to),
            halves: [w(from, mid), w(mid, to)],
            clock_s: before_s,
        });
    }
    let ids: Vec<String> = means.iter().map(|m| m.id.clone()).collect();
    let n = means.len();
    if n < 6 {
        return ChannelCheck::not_testable(
            name,
            ids,
            format!("{n} operating points with voltage and both encoders; the balance needs 6"),
        );
    }
    let row = |m: &[f64; 3]| vec![m[1], m[2], 1.0];
    let y: Vec<f64> = means.iter().map(|m| m.whole[0]).collect();
    let x0: Vec<Vec<f64>> = means.iter().map(|m| row(&m.whole)).collect();
    let Some((b0, rss0)) = ols(&x0, &y) else {
        return ChannelCheck::not_testable(name, ids, "the drive balance regression is singular".into());
    };
    let resid = |m: &[f64; 3]| m[0] - row(m).iter().zip(&b0).map(|(a, b)| a * b).sum::<f64>();
    let d2: f64 = means.iter().map(|m| (resid(&m.halves[0]) - resid(&m.halves[1])).powi(2)).sum();
    let stat = (rss0 / (n - 3) as f64).sqrt();
    let floor = (d2 / (4 * n) as f64).sqrt();
    // Does the residual follow the recorded time? Drift fit and correlation.
    let (c0, c1) = (means[0].clock_s, means[n - 1].clock_s);
    let s: Vec<f64> = means.iter().map(|m| if c1 > c0 { (m.clock_s - c0) / (c1 - c0) } else { 0.0 }).collect();
    let x1: Vec<Vec<f64>> = means
        .iter()
        .zip(&s)
        .map(|(m, &si)| vec![m.whole[1], m.whole[2], 1.0, m.whole[1] * si, m.whole[2] * si])
        .collect();
    let r: Vec<f64> = means.iter().map(|m| resid(&m.whole)).collect();
    let corr = {
        let ms = s.iter().sum::<f64>() / n as f64;
        let mr = r.iter().sum::<f64>() / n as f64;
        let sxy: f64 = s.iter().zip(&r).map(|(a, b)| (a - ms) * (b - mr)).sum();
        let sxx: f64 = s.iter().map(|a| (a - ms).powi(2)).sum();
        let syy: f64 = r.iter().map(|b| (b - mr).powi(2)).sum();
        if sxx > 0.0 && syy > 0.0 { sxy / (sxx * syy).sqrt() } else { 0.0 }
    };
    let drift = match (n >= 8, ols(&x1, &y)) {
        (true, Some((b1, rss1))) => {
            let pct = |slope: f64, at0: f64| if at0 != 0.0 { 100.0 * slope / at0 } else { f64::NAN };
            format!(
                "; with a, b drifting over the {:.0} s of recorded time from the first to the last point: a {:+.1} %, b {:+.1} %, residual {:.2e} V",
                c1 - c0,
                pct(b1[3], b1[0]),
                pct(b1[4], b1[1]),
                (rss1 / (n - 5) as f64).sqrt()
            )
        }
        _ => String::new(),
    };
    ChannelCheck::new(
        name,
        ids,
        stat,
        floor,
        o.drive_balance_ratio,
        format!(
            "⟨V⟩ = a⟨φ2−φ1⟩ + b⟨Ω2⟩ + c over {n} operating points, constants fitted on the records: a {:.3} V/rad, \
             b {:.4} V·s/rad, c {:.3} V, residual {stat:.2e} V against {floor:.2e} V within the runs; \
             correlation of the residual with recorded time {corr:+.2}{drift} (a ∝ R/k_T, b ≈ n k_e: a winding that warms raises a, warm magnets lower b)",
            b0[0], b0[1], b0[2]
        ),
    )
}
