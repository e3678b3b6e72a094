//! `rig-lab`: the pipeline's command line (`reproduce`, `graph`, `diff`,
//! `merge-shards`); parses flags and calls the library. One match, one module
//! per command. `cargo xtask ARGS` builds this binary with the workspace
//! (`cargo build --workspace --bins`) when its sources changed and runs it
//! with ARGS (`xtask/src/main.rs`); run directly it checks, before a
//! `reproduce`, that it was built from the sources on disk.

mod diff;
mod graph;
mod merge_shards;
mod reproduce;

use clap::{Parser, Subcommand};
use std::path::PathBuf;

#[derive(Parser)]
#[command(name = "cargo xtask", about = "rig-lab tasks: reproduce the reports, print the DAG, diff against a revision")]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Run the pipeline.toml DAG (only what changed) into the out dir.
    Reproduce(reproduce::Args),
    /// Print the stage DAG as Mermaid (default) or Graphviz DOT.
    Graph(graph::Args),
    /// Compare every table and figure series with a git revision.
    Diff(diff::Args),
    /// Join severity-map shards of a job array into the map tables.
    MergeShards(merge_shards::Args),
}

/// The workspace root (this crate is `crates/pipeline`): pipeline.toml lives
/// there, and the default paths are relative to it.
fn workspace_root() -> PathBuf {
    let manifest_dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR"));
    manifest_dir.ancestors().nth(2).unwrap_or(manifest_dir).to_path_buf()
}

fn main() -> std::process::ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        Command::Reproduce(args) => reproduce::run(args),
        Command::Graph(args) => graph::run(args),
        Command::Diff(args) => diff::run(args),
        Command::MergeShards(args) => merge_shards::run(args),
    };
    match result {
        Ok(()) => std::process::ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("error: {}", rig_pipeline::describe(&e));
            std::process::ExitCode::FAILURE
        }
    }
}
