//! Stage `estimation`: least-squares identification (Table 4.4 → 4.5) on the
//! campaign's voltage steps, PI gains and baseline Coulomb friction from the
//! operating points (rig_estimate::estimate_rig), with its fit report.

use crate::StageCtx;
use anyhow::{Context, Result};
use rig_calibrate::{CampaignCalibration, ThesisData};
use rig_estimate::{EstimateOptions, InitialValues, PiMethod, SolverKind, StepResidual, estimate_rig, render};
use serde::Deserialize;

/// `[stage.params]` of `estimation`; every knob is explicit there.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    pub solver: Solver,
    pub max_iterations: usize,
    pub ftol: f64,
    pub xtol: f64,
    pub gtol: f64,
    pub fd_step: f64,
    pub gear_ratio: f64,
    pub window_s: f64,
    pub residual: Residual,
    pub free_inductance: bool,
    /// Comma-separated voltage-step ids; empty: the estimator's own split.
    pub holdout: String,
    pub whiteness_max_lag: usize,
    pub pi_method: Pi,
    pub pi_window_s: f64,
    pub saturation_margin_v: f64,
    /// pipeline.toml's `[shared.stick_episodes]`.
    pub stick_episodes: rig_estimate::FrictionOptions,
    /// pipeline.toml's `[shared.integrator]`.
    pub integrator: rig_model::SimOptions,
}

/// `solver = "lm" | "gauss_newton_ls"`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Solver {
    Lm,
    GaussNewtonLs,
}

/// `residual = "speed" | "angle"`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Residual {
    Speed,
    Angle,
}

/// `pi_method = "corrected_ls" | "iv"`.
#[derive(Debug, Clone, Copy, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Pi {
    CorrectedLs,
    Iv,
}

/// The estimator's options from the stage's params, started from `initial`.
fn options(p: &Params, initial: InitialValues) -> EstimateOptions {
    let mut o = EstimateOptions::new(initial);
    o.solver_kind = match p.solver {
        Solver::Lm => SolverKind::LevenbergMarquardt,
        Solver::GaussNewtonLs => SolverKind::GaussNewtonLineSearch,
    };
    o.solver.max_iterations = p.max_iterations;
    o.solver.ftol = p.ftol;
    o.solver.xtol = p.xtol;
    o.solver.gtol = p.gtol;
    o.solver.fd_step = p.fd_step;
    o.gear_ratio = p.gear_ratio;
    o.speed_window_s = p.window_s;
    o.step_residual = match p.residual {
        Residual::Angle => StepResidual::Angle,
        Residual::Speed => StepResidual::Speed,
    };
    o.free_inductance = p.free_inductance;
    o.holdout = (!p.holdout.trim().is_empty()).then(|| p.holdout.split(',').map(|s| s.trim().to_string()).collect());
    o.whiteness_max_lag = p.whiteness_max_lag;
    o.pi.method = match p.pi_method {
        Pi::CorrectedLs => PiMethod::CorrectedLs,
        Pi::Iv => PiMethod::Iv,
    };
    o.pi.window_s = p.pi_window_s;
    o.pi.saturation_margin_v = p.saturation_margin_v;
    o.friction = p.stick_episodes.clone();
    o.integrator = p.integrator.clone();
    o
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let campaign = ctx.campaign()?.clone();
    let thesis: ThesisData = ctx.read_json("data/thesis.json")?;
    let cal: CampaignCalibration = ctx.read_json("data/campaign-calibration.json")?;
    let o = options(&p, InitialValues::from_thesis_data(&thesis));
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

#[cfg(test)]
mod tests {
    use super::*;

    /// `rig_diagnose::diagnose_campaign` (the confusion battery's blind chain)
    /// calibrates with `CalibrationSettings::default()` and estimates with
    /// `EstimateOptions::new`: they must be what this DAG runs, or the battery
    /// validates another chain than the reports'. Changing either side fails here.
    #[test]
    fn the_blind_chain_runs_with_the_dags_options() {
        // pipeline.toml as the runner hands it over: listed [shared.<name>] tables join the params.
        let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../pipeline.toml");
        let doc: toml::Table = toml::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
        let params = |name: &str| {
            let stage = doc["stage"].as_array().unwrap().iter().find(|s| s["name"].as_str() == Some(name)).unwrap();
            let mut p = stage["params"].as_table().unwrap().clone();
            for listed in stage.get("shared").and_then(|v| v.as_array()).into_iter().flatten() {
                let key = listed.as_str().unwrap();
                p.insert(key.to_string(), doc["shared"][key].clone());
            }
            toml::Value::Table(p)
        };
        let cal: rig_calibrate::CalibrationSettings = params("campaign-calibration").try_into().unwrap();
        assert_eq!(cal, rig_calibrate::CalibrationSettings::default(), "campaign-calibration params vs code defaults");
        let p: Params = params("estimation").try_into().unwrap();
        let initial = || InitialValues::from_table_4_4(|_| Some(1.0)).unwrap();
        assert_eq!(options(&p, initial()), EstimateOptions::new(initial()), "estimation params vs code defaults");
    }
}
