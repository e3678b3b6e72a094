//! Rendering (stub).
use crate::LaviError;
use crate::data::Prepared;
use crate::study::Study;
use rig_ingest::lavi::LaviRecording;

#[derive(Debug, Default)]
pub struct StudyOutput {}

pub fn render(_s: &Study, _d: &Prepared, _r: &LaviRecording) -> Result<StudyOutput, LaviError> {
    Ok(StudyOutput {})
}
