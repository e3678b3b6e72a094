//! The sweeps study (the `sweeps` stage's one call): severity maps (Fig.
//! 4.16) and bifurcation diagrams (Figs. 4.18, 4.20) of the thesis model as
//! published and of the rig model, swept up and down by continuation, with
//! the campaign's operating points and the chapter's labelled points
//! classified by the same classifier ([`crate::operating`]).
//!
//! Sweeps classify the model's own Ω1 (dense output at `sample_rate_hz`, no
//! encoder; a continuation has no recording to mimic); operating points go
//! through the sensor chain.

pub mod render;

use crate::operating::{LabelledPoint, OpPoint, RunProtocol, labelled_points, op_point};
use crate::{
    ChainResult, ClassifyOptions, MapSlice, MapSpec, Point, Shard, SweepError, SweepSettings, WindowSpec,
    bifurcation_chains, linspace, run_chains, run_map_shard,
};
use rayon::prelude::*;
use rig_model::SimOptions;
use rig_types::{Campaign, RigParams, Run};
use serde::Deserialize;

/// `[stage.params]` of the `sweeps` stage (meanings in pipeline.toml).
#[derive(Debug, Clone, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SweepsParams {
    /// Integrator tolerances (pipeline.toml's `[shared.integrator]`).
    pub integrator: SimOptions,
    pub first_transient_s: f64,
    pub transient_s: f64,
    pub window_s: f64,
    pub sample_rate_hz: f64,
    pub map_rpm_min: f64,
    pub map_rpm_max: f64,
    pub map_rpm_points: usize,
    pub map_force_min_n: f64,
    pub map_force_max_n: f64,
    pub map_force_points: usize,
    pub diagram_points: usize,
    pub speed_sweep_force_n: f64,
    pub friction_sweep_rpm: f64,
    /// `"i/n"`: only chains of shard i of the maps.
    pub shard: String,
    /// The regime classifier's thresholds (pipeline.toml's `[shared.classify]`).
    pub classify: ClassifyOptions,
}

impl SweepsParams {
    pub fn settings(&self) -> SweepSettings {
        SweepSettings {
            window: WindowSpec {
                first_transient_s: self.first_transient_s,
                transient_s: self.transient_s,
                window_s: self.window_s,
                sample_rate_hz: self.sample_rate_hz,
            },
            sim: self.integrator.clone(),
            classify: self.classify.clone(),
        }
    }

    pub fn map(&self) -> MapSpec {
        MapSpec {
            speeds_rpm: linspace(self.map_rpm_min, self.map_rpm_max, self.map_rpm_points),
            forces_n: linspace(self.map_force_min_n, self.map_force_max_n, self.map_force_points),
        }
    }

    pub fn shard(&self) -> Result<Shard, SweepError> {
        Shard::parse(&self.shard)
    }

    /// Simulated points the study runs for `shard` (for a progress bar).
    pub fn progress_total(&self, shard: Shard) -> usize {
        let map = self.map();
        let chains = 2 * map.forces_n.len();
        (map.n_points() * shard.range(chains).len() / chains.max(1) + 8 * self.diagram_points) * 2
    }
}

/// One model's sweeps.
#[derive(Debug, Clone)]
pub struct ModelSweeps {
    pub name: &'static str,
    pub params: RigParams,
    pub map: MapSlice,
    pub speed: Vec<ChainResult>,
    pub friction: Vec<ChainResult>,
    pub speed_campaign: Vec<ChainResult>,
    pub friction_campaign: Vec<ChainResult>,
}

/// Everything the sweeps study found.
#[derive(Debug, Clone)]
pub struct SweepsStudy {
    pub settings: SweepSettings,
    /// Fixed force of Fig. 4.18 and fixed speed of Fig. 4.20, then the campaign's.
    pub speed_sweep_force_n: f64,
    pub friction_sweep_rpm: f64,
    pub campaign_force_n: f64,
    pub campaign_rpm: f64,
    /// Thesis model, then rig model.
    pub models: Vec<ModelSweeps>,
    pub ops: Vec<OpPoint>,
    pub labelled: Vec<crate::operating::Labelled>,
    /// Figs. 4.19a/b and 4.21a/b: (figure id, the chapter's point, run id).
    pub chosen: Vec<(String, Point, String)>,
}

/// One shard of both models' severity maps (thesis, then rig).
pub fn map_shards(
    thesis: &RigParams,
    rig: &RigParams,
    p: &SweepsParams,
    shard: Shard,
    progress: &(dyn Fn() + Sync),
) -> Vec<(&'static str, MapSlice)> {
    let (map, settings) = (p.map(), p.settings());
    [("thesis", thesis), ("rig", rig)]
        .into_iter()
        .map(|(name, m)| (name, run_map_shard(m, &map, shard, &settings, progress)))
        .collect()
}

/// The campaign's own speed and force series: the normal force most of its
/// operating points share (the speed series' force) and the set-point most
/// share (the force series' set-point); ties go to the smaller value. Read
/// from the campaign, so another lab's set-points get their own diagrams.
pub fn campaign_series(campaign: &Campaign) -> (f64, f64) {
    let mode = |values: Vec<f64>| {
        let mut counts: Vec<(f64, usize)> = Vec::new();
        for v in values {
            match counts.iter_mut().find(|(x, _)| *x == v) {
                Some(c) => c.1 += 1,
                None => counts.push((v, 1)),
            }
        }
        counts.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.total_cmp(&b.0)));
        counts.first().map_or(f64::NAN, |c| c.0)
    };
    let points: Vec<(f64, f64)> = campaign
        .runs_of("operating_point")
        .filter_map(|r| match r.kind {
            rig_types::RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, .. } => {
                Some((motor_rpm_setpoint, normal_force_n))
            }
            _ => None,
        })
        .collect();
    (mode(points.iter().map(|p| p.1).collect()), mode(points.iter().map(|p| p.0).collect()))
}

/// The whole study: both models' maps and diagrams, every operating point
/// of `campaign`, the chapter's labelled points.
pub fn sweeps_study(
    thesis: RigParams,
    rig: RigParams,
    campaign: &Campaign,
    labels: &[LabelledPoint],
    p: &SweepsParams,
    progress: &(dyn Fn() + Sync),
    on_model: &dyn Fn(&str),
) -> Result<SweepsStudy, SweepError> {
    if campaign.runs_of("operating_point").next().is_none() {
        return Err(SweepError::Analysis(format!("campaign {} has no operating_point run", campaign.name)));
    }
    let (cfs, cfr) = campaign_series(campaign);
    let settings = p.settings();
    let map = p.map();
    let n_diag = p.diagram_points;
    let speeds_rpm = linspace(map.speeds_rpm[0], *map.speeds_rpm.last().expect("linspace is not empty"), n_diag);
    let forces_n = linspace(map.forces_n[0], *map.forces_n.last().expect("linspace is not empty"), n_diag);
    let mut models = Vec::new();
    for (name, m) in [("thesis", thesis), ("rig", rig)] {
        on_model(name);
        let diag = |values: &[f64], f: &dyn Fn(f64) -> Point| {
            run_chains(&m, &bifurcation_chains(values, f), &settings, progress)
        };
        let (fs, fr) = (p.speed_sweep_force_n, p.friction_sweep_rpm);
        models.push(ModelSweeps {
            name,
            map: run_map_shard(&m, &map, Shard::WHOLE, &settings, progress),
            speed: diag(&speeds_rpm, &|v| Point { motor_rpm: v, normal_force_n: fs }),
            friction: diag(&forces_n, &|v| Point { motor_rpm: fr, normal_force_n: v }),
            speed_campaign: diag(&speeds_rpm, &|v| Point { motor_rpm: v, normal_force_n: cfs }),
            friction_campaign: diag(&forces_n, &|v| Point { motor_rpm: cfr, normal_force_n: v }),
            params: m,
        });
    }

    let tpr = campaign.rig.encoder_ticks_per_rev;
    let runs: Vec<&Run> = campaign.runs_of("operating_point").collect();
    if runs.is_empty() {
        return Err(SweepError::Analysis(format!("campaign {} has no operating_point run", campaign.name)));
    }
    let (th, rg) = (&models[0].params, &models[1].params);
    let ops: Vec<OpPoint> = runs.par_iter().map(|r| op_point(r, th, rg, &settings, tpr)).collect::<Result<_, _>>()?;
    let protocol = RunProtocol::of_campaign(campaign).ok_or_else(|| {
        SweepError::Analysis(format!("campaign {}: no operating-point protocol (sample rate, ramp)", campaign.name))
    })?;
    let labelled = labelled_points(labels, th, rg, &protocol, &settings, tpr)?;
    let chosen = crate::operating::time_response_runs(&runs)
        .into_iter()
        .map(|(fig, target, run)| (fig, target, run.id.clone()))
        .collect();
    Ok(SweepsStudy {
        settings,
        speed_sweep_force_n: p.speed_sweep_force_n,
        friction_sweep_rpm: p.friction_sweep_rpm,
        campaign_force_n: cfs,
        campaign_rpm: cfr,
        models,
        ops,
        labelled,
        chosen,
    })
}
