//! `rig-lab reproduce` (`cargo xtask reproduce`): runs the DAG through `rig_pipeline::Runner`.

use anyhow::{Context, Result};
use rig_pipeline::Runner;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct Args {
    /// Campaign folder (rig-campaign/1 format); default: settings.campaign of pipeline.toml.
    #[arg(long)]
    campaign: Option<PathBuf>,
    /// Out dir; default: settings.out of pipeline.toml (reports/).
    #[arg(long)]
    out: Option<PathBuf>,
    /// Stages run at once, and the size of the thread pool inside stages.
    #[arg(long, default_value_t = 2)]
    jobs: usize,
    /// Start ready stages in declaration order instead of the longest
    /// remaining path first (pipeline.toml `cpu_s`): to measure the schedule.
    #[arg(long)]
    declaration_order: bool,
    /// List what would run and why; run nothing.
    #[arg(long)]
    dry_run: bool,
    /// Print for each stage why it runs or is skipped.
    #[arg(long)]
    why: bool,
    /// Run only this stage and what it depends on (repeatable); an on-demand
    /// stage (pipeline.toml `on_demand = true`, e.g. the confusion battery) runs when named here.
    #[arg(long)]
    only: Vec<String>,
    /// Also run the on-demand stages (the confusion battery, ~70 s).
    #[arg(long)]
    all: bool,
    /// Override a stage param for this run, `STAGE.KEY=VALUE` (repeatable), e.g.
    /// `--set sweeps.shard=2/4` for job 2 of a 4-job array (then `cargo xtask merge-shards`).
    #[arg(long = "set", value_name = "STAGE.KEY=VALUE")]
    set: Vec<String>,
}

pub fn run(args: Args) -> Result<()> {
    rig_pipeline::check_built_from(&super::workspace_root())?;
    let toml = super::workspace_root().join("pipeline.toml");
    let only: Vec<&str> = args.only.iter().map(String::as_str).collect();
    let mut runner = Runner::new(&toml)?.jobs(args.jobs).dry_run(args.dry_run).only(&only).all(args.all).progress(true);
    runner = runner.declaration_order(args.declaration_order);
    for item in &args.set {
        let (lhs, value) = item.split_once('=').with_context(|| format!("--set {item}: expected STAGE.KEY=VALUE"))?;
        let (stage, key) = lhs.split_once('.').with_context(|| format!("--set {item}: expected STAGE.KEY=VALUE"))?;
        runner = runner.set_param(stage, key, value)?;
    }
    if let Some(c) = &args.campaign {
        runner = runner.campaign(c);
    }
    if let Some(o) = &args.out {
        runner = runner.out(o);
    }
    let out_dir = runner.out_dir();
    let report = runner.run()?;
    eprint!("{}", report.summary(args.why || args.dry_run));
    if let Some(m) = &report.manifest {
        eprintln!("manifest: {}", m.display());
        // Wall and CPU time per stage: not reproducible, so beside the manifest, not in it.
        let t = rig_pipeline::timing::write(&out_dir, &report, args.jobs)?;
        eprint!("{}", rig_pipeline::timing::table(&report));
        eprintln!("timings: {}", t.display());
    }
    report.into_result().map(|_| ())
}
