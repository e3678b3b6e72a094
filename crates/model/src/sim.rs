//! The integration loop: Dormand–Prince steps, stick/slip events located on
//! the dense output with a restart after each, and sampling of every
//! trajectory channel at the requested times.

use crate::dopri::{DIM, Dopri, StepFailure, Vector, locate_root};
use crate::exact::{Compute, Exact, ROWS, apply, apply_along, same_step};
use crate::system::{CUR, INT, Mode, PHI1, PHI2, Region, System, TEMP, VoltageIn, W1, W2};
use crate::{Channels, ModelError, SimOptions, State};
use rig_types::{FrictionLaw, ModelKind, Trajectory};

/// Step budget of one call: accepted plus rejected steps may not exceed
/// `MAX_STEPS + MAX_STEPS_PER_S × (simulated seconds)`. A run that needs more
/// is reported as an error instead of hanging. The stiffest legitimate case,
/// the thesis model creeping on its steep lookup, needs ~6·10³ steps per
/// simulated second; a parameter set with, say, L/R of a few µs needs ~10⁵
/// and fails after a few seconds of CPU time instead of grinding on.
pub const MAX_STEPS: u64 = 1_000_000;
/// See [`MAX_STEPS`].
pub const MAX_STEPS_PER_S: f64 = 25_000.0;
/// Consecutive steps cut short at a kink of the right-hand side, each
/// advancing less than [`KINK_HUG_DT_S`], after which kinks are no longer
/// located until the next exact step or event: the trajectory is running
/// along the kink (a steady state that needs exactly the drive's voltage
/// limit, where the PI's raw voltage hovers at the clamp), and cutting every
/// step there would stall the run in ever shorter steps. Dormand–Prince
/// integrates across such a kink under its own error control (the
/// right-hand side is continuous there, only its derivative jumps).
const MAX_KINK_HUGS: u32 = 3;
const KINK_HUG_DT_S: f64 = 1e-5;
/// Consecutive events that may happen without time advancing by more than
/// [`ZENO_DT_S`] before the run is declared stuck in an event loop.
const MAX_ZENO_EVENTS: u32 = 100;
/// Most sample steps of one exact block (see `run`): the default 10 ms at up to 1.6 kHz.
const MAX_BLOCK: usize = 16;
/// Samples of consecutive blocks held before they are appended to the
/// trajectory together (a channel's append has a fixed cost that a 5-sample
/// block would pay nine times).
const PENDING: usize = 128;
/// Slack of a block's extent against max_step_s: sample times are sums that
/// miss k·h by a few ulps.
const H_GRID_REL: f64 = 1e-9;
const ZENO_DT_S: f64 = 1e-9;

/// Counters of one run, for benches and tests.
#[derive(Debug, Clone, Copy, Default, PartialEq)]
pub struct SimStats {
    pub accepted_steps: u64,
    pub rejected_steps: u64,
    pub rhs_evaluations: u64,
    /// Stick→slip and slip→stick (or reversal) transitions located.
    pub events: u64,
    /// Exact steps (module `exact`) and the propagators e^{M h} they needed;
    /// `accepted_steps` counts the Dormand–Prince steps only.
    pub exact_steps: u64,
    pub propagators: u64,
}

fn failed(t: f64, reason: impl Into<String>) -> ModelError {
    ModelError::IntegratorFailed { time_s: t, reason: reason.into() }
}

/// Where the thesis model counts as "stuck": inside the static branch of its
/// lookup, |Ω1| below the static set-point (it has no stick phase of its own).
fn thesis_stuck(sys: &System, y: &Vector) -> bool {
    match &sys.p.friction {
        FrictionLaw::Thesis(f) => rig_types::units::rad_s_to_rpm(y[W1]).abs() < f.static_setpoint_rpm,
        _ => y[W1] == 0.0,
    }
}

/// Whether the event function went from `g0` to `g1` across the end of
/// `mode` (see `System::event`): stick ends where it crosses from ≤ 0 to > 0,
/// slip where it crosses from ≥ 0 to < 0; the continuous mode has no event.
#[inline]
fn ends_mode(mode: Mode, g0: f64, g1: f64) -> bool {
    match mode {
        Mode::Stick => g0 <= 0.0 && g1 > 0.0,
        Mode::Slip { .. } => g0 >= 0.0 && g1 < 0.0,
        Mode::Continuous => false,
    }
}

/// Whether an exact step that started in `region` with event value `g0` may
/// end at (t1, y1): no event crossed, the same region (up to the ramp flag),
/// a finite state. If so, the region and event value carried to the next step.
#[inline(always)]
fn exact_end(
    sys: &System,
    mode: Mode,
    region: &Region,
    g0: Option<f64>,
    t1: f64,
    y1: &Vector,
) -> Option<Option<(Region, Option<f64>)>> {
    let g1 = sys.event(mode, t1, y1);
    let crossed = matches!((g0, g1), (Some(a), Some(b)) if ends_mode(mode, a, b));
    let end = sys.region(mode, t1, y1);
    let same_region = end.map(|r| Region { ramping: region.ramping, ..r }) == Some(*region);
    (!crossed && same_region && y1.iter().all(|v| v.is_finite())).then(|| end.map(|r| (r, g1)))
}

/// Whether `mode` at state `y` counts as stuck in the output's `stuck` channel.
#[inline]
fn stuck_flag(sys: &System, mode: Mode, y: &Vector) -> bool {
    match (sys.kind, mode) {
        (ModelKind::Thesis, _) => sys.brake_closed() && thesis_stuck(sys, y),
        (_, Mode::Stick) => true,
        _ => false,
    }
}

/// Appends the sample at `t`; the friction torque only if `friction` ([`Channels`]).
#[inline]
fn push_sample(out: &mut Trajectory, sys: &System, mode: Mode, t: f64, y: &Vector, friction: bool) {
    out.time_s.push(t);
    out.rotor_angle_rad.push(y[PHI1]);
    out.rotor_speed_rad_s.push(y[W1]);
    out.motor_angle_rad.push(y[PHI2]);
    out.motor_speed_rad_s.push(y[W2]);
    out.current_a.push(y[CUR]);
    out.voltage_v.push(sys.voltage(t, y).0);
    if friction {
        out.friction_torque_nm.push(sys.friction_torque_nm(mode, t, y));
    }
    out.stuck.push(stuck_flag(sys, mode, y));
}

/// Appends the samples at `times`, whose states are held channel by channel
/// in `states[..][..times.len()]`, all in `mode` and `region`: one append per
/// channel. The voltage and the friction torque take the shortcuts
/// [`System::voltage_in`] and [`System::friction_torque_constant_in`] allow
/// (the same values as [`push_sample`] writes); the friction torque only if
/// `friction`.
fn push_pending<const P: usize>(
    out: &mut Trajectory,
    sys: &System,
    (mode, region): (Mode, &Region),
    times: &[f64],
    states: &[[f64; P]; ROWS],
    friction: bool,
) {
    let n = times.len();
    if n == 0 {
        return;
    }
    let [phi1, phi2, w1, w2, cur, int] = states.each_ref().map(|c| &c[..n]);
    out.time_s.extend_from_slice(times);
    out.rotor_angle_rad.extend_from_slice(phi1);
    out.motor_angle_rad.extend_from_slice(phi2);
    out.rotor_speed_rad_s.extend_from_slice(w1);
    out.motor_speed_rad_s.extend_from_slice(w2);
    out.current_a.extend_from_slice(cur);
    let y = |j: usize| -> Vector { [phi1[j], phi2[j], w1[j], w2[j], cur[j], int[j], 0.0] };
    match sys.voltage_in(region) {
        VoltageIn::Constant(v) => out.voltage_v.extend(times.iter().map(|_| v)),
        // Outside the ramp the reference is one constant: a loop over the two channels alone.
        VoltageIn::Unclamped if !region.ramping => {
            let r = sys.reference_rad_s(times[0]);
            out.voltage_v.extend(w2.iter().zip(int).map(|(&w, &i)| sys.pi_unclamped_of_v(r, w, i)))
        }
        VoltageIn::Unclamped => out.voltage_v.extend(
            times
                .iter()
                .zip(w2.iter().zip(int))
                .map(|(&t, (&w, &i))| sys.pi_unclamped_of_v(sys.reference_rad_s(t), w, i)),
        ),
    }
    if friction && sys.friction_torque_constant_in(region) {
        let f = sys.friction_torque_nm(mode, times[0], &y(0));
        out.friction_torque_nm.extend(times.iter().map(|_| f));
    } else if friction {
        out.friction_torque_nm.extend(times.iter().enumerate().map(|(j, &t)| sys.friction_torque_nm(mode, t, &y(j))));
    }
    if sys.kind == ModelKind::Rig {
        let stuck = stuck_flag(sys, mode, &y(0));
        out.stuck.extend(times.iter().map(|_| stuck));
    } else {
        out.stuck.extend((0..n).map(|j| stuck_flag(sys, mode, &y(j))));
    }
}

/// The end of the exact step from `t` toward the next sample `samples[idx]`
/// (or `t_end` past the last): the next sample where it lies within
/// `max_step_s` (a sample a rounding error beyond it too: a grid spaced by
/// max_step_s, 100 Hz at the default 10 ms, would otherwise alternate a step
/// of t + max_step_s, which falls an ulp short of k/rate, with an ulp-long
/// Dormand–Prince step to the sample), else t + `max_step_s`; never past
/// `t_stop`. And whether the step is nominal, one the run repeats: of
/// `max_step_s` or from one sample to the next (its propagator is cached).
#[inline]
fn exact_step_end(samples: &[f64], idx: usize, t: f64, (t_stop, t_end): (f64, f64), max_step_s: f64) -> (f64, bool) {
    let next = samples.get(idx).copied().unwrap_or(t_end);
    let t1 = if next - t <= max_step_s * (1.0 + H_GRID_REL) { next } else { t + max_step_s };
    let t1 = t1.min(t_stop);
    let nominal = same_step(t1 - t, max_step_s, t) || (idx > 0 && samples[idx - 1] == t);
    (t1, nominal)
}

/// Samples in the block that starts at `samples[idx]`, one step `h` after `t`:
/// the run of samples after it spaced by the same `h`, at most [`MAX_BLOCK`],
/// none past `t_stop` or more than `max_step_s` after `t` (see `run`).
#[inline]
fn block_len(samples: &[f64], idx: usize, t: f64, h: f64, t_stop: f64, max_step_s: f64) -> usize {
    let mut k = 1;
    while k < MAX_BLOCK
        && idx + k < samples.len()
        && samples[idx + k] <= t_stop
        && samples[idx + k] - t <= max_step_s * (1.0 + H_GRID_REL)
        && same_step(samples[idx + k] - samples[idx + k - 1], h, samples[idx + k])
    {
        k += 1;
    }
    k
}

/// Empties every channel of `out`, keeping its allocations, and makes room
/// for `n` samples in each it will write (not the friction torque's unless `friction`).
fn clear(out: &mut Trajectory, n: usize, friction: bool) {
    for c in out.numeric_channels_mut() {
        c.clear();
    }
    for c in out.numeric_channels_mut().into_iter().take(if friction { 8 } else { 7 }) {
        c.reserve(n);
    }
    out.stuck.clear();
    out.stuck.reserve(n);
}

/// Integrates from `from` = (t0, y0, mode0) to the last sample time, stopping
/// exactly at each `breakpoints` time (kinks of the input, e.g. the end of the
/// ramp), into `out`'s `channels` (emptied first; its allocations are
/// reused). Samples must be sorted and >= t0 (checked by the caller).
pub(crate) fn run(
    sys: &System,
    from: (f64, Vector, Mode),
    samples: &[f64],
    breakpoints: &[f64],
    (opts, channels): (&SimOptions, Channels),
    out: &mut Trajectory,
) -> Result<(State, SimStats), ModelError> {
    let (t0, y0, mode0) = from;
    let n = samples.len();
    let friction = channels == Channels::All;
    clear(out, n, friction);
    let t_end = samples.last().copied().unwrap_or(t0).max(t0);
    let (mut t, mut y, mut mode) = (t0, y0, mode0);
    if mode == Mode::Stick {
        y[W1] = 0.0;
    }
    let mut idx = 0;
    while idx < n && samples[idx] <= t0 {
        push_sample(out, sys, mode, samples[idx], &y, friction);
        idx += 1;
    }
    let mut dp = Dopri::new(opts.rtol, opts.atol, opts.max_step_s).with_norm_dim(if sys.has_thermal_state() {
        DIM
    } else {
        DIM - 1
    });
    let mut stats = SimStats::default();
    let mut zeno = 0u32;
    let mut kink_hugs = 0u32;
    let budget = MAX_STEPS + (MAX_STEPS_PER_S * (t_end - t0)) as u64;
    let mut exact = Exact::default();
    // States of accepted blocks not yet appended, channel by channel (φ1 φ2 Ω1 Ω2 i ∫e).
    let mut pending = [[0.0; PENDING]; ROWS];
    let mut fsal_valid = true;
    // The region and event value at the end of an accepted exact step (the next one's start).
    let mut carried = None;
    while t < t_end {
        let mut t_stop = breakpoints.iter().copied().filter(|&b| b > t && b < t_end).fold(t_end, f64::min);
        let start = match carried.take() {
            Some((r, g)) => Some((Region { ramping: sys.ramping(t), ..r }, g)),
            None => sys.region(mode, t, &y).map(|r| (r, sys.event(mode, t, &y))),
        };
        if let Some((region, g0)) = start {
            // An exact step to the next sample (or by max_step_s, or to the breakpoint).
            // Cache propagators of step lengths the run repeats (max_step_s, sample to
            // sample); compute a one-off one where Dormand–Prince would need more than
            // 16 steps (a stiff region, e.g. the thesis lookup's creep segment).
            let (t1, nominal) = exact_step_end(samples, idx, t, (t_stop, t_end), opts.max_step_s);
            let h = t1 - t;
            let stiff = dp.proposed_step() * 16.0 < h;
            let compute = if nominal {
                Compute::Cache
            } else if stiff {
                Compute::Once
            } else {
                Compute::No
            };
            if let Some((phi, h_phi)) = exact.propagator(sys, &region, &y, t, h, compute) {
                // A block: where the samples are denser than max_step_s, the step to
                // the next sample is repeated along the uniform grid for up to
                // max_step_s (the step the run takes where it samples less often),
                // and the event and the region are checked at the block's end only.
                // The states are the same products as sample-by-sample steps; if the
                // block's end fails a check, only its first step is taken (below), as
                // without blocks.
                //
                // After an exact step (or block), the steps that follow are taken in
                // this inner loop while the next pass of the outer one would take them
                // with the same propagator: the same region, a cached step length, the
                // same entry (checked first, as the last used). The same steps and
                // checks as the outer loop's, without its set-up; where one fails, the
                // outer loop takes over and repeats that step's checks.
                let cached = compute == Compute::Cache;
                let (mut t1, mut h, mut g0, mut steps) = (t1, h, g0, 0u64);
                // Samples of accepted blocks not yet appended: samples[idx - held..idx],
                // states pending[..][..held].
                let mut held = 0;
                let taken = loop {
                    let k = if cached && idx < n && samples[idx] == t1 {
                        block_len(samples, idx, t, h, t_stop, opts.max_step_s)
                    } else {
                        1
                    };
                    let mut ok = false;
                    if k > 1 {
                        if held + k > PENDING {
                            push_pending(out, sys, (mode, &region), &samples[idx - held..idx], &pending, friction);
                            held = 0;
                        }
                        let mut yk = apply_along(phi, &y, t, &samples[idx..idx + k], &mut pending, held);
                        let tk = samples[idx + k - 1];
                        if sys.exact_steps_age() {
                            // The time since the last event grows with time (the friction extension).
                            yk[TEMP] = y[TEMP] + (tk - t);
                        }
                        if let Some(end) = exact_end(sys, mode, &region, g0, tk, &yk) {
                            (carried, steps, idx, t, y, ok, held) =
                                (end, steps + k as u64, idx + k, tk, yk, true, held + k);
                        }
                    }
                    if !ok {
                        let mut y1 = apply(phi, &y, t);
                        if sys.exact_steps_age() {
                            y1[TEMP] = y[TEMP] + (t1 - t);
                        }
                        if let Some(end) = exact_end(sys, mode, &region, g0, t1, &y1) {
                            if held > 0 {
                                push_pending(out, sys, (mode, &region), &samples[idx - held..idx], &pending, friction);
                                held = 0;
                            }
                            while idx < n && samples[idx] <= t1 {
                                push_sample(out, sys, mode, samples[idx], &y1, friction);
                                idx += 1;
                            }
                            (carried, steps, t, y, ok) = (end, steps + 1, t1, y1, true);
                        }
                    }
                    if !ok {
                        break steps > 0;
                    }
                    // Would the outer loop's next pass take the same propagator?
                    // exact_end found the end in `region` up to the ramp flag.
                    let Some((_, g)) = carried.filter(|_| cached && t < t_stop) else { break true };
                    if sys.ramping(t) != region.ramping {
                        break true;
                    }
                    let (t1_next, nominal) = exact_step_end(samples, idx, t, (t_stop, t_end), opts.max_step_s);
                    let h_next = t1_next - t;
                    if !nominal || !same_step(h_phi, h_next, t) {
                        break true;
                    }
                    (t1, h, g0) = (t1_next, h_next, g);
                };
                push_pending(out, sys, (mode, &region), &samples[idx - held..idx], &pending, friction);
                exact.steps += steps;
                if taken {
                    kink_hugs = 0;
                    fsal_valid = false;
                    continue;
                }
            }
            // An event or a switch inside (or no propagator): a Dormand–Prince step, ending
            // no later than t1 while exact steps are still being taken, so that they resume
            // on the sample grid.
            if exact.viable() {
                t_stop = t1;
            }
        }
        if !fsal_valid {
            dp.reset();
            fsal_valid = true;
        }
        dp.step(t, &y, t_stop, &mut |tt, yy| sys.rhs(mode, tt, yy)).map_err(|e| match e {
            StepFailure::StepTooSmall { h } => failed(t, format!("step size {h:e} s fell below round-off")),
            StepFailure::NonFinite => failed(t, "the right-hand side is not finite"),
        })?;
        let step = dp.last_step();
        if dp.n_accept + dp.n_reject > budget {
            let m = &sys.p.motor;
            return Err(failed(
                t,
                format!(
                    "more than {budget} steps over {:.3} s (mean accepted step {:.2e} s; electrical time constant \
                     L/R = {:.2e} s): the parameters make the equations too stiff, or the tolerances are too tight",
                    t - t0,
                    (t - t0) / dp.n_accept.max(1) as f64,
                    m.inductance_h / m.resistance_ohm
                ),
            ));
        }
        let (mut t_next, mut y_next, mut switch) = (step.t1(), step.y1, None);
        let mut cut_at_kink = false;
        if start.is_some() && kink_hugs < MAX_KINK_HUGS {
            // In a piecewise-affine regime: end the step at the first switch of the
            // right-hand side inside it (voltage clamp, a kink of the friction lookup),
            // located on the dense output like an event, so that no step integrates
            // across a kink and the next one can be exact again.
            let (s0, s1) = (sys.switching(mode, t, &y), sys.switching(mode, step.t1(), &step.y1));
            for k in 0..s0.len() {
                if (s0[k] > 0.0) != (s1[k] > 0.0) {
                    let tk = locate_root(t, s0[k], step.t1(), s1[k], |tt| sys.switching(mode, tt, &step.dense(tt))[k]);
                    if tk < t_next {
                        t_next = tk;
                        y_next = step.dense(tk);
                        fsal_valid = false;
                        cut_at_kink = true;
                    }
                }
            }
        }
        if let Some(g0) = sys.event(mode, t, &y) {
            let g1 = sys.event(mode, t_next, &y_next).unwrap_or(0.0);
            if ends_mode(mode, g0, g1) {
                let te = locate_root(t, g0, t_next, g1, |tt| sys.event(mode, tt, &step.dense(tt)).unwrap_or(0.0));
                t_next = te;
                y_next = step.dense(te);
                switch = Some(mode);
            }
        }
        kink_hugs = match (switch, cut_at_kink && t_next - t < KINK_HUG_DT_S) {
            (Some(_), _) => 0,
            (None, true) => kink_hugs + 1,
            (None, false) => kink_hugs,
        };
        while idx < n && samples[idx] <= t_next {
            push_sample(out, sys, mode, samples[idx], &step.dense(samples[idx]), friction);
            idx += 1;
        }
        let advanced = t_next - t;
        t = t_next;
        y = y_next;
        if let Some(old) = switch {
            stats.events += 1;
            mode = match old {
                // Break-away: slip in the direction the shaft pulls.
                Mode::Stick => {
                    if sys.has_slip_age() {
                        // Break-away: the time since break-away starts at 0 (friction extension).
                        y[TEMP] = 0.0;
                    }
                    Mode::Slip { sign: sys.rotor_torque_nm(&y).signum() }
                }
                // Ω1 reached zero: stick if static friction can hold the shaft, else reverse.
                _ => {
                    y[W1] = 0.0;
                    if sys.has_contact_age() {
                        // A new contact: its age starts at 0 (Effect::StaticFrictionAging).
                        y[TEMP] = 0.0;
                    }
                    sys.mode_at_rest(t, &y)
                }
            };
            dp.reset();
            zeno = if advanced < ZENO_DT_S { zeno + 1 } else { 0 };
            if zeno > MAX_ZENO_EVENTS {
                return Err(failed(t, "stick/slip events do not advance time (Zeno loop)"));
            }
        }
    }
    // Samples at exactly t_end when the loop ended on an event or never ran.
    while idx < n {
        push_sample(out, sys, mode, samples[idx], &y, friction);
        idx += 1;
    }
    stats.accepted_steps = dp.n_accept;
    stats.rejected_steps = dp.n_reject;
    stats.rhs_evaluations = dp.n_eval;
    stats.exact_steps = exact.steps;
    stats.propagators = exact.computed;
    let end = State {
        time_s: t,
        rotor_angle_rad: y[PHI1],
        rotor_speed_rad_s: y[W1],
        motor_angle_rad: y[PHI2],
        motor_speed_rad_s: y[W2],
        current_a: y[CUR],
        pi_integral_rad: y[INT],
        stuck: mode == Mode::Stick,
    };
    Ok((end, stats))
}
