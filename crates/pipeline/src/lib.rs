//! Stages from `pipeline.toml`, content hashes, an atomic artifact store and the
//! manifest. A library so it can be tested; `xtask` is a thin front door.
//!
//! CONTRACT for stage authors (one module each in `stages/`): a stage is a
//! [`StageFn`] that reads its inputs through [`StageCtx`] and writes every
//! output through it. Writes are staged in memory and committed by the runner
//! (temporary file + rename) only when the stage succeeds, so a failed or
//! interrupted stage leaves no torn file.

mod ctx;
pub mod stages;

pub use ctx::{StageCtx, StageFn};
pub mod diff;
pub mod testing;
