//! The `simulation` stage's study: the thesis model as published and the rig model on every
//! operating point of the campaign at the recording's sample times; the misfit
//! table, the friction laws (Fig. 4.15), the limit cycles (Fig. 4.17) and one
//! overlay of measured and simulated rotor speed per run.
//!
//! Definitions used in the table (the same rule for measurement and models):
//! - *steady window*: the second half of the record (t_end / 2 ≤ t ≤ t_end − 40 ms;
//!   20 s of a 40 s run, i.e. ≥ 5 torsional periods of ≈ 2 s and ≥ 18 s after
//!   the 2 s ramp). The last 40 ms (the differentiator's two half-windows) are
//!   left out because its window shrinks to a one-sample difference at the
//!   end of the record, where one encoder tick reads as 30 rpm;
//! - *rotor speed*: the measurement's Ω1 comes from the rotor encoder through
//!   `rig_types::sensor::encoder_speed_rad_s` (central difference ±20 ms, then
//!   a ±20 ms moving average). Simulated angles go through the same encoder
//!   model (`rig_types::sensor::encoder_ticks`, floor to
//!   `encoder_ticks_per_rev`) and the same differentiator, so both sides see
//!   the same quantisation and filter;
//! - *stick-slip*: [`crate::Regime::stick_slip`] of the classifier
//!   ([`crate::classify`], the thresholds of pipeline.toml's
//!   `[shared.classify]`) on the steady window: a vibrating regime whose
//!   minimum speed reaches max(`stick_floor_rad_s` = 0.3 rad/s, `stick_rel` =
//!   10 % of the mean); 0.3 rad/s is about twice the differentiator's
//!   one-tick resolution (2π/1000 rad over 40 ms = 0.157 rad/s);
//! - *NRMSE*: rms(Ω1,sim − Ω1,meas) / rms(Ω1,meas) over the steady window,
//!   dimensionless; 0 is a perfect fit, ≈ 1 is no better than predicting zero,
//!   ≈ √2 is two uncorrelated signals of equal size (a phase drift between two
//!   equal limit cycles ends there).

use crate::{ClassifyOptions, SweepError, classify};
use rayon::prelude::*;
use rig_model::{SimOptions, friction_coefficient, simulate};
use rig_types::sensor::{ForceCal, SPEED_HALF_WINDOW_S, encoder_speed_rad_s, force_n, quantised_speed_rad_s};
use rig_types::units::RAD_S_TO_RPM;
use rig_types::{
    Campaign, FigureSpec, FrictionLaw, RigParams, Run, RunInput, RunKind, Series, SeriesStyle, Table, fmt_fixed,
};

/// Most points a figure series gets (the common rules allow ~2000).
const MAX_POINTS: usize = 2000;
/// Overlays keep half that: 40 s at ≤ 1000 points is one point per ≤ 42 ms,
/// ~25 per 1 s slip phase, and 30 overlays stay small in the snapshots.
const OVERLAY_POINTS: usize = 1000;

/// What one model (or the measurement) shows in the steady window.
#[derive(Debug, Clone)]
struct Summary {
    stick_slip: bool,
    min_rpm: f64,
    max_rpm: f64,
    /// `None` for the measurement itself.
    nrmse: Option<f64>,
}

#[derive(Debug, Clone)]
struct RunResult {
    id: String,
    setpoint_rpm: f64,
    normal_force_n: f64,
    time_s: Vec<f64>,
    measured_rad_s: Vec<f64>,
    thesis_rad_s: Vec<f64>,
    rig_rad_s: Vec<f64>,
    measured: Summary,
    thesis: Summary,
    rig: Summary,
}

/// The misfit table and every figure of the study.
pub struct MisfitOutput {
    /// tables/campaign-simulation-misfit.csv.
    pub table: Table,
    /// One overlay per run, Fig. 4.15, Figs. 4.17a/b.
    pub figures: Vec<FigureSpec>,
}

/// Both models on every operating point of `campaign` (at the recording's
/// sample times), the friction laws against the measured μ (force sensor
/// through `force`), and the limit cycles over the last `limit_cycle_s`.
pub fn misfit_study(
    campaign: &Campaign,
    thesis: &RigParams,
    rig: &RigParams,
    force: ForceCal,
    opts: &SimOptions,
    classify: &ClassifyOptions,
    limit_cycle_s: f64,
) -> Result<MisfitOutput, SweepError> {
    let ticks_per_rev = campaign.rig.encoder_ticks_per_rev;
    let radius_m = campaign.rig.brake_disc_radius_m;
    let runs: Vec<&Run> = campaign.runs_of("operating_point").collect();
    if runs.is_empty() {
        return Err(SweepError::Analysis(format!("campaign {} has no operating_point run to simulate", campaign.name)));
    }
    // Parallel over runs; collect keeps campaign order, so outputs do not depend on threads.
    let results: Vec<RunResult> = runs
        .par_iter()
        .map(|r| compare_run(r, thesis, rig, opts, classify, ticks_per_rev))
        .collect::<Result<_, _>>()?;
    let mut figures: Vec<FigureSpec> = results.iter().map(overlay_figure).collect();
    let measured_mu = measured_friction_points(&runs, force, radius_m, ticks_per_rev);
    figures.push(friction_figure(thesis, rig, measured_mu));
    // The limit cycles start from rest with the campaign's ramp.
    let ramp_s = crate::operating::RunProtocol::of_campaign(campaign).map_or(0.0, |p| p.ramp_s);
    for (id, rpm, n) in [("fig-4-17a", 54.5, 4.5), ("fig-4-17b", 122.0, 25.0)] {
        figures.push(limit_cycle_figure(id, (rpm, n, ramp_s), thesis, rig, opts, limit_cycle_s)?);
    }
    Ok(MisfitOutput { table: misfit_table(&results), figures })
}

fn input_of(run: &Run) -> Result<RunInput, SweepError> {
    match run.kind {
        RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } => {
            Ok(RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s })
        }
        _ => Err(SweepError::Analysis(format!("run {} is not an operating_point", run.id))),
    }
}

/// Sample range of the steady window (see the module docs).
fn steady_window(time_s: &[f64]) -> std::ops::Range<usize> {
    let t_end = time_s.last().copied().unwrap_or(0.0);
    let start = time_s.partition_point(|&t| t < t_end / 2.0);
    let end = time_s.partition_point(|&t| t <= t_end - 2.0 * SPEED_HALF_WINDOW_S);
    start..end.max(start + 1).min(time_s.len())
}

/// The window's extremes, the classifier's stick-slip verdict at `fs_hz` and
/// the NRMSE against `reference`.
fn summarise(
    speed: &[f64],
    window: std::ops::Range<usize>,
    fs_hz: f64,
    o: &ClassifyOptions,
    reference: Option<&[f64]>,
) -> Summary {
    let w = &speed[window.clone()];
    let min = w.iter().copied().fold(f64::INFINITY, f64::min);
    let max = w.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let stick_slip = classify(w, fs_hz, o).regime.stick_slip();
    let nrmse = reference.map(|m| {
        let m = &m[window.clone()];
        let num = w.iter().zip(m).map(|(s, x)| (s - x).powi(2)).sum::<f64>();
        let den = m.iter().map(|x| x * x).sum::<f64>();
        (num / den).sqrt()
    });
    Summary { stick_slip, min_rpm: min * RAD_S_TO_RPM, max_rpm: max * RAD_S_TO_RPM, nrmse }
}

fn compare_run(
    run: &Run,
    thesis: &RigParams,
    rig: &RigParams,
    opts: &SimOptions,
    o: &ClassifyOptions,
    tpr: u32,
) -> Result<RunResult, SweepError> {
    let input = input_of(run)?;
    let RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, .. } = input else { unreachable!() };
    let time_s = run.data.time_s.clone();
    let ticks = run
        .data
        .rotor_ticks
        .as_ref()
        .ok_or_else(|| SweepError::Analysis(format!("run {}: no rotor_ticks column", run.id)))?;
    let measured = encoder_speed_rad_s(&time_s, ticks, tpr);
    let simulated = |p: &RigParams, which: &str| -> Result<Vec<f64>, SweepError> {
        let tr = simulate(p, &input, &time_s, opts)
            .map_err(|e| SweepError::Analysis(format!("run {}: {which} model: {e}", run.id)))?;
        Ok(quantised_speed_rad_s(&time_s, &tr.rotor_angle_rad, tpr))
    };
    let thesis_speed = simulated(thesis, "thesis")?;
    let rig_speed = simulated(rig, "rig")?;
    let window = steady_window(&time_s);
    let fs = (time_s.len().max(2) - 1) as f64 / (time_s[time_s.len() - 1] - time_s[0]).max(f64::MIN_POSITIVE);
    Ok(RunResult {
        id: run.id.clone(),
        setpoint_rpm: motor_rpm_setpoint,
        normal_force_n,
        measured: summarise(&measured, window.clone(), fs, o, None),
        thesis: summarise(&thesis_speed, window.clone(), fs, o, Some(&measured)),
        rig: summarise(&rig_speed, window, fs, o, Some(&measured)),
        time_s,
        measured_rad_s: measured,
        thesis_rad_s: thesis_speed,
        rig_rad_s: rig_speed,
    })
}

fn misfit_table(results: &[RunResult]) -> Table {
    let mut t = Table::new([
        "run",
        "motor_rpm_setpoint",
        "normal_force_n",
        "measured_stick_slip",
        "measured_rotor_rpm_min",
        "measured_rotor_rpm_max",
        "thesis_stick_slip",
        "thesis_rotor_rpm_min",
        "thesis_rotor_rpm_max",
        "thesis_nrmse",
        "rig_stick_slip",
        "rig_rotor_rpm_min",
        "rig_rotor_rpm_max",
        "rig_nrmse",
    ]);
    let yes = |b: bool| if b { "yes" } else { "no" }.to_string();
    for r in results {
        let mut row = vec![r.id.clone(), fmt_fixed(r.setpoint_rpm, 1), fmt_fixed(r.normal_force_n, 2)];
        for s in [&r.measured, &r.thesis, &r.rig] {
            // One decimal of rpm: the differentiator resolves 0.157 rad/s = 1.5 rpm per tick,
            // averaged down by its moving average.
            row.extend([yes(s.stick_slip), fmt_fixed(s.min_rpm, 1), fmt_fixed(s.max_rpm, 1)]);
            if let Some(e) = s.nrmse {
                row.push(fmt_fixed(e, 3));
            }
        }
        t.push(row);
    }
    t
}

/// Every k-th sample so that a series keeps at most [`OVERLAY_POINTS`] points.
fn decimate(x: &[f64]) -> Vec<f64> {
    let stride = x.len().div_ceil(OVERLAY_POINTS).max(1);
    x.iter().step_by(stride).copied().collect()
}

fn rpm(x: &[f64]) -> Vec<f64> {
    x.iter().map(|v| v * RAD_S_TO_RPM).collect()
}

fn overlay_figure(r: &RunResult) -> FigureSpec {
    let t = decimate(&r.time_s);
    let series = |name: &str, y: &[f64], style| Series { name: name.into(), x: t.clone(), y: decimate(&rpm(y)), style };
    FigureSpec {
        id: format!("overlay-{}", r.id),
        title: format!(
            "Run {}: rotor speed, measured and simulated ({} rpm, {} N)",
            r.id,
            fmt_fixed(r.setpoint_rpm, 1),
            fmt_fixed(r.normal_force_n, 2)
        ),
        caption: format!(
            "Rotor-1 speed of operating point {} (motor set-point {} rpm, normal force {} N): measured \
             (rotor encoder through the calibration differentiator, ±20 ms central difference and moving \
             average), the thesis model as published (Table 4.5, n = 1, Eq. 4-10 lookup) and the rig model \
             (data/rig-params.json), both simulated from rest at the recording's sample times and passed \
             through the same encoder model and differentiator. NRMSE over the second half: thesis {}, rig {}. \
             Every {}-th sample shown.",
            r.id,
            fmt_fixed(r.setpoint_rpm, 1),
            fmt_fixed(r.normal_force_n, 2),
            fmt_fixed(r.thesis.nrmse.unwrap_or(f64::NAN), 3),
            fmt_fixed(r.rig.nrmse.unwrap_or(f64::NAN), 3),
            r.time_s.len().div_ceil(OVERLAY_POINTS).max(1)
        ),
        x_label: "time [s]".into(),
        y_label: "rotor speed [rpm]".into(),
        series: vec![
            series("measured", &r.measured_rad_s, SeriesStyle::Line),
            series("thesis model", &r.thesis_rad_s, SeriesStyle::Dashed),
            series("rig model", &r.rig_rad_s, SeriesStyle::Line),
        ],
        x_decimals: 3,
        // 0.1 rpm: the differentiator's one-tick step (1.5 rpm) averaged over 21 samples is 0.07 rpm.
        y_decimals: 1,
        heatmap: None,
    }
}

/// Measured μ = T1 / (N0 r) against rotor rpm in every run's steady window
/// (force sensor through the campaign calibration), thinned to MAX_POINTS.
fn measured_friction_points(runs: &[&Run], cal: ForceCal, radius_m: f64, tpr: u32) -> Option<Series> {
    let mut x = Vec::new();
    let mut y = Vec::new();
    for run in runs {
        let RunKind::OperatingPoint { normal_force_n, .. } = run.kind else { continue };
        let (Some(ticks), Some(force)) = (&run.data.rotor_ticks, &run.data.brake_force_mv) else { continue };
        if normal_force_n <= 0.0 {
            continue;
        }
        let speed = encoder_speed_rad_s(&run.data.time_s, ticks, tpr);
        let torque: Vec<f64> = force_n(force, cal).iter().map(|f| f * radius_m).collect();
        for k in steady_window(&run.data.time_s) {
            x.push(speed[k] * RAD_S_TO_RPM);
            y.push(torque[k] / (normal_force_n * radius_m));
        }
    }
    if x.is_empty() {
        return None;
    }
    let stride = x.len().div_ceil(MAX_POINTS).max(1);
    Some(Series {
        name: "measured T1/(N r), steady windows".into(),
        x: x.iter().step_by(stride).copied().collect(),
        y: y.iter().step_by(stride).copied().collect(),
        style: SeriesStyle::Points,
    })
}

fn friction_figure(thesis: &RigParams, rig: &RigParams, measured: Option<Series>) -> FigureSpec {
    // Fine grid near zero, where the published lookup has its set-points (0.05 and 0.5 rpm).
    let mut grid_rpm: Vec<f64> = (-200..=100).map(|k| f64::from(k) * 0.01).collect();
    grid_rpm.extend((11..=150).map(f64::from));
    let law = |l: &FrictionLaw| grid_rpm.iter().map(|&w| friction_coefficient(l, w / RAD_S_TO_RPM)).collect();
    let mut series = vec![
        Series {
            name: "thesis model (Eq. 4-10, Table 4.7)".into(),
            x: grid_rpm.clone(),
            y: law(&thesis.friction),
            style: SeriesStyle::Line,
        },
        Series {
            name: "rig model, slip μ(|Ω1|)".into(),
            x: grid_rpm.clone(),
            y: law(&rig.friction),
            style: SeriesStyle::Dashed,
        },
    ];
    let mu_static = match &rig.friction {
        FrictionLaw::Thesis(f) => f.mu_static,
        FrictionLaw::Coulomb { mu_static, .. }
        | FrictionLaw::Stribeck { mu_static, .. }
        | FrictionLaw::Viscous { mu_static, .. } => *mu_static,
    };
    series.push(Series {
        name: "rig model, static μs (stick phase)".into(),
        x: vec![0.0],
        y: vec![mu_static],
        style: SeriesStyle::Markers,
    });
    series.extend(measured);
    FigureSpec {
        id: "fig-4-15".into(),
        title: "Friction coefficient against rotor speed: thesis and rig models".into(),
        caption: "Brake friction coefficient μ = T1 / (N r) against rotor-1 speed. Thesis model: Eq. 4-10 with \
                  Table 4.7 read as a lookup over rotor rpm (μneg for Ω1 ≤ 0, linear to μst at 0.05 rpm and to \
                  μdyn at 0.5 rpm; see rig-model's crate docs for why), signed and without a stick phase. Rig \
                  model: the slip law of data/rig-params.json, symmetric in the sign of Ω1, and its static \
                  coefficient μs that holds the rotor while |shaft torque| ≤ μs N r. Points: the measured ratio \
                  of force-sensor torque (campaign calibration) to N0 r in the second half of every operating \
                  point, thinned to at most 2000 points."
            .into(),
        x_label: "rotor speed [rpm]".into(),
        y_label: "friction coefficient μ [-]".into(),
        series,
        x_decimals: 2,
        y_decimals: 4,
        heatmap: None,
    }
}

/// Phase portrait (twist φ2 − φ1, rotor rpm) of both models over the last
/// `window_s` of a 3·window_s run from rest, sampled at MAX_POINTS / window_s Hz.
fn limit_cycle_figure(
    id: &str,
    (setpoint_rpm, normal_force_n, ramp_s): (f64, f64, f64),
    thesis: &RigParams,
    rig: &RigParams,
    opts: &SimOptions,
    window_s: f64,
) -> Result<FigureSpec, SweepError> {
    let t_end = 3.0 * window_s;
    let dt = window_s / (MAX_POINTS - 1) as f64;
    let t: Vec<f64> = (0..MAX_POINTS).map(|k| t_end - window_s + k as f64 * dt).collect();
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: setpoint_rpm, normal_force_n, ramp_s };
    let mut series = Vec::new();
    let mut ranges = Vec::new();
    for (name, p, style) in [("thesis model", thesis, SeriesStyle::Dashed), ("rig model", rig, SeriesStyle::Line)] {
        let tr = simulate(p, &input, &t, opts).map_err(|e| SweepError::Analysis(format!("{id}: {name}: {e}")))?;
        let twist = tr.motor_angle_rad.iter().zip(&tr.rotor_angle_rad).map(|(a, b)| a - b).collect();
        let y = rpm(&tr.rotor_speed_rad_s);
        let (lo, hi) =
            (y.iter().copied().fold(f64::INFINITY, f64::min), y.iter().copied().fold(f64::NEG_INFINITY, f64::max));
        let stuck = tr.stuck.iter().filter(|s| **s).count() as f64 / tr.len() as f64;
        ranges.push(format!(
            "{name}: rotor speed {} to {} rpm, stuck {} % of the window",
            fmt_fixed(lo, 2),
            fmt_fixed(hi, 2),
            fmt_fixed(100.0 * stuck, 1)
        ));
        series.push(Series { name: name.into(), x: twist, y, style });
    }
    Ok(FigureSpec {
        id: id.into(),
        title: format!("Limit cycle at {setpoint_rpm} rpm and {normal_force_n} N: thesis and rig models"),
        caption: format!(
            "Phase portrait of rotor-1 speed against shaft twist φ2 − φ1 for motor set-point {setpoint_rpm} rpm \
             and normal force {normal_force_n} N (the operating points of the thesis' Fig. 4.17), simulated from \
             rest with a {ramp_s} s ramp (the campaign's) for {t_end} s; the last {window_s} s are shown, sampled every {} ms from the \
             integrator's dense output (model speed, no encoder). Thesis model: Table 4.5, n = 1, Eq. 4-10 \
             lookup, PI gains of the rig. Rig model: data/rig-params.json. In the window: {}. A model \
             that settles to steady sliding shows a point or an inward spiral, not a limit cycle.",
            fmt_fixed(dt * 1e3, 2),
            ranges.join("; ")
        ),
        x_label: "twist φ2 − φ1 [rad]".into(),
        y_label: "rotor speed [rpm]".into(),
        series,
        x_decimals: 4,
        y_decimals: 2,
        heatmap: None,
    })
}
