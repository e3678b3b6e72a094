//! Stage body (see pipeline.toml). Not written yet.

use crate::StageCtx;
use anyhow::{Result, bail};

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    bail!("stage {} is not implemented yet", ctx.name)
}
