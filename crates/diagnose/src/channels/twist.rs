//! Static-twist checks: linearity, dead zone and hysteresis of the held
//! rotor angle against the applied torque (Table 4.3's procedure, whose model
//! is the linear spring T = K_s θ of Eq. 4-1).

use super::{ChannelCheck, ChannelOptions};
use rig_calibrate::CampaignCalibration;
use rig_types::Campaign;

/// Least squares of y on the columns of `x` (rows of equal length), by the
/// workspace's normal equations (`rig_estimate::linear::Normal`; at most 3
/// columns here). None when singular.
fn lstsq(x: &[Vec<f64>], y: &[f64]) -> Option<Vec<f64>> {
    let mut n = rig_estimate::linear::Normal::new(x.first()?.len());
    for (row, &v) in x.iter().zip(y) {
        n.add_row(row, v);
    }
    n.solve()
}

/// The three static-twist checks (campaign order of the twist runs).
///
/// The angle of each run is the calibration's mean held angle θ_i at torque
/// T_i. Eq. 4-1 (K_s = G I_s / L_s, a linear spring) predicts θ = T/K_s:
/// - linearity: RMS over the runs of the difference between the quadratic
///   fit θ = a + bT + cT² and the line θ = a + bT (floor σ_θ/√n: one extra
///   parameter fitted to noise moves the fit by that much);
/// - dead zone (backlash, or a preload): |a| of the line; its floor adds
///   half a tick, since whether the encoder floors or rounds is not in the
///   recording format;
/// - hysteresis: mean line residual of the unloading runs (torque below the
///   largest torque held before, campaign order) minus that of the loading
///   runs. A protocol with one branch only cannot show it (reported, never flagged).
pub fn static_twist_checks(c: &Campaign, cal: &CampaignCalibration, o: &ChannelOptions) -> Vec<ChannelCheck> {
    let runs = &cal.twist_runs;
    let ids: Vec<String> = runs.iter().map(|r| r.id.clone()).collect();
    let n = runs.len();
    let tick_rad = rig_types::sensor::tick_rad(c.rig.encoder_ticks_per_rev);
    let names = ["static_twist.linearity", "static_twist.dead_zone", "static_twist.hysteresis"];
    if n < 3 {
        return names
            .iter()
            .map(|ch| ChannelCheck::not_testable(ch, ids.clone(), format!("{n} static_twist runs: at least 3 needed")))
            .collect();
    }
    let samples: Vec<usize> = c.runs_of("static_twist").map(|r| r.data.time_s.len().max(1)).collect();
    let wander2 = runs.iter().zip(&samples).map(|(r, &m)| r.angle_std_rad.powi(2) / m as f64).sum::<f64>() / n as f64;
    let sigma = (tick_rad * tick_rad / 12.0 + wander2).sqrt();
    let t: Vec<f64> = runs.iter().map(|r| r.torque_nm).collect();
    let th: Vec<f64> = runs.iter().map(|r| r.angle_rad).collect();
    let lin_rows: Vec<Vec<f64>> = t.iter().map(|&x| vec![1.0, x]).collect();
    let Some(line) = lstsq(&lin_rows, &th) else {
        return names
            .iter()
            .map(|ch| ChannelCheck::not_testable(ch, ids.clone(), "all twist torques are equal".into()))
            .collect();
    };
    let line_at = |x: f64| line[0] + line[1] * x;
    let resid: Vec<f64> = t.iter().zip(&th).map(|(&x, &y)| y - line_at(x)).collect();
    let mut out = Vec::new();

    // Linearity.
    if n >= 4 {
        let q_rows: Vec<Vec<f64>> = t.iter().map(|&x| vec![1.0, x, x * x]).collect();
        let q = lstsq(&q_rows, &th).unwrap_or_else(|| vec![line[0], line[1], 0.0]);
        let d: Vec<f64> = t.iter().map(|&x| q[0] + q[1] * x + q[2] * x * x - line_at(x)).collect();
        let stat = super::rms(&d);
        let k_lo = 1.0 / (q[1] + 2.0 * q[2] * t.iter().copied().fold(f64::INFINITY, f64::min));
        let k_hi = 1.0 / (q[1] + 2.0 * q[2] * t.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        out.push(ChannelCheck::new(
            names[0],
            ids.clone(),
            stat,
            sigma / (n as f64).sqrt(),
            o.twist_linearity_ratio,
            format!(
                "angle vs torque bends by {:.2e} rad RMS from a straight line; tangent stiffness {k_lo:.4} → {k_hi:.4} N·m/rad over the torques",
                stat
            ),
        ));
    } else {
        out.push(ChannelCheck::not_testable(names[0], ids.clone(), "3 twist runs: a curvature needs 4".into()));
    }

    // Dead zone: the intercept's standard error under σ_θ, plus half a tick.
    let m = t.iter().sum::<f64>() / n as f64;
    let sxx: f64 = t.iter().map(|x| (x - m).powi(2)).sum();
    let se_a = sigma * (1.0 / n as f64 + m * m / sxx).sqrt();
    let floor = (se_a * se_a + (tick_rad / 2.0).powi(2)).sqrt();
    out.push(ChannelCheck::new(
        names[1],
        ids.clone(),
        line[0].abs(),
        floor,
        o.twist_dead_zone_ratio,
        format!(
            "the line through the held angles meets zero torque at {:+.2e} rad ({:+.1} ticks); stiffness of the line {:.4} N·m/rad",
            line[0],
            line[0] / tick_rad,
            1.0 / line[1]
        ),
    ));

    // Hysteresis: loading vs unloading branch.
    let mut max_before = f64::NEG_INFINITY;
    let mut unloading = vec![false; n];
    for (i, &x) in t.iter().enumerate() {
        unloading[i] = x.abs() < max_before;
        max_before = max_before.max(x.abs());
    }
    let (nu, nl) = (unloading.iter().filter(|&&u| u).count(), unloading.iter().filter(|&&u| !u).count());
    if nu == 0 || nl == 0 {
        out.push(ChannelCheck::not_testable(
            names[2],
            ids,
            "every twist run loads beyond the previous torque (loading branch only): hysteresis needs runs that revisit a torque on the way down".into(),
        ));
    } else {
        let mean = |want: bool| {
            resid.iter().zip(&unloading).filter(|(_, u)| **u == want).map(|(r, _)| r).sum::<f64>()
                / if want { nu } else { nl } as f64
        };
        let d = mean(true) - mean(false);
        out.push(ChannelCheck::new(
            names[2],
            ids,
            d.abs(),
            sigma * (1.0 / nu as f64 + 1.0 / nl as f64).sqrt(),
            o.twist_hysteresis_ratio,
            format!("unloading runs ({nu}) hold {d:+.2e} rad more twist than loading runs ({nl}) at the same line"),
        ));
    }
    out
}
