//! `rig-lab diff --baseline REV` (`cargo xtask diff`): calls `rig_pipeline::diff::run`.

use anyhow::Result;

#[derive(clap::Args)]
pub struct Args {
    /// The git revision to compare against (e.g. HEAD~1, main).
    #[arg(long)]
    baseline: String,
    /// The out dir to compare, relative to the workspace root.
    #[arg(long, default_value = "reports")]
    out: String,
}

pub fn run(args: Args) -> Result<()> {
    let report = rig_pipeline::diff::run(&super::workspace_root(), &args.baseline, &args.out)?;
    print!("{report}");
    Ok(())
}
