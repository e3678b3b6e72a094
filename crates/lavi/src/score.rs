//! The phase-insensitive misfit: window features of a free run against the
//! measured ones, each error in units of its issue-10 target, combined by RMS.
//!
//! e = (sim − meas) / tol with tol = 10 % of the measured maximum
//! (`bit_speed_max_rpm`), 10 rpm (`bit_speed_min_rpm`), 25 % of the measured
//! stick fraction but at least 0.01 (25 % of 0.04, so a window that hardly sticks
//! does not divide by zero; `stick_fraction`), 3 % of the measured fundamental
//! (`fundamental_hz`; a run without a line scores the cap) and 30 % of the
//! measured loop area (`loop_area`), 10 % of the measured mean slip torque
//! (`slip_torque_nm`) and of the measured break-away torque
//! (`breakaway_torque_nm`: issue 26). A feature the measurement lacks (no stick
//! phase ends in the window) scores 0 when the run lacks it too, the cap
//! otherwise. Each |e| is capped at 10 so that one
//! diverging feature cannot hide the others; M = √(mean e²). M ≤ 1 means the
//! features are, in RMS, within their targets; a feature meets its target when |e| ≤ 1.

use crate::LaviError;
use crate::data::{Prepared, RPM_TO_RAD_S, WindowSpec, derivative};
use crate::features::{FeatureOptions, Features, N_FEATURES, StickTorque, stick_torque, window_features};
use crate::sim::{Inputs, Model, Run, Start, delay_samples, simulate};
use rayon::prelude::*;

/// Cap on one feature's normalised error.
pub const ERROR_CAP: f64 = 10.0;

/// Normalised errors of the features (order of [`crate::features::FEATURES`]).
pub fn feature_errors(meas: &Features, sim: &Features) -> [f64; N_FEATURES] {
    let tol = [
        0.10 * meas.bit_speed_max_rpm.abs(),
        10.0,
        0.25 * meas.stick_fraction.max(0.04),
        0.03 * meas.fundamental_hz,
        0.30 * meas.loop_area,
        0.10 * meas.slip_torque_nm.abs(),
        0.10 * meas.breakaway_torque_nm.abs(),
    ];
    let mut e = [0.0; N_FEATURES];
    for (i, ei) in e.iter_mut().enumerate() {
        let x = (sim.get(i) - meas.get(i)) / tol[i];
        *ei = if x.is_finite() {
            x.clamp(-ERROR_CAP, ERROR_CAP)
        } else if meas.get(i).is_nan() && sim.get(i).is_nan() {
            0.0
        } else {
            ERROR_CAP
        };
    }
    e
}

/// M = √(mean e²) of [`feature_errors`].
pub fn misfit_of(meas: &Features, sim: &Features) -> f64 {
    let e = feature_errors(meas, sim);
    (e.iter().map(|x| x * x).sum::<f64>() / e.len() as f64).sqrt()
}

/// Everything a free run and its score need, per window.
#[derive(Debug)]
pub struct Evaluator<'a> {
    pub data: &'a Prepared,
    /// Calibration window first.
    pub windows: Vec<WindowSpec>,
    pub measured: Vec<Features>,
    pub fopts: FeatureOptions,
    pub substeps: usize,
    pub slip_speed_rpm: f64,
    top_rad_s: Vec<f64>,
    top_ref_rad_s: Vec<f64>,
    bit_acc_rad_s2: Vec<f64>,
}

impl<'a> Evaluator<'a> {
    /// `drive_ref_window_s`: the centred moving mean of the measured top speed
    /// that the compliant drive's controller follows.
    pub fn new(
        data: &'a Prepared,
        windows: Vec<WindowSpec>,
        fopts: FeatureOptions,
        substeps: usize,
        slip_speed_rpm: f64,
        drive_ref_window_s: f64,
    ) -> Result<Self, LaviError> {
        let top_rad_s: Vec<f64> = data.top_rpm.iter().map(|v| v * RPM_TO_RAD_S).collect();
        let bit: Vec<f64> = data.bit_rpm.iter().map(|v| v * RPM_TO_RAD_S).collect();
        let half = ((drive_ref_window_s * data.fs_hz) as usize / 2).max(1);
        let mut prefix = vec![0.0; top_rad_s.len() + 1];
        for (i, v) in top_rad_s.iter().enumerate() {
            prefix[i + 1] = prefix[i] + v;
        }
        let n = top_rad_s.len();
        let top_ref_rad_s = (0..n)
            .map(|i| {
                (prefix[(i + half + 1).min(n)] - prefix[i.saturating_sub(half)])
                    / ((i + half + 1).min(n) - i.saturating_sub(half)) as f64
            })
            .collect();
        // The recorded channels through the same one low-pass as a simulated run's.
        let measured = windows
            .iter()
            .map(|w| {
                window_features(
                    &data.bit_raw_rpm[w.span.clone()],
                    &data.torque_raw_nm[w.span.clone()],
                    w.window.clone(),
                    &fopts,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Evaluator {
            data,
            windows,
            measured,
            fopts,
            substeps,
            slip_speed_rpm,
            top_rad_s,
            top_ref_rad_s,
            bit_acc_rad_s2: derivative(&bit, data.fs_hz),
        })
    }

    /// Index of the calibration window.
    pub fn calibration(&self) -> usize {
        0
    }

    /// Indices of the held-out windows.
    pub fn heldout(&self) -> Vec<usize> {
        (1..self.windows.len()).collect()
    }

    /// Free run of `m` over window `wi`'s span (warm-up included), from the measured state at its start.
    pub fn simulate(&self, m: &Model, wi: usize) -> Result<Run, LaviError> {
        let s = self.windows[wi].span.clone();
        let u = Inputs {
            fs_hz: self.data.fs_hz,
            top_rad_s: &self.top_rad_s[s.clone()],
            wob_n: &self.data.wob_n[s.clone()],
            top_ref_rad_s: &self.top_ref_rad_s[s.clone()],
        };
        // The contact torque at the start as the channel reads it: τ later when the channel is late by τ.
        let at = (s.start as isize + delay_samples(m.torque_delay_s, self.data.fs_hz))
            .clamp(0, self.data.len() as isize - 1) as usize;
        let start = Start {
            bit_rad_s: self.data.bit_rpm[s.start] * RPM_TO_RAD_S,
            bit_acc_rad_s2: self.bit_acc_rad_s2[s.start],
            torque_nm: self.data.torque_nm[at],
        };
        simulate(m, &u, start, self.substeps)
    }

    /// Features of the free run (the same function as for the measurement).
    pub fn features(&self, m: &Model, wi: usize) -> Result<Features, LaviError> {
        let r = self.simulate(m, wi)?;
        let rpm: Vec<f64> = r.bit_rad_s.iter().map(|v| v / RPM_TO_RAD_S).collect();
        window_features(&rpm, &r.torque_nm, self.windows[wi].window.clone(), &self.fopts)
    }

    /// [`StickTorque`] of window `wi`: as recorded (`m` None) or in the free run of `m`.
    pub fn stick_torque(&self, m: Option<&Model>, wi: usize) -> Result<StickTorque, LaviError> {
        let w = &self.windows[wi];
        match m {
            None => stick_torque(
                &self.data.bit_raw_rpm[w.span.clone()],
                &self.data.torque_raw_nm[w.span.clone()],
                w.window.clone(),
                &self.fopts,
            ),
            Some(m) => {
                let r = self.simulate(m, wi)?;
                let rpm: Vec<f64> = r.bit_rad_s.iter().map(|v| v / RPM_TO_RAD_S).collect();
                stick_torque(&rpm, &r.torque_nm, w.window.clone(), &self.fopts)
            }
        }
    }

    /// Misfit of `m` on window `wi`; a run that diverges scores the cap.
    pub fn misfit(&self, m: &Model, wi: usize) -> f64 {
        match self.features(m, wi) {
            Ok(f) => misfit_of(&self.measured[wi], &f),
            Err(_) => ERROR_CAP,
        }
    }

    /// Misfits on every held-out window, in window order (run in parallel,
    /// collected in order: the same numbers on any thread count).
    pub fn heldout_misfits(&self, m: &Model) -> Vec<f64> {
        self.heldout().into_par_iter().map(|w| self.misfit(m, w)).collect()
    }

    /// Features of the free run on every window (calibration first), in
    /// parallel and in window order; a run that fails has NaN features.
    pub fn all_features(&self, m: &Model) -> Vec<Features> {
        (0..self.windows.len()).into_par_iter().map(|w| self.features(m, w).unwrap_or(Features::NAN)).collect()
    }
}
