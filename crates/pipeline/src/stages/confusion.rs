//! Stage `confusion`: the virtual rig's battery of hidden-effect campaigns
//! (null draws, stick-slipping nulls, every vocabulary effect, compounds,
//! effects outside the vocabulary, structural faults; rig_virtual_rig::battery),
//! each diagnosed blind by rig_diagnose::diagnose_campaign, the blind chain
//! (calibrate → estimate → diagnose) with the options of the DAG's
//! `campaign-calibration`, `estimation` and `diagnosis` stages (pipeline.toml's
//! `params_of`), the campaigns in parallel: confusion matrix,
//! false-alarm rates on nulls, detection by effect size, the wrong answers
//! and confusion.md. With `shard = "i/n"` only shard i's cases run and their
//! diagnoses are written as a JSON slice for `cargo xtask merge-shards`.

use crate::StageCtx;
use anyhow::{Context, Result, anyhow};
use rig_calibrate::ThesisData;
use rig_diagnose::{BlindChain, diagnose_campaign};
use rig_sweep::Shard;
use rig_virtual_rig::battery::{Battery, DiagnosisResult};

/// `[stage.params]` of the confusion stage.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfusionParams {
    /// `smoke` (4 cases, for the shard tests), `ci` (small protocol) or `full` (full protocol).
    pub battery: String,
    /// First case seed.
    pub seed: u64,
    /// `"i/n"`: only shard i of n (interleaved: case k in shard k mod n + 1), written as a slice to merge.
    pub shard: String,
    /// The params of the DAG's stages the blind chain runs (`params_of`).
    #[serde(rename = "campaign-calibration")]
    pub calibration: rig_calibrate::CalibrationSettings,
    pub estimation: rig_estimate::EstimateParams,
    pub diagnosis: rig_diagnose::DiagnoseOptions,
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: ConfusionParams = ctx.typed_params()?;
    let battery = Battery::named(&p.battery, p.seed).ok_or_else(|| {
        anyhow!("pipeline.toml: stage confusion: battery = {:?} must be \"smoke\", \"ci\" or \"full\"", p.battery)
    })?;
    let shard = Shard::parse(&p.shard).context("pipeline.toml: stage confusion: [stage.params] shard")?;
    // The chain the DAG runs, with its stages' params (pipeline.toml is their
    // one home); the thesis values start the blind estimate of each baseline.
    let chain = BlindChain { calibration: p.calibration, estimation: p.estimation, diagnosis: p.diagnosis };
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let diagnose = |_: &_, c: &_| {
        let d = diagnose_campaign(c, Some(&thesis), &chain).map_err(|e| e.to_string())?;
        serde_json::to_value(&d).and_then(serde_json::from_value::<DiagnosisResult>).map_err(|e| e.to_string())
    };
    if shard != Shard::WHOLE {
        let slice = battery.run_slice(shard.index, shard.count, diagnose);
        return ctx
            .write_json(&format!("tables/confusion-slice.shard-{}-of-{}.json", shard.index, shard.count), &slice);
    }
    let out = battery.run(diagnose);
    crate::shards::write_battery(ctx, &battery, &out)
}
