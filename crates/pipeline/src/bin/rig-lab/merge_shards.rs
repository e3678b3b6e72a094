//! `rig-lab merge-shards` (`cargo xtask merge-shards`): joins the severity-map and battery slices of
//! a job array (see `rig_pipeline::shards`).

use anyhow::Result;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Where the merged outputs go (tables/sweep-map-<model>.csv; the confusion stage's tables, figure and confusion.md).
    #[arg(long)]
    out: PathBuf,
    /// The out dirs of the shard runs (`--set sweeps.shard=i/n` or `--set confusion.shard=i/n`, `--out DIR`).
    #[arg(required = true)]
    shard_dirs: Vec<PathBuf>,
}

pub fn run(args: Args) -> Result<()> {
    for path in rig_pipeline::shards::merge(&args.shard_dirs, &args.out)? {
        eprintln!("wrote {}", path.display());
    }
    Ok(())
}
