//! Stage `slider`: the ENS Lyon paper-on-paper spring–slider (Colas et al.
//! 2019; read from ../shared or any folder in its layout, never copied)
//! through rig_slider: measured features, the Coulomb baseline and the
//! candidate models (a friction law on a set-up) fitted on the calibration
//! stiffnesses and chosen by forward selection, held-out predictions,
//! `slider-diagnosis.json` (schema of ../shared/spec/diagnosis.md),
//! tables, figures and `slider.md`.
//!
//! `folder` may start with `{shared}` (the shared folder); another folder
//! in the same layout is given with `--set slider.folder=DIR`. The stage's
//! key covers the declared input's content and the `folder` string, not the
//! content of another folder.

use crate::StageCtx;
use anyhow::Result;
use rig_slider::{StudyParams, render, run_study};
use std::path::PathBuf;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let params: StudyParams = ctx.typed_params()?;
    let dir = match params.folder.strip_prefix("{shared}") {
        Some(rest) => match ctx.shared_dir.as_ref() {
            Some(shared) => shared.join(rest.trim_start_matches('/')),
            None => return Ok(()), // no ../shared: the runner reports the optional stage as skipped
        },
        None => PathBuf::from(&params.folder),
    };
    if params.folder.starts_with("{shared}") && !dir.exists() {
        return Ok(());
    }
    let study = run_study(&dir, &params)?;
    let out = render(&study);
    for (rel, table) in &out.tables {
        ctx.write_table(rel, table)?;
    }
    for f in &out.figures {
        ctx.write_figure(f)?;
    }
    ctx.write_json("slider-diagnosis.json", &out.diagnosis)?;
    ctx.write_text("slider.md", &out.markdown)?;
    Ok(())
}
