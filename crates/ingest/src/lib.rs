//! Campaign folders (`rig-campaign/1`, ../shared/spec/recording-format.md) and
//! thesis tables to typed data, with polars; validates before it returns.

pub mod thesis;

use rig_types::Campaign;
use std::path::Path;

/// Reads and validates a whole campaign folder. Not written yet.
pub fn read_campaign(dir: &Path) -> Result<Campaign, IngestError> {
    let _ = dir;
    todo!("rig-ingest: read_campaign")
}

/// Why a campaign was refused: the file, the line (for CSV) and the rule.
#[derive(Debug, thiserror::Error)]
#[error("{file}{}: {rule}", line.map(|l| format!(":{l}")).unwrap_or_default())]
pub struct IngestError {
    pub file: std::path::PathBuf,
    pub line: Option<usize>,
    pub rule: String,
}
