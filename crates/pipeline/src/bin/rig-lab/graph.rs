//! `rig-lab graph [--dot]` (`cargo xtask graph`): the stage DAG of pipeline.toml.

use anyhow::Result;
use rig_pipeline::{Runner, graph};

#[derive(clap::Args)]
pub struct Args {
    /// Graphviz DOT instead of Mermaid.
    #[arg(long)]
    dot: bool,
}

pub fn run(args: Args) -> Result<()> {
    let runner = Runner::new(&super::workspace_root().join("pipeline.toml"))?;
    let text = if args.dot { graph::dot(runner.config()) } else { graph::mermaid(runner.config()) };
    print!("{text}");
    Ok(())
}
