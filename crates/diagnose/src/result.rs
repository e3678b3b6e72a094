//! The diagnosis as data: `diagnosis.json` exactly as ../shared/spec/diagnosis.md
//! gives it (serde, fixed key order, rounded floats), plus the per-run detail
//! that the markdown report and tables are made of (not serialised).

use serde::Serialize;
use std::collections::BTreeMap;

/// Rounds to `sig` significant digits so the JSON does not carry noise digits
/// and stays byte-identical across platforms.
pub fn round_sig(x: f64, sig: i32) -> f64 {
    if x == 0.0 || !x.is_finite() {
        return if x.is_finite() { 0.0 } else { x };
    }
    let e = x.abs().log10().floor() as i32;
    let f = 10f64.powi(sig - 1 - e);
    let r = (x * f).round() / f;
    if r == 0.0 { 0.0 } else { r }
}

/// `diagnosis.json`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Diagnosis {
    pub campaign: String,
    pub verdict: String,
    /// Vocabulary effects in the order forward selection added them, then,
    /// when the adequacy test fails, one `unexplained` finding (spec).
    pub findings: Vec<Finding>,
    /// Every effect tried against the baseline (first selection step).
    pub candidates: Vec<CandidateScore>,
    /// The test of the final model against noise (crate docs).
    pub adequacy: Adequacy,
    /// Where the model's damping acts, as selected on the free run
    /// ([`crate::structure`]).
    pub structure: Structure,
    /// Parameters a fit pinned at a physical bound, with their unconstrained
    /// values (a symptom, never a silent fix).
    pub parameters_at_bounds: Vec<ParamAtBound>,
    /// Operating points recorded with the brake open (`normal_force_n = 0`):
    /// no friction coefficient can be read on them (μ = F/N has no N), so
    /// the selection, its cross-validation and the joint friction fits leave
    /// them out ([`crate::prepare::brake_open`]); the free-run checks still
    /// simulate them (the drive and the shaft with the rotor free). Absent
    /// when every operating point has the brake applied.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub brake_open_runs: Vec<String>,
    /// The drive channel's runs when some operating points have the brake
    /// open (absent otherwise): the teacher-forced PI loop reads the
    /// reference, the motor speed and the voltage, none of which needs the
    /// brake, so its fits read those runs too
    /// ([`crate::prepare::PreparedRuns::drive_units`]).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub drive_channel: Option<DriveChannel>,
    /// Detail for the report; not part of the JSON contract.
    #[serde(skip)]
    pub detail: Detail,
}

/// What the drive channel read ([`Diagnosis::drive_channel`]).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DriveChannel {
    /// Operating points every drive fit read (each fold's PI gains and
    /// drive limit on its training runs, the baseline's gains and the
    /// reported limit on all): the brake applied and open.
    pub runs: usize,
    /// Of them, with the brake open. The selection's units, whose misfits
    /// the step rule compares, are the braked runs alone (the friction
    /// channel's: a run's misfit M_r joins both channels).
    pub brake_open: usize,
    /// Each run with the brake open, held out of its fold's drive fit: its
    /// relative RMS voltage error e_V (crate docs, the misfit) under the
    /// baseline drive and under the final model's, beside its noise floor
    /// σ_V / V_supply.
    pub brake_open_heldout: Vec<DriveRunError>,
}

/// One run's held-out drive error ([`DriveChannel::brake_open_heldout`]).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct DriveRunError {
    pub run: String,
    pub relative_voltage_error_baseline: f64,
    pub relative_voltage_error_final: f64,
    pub noise_floor: f64,
}

#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct Finding {
    pub effect: String,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub params: BTreeMap<String, f64>,
    #[serde(skip_serializing_if = "BTreeMap::is_empty")]
    pub params_stderr: BTreeMap<String, f64>,
    pub evidence: String,
    /// `unexplained` only: the final model's held-out misfit over the noise floor.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub residual_over_noise: Option<f64>,
    /// `unexplained` only: run kinds and channels where the mismatch shows.
    #[serde(rename = "where", skip_serializing_if = "Vec::is_empty")]
    pub where_: Vec<String>,
    /// `unexplained` only: signals the leftover mismatch follows, best first.
    #[serde(skip_serializing_if = "Vec::is_empty")]
    pub signature: Vec<SignatureEntry>,
    pub heldout_runs: Vec<String>,
    /// The misfit of the model before this finding (the bare baseline for the
    /// first, the model with the earlier findings after that).
    pub heldout_misfit_baseline: f64,
    pub heldout_misfit_extended: f64,
    pub relative_gain: f64,
    /// Standard deviation of the relative gain across the cross-validation folds.
    pub relative_gain_fold_sd: f64,
    /// The selection criterion of this step (crate docs); absent for `unexplained`.
    #[serde(skip_serializing_if = "Option::is_none")]
    pub criterion: Option<f64>,
    /// `unexplained` only: the best data-driven extension, simulated in free
    /// run ([`crate::extension`]; spec: `extension`).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub extension: Option<Extension>,
}

/// An `unexplained` finding's `extension` (spec): the extended law, its
/// terms, and the cross-validated free-run misfit of the final model before
/// and after it ([`crate::extension`]).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Extension {
    pub formula: String,
    pub terms: Vec<ExtensionTerm>,
    pub free_run_misfit_before: f64,
    pub free_run_misfit_after: f64,
    pub relative_gain: f64,
    /// Standard deviation of the relative gain across the folds.
    pub relative_gain_sd: f64,
    /// The free-run checks the extended model (held-out free runs) still
    /// flags, `check ratio× (threshold t)`; empty when its free run matches.
    pub free_run_flagged: Vec<String>,
}

/// One term of an [`Extension`]: a library signal, its coefficient fitted
/// on every run and its standard error (jackknife over the folds).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ExtensionTerm {
    pub signal: String,
    pub coefficient: f64,
    pub stderr: f64,
}

/// One term of an `unexplained` finding's `signature`.
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct SignatureEntry {
    pub signal: String,
    pub heldout_gain: f64,
    pub description: String,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CandidateScore {
    pub effect: String,
    pub heldout_misfit_extended: f64,
    pub relative_gain: f64,
    pub relative_gain_fold_sd: f64,
    /// −t of the paired run-level comparison with the baseline (crate docs):
    /// negative favours the candidate.
    pub criterion: f64,
}

/// diagnosis.json's `structure` (spec): the winning damping placement's id
/// ([`crate::structure::REGISTRY`]) and a sentence with its free-run gain.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct Structure {
    pub damping: String,
    pub notes: String,
}

/// One entry of `parameters_at_bounds` (spec).
#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct ParamAtBound {
    pub parameter: String,
    pub bound: f64,
    pub unconstrained: f64,
    pub meaning: String,
}

/// One structural candidate's score (report table; not in the JSON).
#[derive(Debug, Clone, PartialEq)]
pub struct StructureScore {
    pub id: String,
    pub description: String,
    /// Cross-validated free-run misfit of the extended model with this structure.
    pub free_run_misfit: f64,
    /// Relative gain over the baseline structure, its spread across folds, paired t.
    pub relative_gain: f64,
    pub relative_gain_fold_sd: f64,
    pub t: f64,
    /// Cross-validated teacher-forced misfit of the rotor torque balance with
    /// this structure (RMS over held-out runs of each run's RMS residual, N·m).
    pub balance_misfit: f64,
    /// Its relative gain over the baseline structure's, the gain's spread
    /// across folds and the paired run-level t.
    pub balance_gain: f64,
    pub balance_gain_fold_sd: f64,
    pub balance_t: f64,
    /// The same balance on the event-locked rows only (the balance window at
    /// every stick↔slip transition and the next,
    /// [`crate::channels::BalanceData::run_event_rms`]): cross-validated
    /// misfit, N·m, its gain over the baseline structure's, the gain's
    /// spread across folds and the paired run-level t.
    pub event_misfit: f64,
    pub event_gain: f64,
    pub event_gain_fold_sd: f64,
    pub event_t: f64,
    /// The force's ring after the break-aways, at full rate
    /// ([`crate::structure`]'s `sensor_dynamics`: each run's event-averaged
    /// force fitted with the true drop through the candidate's sensor):
    /// cross-validated misfit, N·m at the disc, its gain over the records as recorded, the
    /// gain's spread across folds and the paired run-level t.
    pub ring_misfit: f64,
    pub ring_gain: f64,
    pub ring_gain_fold_sd: f64,
    pub ring_t: f64,
    pub admissible: bool,
    pub accepted: bool,
}

/// The adequacy test of the final model.
#[derive(Debug, Clone, Serialize, PartialEq, Default)]
pub struct Adequacy {
    /// Cross-validated misfit of the final model over the noise floor.
    pub residual_over_noise: f64,
    /// The threshold (calibrated on effect-free virtual-rig campaigns, crate docs).
    pub threshold: f64,
    /// Consistent order lines locked to a shaft angle (none in an adequate model).
    pub order_lines: usize,
    /// Significant checks of the other run kinds and channels.
    pub channel_checks: usize,
    /// Flagged free-run checks of the final model (extended model with its
    /// structure; crate docs): part of the test since issue 25.
    pub free_run_checks: usize,
    pub adequate: bool,
}

/// Per-run comparison row (tables/diagnosis-runs.csv).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunRow {
    pub id: String,
    /// The cross-validation fold the run is held out in.
    pub fold: usize,
    pub normal_force_n: f64,
    pub motor_rpm_setpoint: f64,
    pub slip_samples: usize,
    /// Misfit of the baseline and of the verdict's extended model (equal for none/unexplained).
    pub misfit_baseline: f64,
    pub misfit_extended: f64,
    pub misfit_noise_floor: f64,
    pub force_noise_n: f64,
    pub voltage_noise_v: f64,
    /// Measured features over the steady state.
    pub measured: Features,
    /// Features of the free-run baseline simulation, when one was made.
    pub simulated: Option<Features>,
    /// Features of the free-run extended model (baseline + findings).
    pub extended: Option<Features>,
    /// This run's nuisance phases under the final joint fit, rad: (θ of the
    /// time modulation, θ of the angle modulation); 0 without those effects.
    /// The spec's laws take θ free per run, so the free run of this run is
    /// simulated with them ([`crate::channels::with_run_phases`]).
    pub phases_rad: (f64, f64),
}

/// Features of one run's steady state (measured or simulated).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Features {
    /// Fraction of the steady state with rotor 1 stuck (|Ω1| < slip threshold).
    pub stuck_fraction: f64,
    /// Stick-slip by the one definition of the workspace, the regime
    /// classifier's ([`rig_sweep::Regime::stick_slip`], `[shared.classify]`),
    /// on the same steady window; the sweeps' agreement table uses the same rule.
    pub stick_slip: bool,
    pub rotor_min_rad_s: f64,
    pub rotor_max_rad_s: f64,
    /// Largest spectral peak of Ω1 above 0.05 Hz, Hz (0 when no oscillation).
    pub fundamental_hz: f64,
    /// Deepest dip of the motor speed below the set-point, rad/s.
    pub motor_dip_rad_s: f64,
}

impl Features {
    pub fn stick_slip(&self) -> bool {
        self.stick_slip
    }
}

/// Every recorded channel of an operating point reduced to phase-insensitive
/// run-level features over the steady window (issue 25, item 3), measured or
/// simulated; `values[i]` is the feature [`ChannelFeatures::NAMES`]`[i]` in
/// [`ChannelFeatures::UNITS`]`[i]`, NaN where the run does not define it (no
/// slip sample, no break-away, no force channel). The definitions and noise
/// floors are in `channels::free_run`'s docs.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ChannelFeatures {
    pub values: [f64; ChannelFeatures::N],
}

impl ChannelFeatures {
    pub const N: usize = 9;
    /// Check names (`operating_point.<name>`).
    pub const NAMES: [&'static str; Self::N] = [
        "rotor_max",
        "rotor_min",
        "motor_max",
        "motor_min",
        "voltage_mean",
        "voltage_swing",
        "slip_friction",
        "breakaway_friction",
        "stick_fraction",
    ];
    pub const UNITS: [&'static str; Self::N] = ["rad/s", "rad/s", "rad/s", "rad/s", "V", "V", "N", "N", ""];
    pub const ROTOR_MAX: usize = 0;
    pub const ROTOR_MIN: usize = 1;
    pub const BREAKAWAY: usize = 7;
    pub const STICK_FRACTION: usize = 8;

    pub fn nan() -> Self {
        ChannelFeatures { values: [f64::NAN; Self::N] }
    }
}

impl Default for ChannelFeatures {
    fn default() -> Self {
        Self::nan()
    }
}

/// Everything else the report shows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Detail {
    pub runs: Vec<RunRow>,
    /// (candidate id, criterion, held-out misfit, relative gain, significant, parameter text).
    pub scores: Vec<(String, f64, f64, f64, bool, String)>,
    /// Forward selection, every step and every effect tried in it.
    pub steps: Vec<StepRow>,
    /// Per-channel held-out misfit over its noise floor (friction, drive) of the final model.
    pub channel_over_noise: (f64, f64),
    /// Residual signature terms (all channels, best first), when something was left.
    pub signature: Vec<crate::signature::Term>,
    /// Held-out gain of the whole sparse signature model.
    pub signature_gain: f64,
    /// The best signature term's evidence: (signal value bin centre, mean residual, held-out?) per bin.
    pub signature_curve: Vec<(f64, f64, bool)>,
    /// Number of folds of the cross-validation.
    pub folds: usize,
    pub heldout_misfit_baseline: f64,
    pub heldout_misfit_noise_floor: f64,
    /// Consistent order lines found (text), for `unexplained`.
    pub lines: Vec<String>,
    /// Normal-force scan: (frequency Hz, ΔRSS fraction) for the evidence figure.
    pub freq_scan: Vec<(f64, f64)>,
    /// Friction evidence: slip-speed bins (centre rad/s, mean μ_obs, baseline μ̂, extended μ̂).
    pub mu_vs_speed: Vec<MuBin>,
    /// Baseline μ residual against rotor angle mod 2π: (bin centre rad, mean
    /// over revolutions, lower and upper end of its 95 % interval, revolutions).
    pub residual_vs_angle: Vec<(f64, f64, f64, f64, usize)>,
    /// Baseline coefficients (μk, PI gains, supply).
    pub baseline_text: String,
    /// Thesis ladder: (rung, held-out misfit, cause).
    pub rungs: Vec<(String, f64, String)>,
    /// Checks of the other run kinds (static twist, voltage steps, torque
    /// balance) that enter the adequacy test.
    pub channel_checks: Vec<crate::ChannelCheck>,
    /// Free-run checks of the operating points with the baseline and with the
    /// final model (extended model with its selected structure); the final
    /// model's enter the adequacy test (`diagnose`).
    pub free_run_baseline: Vec<crate::ChannelCheck>,
    pub free_run_extended: Vec<crate::ChannelCheck>,
    /// Every structural candidate tried ([`crate::structure`]).
    pub structure_scores: Vec<StructureScore>,
    /// Rotor speed of every operating point over its steady window, measured
    /// and free-run simulated by both models (small-multiples figure and the
    /// diagnosis-speed-traces table).
    pub speed_traces: Vec<SpeedTraces>,
    /// One encoder tick over the motor-speed differentiator window, rad/s:
    /// the resolution of the motor-dip feature (0 when not computed).
    pub motor_speed_tick_rad_s: f64,
    /// The extended model's static level when a finding modulates the
    /// normal force ([`crate::breakaway`]); `None`: the baseline's stands.
    pub breakaway: Option<crate::breakaway::BreakAwayLevel>,
    /// The free-run second look at the effects teacher-forcing refused (`second_look` module).
    pub second_look: Vec<crate::second_look::SecondLookRow>,
    /// The extension's forward selection, one row per library signal tried
    /// per step (`effect` is the signal; `unexplained` with a baseline only).
    pub extension_steps: Vec<StepRow>,
    /// Rotor speed per operating point: measured, the final model's free run
    /// (`baseline_rad_s`) and the extension's held-out free run (`extended_rad_s`).
    pub extension_traces: Vec<SpeedTraces>,
    /// The free-run checks of the extended model (held-out free runs).
    pub extension_free_run: Vec<crate::ChannelCheck>,
}

/// One operating point's rotor speed over the steady window (about 20 Hz).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct SpeedTraces {
    pub id: String,
    pub time_s: Vec<f64>,
    pub measured_rad_s: Vec<f64>,
    /// `None` where that model's simulation failed.
    pub baseline_rad_s: Option<Vec<f64>>,
    pub extended_rad_s: Option<Vec<f64>>,
}

/// One effect tried in one forward-selection step.
#[derive(Debug, Clone, PartialEq)]
pub struct StepRow {
    pub step: usize,
    pub effect: String,
    /// Cross-validated misfit of the model before and with the effect.
    pub misfit_before: f64,
    pub misfit_after: f64,
    pub gain: f64,
    pub gain_fold_sd: f64,
    /// Paired run-level t of ln(M_before/M_after) (crate docs).
    pub t: f64,
    pub accepted: bool,
    /// Why the step's best effect was not accepted although significant: its
    /// fit contradicts the effect's definition (diagnosis.md's table).
    pub inadmissible: Option<String>,
}

impl<M> From<&rig_types::select::Trial<M>> for StepRow {
    /// One trial of the engine's trace as the report prints it (the
    /// vocabulary's selection and the extension's).
    fn from(t: &rig_types::select::Trial<M>) -> Self {
        StepRow {
            step: t.step,
            effect: t.id.clone(),
            misfit_before: t.comparison.before,
            misfit_after: t.comparison.after,
            gain: t.comparison.gain,
            gain_fold_sd: t.comparison.gain_fold_sd,
            t: t.comparison.t,
            accepted: t.accepted,
            inadmissible: t.inadmissible.clone(),
        }
    }
}

/// One slip-speed bin of the friction-vs-slip evidence: the sample means of
/// measured μ and of both models over the bin's slip samples, and the 95 %
/// half-width of the measured mean with the run as the independent unit.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct MuBin {
    pub speed_rad_s: f64,
    pub measured: f64,
    pub baseline: f64,
    pub extended: f64,
    /// NaN when fewer than two runs have 5 samples in the bin.
    pub measured_half_width_95: f64,
}
