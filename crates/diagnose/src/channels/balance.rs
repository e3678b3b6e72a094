//! Torque balance of rotor 1 in the measured channels of the operating
//! points: encoders and force sensor must satisfy the rotor equation.

use super::{ChannelCheck, ChannelOptions, rms};
use crate::DiagnoseOptions;
use crate::prepare::diff_noise;
use rig_calibrate::CampaignCalibration;
use rig_types::sensor::{ForceCal, force_n, nominal_window_samples, tick_rad, ticks_to_rad};
use rig_types::{Campaign, RigParams, RunKind};

/// Regressors of one window boundary: [⟨Ω̇1⟩, ⟨φ2−φ1⟩, ⟨Ω2−Ω1⟩, ⟨Ω1⟩, 1] and r⟨F⟩.
type Row = ([f64; 5], f64);

/// Triangle-weighted means around every boundary b = jw (weights w − |k − b|),
/// the kernel for which (mean speed of the next window − of the previous) / T
/// is exactly the weighted mean of the acceleration, so no derivative of a
/// quantised angle is taken.
fn rows(phi1: &[f64], phi2: &[f64], force_n: &[f64], dt: f64, w: usize, r_m: f64, from: usize) -> Vec<Row> {
    let n = phi1.len();
    let tw = |k: usize| phi2[k] - phi1[k];
    let big_t = w as f64 * dt;
    let mut out = Vec::new();
    let mut b = from.max(w);
    while b + w < n {
        let (mut s_tw, mut s_f, mut s_k) = (0.0, 0.0, 0.0);
        for (k, &f) in force_n.iter().enumerate().take(b + w + 1).skip(b - w) {
            let wt = (w - k.abs_diff(b)) as f64;
            s_tw += wt * tw(k);
            s_f += wt * f;
            s_k += wt;
        }
        let w1_prev = (phi1[b] - phi1[b - w]) / big_t;
        let w1_next = (phi1[b + w] - phi1[b]) / big_t;
        let tw_prev = (tw(b) - tw(b - w)) / big_t;
        let tw_next = (tw(b + w) - tw(b)) / big_t;
        out.push((
            [(w1_next - w1_prev) / big_t, s_tw / s_k, 0.5 * (tw_prev + tw_next), 0.5 * (w1_prev + w1_next), 1.0],
            r_m * s_f / s_k,
        ));
        b += w;
    }
    out
}

/// One operating point's balance rows and what its noise floor needs.
#[derive(Debug, Clone)]
struct RunRows {
    id: String,
    rows: Vec<Row>,
    force_noise_n: f64,
    kernel_gain: f64,
}

/// The rotor torque balance's data: every operating point's window rows over
/// its steady state, with J1 from the calibration. Built once; fitted on any
/// subset of runs with any of the damping terms ([`BalanceData::fit`]), which
/// is how the structural candidates ([`crate::structure`]) are fitted
/// teacher-forced on training folds.
#[derive(Debug, Clone)]
pub struct BalanceData {
    runs: Vec<RunRows>,
    /// Rotor inertia held at the calibration's (Eqs. 4-4/4-5), kg·m².
    pub j1_kgm2: f64,
}

/// A fitted rotor balance r·F = −J1 Ω̇1 + K tw + C tẇ − C_r Ω1 + c0.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BalanceFit {
    pub stiffness_nm_rad: f64,
    /// C on the twist rate Ω2 − Ω1 (0 when not fitted).
    pub twist_damping_nm_s_rad: f64,
    /// C_r, a drag on the absolute rotor speed Ω1 (0 when not fitted).
    pub rotor_drag_nm_s_rad: f64,
    pub offset_nm: f64,
}

impl BalanceFit {
    fn beta(&self, j1: f64) -> [f64; 5] {
        [-j1, self.stiffness_nm_rad, self.twist_damping_nm_s_rad, -self.rotor_drag_nm_s_rad, self.offset_nm]
    }
}

/// The rows of every operating point of `c` ([`rows`], steady state only).
pub fn balance_data(
    c: &Campaign,
    cal: &CampaignCalibration,
    opts: &DiagnoseOptions,
    o: &ChannelOptions,
) -> BalanceData {
    balance_data_aligned(c, cal, opts, o, 0, 0)
}

/// `x` advanced by `lead` samples, x'[k] = x[k + lead] (the last sample held):
/// a channel recorded `lead` samples late, put back in time.
fn advanced(x: Vec<f64>, lead: usize) -> Vec<f64> {
    if lead == 0 || x.is_empty() {
        return x;
    }
    let n = x.len();
    (0..n).map(|k| x[(k + lead).min(n - 1)]).collect()
}

/// [`balance_data`] with the rotor encoder's angle advanced by `rotor_lead`
/// samples and the force channel's by `force_lead`: the balance of a
/// campaign whose channel is recorded that many samples late (the
/// structural candidate `channel_delay`, [`crate::structure`]).
pub fn balance_data_aligned(
    c: &Campaign,
    cal: &CampaignCalibration,
    opts: &DiagnoseOptions,
    o: &ChannelOptions,
    rotor_lead: usize,
    force_lead: usize,
) -> BalanceData {
    let w = nominal_window_samples(o.balance_window_s, c.rig.sample_rate_hz).max(2);
    let dt = 1.0 / c.rig.sample_rate_hz;
    let r_m = c.rig.brake_disc_radius_m;
    // Σk²/(Σk)² of the triangle kernel: the variance gain of white noise.
    let kernel_gain = {
        let ks: Vec<f64> = (0..=2 * w).map(|k| (w - k.abs_diff(w)) as f64).collect();
        ks.iter().map(|k| k * k).sum::<f64>() / ks.iter().sum::<f64>().powi(2)
    };
    let mut runs = Vec::new();
    for run in c.runs_of("operating_point") {
        let RunKind::OperatingPoint { ramp_s, .. } = run.kind else { continue };
        let d = &run.data;
        let (Some(t1), Some(t2), Some(mv)) = (&d.rotor_ticks, &d.motor_ticks, &d.brake_force_mv) else { continue };
        let phi1 = advanced(ticks_to_rad(t1, c.rig.encoder_ticks_per_rev), rotor_lead);
        let phi2 = ticks_to_rad(t2, c.rig.encoder_ticks_per_rev);
        let f = advanced(
            force_n(mv, ForceCal { factor_mv_per_n: cal.force_factor_mv_per_n, offset_mv: cal.force_offset_mv }),
            force_lead,
        );
        let from = d.time_s.partition_point(|&x| x < ramp_s + opts.settle_s);
        runs.push(RunRows {
            id: run.id.clone(),
            rows: rows(&phi1, &phi2, &f, dt, w, r_m, from),
            force_noise_n: diff_noise(&f),
            kernel_gain,
        });
    }
    BalanceData { runs, j1_kgm2: cal.rotor_inertia_kgm2 }
}

impl BalanceData {
    /// Least squares of the balance over the runs `include` accepts, J1
    /// held; C (twist rate) and C_r (absolute rotor speed) are fitted only
    /// when asked, else held at 0. `None` when the regression is singular.
    pub fn fit(&self, include: impl Fn(&str) -> bool, twist_damping: bool, rotor_drag: bool) -> Option<BalanceFit> {
        let j1 = self.j1_kgm2;
        let free = [false, true, twist_damping, rotor_drag, true];
        let mut ne = rig_estimate::linear::Normal::new(5);
        for r in self.runs.iter().filter(|r| include(&r.id)) {
            for (x, y) in &r.rows {
                let row: Vec<(usize, f64)> = x.iter().copied().enumerate().filter(|(i, _)| free[*i]).collect();
                ne.add_sparse(&row, y + j1 * x[0]);
            }
        }
        // A held coefficient: one unit row pins it at 0 (its column carries no data).
        for (i, _) in free.iter().enumerate().filter(|(_, f)| !**f) {
            ne.add_sparse(&[(i, 1.0)], 0.0);
        }
        let b = ne.solve()?;
        Some(BalanceFit {
            stiffness_nm_rad: b[1],
            twist_damping_nm_s_rad: b[2],
            rotor_drag_nm_s_rad: -b[3],
            offset_nm: b[4],
        })
    }

    /// Each run's RMS residual of `fit`, N·m, over the runs `include`
    /// accepts (runs without rows left out): the teacher-forced misfit a
    /// structural candidate is compared on.
    pub fn run_rms(&self, fit: &BalanceFit, include: impl Fn(&str) -> bool) -> Vec<(String, f64)> {
        let beta = fit.beta(self.j1_kgm2);
        self.runs
            .iter()
            .filter(|r| include(&r.id) && !r.rows.is_empty())
            .map(|r| {
                let e: Vec<f64> =
                    r.rows.iter().map(|(x, y)| y - x.iter().zip(&beta).map(|(a, b)| a * b).sum::<f64>()).collect();
                (r.id.clone(), rms(&e))
            })
            .collect()
    }
}

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
    let w = nominal_window_samples(o.balance_window_s, c.rig.sample_rate_hz).max(2);
    let dt = 1.0 / c.rig.sample_rate_hz;
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
    let big_t = w as f64 * dt;
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
