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
    pub findings: Vec<Finding>,
    pub candidates: Vec<CandidateScore>,
    /// Detail for the report; not part of the JSON contract.
    #[serde(skip)]
    pub detail: Detail,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct Finding {
    pub effect: String,
    pub params: BTreeMap<String, f64>,
    pub params_stderr: BTreeMap<String, f64>,
    pub evidence: String,
    pub heldout_runs: Vec<String>,
    pub heldout_misfit_baseline: f64,
    pub heldout_misfit_extended: f64,
    pub relative_gain: f64,
}

#[derive(Debug, Clone, Serialize, PartialEq)]
pub struct CandidateScore {
    pub effect: String,
    pub heldout_misfit_extended: f64,
    /// BIC(candidate) − BIC(baseline) on the training runs.
    pub criterion: f64,
}

/// Per-run comparison row (tables/diagnosis-runs.csv).
#[derive(Debug, Clone, PartialEq, Default)]
pub struct RunRow {
    pub id: String,
    pub heldout: bool,
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
}

/// Features of one run's steady state (measured or simulated).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Features {
    /// Fraction of the steady state with rotor 1 stuck (|Ω1| < slip threshold).
    pub stuck_fraction: f64,
    pub rotor_min_rad_s: f64,
    pub rotor_max_rad_s: f64,
    /// Largest spectral peak of Ω1 above 0.05 Hz, Hz (0 when no oscillation).
    pub fundamental_hz: f64,
    /// Deepest dip of the motor speed below the set-point, rad/s.
    pub motor_dip_rad_s: f64,
}

impl Features {
    pub fn stick_slip(&self) -> bool {
        self.stuck_fraction > 0.02 && self.rotor_max_rad_s > 0.0
    }
}

/// Everything else the report shows.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Detail {
    pub runs: Vec<RunRow>,
    /// (candidate id, ΔBIC, held-out misfit, relative gain, significant, parameter text).
    pub scores: Vec<(String, f64, f64, f64, bool, String)>,
    pub heldout_misfit_baseline: f64,
    pub heldout_misfit_noise_floor: f64,
    /// Consistent order lines found (text), for `unexplained`.
    pub lines: Vec<String>,
    /// Normal-force scan: (frequency Hz, ΔRSS fraction) for the evidence figure.
    pub freq_scan: Vec<(f64, f64)>,
    /// Friction evidence: slip-speed bins (centre rad/s, mean μ_obs, baseline μ̂, extended μ̂).
    pub mu_vs_speed: Vec<(f64, f64, f64, f64)>,
    /// Baseline μ residual against rotor angle mod 2π (bin centre rad, mean residual).
    pub residual_vs_angle: Vec<(f64, f64)>,
    /// Baseline coefficients (μk, PI gains, supply).
    pub baseline_text: String,
    /// Thesis ladder: (rung, held-out misfit, cause).
    pub rungs: Vec<(String, f64, String)>,
}
