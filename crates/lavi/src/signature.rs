//! Residual signature (stub).
use crate::LaviError;
use crate::score::Evaluator;
use crate::sim::Model;
use serde::Serialize;

#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct SignatureTerm {
    pub signal: String,
    pub heldout_gain: f64,
    pub description: String,
}

pub fn residual_signature(_ev: &Evaluator, _m: &Model) -> Result<Vec<SignatureTerm>, LaviError> {
    Ok(Vec::new())
}
