//! The one error type of the runner: what is wrong in pipeline.toml, on disk,
//! or in what a stage tried to write. Stage bodies themselves fail with anyhow.

use std::path::PathBuf;

#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    /// pipeline.toml breaks a rule (unknown stage, cycle, undeclared `@stage/rel`, ...).
    #[error("{}{}: {reason}", path.display(), stage.as_ref().map(|s| format!(": stage {s}")).unwrap_or_default())]
    Config { path: PathBuf, stage: Option<String>, reason: String },

    /// Reading or writing a file failed.
    #[error("{}: {source}", path.display())]
    Io {
        path: PathBuf,
        #[source]
        source: std::io::Error,
    },

    /// A stage staged a file that its `outputs` in pipeline.toml do not declare.
    #[error("stage {stage}: wrote {rel}, which is not declared in its outputs in pipeline.toml")]
    UndeclaredOutput { stage: String, rel: String },

    /// A non-optional stage's input does not exist.
    #[error("stage {stage}: input {label} ({}) does not exist; fix the path or mark the stage optional in pipeline.toml", path.display())]
    MissingInput { stage: String, label: String, path: PathBuf },

    /// `--only` named a stage that pipeline.toml does not declare.
    #[error("no stage named {0} in pipeline.toml")]
    UnknownStage(String),

    /// The campaign breaks a rule of the recording format (refused before any stage runs).
    #[error("campaign refused: {0}")]
    Campaign(#[from] rig_ingest::IngestError),

    /// The campaign the reader accepted lacks runs a stage of this run needs
    /// (refused before any stage runs): each clause names the run kind, what
    /// the campaign has, and each stage that needs more and what for.
    #[error("campaign refused: {}: {}", path.display(), unmet.join("; "))]
    CampaignUnfit { path: PathBuf, unmet: Vec<String> },

    /// The running binary was built from other sources than are on disk (see
    /// [`crate::fingerprint`]): its results would be stored under the new code's keys.
    #[error(
        "this binary was built from other sources than are in {} now (fingerprint {built}, on disk {on_disk}): \
         a source changed after the build. Run `cargo xtask reproduce`, which rebuilds first; a stale binary \
         would store its old results under the new code's cache keys",
        root.display()
    )]
    StaleBinary { root: PathBuf, built: String, on_disk: String },

    /// A cache record or the manifest could not be (de)serialised.
    #[error("{}: {reason}", path.display())]
    Json { path: PathBuf, reason: String },
}

/// An error and its causes as one line, each clause said once: `a: b: c`
/// like anyhow's `{:#}`, but a cause whose text the line already holds (an
/// error type that prints its source and also returns it from `source()`,
/// like [`PipelineError::Campaign`] or `Io`) is not said again. The one way
/// `xtask` and [`crate::RunReport::into_result`] print an error.
pub fn describe(e: &anyhow::Error) -> String {
    let mut line = String::new();
    for cause in e.chain() {
        let clause = cause.to_string();
        if line.contains(&clause) {
            continue;
        }
        if clause.starts_with(&line) {
            // A cause that restates the line and adds to it: the longer text, once.
            line = clause;
            continue;
        }
        line.push_str(": ");
        line.push_str(&clause);
    }
    line
}
