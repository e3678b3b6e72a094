//! The torque channel against the equation of motion on the calibration
//! window: the top speed on the bit's clock, the channel's balance, and the
//! torque–speed loop's spread by trial delays.

use super::Structure;
use crate::data::{Prepared, RPM_TO_RAD_S, WindowSpec, derivative};
use crate::eom::TorqueScan;
use crate::sim::Model;
use serde::Serialize;

/// The top speed over samples `r`, rad/s, on the bit speed's clock when the
/// top-speed channel is late by `top_delay_s` (negative: early): sample i is the
/// channel's sample i + τ_top f_s (whole samples, the record's ends standing in beyond them).
pub fn top_rad_s(d: &Prepared, r: std::ops::Range<usize>, top_delay_s: f64) -> Vec<f64> {
    let k = crate::sim::delay_samples(top_delay_s, d.fs_hz);
    crate::sim::read_late(&d.top_rpm, &r, k).iter().map(|v| v * RPM_TO_RAD_S).collect()
}

/// The torque channel's delay on the speed channels that fits the equation of
/// motion best (least residual of the unconstrained fit under `st`'s damping and
/// sensor inertia) on the calibration window, over ±`max_s` in steps of one sample.
pub fn best_delay_s(d: &Prepared, cal: &WindowSpec, st: Structure, max_s: f64) -> f64 {
    let r = (cal.span.start + cal.window.start)..(cal.span.start + cal.window.end);
    let t = &d.time_s[r.clone()];
    let bit: Vec<f64> = d.bit_rpm[r.clone()].iter().map(|v| v * RPM_TO_RAD_S).collect();
    let top = top_rad_s(d, r.clone(), st.top_delay_s);
    let acc = derivative(&bit, d.fs_hz);
    let m = (max_s * d.fs_hz).round() as isize;
    // The design's columns but the torque's are the same at every delay: made once
    // (the same R² as a fit per delay, bit for bit: eom::TorqueScan).
    let scan = TorqueScan::new(t, &top, &bit, &acc, st.damping);
    let mut tf = vec![0.0; acc.len()];
    let mut best = (f64::NEG_INFINITY, 0.0);
    for k in -m..=m {
        let at = |i: usize| d.torque_nm[(i as isize + k).clamp(0, d.len() as isize - 1) as usize];
        for ((x, i), a) in tf.iter_mut().zip(r.clone()).zip(&acc) {
            *x = at(i) - st.sensor_inertia_kgm2 * a;
        }
        if acc.len() >= 8
            && let Some(r2) = scan.r_squared(&tf)
            && r2 > best.0
        {
            best = (r2, k as f64 / d.fs_hz);
        }
    }
    best.1
}

/// What the torque channel reads, tested teacher-forced on one window: the
/// bit's Newton balance (Real et al. 2018's 1-DOF equation, the one of
/// [`crate::eom`]) with a model's J, k, c, c_a, the torque predicted as
/// T̂ = k Δφ + c (Ω_top − Ω) − c_a Ω − J Ω̇ + T_0 and compared with the channel
/// read `torque_delay_s` later (T_0, the shaft's torque at the window's first
/// sample, the one constant fitted per window: the twist's offset). A term
/// the balance lacks (a drag outside the contact the model's dampings do not
/// carry, a torque that is no function of the bit's state) stays in the
/// residual. An inertia J_s between sensor and contact stays there only when
/// J is known: fitted on the same torque it lowers J by J_s instead.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct ChannelBalance {
    /// 1 − Σ(T − T̂)² / Σ(T − mean T)² over the window.
    pub r_squared: f64,
    /// RMS of T − T̂, N m.
    pub residual_rms_nm: f64,
}

/// [`ChannelBalance`] of window `w` (its `window` samples) under `m`'s J, k, c, c_a and torque delay.
pub fn channel_balance(d: &Prepared, w: &WindowSpec, m: &Model) -> ChannelBalance {
    let r = (w.span.start + w.window.start)..(w.span.start + w.window.end);
    let bit: Vec<f64> = d.bit_rpm[r.clone()].iter().map(|v| v * RPM_TO_RAD_S).collect();
    let top = top_rad_s(d, r.clone(), m.structure.top_delay_s);
    let acc = derivative(&bit, d.fs_hz);
    let dphi = rig_model::one_dof::integrated_twist_rad(&d.time_s[r.clone()], &top, &bit);
    let shift = crate::sim::delay_samples(m.torque_delay_s, d.fs_hz);
    let measured: Vec<f64> =
        r.map(|i| d.torque_nm[(i as isize + shift).clamp(0, d.len() as isize - 1) as usize]).collect();
    let shaft: Vec<f64> = (0..bit.len())
        .map(|i| {
            m.stiffness_nm_rad * dphi[i] + m.damping_nm_s_rad * (top[i] - bit[i])
                - m.absolute_damping_nm_s_rad * bit[i]
                - m.inertia_kgm2 * acc[i]
        })
        .collect();
    let n = measured.len() as f64;
    let t0 = measured.iter().zip(&shaft).map(|(t, p)| t - p).sum::<f64>() / n;
    let mean = measured.iter().sum::<f64>() / n;
    let sse: f64 = measured.iter().zip(&shaft).map(|(t, p)| (t - p - t0).powi(2)).sum();
    let sst: f64 = measured.iter().map(|t| (t - mean).powi(2)).sum();
    ChannelBalance { r_squared: 1.0 - sse / sst, residual_rms_nm: (sse / n).sqrt() }
}

/// How far the torque–bit-speed cloud of the calibration window's slip
/// samples is from a curve when the torque is read `shift_s` later: the
/// standard deviation of the torque in each of `bins` equal bit-speed bins
/// (0 to the window's largest bit speed; bins with fewer than 10 samples left
/// out), its RMS and largest value. A single-valued law T(Ω) leaves only the
/// noise; a loop leaves its width.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct LoopSpread {
    pub shift_s: f64,
    pub rms_bin_std_nm: f64,
    pub max_bin_std_nm: f64,
}

/// [`LoopSpread`] of the calibration window at `shift_s`.
pub fn loop_spread(d: &Prepared, cal: &WindowSpec, slip_speed_rpm: f64, bins: usize, shift_s: f64) -> LoopSpread {
    let r = (cal.span.start + cal.window.start)..(cal.span.start + cal.window.end);
    let shift = (shift_s * d.fs_hz).round() as isize;
    let (v, t): (Vec<f64>, Vec<f64>) = r
        .filter(|&i| d.bit_rpm[i] > slip_speed_rpm)
        .map(|i| (d.bit_rpm[i], d.torque_nm[(i as isize + shift).clamp(0, d.len() as isize - 1) as usize]))
        .unzip();
    let vmax = v.iter().cloned().fold(0.0, f64::max);
    let stds: Vec<f64> = rig_spectra::stickslip::bin_means(&v, &t, 0.0, vmax * (1.0 + 1e-9), bins.max(1))
        .iter()
        .filter(|b| b.count >= 10)
        .map(|b| b.std)
        .collect();
    LoopSpread {
        shift_s: shift as f64 / d.fs_hz,
        rms_bin_std_nm: (stds.iter().map(|x| x * x).sum::<f64>() / stds.len().max(1) as f64).sqrt(),
        max_bin_std_nm: stds.iter().cloned().fold(0.0, f64::max),
    }
}

/// The shift within ±`max_s` (one-sample steps) at which the cloud is closest
/// to a curve (least RMS bin spread of [`loop_spread`]).
pub fn narrowest_loop(d: &Prepared, cal: &WindowSpec, slip_speed_rpm: f64, bins: usize, max_s: f64) -> LoopSpread {
    let m = (max_s * d.fs_hz).round() as isize;
    (-m..=m)
        .map(|k| loop_spread(d, cal, slip_speed_rpm, bins, k as f64 / d.fs_hz))
        .reduce(|a, b| if b.rms_bin_std_nm < a.rms_bin_std_nm { b } else { a })
        .expect("at least the zero shift")
}
