//! Stage `confusion`: the virtual rig's battery of hidden-effect campaigns
//! (null draws, every vocabulary effect, compounds, effects outside the
//! vocabulary; rig_virtual_rig::battery), each diagnosed blind by
//! rig_diagnose::diagnose_campaign with the diagnosis stage's options as run:
//! confusion matrix, false-alarm rate on nulls, detection by effect size,
//! the wrong answers and confusion.md.

use crate::StageCtx;
use anyhow::{Result, bail};
use rig_calibrate::ThesisData;
use rig_diagnose::{DiagnoseOptions, diagnose_campaign};
use rig_virtual_rig::battery::{
    Battery, DiagnosisResult, confusion_table, detection_sheet, detection_table, false_alarm_table, report_markdown,
    wrong_table,
};

/// `[stage.params]` of the confusion stage.
#[derive(Debug, Clone, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ConfusionParams {
    /// `ci` (13 campaigns, small protocol) or `full` (the whole battery, full protocol).
    pub battery: String,
    /// First case seed.
    pub seed: u64,
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: ConfusionParams = ctx.typed_params()?;
    let battery = match p.battery.as_str() {
        "ci" => Battery::ci_seeded(p.seed),
        "full" => Battery::full_seeded(p.seed),
        other => bail!("pipeline.toml: stage confusion: battery = {other:?} must be \"ci\" or \"full\""),
    };
    // The diagnosis stage's options as it ran them (pipeline.toml is their one
    // home); the thesis values start the blind estimate of each baseline.
    let opts: DiagnoseOptions = ctx.read_json("data/diagnose-options.json")?;
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let out = battery.run(|_, c| {
        let d = diagnose_campaign(c, Some(&thesis), &opts).map_err(|e| e.to_string())?;
        serde_json::to_value(&d).and_then(serde_json::from_value::<DiagnosisResult>).map_err(|e| e.to_string())
    });
    ctx.write_table("tables/confusion-matrix.csv", &confusion_table(&out))?;
    ctx.write_table("tables/confusion-false-alarms.csv", &false_alarm_table(&out))?;
    let detection = detection_table(&out);
    ctx.write_table("tables/confusion-detection.csv", &detection)?;
    if let Some(sheet) = detection_sheet(&detection, battery.name) {
        ctx.write_sheet(&sheet)?;
    }
    ctx.write_table("tables/confusion-wrong.csv", &wrong_table(&out))?;
    ctx.write_text("confusion.md", &report_markdown(&battery, &out))?;
    Ok(())
}
