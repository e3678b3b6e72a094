//! Stage `diagnosis`: blind diagnosis of the campaign (rig_diagnose): what
//! the rig model gets wrong, the cause, the extended model and its held-out
//! gain; diagnosis.json exactly as ../shared/spec/diagnosis.md, diagnosis.md,
//! tables/diagnosis-{runs,candidates,rungs,checks,speed-traces}.csv (runs and
//! speed traces with Parquet twins), the evidence figures and the
//! small-multiples sheet of every operating point's rotor speed.

use crate::StageCtx;
use anyhow::{Context, Result};
use rig_calibrate::{CampaignCalibration, ThesisData};
use rig_diagnose::{DiagnoseOptions, diagnose, render};
use rig_types::RigParams;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let opts: DiagnoseOptions = ctx.typed_params()?;
    let campaign = ctx.campaign()?.clone();
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let d = diagnose(&campaign, &cal, Some(&rig), Some(thesis.friction.mu_dynamic), &opts)
        .with_context(|| format!("diagnosing campaign {}", campaign.name))?;
    ctx.write_json("diagnosis.json", &d)?;
    ctx.write_text("diagnosis.md", &render::markdown(&d))?;
    ctx.write_table_with_parquet("tables/diagnosis-runs.csv", &render::runs_table(&d))?;
    ctx.write_table_with_parquet("tables/diagnosis-speed-traces.csv", &render::speed_traces_table(&d))?;
    ctx.write_table("tables/diagnosis-candidates.csv", &render::candidates_table(&d))?;
    ctx.write_table("tables/diagnosis-rungs.csv", &render::rungs_table(&d))?;
    ctx.write_table("tables/diagnosis-checks.csv", &render::checks_table(&d))?;
    for f in render::figures(&d) {
        ctx.write_figure(&f)?;
    }
    if let Some(sheet) = render::speed_sheet(&d) {
        ctx.write_sheet(&sheet)?;
    }
    Ok(())
}
