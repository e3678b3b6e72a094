//! Stage `thesis-tables`: recomputes Eqs. 4-1, 4-4, 4-5 and Tables 4.2, 4.3,
//! 4.6 from the published inputs, audits every published number, and writes
//! the thesis' parameters for downstream stages (`data/thesis.json`).

use crate::StageCtx;
use anyhow::Result;
use rig_calibrate::{audit, render, thesis};
use serde::Deserialize;

/// `[stage.params]` of `thesis-tables`.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    /// A published value within this many units of its last printed digit is `rounding`.
    pub rounding_tolerance: f64,
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let tolerance = ctx.typed_params::<Params>()?.rounding_tolerance;
    let tables = rig_ingest::thesis::read_thesis_tables(&ctx.thesis_dir)?;
    let o = thesis::thesis_outputs(&tables, tolerance)?;

    ctx.write_table("tables/thesis-eq-4-1.csv", &o.eq_4_1)?;
    ctx.write_table("tables/thesis-table-4-2.csv", &o.table_4_2)?;
    ctx.write_table("tables/thesis-eq-4-4-4-5.csv", &o.eq_4_4_4_5)?;
    ctx.write_table("tables/thesis-table-4-3.csv", &o.table_4_3)?;
    ctx.write_table("tables/thesis-table-4-6.csv", &o.table_4_6)?;
    ctx.write_table("audit.csv", &audit::audit_table(&o.audit_rows))?;
    ctx.write_text("audit.md", &audit::audit_markdown(&o.audit_rows, tolerance))?;
    ctx.write_json("data/thesis.json", &o.data)?;

    let (ko, kw) = &o.stiffness_fits;
    ctx.write_figure(&render::fit_figure(
        "fig-4-10-thesis",
        "Fig. 4.10 (thesis data): torque vs angular displacement of rotor 1",
        &format!(
            "The five static trials of Table 4.3 (torque vs angle as printed) with least-squares lines through the origin \
             (K = {:.4} N·m/rad, 95 % CI {:.4} to {:.4}) and with an offset (K = {:.4}, offset {:.4} N·m). \
             Eq. 4-1 gives K_sA = 0.268 N·m/rad; Table 4.3's mean of the printed ratios is 0.258.",
            ko.slope, ko.slope_ci[0], ko.slope_ci[1], kw.slope, kw.intercept
        ),
        ("angle [rad]", "torque [N·m]"),
        &thesis::table_4_3_points(&tables),
        (ko, kw),
        "K",
        (3, 4),
    ))?;
    let (fo, fw) = &o.force_fits;
    ctx.write_figure(&render::fit_figure(
        "fig-4-14-thesis",
        "Fig. 4.14 (thesis data): force-sensor voltage vs weight",
        &format!(
            "The four calibration trials of Table 4.6 with least-squares lines through the origin \
             (factor {:.3} mV/N, 95 % CI {:.3} to {:.3}) and with an offset (factor {:.3} mV/N, offset {:.3} mV). \
             The chapter uses the mean of the per-trial ratios, 214.114 mV/N.",
            fo.slope, fo.slope_ci[0], fo.slope_ci[1], fw.slope, fw.intercept
        ),
        ("weight [N]", "voltage [mV]"),
        &thesis::table_4_6_points(&tables),
        (fo, fw),
        "factor",
        (3, 1),
    ))?;
    Ok(())
}
