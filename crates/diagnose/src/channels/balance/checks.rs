//! The rotor torque balance's checks: its RMS residual against the sensor
//! noise floor, and the tick-loss drift of the recorded twist.

use super::super::{ChannelCheck, ChannelOptions, rms};
use super::{BalanceData, balance_data, residuals};
use crate::DiagnoseOptions;
use rig_calibrate::CampaignCalibration;
use rig_types::sensor::tick_rad;
use rig_types::{Campaign, RigParams};

/// Rotor-1 torque balance over the steady state of every operating point.
///
/// Eq. 4-7, first row, in the rig model's reading (rig-model docs: the
/// damping C acts on the twist rate): J1 Ω̇1 = K(φ2 − φ1) + C(Ω2 − Ω1) − T1,
/// with T1 = r·F measured by the force sensor (Eq. 4-10's r). It departs from
/// the thesis by adding an absolute drag d·Ω1 and a constant (force-sensor
/// offset drift), and by fitting K, C, d and the constant to the records
/// themselves (one least squares over all runs): a bearing drag or a slightly
/// wrong calibration is then no finding, and what is left is what no linear
/// rotor equation explains (a torque that follows angle, time or stick/slip).
/// Terms are triangle-weighted window means (window `balance_window_s`).
/// Statistic: per run the RMS residual, over runs their RMS, N·m. Floor: the
/// same expression under sensor noise alone: force noise (measured per run by
/// first differences) and one-tick quantisation of both encoders propagated
/// through the fitted coefficients.
pub fn torque_balance_check(
    c: &Campaign,
    cal: &CampaignCalibration,
    baseline: &RigParams,
    opts: &DiagnoseOptions,
    o: &ChannelOptions,
) -> ChannelCheck {
    torque_balance_check_of(c, &balance_data(c, cal, opts, o), baseline, o)
}

/// [`torque_balance_check`] of balance data already built.
pub fn torque_balance_check_of(
    c: &Campaign,
    data: &BalanceData,
    baseline: &RigParams,
    o: &ChannelOptions,
) -> ChannelCheck {
    let name = "operating_point.torque_balance";
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    let r_m = c.rig.brake_disc_radius_m;
    let per_run = &data.runs;
    let ids: Vec<String> = per_run.iter().map(|r| r.id.clone()).collect();
    // J1 is the calibration's (Eqs. 4-4/4-5): fitted here it would be
    // attenuated towards 0 by the quantisation noise of Ω̇1 (errors in variables).
    let j1 = data.j1_kgm2;
    let Some(fit) = data.fit(|_| true, true, true) else {
        return ChannelCheck::not_testable(name, ids, "the rotor balance regression is singular".into());
    };
    let beta = fit.beta(j1);
    // r·F = −J1 Ω̇1 + K tw + C tẇ − d Ω1 + c0.
    let (k, cc, drag) = (beta[1], beta[2], -beta[3]);
    let run_rms: Vec<f64> = per_run
        .iter()
        .filter(|r| !r.rows.is_empty())
        .map(|r| {
            let e: Vec<f64> =
                r.rows.iter().map(|(x, y)| y - x.iter().zip(&beta).map(|(a, b)| a * b).sum::<f64>()).collect();
            rms(&e)
        })
        .collect();
    let big_t = data.window_s;
    // Quantisation: uniform error tick²/12 per angle sample. Ω̇1 = second
    // difference of three boundary angles / T² (variance 6·tick²/12 / T⁴);
    // the twist (two encoders) under the kernel; the rates, difference of
    // two-boundary twists / 2T (variance 2·2·tick²/12 / 4T²).
    let q2 = rad * rad / 12.0;
    let floors: Vec<f64> = per_run
        .iter()
        .filter(|r| !r.rows.is_empty())
        .map(|r| {
            let var = (r_m * r.force_noise_n).powi(2) * r.kernel_gain
                + j1.powi(2) * 6.0 * q2 / big_t.powi(4)
                + k.powi(2) * 2.0 * q2 * r.kernel_gain
                + cc.powi(2) * q2 / big_t.powi(2)
                + drag.powi(2) * 0.5 * q2 / big_t.powi(2);
            var.sqrt()
        })
        .collect();
    let stat = rms(&run_rms);
    let floor = rms(&floors);
    let worst = ids
        .iter()
        .zip(&run_rms)
        .zip(&floors)
        .max_by(|a, b| (a.0.1 / a.1).total_cmp(&(b.0.1 / b.1)))
        .map(|((id, e), f)| format!("{id} {:.1}×", e / f))
        .unwrap_or_default();
    ChannelCheck::new(
        name,
        ids,
        stat,
        floor,
        o.torque_balance_ratio,
        format!(
            "rotor balance fitted on the records (J1 held): J1 {j1:.4} kg·m² (calibration; baseline {:.4}), K {k:.4} N·m/rad ({:.4}), C {cc:.2e} N·m·s/rad ({:.2e}), drag d {drag:.2e} N·m·s/rad, offset {:.2e} N·m; RMS residual {stat:.2e} N·m; worst run {worst}",
            baseline.rotor_inertia_kgm2, baseline.shaft_stiffness_nm_rad, baseline.shaft_damping_nm_s_rad, beta[4]
        ),
    )
}

/// The tick-loss check's name (run kind `operating_point`).
pub const TICK_LOSS_CHECK: &str = "operating_point.tick_loss";

/// The floor of the tick-loss fraction: a drift of the twist below 2·10⁻⁴
/// rad per rad travelled (0.2 ticks in 1000 of a 1000-tick encoder) is
/// within what the balance's slow wander gives (stated in
/// [`tick_loss_check_of`]'s calibration).
pub const MIN_TICK_LOSS: f64 = 2e-4;

/// A run's drift needs this many balance rows (10 s at 0.1 s).
const MIN_DRIFT_ROWS: usize = 100;

/// Does an encoder lose ticks? A lost tick is a step of one tick in the
/// recorded angle that is never given back, so the recorded twist φ2 − φ1
/// grows with the angle travelled: by p·φ1 when the rotor encoder loses a
/// fraction p of its ticks (by −p·φ2 for the motor's). A transport delay of
/// the encoder is a *shift*, φ1(t − d) ≈ φ1 − Ω1·d: bounded, the same at the
/// start and the end of a steady slip, zero in every stick. The balance
/// fitted on the records ([`BalanceData::fit`], C and C_r free) leaves both
/// faults in its residual: a delay as K·Ω1·d, constant within a steady run
/// (it is what the `channel_delay` candidate fits), a tick loss as
/// −K·p·(φ1 − φ̄1), a ramp on the travelled angle.
///
/// Statistic: per run with at least [`MIN_DRIFT_ROWS`] steady rows, the
/// least-squares slope of the balance residual on the recorded rotor angle,
/// divided by −K: p_r, the twist gained per radian travelled
/// (dimensionless; ticks lost per tick). Over runs, the mean p̄ (a tick loss
/// is the same fraction in every run; a model error that drifts does not
/// keep its sign across 30 runs of different set-points). Floor: p̄'s
/// standard error over runs ⊕ [`MIN_TICK_LOSS`]. Flagged above
/// `tick_loss_ratio` (pipeline.toml); when flagged the `channel_delay`
/// candidate refuses the rotor encoder ([`crate::structure`]).
pub fn tick_loss_check_of(data: &BalanceData, o: &ChannelOptions) -> ChannelCheck {
    let ids: Vec<String> = data.runs.iter().map(|r| r.id.clone()).collect();
    let Some(fit) = data.fit(|_| true, true, true) else {
        return ChannelCheck::not_testable(TICK_LOSS_CHECK, ids, "the rotor balance regression is singular".into());
    };
    let beta = fit.beta(data.j1_kgm2);
    let k = fit.stiffness_nm_rad;
    let mut p = Vec::new();
    for r in data.runs.iter().filter(|r| r.rows.len() >= MIN_DRIFT_ROWS) {
        let e = residuals(&r.rows, &beta);
        let n = e.len() as f64;
        let (ma, me) = (r.angle_rad.iter().sum::<f64>() / n, e.iter().sum::<f64>() / n);
        let sxx: f64 = r.angle_rad.iter().map(|a| (a - ma).powi(2)).sum();
        let sxy: f64 = r.angle_rad.iter().zip(&e).map(|(a, y)| (a - ma) * (y - me)).sum();
        if sxx > 0.0 && k > 0.0 {
            p.push((r.id.as_str(), -sxy / sxx / k));
        }
    }
    if p.len() < 3 || k <= 0.0 {
        return ChannelCheck::not_testable(
            TICK_LOSS_CHECK,
            ids,
            format!("{} runs with {MIN_DRIFT_ROWS} steady balance rows (3 needed)", p.len()),
        );
    }
    let n = p.len() as f64;
    let mean = p.iter().map(|x| x.1).sum::<f64>() / n;
    let sd = (p.iter().map(|x| (x.1 - mean).powi(2)).sum::<f64>() / (n - 1.0)).sqrt();
    let se = sd / n.sqrt();
    let same_sign = p.iter().filter(|x| x.1 * mean > 0.0).count();
    ChannelCheck::new(
        TICK_LOSS_CHECK,
        p.iter().map(|x| x.0.to_string()).collect(),
        mean.abs(),
        se.hypot(MIN_TICK_LOSS),
        o.tick_loss_ratio,
        format!(
            "the recorded twist drifts by {:.2e} rad per rad the rotor travels (mean over {} runs ± {:.1e}, {} of \
             them of that sign; {}): {}",
            mean,
            p.len(),
            se,
            same_sign,
            if mean > 0.0 { "the rotor encoder falls behind" } else { "the motor encoder falls behind" },
            "a lost tick is a step in the angle never given back; a delay is a shift"
        ),
    )
}
