//! Force-sensor factor, static stiffness, log decrement, inertia (thesis
//! §4.3–4.4) for the published tables and for a recorded campaign; the audit
//! of the chapter's published numbers. Pure functions, no IO.

pub mod audit;
pub mod campaign;
pub mod formulas;
pub mod published;
pub mod render;
pub mod signal;
pub mod stats;
pub mod thesis;

pub use audit::{AuditRow, Status};
pub use campaign::{
    CalibrationSettings, CampaignCalibration, ForceRun, StepDecay, TwistRun, calibrate_campaign,
    calibrate_campaign_with, friction_torque_nm,
};
pub use published::ThesisTables;
pub use signal::{DecayAnalysis, DecayPair, DecaySettings};
pub use stats::LineFit;
pub use thesis::{ThesisData, ThesisOutputs, thesis_data, thesis_outputs};

/// Why a calibration could not be computed. Each variant names what a person
/// must fix: the run (by id), the column, or the table row.
#[derive(Debug, thiserror::Error)]
pub enum CalibrateError {
    /// A campaign lacks enough runs of a kind (add runs of that kind to campaign.toml).
    #[error("campaign: need at least {need} `{kind}` runs, found {got}")]
    MissingRuns { kind: String, need: usize, got: usize },
    /// A run lacks a column its calibration needs (the reader should have refused it).
    #[error("run {run}: column `{column}` is missing")]
    MissingColumn { run: String, column: String },
    /// A fit got fewer points than it needs.
    #[error("{what}: need at least {need} points, got {got}")]
    TooFewPoints { what: String, need: usize, got: usize },
    /// A recording shows no measurable free decay (data, not a bug: the run is named).
    #[error("{what}: no free decay measurable: {reason}")]
    NoDecay { what: String, reason: String },
    /// A numeric input is outside the domain of the formula (message names it).
    #[error("{0}")]
    Domain(String),
    /// A published table is missing a row or column the audit needs (file and row named).
    #[error("thesis table {table}: {reason}")]
    Published { table: String, reason: String },
}
