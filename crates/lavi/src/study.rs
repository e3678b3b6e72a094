//! The study in order: prepare, windows, features, baseline, candidates,
//! selection, the chapter's hypothesis (WOB), adequacy and signature.

use crate::data::{Prepared, RPM_TO_RAD_S, WindowSpec, prepare, windows};
use crate::eom::Damping;
use crate::fit::{
    AtBound, ChannelBalance, Derivation, LoopSpread, MAX_DELAY_S, Structure, best_delay_s, channel_balance, derive,
    loop_spread, narrowest_loop,
};
use crate::render::{StudyOutput, render};
use crate::score::Evaluator;
use crate::select::{Selection, forward_select, mean, overall};
use crate::signature::{SignatureTerm, residual_signature};
use crate::sim::{FrictionLaw, Model};
use crate::{Candidate, FeatureOptions, Features, LaviError, StickTorque, StudyParams, window_features};
use rig_ingest::lavi::LaviRecording;
use serde::Serialize;
use std::path::Path;

/// The chapter's hypothesis (Eq. 4-11: a vibrating normal force) on a rig that measures it.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct WobHypothesis {
    /// Relative WOB variation in the calibration window: std / mean.
    pub wob_relative_std: f64,
    /// Per window (calibration first): loop area of W(t)·μ(Ω_meas(t)) over the measured loop area.
    pub loop_fraction: Vec<f64>,
    pub loop_fraction_heldout_mean: f64,
    /// 1 − held-out misfit (baseline + WOB) / held-out misfit (baseline), RMS over the windows.
    pub misfit_gain: f64,
}

/// Every number of the study.
#[derive(Debug, Clone, Serialize)]
pub struct Study {
    pub params: StudyParams,
    pub windows: Vec<WindowSpec>,
    pub measured: Vec<Features>,
    pub baseline: Model,
    pub derivation: Derivation,
    pub baseline_features: Vec<Features>,
    pub selection: Selection,
    pub final_features: Vec<Features>,
    /// Per window (calibration first): the measured features of its first and of its second half
    /// (what the record resolves: a feature that moves this much within one window).
    pub halves: Vec<[Features; 2]>,
    pub wob: WobHypothesis,
    pub adequate: bool,
    pub signature: Vec<SignatureTerm>,
    /// Features of every step-1 candidate's free run per window (candidate order of the trials).
    pub candidate_features: Vec<(Candidate, Vec<Features>)>,
    /// The equation of motion under each structure tried, unconstrained (structure lead).
    pub structures: Vec<(String, Derivation)>,
    /// Per structure (order of `structures`): the held-out misfit (RMS over the windows) of its
    /// free run with J, k, c and the least-squares law of that structure (the
    /// law fitted to the torque as that structure reads it: T(t + τ) against Ω(t)
    /// for a delay), no simulation fit.
    pub structure_heldout: Vec<f64>,
    /// Per structure: that least-squares law.
    pub structure_laws: Vec<FrictionLaw>,
    /// The torque–speed cloud of the calibration window: as recorded, read at
    /// the equation of motion's best delay, and at its narrowest shift (±50 ms).
    pub loop_spread: [LoopSpread; 3],
    /// Parameters of the final model at a bound (least squares and simulation fits).
    pub parameters_at_bounds: Vec<AtBound>,
    /// Per window (calibration first): what the torque channel reads, teacher-forced
    /// ([`channel_balance`]): as recorded under the baseline's J, k, c, and read at the
    /// equation of motion's delay under that structure's J, k, c (calibration window).
    pub channel_balance: Vec<[ChannelBalance; 2]>,
    /// Per window: the torque through the stick phases as recorded and in the final model's free run.
    pub stick_torque: Vec<[StickTorque; 2]>,
    /// Per step-1 candidate (trial order): the torque through the stick phases of its free runs, per held-out window.
    pub candidate_stick_torque: Vec<(Candidate, Vec<StickTorque>)>,
    /// The drive that answers the bit (`motor_drive`): its identification and its free runs' channels.
    pub drive: Option<crate::drive::DriveReport>,
    /// The top speed's clock (`top_delay`): its scan, its rivals side by side, per window before → after.
    pub top_delay: Option<crate::top_delay::TopDelayReport>,
    /// The weight on bit's slow level (`wob_level`): its last trial per window before → after, side by side.
    pub wob_level: Option<crate::wob_level::WobLevelReport>,
    /// A static level above the law (`static_friction`): its last trial per window before → after, side by side.
    pub static_friction: Option<crate::static_friction::StaticFrictionReport>,
    /// Per window (calibration first): where the stick phases sit on the bit's angle, measured and in the final model's free run.
    pub angle_locks: Vec<crate::wob_angle::AngleLock>,
    /// Free runs made and outcomes reused over the study ([`Evaluator::run_counts`]; not an output).
    #[serde(skip)]
    pub free_runs: [usize; 2],
}

impl Study {
    /// The verdict: the first selected effect, `none`, or `unexplained`.
    pub fn verdict(&self) -> &'static str {
        if !self.adequate {
            "unexplained"
        } else {
            self.selection.chosen.first().map_or("none", |&i| self.selection.trials[i].candidate.id())
        }
    }
}

/// Runs the study on a LAVI CSV.
pub fn analyse(path: &Path, p: &StudyParams) -> Result<(Study, Prepared, LaviRecording), LaviError> {
    let (rec, d) = prepare(path, p)?;
    let wins = windows(&d, p)?;
    let ev = Evaluator::of_study(&d, wins.clone(), p)?;
    let (baseline, derivation) = derive(&d, &wins[0], p.slip_speed_rpm, Structure::BASELINE)?;
    let sim_features = |m: &Model| -> Vec<Features> { ev.all_features(m) };
    let baseline_features = sim_features(&baseline);
    let selection = forward_select(&ev, &baseline, &Candidate::ALL, p.fit_evaluations, &p.selection)?;
    let final_features = sim_features(&selection.final_model);
    let halves = halves_of(&d, &wins, &ev.fopts)?;
    let wob = wob_hypothesis(&ev, &selection)?;
    let adequate = overall(&selection.final_heldout) <= p.adequacy_threshold;
    let signature = if adequate { Vec::new() } else { residual_signature(&ev, &selection.final_model)? };
    let candidate_features: Vec<(Candidate, Vec<Features>)> =
        selection.trials.iter().filter(|t| t.step == 1).map(|t| (t.candidate, sim_features(&t.fitted.model))).collect();
    let structures = structure_lead(&d, &wins[0], p.slip_speed_rpm, &selection)?;
    let (structure_heldout, structure_laws) = structures
        .iter()
        .map(|(_, der)| {
            let (m, _) = derive(&d, &wins[0], p.slip_speed_rpm, der.structure)?;
            Ok((overall(&ev.heldout_misfits(&m)), m.friction))
        })
        .collect::<Result<Vec<(f64, FrictionLaw)>, LaviError>>()?
        .into_iter()
        .unzip();
    let tau = best_delay_s(&d, &wins[0], Structure::BASELINE, MAX_DELAY_S);
    let spread = |shift_s| loop_spread(&d, &wins[0], p.slip_speed_rpm, p.bins, shift_s);
    let loop_spread = [spread(0.0), spread(tau), narrowest_loop(&d, &wins[0], p.slip_speed_rpm, p.bins, MAX_DELAY_S)];
    let (aligned, _) =
        derive(&d, &wins[0], p.slip_speed_rpm, Structure { torque_delay_s: tau, ..Structure::BASELINE })?;
    let channel_balance =
        wins.iter().map(|w| [channel_balance(&d, w, &baseline), channel_balance(&d, w, &aligned)]).collect();
    let (_, final_der) = derive(&d, &wins[0], p.slip_speed_rpm, selection.final_model.structure)?;
    let mut parameters_at_bounds = final_der.at_bounds;
    for &i in &selection.chosen {
        for b in &selection.trials[i].fitted.at_bounds {
            if parameters_at_bounds.iter().all(|x| x.parameter != b.parameter) {
                parameters_at_bounds.push(b.clone());
            }
        }
    }
    let stick_torque = (0..wins.len())
        .map(|w| Ok([ev.stick_torque(None, w)?, ev.stick_torque(Some(&selection.final_model), w)?]))
        .collect::<Result<Vec<_>, LaviError>>()?;
    let candidate_stick_torque = selection
        .trials
        .iter()
        .filter(|t| t.step == 1)
        .map(|t| {
            let per: Vec<StickTorque> = ev
                .heldout()
                .into_iter()
                .map(|w| ev.stick_torque(Some(&t.fitted.model), w))
                .collect::<Result<_, _>>()?;
            Ok((t.candidate, per))
        })
        .collect::<Result<Vec<_>, LaviError>>()?;
    let drive = crate::drive::report(&ev, &selection)?;
    let top_delay = crate::top_delay::report(&selection, &candidate_features);
    let wob_level = crate::wob_level::report(&ev, &selection, &baseline, p)?;
    let static_friction = crate::static_friction::report(&ev, &selection, &baseline);
    let angle_locks = crate::wob_angle::angle_locks(&ev, &selection.final_model)?;
    let study = Study {
        params: p.clone(),
        windows: wins,
        measured: ev.measured.clone(),
        baseline,
        derivation,
        baseline_features,
        selection,
        final_features,
        halves,
        wob,
        adequate,
        signature,
        candidate_features,
        structures,
        structure_heldout,
        structure_laws,
        loop_spread,
        channel_balance,
        parameters_at_bounds,
        stick_torque,
        candidate_stick_torque,
        drive,
        top_delay,
        wob_level,
        static_friction,
        angle_locks,
        free_runs: ev.run_counts(),
    };
    Ok((study, d, rec))
}

/// The measured features of each window's first and second half (the same one function and
/// low-pass of the whole span as the window's own features, [`crate::features::window_features`]).
fn halves_of(d: &Prepared, wins: &[WindowSpec], o: &FeatureOptions) -> Result<Vec<[Features; 2]>, LaviError> {
    wins.iter()
        .map(|w| {
            let (b, t) = (&d.bit_raw_rpm[w.span.clone()], &d.torque_raw_nm[w.span.clone()]);
            let mid = w.window.start + w.window.len() / 2;
            Ok([
                crate::features::window_features(b, t, w.window.start..mid, o)?,
                crate::features::window_features(b, t, mid..w.window.end, o)?,
            ])
        })
        .collect()
}

/// Runs the study and renders its outputs (tables, figures, lavi.md, lavi-diagnosis.json).
pub fn run_study(path: &Path, p: &StudyParams) -> Result<StudyOutput, LaviError> {
    let (study, d, rec) = analyse(path, p)?;
    render(&study, &d, &rec)
}

/// The equation of motion of the calibration window under each structure the
/// negative damping may point at: the damping on the twist rate (baseline), on
/// the absolute bit speed, on both; a torque-channel delay (the best one by
/// least squares within ±50 ms); the sensor inertia the `sensor_inertia`
/// candidate fitted at step 1. Each unconstrained, with what it pins.
fn structure_lead(
    d: &Prepared,
    cal: &WindowSpec,
    slip_speed_rpm: f64,
    sel: &Selection,
) -> Result<Vec<(String, Derivation)>, LaviError> {
    let b = Structure::BASELINE;
    let tau = best_delay_s(d, cal, b, MAX_DELAY_S);
    let js = sel
        .trials
        .iter()
        .find(|t| t.step == 1 && t.candidate == Candidate::SensorInertia)
        .map_or(0.0, |t| t.fitted.model.sensor_inertia_kgm2);
    let list = [
        ("damping on the twist rate (baseline)".to_string(), b),
        ("damping on the absolute bit speed".to_string(), Structure { damping: Damping::Absolute, ..b }),
        ("damping on both".to_string(), Structure { damping: Damping::Both, ..b }),
        (format!("torque channel late by {:.0} ms", 1e3 * tau), Structure { torque_delay_s: tau, ..b }),
        (
            format!("torque channel late by {:.0} ms, damping on both", 1e3 * tau),
            Structure { torque_delay_s: tau, damping: Damping::Both, ..b },
        ),
        (format!("sensor inertia {js:.4} kg m2"), Structure { sensor_inertia_kgm2: js, ..b }),
    ];
    list.into_iter().map(|(name, st)| Ok((name, derive(d, cal, slip_speed_rpm, st)?.1))).collect()
}

fn wob_hypothesis(ev: &Evaluator, sel: &Selection) -> Result<WobHypothesis, LaviError> {
    let d = ev.data;
    let (m, _) = derive(d, &ev.windows[0], ev.slip_speed_rpm, Structure { wob: true, ..Structure::BASELINE })?;
    let w_ref = m.wob_ref_n.unwrap_or(1.0);
    let mut loop_fraction = Vec::new();
    for (wi, w) in ev.windows.iter().enumerate() {
        let s = w.span.clone();
        let pred: Vec<f64> = s
            .clone()
            .map(|i| {
                let om = d.bit_rpm[i] * RPM_TO_RAD_S;
                om.signum() * d.wob_n[i] / w_ref * m.friction.slip_nm(om)
            })
            .collect();
        let f = window_features(&d.bit_rpm[s], &pred, w.window.clone(), &ev.fopts)?;
        loop_fraction.push(f.loop_area / ev.measured[wi].loop_area);
    }
    let cal =
        ev.windows[0].span.start + ev.windows[0].window.start..ev.windows[0].span.start + ev.windows[0].window.end;
    let wob = &d.wob_n[cal];
    let misfit_gain = sel
        .trials
        .iter()
        .find(|t| t.step == 1 && t.candidate == Candidate::WobNormalForce)
        .map_or(f64::NAN, |t| t.relative_gain);
    Ok(WobHypothesis {
        wob_relative_std: crate::select::std(wob) / mean(wob),
        loop_fraction_heldout_mean: mean(&loop_fraction[1..]),
        loop_fraction,
        misfit_gain,
    })
}
