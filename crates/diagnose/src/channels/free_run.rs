//! Free-run checks of the operating points: a model (baseline or extended)
//! simulated from rest under the run's protocol and compared with the record
//! on phase-insensitive steady-state features.

use super::{ChannelCheck, ChannelOptions, rms};
use crate::DiagnoseOptions;
use crate::prepare::centred_speed;
use crate::result::Features;
use crate::select::steady_features;
use rig_model::SimOptions;
use rig_types::sensor::{half_window_samples, nominal_window_samples, tick_rad, ticks_to_rad};
use rig_types::{Campaign, RigParams, RunInput, RunKind};

/// What the free-run comparison needs from the diagnosis options.
#[derive(Debug, Clone, PartialEq)]
pub struct FreeRunSettings {
    pub settle_s: f64,
    pub steady_s: f64,
    pub slip_speed_rad_s: f64,
    pub rotor_speed_half_window_s: f64,
    pub motor_speed_half_window_s: f64,
    /// The regime classifier's thresholds (`[shared.classify]`).
    pub classify: rig_sweep::ClassifyOptions,
    /// `[shared.integrator]`.
    pub integrator: SimOptions,
}

impl FreeRunSettings {
    pub fn of(opts: &DiagnoseOptions, o: &ChannelOptions) -> Self {
        FreeRunSettings {
            settle_s: opts.settle_s,
            steady_s: o.free_run_steady_s,
            slip_speed_rad_s: opts.slip_speed_rad_s,
            rotor_speed_half_window_s: opts.rotor_speed_half_window_s,
            motor_speed_half_window_s: opts.motor_speed_half_window_s,
            classify: opts.classify.clone(),
            integrator: opts.integrator.clone(),
        }
    }
}

/// Measured and simulated features of one run over the same window, with
/// the window length.
#[derive(Debug, Clone)]
pub struct Pair {
    pub id: String,
    pub measured: Features,
    pub simulated: Option<Features>,
    pub window_s: f64,
    /// Rotor speed over the steady window, for the small-multiples figure.
    pub trace: Trace,
    /// One encoder tick over the motor-speed differentiator window,
    /// tick/(2h·dt), rad/s: the smallest motor-speed step (dip) it can show.
    pub motor_tick_rad_s: f64,
}

/// Ω1 over a run's steady window at about [`TRACE_RATE_HZ`] (every k-th
/// sample of the centred difference the features use), measured and simulated.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct Trace {
    pub time_s: Vec<f64>,
    pub measured_rad_s: Vec<f64>,
    pub simulated_rad_s: Option<Vec<f64>>,
}

/// Rate of a [`Trace`]: ten points per second of the fastest stick-slip
/// cycle the rig shows (periods 2-6 s) and then some.
pub const TRACE_RATE_HZ: f64 = 20.0;

/// One [`Pair`] per operating point of `c` with model `p` (one simulation per
/// run over ramp + settle + `steady_s` only, in parallel, campaign order kept;
/// `simulated` is `None` where the integrator failed — data, not an error).
pub fn free_run_pairs(c: &Campaign, p: &RigParams, s: &FreeRunSettings) -> Vec<Pair> {
    free_run_pairs_by(c, s, |_| Some(p.clone()))
}

/// [`free_run_pairs`] with each run's own model: `params_of(run id)`, runs
/// for which it gives `None` are skipped (a cross-validation fold's held-out
/// runs, each with the model fitted without them).
pub fn free_run_pairs_by(
    c: &Campaign,
    s: &FreeRunSettings,
    params_of: impl Fn(&str) -> Option<RigParams> + Sync,
) -> Vec<Pair> {
    use rayon::prelude::*;
    let runs: Vec<&rig_types::Run> = c.runs_of("operating_point").collect();
    runs.par_iter()
        .map(|r| params_of(&r.id).and_then(|p| pair(c, r, &p, s)))
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// The speed resolution of the centred difference, tick/(2h·dt)/√6, rad/s:
/// the noise floor of a rotor-speed extremum.
pub fn speed_floor_rad_s(c: &Campaign, s: &FreeRunSettings) -> f64 {
    tick_rad(c.rig.encoder_ticks_per_rev)
        / (2.0 * nominal_window_samples(s.rotor_speed_half_window_s, c.rig.sample_rate_hz) as f64
            / c.rig.sample_rate_hz)
        / 6f64.sqrt()
}

/// Free-run misfit of one run (crate docs, "The free-run misfit"):
/// M_fr = sqrt(1 + mean(e²)) over the feature errors in units of their
/// floors — e_max, e_min: measured − simulated extreme of Ω1 over the speed
/// resolution `floor_rad_s`; e_f: the relative error of the stick-slip
/// fundamental over the window's relative Rayleigh resolution 1/(T·f), when
/// both record and simulation stick and slip. The 1 is the floor itself (a
/// model at the noise scores ≈ 1.4, never 0, so ln ratios stay finite).
/// `None` when the simulation failed.
pub fn free_run_misfit(q: &Pair, floor_rad_s: f64) -> Option<f64> {
    let f = q.simulated?;
    let m = &q.measured;
    let mut e2 = vec![
        ((m.rotor_max_rad_s - f.rotor_max_rad_s) / floor_rad_s).powi(2),
        ((m.rotor_min_rad_s - f.rotor_min_rad_s) / floor_rad_s).powi(2),
    ];
    if m.stick_slip() && f.stick_slip() && m.fundamental_hz > 0.0 {
        e2.push(((m.fundamental_hz - f.fundamental_hz) * q.window_s).powi(2));
    }
    Some((1.0 + e2.iter().sum::<f64>() / e2.len() as f64).sqrt())
}

/// Features of one run: measured from the encoders and simulated with `p`,
/// both through the same centred difference (the diagnosis' speed operator,
/// so the smoothing of the extrema is the same on both sides).
fn pair(c: &Campaign, run: &rig_types::Run, p: &RigParams, s: &FreeRunSettings) -> Option<Pair> {
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else { return None };
    let t = &run.data.time_s;
    let from = t.partition_point(|&x| x < ramp_s + s.settle_s);
    let to = t.partition_point(|&x| x < ramp_s + s.settle_s + s.steady_s);
    if to < from + 16 {
        return None;
    }
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    let phi1 = ticks_to_rad(&run.data.rotor_ticks.as_ref()?[..to], c.rig.encoder_ticks_per_rev);
    let phi2 = ticks_to_rad(&run.data.motor_ticks.as_ref()?[..to], c.rig.encoder_ticks_per_rev);
    let tt = &t[..to];
    let w_set = rig_types::units::rpm_to_rad_s(motor_rpm_setpoint);
    let dt = (tt[to - 1] - tt[0]) / (to - 1) as f64;
    let stride = ((1.0 / (TRACE_RATE_HZ * dt)).round() as usize).max(1);
    let (h1, h2) =
        (half_window_samples(tt, s.rotor_speed_half_window_s), half_window_samples(tt, s.motor_speed_half_window_s));
    let feat = |a1: &[f64], a2: &[f64]| {
        let w1 = centred_speed(tt, a1, h1);
        let w2 = centred_speed(tt, a2, h2);
        let f = steady_features(&tt[from..], &w1[from..], &w2[from..], w_set, s.slip_speed_rad_s, &s.classify);
        (f, w1[from..].iter().step_by(stride).copied().collect::<Vec<f64>>())
    };
    let (measured, measured_rad_s) = feat(&phi1, &phi2);
    let input = RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s };
    let sim =
        rig_model::simulate(p, &input, tt, &s.integrator).ok().map(|tr| feat(&tr.rotor_angle_rad, &tr.motor_angle_rad));
    let (simulated, simulated_rad_s) = sim.map_or((None, None), |(f, w)| (Some(f), Some(w)));
    let trace = Trace { time_s: tt[from..].iter().step_by(stride).copied().collect(), measured_rad_s, simulated_rad_s };
    let motor_tick_rad_s = rad / (2.0 * h2 as f64 * dt);
    Some(Pair { id: run.id.clone(), measured, simulated, window_s: tt[to - 1] - tt[from], trace, motor_tick_rad_s })
}

/// Each operating point's measured rotor speed with the baseline's and the
/// extended model's free runs (pairs of [`free_run_pairs`], matched by run id).
pub fn speed_traces(baseline: &[Pair], extended: &[Pair]) -> Vec<crate::result::SpeedTraces> {
    baseline
        .iter()
        .map(|b| crate::result::SpeedTraces {
            id: b.id.clone(),
            time_s: b.trace.time_s.clone(),
            measured_rad_s: b.trace.measured_rad_s.clone(),
            baseline_rad_s: b.trace.simulated_rad_s.clone(),
            extended_rad_s: extended.iter().find(|e| e.id == b.id).and_then(|e| e.trace.simulated_rad_s.clone()),
        })
        .collect()
}

/// The four free-run checks of model `p` (one simulation per operating point,
/// over ramp + settle + `steady_s` only, in parallel, campaign order kept).
///
/// The thesis compares measured and simulated motion on the same features
/// (Figs. 4.16–4.29: regime, rotor speed range, stick-slip frequency); the
/// features are [`steady_features`], the one definition the per-run table uses:
/// - regime: runs where one side sticks-and-slips and the other does not
///   (floor: one run, the boundary of the severity map being uncertain);
/// - rotor_max / rotor_min: RMS over the runs of measured − simulated extreme
///   of Ω1, rad/s; floor: the speed resolution of the centred difference,
///   tick/(2h·dt)/√6;
/// - fundamental: RMS over the runs that stick-slip on both sides of the
///   relative error of the stick-slip frequency; floor: the relative Rayleigh
///   resolution 1/(T·f) of the window, RMS over those runs.
///
/// Extrema and fundamental over a window of many cycles do not depend on the
/// phases of a modulation, which [`super::extended_params`] sets to 0.
pub fn free_run_checks(c: &Campaign, p: &RigParams, s: &FreeRunSettings, o: &ChannelOptions) -> Vec<ChannelCheck> {
    free_run_checks_of(c, &free_run_pairs(c, p, s), s, o)
}

/// The four free-run checks of pairs already simulated ([`free_run_pairs`]).
pub fn free_run_checks_of(c: &Campaign, pairs: &[Pair], s: &FreeRunSettings, o: &ChannelOptions) -> Vec<ChannelCheck> {
    let names = [
        "operating_point.regime",
        "operating_point.rotor_max",
        "operating_point.rotor_min",
        "operating_point.fundamental",
    ];
    let ids: Vec<String> = pairs.iter().map(|q| q.id.clone()).collect();
    let failed: Vec<&str> = pairs.iter().filter(|q| q.simulated.is_none()).map(|q| q.id.as_str()).collect();
    let ok: Vec<(&Pair, Features)> = pairs.iter().filter_map(|q| q.simulated.map(|f| (q, f))).collect();
    if ok.is_empty() {
        return names
            .iter()
            .map(|ch| ChannelCheck::not_testable(ch, ids.clone(), "no operating point simulated".into()))
            .collect();
    }
    let fail_note = if failed.is_empty() { String::new() } else { format!("; not integrated: {}", failed.join(", ")) };
    let mut out = Vec::new();

    let differ: Vec<&str> =
        ok.iter().filter(|(q, f)| q.measured.stick_slip() != f.stick_slip()).map(|(q, _)| q.id.as_str()).collect();
    out.push(ChannelCheck::new(
        names[0],
        ids.clone(),
        differ.len() as f64,
        1.0,
        o.regime_ratio,
        format!(
            "{} of {} runs change regime (stick-slip ↔ pure slip) in the simulation: {}{fail_note}",
            differ.len(),
            ok.len(),
            differ.join(", ")
        ),
    ));

    let floor = speed_floor_rad_s(c, s);
    for (name, th, get) in [
        (names[1], o.rotor_max_ratio, (|f: &Features| f.rotor_max_rad_s) as fn(&Features) -> f64),
        (names[2], o.rotor_min_ratio, |f: &Features| f.rotor_min_rad_s),
    ] {
        let d: Vec<f64> = ok.iter().map(|(q, f)| get(&q.measured) - get(f)).collect();
        let worst = ok
            .iter()
            .zip(&d)
            .max_by(|a, b| a.1.abs().total_cmp(&b.1.abs()))
            .map(|((q, f), _)| format!("{} measured {:.2}, simulated {:.2} rad/s", q.id, get(&q.measured), get(f)))
            .unwrap_or_default();
        let bias = d.iter().sum::<f64>() / d.len() as f64;
        out.push(ChannelCheck::new(
            name,
            ids.clone(),
            rms(&d),
            floor,
            th,
            format!("measured − simulated: RMS {:.3} rad/s, mean {bias:+.3} rad/s; worst {worst}{fail_note}", rms(&d)),
        ));
    }

    let both: Vec<(&Pair, Features)> = ok
        .iter()
        .filter(|(q, f)| q.measured.stick_slip() && f.stick_slip() && q.measured.fundamental_hz > 0.0)
        .map(|(q, f)| (*q, *f))
        .collect();
    if both.is_empty() {
        out.push(ChannelCheck::not_testable(
            names[3],
            ids,
            "no run sticks and slips in both record and simulation".into(),
        ));
    } else {
        let rel: Vec<f64> = both
            .iter()
            .map(|(q, f)| (q.measured.fundamental_hz - f.fundamental_hz) / q.measured.fundamental_hz)
            .collect();
        let res: Vec<f64> = both.iter().map(|(q, _)| 1.0 / (q.window_s * q.measured.fundamental_hz)).collect();
        let rows: Vec<String> = both
            .iter()
            .map(|(q, f)| format!("{} {:.2}/{:.2} Hz", q.id, q.measured.fundamental_hz, f.fundamental_hz))
            .collect();
        out.push(ChannelCheck::new(
            names[3],
            both.iter().map(|(q, _)| q.id.clone()).collect(),
            rms(&rel),
            rms(&res),
            o.fundamental_ratio,
            format!("stick-slip fundamental measured/simulated: {}", rows.join(", ")),
        ));
    }
    out
}
