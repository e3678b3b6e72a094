//! Operating points: a campaign run (or a labelled point of the chapter)
//! classified from its recording and from both models simulated from rest
//! with the recording's ramp at the recording's sample times.
//!
//! Signal path: measured ticks and simulated angles go through the same
//! sensor chain (`rig_types::sensor`: encoder quantisation to
//! `encoder_ticks_per_rev`, then the documented ±20 ms differentiator), so
//! measured and simulated windows see the same quantisation and filter before
//! the same classifier. The window is the last `window_s` of the record minus
//! the differentiator's 40 ms edge (18 s after a 2 s ramp in the shipped
//! campaign's 40 s records). The chapter's labelled points are simulated with
//! the campaign's own protocol ([`RunProtocol::of_campaign`]: its sample rate,
//! its operating points' ramp and length), never an assumed one.

use crate::{Classification, Point, SweepError, SweepSettings, classify};
use rig_model::simulate;
use rig_types::sensor::{SPEED_HALF_WINDOW_S, encoder_speed_rad_s, quantised_speed_rad_s};
use rig_types::{Campaign, RigParams, Run, RunInput, RunKind};

/// A campaign run classified from its recording and from both models.
#[derive(Debug, Clone)]
pub struct OpPoint {
    pub id: String,
    pub point: Point,
    pub measured: Classification,
    pub thesis: Classification,
    pub rig: Classification,
}

/// A labelled point of the chapter (Figs. 4.17, 4.19, 4.21–4.24), as read
/// from the thesis tables.
#[derive(Debug, Clone)]
pub struct LabelledPoint {
    /// `fig-<figure><panel>`.
    pub id: String,
    pub point: Point,
    /// `vibrating` or `quiet`.
    pub label: String,
    pub source: String,
}

/// A labelled point with both models simulated from rest.
#[derive(Debug, Clone)]
pub struct Labelled {
    pub point: LabelledPoint,
    pub thesis: Classification,
    pub rig: Classification,
}

/// Samples of the classification window: last `window_s` before the differentiator's edge.
fn window_range(time_s: &[f64], window_s: f64) -> std::ops::Range<usize> {
    let t_end = time_s.last().copied().unwrap_or(0.0) - 2.0 * SPEED_HALF_WINDOW_S;
    let start = time_s.partition_point(|&t| t < t_end - window_s);
    let end = time_s.partition_point(|&t| t <= t_end);
    start..end.max(start)
}

/// Classifies the window of a speed record sampled at `time_s`.
pub fn classify_record(time_s: &[f64], speed_rad_s: &[f64], s: &SweepSettings) -> Classification {
    let w = window_range(time_s, s.window.window_s);
    let fs = (time_s.len().max(2) - 1) as f64 / (time_s[time_s.len() - 1] - time_s[0]).max(f64::MIN_POSITIVE);
    classify(&speed_rad_s[w], fs, &s.classify)
}

fn simulated(
    p: &RigParams,
    input: &RunInput,
    time_s: &[f64],
    s: &SweepSettings,
    tpr: u32,
) -> Result<Classification, rig_model::ModelError> {
    let tr = simulate(p, input, time_s, &s.sim)?;
    Ok(classify_record(time_s, &quantised_speed_rad_s(time_s, &tr.rotor_angle_rad, tpr), s))
}

/// One `operating_point` run: measured, thesis model and rig model, classified.
pub fn op_point(run: &Run, th: &RigParams, rg: &RigParams, s: &SweepSettings, tpr: u32) -> Result<OpPoint, SweepError> {
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else {
        return Err(SweepError::Analysis(format!("run {} is not an operating_point", run.id)));
    };
    let ticks = run
        .data
        .rotor_ticks
        .as_ref()
        .ok_or_else(|| SweepError::Analysis(format!("run {}: no rotor_ticks column", run.id)))?;
    let time_s = &run.data.time_s;
    let input = RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s };
    let model = |p: &RigParams, which: &str| {
        simulated(p, &input, time_s, s, tpr)
            .map_err(|e| SweepError::Analysis(format!("run {}: {which} model: {e}", run.id)))
    };
    Ok(OpPoint {
        id: run.id.clone(),
        point: Point { motor_rpm: motor_rpm_setpoint, normal_force_n },
        measured: classify_record(time_s, &encoder_speed_rad_s(time_s, ticks, tpr), s),
        thesis: model(th, "thesis")?,
        rig: model(rg, "rig")?,
    })
}

/// How a campaign records its operating points, read from the campaign:
/// what a simulation "like a campaign run" must imitate.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunProtocol {
    /// The operating points' sample rate as their time columns measure it
    /// (`Campaign::clock_rate_hz`: campaign.toml's `sample_rate_hz` unless
    /// the columns disagree with it beyond `rig_types::sensor::CLOCK_TOLERANCE`), Hz.
    pub sample_rate_hz: f64,
    /// The longest operating-point record, s, from its time column (which is
    /// authoritative): its samples × its mean step.
    pub duration_s: f64,
    /// The median ramp of the operating points, s.
    pub ramp_s: f64,
}

impl RunProtocol {
    /// The protocol of `c`'s operating points; `None` without any.
    pub fn of_campaign(c: &Campaign) -> Option<Self> {
        let rate = c.clock_rate_hz("operating_point");
        let mut ramps = Vec::new();
        let mut duration_s = 0.0f64;
        for r in c.runs_of("operating_point") {
            if let RunKind::OperatingPoint { ramp_s, .. } = r.kind {
                ramps.push(ramp_s);
                duration_s = duration_s.max(record_length_s(&r.data.time_s, rate));
            }
        }
        if ramps.is_empty() || rate.is_nan() || rate <= 0.0 {
            return None;
        }
        ramps.sort_by(f64::total_cmp);
        Some(RunProtocol { sample_rate_hz: rate, duration_s, ramp_s: ramps[ramps.len() / 2] })
    }

    /// Sample times 0, 1/rate, … up to `duration_s` inclusive.
    pub fn times_s(&self) -> Vec<f64> {
        let n = (self.duration_s * self.sample_rate_hz).round() as usize;
        (0..=n).map(|k| k as f64 / self.sample_rate_hz).collect()
    }
}

/// A record's length, s: its n samples × its mean step (t_last − t_0)/(n − 1),
/// so a clock off the nominal rate keeps the record's seconds; one sample
/// lasts 1/`nominal_rate_hz`.
fn record_length_s(time_s: &[f64], nominal_rate_hz: f64) -> f64 {
    match time_s {
        [] => 0.0,
        [_] => 1.0 / nominal_rate_hz,
        [first, .., last] => {
            let n = time_s.len() as f64;
            n * (last - first) / (n - 1.0)
        }
    }
}

/// A labelled point of the chapter simulated like a campaign run (the
/// campaign's sample rate, record length and ramp), encoder and differentiator.
pub fn from_rest(
    p: &RigParams,
    pt: Point,
    protocol: &RunProtocol,
    s: &SweepSettings,
    tpr: u32,
) -> Result<Classification, rig_model::ModelError> {
    let time_s = protocol.times_s();
    let input = RunInput::OperatingPoint {
        motor_rpm_setpoint: pt.motor_rpm,
        normal_force_n: pt.normal_force_n,
        ramp_s: protocol.ramp_s,
    };
    simulated(p, &input, &time_s, s, tpr)
}

/// Both models at each labelled point of the chapter.
pub fn labelled_points(
    labels: &[LabelledPoint],
    th: &RigParams,
    rg: &RigParams,
    protocol: &RunProtocol,
    s: &SweepSettings,
    tpr: u32,
) -> Result<Vec<Labelled>, SweepError> {
    let mut out = Vec::new();
    for l in labels {
        let at = |p: &RigParams, which: &str| {
            from_rest(p, l.point, protocol, s, tpr)
                .map_err(|e| SweepError::Analysis(format!("{which} model at {}: {e}", l.id)))
        };
        let thesis = at(th, "thesis")?;
        let rig = at(rg, "rig")?;
        out.push(Labelled { point: l.clone(), thesis, rig });
    }
    Ok(out)
}

/// The set-point and force of an operating-point run (NaN for other kinds).
fn condition(r: &Run) -> (f64, f64) {
    match r.kind {
        RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, .. } => (motor_rpm_setpoint, normal_force_n),
        _ => (f64::NAN, f64::NAN),
    }
}

/// Figs. 4.19a/b and 4.21a/b: the campaign runs nearest (range-normalised
/// distance over motor rpm and force) to the chapter's points; panel (b) may
/// not reuse panel (a)'s run, so the pair still contrasts two conditions.
/// `runs` must not be empty.
pub fn time_response_runs<'a>(runs: &[&'a Run]) -> Vec<(String, Point, &'a Run)> {
    let speeds: Vec<f64> = runs.iter().map(|r| condition(r).0).collect();
    let forces: Vec<f64> = runs.iter().map(|r| condition(r).1).collect();
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
                    let dist = |r: &Run| ((condition(r).0 - rpm) / sr).powi(2) + ((condition(r).1 - n) / fr).powi(2);
                    dist(x).total_cmp(&dist(y))
                })
                .expect("runs is not empty");
            used = Some(best.id.as_str());
            out.push((format!("{fig}{panel}"), Point { motor_rpm: rpm, normal_force_n: n }, *best));
        }
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;
    use rig_types::{RigInfo, Run, RunData};

    fn campaign(rate_declared_hz: f64, rate_true_hz: f64, samples: usize) -> Campaign {
        let run = Run {
            id: "op-1".into(),
            kind: RunKind::OperatingPoint { motor_rpm_setpoint: 40.0, normal_force_n: 5.0, ramp_s: 2.0 },
            file: "runs/op-1.csv".into(),
            data: RunData { time_s: (0..samples).map(|k| k as f64 / rate_true_hz).collect(), ..Default::default() },
        };
        Campaign {
            name: "c".into(),
            description: String::new(),
            rig: RigInfo {
                encoder_ticks_per_rev: 1000,
                brake_disc_radius_m: 0.062,
                supply_voltage_v: 24.0,
                sample_rate_hz: rate_declared_hz,
            },
            runs: vec![run],
        }
    }

    /// The time column is authoritative: 10 200 samples of a clock at 510 Hz
    /// declared 500 Hz last 20 s, not 20.4 s, sampled at 510 Hz.
    #[test]
    fn the_record_length_is_read_from_the_time_column() {
        let p = RunProtocol::of_campaign(&campaign(500.0, 510.0, 10_200)).unwrap();
        assert!((p.duration_s - 20.0).abs() < 1e-9, "{}", p.duration_s);
        // and the simulated grid is the records' clock, not the declaration.
        assert!((p.sample_rate_hz - 510.0).abs() < 1e-6, "{}", p.sample_rate_hz);
        // At the nominal rate the length is samples / rate, as before.
        let p = RunProtocol::of_campaign(&campaign(500.0, 500.0, 20_000)).unwrap();
        assert!((p.duration_s - 40.0).abs() < 1e-9, "{}", p.duration_s);
        assert_eq!(p.sample_rate_hz, 500.0);
        assert_eq!(p.times_s().len(), 20_001);
    }
}
