//! Stage `harmonic`: Eq. 4-11 as published and the normal-force alternative
//! for each ω_p of Table 4.8, both models (`rig_sweep::harmonic`): Figs.
//! 4.27-4.29, their line analysis and harmonic.md.

use crate::StageCtx;
use anyhow::Result;
use rig_calibrate::ThesisData;
use rig_sweep::harmonic::{self, HarmonicOptions};
use rig_types::RigParams;

/// `[stage.params]` of `harmonic`.
pub type Params = HarmonicOptions;

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    // The chapter publishes no PI gains: the rig's identified ones (estimation stage).
    let thesis_params = super::thesis_model(&thesis, rig.drive.clone());
    let omegas: Vec<f64> = thesis.peaks.iter().map(|pk| pk.omega_rad_s).collect();
    anyhow::ensure!(!omegas.is_empty(), "data/thesis.json: Table 4.8 peaks are missing");
    let cases = harmonic::study(&thesis_params, &rig, &omegas, &p)?;
    let (lines, summary) = harmonic::tables(&cases);
    ctx.write_table("tables/harmonic-lines.csv", &lines)?;
    ctx.write_table("tables/harmonic-summary.csv", &summary)?;
    for f in harmonic::figures(&cases, &omegas, &p) {
        ctx.write_figure(&f)?;
    }
    ctx.write_text("harmonic.md", &harmonic::markdown(&cases, &p))?;
    Ok(())
}
