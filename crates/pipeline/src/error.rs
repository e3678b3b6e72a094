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
