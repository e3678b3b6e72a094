//! The one error type of rig-ingest: every refusal names the file, the line
//! (when there is one) and the rule a person must fix.

use std::path::{Path, PathBuf};

/// Why a campaign (or another recording) was refused.
///
/// `Display` is always `<file>[:<line>]: <rule>`, e.g.
/// `data/c/runs/op-01.csv:1534: time_s must be strictly increasing (0.3040 after 0.3060)`.
/// CSV lines are 1-based with the header on line 1; campaign.toml lines are
/// those of the offending key (or table). The pipeline prints this text as is.
#[derive(Debug, thiserror::Error)]
pub enum IngestError {
    /// A file or folder could not be read at all (missing, permissions, not UTF-8 ...).
    #[error("{}: {rule}: {source}", file.display())]
    Io {
        file: PathBuf,
        rule: String,
        #[source]
        source: std::io::Error,
    },
    /// A rule of the format is broken: bad TOML, a missing or unknown key,
    /// a value out of its physical range, a malformed CSV row ...
    #[error("{}{}: {rule}", file.display(), line.map(|l| format!(":{l}")).unwrap_or_default())]
    Rule { file: PathBuf, line: Option<usize>, rule: String },
    /// polars refused a CSV that passed the line-level checks (should be rare:
    /// the checks before polars are meant to catch everything with a line number).
    #[error("{}: CSV could not be parsed: {message}", file.display())]
    Csv { file: PathBuf, message: String },
}

impl IngestError {
    /// A broken rule at `file`, optionally at a 1-based `line`.
    pub fn rule(file: impl AsRef<Path>, line: Option<usize>, rule: impl Into<String>) -> Self {
        IngestError::Rule { file: file.as_ref().to_path_buf(), line, rule: rule.into() }
    }

    /// The file a person must fix.
    pub fn file(&self) -> &Path {
        match self {
            IngestError::Io { file, .. } | IngestError::Rule { file, .. } | IngestError::Csv { file, .. } => file,
        }
    }

    /// The 1-based line of the offending row or key, when known.
    pub fn line(&self) -> Option<usize> {
        match self {
            IngestError::Rule { line, .. } => *line,
            _ => None,
        }
    }
}
