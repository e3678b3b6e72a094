//! The extension of an `unexplained` answer (issue 25, item 6;
//! ../shared/spec/diagnosis.md, `extension`): the best data-driven friction
//! term from a library of state and history signals the simulator carries
//! (rig-model's `extension` module and `Effect::FrictionExtension`), chosen
//! by sparse forward selection on the cross-validated **free-run** misfit.
//!
//! # The library
//!
//! | signal | acts on | fitted on |
//! |---|---|---|
//! | `slip_speed_rad_s` (\|Ω1\|) | μ in slip | every 5th slip sample: μ_obs/μ̂ − 1 |
//! | `breakaway_transient` (exp(−t_slip/τ_b), t_slip the time since the rotor last stood) | μ in slip | the same |
//! | `static_level` (1) | μs at break-away | every break-away: F_peak/(μ̂s·N) − 1 |
//! | `log_dwell` (ln(1 + t_stick/τ_d), t_stick the length of the stick episode) | μs at break-away | **free run** (below), with `static_level` |
//!
//! μ̂ and μ̂s are the final model's (findings and structure, each run with its
//! own nuisance phases); the records give μ_obs = F/N0 in slip
//! ([`crate::prepare`]) and, for every stick episode that ends in a
//! break-away (the estimation's rules, `rig_estimate::friction::stick_episodes`,
//! `[shared.stick_episodes]`, as the free-run `breakaway_friction` feature
//! reads them; the stretches of |Ω1| below the slip speed this used before
//! are mostly encoder chatter of a creeping rotor), the raw peak of the
//! friction force and the episode's length. Heat (integrated friction power) and
//! slid distance would need more simulator states (rig-model's docs); the
//! teacher-forced residual signature still names them.
//!
//! # The ageing law (issue 25, item 5)
//!
//! `log_dwell` always enters with `static_level`: μs(t_stick) = μs_model·(1 +
//! c_0 + c_d·ln(1 + t_stick/τ_d)) = μs0 + β·ln(1 + t_stick/τ_d), contact
//! ageing (Dieterich 1972; Baumberger & Caroli, Adv. Phys. 55 (2006) 279),
//! simulated in the rig model by `Effect::FrictionExtension` (the pad state
//! is the contact's age, reset at every stick/slip event and 0 at the start
//! of a run, which starts at rest). Its signature is at break-away and in
//! the stick durations, where teacher-forcing in slip cannot see it, and a
//! teacher-forced fit on the break-aways alone made the free run of the CI
//! battery's ageing case 18× worse (misfit 2.86 → 52.5), so c_d is fitted
//! **by free-run simulation**: Brent's search ([`brent_min`], at most
//! [`DWELL_FIT_EVALS`] free runs of the training runs) over c_d ∈ [0,
//! [`DWELL_SLOPE_MAX`]] of the training runs' mean squared free-run misfit
//! (every channel), with c_0 at each c_d the least squares of the training
//! break-aways (the level the records fix at that slope). τ_d = 0.1 s is not
//! fitted: every dwell of the rig (0.3 s steady sticks to 2 s from rest) is
//! several τ_d, where β·ln(1 + t/τ) hardly tells τ from β (the CI case's
//! truth, β = 0.028 at τ = 0.187 s, and the fit, β = 0.022 at 0.1 s, rise by
//! 0.052 and 0.053 over 1 s). The law lives here, in the extension's library,
//! and not in the vocabulary's free-run hook
//! ([`crate::effects::VocabularyEffect::fit_free_run`]): ageing is outside
//! the spec's vocabulary, so an ageing campaign is `unexplained` with this
//! extension (the `operating_point.breakaway_dwell` check keeps it so).
//!
//! # Fit, selection and gain
//!
//! A set of signals is fitted teacher-forced by least squares (the workspace's
//! solver, no intercept: the signals' coefficients are relative changes of the
//! model's coefficients) on the training folds, and every held-out run is then
//! **simulated free** with the model fitted without it; its free-run misfit
//! ([`crate::channels::free_run_misfit_channels`], every channel) is the
//! run's score. The selection is the one engine's
//! ([`rig_types::select::forward_select_from`], issue 26, item 3): the runs
//! are the units in campaign order, the diagnosis' folds over runs, the final
//! model the baseline, each signal a candidate ([`Signal`]: its fit refits
//! the current set with it), and each step judged by the selection's rule
//! (gain ≥ the minimum, paired run-level t ≥ `min_t`) against the model the
//! step starts from: the final model at step 1, then the last accepted set.
//! Until this moved onto the engine every step was compared with the final
//! model, so a second signal was accepted on the first one's gain. A run
//! whose free run gives no misfit (NaN) is left out of a comparison
//! ([`rig_types::select::compare_where_scored`]); ties go to the first
//! signal in library order; `log_dwell` brings `static_level`, which then no
//! longer applies ([`rig_types::select::Candidate::applies`]). The reported
//! extension is the selected set, or, when no signal passes, the first
//! step's best single signal (its gain then says it explains nothing), with
//! its gain over the final model. Coefficients are fitted on every run;
//! their standard errors are the jackknife over the folds (the run, not the
//! sample, is the independent unit).
//!
//! # Cost
//!
//! One free-run simulation of every operating point per candidate set: at
//! most 4 + 3 + 2 + 1 = 10 sets (the library has four signals), each one
//! rayon-parallel over runs (the engine collects in order; deterministic),
//! the reported set's read back from the study's cache, and the
//! teacher-forced rows are built once; a set with the ageing law adds its
//! free-run fit, (folds + 1) × at most [`DWELL_FIT_EVALS`] free runs of the
//! training runs (the CI ageing case: 2.4 → 14 s on a loaded 2-core
//! machine). Only an `unexplained` verdict with a baseline model pays it.
//! Those free runs hold the extension's break-away terms alone (its slip
//! coefficients are 0), so on a final model without vocabulary effects the
//! simulator takes exact steps for them (rig-model's docs, "Integrator"):
//! an `outside` case's diagnosis −42 % (docs/performance.md, fifteenth
//! session).

pub mod drift;
pub mod dwell;

use crate::channels::{
    ChannelCheck, FreeRunPair, FreeRunSettings, MeasuredRuns, free_run_channel_misfits_measured, free_run_checks_of,
    free_run_misfit_channels, free_run_pairs_measured, speed_floor_rad_s, with_run_phases,
};
use crate::prepare::RunSignals;
use crate::result::{Extension, ExtensionTerm, SpeedTraces, StepRow, round_sig};
use rig_estimate::friction::stick_episodes;
use rig_model::extension::{BREAKAWAY_TIME_S, DWELL_TIME_S, slip_signals, static_signals};
use rig_model::friction::{normal_force_n, slip_mu, static_mu};
use rig_types::contract::SelectionRule;
use rig_types::minimize::brent_min;
use rig_types::select::{
    Candidate, Fold, Search, SelectError, Selection, Study, compare_where_scored, forward_select_from, train_sets,
};
use rig_types::{Campaign, Effect, RigParams};
use std::collections::BTreeMap;
use std::sync::Mutex;

/// The library's signals, in the order of [`Effect::FrictionExtension`]'s
/// coefficients; the first two act in slip, the last two at break-away.
pub const SIGNALS: [&str; 4] = ["slip_speed_rad_s", "breakaway_transient", "static_level", "log_dwell"];

/// Index of `static_level` in [`SIGNALS`].
const LEVEL: usize = 2;
/// Index of `log_dwell` in [`SIGNALS`]: the ageing law, fitted in free run.
const DWELL: usize = 3;

/// Upper end of the ageing law's slope c_d = β/μs (relative growth of the
/// static level per e-fold of dwell; lower end 0: a contact strengthens with
/// its age, never weakens). Measured ageing of dry contacts is β/μ ≈ 0.01
/// (rocks, Dieterich 1972) to a few % (paper, polymers: Baumberger & Caroli
/// 2006); 0.15 leaves a factor of two above the largest.
pub const DWELL_SLOPE_MAX: f64 = 0.15;
/// Brent's tolerance on c_d (a tenth of the smallest slope the
/// `breakaway_dwell` check resolves, 0.006 ⊕ its standard error).
pub const DWELL_SLOPE_TOL: f64 = 5e-4;
/// Free-run simulations of the training runs per fit (Brent's evaluations).
pub const DWELL_FIT_EVALS: usize = 14;
/// A training run whose free run failed counts as this squared misfit (a
/// law that makes the integrator fail is no fit).
const FAILED_RUN_MISFIT: f64 = 1e6;

/// Teacher-forced rows of one run: (signals, relative error of the model).
#[derive(Debug, Default)]
struct RunRows {
    slip: Vec<([f64; 2], f64)>,
    breakaway: Vec<([f64; 2], f64)>,
}

/// The extension with its selection steps and the free runs of the
/// reported extension beside the record (held-out: each run simulated with
/// the coefficients fitted without its fold).
#[derive(Debug, Clone)]
pub struct ExtensionResult {
    pub extension: Extension,
    pub steps: Vec<StepRow>,
    pub traces: Vec<SpeedTraces>,
    /// The free-run checks of the extended model (held-out free runs).
    pub checks: Vec<ChannelCheck>,
}

/// What the extension is fitted and simulated from.
pub struct Inputs<'a> {
    pub c: &'a Campaign,
    /// The diagnosis' signals of every operating point (folds, slip samples, μ_obs).
    pub runs: &'a [RunSignals],
    /// The final model: baseline + findings + selected structure.
    pub model: &'a RigParams,
    /// `model`'s free runs (campaign order).
    pub before: &'a [FreeRunPair],
    /// Each run's nuisance phases (θ of the time and angle modulations).
    pub phases: &'a BTreeMap<String, (f64, f64)>,
    pub s: &'a FreeRunSettings,
    /// The records' side of every free run, measured once under `s`
    /// ([`MeasuredRuns::of`]): every free run here simulates only.
    pub measured: &'a MeasuredRuns,
    pub opts: &'a crate::DiagnoseOptions,
}

/// Fits, selects and simulates the extension on top of the final model
/// (module docs). `None` without operating points to fit.
pub fn extend(x: &Inputs) -> Option<ExtensionResult> {
    let Inputs { c, runs, model, before, s, opts, .. } = *x;
    let folds = runs.iter().map(|r| r.fold + 1).max().unwrap_or(0);
    let floor = speed_floor_rad_s(c, s);
    let base: Vec<f64> = runs
        .iter()
        .map(|r| {
            let q = before.iter().find(|q| q.id == r.id);
            q.and_then(|q| free_run_misfit_channels(q, floor)).unwrap_or(f64::NAN)
        })
        .collect();
    if folds == 0 || base.iter().all(|m| m.is_nan()) {
        return None;
    }
    let rows: Vec<RunRows> = {
        use rayon::prelude::*;
        runs.par_iter().map(|r| run_rows(r, &with_run_phases(model, x.phase(&r.id)), s)).collect()
    };
    let library = Library { x, rows, floor, base, pairs: Mutex::default() };
    // Fold f holds out fold f's runs and trains on the others (the vocabulary's folds).
    let run_folds: Vec<Fold> = (0..folds)
        .map(|f| {
            let (held_out, train): (Vec<usize>, Vec<usize>) = (0..runs.len()).partition(|&r| runs[r].fold == f);
            Fold { train, held_out }
        })
        .collect();
    let sel = select_signals(&library, &run_folds, &opts.selection).ok()?;
    let steps: Vec<StepRow> = sel.trials.iter().map(StepRow::from).collect();
    // The selected set, or else the first step's best single signal (module docs).
    let reported = sel.chosen.last().map(|&i| &sel.trials[i]).or_else(|| sel.step(1).find(|t| t.best))?;
    let set = reported.fitted.first()?.set.clone();
    // Its gain over the final model (each step was judged against the step before it).
    let cmp = compare_where_scored(&sel.baseline_misfits, &reported.misfits, &sel.fold_of, folds);
    let all: Vec<usize> = (0..runs.len()).collect();
    let full = library.fit_set(&set, &all)?;
    // The extended model's held-out free runs (each run simulated with the
    // coefficients fitted without its fold: the ones its score was read from).
    let model_of = |r: usize| {
        let s = sel.train_sets.iter().position(|t| *t == run_folds[runs[r].fold].train)?;
        Some(reported.fitted.get(s)?.coef)
    };
    let pairs: Vec<FreeRunPair> = (0..runs.len()).filter_map(|r| library.pair(r, model_of(r)?)).collect::<Vec<_>>();
    // The extended model's free-run checks (held-out runs): does it now match?
    let checks = free_run_checks_of(c, &pairs, s, &opts.channels);
    let free_run_flagged = checks
        .iter()
        .filter(|k| k.flagged)
        .map(|k| format!("{} {:.1}× (threshold {:.1})", k.channel, k.ratio, k.threshold))
        .collect();
    let terms = set
        .iter()
        .map(|&j| {
            let v: Vec<f64> = reported.fitted.iter().map(|m| m.coef[j]).collect();
            let k = v.len() as f64;
            let m = v.iter().sum::<f64>() / k.max(1.0);
            let se = if v.len() == folds && folds > 1 {
                ((k - 1.0) / k * v.iter().map(|x| (x - m).powi(2)).sum::<f64>()).sqrt()
            } else {
                f64::NAN
            };
            ExtensionTerm { signal: SIGNALS[j].into(), coefficient: round_sig(full[j], 4), stderr: round_sig(se, 2) }
        })
        .collect();
    let traces = before
        .iter()
        .map(|b| SpeedTraces {
            id: b.id.clone(),
            time_s: b.trace.time_s.clone(),
            measured_rad_s: b.trace.measured_rad_s.clone(),
            baseline_rad_s: b.trace.simulated_rad_s.clone(),
            extended_rad_s: pairs.iter().find(|e| e.id == b.id).and_then(|e| e.trace.simulated_rad_s.clone()),
        })
        .collect();
    Some(ExtensionResult {
        extension: Extension {
            formula: formula(&set, &full, static_mu(&model.friction), !sel.chosen.is_empty()),
            terms,
            free_run_misfit_before: round_sig(cmp.before, 4),
            free_run_misfit_after: round_sig(cmp.after, 4),
            relative_gain: round_sig(cmp.gain, 3),
            relative_gain_sd: round_sig(cmp.gain_fold_sd, 2),
            free_run_flagged,
        },
        steps,
        traces,
        checks,
    })
}

impl Inputs<'_> {
    /// Run `id`'s nuisance phases (θ of the time and angle modulations).
    fn phase(&self, id: &str) -> (f64, f64) {
        self.phases.get(id).copied().unwrap_or_default()
    }

    /// The final model with the extension's coefficients `coef`, run `id`'s phases set.
    fn with_extension(&self, coef: [f64; 4], id: &str) -> RigParams {
        let mut p = self.model.clone();
        p.effects.push(Effect::FrictionExtension {
            slip_speed_per_rad_s: coef[0],
            breakaway_transient: coef[1],
            static_level: coef[2],
            dwell_per_efold: coef[3],
        });
        with_run_phases(&p, self.phase(id))
    }
}

/// An extension fitted on one training set: the library's signals it holds
/// (indices into [`SIGNALS`], ascending) and their coefficients, relative
/// changes of the final model's (0 for a signal it does not hold). The
/// empty set is the final model.
#[derive(Debug, Clone, Default, PartialEq)]
pub struct Terms {
    pub set: Vec<usize>,
    pub coef: [f64; 4],
}

/// What the extension's selection asks of its study beside the misfit
/// ([`Study::score`]: a run's held-out free-run misfit, NaN where it has none):
/// the coefficients of a signal set fitted on the `train` runs.
trait SignalFits: Study<Terms> {
    fn fit_set(&self, set: &[usize], train: &[usize]) -> Option<[f64; 4]>;
}

/// One library signal as a candidate of the engine: its fit refits every
/// coefficient of the current set with it (the ageing law `log_dwell`
/// brings its level `static_level`, module docs); it no longer applies once
/// the current model holds it (brought as that companion).
struct Signal(usize);

impl<S: SignalFits> Candidate<S, Terms> for Signal {
    fn id(&self) -> &str {
        SIGNALS[self.0]
    }

    fn fit(&self, study: &S, current: &Terms, train: &[usize]) -> Result<Terms, String> {
        let mut set: Vec<usize> = current.set.iter().copied().chain([self.0]).collect();
        if self.0 == DWELL && !set.contains(&LEVEL) {
            set.push(LEVEL);
        }
        set.sort_unstable();
        let coef = study.fit_set(&set, train).ok_or_else(|| format!("{}: no least-squares fit", SIGNALS[self.0]))?;
        Ok(Terms { set, coef })
    }

    fn applies(&self, _: &S, current: &[Terms]) -> bool {
        !current.iter().any(|m| m.set.contains(&self.0))
    }
}

/// Forward selection over the library's signals on the one engine
/// ([`rig_types::select::forward_select_from`]): the runs are the units in
/// campaign order, `folds` the diagnosis' folds over runs, the baseline the
/// final model (the empty set) on every training set, each signal a
/// candidate, judged by the selection's rule against the step's starting
/// model (a unit scored NaN, a run with no free-run misfit, left out).
fn select_signals<S: SignalFits>(
    study: &S,
    folds: &[Fold],
    rule: &SelectionRule,
) -> Result<Selection<Terms>, SelectError> {
    let signals: Vec<Signal> = (0..SIGNALS.len()).map(Signal).collect();
    let candidates: Vec<&dyn Candidate<S, Terms>> = signals.iter().map(|c| c as &dyn Candidate<S, Terms>).collect();
    let baselines = vec![Terms::default(); train_sets(folds).len()];
    let search = Search { units_ascending: true, ..Search::default() };
    forward_select_from(study, &candidates, &baselines, folds, rule, &search)
}

/// The extension's study: the runs' teacher-forced rows, the final model's
/// free-run misfits, and every held-out free run simulated so far (by run
/// and coefficients: the reported set's are read back, not simulated twice).
struct Library<'a> {
    x: &'a Inputs<'a>,
    rows: Vec<RunRows>,
    floor: f64,
    /// The final model's free-run misfit of every run (NaN: none).
    base: Vec<f64>,
    pairs: FreeRuns,
}

/// The held-out free runs a [`Library`] has simulated, by run and the bits of
/// the extension's coefficients (`None`: no features to compare).
type FreeRuns = Mutex<BTreeMap<(usize, [u64; 4]), Option<FreeRunPair>>>;

impl Library<'_> {
    /// Run `r`'s free run with the extension's coefficients `coef` (`None`: no features to compare).
    fn pair(&self, r: usize, coef: [f64; 4]) -> Option<FreeRunPair> {
        let key = (r, coef.map(f64::to_bits));
        if let Some(q) = self.pairs.lock().expect("free-run cache").get(&key) {
            return q.clone();
        }
        let Inputs { c, runs, s, measured, .. } = *self.x;
        let id = runs[r].id.as_str();
        let q = free_run_pairs_measured(c, s, measured, |k| (k == id).then(|| self.x.with_extension(coef, id))).pop();
        self.pairs.lock().expect("free-run cache").insert(key, q.clone());
        q
    }

    /// Coefficients of a signal set fitted teacher-forced on the `train` runs.
    fn teacher_forced(&self, set: &[usize], train: &[bool]) -> Option<[f64; 4]> {
        let mut coef = [0.0; 4];
        for (part, offset) in [(0usize, 0usize), (1, 2)] {
            let cols: Vec<usize> = set.iter().filter(|&&j| j / 2 == part).map(|&j| j - offset).collect();
            if cols.is_empty() {
                continue;
            }
            let (mut x, mut y) = (Vec::new(), Vec::new());
            for (_, rr) in self.rows.iter().enumerate().filter(|(r, _)| train[*r]) {
                for (sig, e) in if part == 0 { &rr.slip } else { &rr.breakaway } {
                    x.push(cols.iter().map(|&j| sig[j]).collect::<Vec<f64>>());
                    y.push(*e);
                }
            }
            let b = rig_estimate::linear::ols(&x, &y, "friction extension").ok()?.beta;
            for (k, &j) in cols.iter().enumerate() {
                coef[j + offset] = b[k];
            }
        }
        Some(coef)
    }
}

impl Study<Terms> for Library<'_> {
    /// Run `r`'s held-out free-run misfit, every channel
    /// ([`free_run_misfit_channels`]); the final model's for the empty set;
    /// NaN where the free run gives none.
    fn score(&self, m: &Terms, r: usize) -> f64 {
        if m.set.is_empty() {
            return self.base[r];
        }
        self.pair(r, m.coef).and_then(|q| free_run_misfit_channels(&q, self.floor)).unwrap_or(f64::NAN)
    }
}

impl SignalFits for Library<'_> {
    /// The set fitted teacher-forced, and the ageing law (`log_dwell` with
    /// its `static_level`, module docs "The ageing law") by free-run
    /// simulation of the training runs: the slope c_d by Brent, the level c_0
    /// the break-aways' least squares at that slope.
    fn fit_set(&self, set: &[usize], train: &[usize]) -> Option<[f64; 4]> {
        let Inputs { c, runs, s, measured, .. } = *self.x;
        let mut mask = vec![false; runs.len()];
        train.iter().for_each(|&r| mask[r] = true);
        let mut coef = self.teacher_forced(set, &mask)?;
        if !set.contains(&DWELL) {
            return Some(coef);
        }
        let rows_b: Vec<(f64, f64)> = self
            .rows
            .iter()
            .enumerate()
            .filter(|(r, _)| mask[*r])
            .flat_map(|(_, rr)| rr.breakaway.iter().map(|(sig, e)| (sig[1], *e)))
            .collect();
        if rows_b.is_empty() {
            return Some(coef);
        }
        let n = rows_b.len() as f64;
        let level_at = |cd: f64| rows_b.iter().map(|(x, e)| e - cd * x).sum::<f64>() / n;
        let training: BTreeMap<&str, ()> = train.iter().map(|&r| (runs[r].id.as_str(), ())).collect();
        let misfit = |cd: f64| {
            let mut k = coef;
            (k[LEVEL], k[DWELL]) = (level_at(cd), cd);
            // Only the misfit is read: the features it does not read are not made.
            let misfits = free_run_channel_misfits_measured(
                c,
                s,
                measured,
                |id| training.contains_key(id).then(|| self.x.with_extension(k, id)),
                self.floor,
            );
            let m2: Vec<f64> = misfits.iter().map(|m| m.map_or(FAILED_RUN_MISFIT, |m| m * m)).collect();
            m2.iter().sum::<f64>() / m2.len().max(1) as f64
        };
        let cd = brent_min(0.0, DWELL_SLOPE_MAX, DWELL_SLOPE_TOL, DWELL_FIT_EVALS, misfit);
        (coef[LEVEL], coef[DWELL]) = (level_at(cd), cd);
        Some(coef)
    }
}

/// The extended law in words and symbols, with the coefficients fitted on
/// every run; `mu_s` the model's static coefficient (the ageing law's μs0
/// and β in its units).
fn formula(set: &[usize], coef: &[f64; 4], mu_s: f64, selected: bool) -> String {
    let has = |j: usize| set.contains(&j);
    let mut slip = Vec::new();
    if has(0) {
        slip.push(format!("{:+.4}·|Ω1|", coef[0]));
    }
    if has(1) {
        slip.push(format!("{:+.4}·exp(−t_slip/{BREAKAWAY_TIME_S} s)", coef[1]));
    }
    let mut stat = Vec::new();
    if has(LEVEL) {
        stat.push(format!("{:+.4}", coef[LEVEL]));
    }
    if has(DWELL) {
        stat.push(format!("{:+.4}·ln(1 + t_stick/{DWELL_TIME_S} s)", coef[DWELL]));
    }
    let mut parts = Vec::new();
    if !slip.is_empty() {
        parts.push(format!("μ = μ_model·(1 {})", slip.join(" ")));
    }
    if !stat.is_empty() {
        parts.push(format!("μs = μs_model·(1 {})", stat.join(" ")));
    }
    if has(DWELL) {
        parts.push(format!(
            "contact ageing μs(t_stick) = μs0 + β·ln(1 + t_stick/{DWELL_TIME_S} s) with μs0 = {:.4}, β = {:.4} per \
             e-fold of dwell (Dieterich 1972; Baumberger & Caroli 2006; β fitted by free-run simulation)",
            mu_s * (1.0 + coef[LEVEL]),
            mu_s * coef[DWELL]
        ));
    }
    let note = if selected {
        "selected on the cross-validated free-run misfit"
    } else {
        "the best single signal; it does not pass the selection rule"
    };
    format!(
        "{} (t_slip: time since the rotor last stood, t_stick: time stuck, rad/s for |Ω1|; {note})",
        parts.join("; ")
    )
}

/// The teacher-forced rows of one run against model `p` (its phases set).
fn run_rows(r: &RunSignals, p: &RigParams, s: &FreeRunSettings) -> RunRows {
    let mut out = RunRows::default();
    let n0 = r.normal_force_n;
    if n0 <= 0.0 || r.time_s.len() < 3 {
        return out;
    }
    let slip = s.slip_speed_rad_s;
    let n_of = |k: usize| normal_force_n(n0, &p.effects, p.harmonic.as_ref(), r.time_s[k], r.rotor_angle_rad[k]);
    // Time since the rotor last stood (|Ω1| below the slip speed); the run starts at rest.
    let mut since = vec![0.0; r.time_s.len()];
    let mut last = r.time_s[0];
    for (k, w) in r.rotor_speed_rad_s.iter().enumerate() {
        if w.abs() < slip {
            last = r.time_s[k];
        }
        since[k] = r.time_s[k] - last;
    }
    for (j, &k) in r.slip_idx.iter().enumerate().step_by(5) {
        let w = r.rotor_speed_rad_s[k].abs();
        let mu = slip_mu(&p.friction, w) * n_of(k) / n0;
        if mu.abs() > 1e-9 && j < r.mu_obs.len() {
            out.slip.push((slip_signals(w, since[k]), r.mu_obs[j] / mu - 1.0));
        }
    }
    // Every stick episode that ends in a break-away, by the estimation's
    // rules (`[shared.stick_episodes]`, the free-run `breakaway_friction`
    // feature's reading): its raw peak force against the model's static
    // level at that instant, and its length as the contact's age.
    if n0 >= s.stick_episodes.min_normal_force_n {
        let mu_s = static_mu(&p.friction);
        for e in stick_episodes(&r.time_s, &r.rotor_angle_rad, &s.stick_episodes) {
            let Some(kp) = e.clone().max_by(|&a, &b| r.friction_force_n[a].total_cmp(&r.friction_force_n[b])) else {
                continue;
            };
            let level = mu_s * n_of(kp);
            if level > 0.0 {
                let dwell = r.time_s[e.end - 1] - r.time_s[e.start];
                out.breakaway.push((static_signals(dwell), r.friction_force_n[kp] / level - 1.0));
            }
        }
    }
    out
}

/// Puts the extension into an `unexplained` diagnosis (its finding's
/// `extension`, the selection steps and the free runs for the report);
/// nothing for any other verdict. The one call from [`crate::diagnose`].
pub fn attach(d: &mut crate::Diagnosis, inputs: &Inputs) {
    if d.verdict != "unexplained" {
        return;
    }
    let Some(x) = extend(inputs) else { return };
    if let Some(f) = d.findings.iter_mut().find(|f| f.effect == "unexplained") {
        f.extension = Some(x.extension);
    }
    d.detail.extension_steps = x.steps;
    d.detail.extension_traces = x.traces;
    d.detail.extension_free_run = x.checks;
}

/// Parameters of the vocabulary findings that the extended model
/// ([`crate::channels::extended_params`]) or the simulator can only use at a
/// bound (issue 25, item 4: reported, never silently fixed): the extension's
/// ageing slope at an end of its bracket, the break-away
/// coefficient of a slip law that fits μk but not μs (the viscous law), held
/// at max(μs of the baseline, μk), and a
/// modulation depth outside [0, 1] (N would change sign; rig-model refuses it).
pub fn vocabulary_bounds(baseline: &RigParams, findings: &[crate::Finding]) -> Vec<crate::ParamAtBound> {
    let mut out = Vec::new();
    let mu_s0 = static_mu(&baseline.friction);
    for f in findings {
        let g = |k: &str| f.params.get(k).copied();
        // A slip law that fits its own μk but not its own μs (the viscous law)
        // keeps the baseline's break-away coefficient, held at μk when below it.
        if g("mu_static").is_none()
            && let Some(mu_k) = g("mu_kinetic").filter(|&m| m > mu_s0)
        {
            out.push(crate::ParamAtBound {
                parameter: format!("{}.mu_static", f.effect),
                bound: round_sig(mu_k, 4),
                unconstrained: round_sig(mu_s0, 4),
                meaning: format!(
                    "the slip law's μk {mu_k:.4} exceeds the baseline's break-away coefficient μs {mu_s0:.4}; the \
                     extended model holds μs at μk (no break-away below the slip level): the break-away level is \
                     not measured by the slip channel, see the free-run breakaway_friction check"
                ),
            });
        }
        // The ageing law's slope where its free-run fit stopped at an end of
        // its bracket [0, DWELL_SLOPE_MAX] (module docs, "The ageing law").
        let dwell = f.extension.iter().flat_map(|x| &x.terms).find(|t| t.signal == SIGNALS[DWELL]);
        if let Some(t) = dwell.filter(|t| {
            t.coefficient <= 2.0 * DWELL_SLOPE_TOL || t.coefficient >= DWELL_SLOPE_MAX - 2.0 * DWELL_SLOPE_TOL
        }) {
            let at_upper = t.coefficient > 0.5 * DWELL_SLOPE_MAX;
            out.push(crate::ParamAtBound {
                parameter: "extension.log_dwell".into(),
                bound: if at_upper { DWELL_SLOPE_MAX } else { 0.0 },
                unconstrained: t.coefficient,
                meaning: if at_upper {
                    "the ageing law's free-run fit wants a static level that grows faster with the dwell than any \
                     dry contact ages (bracket end): the break-aways follow something else than contact ageing"
                } else {
                    "the ageing law's free-run fit puts its slope at 0: the free run wants no contact ageing"
                }
                .into(),
            });
        }
        if let Some(a) = g("amplitude_ratio").filter(|a| !(0.0..=1.0).contains(a)) {
            out.push(crate::ParamAtBound {
                parameter: format!("{}.amplitude_ratio", f.effect),
                bound: if a < 0.0 { 0.0 } else { 1.0 },
                unconstrained: round_sig(a, 4),
                meaning: "a modulation depth outside [0, 1] makes the normal force change sign: the simulator \
                          refuses it, so the extended model's free run fails"
                    .into(),
            });
        }
    }
    out
}

#[cfg(test)]
mod tests;
