//! The recorded side measured once per campaign, and each run's model
//! side simulated and measured beside it (the pairs the misfit and the
//! checks read).

use super::*;

/// What [`pair`] reads from one run's record alone, the same for every model
/// simulated against it: built once per run ([`MeasuredRuns`]) and shared by
/// the baseline's, the extended and the final model's free runs.
#[derive(Debug, Clone)]
pub struct MeasuredRun {
    pub(super) id: String,
    pub(super) normal_force_n: f64,
    pub(super) input: RunInput,
    pub(super) from: usize,
    pub(super) to: usize,
    pub(super) h1: usize,
    pub(super) h2: usize,
    pub(super) dt: f64,
    pub(super) stride: usize,
    pub(super) regime_from: usize,
    pub(super) measured: Features,
    pub(super) window_measured: Features,
    /// Whether the friction-level features are read (force law, force channel, N0 > 0).
    pub(super) has_force: bool,
    pub(super) has_voltage: bool,
    pub(super) channels_measured: ChannelFeatures,
    pub(super) floors: ChannelFeatures,
    pub(super) measured_trace: Vec<f64>,
    /// The record's dwell row ([`dwell_of`]; `None` without a force channel).
    pub(super) dwell: Option<DwellRow>,
}

/// Every operating point's [`MeasuredRun`] of one campaign under one set of
/// [`FreeRunSettings`], campaign order kept (`None`: a run [`pair`] skips).
#[derive(Debug, Clone)]
pub struct MeasuredRuns {
    pub(super) runs: Vec<Option<MeasuredRun>>,
    pub(super) settings: FreeRunSettings,
}

impl MeasuredRuns {
    /// The record's side of every operating point of `c` (in parallel).
    pub fn of(c: &Campaign, s: &FreeRunSettings) -> Self {
        use rayon::prelude::*;
        let runs: Vec<&rig_types::Run> = c.runs_of("operating_point").collect();
        MeasuredRuns { runs: runs.par_iter().map(|r| measure(c, r, s)).collect(), settings: s.clone() }
    }
}

/// [`free_run_pairs_by`] against records already measured with the same
/// settings (`m` from [`MeasuredRuns::of`] with `s`): only the simulations
/// run; the pairs are the same to the bit.
pub fn free_run_pairs_measured(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    params_of: impl Fn(&str) -> Option<RigParams> + Sync,
) -> Vec<Pair> {
    pairs_where(c, s, m, |r, mr| params_of(&r.id).map(|p| simulate_pair(c, r, mr, &p, s, Reads::All)))
}

/// [`free_run_pairs_measured`] beside pairs already simulated: a run whose
/// model is `known_model` to the bit ([`same_model`]) takes its pair from
/// `known` (`known_model`'s pairs from [`free_run_pairs_measured`] with the
/// same `c`, `s`, `m`: the same simulation of the same record, so the same
/// pair to the bit); only the others are simulated. The diagnosis' extended
/// model is the baseline on every run that no finding moves (a null, a
/// structural fault, an `outside` case, a missed rung): its free runs are
/// the baseline's.
pub fn free_run_pairs_reusing(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    params_of: impl Fn(&str) -> Option<RigParams> + Sync,
    known_model: &RigParams,
    known: &[Pair],
) -> Vec<Pair> {
    pairs_where(c, s, m, |r, mr| {
        let p = params_of(&r.id)?;
        match known.iter().find(|q| q.id == r.id) {
            Some(q) if same_model(&p, known_model) => Some(q.clone()),
            _ => Some(simulate_pair(c, r, mr, &p, s, Reads::All)),
        }
    })
}

/// Whether two models are the same to the bit: equal, and spelt alike (so
/// +0 and −0 differ; a NaN is equal to nothing). Every field of a
/// [`RigParams`] is a number, an enum or a list of them.
pub(super) fn same_model(a: &RigParams, b: &RigParams) -> bool {
    a == b && format!("{a:?}") == format!("{b:?}")
}

/// Each operating point's pair by `pair_of(run, its record)` (in parallel;
/// campaign order kept; runs it gives `None` for, or with no measured
/// record, skipped).
fn pairs_where(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    pair_of: impl Fn(&rig_types::Run, &MeasuredRun) -> Option<Pair> + Sync,
) -> Vec<Pair> {
    use rayon::prelude::*;
    assert!(m.settings == *s, "free-run pairs: records measured under other settings");
    let runs: Vec<&rig_types::Run> = c.runs_of("operating_point").collect();
    assert_eq!(runs.len(), m.runs.len(), "free-run pairs: records of another campaign");
    runs.par_iter()
        .zip(&m.runs)
        .map(|(r, mr)| {
            let mr = mr.as_ref()?;
            debug_assert_eq!(mr.id, r.id);
            pair_of(r, mr)
        })
        .collect::<Vec<_>>()
        .into_iter()
        .flatten()
        .collect()
}

/// [`free_run_misfit`] of the run `id` simulated with `p`, against its
/// record measured under `s` (`m` from [`MeasuredRuns::of`] with `s`): the
/// same value to the bit as [`free_run_pairs_measured`]'s pair gives, without
/// the features that misfit does not read (the force's, the break-away
/// peaks, the dwell row). `None` where that pair would be missing or have no
/// misfit.
pub fn free_run_misfit_measured(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    id: &str,
    p: &RigParams,
    floor_rad_s: f64,
) -> Option<f64> {
    assert!(m.settings == *s, "free_run_misfit_measured: records measured under other settings");
    let (r, mr) = c.runs_of("operating_point").zip(&m.runs).find(|(r, _)| r.id == id)?;
    let mr = mr.as_ref()?;
    free_run_misfit(&simulate_pair(c, r, mr, p, s, Reads::RotorMisfit), floor_rad_s)
}

/// [`free_run_misfit_channels`] of every operating point simulated with
/// `params_of(run id)` against its record measured under `s` (`m` from
/// [`MeasuredRuns::of`] with `s`; campaign order, the runs
/// [`free_run_pairs_measured`] skips left out): each value to the bit the
/// misfit of that function's pair, without the features this misfit does
/// not read ([`Reads::ChannelMisfit`]). `None` where the pair has no misfit.
pub fn free_run_channel_misfits_measured(
    c: &Campaign,
    s: &FreeRunSettings,
    m: &MeasuredRuns,
    params_of: impl Fn(&str) -> Option<RigParams> + Sync,
    floor_rad_s: f64,
) -> Vec<Option<f64>> {
    pairs_where(c, s, m, |r, mr| params_of(&r.id).map(|p| simulate_pair(c, r, mr, &p, s, Reads::ChannelMisfit)))
        .iter()
        .map(|q| free_run_misfit_channels(q, floor_rad_s))
        .collect()
}

/// Features of one run: measured from the encoders, the voltage and force
/// channels, and simulated with `p`, all through the same operators (the
/// diagnosis' centred differences, so the smoothing of the extrema is the
/// same on both sides; the force smoothed over the rotor-speed window).
pub(super) fn pair(c: &Campaign, run: &rig_types::Run, p: &RigParams, s: &FreeRunSettings) -> Option<Pair> {
    let m = measure(c, run, s)?;
    Some(simulate_pair(c, run, &m, p, s, Reads::All))
}

/// The record's side of [`pair`]: features, floors and trace of one run.
pub(super) fn measure(c: &Campaign, run: &rig_types::Run, s: &FreeRunSettings) -> Option<MeasuredRun> {
    let RunKind::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s } = run.kind else { return None };
    let t = &run.data.time_s;
    let from = t.partition_point(|&x| x < ramp_s + s.settle_s);
    let to = t.partition_point(|&x| x < ramp_s + s.settle_s + s.steady_s);
    if to < from + 16 {
        return None;
    }
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    let phi1_all = ticks_to_rad(run.data.rotor_ticks.as_ref()?, c.rig.encoder_ticks_per_rev);
    let phi1 = &phi1_all[..to];
    let phi2 = ticks_to_rad(&run.data.motor_ticks.as_ref()?[..to], c.rig.encoder_ticks_per_rev);
    let tt = &t[..to];
    let w_set = rig_types::units::rpm_to_rad_s(motor_rpm_setpoint);
    let dt = (tt[to - 1] - tt[0]) / (to - 1) as f64;
    let stride = ((1.0 / (TRACE_RATE_HZ * dt)).round() as usize).max(1);
    let (h1, h2) =
        (half_window_samples(tt, s.rotor_speed_half_window_s), half_window_samples(tt, s.motor_speed_half_window_s));
    let (m1, m2) = (centred_speed(tt, phi1, h1), centred_speed(tt, &phi2, h2));
    // The regime is the attractor's, read over the record's last `steady_s`
    // ([`attractor_stick_slip`]); every other feature over the window.
    let regime_from = t.partition_point(|&x| x < t[t.len() - 1] - s.steady_s).max(from);
    let window_measured =
        steady_features(&tt[from..], &m1[from..], &m2[from..], w_set, s.slip_speed_rad_s, &s.classify);
    let measured =
        Features { stick_slip: attractor_stick_slip(t, &phi1_all, regime_from, h1, &s.classify), ..window_measured };
    let m_voltage = run.data.motor_voltage_v.as_ref().map(|v| v[from..to].to_vec());
    let m_force = match (s.force, run.data.brake_force_mv.as_ref()) {
        (Some(law), Some(mv)) if normal_force_n > 0.0 => Some(law.force_n(&mv[..to])),
        _ => None,
    };
    let m_force_smooth = m_force.as_ref().map(|f| centred_moving_average(f, h1)[from..].to_vec());
    let m_peaks = m_force
        .as_ref()
        .map(|f| breakaway_peaks(tt, phi1, f, from, normal_force_n, &s.stick_episodes))
        .unwrap_or_default();
    let m_win = Window {
        w1: &m1[from..],
        w2: &m2[from..],
        voltage_v: m_voltage.as_deref(),
        force_n: m_force_smooth.as_deref(),
        peaks: &m_peaks,
    };
    let sigma_v = m_voltage.as_deref().map_or(f64::NAN, diff_noise);
    let channels_measured = ChannelFeatures { values: channel_values(&m_win, s.slip_speed_rad_s, sigma_v.max(0.0)) };
    let cycle_s = if window_measured.stick_slip() && window_measured.fundamental_hz > 0.0 {
        1.0 / window_measured.fundamental_hz
    } else {
        1.0
    };
    let res = |h: usize| rad / (2.0 * h as f64 * dt) / 6f64.sqrt();
    let noise = Noise {
        res_rad_s: (res(h1), res(h2)),
        sigma_v,
        sigma_f: m_force.as_ref().map_or(f64::NAN, |f| diff_noise(&f[from..])),
    };
    let mut floors = channel_floors(&m_win, s.slip_speed_rad_s, &noise, h1, (cycle_s / dt).round() as usize);
    // The dwell rows read the whole run, from rest (record and simulation alike).
    let dwell = match (s.force, run.data.brake_force_mv.as_ref()) {
        (Some(law), Some(mv)) if normal_force_n > 0.0 => {
            dwell_of(&run.id, t, &centred_speed(t, &phi1_all, h1), &law.force_n(mv), h1, s.slip_speed_rad_s)
        }
        _ => None,
    };
    let slip = &mut floors.values[6];
    *slip = slip.hypot(normal_force_n * s.mu_kinetic_stderr);
    Some(MeasuredRun {
        id: run.id.clone(),
        normal_force_n,
        input: RunInput::OperatingPoint { motor_rpm_setpoint, normal_force_n, ramp_s },
        from,
        to,
        h1,
        h2,
        dt,
        stride,
        regime_from,
        measured,
        window_measured,
        has_force: m_force.is_some(),
        has_voltage: m_voltage.is_some(),
        channels_measured,
        floors,
        measured_trace: m1[from..].iter().step_by(stride).copied().collect(),
        dwell,
    })
}

/// A run's dwell row ([`dwell_row`]) from its rotor speed and friction force
/// over the whole run, from rest: one rule for the record and a simulation.
pub(super) fn dwell_of(
    id: &str,
    t: &[f64],
    w1: &[f64],
    force_n: &[f64],
    h1: usize,
    slip_speed_rad_s: f64,
) -> Option<DwellRow> {
    let slip: Vec<f64> = w1.iter().zip(force_n).filter(|(w, _)| w.abs() >= slip_speed_rad_s).map(|x| *x.1).collect();
    let smooth = centred_moving_average(force_n, h1);
    dwell_row(id, t, w1, &smooth, mean(&slip), slip_speed_rad_s)
}

/// What a simulated side of a pair is made for: which features
/// [`simulate_pair`] computes.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub(super) enum Reads {
    /// Every feature, the trace and the dwell row: the checks and the report.
    All,
    /// What [`free_run_misfit`] reads and nothing else ([`rotor_side`]: Ω1's
    /// extremes, the attractor's regime, the fundamental where read; the
    /// motor's, voltage's and force's features, the break-away peaks, the
    /// window's regime and the dwell row are left out: NaN, empty, `None`),
    /// for [`free_run_misfit_measured`] alone.
    RotorMisfit,
    /// What [`free_run_misfit_channels`] reads and nothing else: every
    /// channel feature, the attractor's regime and the fundamental where read
    /// ([`Reads::RotorMisfit`]'s rule); the window's regime, the stuck
    /// fraction and motor dip of [`Features`], the trace and the dwell row
    /// are left out (`None`, NaN, empty), for
    /// [`free_run_channel_misfits_measured`] alone.
    ChannelMisfit,
}

/// The model's side of [`pair`]: run `p` on the record `m` was measured from,
/// with the features `reads` asks for.
pub(super) fn simulate_pair(
    c: &Campaign,
    run: &rig_types::Run,
    m: &MeasuredRun,
    p: &RigParams,
    s: &FreeRunSettings,
    reads: Reads,
) -> Pair {
    let t = &run.data.time_s;
    let MeasuredRun { from, to, h1, h2, dt, stride, regime_from, normal_force_n, .. } = *m;
    let tt = &t[..to];
    let w_set = match m.input {
        RunInput::OperatingPoint { motor_rpm_setpoint, .. } => rig_types::units::rpm_to_rad_s(motor_rpm_setpoint),
        _ => unreachable!("a MeasuredRun is an operating point's"),
    };
    let rad = tick_rad(c.rig.encoder_ticks_per_rev);
    // The whole record is simulated (the regime is read at its end); the
    // window's features from its first `to` samples. A rotor-only pair reads
    // no force, so its run writes no friction torque (the other channels are
    // the same to the bit).
    let channels =
        if reads == Reads::RotorMisfit { rig_model::Channels::WithoutFriction } else { rig_model::Channels::All };
    let sim = rig_model::simulate_channels(p, &m.input, t, &s.integrator, channels).ok().map(|tr| {
        if reads == Reads::RotorMisfit {
            return rotor_side(t, &tr.rotor_angle_rad, m, s);
        }
        // Ω1 and Ω2 over the window alone: every reader below starts at `from`.
        let (w1, w2) = (
            centred_speed_from(tt, &tr.rotor_angle_rad[..to], h1, from),
            centred_speed_from(tt, &tr.motor_angle_rad[..to], h2, from),
        );
        let has_force = m.has_force;
        let force: Vec<f64> = if has_force {
            tr.friction_torque_nm[..to].iter().map(|x| x / p.brake_disc_radius_m).collect()
        } else {
            Vec::new()
        };
        let force_smooth = has_force.then(|| centred_moving_average(&force, h1)[from..].to_vec());
        // The simulated angle through the encoder, as the record's: the
        // window's first `to` samples for the peaks, the whole run for the
        // dwell row (only where the record has one).
        let peaks = if has_force {
            let ticks = rig_types::sensor::encoder_ticks(&tr.rotor_angle_rad[..to], c.rig.encoder_ticks_per_rev);
            let enc = ticks_to_rad(&ticks, c.rig.encoder_ticks_per_rev);
            breakaway_peaks(tt, &enc, &force, from, normal_force_n, &s.stick_episodes)
        } else {
            Vec::new()
        };
        let dwell = m.dwell.as_ref().filter(|_| reads == Reads::All).and_then(|_| {
            let ticks = rig_types::sensor::encoder_ticks(&tr.rotor_angle_rad, c.rig.encoder_ticks_per_rev);
            let enc = ticks_to_rad(&ticks, c.rig.encoder_ticks_per_rev);
            let all: Vec<f64> = tr.friction_torque_nm.iter().map(|x| x / p.brake_disc_radius_m).collect();
            dwell_of(&m.id, t, &centred_speed(t, &enc, h1), &all, h1, s.slip_speed_rad_s)
        });
        let win = Window {
            w1: &w1,
            w2: &w2,
            voltage_v: m.has_voltage.then(|| &tr.voltage_v[from..to]),
            force_n: force_smooth.as_deref(),
            peaks: &peaks,
        };
        let ch = ChannelFeatures { values: channel_values(&win, s.slip_speed_rad_s, 0.0) };
        let stick_slip = attractor_stick_slip(t, &tr.rotor_angle_rad, regime_from, h1, &s.classify);
        if reads == Reads::ChannelMisfit {
            let (w, ts) = (&w1, &tt[from..]);
            let (min, max) = (ch.values[ChannelFeatures::ROTOR_MIN], ch.values[ChannelFeatures::ROTOR_MAX]);
            let f = misfit_features(stick_slip, read_fundamental_hz(stick_slip, m, ts, w, s), min, max);
            return (f, Vec::new(), ch, None, None);
        }
        let window = steady_features(&tt[from..], &w1, &w2, w_set, s.slip_speed_rad_s, &s.classify);
        let f = Features { stick_slip, ..window };
        let trace = w1.iter().step_by(stride).copied().collect::<Vec<f64>>();
        (f, trace, ch, Some(window.stick_slip), dwell)
    });
    let (simulated, simulated_rad_s, channels_simulated, sim_window_ss, sim_dwell) =
        sim.map_or((None, None, None, None, None), |(f, w, ch, ss, d)| (Some(f), Some(w), Some(ch), ss, d));
    // Neither misfit reads the trace.
    let trace = match reads {
        Reads::All => Trace {
            time_s: tt[from..].iter().step_by(stride).copied().collect(),
            measured_rad_s: m.measured_trace.clone(),
            simulated_rad_s,
        },
        _ => Trace { simulated_rad_s, ..Trace::default() },
    };
    let motor_tick_rad_s = rad / (2.0 * h2 as f64 * dt);
    Pair {
        id: m.id.clone(),
        measured: m.measured,
        simulated,
        window_s: tt[to - 1] - tt[from],
        trace,
        motor_tick_rad_s,
        channels_measured: m.channels_measured,
        channels_simulated,
        floors: m.floors,
        window_stick_slip: (m.window_measured.stick_slip, sim_window_ss),
        dwell: (m.dwell.clone(), sim_dwell),
    }
}

/// A simulation's side of a pair: its features, speed trace, channel
/// features, window regime (`None`: not read) and dwell row.
type SimSide = (Features, Vec<f64>, ChannelFeatures, Option<bool>, Option<DwellRow>);

/// What a simulation of [`simulate_pair`] gives for [`free_run_misfit`] alone
/// (`rotor_only`), to the bit the full pair's values that misfit reads: the
/// attractor's regime, the Ω1 extremes of the window (channel features 0, 1),
/// and the fundamental only where it is read (both regimes stick-slip and
/// the record's fundamental > 0; else 0). Not computed, so not read: Ω2 and
/// its features (NaN), the window's regime (the checks': `None`), the stuck
/// fraction and motor dip (NaN).
fn rotor_side(t: &[f64], rotor_angle_rad: &[f64], m: &MeasuredRun, s: &FreeRunSettings) -> SimSide {
    let MeasuredRun { from, to, h1, stride, regime_from, .. } = *m;
    let tt = &t[..to];
    let w1 = centred_speed_from(tt, &rotor_angle_rad[..to], h1, from);
    let win = &w1[..];
    let stick_slip = attractor_stick_slip(t, rotor_angle_rad, regime_from, h1, &s.classify);
    let fundamental_hz = read_fundamental_hz(stick_slip, m, &tt[from..], win, s);
    let min = win.iter().copied().fold(f64::INFINITY, f64::min);
    let max = win.iter().copied().fold(f64::NEG_INFINITY, f64::max);
    let f = misfit_features(stick_slip, fundamental_hz, min, max);
    let mut ch = ChannelFeatures::nan();
    ch.values[ChannelFeatures::ROTOR_MAX] = max;
    ch.values[ChannelFeatures::ROTOR_MIN] = min;
    let trace = win.iter().step_by(stride).copied().collect();
    (f, trace, ch, None, None)
}

/// The simulated fundamental where a misfit reads it (both regimes
/// stick-slip and the record's fundamental > 0; else 0): [`steady_features`]'
/// value to the bit ([`steady_fundamental_hz`]) over the window `t`, `w1`.
fn read_fundamental_hz(stick_slip: bool, m: &MeasuredRun, t: &[f64], w1: &[f64], s: &FreeRunSettings) -> f64 {
    if stick_slip && m.measured.stick_slip() && m.measured.fundamental_hz > 0.0 {
        steady_fundamental_hz(t, w1, s.slip_speed_rad_s)
    } else {
        0.0
    }
}

/// A misfit's simulated [`Features`]: the attractor's regime, the
/// fundamental where read and Ω1's extremes; the stuck fraction and motor
/// dip, which no misfit reads, NaN.
fn misfit_features(stick_slip: bool, fundamental_hz: f64, min: f64, max: f64) -> Features {
    Features {
        stuck_fraction: f64::NAN,
        stick_slip,
        rotor_min_rad_s: min,
        rotor_max_rad_s: max,
        fundamental_hz,
        motor_dip_rad_s: f64::NAN,
    }
}

/// Stick-slip of the attractor a run settles to: the regime classifier
/// (`rig_sweep::classify`, `[shared.classify]`, the one definition of
/// stick-slip) on Ω1 (centred difference of half window `h`) over samples
/// `from..` of the whole run, its last `steady_s`.
///
/// Why not the features' window (issue 25's regime changes of op-19, op-27):
/// at the stick-slip boundary a run from rest sticks and slips for a while
/// and then decays to steady slip, and how long it keeps sticking is set by
/// the phase of the normal-force modulation at each break-away, not by the
/// model's level: the final model of the shipped campaign keeps op-26
/// sticking until 3.8 s, 12.6 s or 10.4 s for modulation phases moved by
/// −0.01, 0 and +0.03 rad, op-19 until 4.3 s or 17.4 s (record 19.5 s) for
/// 0 and +0.3 rad. A window that starts after the ramp (5–21 s) cuts such a
/// transient at an arbitrary point, and the classifier's decay rule (second
/// half's swing below 0.6 of the first's) then reads the same behaviour
/// both ways: the record's op-22, op-26, op-27 all stop sticking at
/// 8.6–10.5 s, and their decay ratios 0.63, 0.64, 0.56 made two of them
/// stick-slip and one not. What the rig settles to is determined; how long
/// it takes near the boundary is not, within the modulation's phase: over 8
/// phases spread over 2π the final model ends in steady slip at every one
/// for op-02, op-19, op-20, op-22, op-26, op-27, op-28 and sticks and slips
/// at every one for op-03, as the record does, while its last stick ranges
/// over 4.3–11.0 s for op-19 (record 19.5 s), 0–16.3 s for op-22 (10.0),
/// 3.8–12.6 s for op-26 (10.5) and 4.0–10.7 s for op-27 (8.6)
/// (`crates/pipeline/examples/breakaway_probe.rs`, `TRANSIENT=1`). So a
/// run changes regime in the check only when the end of the run and the
/// features' window both differ; a difference in one of them is listed.
pub(super) fn attractor_stick_slip(
    t: &[f64],
    rotor_angle_rad: &[f64],
    from: usize,
    h: usize,
    classify: &rig_sweep::ClassifyOptions,
) -> bool {
    let n = t.len().min(rotor_angle_rad.len());
    if n < from + 16 {
        return false;
    }
    let w1 = centred_speed_from(&t[..n], &rotor_angle_rad[..n], h, from);
    let fs_hz = (n - from - 1) as f64 / (t[n - 1] - t[from]);
    rig_sweep::classify(&w1, fs_hz, classify).regime.stick_slip()
}

/// `centred_speed(t, angle_rad, h)[from..]`, to the bit, made from the
/// samples that reach it alone (`from − h..`): the centred difference at
/// sample i reads samples i − h and i + h (clamped to the ends), and its
/// values from `from` on read nothing before `from − h`. A free run's
/// readers start at its window (or the attractor's last `steady_s`), the
/// record's first 8-24 s of 40 s not read.
pub(super) fn centred_speed_from(t: &[f64], angle_rad: &[f64], h: usize, from: usize) -> Vec<f64> {
    let n = t.len().min(angle_rad.len());
    let from = from.min(n);
    let lo = from.saturating_sub(h.max(1));
    let mut w = centred_speed(&t[lo..n], &angle_rad[lo..n], h);
    w.drain(..from - lo);
    w
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
