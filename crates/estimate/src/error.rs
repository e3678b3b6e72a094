//! The one error enum of rig-estimate: every variant names what a person must fix.

use thiserror::Error;

/// Why an estimation could not produce a result at all. Non-convergence is
/// *not* an error: it is reported as data (`converged: false`) in the fit.
#[derive(Debug, Error)]
pub enum EstimateError {
    /// The campaign lacks runs a step needs (e.g. no `voltage_step` run).
    #[error("campaign {campaign}: {what} (rule: {rule})")]
    MissingRuns { campaign: String, what: String, rule: &'static str },
    /// A run lacks a column its kind must have (rig-ingest should have refused it).
    #[error("campaign run {run}: column {column} is missing (recording-format.md: columns of kind {kind})")]
    MissingColumn { run: String, column: &'static str, kind: &'static str },
    /// Too few usable samples for a regression or a fit.
    #[error("{context}: only {got} usable samples, need at least {need} ({rule})")]
    TooFewSamples { context: String, got: usize, need: usize, rule: &'static str },
    /// An option or an initial value is outside its domain.
    #[error("estimation option {name} = {value}: {rule}")]
    InvalidOption { name: String, value: f64, rule: &'static str },
    /// The model failed at the *initial* parameters (later trial points that
    /// fail are rejected steps, not errors).
    #[error("run {run}: rig-model failed at the initial parameters: {source}")]
    Model {
        run: String,
        #[source]
        source: rig_model::ModelError,
    },
    /// A problem's residual function failed at the initial parameters.
    #[error("residuals could not be evaluated at the initial parameters: {0}")]
    Residuals(String),
    /// A linear system was singular (e.g. a regressor that never varies).
    #[error("{context}: normal equations are singular ({rule})")]
    Singular { context: String, rule: &'static str },
    /// The argmin solver reported an error.
    #[error("argmin: {0}")]
    Argmin(String),
}

impl From<rig_types::linear::LinearError> for EstimateError {
    fn from(e: rig_types::linear::LinearError) -> Self {
        match e {
            rig_types::linear::LinearError::Singular { context, rule } => EstimateError::Singular { context, rule },
            rig_types::linear::LinearError::TooFewRows { context, got, need, rule } => {
                EstimateError::TooFewSamples { context, got, need, rule }
            }
        }
    }
}
