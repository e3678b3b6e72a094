//! The campaign's operating points against the rig model, in the frequency
//! domain (thesis section 4.6, Figs. 4.22-4.26, Table 4.8): every operating
//! point measured and simulated, its steady window, the line analysis of rotor
//! speed and friction torque, and Table 4.8's published peaks through the same
//! line analysis. The `spectra` stage writes what [`render`] makes of it.

pub mod render;

use crate::SweepError;
use rayon::prelude::*;
use rig_calibrate::{CampaignCalibration, friction_torque_nm};
use rig_model::{SimOptions, simulate};
use rig_spectra::{Line, LineAnalysis, LineAnalysisOptions, LineOptions, SignalLines, analyse_lines, line_analysis};
use rig_types::sensor::encoder_speed_rad_s as rotor_speed_rad_s;
use rig_types::units::RAD_S_TO_RPM;
use rig_types::{Campaign, RigInfo, RigParams, Run, RunInput, RunKind, Trajectory};
use serde::Deserialize;

/// The study's settings (pipeline.toml `[stage.params]` of `spectra`).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SpectraOptions {
    /// Integrator tolerances of the rig-model runs (pipeline.toml's `[shared.integrator]`).
    pub integrator: SimOptions,
    pub settle_s: f64,
    pub min_freq_hz: f64,
    pub max_freq_hz: f64,
    pub welch_segment_s: f64,
    pub tolerance_bins: f64,
    pub table_4_8_records_s: Vec<f64>,
}

/// One operating point, measured or simulated, over its steady window.
pub struct Signals {
    pub time_s: Vec<f64>,
    pub rotor_rpm: Vec<f64>,
    pub motor_rpm: Vec<f64>,
    pub twist_rad: Vec<f64>,
    pub torque_nm: Vec<f64>,
}

impl Signals {
    fn window(&self, from_s: f64) -> Signals {
        let i0 = self.time_s.partition_point(|t| *t < from_s);
        Signals {
            time_s: self.time_s[i0..].to_vec(),
            rotor_rpm: self.rotor_rpm[i0..].to_vec(),
            motor_rpm: self.motor_rpm[i0..].to_vec(),
            twist_rad: self.twist_rad[i0..].to_vec(),
            torque_nm: self.torque_nm[i0..].to_vec(),
        }
    }

    /// Sample rate from the first and last time stamps.
    pub fn fs_hz(&self) -> f64 {
        let n = self.time_s.len();
        (n - 1) as f64 / (self.time_s[n - 1] - self.time_s[0])
    }
}

fn measured(run: &Run, rig: &RigInfo, cal: &CampaignCalibration) -> Result<Signals, SweepError> {
    let d = &run.data;
    let (Some(rt), Some(mt), Some(mv)) = (&d.rotor_ticks, &d.motor_ticks, &d.brake_force_mv) else {
        return Err(SweepError::Analysis(format!(
            "run {}: an operating_point needs rotor_ticks, motor_ticks and brake_force_mv",
            run.id
        )));
    };
    let tpr = rig.encoder_ticks_per_rev;
    let rad = 2.0 * std::f64::consts::PI / tpr as f64;
    let rpm = |x: Vec<f64>| x.into_iter().map(|v| v * RAD_S_TO_RPM).collect::<Vec<f64>>();
    Ok(Signals {
        time_s: d.time_s.clone(),
        rotor_rpm: rpm(rotor_speed_rad_s(&d.time_s, rt, tpr)),
        motor_rpm: rpm(rotor_speed_rad_s(&d.time_s, mt, tpr)),
        twist_rad: mt.iter().zip(rt).map(|(m, r)| (m - r) as f64 * rad).collect(),
        torque_nm: friction_torque_nm(mv, cal, rig.brake_disc_radius_m),
    })
}

fn simulated(tr: &Trajectory) -> Signals {
    Signals {
        time_s: tr.time_s.clone(),
        rotor_rpm: tr.rotor_speed_rad_s.iter().map(|v| v * RAD_S_TO_RPM).collect(),
        motor_rpm: tr.motor_speed_rad_s.iter().map(|v| v * RAD_S_TO_RPM).collect(),
        twist_rad: tr.motor_angle_rad.iter().zip(&tr.rotor_angle_rad).map(|(m, r)| m - r).collect(),
        torque_nm: tr.friction_torque_nm.clone(),
    }
}

impl SpectraOptions {
    /// The band and tolerance of every line analysis of the study: 0.1 Hz
    /// keeps drift out (steady windows are ~30 s: 3 bins), 10 Hz is the range
    /// of the stick-slip harmonics that the encoder differentiator passes;
    /// the tolerance is argued in pipeline.toml (`spectra`).
    pub fn line_options(&self) -> LineAnalysisOptions {
        LineAnalysisOptions {
            min_freq_hz: self.min_freq_hz,
            max_freq_hz: self.max_freq_hz,
            tolerance_bins: self.tolerance_bins,
        }
    }
}

/// `rig_spectra::line_analysis` of one signal with the study's options.
pub fn lines_of(x: &[f64], fs_hz: f64, o: &SpectraOptions) -> Result<SignalLines, SweepError> {
    line_analysis(x, fs_hz, &o.line_options()).map_err(|e| SweepError::Analysis(format!("spectrum: {e}")))
}

/// One operating point of the campaign: its run and what it imposes.
pub struct OperatingPoint<'a> {
    pub run: &'a Run,
    pub motor_rpm_setpoint: f64,
    pub normal_force_n: f64,
    pub ramp_s: f64,
    /// Measured and simulated signals over the steady window (from ramp + settling to the end).
    pub measured: Signals,
    pub simulated: Signals,
    /// Line analysis of the measured, then the simulated signals: `rotor_rpm`
    /// and `torque_nm`, at the measured window's sample rate.
    pub measured_lines: Vec<NamedLines>,
    pub simulated_lines: Vec<NamedLines>,
}

/// The line analysis of one named signal of one operating point.
pub struct NamedLines {
    /// `rotor_rpm` or `torque_nm`.
    pub signal: &'static str,
    pub lines: SignalLines,
}

fn signal_lines(sig: &Signals, fs_hz: f64, o: &SpectraOptions) -> Result<Vec<NamedLines>, SweepError> {
    [("rotor_rpm", &sig.rotor_rpm), ("torque_nm", &sig.torque_nm)]
        .into_iter()
        .map(|(signal, x)| Ok(NamedLines { signal, lines: lines_of(x, fs_hz, o)? }))
        .collect()
}

impl OperatingPoint<'_> {
    /// Length of the measured steady window, s.
    pub fn window_s(&self) -> f64 {
        let t = &self.measured.time_s;
        t[t.len() - 1] - t[0]
    }
}

/// An operating point left out of the study: its record ends before the
/// steady window (ramp, then `settle_s`) has [`MIN_STEADY_SAMPLES`] samples.
pub struct ShortRun {
    pub id: String,
    /// The record's last time stamp, s.
    pub duration_s: f64,
    /// Where its steady window would start, s.
    pub steady_from_s: f64,
}

/// Every operating point of the campaign, measured and simulated with `rig`.
pub struct SpectraStudy<'a> {
    pub points: Vec<OperatingPoint<'a>>,
    /// Operating points that end before their steady window starts, left out.
    pub short: Vec<ShortRun>,
    /// The campaign's brake disc radius, m (for captions).
    pub brake_disc_radius_m: f64,
}

/// Measures every operating point of `campaign` and simulates it with `rig`
/// at the same set-point (in parallel, collected in campaign order), both cut
/// to the steady window; a run with no steady window is left out and listed
/// (an error when every run is).
pub fn study<'a>(
    campaign: &'a Campaign,
    cal: &CampaignCalibration,
    rig: &RigParams,
    o: &SpectraOptions,
) -> Result<SpectraStudy<'a>, SweepError> {
    let ops: Vec<(&Run, f64, f64, f64)> = campaign
        .runs
        .iter()
        .filter_map(|r| match r.kind {
            RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } => {
                Some((r, motor_rpm_setpoint, normal_force_n, ramp_s))
            }
            _ => None,
        })
        .collect();
    if ops.is_empty() {
        return Err(SweepError::Analysis(format!("campaign {}: no operating_point runs", campaign.name)));
    }
    // A run that ends before its ramp and settling are over has no steady
    // window: left out, and said (`SpectraStudy::short`); the study needs one.
    let (ops, short): (Vec<_>, Vec<_>) = ops
        .into_iter()
        .partition(|(run, _, _, ramp)| steady_samples(&run.data.time_s, ramp + o.settle_s) > MIN_STEADY_SAMPLES);
    if ops.is_empty() {
        return Err(SweepError::Analysis(format!(
            "campaign {}: needs at least 1 operating_point run with a steady window (more than {MIN_STEADY_SAMPLES} samples after ramp_s + settle_s = ramp_s + {} s); every run ends before",
            campaign.name, o.settle_s
        )));
    }
    let short: Vec<ShortRun> = short
        .into_iter()
        .map(|(run, _, _, ramp)| ShortRun {
            id: run.id.clone(),
            duration_s: run.data.time_s.last().copied().unwrap_or(0.0),
            steady_from_s: ramp + o.settle_s,
        })
        .collect();
    let sims: Vec<Result<Trajectory, SweepError>> = ops
        .par_iter()
        .map(|(run, rpm, n, ramp)| {
            let input = RunInput::OperatingPoint { motor_rpm_setpoint: *rpm, normal_force_n: *n, ramp_s: *ramp };
            simulate(rig, &input, &run.data.time_s, &o.integrator)
                .map_err(|e| SweepError::Analysis(format!("simulating run {}: {e}", run.id)))
        })
        .collect();
    let mut points = Vec::new();
    for ((run, rpm, n, ramp), sim) in ops.into_iter().zip(sims) {
        let start = ramp + o.settle_s;
        let m = measured(run, &campaign.rig, cal)?.window(start);
        let s = simulated(&sim?).window(start);
        let fs = m.fs_hz();
        points.push(OperatingPoint {
            run,
            motor_rpm_setpoint: rpm,
            normal_force_n: n,
            ramp_s: ramp,
            measured_lines: signal_lines(&m, fs, o)?,
            simulated_lines: signal_lines(&s, fs, o)?,
            measured: m,
            simulated: s,
        });
    }
    Ok(SpectraStudy { points, short, brake_disc_radius_m: campaign.rig.brake_disc_radius_m })
}

/// Fewest samples a steady window may have (the line analysis' Welch
/// segments need more).
const MIN_STEADY_SAMPLES: usize = 64;

/// Samples of a record at or after `from_s` (its time column, authoritative).
fn steady_samples(time_s: &[f64], from_s: f64) -> usize {
    time_s.len() - time_s.partition_point(|t| *t < from_s)
}

impl SpectraStudy<'_> {
    /// The operating point nearest to (rpm, N), distances scaled by the campaign's spans.
    pub fn nearest(&self, rpm: f64, n: f64) -> Option<&OperatingPoint<'_>> {
        let span = |f: fn(&OperatingPoint) -> f64| {
            let lo = self.points.iter().map(f).fold(f64::INFINITY, f64::min);
            let hi = self.points.iter().map(f).fold(f64::NEG_INFINITY, f64::max);
            (hi - lo).max(1e-9)
        };
        let (sr, sn) = (span(|o| o.motor_rpm_setpoint), span(|o| o.normal_force_n));
        self.points.iter().min_by(|a, b| {
            let d = |o: &OperatingPoint| {
                ((o.motor_rpm_setpoint - rpm) / sr).powi(2) + ((o.normal_force_n - n) / sn).powi(2)
            };
            d(a).total_cmp(&d(b))
        })
    }
}

/// Table 4.8's three published peaks, Hz (amplitudes are not published).
pub const TABLE_4_8_PEAKS_HZ: [f64; 3] = [0.352, 0.718, 1.069];

/// Table 4.8's peaks through the line analysis at record length `t_s`
/// (resolution 1/T), amplitudes taken equal, the library's default options.
pub fn table_4_8_lines(t_s: f64) -> LineAnalysis {
    let lines: Vec<Line> =
        TABLE_4_8_PEAKS_HZ.iter().map(|&f| Line { freq_hz: f, amplitude: 1.0, sigma_hz: 0.0 }).collect();
    analyse_lines(&lines, 1.0 / t_s, &LineOptions::default())
}
