//! Stage `sweeps`: severity maps (Fig. 4.16) and bifurcation diagrams (Figs.
//! 4.18, 4.20) of the thesis model as published and of the rig model, swept
//! up and down by continuation (rig-sweep), with the campaign's operating
//! points classified from the recordings by the same classifier, the
//! chapter's labelled points, the agreement table and the measured time
//! responses of Figs. 4.19 and 4.21.
//!
//! Signal paths: sweeps classify the model's own Ω1 (dense output at
//! `sample_rate_hz`, no encoder; a continuation has no recording to mimic).
//! Operating points — measured, and both models simulated from rest with the
//! recording's ramp at the recording's sample times — go through the encoder
//! (1000 ticks/rev) and `rig_calibrate::rotor_speed_rad_s`, so that measured
//! and simulated windows see the same quantisation and filter before the
//! same classifier. Their window is the last `window_s` of the record minus
//! the differentiator's 40 ms edge (18 s after a 2 s ramp in a 40 s record).

use crate::StageCtx;
use anyhow::{Context, Result, anyhow, bail};
use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use rig_calibrate::signal::SPEED_HALF_WINDOW_S;
use rig_calibrate::{ThesisData, rotor_speed_rad_s};
use rig_model::{SimOptions, simulate};
use rig_sweep::{
    ChainResult, Classification, ClassifyOptions, MapSlice, MapSpec, Point, Shard, SweepSettings, WindowSpec,
    bifurcation_chains, chain_table, classify, hysteresis, linspace, map_table, run_chains, run_map_shard,
};
use rig_types::units::RAD_S_TO_RPM;
use rig_types::{FigureSpec, Heatmap, RigParams, Run, RunInput, RunKind, Series, SeriesStyle, Table, fmt_fixed};
use serde::Deserialize;
use std::f64::consts::PI;
use std::io::IsTerminal;

const MAX_POINTS: usize = 2000;
/// Max and min of a window, for the diagrams' two series.
type Extreme = (&'static str, fn(&Classification) -> f64);
const EXTREMES: [Extreme; 2] = [("max", |k| k.max_rad_s), ("min", |k| k.min_rad_s)];

/// One model's results.
struct ModelSweeps {
    name: &'static str,
    params: RigParams,
    map: MapSlice,
    speed: Vec<ChainResult>,
    friction: Vec<ChainResult>,
    speed_campaign: Vec<ChainResult>,
    friction_campaign: Vec<ChainResult>,
}

/// A classified operating point (measured or simulated from rest).
struct OpPoint {
    id: String,
    point: Point,
    measured: Classification,
    thesis: Classification,
    rig: Classification,
}

struct Diagrams {
    speed_force_n: f64,
    friction_rpm: f64,
    campaign_force_n: f64,
    campaign_rpm: f64,
    speeds_rpm: Vec<f64>,
    forces_n: Vec<f64>,
}

/// `[stage.params]` of `sweeps` (meanings in pipeline.toml).
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Params {
    pub rtol: f64,
    pub atol: f64,
    pub max_step_s: f64,
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
    pub speed_sweep_campaign_force_n: f64,
    pub friction_sweep_campaign_rpm: f64,
    /// `"i/n"`: only chains of shard i of the maps.
    pub shard: String,
    /// The regime classifier's thresholds (`[stage.params.classify]`).
    pub classify: ClassifyOptions,
}

pub fn run(ctx: &mut StageCtx) -> Result<()> {
    let p: Params = ctx.typed_params()?;
    let settings = SweepSettings {
        window: WindowSpec {
            first_transient_s: p.first_transient_s,
            transient_s: p.transient_s,
            window_s: p.window_s,
            sample_rate_hz: p.sample_rate_hz,
        },
        sim: SimOptions { rtol: p.rtol, atol: p.atol, max_step_s: p.max_step_s },
        classify: p.classify.clone(),
    };
    let shard = Shard::parse(&p.shard).context("pipeline.toml: [stage.params] shard")?;
    let map = MapSpec {
        speeds_rpm: linspace(p.map_rpm_min, p.map_rpm_max, p.map_rpm_points),
        forces_n: linspace(p.map_force_min_n, p.map_force_max_n, p.map_force_points),
    };
    let n_diag = p.diagram_points;
    let d = Diagrams {
        speed_force_n: p.speed_sweep_force_n,
        friction_rpm: p.friction_sweep_rpm,
        campaign_force_n: p.speed_sweep_campaign_force_n,
        campaign_rpm: p.friction_sweep_campaign_rpm,
        speeds_rpm: linspace(map.speeds_rpm[0], *map.speeds_rpm.last().expect("linspace is not empty"), n_diag),
        forces_n: linspace(map.forces_n[0], *map.forces_n.last().expect("linspace is not empty"), n_diag),
    };
    let rig: RigParams = ctx.read_json("data/rig-params.json")?;
    let thesis = thesis_params(ctx, &rig)?;

    let diag_points = 8 * n_diag;
    let total = (map.n_points() * shard.range(2 * map.forces_n.len()).len() / (2 * map.forces_n.len()).max(1)
        + diag_points)
        * 2;
    let bar = progress_bar(total as u64);
    let tick = || bar.inc(1);
    if shard != Shard::WHOLE {
        // A partial map: only this shard's slices; rig_sweep::merge_slices joins them.
        for (name, p) in [("thesis", &thesis), ("rig", &rig)] {
            let slice = run_map_shard(p, &map, shard, &settings, &tick);
            ctx.write_json(&format!("tables/sweep-map-{name}.shard-{}-of-{}.json", shard.index, shard.count), &slice)?;
        }
        bar.finish_and_clear();
        return Ok(());
    }
    let mut models = Vec::new();
    for (name, p) in [("thesis", thesis), ("rig", rig)] {
        bar.set_message(format!("{name} model"));
        let diag =
            |values: &[f64], f: &dyn Fn(f64) -> Point| run_chains(&p, &bifurcation_chains(values, f), &settings, &tick);
        let (fs, fr) = (d.speed_force_n, d.friction_rpm);
        let (cfs, cfr) = (d.campaign_force_n, d.campaign_rpm);
        models.push(ModelSweeps {
            name,
            map: run_map_shard(&p, &map, Shard::WHOLE, &settings, &tick),
            speed: diag(&d.speeds_rpm, &|v| Point { motor_rpm: v, normal_force_n: fs }),
            friction: diag(&d.forces_n, &|v| Point { motor_rpm: fr, normal_force_n: v }),
            speed_campaign: diag(&d.speeds_rpm, &|v| Point { motor_rpm: v, normal_force_n: cfs }),
            friction_campaign: diag(&d.forces_n, &|v| Point { motor_rpm: cfr, normal_force_n: v }),
            params: p,
        });
    }
    bar.finish_and_clear();

    let campaign = ctx.campaign()?.clone();
    let tpr = campaign.rig.encoder_ticks_per_rev;
    let runs: Vec<&Run> = campaign.runs_of("operating_point").collect();
    if runs.is_empty() {
        bail!("campaign {} has no operating_point run", campaign.name);
    }
    let (th, rg) = (&models[0].params, &models[1].params);
    let ops: Vec<OpPoint> = {
        use rayon::prelude::*;
        runs.par_iter().map(|r| op_point(r, th, rg, &settings, tpr)).collect::<Result<_>>()?
    };
    let labelled =
        rig_ingest::thesis::read_thesis_tables(&ctx.thesis_dir).context("reading the thesis tables")?.labelled_points;
    let mut labels = Vec::new();
    for l in &labelled {
        let p = Point { motor_rpm: l.motor_rpm, normal_force_n: l.frict_n };
        let t = from_rest(th, p, &settings, tpr).with_context(|| format!("thesis model at Fig. {}", l.figure))?;
        let r = from_rest(rg, p, &settings, tpr).with_context(|| format!("rig model at Fig. {}", l.figure))?;
        let id = format!("fig-{}{}", l.figure, l.panel);
        labels.push((id, p, l.label.clone(), l.source.clone(), t, r));
    }

    for m in &models {
        ctx.write_table(&format!("tables/sweep-map-{}.csv", m.name), &map_table(&m.map))?;
        for (kind, chains) in [
            ("speed", &m.speed),
            ("friction", &m.friction),
            ("speed-campaign", &m.speed_campaign),
            ("friction-campaign", &m.friction_campaign),
        ] {
            ctx.write_table(&format!("tables/sweep-bifurcation-{kind}-{}.csv", m.name), &chain_table(chains))?;
        }
    }
    ctx.write_table("tables/sweep-agreement.csv", &agreement_table(&ops, &labels, &models))?;
    for m in &models {
        for dir in [0, 1] {
            ctx.write_figure(&map_figure(m, dir, &ops, &labels, &settings.window))?;
        }
    }
    let speed_fig = |id: &str, force: f64, pick: fn(&ModelSweeps) -> &Vec<ChainResult>| {
        diagram_figure(
            id,
            "motor speed MRPM [rpm]",
            &models,
            pick,
            |p| p.motor_rpm,
            &ops,
            |p| (p.normal_force_n - force).abs() < 0.5,
            &format!("{} N", fmt_fixed(force, 2)),
        )
    };
    ctx.write_figure(&speed_fig("fig-4-18", d.speed_force_n, |m| &m.speed))?;
    ctx.write_figure(&speed_fig("fig-4-18-campaign", d.campaign_force_n, |m| &m.speed_campaign))?;
    let friction_fig = |id: &str, rpm: f64, pick: fn(&ModelSweeps) -> &Vec<ChainResult>| {
        diagram_figure(
            id,
            "normal force Frict [N]",
            &models,
            pick,
            |p| p.normal_force_n,
            &ops,
            |p| (p.motor_rpm - rpm).abs() < 2.5,
            &format!("{} rpm", fmt_fixed(rpm, 1)),
        )
    };
    ctx.write_figure(&friction_fig("fig-4-20", d.friction_rpm, |m| &m.friction))?;
    ctx.write_figure(&friction_fig("fig-4-20-campaign", d.campaign_rpm, |m| &m.friction_campaign))?;
    let chosen = time_response_runs(&runs);
    for (fig, target, run) in &chosen {
        let op = ops.iter().find(|o| o.id == run.id).expect("every run has an op point");
        ctx.write_figure(&time_response_figure(fig, *target, run, op, tpr)?)?;
    }
    ctx.write_text("sweeps.md", &report_md(&models, &ops, &labels, &chosen, &settings))?;
    Ok(())
}

fn progress_bar(total: u64) -> ProgressBar {
    let target =
        if std::io::stderr().is_terminal() { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
    let bar = ProgressBar::with_draw_target(Some(total), target);
    if let Ok(style) = ProgressStyle::with_template("sweeps {msg} [{bar:30}] {pos}/{len} points, ETA {eta}") {
        bar.set_style(style);
    }
    bar
}

/// The thesis model (data/thesis.json: Table 4.5, the chapter's ξ, Table 4.7,
/// r) with the rig's PI gains, which the chapter does not publish — the same
/// construction as the simulation stage.
fn thesis_params(ctx: &StageCtx, rig: &RigParams) -> Result<RigParams> {
    let data: ThesisData = ctx.read_json("data/thesis.json")?;
    Ok(super::thesis_model(&data, rig.drive.clone()))
}

/// Samples of the classification window: last `window_s` before the differentiator's edge.
fn window_range(time_s: &[f64], window_s: f64) -> std::ops::Range<usize> {
    let t_end = time_s.last().copied().unwrap_or(0.0) - 2.0 * SPEED_HALF_WINDOW_S;
    let start = time_s.partition_point(|&t| t < t_end - window_s);
    let end = time_s.partition_point(|&t| t <= t_end);
    start..end.max(start)
}

fn encoder_speed(time_s: &[f64], angle_rad: &[f64], tpr: u32) -> Vec<f64> {
    let tick = 2.0 * PI / f64::from(tpr);
    let ticks: Vec<i64> = angle_rad.iter().map(|a| (a / tick).floor() as i64).collect();
    rotor_speed_rad_s(time_s, &ticks, tpr)
}

fn classify_window(time_s: &[f64], speed: &[f64], s: &SweepSettings) -> Classification {
    let w = window_range(time_s, s.window.window_s);
    let fs = (time_s.len().max(2) - 1) as f64 / (time_s[time_s.len() - 1] - time_s[0]).max(f64::MIN_POSITIVE);
    classify(&speed[w], fs, &s.classify)
}

fn simulated(p: &RigParams, input: &RunInput, time_s: &[f64], s: &SweepSettings, tpr: u32) -> Result<Classification> {
    let tr = simulate(p, input, time_s, &s.sim)?;
    Ok(classify_window(time_s, &encoder_speed(time_s, &tr.rotor_angle_rad, tpr), s))
}

fn op_point(run: &Run, th: &RigParams, rg: &RigParams, s: &SweepSettings, tpr: u32) -> Result<OpPoint> {
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else {
        return Err(anyhow!("run {} is not an operating_point", run.id));
    };
    let ticks = run.data.rotor_ticks.as_ref().ok_or_else(|| anyhow!("run {}: no rotor_ticks column", run.id))?;
    let time_s = &run.data.time_s;
    let input = RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s };
    Ok(OpPoint {
        id: run.id.clone(),
        point: Point { motor_rpm: motor_rpm_setpoint, normal_force_n },
        measured: classify_window(time_s, &rotor_speed_rad_s(time_s, ticks, tpr), s),
        thesis: simulated(th, &input, time_s, s, tpr).with_context(|| format!("run {}: thesis model", run.id))?,
        rig: simulated(rg, &input, time_s, s, tpr).with_context(|| format!("run {}: rig model", run.id))?,
    })
}

/// A labelled point of the chapter simulated like a campaign run: 2 s ramp,
/// 40 s at 500 Hz (the campaign's protocol), encoder and differentiator.
fn from_rest(p: &RigParams, pt: Point, s: &SweepSettings, tpr: u32) -> Result<Classification> {
    let time_s: Vec<f64> = (0..=20_000).map(|k| k as f64 / 500.0).collect();
    let input =
        RunInput::OperatingPoint { motor_rpm_setpoint: pt.motor_rpm, normal_force_n: pt.normal_force_n, ramp_s: 2.0 };
    simulated(p, &input, &time_s, s, tpr)
}

/// The map class of the grid point nearest to `p` (range-normalised distance), per direction.
fn nearest_map_label(m: &ModelSweeps, p: Point, dir: usize) -> String {
    let spec = &m.map.spec;
    let (sr, fr) = (range(&spec.speeds_rpm), range(&spec.forces_n));
    let near = |v: &[f64], x: f64, r: f64| {
        (0..v.len()).min_by(|&a, &b| ((v[a] - x) / r).abs().total_cmp(&((v[b] - x) / r).abs())).unwrap_or(0)
    };
    let (i, j) = (near(&spec.speeds_rpm, p.motor_rpm, sr), near(&spec.forces_n, p.normal_force_n, fr));
    let chain = &m.map.chains[2 * j + dir];
    let k = if dir == 0 { i } else { spec.speeds_rpm.len() - 1 - i };
    label(&chain.points[k].result)
}

fn range(v: &[f64]) -> f64 {
    (v.last().copied().unwrap_or(1.0) - v.first().copied().unwrap_or(0.0)).abs().max(f64::MIN_POSITIVE)
}

fn label(r: &Result<Classification, String>) -> String {
    r.as_ref().map(|c| c.regime.label()).unwrap_or_else(|_| "not converged".into())
}

fn yes(b: bool) -> String {
    if b { "yes" } else { "no" }.into()
}

type Labelled = (String, Point, String, String, Classification, Classification);

fn agreement_table(ops: &[OpPoint], labels: &[Labelled], models: &[ModelSweeps]) -> Table {
    let mut t = Table::new([
        "point",
        "source",
        "motor_rpm",
        "normal_force_n",
        "measured_class",
        "measured_severity_full",
        "thesis_class",
        "thesis_agree_vibration",
        "thesis_agree_class",
        "rig_class",
        "rig_agree_vibration",
        "rig_agree_class",
        "thesis_map_up",
        "thesis_map_down",
        "rig_map_up",
        "rig_map_down",
    ]);
    let maps = |p: Point| models.iter().flat_map(move |m| [nearest_map_label(m, p, 0), nearest_map_label(m, p, 1)]);
    for o in ops {
        let (m, th, rg) = (&o.measured.regime, &o.thesis.regime, &o.rig.regime);
        let mut row = vec![
            o.id.clone(),
            "campaign".into(),
            fmt_fixed(o.point.motor_rpm, 1),
            fmt_fixed(o.point.normal_force_n, 2),
            m.label(),
            fmt_fixed(o.measured.severity_full, 3),
            th.label(),
            yes(th.vibrating() == m.vibrating()),
            yes(th.label() == m.label()),
            rg.label(),
            yes(rg.vibrating() == m.vibrating()),
            yes(rg.label() == m.label()),
        ];
        row.extend(maps(o.point));
        t.push(row);
    }
    for (id, p, lab, source, th, rg) in labels {
        let vib = lab == "vibrating";
        let mut row = vec![
            id.clone(),
            format!("thesis {source}"),
            fmt_fixed(p.motor_rpm, 1),
            fmt_fixed(p.normal_force_n, 2),
            lab.clone(),
            String::new(),
            th.regime.label(),
            yes(th.regime.vibrating() == vib),
            String::new(),
            rg.regime.label(),
            yes(rg.regime.vibrating() == vib),
            String::new(),
        ];
        row.extend(maps(*p));
        t.push(row);
    }
    t
}

fn ok_points(c: &ChainResult) -> impl Iterator<Item = (Point, &Classification)> {
    c.points.iter().filter_map(|o| o.result.as_ref().ok().map(|k| (o.point, k)))
}

/// Heat map of severity (max − min)/mean over the map for one direction, with
/// the points where the other direction disagrees, and the measured points.
fn map_figure(m: &ModelSweeps, dir: usize, ops: &[OpPoint], labels: &[Labelled], w: &WindowSpec) -> FigureSpec {
    let spec = &m.map.spec;
    let (nx, ny) = (spec.speeds_rpm.len(), spec.forces_n.len());
    let mut z = vec![vec![0.0; nx]; ny];
    let mut failed = 0;
    let mut bistable = (Vec::new(), Vec::new());
    for (j, z_row) in z.iter_mut().enumerate() {
        let (up, down) = (&m.map.chains[2 * j], &m.map.chains[2 * j + 1]);
        let chain = if dir == 0 { up } else { down };
        for (k, o) in chain.points.iter().enumerate() {
            let i = if dir == 0 { k } else { nx - 1 - k };
            match &o.result {
                Ok(c) => z_row[i] = c.severity_full,
                Err(_) => failed += 1,
            }
        }
        for (p, _, _) in hysteresis(up, down) {
            bistable.0.push(p.motor_rpm);
            bistable.1.push(p.normal_force_n);
        }
    }
    let mut series =
        vec![Series {
            name: "up ≠ down (bistable)".into(), x: bistable.0, y: bistable.1, style: SeriesStyle::Points
        }];
    for vib in [true, false] {
        let pts: Vec<&OpPoint> = ops.iter().filter(|o| o.measured.regime.vibrating() == vib).collect();
        series.push(Series {
            name: format!("measured {}", if vib { "vibrating" } else { "quiet" }),
            x: pts.iter().map(|o| o.point.motor_rpm).collect(),
            y: pts.iter().map(|o| o.point.normal_force_n).collect(),
            style: if vib { SeriesStyle::Markers } else { SeriesStyle::Points },
        });
        let ls: Vec<&Labelled> = labels.iter().filter(|l| (l.2 == "vibrating") == vib).collect();
        series.push(Series {
            name: format!("thesis label {}", if vib { "vibrating" } else { "quiet" }),
            x: ls.iter().map(|l| l.1.motor_rpm).collect(),
            y: ls.iter().map(|l| l.1.normal_force_n).collect(),
            style: if vib { SeriesStyle::Markers } else { SeriesStyle::Points },
        });
    }
    let dname = if dir == 0 { "up" } else { "down" };
    FigureSpec {
        id: format!("fig-4-16-{}-{dname}", m.name),
        title: format!("Severity map of the {} model, motor speed swept {dname}", m.name),
        caption: format!(
            "Stick-slip severity (max − min)/mean of rotor speed over a {nx} × {ny} grid of motor set-point × \
             normal force (the chapter's Frict), {} model, each friction row swept {dname} in speed by \
             continuation (each point starts from the previous point's end state; {} s discarded after each \
             step, the next {} s classified). Points: grid cells where the up and down sweeps end in different \
             regimes (the bistable band); campaign operating points classified from their recordings by the \
             same classifier (vibrating = any regime but equilibrium); the chapter's labelled points \
             (Figs. 4.17, 4.19, 4.21–4.24). {failed} grid points did not converge (shown as 0).",
            m.name,
            fmt_fixed(w.transient_s, 1),
            fmt_fixed(w.window_s, 1)
        ),
        x_label: "motor speed MRPM [rpm]".into(),
        y_label: "normal force Frict [N]".into(),
        series,
        x_decimals: 2,
        y_decimals: 3,
        heatmap: Some(Heatmap {
            x: spec.speeds_rpm.clone(),
            y: spec.forces_n.clone(),
            z,
            z_label: "severity (max − min)/mean [-]".into(),
        }),
    }
}

#[allow(clippy::too_many_arguments)]
fn diagram_figure(
    id: &str,
    x_label: &str,
    models: &[ModelSweeps],
    pick: fn(&ModelSweeps) -> &Vec<ChainResult>,
    x_of: fn(&Point) -> f64,
    ops: &[OpPoint],
    on_line: impl Fn(&Point) -> bool,
    fixed: &str,
) -> FigureSpec {
    let mut series = Vec::new();
    for m in models {
        for c in pick(m) {
            let pts: Vec<(Point, &Classification)> = ok_points(c).collect();
            let style = if c.direction == rig_sweep::Direction::Up { SeriesStyle::Line } else { SeriesStyle::Dashed };
            for (which, f) in EXTREMES {
                series.push(Series {
                    name: format!("{} model {} RRPM {which}", m.name, c.direction.as_str()),
                    x: pts.iter().map(|(p, _)| x_of(p)).collect(),
                    y: pts.iter().map(|(_, k)| f(k) * RAD_S_TO_RPM).collect(),
                    style,
                });
            }
        }
    }
    let meas: Vec<&OpPoint> = ops.iter().filter(|o| on_line(&o.point)).collect();
    let ids: Vec<&str> = meas.iter().map(|o| o.id.as_str()).collect();
    for (which, f) in EXTREMES {
        series.push(Series {
            name: format!("measured RRPM {which}"),
            x: meas.iter().map(|o| x_of(&o.point)).collect(),
            y: meas.iter().map(|o| f(&o.measured) * RAD_S_TO_RPM).collect(),
            style: SeriesStyle::Markers,
        });
    }
    FigureSpec {
        id: id.into(),
        title: format!("Bifurcation diagram at {fixed}: min and max rotor speed, up and down, both models"),
        caption: format!(
            "Minimum and maximum rotor-1 speed RRPM in the classification window at {fixed}, thesis model as \
             published and rig model, each swept up (solid) and down (dashed) by continuation (each point starts \
             from the previous point's end state), so where the two directions differ the model is bistable. \
             Markers: campaign runs at {fixed} ({}), min and max of the encoder-derived rotor speed over the last \
             20 s of the record. Where min and max meet the rotor slides steadily; min at 0 is stick-slip.",
            if ids.is_empty() { "none in this campaign".to_string() } else { ids.join(", ") }
        ),
        x_label: x_label.into(),
        y_label: "rotor speed RRPM [rpm]".into(),
        series,
        x_decimals: 3,
        y_decimals: 2,
        heatmap: None,
    }
}

/// Figs. 4.19a/b and 4.21a/b: the campaign runs nearest (range-normalised
/// distance over motor rpm and force) to the chapter's points; panel (b) may
/// not reuse panel (a)'s run, so the pair still contrasts two conditions.
fn time_response_runs<'a>(runs: &[&'a Run]) -> Vec<(String, Point, &'a Run)> {
    let op = |r: &Run| match r.kind {
        RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, .. } => (motor_rpm_setpoint, normal_force_n),
        _ => (f64::NAN, f64::NAN),
    };
    let speeds: Vec<f64> = runs.iter().map(|r| op(r).0).collect();
    let forces: Vec<f64> = runs.iter().map(|r| op(r).1).collect();
    let span = |v: &[f64]| {
        let lo = v.iter().copied().fold(f64::INFINITY, f64::min);
        (v.iter().copied().fold(f64::NEG_INFINITY, f64::max) - lo).max(f64::MIN_POSITIVE)
    };
    let (sr, fr) = (span(&speeds), span(&forces));
    let mut out: Vec<(String, Point, &Run)> = Vec::new();
    for (fig, a, b) in [("fig-4-19", (80.0, 7.5), (80.0, 15.0)), ("fig-4-21", (55.0, 0.75), (55.0, 7.5))] {
        let mut used: Option<&str> = None;
        for (panel, (rpm, n)) in [("a", a), ("b", b)] {
            let best = runs
                .iter()
                .filter(|r| Some(r.id.as_str()) != used)
                .min_by(|x, y| {
                    let dist = |r: &Run| ((op(r).0 - rpm) / sr).powi(2) + ((op(r).1 - n) / fr).powi(2);
                    dist(x).total_cmp(&dist(y))
                })
                .expect("runs is not empty");
            used = Some(best.id.as_str());
            out.push((format!("{fig}{panel}"), Point { motor_rpm: rpm, normal_force_n: n }, *best));
        }
    }
    out
}

fn thin(x: &[f64]) -> Vec<f64> {
    rig_spectra::thin_indices(x.len(), MAX_POINTS).into_iter().map(|i| x[i]).collect()
}

fn time_response_figure(id: &str, target: Point, run: &Run, op: &OpPoint, tpr: u32) -> Result<FigureSpec> {
    let t = &run.data.time_s;
    let rotor = run.data.rotor_ticks.as_ref().ok_or_else(|| anyhow!("run {}: no rotor_ticks", run.id))?;
    let motor = run.data.motor_ticks.as_ref().ok_or_else(|| anyhow!("run {}: no motor_ticks", run.id))?;
    let rpm =
        |ticks: &[i64]| thin(&rotor_speed_rad_s(t, ticks, tpr).iter().map(|v| v * RAD_S_TO_RPM).collect::<Vec<_>>());
    Ok(FigureSpec {
        id: id.into(),
        title: format!(
            "Measured time response, run {} ({} rpm, {} N), nearest to the chapter's {} rpm, {} N",
            run.id,
            fmt_fixed(op.point.motor_rpm, 1),
            fmt_fixed(op.point.normal_force_n, 2),
            fmt_fixed(target.motor_rpm, 1),
            fmt_fixed(target.normal_force_n, 2)
        ),
        caption: format!(
            "Rotor speed RRPM and motor-side speed MRPM of campaign run {} (set-point {} rpm, normal force {} N), \
             the run nearest (range-normalised distance) to the chapter's point at {} rpm and {} N; the (b) panel \
             never reuses the (a) panel's run. Speeds from the encoders through the calibration differentiator \
             (±20 ms central difference and moving average), thinned to at most {MAX_POINTS} points. The same \
             classifier as the sweeps calls the last 20 s `{}` (severity (max − min)/mean {}).",
            run.id,
            fmt_fixed(op.point.motor_rpm, 1),
            fmt_fixed(op.point.normal_force_n, 2),
            fmt_fixed(target.motor_rpm, 1),
            fmt_fixed(target.normal_force_n, 2),
            op.measured.regime.label(),
            fmt_fixed(op.measured.severity_full, 3)
        ),
        x_label: "time [s]".into(),
        y_label: "speed [rpm]".into(),
        series: vec![
            Series { name: "rotor RRPM".into(), x: thin(t), y: rpm(rotor), style: SeriesStyle::Line },
            Series { name: "motor MRPM".into(), x: thin(t), y: rpm(motor), style: SeriesStyle::Dashed },
        ],
        x_decimals: 3,
        y_decimals: 2,
        heatmap: None,
    })
}

fn report_md(
    models: &[ModelSweeps],
    ops: &[OpPoint],
    labels: &[Labelled],
    chosen: &[(String, Point, &Run)],
    s: &SweepSettings,
) -> String {
    let w = &s.window;
    let mut md = String::from("# Sweeps: severity maps and bifurcation diagrams, up and down\n\n");
    md.push_str(&format!(
        "Every point of a sweep starts from the previous point's end state (continuation). After each parameter \
         step {} s are discarded (5 torsional periods of ≈ 2 s; the first point of a chain starts from rest and \
         gets {} s), then {} s are classified at {} Hz (3 to 10 stick-slip cycles). Classes: equilibrium \
         (peak-to-peak below max(0.5 rad/s, 10 % of the mean)), period-k (Poincaré section: peaks of Ω1 between \
         upward crossings of its mean, k clusters repeating), quasi-periodic (spectral line analysis finds an \
         incommensurate second base and explains every line) and chaotic (anything else); `stick-slip` when the \
         minimum speed falls to max(0.3 rad/s, 10 % of the mean). Severity in both conventions is in the tables \
         (`severity_half` = (max − min)/(2·mean), `severity_full` = (max − min)/mean).\n\n",
        fmt_fixed(w.transient_s, 1),
        fmt_fixed(w.first_transient_s, 1),
        fmt_fixed(w.window_s, 1),
        fmt_fixed(w.sample_rate_hz, 0)
    ));
    md.push_str("## Where up and down sweeps differ (the bistable band)\n\n");
    for m in models {
        for (what, chains) in [
            ("speed sweep (Fig. 4.18)", &m.speed),
            ("friction sweep (Fig. 4.20)", &m.friction),
            ("speed sweep, campaign force", &m.speed_campaign),
            ("friction sweep, campaign speed", &m.friction_campaign),
        ] {
            let h = hysteresis(&chains[0], &chains[1]);
            md.push_str(&format!("- {} model, {what}: ", m.name));
            if h.is_empty() {
                md.push_str("up and down agree everywhere.\n");
            } else {
                let (lo, hi) = (h.first().expect("not empty").0, h.last().expect("not empty").0);
                md.push_str(&format!(
                    "{} of {} points differ, from ({} rpm, {} N) to ({} rpm, {} N); e.g. up `{}` vs down `{}`.\n",
                    h.len(),
                    chains[0].points.len(),
                    fmt_fixed(lo.motor_rpm, 1),
                    fmt_fixed(lo.normal_force_n, 2),
                    fmt_fixed(hi.motor_rpm, 1),
                    fmt_fixed(hi.normal_force_n, 2),
                    h[0].1,
                    h[0].2
                ));
            }
        }
        let bistable: usize =
            (0..m.map.chains.len() / 2).map(|j| hysteresis(&m.map.chains[2 * j], &m.map.chains[2 * j + 1]).len()).sum();
        md.push_str(&format!(
            "- {} model, severity map: {} of {} grid points end in different regimes up and down.\n",
            m.name,
            bistable,
            m.map.spec.speeds_rpm.len() * m.map.spec.forces_n.len()
        ));
    }
    md.push_str("\n## Where the models agree with the measurements\n\n");
    md.push_str(
        "Campaign runs classified from their recordings and both models simulated from rest with the same \
         protocol (`tables/sweep-agreement.csv`):\n\n",
    );
    for (name, pick) in [("thesis", 0usize), ("rig", 1)] {
        let cls = |o: &OpPoint| if pick == 0 { o.thesis.regime } else { o.rig.regime };
        let vib = ops.iter().filter(|o| cls(o).vibrating() == o.measured.regime.vibrating()).count();
        let same = ops.iter().filter(|o| cls(o).label() == o.measured.regime.label()).count();
        let lab = labels
            .iter()
            .filter(|l| (if pick == 0 { &l.4 } else { &l.5 }).regime.vibrating() == (l.2 == "vibrating"))
            .count();
        md.push_str(&format!(
            "- {name} model: vibrating/quiet agrees on {vib} of {} runs, exact class on {same}; the chapter's \
             labelled points: {lab} of {}.\n",
            ops.len(),
            labels.len()
        ));
        let miss: Vec<String> = ops
            .iter()
            .filter(|o| cls(o).vibrating() != o.measured.regime.vibrating())
            .map(|o| {
                format!(
                    "{} ({} rpm, {} N: measured `{}`, model `{}`)",
                    o.id,
                    fmt_fixed(o.point.motor_rpm, 1),
                    fmt_fixed(o.point.normal_force_n, 2),
                    o.measured.regime.label(),
                    cls(o).label()
                )
            })
            .collect();
        if !miss.is_empty() {
            md.push_str(&format!("  Disagree: {}.\n", miss.join("; ")));
        }
    }
    md.push_str("\n## Runs shown as Figs. 4.19 and 4.21\n\n");
    for (fig, target, run) in chosen {
        md.push_str(&format!(
            "- {fig}: run {} for the chapter's {} rpm, {} N.\n",
            run.id,
            fmt_fixed(target.motor_rpm, 1),
            fmt_fixed(target.normal_force_n, 2)
        ));
    }
    md
}
