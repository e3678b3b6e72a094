//! Stage `sweeps`: severity maps (Fig. 4.16) and bifurcation diagrams (Figs.
//! 4.18, 4.20) of the thesis model as published and of the rig model, swept
//! up and down by continuation, the campaign's operating points and the
//! chapter's labelled points classified by the same classifier, the agreement
//! table and the measured time responses of Figs. 4.19 and 4.21 — all of it
//! `rig_sweep::sweeps_study`, rendered by `rig_sweep::study::render`.

use crate::StageCtx;
use anyhow::{Context, Result};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rig_sweep::operating::LabelledPoint;
use rig_sweep::study::render;
use rig_sweep::{Point, Shard, map_shards, sweeps_study};
use rig_types::RigParams;
use rig_types::contract::ThesisData;
use std::io::IsTerminal;

/// `[stage.params]` of `sweeps` (meanings in pipeline.toml).
pub type Params = rig_sweep::SweepsParams;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let shard = p.shard().context("pipeline.toml: [stage.params] shard")?;
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    // The thesis model with the rig's PI gains, which the chapter does not publish.
    let data: ThesisData = ctx.read_json("data/thesis.json")?;
    let thesis = super::thesis_model(&data, rig.drive.clone());

    let bar = progress_bar(p.progress_total(shard) as u64);
    let tick = || bar.inc(1);
    if shard != Shard::WHOLE {
        // A partial map: only this shard's slices; rig_sweep::merge_slices joins them.
        for (name, slice) in map_shards(&thesis, &rig, &p, shard, &tick) {
            ctx.write_json(&format!("tables/sweep-map-{name}.shard-{}-of-{}.json", shard.index, shard.count), &slice)?;
        }
        bar.finish_and_clear();
        return Ok(());
    }
    // The chapter's labelled points, as the thesis-tables stage passes them on.
    let labels: Vec<LabelledPoint> = data
        .labelled_points
        .iter()
        .map(|l| LabelledPoint {
            id: format!("fig-{}{}", l.figure, l.panel),
            point: Point { motor_rpm: l.motor_rpm, normal_force_n: l.frict_n },
            label: l.label.clone(),
            source: l.source.clone(),
        })
        .collect();
    let campaign = ctx.campaign()?.clone();
    let study =
        sweeps_study(thesis, rig, &campaign, &labels, &p, &tick, &|name| bar.set_message(format!("{name} model")))?;
    bar.finish_and_clear();

    let out = render::outputs(&study, &campaign)?;
    for (path, table) in &out.tables {
        ctx.write_table(path, table)?;
    }
    for (path, table) in &out.large_tables {
        ctx.write_table_with_parquet(path, table)?;
    }
    for f in &out.figures {
        ctx.write_figure(f)?;
    }
    for s in &out.sheets {
        ctx.write_sheet(s)?;
    }
    ctx.write_text("sweeps.md", &out.markdown)?;
    Ok(())
}

fn progress_bar(total: u64) -> ProgressBar {
    let target =
        if std::io::stderr().is_terminal() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
    let bar = ProgressBar::with_draw_target(Some(total), target);
    if let Ok(style) = ProgressStyle::with_template("sweeps {msg} [{bar:30}] {pos}/{len} points, ETA {eta}") {
        bar.set_style(style);
    }
    bar
}
