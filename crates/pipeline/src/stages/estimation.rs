//! Stage `estimation`: least-squares identification (Table 4.4 → 4.5) on the
//! campaign's voltage steps, PI gains and baseline Coulomb friction from the
//! operating points (rig_estimate::estimate_rig), with its fit report.

use crate::StageCtx;
use anyhow::{Context, Result, bail};
use rig_calibrate::{CampaignCalibration, ThesisData};
use rig_estimate::{EstimateOptions, InitialValues, PiMethod, SolverKind, StepResidual, estimate_rig, output};

/// Options from `[stage.params]`; every knob is explicit there.
fn options(ctx: &StageCtx, thesis: &ThesisData) -> Result<EstimateOptions> {
    let mut o = EstimateOptions::new(InitialValues::from_thesis_data(thesis));
    o.solver_kind = match ctx.param_str("solver")?.as_str() {
        "lm" => SolverKind::LevenbergMarquardt,
        "gauss_newton_ls" => SolverKind::GaussNewtonLineSearch,
        other => bail!("pipeline.toml: stage {}: solver = {other:?} must be \"lm\" or \"gauss_newton_ls\"", ctx.name),
    };
    o.solver.max_iterations = ctx.param_usize("max_iterations")?;
    o.solver.ftol = ctx.param_f64("ftol")?;
    o.solver.xtol = ctx.param_f64("xtol")?;
    o.solver.gtol = ctx.param_f64("gtol")?;
    o.solver.fd_step = ctx.param_f64("fd_step")?;
    o.gear_ratio = ctx.param_f64("gear_ratio")?;
    o.speed_window_samples = ctx.param_usize("window_samples")?;
    o.step_residual = match ctx.param_str("residual")?.as_str() {
        "angle" => StepResidual::Angle,
        "speed" => StepResidual::Speed,
        other => bail!("pipeline.toml: stage {}: residual = {other:?} must be \"angle\" or \"speed\"", ctx.name),
    };
    o.free_inductance = match ctx.params.get("free_inductance") {
        Some(toml::Value::Boolean(b)) => *b,
        other => bail!("pipeline.toml: stage {}: free_inductance = {other:?} must be true or false", ctx.name),
    };
    let holdout = ctx.param_str("holdout")?;
    o.holdout = (!holdout.trim().is_empty()).then(|| holdout.split(',').map(|s| s.trim().to_string()).collect());
    o.whiteness_max_lag = ctx.param_usize("whiteness_max_lag")?;
    o.pi.method = match ctx.param_str("pi_method")?.as_str() {
        "corrected_ls" => PiMethod::CorrectedLs,
        "iv" => PiMethod::Iv,
        other => bail!("pipeline.toml: stage {}: pi_method = {other:?} must be \"corrected_ls\" or \"iv\"", ctx.name),
    };
    o.pi.window_samples = ctx.param_usize("pi_window_samples")?;
    o.pi.saturation_margin_v = ctx.param_f64("saturation_margin_v")?;
    o.friction.slip_threshold_rad_s = ctx.param_f64("slip_threshold_rad_s")?;
    o.friction.speed_half_window = ctx.param_usize("speed_half_window")?;
    o.friction.min_stick_s = ctx.param_f64("min_stick_s")?;
    Ok(o)
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let campaign = ctx.campaign()?.clone();
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let o = options(ctx, &thesis)?;
    let est = estimate_rig(&campaign, &cal, &o).with_context(|| format!("estimating campaign {}", campaign.name))?;

    ctx.write_json("data/rig-params.json", &est.params)?;
    ctx.write_table("tables/campaign-estimation.csv", &output::estimation_table(&est))?;
    ctx.write_table("tables/campaign-estimation-correlation.csv", &output::correlation_table(&est))?;
    ctx.write_table("tables/campaign-estimation-validation.csv", &output::validation_table(&est))?;
    ctx.write_table("tables/campaign-estimation-history.csv", &output::history_table(&est))?;
    ctx.write_text("estimation.md", &output::report_markdown(&est, &campaign.name, &o))?;
    if let Some(fig) = output::fig_4_11(&est) {
        ctx.write_figure(&fig)?;
    }
    ctx.write_figure(&output::fig_4_12(&est))?;
    Ok(())
}
