//! The phase-insensitive misfit: window features of a free run against the
//! measured ones, each error in units of its issue-10 target, combined by RMS.
//!
//! e = (sim − meas) / tol with tol = 10 % of the measured maximum
//! (`bit_speed_max_rpm`), 10 rpm (`bit_speed_min_rpm`), 25 % of the measured
//! stick fraction but at least 0.01 (25 % of 0.04, so a window that hardly sticks
//! does not divide by zero; `stick_fraction`), 3 % of the measured fundamental
//! (`fundamental_hz`; a run without a line scores the cap) and 30 % of the
//! measured loop area (`loop_area`), 10 % of the measured mean slip torque
//! (`slip_torque_nm`) and of the measured break-away torque
//! (`breakaway_torque_nm`: issue 26). A feature the measurement lacks (no stick
//! phase ends in the window) scores 0 when the run lacks it too, the cap
//! otherwise. Each |e| is capped at 10 so that one
//! diverging feature cannot hide the others.
//!
//! The misfit is joint in motion and torque (issue 26: "a friction law that
//! reproduces the motion with a friction level off the measured one by more
//! than its uncertainty is not an explanation"): the five motion features
//! ([`MOTION`]: bit-speed maximum and minimum, stick fraction, fundamental,
//! loop area) and the two torque-level features ([`TORQUE`]) weigh half each,
//! M = √(½ mean_motion e² + ½ mean_torque e²). A plain RMS over the seven
//! would let five motion features outvote the two torque ones (a model with
//! its motion on target and its torque level three tolerances off scored
//! √(18/7) = 1.60; jointly √(9/2) = 2.12). M ≤ 1 means motion and torque
//! level are, in this weighted RMS, within their targets; a feature meets its
//! target when |e| ≤ 1.

use crate::LaviError;
use crate::data::{Prepared, RPM_TO_RAD_S, WindowSpec, derivative};
use crate::features::{
    FeatureOptions, Features, N_FEATURES, StickTorque, stick_torque, window_features, window_features_and_stick,
};
use crate::sim::{Inputs, Job, Model, Run, Start, delay_samples, read_late, simulate_batch};
use rayon::prelude::*;
use std::collections::HashMap;
use std::sync::Mutex;
use std::sync::atomic::{AtomicUsize, Ordering};

/// Cap on one feature's normalised error.
pub const ERROR_CAP: f64 = 10.0;

/// Normalised errors of the features (order of [`crate::features::FEATURES`]).
pub fn feature_errors(meas: &Features, sim: &Features) -> [f64; N_FEATURES] {
    let tol = [
        0.10 * meas.bit_speed_max_rpm.abs(),
        10.0,
        0.25 * meas.stick_fraction.max(0.04),
        0.03 * meas.fundamental_hz,
        0.30 * meas.loop_area,
        0.10 * meas.slip_torque_nm.abs(),
        0.10 * meas.breakaway_torque_nm.abs(),
    ];
    let mut e = [0.0; N_FEATURES];
    for (i, ei) in e.iter_mut().enumerate() {
        let x = (sim.get(i) - meas.get(i)) / tol[i];
        *ei = if x.is_finite() {
            x.clamp(-ERROR_CAP, ERROR_CAP)
        } else if meas.get(i).is_nan() && sim.get(i).is_nan() {
            0.0
        } else {
            ERROR_CAP
        };
    }
    e
}

/// The motion features (indices into [`crate::features::FEATURES`]).
pub const MOTION: std::ops::Range<usize> = 0..5;
/// The torque-level features: mean slip torque, break-away torque.
pub const TORQUE: std::ops::Range<usize> = 5..N_FEATURES;

/// Mean square of the errors `e[r]`.
fn mean_square(e: &[f64], r: std::ops::Range<usize>) -> f64 {
    let n = r.len() as f64;
    e[r].iter().map(|x| x * x).sum::<f64>() / n
}

/// RMS over the motion features and over the torque features of [`feature_errors`].
pub fn group_misfits(meas: &Features, sim: &Features) -> (f64, f64) {
    let e = feature_errors(meas, sim);
    (mean_square(&e, MOTION).sqrt(), mean_square(&e, TORQUE).sqrt())
}

/// The joint misfit M = √(½ mean_motion e² + ½ mean_torque e²) (module docs).
pub fn misfit_of(meas: &Features, sim: &Features) -> f64 {
    let (motion, torque) = group_misfits(meas, sim);
    (0.5 * (motion * motion + torque * torque)).sqrt()
}

/// What a free run of a model on a window is judged by: its features and the
/// torque through its stick phases, or the sample where it diverged.
type Outcome = Result<(Features, StickTorque), usize>;

/// Free runs one batch of the core holds ([`Evaluator::outcomes`]): the
/// runs advance together, overlapping their chains (docs/performance.md,
/// sixteenth session: four at once cost about half of four one by one).
pub const BATCH: usize = 4;

/// A free run of a model on a window as the core takes it ([`Evaluator::simulate_many`]).
struct WindowRun<'e> {
    /// The model as run (`wob_level` as its scaled reference).
    model: Model,
    top: std::borrow::Cow<'e, [f64]>,
    top_ref: std::borrow::Cow<'e, [f64]>,
    /// The weight on bit's slow level over the whole record (`wob_level`).
    level: Option<std::borrow::Cow<'e, [f64]>>,
    span: std::ops::Range<usize>,
    start: Start,
}

/// Everything a free run and its score need, per window.
///
/// A free run is a pure function of the model and the window, so its outcome
/// is kept ([`Evaluator::outcome`]) keyed by the model's every field as `Debug`
/// prints it (each float's shortest round-trip digits: equal keys, equal
/// bits) and the window: the fits' final points, the selection's scores and
/// the report's features and stick torques of the same model are one run.
/// The numbers are the same as running it again; on any thread count, as a
/// run's outcome does not depend on which thread makes it first.
#[derive(Debug)]
pub struct Evaluator<'a> {
    pub data: &'a Prepared,
    /// Calibration window first.
    pub windows: Vec<WindowSpec>,
    pub measured: Vec<Features>,
    pub fopts: FeatureOptions,
    pub substeps: usize,
    pub slip_speed_rpm: f64,
    top_rad_s: Vec<f64>,
    top_ref_rad_s: Vec<f64>,
    bit_acc_rad_s2: Vec<f64>,
    /// The bit's angle, rad: the record's bit speed integrated from its first sample (`wob_angle`).
    bit_angle_rad: Vec<f64>,
    /// The weight on bit's slow level over the whole record at each span of `wob_level`'s fit.
    wob_levels: Vec<(f64, Vec<f64>)>,
    outcomes: Mutex<HashMap<(String, usize), Outcome>>,
    /// The least-squares derivations on the calibration window per structure ([`Evaluator::derivation`]).
    derivations: Mutex<HashMap<String, (Model, crate::fit::Derivation)>>,
    /// Free runs made and outcomes reused ([`Evaluator::run_counts`]).
    made: AtomicUsize,
    reused: AtomicUsize,
}

impl<'a> Evaluator<'a> {
    /// The study's evaluator: the record's windows judged with `p`'s
    /// feature options, substeps, slip speed and drive reference (the one
    /// place the study, its figures and its probes build it).
    pub fn of_study(data: &'a Prepared, windows: Vec<WindowSpec>, p: &crate::StudyParams) -> Result<Self, LaviError> {
        Self::new(
            data,
            windows,
            FeatureOptions::of_study(data.fs_hz, p),
            p.substeps,
            p.slip_speed_rpm,
            p.drive_ref_window_s,
        )
    }

    /// `drive_ref_window_s`: the centred moving mean of the measured top speed
    /// that the compliant drive's controller follows.
    pub fn new(
        data: &'a Prepared,
        windows: Vec<WindowSpec>,
        fopts: FeatureOptions,
        substeps: usize,
        slip_speed_rpm: f64,
        drive_ref_window_s: f64,
    ) -> Result<Self, LaviError> {
        let top_rad_s: Vec<f64> = data.top_rpm.iter().map(|v| v * RPM_TO_RAD_S).collect();
        let bit: Vec<f64> = data.bit_rpm.iter().map(|v| v * RPM_TO_RAD_S).collect();
        let half = ((drive_ref_window_s * data.fs_hz) as usize / 2).max(1);
        let mut prefix = vec![0.0; top_rad_s.len() + 1];
        for (i, v) in top_rad_s.iter().enumerate() {
            prefix[i + 1] = prefix[i] + v;
        }
        let n = top_rad_s.len();
        let top_ref_rad_s = (0..n)
            .map(|i| {
                (prefix[(i + half + 1).min(n)] - prefix[i.saturating_sub(half)])
                    / ((i + half + 1).min(n) - i.saturating_sub(half)) as f64
            })
            .collect();
        // The recorded channels through the same one low-pass as a simulated run's.
        let measured = windows
            .iter()
            .map(|w| {
                window_features(
                    &data.bit_raw_rpm[w.span.clone()],
                    &data.torque_raw_nm[w.span.clone()],
                    w.window.clone(),
                    &fopts,
                )
            })
            .collect::<Result<Vec<_>, _>>()?;
        Ok(Evaluator {
            data,
            windows,
            measured,
            fopts,
            substeps,
            slip_speed_rpm,
            top_rad_s,
            top_ref_rad_s,
            bit_acc_rad_s2: derivative(&bit, data.fs_hz),
            // The bit's angle ∫ Ω dt: the workspace's one trapezoid integral of a speed difference
            // (rig_model::one_dof::integrated_twist_rad), the bit against a resting reference.
            bit_angle_rad: rig_model::one_dof::integrated_twist_rad(
                &data.time_s,
                &data.bit_raw_rpm.iter().map(|v| v * RPM_TO_RAD_S).collect::<Vec<f64>>(),
                &vec![0.0; data.bit_raw_rpm.len()],
            ),
            wob_levels: crate::wob_level::levels(&data.wob_n, data.fs_hz),
            outcomes: Mutex::new(HashMap::new()),
            derivations: Mutex::new(HashMap::new()),
            made: AtomicUsize::new(0),
            reused: AtomicUsize::new(0),
        })
    }

    /// The compliant drives' reference: the measured top speed's centred moving mean, rad/s (whole record).
    pub fn top_ref_rad_s(&self) -> &[f64] {
        &self.top_ref_rad_s
    }

    /// The weight on bit's slow level W̄ of `l` over the whole record, N (made once per span of the fit).
    pub fn wob_level_n(&self, l: &crate::wob_level::WobLevel) -> std::borrow::Cow<'_, [f64]> {
        match self.wob_levels.iter().find(|(s, _)| *s == l.window_s) {
            Some((_, w)) => std::borrow::Cow::Borrowed(w),
            None => std::borrow::Cow::Owned(l.level_n(&self.data.wob_n, self.data.fs_hz)),
        }
    }

    /// The bit's angle over the whole record, rad (the record's bit speed integrated from its first sample).
    pub fn bit_angle_rad(&self) -> &[f64] {
        &self.bit_angle_rad
    }

    /// Index of the calibration window.
    pub fn calibration(&self) -> usize {
        0
    }

    /// Indices of the held-out windows.
    pub fn heldout(&self) -> Vec<usize> {
        (1..self.windows.len()).collect()
    }

    /// `fit::derive` of structure `st` on the calibration window, made once per
    /// structure (keyed by its `Debug`, every float's shortest round trip): the
    /// candidates of a step re-derive the current structure and the one they
    /// extend it to more than once (`restructure`, its law's check, the
    /// dampings pinned, `motor_drive`'s falling law). A pure function of the
    /// structure, so the same numbers on any thread count; an error is not kept.
    pub fn derivation(&self, st: crate::fit::Structure) -> Result<(Model, crate::fit::Derivation), LaviError> {
        let key = format!("{st:?}");
        if let Some(d) = self.derivations.lock().expect("no thread panicked holding the cache").get(&key) {
            return Ok(d.clone());
        }
        let d = crate::fit::derive(self.data, &self.windows[self.calibration()], self.slip_speed_rpm, st)?;
        self.derivations.lock().expect("no thread panicked holding the cache").insert(key, d.clone());
        Ok(d)
    }

    /// Free run of `m` over window `wi`'s span (warm-up included), from the measured state at its start.
    pub fn simulate(&self, m: &Model, wi: usize) -> Result<Run, LaviError> {
        self.simulate_many(&[(m, wi)]).pop().expect("a batch of one gives one run")
    }

    /// [`Evaluator::simulate`] of every (model, window) pair, in order: one
    /// batch of the core (`sim::simulate_batch`), the same bits as one by one.
    pub fn simulate_many(&self, pairs: &[(&Model, usize)]) -> Vec<Result<Run, LaviError>> {
        let setups: Vec<WindowRun> = pairs.iter().map(|&(m, wi)| self.window_run(m, wi)).collect();
        let jobs: Vec<Job> = setups
            .iter()
            .map(|w| {
                let u = Inputs {
                    fs_hz: self.data.fs_hz,
                    top_rad_s: &w.top,
                    wob_n: &w.level.as_deref().unwrap_or(&self.data.wob_n)[w.span.clone()],
                    top_ref_rad_s: &w.top_ref,
                };
                (&w.model, u, w.start)
            })
            .collect();
        simulate_batch(&jobs, self.substeps)
    }

    /// What the free run of `m` on window `wi` reads (the model as run, its inputs and start).
    fn window_run(&self, m: &Model, wi: usize) -> WindowRun<'_> {
        let s = self.windows[wi].span.clone();
        // The top speed on the bit's clock: the channel read τ_top later when it is late by τ_top.
        let k = delay_samples(m.structure.top_delay_s, self.data.fs_hz);
        let (top, top_ref) = (read_late(&self.top_rad_s, &s, k), read_late(&self.top_ref_rad_s, &s, k));
        // `wob_level`: the friction scaled by the weight on bit's slow level over its reference.
        let level = m.wob_level.map(|l| self.wob_level_n(&l));
        let model = match m.wob_level {
            Some(l) => Model { wob_ref_n: Some(l.reference_n), wob_level: None, ..*m },
            None => *m,
        };
        // The contact torque at the start as the channel reads it: τ later when the channel is late by τ.
        let at = (s.start as isize + delay_samples(model.torque_delay_s, self.data.fs_hz))
            .clamp(0, self.data.len() as isize - 1) as usize;
        let start = Start {
            bit_rad_s: self.data.bit_rpm[s.start] * RPM_TO_RAD_S,
            bit_acc_rad_s2: self.bit_acc_rad_s2[s.start],
            torque_nm: self.data.torque_nm[at],
            bit_angle_rad: self.bit_angle_rad[s.start],
        };
        WindowRun { model, top, top_ref, level, span: s, start }
    }

    /// Features and stick torque of the free run of `m` on window `wi` (the
    /// same functions as for the measurement), made once per model and window
    /// (type docs); a run that diverges is kept as such, any other error is not.
    pub fn outcome(&self, m: &Model, wi: usize) -> Result<(Features, StickTorque), LaviError> {
        self.outcomes(&[(m, wi)]).pop().expect("one pair gives one outcome")
    }

    /// [`Evaluator::outcome`] of every (model, window) pair, in order: the
    /// runs not kept yet are made in batches of [`BATCH`] free runs
    /// (`sim::simulate_batch`), the batches in parallel; the same numbers as
    /// one by one, on any thread count.
    pub fn outcomes(&self, pairs: &[(&Model, usize)]) -> Vec<Result<(Features, StickTorque), LaviError>> {
        let keys: Vec<(String, usize)> = pairs.iter().map(|(m, wi)| (format!("{m:?}"), *wi)).collect();
        let mut found: Vec<Option<Result<(Features, StickTorque), LaviError>>> =
            (0..pairs.len()).map(|_| None).collect();
        // The pairs to run: not kept yet, each key once.
        let mut todo: Vec<usize> = Vec::new();
        {
            let kept = self.outcomes.lock().expect("no thread panicked holding the cache");
            for (j, key) in keys.iter().enumerate() {
                if let Some(o) = kept.get(key) {
                    self.reused.fetch_add(1, Ordering::Relaxed);
                    found[j] = Some(o.map_err(|sample| LaviError::Diverged { sample }));
                } else if !todo.iter().any(|&t| keys[t] == *key) {
                    todo.push(j);
                }
            }
        }
        self.made.fetch_add(todo.len(), Ordering::Relaxed);
        let made: Vec<Result<(Features, StickTorque), LaviError>> = todo
            .par_chunks(BATCH)
            .flat_map_iter(|chunk| {
                let batch: Vec<(&Model, usize)> = chunk.iter().map(|&j| pairs[j]).collect();
                let runs = self.simulate_many(&batch);
                chunk
                    .iter()
                    .zip(runs)
                    .map(|(&j, r)| r.and_then(|r| self.outcome_of_run(&r, pairs[j].1)))
                    .collect::<Vec<_>>()
            })
            .collect();
        {
            let mut kept = self.outcomes.lock().expect("no thread panicked holding the cache");
            for (&j, o) in todo.iter().zip(&made) {
                let k = match o {
                    Ok(x) => Some(Ok(*x)),
                    Err(LaviError::Diverged { sample }) => Some(Err(*sample)),
                    Err(_) => None,
                };
                if let Some(k) = k {
                    kept.insert(keys[j].clone(), k);
                }
            }
        }
        for (&j, o) in todo.iter().zip(made) {
            found[j] = Some(o);
        }
        // A pair whose key came twice in `pairs`: the first's outcome (made once, as one by one).
        (0..pairs.len())
            .map(|j| match found[j].take() {
                Some(o) => o,
                None => {
                    let first = todo.iter().copied().find(|&t| keys[t] == keys[j]).expect("a key not kept is run");
                    match &found[first] {
                        Some(Ok(x)) => Ok(*x),
                        _ => self.outcome(pairs[j].0, pairs[j].1),
                    }
                }
            })
            .collect()
    }

    /// Features and stick torque of a free run on window `wi` (the same functions as for the measurement).
    fn outcome_of_run(&self, r: &Run, wi: usize) -> Result<(Features, StickTorque), LaviError> {
        let rpm: Vec<f64> = r.bit_rad_s.iter().map(|v| v / RPM_TO_RAD_S).collect();
        window_features_and_stick(&rpm, &r.torque_nm, self.windows[wi].window.clone(), &self.fopts)
    }

    /// Free runs made so far and outcomes reused instead of a run (a developer's count: `profile_study`).
    pub fn run_counts(&self) -> [usize; 2] {
        [self.made.load(Ordering::Relaxed), self.reused.load(Ordering::Relaxed)]
    }

    /// Features of the free run (the same function as for the measurement).
    pub fn features(&self, m: &Model, wi: usize) -> Result<Features, LaviError> {
        self.outcome(m, wi).map(|o| o.0)
    }

    /// [`StickTorque`] of window `wi`: as recorded (`m` None) or in the free run of `m`.
    pub fn stick_torque(&self, m: Option<&Model>, wi: usize) -> Result<StickTorque, LaviError> {
        let w = &self.windows[wi];
        match m {
            None => stick_torque(
                &self.data.bit_raw_rpm[w.span.clone()],
                &self.data.torque_raw_nm[w.span.clone()],
                w.window.clone(),
                &self.fopts,
            ),
            Some(m) => self.outcome(m, wi).map(|o| o.1),
        }
    }

    /// Misfit of `m` on window `wi`; a run that diverges scores the cap.
    pub fn misfit(&self, m: &Model, wi: usize) -> f64 {
        match self.features(m, wi) {
            Ok(f) => misfit_of(&self.measured[wi], &f),
            Err(_) => ERROR_CAP,
        }
    }

    /// [`Evaluator::misfit`] of every (model, window) pair, in order, their
    /// free runs made together ([`Evaluator::outcomes`]).
    pub fn misfits(&self, pairs: &[(&Model, usize)]) -> Vec<f64> {
        self.outcomes(pairs)
            .into_iter()
            .zip(pairs)
            .map(|(o, &(_, w))| match o {
                Ok((f, _)) => misfit_of(&self.measured[w], &f),
                Err(_) => ERROR_CAP,
            })
            .collect()
    }

    /// Misfits on every held-out window, in window order (run in parallel,
    /// collected in order: the same numbers on any thread count).
    pub fn heldout_misfits(&self, m: &Model) -> Vec<f64> {
        let pairs: Vec<(&Model, usize)> = self.heldout().into_iter().map(|w| (m, w)).collect();
        self.misfits(&pairs)
    }

    /// Features of the free run on every window (calibration first), in
    /// parallel and in window order; a run that fails has NaN features.
    pub fn all_features(&self, m: &Model) -> Vec<Features> {
        let pairs: Vec<(&Model, usize)> = (0..self.windows.len()).map(|w| (m, w)).collect();
        self.outcomes(&pairs).into_iter().map(|o| o.map_or(Features::NAN, |o| o.0)).collect()
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn features(v: [f64; N_FEATURES]) -> Features {
        Features {
            bit_speed_max_rpm: v[0],
            bit_speed_min_rpm: v[1],
            stick_fraction: v[2],
            fundamental_hz: v[3],
            loop_area: v[4],
            slip_torque_nm: v[5],
            breakaway_torque_nm: v[6],
            stick_phase_s: 0.05,
            stick_phases: 10,
            cycles: 10,
        }
    }

    #[test]
    fn motion_cannot_outvote_the_torque_level() {
        let meas = features([170.0, 5.0, 0.12, 2.7, 60.0, 2.0, 3.0]);
        // Motion exact, both torque levels three tolerances (30 %) low.
        let sim = features([170.0, 5.0, 0.12, 2.7, 60.0, 1.4, 2.1]);
        let (motion, torque) = group_misfits(&meas, &sim);
        assert!(motion.abs() < 1e-12 && (torque - 3.0).abs() < 1e-9, "{motion} {torque}");
        // Jointly √(9/2), where a plain RMS over the seven features gave √(18/7).
        assert!((misfit_of(&meas, &sim) - (4.5f64).sqrt()).abs() < 1e-9);
        // Torque exact, every motion feature one tolerance off: √(1/2).
        let sim = features([187.0, 15.0, 0.15, 2.781, 78.0, 2.0, 3.0]);
        assert!((misfit_of(&meas, &sim) - (0.5f64).sqrt()).abs() < 1e-9, "{}", misfit_of(&meas, &sim));
    }
}
