//! Stage `simulation`: the thesis model as published and the rig model on
//! every operating point of the campaign at the recording's sample times —
//! the misfit table, the friction laws (Fig. 4.15), the limit cycles (Fig.
//! 4.17) and one overlay per run, all `rig_sweep::misfit` (definitions of the
//! table's columns in its docs).

use crate::StageCtx;
use anyhow::Result;
use rig_model::SimOptions;
use rig_sweep::ClassifyOptions;
use rig_sweep::misfit::misfit_study;
use rig_types::RigParams;
use rig_types::contract::{CampaignCalibration, ThesisData};
use rig_types::sensor::ForceCal;
use serde::Deserialize;

/// `[stage.params]` of `simulation`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// pipeline.toml's `[shared.integrator]`.
    pub integrator: SimOptions,
    /// pipeline.toml's `[shared.classify]`: stick-slip is the classifier's verdict.
    pub classify: ClassifyOptions,
    /// Fig. 4.17 shows the last this many seconds of each run.
    pub limit_cycle_s: f64,
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    // The chapter publishes no PI gains: the thesis model gets the rig's identified drive.
    let data: ThesisData = ctx.read_json("data/thesis.json")?;
    let thesis = super::thesis_model(&data, rig.drive.clone());
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let force = ForceCal { factor_mv_per_n: cal.force_factor_mv_per_n, offset_mv: cal.force_offset_mv };
    let campaign = ctx.campaign()?.clone();
    let out = misfit_study(&campaign, &thesis, &rig, force, &p.integrator, &p.classify, p.limit_cycle_s)?;
    ctx.write_table("tables/campaign-simulation-misfit.csv", &out.table)?;
    for f in &out.figures {
        ctx.write_figure(f)?;
    }
    Ok(())
}
