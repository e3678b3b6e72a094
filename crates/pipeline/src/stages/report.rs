//! Stage `report`: the self-contained HTML page (reports/index.html) and
//! figures.md, built from what the other stages left in the out dir
//! (`rig_report`).

use crate::StageCtx;
use anyhow::Result;

/// `[stage.params]` of `report`: none.
#[derive(Debug, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let Params {} = ctx.typed_params()?;
    let report = rig_report::build(&ctx.out_dir, &ctx.campaign_dir)?;
    ctx.write_text("index.html", &report.index_html)?;
    ctx.write_text("figures.md", &report.figures_md)?;
    Ok(())
}
