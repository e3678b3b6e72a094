//! Stage `estimation`: least-squares identification (Table 4.4 → 4.5) on the
//! campaign's voltage steps, PI gains and baseline Coulomb friction from the
//! operating points (rig_estimate::estimate_rig), with its fit report.

use crate::StageCtx;
use anyhow::{Context, Result};
use rig_calibrate::{CampaignCalibration, ThesisData};
use rig_estimate::{InitialValues, estimate_rig, render};

/// `[stage.params]` of `estimation`: `rig_estimate::EstimateParams`, every
/// knob explicit, mapped onto the estimator's options by the one mapping the
/// diagnosis' blind chain uses too (`EstimateParams::options`).
pub type Params = rig_estimate::EstimateParams;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let campaign = ctx.campaign()?.clone();
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let o = p.options(InitialValues::from_thesis_data(&thesis));
    let est = estimate_rig(&campaign, &cal, &o).with_context(|| format!("estimating campaign {}", campaign.name))?;

    ctx.write_json("data/rig-params.json", &est.params)?;
    ctx.write_table("tables/campaign-estimation.csv", &render::estimation_table(&est))?;
    ctx.write_table("tables/campaign-estimation-correlation.csv", &render::correlation_table(&est))?;
    ctx.write_table("tables/campaign-estimation-validation.csv", &render::validation_table(&est))?;
    ctx.write_table("tables/campaign-estimation-history.csv", &render::history_table(&est))?;
    ctx.write_text("estimation.md", &render::report_markdown(&est, &campaign.name, &o))?;
    if let Some(fig) = render::fig_4_11(&est) {
        ctx.write_figure(&fig)?;
    }
    ctx.write_figure(&render::fig_4_12(&est))?;
    Ok(())
}
