//! Stage `diagnosis`: blind diagnosis of the campaign (rig_diagnose): what
//! the rig model gets wrong, the cause, the extended model and its held-out
//! gain; diagnosis.json exactly as ../shared/spec/diagnosis.md, diagnosis.md,
//! tables/diagnosis-{runs,candidates,rungs}.csv and the evidence figures.

use crate::StageCtx;
use anyhow::{Context, Result};
use rig_calibrate::{CampaignCalibration, ThesisData};
use rig_diagnose::{DiagnoseOptions, diagnose, render};
use rig_types::RigParams;

/// `[stage.params]` of pipeline.toml → options (every knob is explicit there).
fn options(ctx: &StageCtx) -> Result<DiagnoseOptions> {
    Ok(DiagnoseOptions {
        heldout_every: ctx.param_usize("heldout_every")?,
        rotor_speed_half_window: ctx.param_usize("rotor_speed_half_window")?,
        motor_speed_half_window: ctx.param_usize("motor_speed_half_window")?,
        slip_speed_rad_s: ctx.param_f64("slip_speed_rad_s")?,
        skip_start_s: ctx.param_f64("skip_start_s")?,
        settle_s: ctx.param_f64("settle_s")?,
        bic_threshold: ctx.param_f64("bic_threshold")?,
        min_relative_gain: ctx.param_f64("min_relative_gain")?,
        freq_min_hz: ctx.param_f64("freq_min_hz")?,
        freq_max_hz: ctx.param_f64("freq_max_hz")?,
        freq_step_hz: ctx.param_f64("freq_step_hz")?,
        max_order: ctx.param_usize("max_order")? as u32,
        line_ratio: ctx.param_f64("line_ratio")?,
        free_run: true,
    })
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let opts = options(ctx)?;
    let campaign = ctx.campaign()?.clone();
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let d = diagnose(&campaign, &cal, Some(&rig), Some(thesis.friction.mu_dynamic), &opts)
        .with_context(|| format!("diagnosing campaign {}", campaign.name))?;
    ctx.write_json("diagnosis.json", &d)?;
    ctx.write_text("diagnosis.md", &render::markdown(&d))?;
    ctx.write_table("tables/diagnosis-runs.csv", &render::runs_table(&d))?;
    ctx.write_table("tables/diagnosis-candidates.csv", &render::candidates_table(&d))?;
    ctx.write_table("tables/diagnosis-rungs.csv", &render::rungs_table(&d))?;
    for f in render::figures(&d) {
        ctx.write_figure(&f)?;
    }
    Ok(())
}
