//! Stage `lavi`: the UFRJ LAVI 2018 recording (run 175, read from ../shared and
//! never copied) through rig_lavi: what the 1-DOF simulation gets wrong on
//! held-out windows, the cause, the extended model and its gain
//! (`lavi-diagnosis.json` in the schema of ../shared/spec/diagnosis.md), the
//! feature and candidate tables, figures and `lavi.md`.

use crate::StageCtx;
use anyhow::{Context, Result};
use rig_lavi::{StudyParams, run_study};

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let Some(dir) = ctx.shared_dir.as_ref().map(|d| d.join("data/ufrj-lavi-2018")) else {
        return Ok(()); // no ../shared: the runner reports the optional stage as skipped
    };
    let path = dir.join("run-175.csv");
    if !path.exists() {
        return Ok(());
    }
    let params: StudyParams = ctx.typed_params()?;
    let out = run_study(&path, &params).with_context(|| format!("reading {}", path.display()))?;
    for (rel, table) in &out.tables {
        ctx.write_table(rel, table)?;
    }
    for f in &out.figures {
        ctx.write_figure(f)?;
    }
    ctx.write_json("lavi-diagnosis.json", &out.diagnosis)?;
    ctx.write_text("lavi.md", &out.markdown)?;
    Ok(())
}
