//! Stage `spectra`: spectra, peaks and line analysis of every operating point
//! (measured and simulated), Table 4.8's lines, Figs. 4.22-4.26
//! (`rig_sweep::spectra`).

use crate::StageCtx;
use anyhow::Result;
use rig_calibrate::CampaignCalibration;
use rig_sweep::spectra::{self, SpectraOptions};
use rig_types::RigParams;

/// `[stage.params]` of `spectra`.
pub type Params = SpectraOptions;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    let campaign = ctx.campaign()?.clone();
    let study = spectra::study(&campaign, &cal, &rig, &p)?;
    for (rel, table) in spectra::render::tables(&study, &p) {
        ctx.write_table(rel, &table)?;
    }
    let (figures, sheets) = spectra::render::figures(&study, &p)?;
    for f in &figures {
        ctx.write_figure(f)?;
    }
    for s in &sheets {
        ctx.write_sheet(s)?;
    }
    Ok(())
}
