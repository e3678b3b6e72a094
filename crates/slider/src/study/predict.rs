//! A model's features at a run ([`predict`]: simulated at the run's (k, V)
//! through the one feature function), a run's measurement ([`measure`]) and
//! a model read through a run's channel ([`through_channel`]).

use super::{Measured, StudyParams};
use crate::features::{Features, Regime, RunConstants, features, spectral_period_s};
use crate::fit::Model;
use crate::sim::{Setup, simulate_more};
use rig_ingest::slider::SliderRun;
use rig_model::one_dof::OneDofState;

/// Points of a figure's trace at most.
pub const TRACE_POINTS: usize = 400;

impl Measured {
    fn constants(&self, p: &StudyParams) -> RunConstants {
        RunConstants {
            stiffness_n_m: self.stiffness_n_m,
            drive_speed_m_s: self.drive_speed_um_s * 1e-6,
            mass_kg: p.mass_kg,
            gravity_m_s2: p.gravity_m_s2,
        }
    }
}

/// Measures one run.
pub fn measure(r: &SliderRun, p: &StudyParams) -> Measured {
    let n = r.time_s.len();
    let duration_s = r.time_s[n - 1] - r.time_s[0];
    let mut m = Measured {
        name: r.name.clone(),
        stiffness_n_m: r.stiffness_n_m,
        drive_speed_um_s: r.drive_speed_um_s,
        duration_s,
        sample_rate_hz: (n - 1) as f64 / duration_s,
        features: Features::default_steady(),
        spectral_period_s: f64::NAN,
        force_step: crate::features::channel_step(&r.force_over_weight),
    };
    m.features = features(&r.time_s, &r.force_over_weight, &m.constants(p), &p.features);
    if m.features.regime == Regime::InertialOscillation {
        let half = (p.features.median_window_s * m.sample_rate_hz / 2.0).round() as usize;
        let filtered = crate::features::running_median(&r.force_over_weight, half);
        m.spectral_period_s = spectral_period_s(&filtered, m.sample_rate_hz, m.features.natural_period_s, p.mains_hz);
    }
    m
}

/// A model's force at run `m` read through that run's channel, then by the
/// one feature function: `channel_s` s simulated (after the warm-up),
/// rounded onto the record's grid (its step, [`Measured::force_step`], at
/// the grid's offset) and with the record's own noise added sample by
/// sample (raw minus its running median: the spikes and the flicker between
/// steps the measurement carries). Whether the record could have shown what
/// the model does: a slip the channel resolves stays an event, one below
/// the hysteresis does not. Deterministic (the record's noise, no draw).
pub fn through_channel(
    model: Model,
    x: &[f64],
    m: &Measured,
    raw: &SliderRun,
    p: &StudyParams,
    channel_s: f64,
) -> Features {
    let mut q = p.clone();
    q.sim_min_window_s = channel_s;
    q.sim_max_window_s = channel_s;
    let (_, clean) = predict_trace(model, x, m, &q, usize::MAX);
    let half = (p.features.median_window_s * m.sample_rate_hz / 2.0).round() as usize;
    let median = crate::features::running_median(&raw.force_over_weight, half);
    let step = m.force_step;
    let offset = raw.force_over_weight[0] - step * (raw.force_over_weight[0] / step).round();
    let n = clean.len().min(raw.force_over_weight.len());
    let force: Vec<f64> = (0..n)
        .map(|i| {
            let on_grid = offset + step * ((clean[i] - offset) / step).round();
            on_grid + raw.force_over_weight[i] - median[i]
        })
        .collect();
    let time: Vec<f64> = (0..n).map(|i| i as f64 / m.sample_rate_hz).collect();
    features(&time, &force, &m.constants(p), &p.features)
}

/// The simulated (and the figures' measured) stretch of run `m`, s.
pub(super) fn window_s(m: &Measured, p: &StudyParams) -> f64 {
    let periods = if m.features.period_s.n > 0 { p.sim_periods * m.features.period_s.median } else { 0.0 };
    periods.max(p.sim_min_window_s).min(p.sim_max_window_s).min(m.duration_s)
}

/// The features of `law` simulated at run `m`'s (k, V), through the same feature function.
///
/// The simulated stretch is [`window_s`] (set by the *measured* period).
/// It is lengthened, up to `sim_max_window_s` and the record's length, when
/// - the law's own slips are too slow to give `min_events` in it (a regime
///   of slips the window cannot hold, which the feature function would call
///   steady sliding): doubled, so a long period is measured as such;
/// - its events do not repeat one cycle ([`crate::fit::repeats`]) and it
///   holds fewer than `spread_periods` periods: to about that many, so the
///   misfit's spread term ([`crate::fit::spread_term`]) reads quartiles of
///   that many events (a cycle that repeats has its dispersion from two).
pub fn predict(model: Model, x: &[f64], m: &Measured, p: &StudyParams) -> Features {
    let cap = p.sim_max_window_s.min(m.duration_s);
    let mut window = window_s(m, p);
    // A law with a track covers enough of it for the events' statistics.
    if let (crate::sim::Law::Track(t), _) = model.law(x) {
        window = window.max(t.min_window_s(m.drive_speed_um_s * 1e-6)).min(cap);
    }
    // The first stretch from the start; a longer one continues it (bit for
    // bit the stretch simulated at once: `sim::simulate_more`).
    SCRATCH.with_borrow_mut(|(_, force, _)| force.clear());
    loop {
        let f = SCRATCH.with_borrow_mut(|(state, force, time)| {
            // A law whose simulation leaves the physical range predicts nothing: no slip.
            let Ok(skip) = simulate_window(model, x, m, p, window, state, force) else {
                return Features::default_steady();
            };
            time.clear();
            time.extend((skip..force.len()).map(|i| i as f64 / m.sample_rate_hz));
            features(time, &force[skip..], &m.constants(p), &p.features)
        });
        let slow_slips = f.regime == Regime::SteadySliding && f.events > 0;
        let periods = f.period_s.n;
        let few = f.events > 0 && periods < p.spread_periods && !crate::fit::repeats(&f);
        if !(slow_slips || few) || window >= cap {
            return f;
        }
        // Periods in a stretch grow with it: n + 1 maxima in the window.
        let grow =
            if slow_slips || periods < 2 { 2.0 } else { 1.1 * (p.spread_periods + 1) as f64 / (periods + 1) as f64 };
        window = (grow.max(1.25) * window).min(cap);
    }
}

thread_local! {
    /// Each thread's simulation buffers (the state at the last sample, force
    /// over weight, time), reused across evaluations.
    static SCRATCH: std::cell::RefCell<(OneDofState, Vec<f64>, Vec<f64>)> = Default::default();
}

/// The simulated force of `cand` at run `m` after its warm-up, thinned to about `points` (for figures).
pub fn predict_trace(model: Model, x: &[f64], m: &Measured, p: &StudyParams, points: usize) -> (Vec<f64>, Vec<f64>) {
    let (mut state, mut f) = (OneDofState::default(), Vec::new());
    let Ok(skip) = simulate_window(model, x, m, p, window_s(m, p), &mut state, &mut f) else {
        return (Vec::new(), Vec::new());
    };
    let step = ((f.len() - skip) / points.max(1)).max(1);
    let t: Vec<f64> = (skip..f.len()).step_by(step).map(|i| (i - skip) as f64 / m.sample_rate_hz).collect();
    (t, f[skip..].iter().step_by(step).copied().collect())
}

/// Simulates `window` s of run `m` after a warm-up of `warmup_fraction` of it
/// into `force`; returns the number of warm-up samples at its start. An
/// empty `force` starts from rest; one a shorter call left (with `state`) is
/// continued ([`simulate_more`]).
fn simulate_window(
    model: Model,
    x: &[f64],
    m: &Measured,
    p: &StudyParams,
    window: f64,
    state: &mut OneDofState,
    force: &mut Vec<f64>,
) -> Result<usize, rig_model::ModelError> {
    let warmup_s = p.warmup_fraction * window;
    let (law, structure) = model.law(x);
    let setup = Setup {
        stiffness_n_m: m.stiffness_n_m,
        drive_speed_m_s: m.drive_speed_um_s * 1e-6,
        mass_kg: p.mass_kg,
        gravity_m_s2: p.gravity_m_s2,
        structure,
        duration_s: warmup_s + window,
        sample_rate_hz: m.sample_rate_hz,
        steps_per_period: p.steps_per_period,
        initial_force_over_weight: law.sliding_level(),
    };
    simulate_more(&law, &setup, state, force)?;
    Ok(((warmup_s * m.sample_rate_hz).round() as usize).min(force.len()))
}
