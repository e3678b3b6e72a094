//! Stages from `pipeline.toml`, content hashes, an atomic artifact store and the
//! manifest. A library so it can be tested; its binary `rig-lab` (`src/bin/rig-lab`)
//! is the command line, which `cargo xtask` builds and runs.
//!
//! CONTRACT for stage authors (one module each in `stages/`): a stage is a
//! [`StageFn`] that reads its inputs through [`StageCtx`] and writes every
//! output through it. Writes are staged in memory and committed by the runner
//! (temporary file + rename) only when the stage succeeds, so a failed or
//! interrupted stage leaves no torn file.
//!
//! The runner ([`Runner`]) reads pipeline.toml ([`PipelineConfig`]), runs the
//! stages in dependency order (independent ones in parallel), skips a stage
//! whose key (blake3 of name, params, inputs and code — computed from the
//! stage's source, see [`code`]) and outputs are unchanged, and writes
//! `<out>/manifest.json`. `cargo xtask reproduce` also writes each stage's wall
//! and CPU time to `<out>/timings.json` ([`timing`]), outside the manifest.

mod accepted;
pub mod code;
mod config;
mod ctx;
mod error;
pub mod fingerprint;
#[cfg(test)]
mod fingerprint_tests;
pub mod graph;
mod hash;
mod manifest;
pub mod needs;
pub mod parquet;
mod runner;
pub mod stages;
mod store;
pub mod timing;

pub use config::{Input, OutputPattern, ParamsCheck, PipelineConfig, Registry, Settings, Sources, StageDecl};
pub use ctx::{StageCtx, StageFn, parse_params};
pub use error::{PipelineError, describe};
pub use runner::{CampaignReader, Outcome, RunReport, Runner, StageReport};
pub use store::{CacheRecord, FileHash};
pub mod shards;
/// `cargo xtask diff` (the `rig-lab` binary's one door is this crate): the comparison lives in rig-report.
pub use rig_report::diff;
pub mod testing;

/// The fingerprint of the sources this crate (and so the binary) was built from.
pub const BUILT_FROM: &str = env!("RIG_SOURCE_FINGERPRINT");

/// Refuses to run when the workspace sources under `root` are not the ones
/// this binary was built from ([`PipelineError::StaleBinary`]; module [`fingerprint`]).
pub fn check_built_from(root: &std::path::Path) -> Result<(), PipelineError> {
    let on_disk =
        fingerprint::fingerprint(root).map_err(|source| PipelineError::Io { path: root.to_path_buf(), source })?;
    if on_disk == BUILT_FROM {
        Ok(())
    } else {
        Err(PipelineError::StaleBinary { root: root.to_path_buf(), built: BUILT_FROM.to_string(), on_disk })
    }
}
