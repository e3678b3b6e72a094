//! Severity maps and bifurcation diagrams over the rig model, up and down, rayon, deterministic order.
//!
//! Front door:
//! - [`classify`] one rotor-speed window → severity (both conventions) and
//!   regime (equilibrium, period-k with or without stick, quasi-periodic,
//!   chaotic), the same function for simulations and recordings;
//! - [`run_chain`] / [`run_chains`] continuation chains (each point from the
//!   previous point's end state), [`bifurcation_chains`] up and down;
//! - [`MapSpec`], [`run_map_shard`], [`merge_slices`], [`Shard`]: severity
//!   maps sharded by chain index and merged back, byte-identical to one run;
//! - [`map_table`], [`chain_table`]: the CSV tables;
//! - [`harmonic`]: Eq. 4-11 and the normal-force modulation (Figs. 4.27-4.29);
//! - [`sweeps_study`] the `sweeps` stage's study (both models' maps and
//!   diagrams, the campaign's operating points and the chapter's labelled
//!   points through [`operating`]), rendered by [`output::outputs`].
//! - [`spectra`]: the campaign's operating points against the rig model in the
//!   frequency domain, and Table 4.8 (Figs. 4.22-4.26).
//!
//! Determinism: chains are independent and run in parallel, and `collect`
//! keeps chain order; nothing reads a clock or a random source.

mod classify;
mod continuation;
pub mod harmonic;
pub mod misfit;
pub mod operating;
pub mod output;
pub mod spectra;
mod study;
mod tables;

pub use classify::{Classification, ClassifyOptions, Regime, classify};
pub use continuation::{
    Chain, ChainResult, Direction, MapSlice, MapSpec, Point, PointOutcome, Shard, SweepSettings, WindowSpec,
    bifurcation_chains, hysteresis, linspace, merge_slices, run_chain, run_chains, run_map_shard,
};
pub use study::{ModelSweeps, SweepsParams, SweepsStudy, map_shards, sweeps_study};
pub use tables::{chain_table, map_table};

/// Errors of this crate; simulation failures at a point are data
/// ([`PointOutcome::result`]), not errors.
#[derive(Debug, thiserror::Error, PartialEq)]
pub enum SweepError {
    /// A `--shard` / `shard = "i/n"` value (pipeline.toml, stage `sweeps`) that cannot be used.
    #[error("shard `{text}`: {rule}")]
    BadShard { text: String, rule: &'static str },
    /// Map slices that do not join into one map.
    #[error("cannot merge map slices: {rule}")]
    Merge { rule: &'static str },
    /// A simulation or spectrum of a study failed (what, and why).
    #[error("{0}")]
    Analysis(String),
}
