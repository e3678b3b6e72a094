//! Stage-to-stage contract types: what one stage writes as JSON
//! (`data/thesis.json`, `data/campaign-calibration.json`) and later stages
//! read, so a reader needs no dependency on the crate that computed them.
//! serde only; the field order is the JSON's (keep it: outputs are compared
//! byte for byte). `rig_calibrate` computes every value here.

use crate::thesis::LabelledPoint;
use crate::{MotorParams, ThesisFriction};
use serde::{Deserialize, Serialize};

/// Default confidence level of every interval of the campaign calibration.
pub const CONFIDENCE: f64 = 0.95;

/// One extremum of a decaying oscillation.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct Extremum {
    pub time_s: f64,
    pub value: f64,
    pub is_max: bool,
}

/// One log-decrement estimate from extremum k and extremum k+2 (same sign):
/// swings S_k = |e_{k+1} − e_k| and S_{k+2} are free of any constant offset,
/// and for x = c + A e^{−σt} cos(ω_d t) they satisfy S_k/S_{k+2} = e^{δ}.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecayPair {
    pub t1_s: f64,
    pub t2_s: f64,
    /// Swings (peak-to-peak) x1 and x2 in the signal's unit.
    pub x1: f64,
    pub x2: f64,
    /// δ (Eq. 4-2a), ξ (Eq. 4-2b), ω_d = 2π/(t2 − t1), ω_n (Eq. 4-3).
    pub log_decrement: f64,
    pub damping_ratio: f64,
    pub damped_rad_s: f64,
    pub natural_rad_s: f64,
}

/// The free decay of one record: the extrema found, the pairs used and their spread.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecayAnalysis {
    pub extrema: Vec<Extremum>,
    pub pairs: Vec<DecayPair>,
    pub log_decrement_mean: f64,
    pub log_decrement_std: f64,
    pub damping_ratio_mean: f64,
    pub damping_ratio_std: f64,
    pub damped_rad_s_mean: f64,
    pub damped_rad_s_std: f64,
    pub natural_rad_s_mean: f64,
    pub natural_rad_s_std: f64,
}

/// Settings of the decay analysis; explicit so a stage can state them.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct DecaySettings {
    /// Half-width of the zero-phase smoothing before extremum search, s.
    pub smooth_half_s: f64,
    /// Half-width of the least-squares parabola that locates each extremum, s
    /// (keep it well under a quarter period so the parabola fits the cosine).
    pub peak_fit_half_s: f64,
    /// An extremum is confirmed only after the signal has left it by this much
    /// (rejects quantisation flicker on flat tops).
    pub hysteresis: f64,
    /// Pairs whose later swing is below this are dropped (quantisation floor).
    pub min_swing: f64,
    /// Extrema skipped at the start (the start-up transient from rest).
    pub skip_extrema: usize,
}

/// A least-squares straight line y = slope·x (+ intercept) with standard
/// errors and two-sided confidence intervals at `confidence`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct LineFit {
    pub slope: f64,
    pub slope_stderr: f64,
    pub slope_ci: [f64; 2],
    /// 0 (and no error) for a fit through the origin.
    pub intercept: f64,
    pub intercept_stderr: f64,
    pub intercept_ci: [f64; 2],
    /// Residual standard deviation (with n − p degrees of freedom).
    pub residual_std: f64,
    pub dof: usize,
    pub confidence: f64,
    pub through_origin: bool,
}

/// One force_calibration run: the sensor's mean output under a known load.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ForceRun {
    pub id: String,
    pub load_n: f64,
    pub mean_mv: f64,
    /// Standard deviation of the samples (sensor noise), mV.
    pub std_mv: f64,
    pub samples: usize,
    /// mean_mv / load_n as in Table 4.6 (no offset); `None` for a zero load.
    pub ratio_mv_per_n: Option<f64>,
}

/// One static_twist run: the held torque and the mean rotor angle.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct TwistRun {
    pub id: String,
    pub torque_nm: f64,
    pub angle_rad: f64,
    pub angle_std_rad: f64,
    /// K_SE = T/φ for this run (Table 4.3); `None` when the angle is zero.
    pub stiffness_nm_rad: Option<f64>,
}

/// The free decay of one voltage step.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct StepDecay {
    pub id: String,
    pub voltage_v: f64,
    /// Analysis of the shaft twist φ2 − φ1 (the quantity used, see `rig_calibrate::calibrate_campaign`).
    pub twist: DecayAnalysis,
    /// Cross-check on the rotor speed Ω1 (the thesis' Fig. 4.8 signal); `None` if it shows no decay.
    pub rotor_speed: Option<DecayAnalysis>,
    /// J1 = K / ω_n² (Eq. 4-4) with the campaign's static stiffness and this step's mean ω_n.
    pub rotor_inertia_kgm2: f64,
}

/// A voltage step left out of the decay analysis, and why.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct SkippedStep {
    pub id: String,
    pub voltage_v: f64,
    pub reason: String,
}

/// Everything the campaign's calibration runs say. Fields named in the brief
/// are the interface other crates rely on.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct CampaignCalibration {
    /// mV = offset + factor · N, least squares with offset over the force runs.
    pub force_factor_mv_per_n: f64,
    pub force_factor_mv_per_n_stderr: f64,
    pub force_factor_mv_per_n_ci: [f64; 2],
    pub force_offset_mv: f64,
    pub force_offset_mv_stderr: f64,
    /// Table 4.6's way: mean of the per-run ratios mV/N (no offset).
    pub force_ratio_mean_mv_per_n: f64,
    pub force_runs: Vec<ForceRun>,
    /// T = K φ through the origin (the encoder is zeroed unloaded), with 95 % CI.
    pub stiffness_nm_rad: f64,
    pub stiffness_nm_rad_stderr: f64,
    pub stiffness_nm_rad_ci: [f64; 2],
    /// The same data fitted with an offset (a check that the origin is right).
    pub stiffness_with_offset: LineFit,
    pub twist_runs: Vec<TwistRun>,
    /// Means over the voltage steps of each step's mean; stderr = spread over steps / √n.
    pub log_decrement: f64,
    pub log_decrement_stderr: f64,
    pub damping_ratio: f64,
    pub damping_ratio_stderr: f64,
    pub damped_frequency_rad_s: f64,
    pub damped_frequency_rad_s_stderr: f64,
    pub natural_frequency_rad_s: f64,
    pub natural_frequency_rad_s_stderr: f64,
    /// J1 = K / ω_n² (Eq. 4-4); stderr propagates K's and ω_n's.
    pub rotor_inertia_kgm2: f64,
    pub rotor_inertia_kgm2_stderr: f64,
    pub steps: Vec<StepDecay>,
    /// Voltage steps that showed no measurable free decay (left out of the means).
    pub steps_without_decay: Vec<SkippedStep>,
    pub settings: CalibrationSettings,
    pub twist_settings: DecaySettings,
    pub speed_settings: DecaySettings,
}

/// The knobs of the campaign calibration (pipeline.toml `[stage.params]` of
/// `campaign-calibration`; [`Default`] holds the documented values).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct CalibrationSettings {
    /// Confidence of every interval (two-sided).
    pub confidence: f64,
    /// Zero-phase smoothing before the extremum search, half-width in s.
    pub smooth_half_s: f64,
    /// Half-width of the parabola that locates each extremum, s: ±0.15 s is
    /// ±25° of phase at the ≈ 0.45 Hz the chapter reports.
    pub peak_fit_half_s: f64,
    /// Twist: an extremum is confirmed after the signal leaves it by this many
    /// encoder ticks (3 rejects quantisation flicker on flat tops).
    pub twist_hysteresis_ticks: f64,
    /// Twist: pairs stop when a swing falls under this many ticks (20: beyond
    /// that one tick is > 5 % of the swing).
    pub twist_min_swing_ticks: f64,
    /// Rotor-speed cross-check: the differentiator leaves ≈ 0.16 rad/s of
    /// quantisation noise, so 0.5 rad/s hysteresis and a 3 rad/s smallest swing.
    pub speed_hysteresis_rad_s: f64,
    pub speed_min_swing_rad_s: f64,
    /// Extrema skipped at the start: the first is reached while the motor is
    /// still spinning up from rest, so the swing into it is forced, not free.
    pub skip_extrema: usize,
}

impl Default for CalibrationSettings {
    fn default() -> Self {
        CalibrationSettings {
            confidence: CONFIDENCE,
            smooth_half_s: 0.02,
            peak_fit_half_s: 0.15,
            twist_hysteresis_ticks: 3.0,
            twist_min_swing_ticks: 20.0,
            speed_hysteresis_rad_s: 0.5,
            speed_min_swing_rad_s: 3.0,
            skip_extrema: 1,
        }
    }
}

impl CalibrationSettings {
    /// Decay settings for the twist, in rad for an encoder of `ticks_per_rev`.
    pub fn twist(&self, ticks_per_rev: u32) -> DecaySettings {
        let tick = crate::sensor::tick_rad(ticks_per_rev);
        DecaySettings {
            smooth_half_s: self.smooth_half_s,
            peak_fit_half_s: self.peak_fit_half_s,
            hysteresis: self.twist_hysteresis_ticks * tick,
            min_swing: self.twist_min_swing_ticks * tick,
            skip_extrema: self.skip_extrema,
        }
    }

    /// Decay settings for the rotor-speed cross-check, rad/s.
    pub fn speed(&self) -> DecaySettings {
        DecaySettings {
            smooth_half_s: self.smooth_half_s,
            peak_fit_half_s: self.peak_fit_half_s,
            hysteresis: self.speed_hysteresis_rad_s,
            min_swing: self.speed_min_swing_rad_s,
            skip_extrema: self.skip_extrema,
        }
    }
}

/// A frequency peak of Table 4.8 in both printed units.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FrequencyPeak {
    pub freq_hz: f64,
    /// As printed in the rad/s column (not recomputed from Hz).
    pub omega_rad_s: f64,
}

/// The thesis' parameters as downstream stages need them (`data/thesis.json`).
/// Values are as published unless the name says `_recomputed`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ThesisData {
    /// Table 4.4 (initial values) and Table 4.5 (estimated), gear_ratio 1
    /// because the chapter's model leaves the 8:1 gearbox out (§4.2).
    pub motor_initial: MotorParams,
    pub motor_estimated: MotorParams,
    /// J_1 and K_s of Table 4.5 (what the thesis model uses).
    pub rotor_inertia_kgm2: f64,
    pub shaft_stiffness_nm_rad: f64,
    /// J_1 and K_s of Table 4.4.
    pub rotor_inertia_initial_kgm2: f64,
    pub shaft_stiffness_initial_nm_rad: f64,
    /// Table 4.2's mean ξ as printed, and ξ by Eq. 4-2b from its mean δ (they disagree, see the audit).
    pub damping_ratio: f64,
    pub damping_ratio_recomputed: f64,
    /// C = 2 ξ √(J_1 K_s) (text under Eq. 4-9) with the printed ξ and Table 4.5's J_1, K_s.
    pub shaft_damping_nm_s_rad: f64,
    /// Same with ξ of Eq. 4-2b.
    pub shaft_damping_recomputed_nm_s_rad: f64,
    /// Table 4.2's mean ω_d and ω_n, printed in Hz.
    pub damped_frequency_hz: f64,
    pub natural_frequency_hz: f64,
    /// Eq. 4-1, 4-4, 4-5 as printed.
    pub k_sa_nm_rad: f64,
    pub j1e_kgm2: f64,
    pub j1a_kgm2: f64,
    /// Table 4.7 with Tol of Eq. 4-10.
    pub friction: ThesisFriction,
    /// r of Eq. 4-10, m.
    pub brake_disc_radius_m: f64,
    /// Table 4.8.
    pub peaks: Vec<FrequencyPeak>,
    /// The 8:1 gearbox the text mentions and the model omits.
    pub gear_ratio: f64,
    /// "8 V (≃ 16 rad/s)".
    pub step_voltage_v: f64,
    pub step_speed_rad_s: f64,
    /// "≃ 0.4 Hz" experimental and "≃ 0.3 Hz" numerical oscillation frequencies (§4.6).
    pub oscillation_experimental_hz: f64,
    pub oscillation_numerical_hz: f64,
    pub encoder_ticks_per_rev: f64,
    /// Operating points the captions label vibrating or quiet.
    pub labelled_points: Vec<LabelledPoint>,
}

/// The rule that lets an effect into a model by forward selection, shared by
/// every study that selects (pipeline.toml's `[shared.selection]`, handed to
/// the `diagnosis`, `lavi` and `slider` stages): declared once so they cannot
/// drift. The rule itself is [`SelectionRule::admits`] (`crate::select`).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SelectionRule {
    /// An effect must lower the held-out misfit by at least this fraction …
    pub min_relative_gain: f64,
    /// … with a paired unit-level t of ln(M_before/M_after) of at least this.
    pub min_t: f64,
}
