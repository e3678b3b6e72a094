//! Model vs measurement: which effects the rig model lacks, found by
//! cross-validation over runs, tested for adequacy against the noise, and —
//! when the vocabulary falls short — what the leftover mismatch follows.
//!
//! # What the diagnosis does (issues 5 and 9, ../shared/spec/diagnosis.md)
//!
//! 1. **Signals** ([`prepare`]): every `operating_point` run becomes angles and
//!    zero-lag speeds from the encoders, the calibrated friction force, the
//!    PI reference, the samples where rotor 1 certainly slips, and the
//!    sensor noise of the force and voltage channels measured in the data.
//!    Runs are assigned to `folds` cross-validation folds, stratified by
//!    set-point then normal force ([`prepare::stratified_folds`]), so a rare
//!    condition (the highest set speed) is in training and test alike.
//!    Runs with the brake open (`normal_force_n = 0`) carry no friction
//!    coefficient: the friction channel and the selection's units leave them
//!    out, the drive channel's fits read them
//!    ([`prepare::PreparedRuns`]: `friction_units`, `drive_units`).
//! 2. **Channels** the vocabulary acts on, predicted *teacher-forced* (driven by
//!    the measured Ω1, φ1, Ω2 and t, so a right model with a small period error
//!    is not punished): the friction coefficient in slip, μ_obs = F/N0
//!    ([`friction`], [`composite`], Eq. 4-10), and the armature voltage of the
//!    PI drive ([`drive`]). The vocabulary is one file per effect ([`effects`], `REGISTRY`).
//! 3. **Forward selection** ([`select`], on the workspace's one engine,
//!    `rig_types::select`: the runs are its units, the k folds over runs its
//!    folds, each effect of the registry a candidate): starting from the baseline (Coulomb μk,
//!    drive saturating at `supply_voltage_v`), every remaining effect is added
//!    to the current model, fitted on the training folds and scored on the
//!    held-out fold (each run is held out exactly once). The effect with the
//!    largest cross-validated gain is kept when the gain is at least
//!    `min_relative_gain` AND the paired run-level t statistic of
//!    ln(M_before/M_after) over the held-out runs is at least `min_t`, and
//!    when it is **admissible**: fitted on every run it has the sign that
//!    defines it (viscous c > 0, velocity weakening μs > μk). A best effect
//!    with the opposite sign is a shape the vocabulary lacks (for example a
//!    fading brake: friction falling with slip power), so selection stops and
//!    the adequacy test judges the mismatch. Repeat until no effect earns its
//!    place; the retained effects are then refitted jointly on every run for
//!    the reported parameters.
//! 4. **Structure** ([`structure`]): where the damping acts (the rig model's
//!    twist rate, the absolute rotor speed, both) and whether a recorded
//!    channel lags the others, each candidate fitted teacher-forced through
//!    the rotor torque balance and selected on the cross-validated balance
//!    and free-run misfits on top of the extended model; reported in
//!    `structure`, and a winner other than the rig model's is a finding
//!    after the vocabulary's (the verdict when there is none). Parameters a
//!    fit wants below their physical bound go to `parameters_at_bounds`.
//! 5. **Adequacy**: the final model's cross-validated misfit against the noise
//!    floor (ratio ≤ `adequacy_ratio`), no angle-locked order line left in most
//!    runs ([`lines`]), no flagged check of the other run kinds
//!    (`channel_checks`), and — since issue 25 — no flagged free-run check
//!    of the final model (baseline + findings + structure simulated from rest
//!    at every operating point: regime, rotor-speed extrema, stick-slip
//!    fundamental; `where` names `free_run`). A model that fails is `unexplained`; the effects
//!    found are kept as a partial explanation and the `unexplained` finding
//!    carries the residual [`signature`]: the signals of a library computed
//!    from the recordings that the leftover residual follows, found by
//!    sequentially thresholded least squares fitted on training folds and
//!    scored on held-out folds.
//! 6. **Second look in free run** ([`second_look`]): when the final model's
//!    free run is flagged while the model is otherwise adequate (the
//!    mismatch shows only in the motion; the structure the rig model's), each effect
//!    the last step refused with a significant paired t but a gain below the
//!    minimum is added with its parameters fitted without each fold, every
//!    run is simulated free, and the effect is admitted when its free-run
//!    gain passes the same rule and no free-run check is left flagged with
//!    it; steps 3–5 are then concluded again with it. An effect too small to
//!    earn its place teacher-forced can still be what the motion shows.
//!
//! # The misfit (defined once; every table and JSON field uses it)
//!
//! For a model m and one run r:
//!
//! `M_r = sqrt( (e_μ² + e_V²) / 2 )`, with
//! `e_μ = RMS_slip(μ̂ − μ_obs) / mean_slip(μ_obs)` (relative error of the
//! friction coefficient over the run's slip samples) and
//! `e_V = RMS(V̂ − V) / supply_voltage_v` (relative error of the drive voltage
//! over the whole run). A run without slip samples (or with N0 = 0) uses
//! `M_r = e_V`. Over a set of runs, `M = sqrt(mean_r M_r²)`. It is
//! dimensionless; its noise floor is the same expression with the RMS errors
//! replaced by the measured sensor noise (σ_F/N0 and σ_V).
//!
//! # The free-run misfit (structure selection)
//!
//! For a model simulated free from rest at run r and the record, over the
//! same steady window: `M_fr,r = sqrt(1 + mean(e²))`, with e_max, e_min the
//! measured − simulated extreme of Ω1 in units of that run's floor of it
//! (the speed resolution of the centred difference ⊕ the extreme's spread
//! over the record's stick-slip cycles), and e_f the stick-slip fundamental's
//! relative error over the relative Rayleigh resolution 1/(T·f) when record
//! and simulation both stick and slip ([`channels::free_run_misfit`]; the
//! structure is selected on it and on the rotor balance, [`structure`]). Over runs, RMS, as M. The extension of an
//! `unexplained` answer ([`extension`]) is selected on the same misfit over
//! every recorded channel's feature ([`channels::free_run_misfit_channels`]:
//! also Ω2 extremes, voltage mean and swing, slip and break-away friction,
//! stick fraction; features and floors in `channels::free_run`'s docs).

//! # The criterion (one that can say no)
//!
//! The 500 Hz samples of a run are strongly correlated (the friction residual
//! of a missing effect is a smooth function of time or angle), so a sample-wise
//! likelihood (the BIC this replaced) counts thousands of dependent samples as
//! independent and passes even losing candidates. The unit of evidence here is
//! the run: `criterion` in diagnosis.json is `−t`, t the paired one-sample t
//! statistic of d_r = ln(M_r,before / M_r,after) over the held-out runs (each
//! run's misfit computed by a model that never saw it). Negative favours the
//! candidate; |t| ≥ 2 at 12–30 runs is a one-sided p ≲ 0.03. Gains are
//! reported with their spread across folds.
//!
//! # Calibration of the thresholds
//!
//! `min_t`, `min_relative_gain` and `adequacy_ratio` live in pipeline.toml.
//! `adequacy_ratio` = 4 was set with the probe example of rig-virtual-rig
//! (small protocol): 12 effect-free campaigns (seeds 101–112) gave final
//! misfits of 1.03–1.47× the noise floor, the right model of every
//! vocabulary effect (two draws each, seeds 201–202) 0.46–2.29×, so 4 leaves
//! a margin above both while an effect outside the vocabulary (48–99× in the
//! campaigns that motivated issue 9) fails it. The thresholds of the other
//! run kinds' checks are calibrated on 30 nulls ([`ChannelOptions`]). The
//! `confusion` stage publishes the battery's false alarms and confusion
//! matrix with every run.

pub mod breakaway;
pub mod channels;
pub mod composite;
pub mod drive;
pub mod effects;
pub mod extension;
pub mod friction;
pub mod lines;
pub mod prepare;
pub mod render;
mod result;
pub mod second_look;
pub mod select;
pub mod signature;
pub mod structure;

pub use channels::{ChannelCheck, ChannelOptions, extended_params};
pub use effects::EffectId;
pub use prepare::{ForceCal, RunSignals};
pub use result::{
    Adequacy, CandidateScore, ChannelFeatures, Diagnosis, DriveChannel, DriveRunError, Extension, ExtensionTerm,
    Finding, ParamAtBound, RunRow, SignatureEntry, StepRow, Structure, StructureScore, round_sig,
};
use rig_types::pipeline_toml::stage_params;
pub use select::diagnose_signals;

/// Knobs of the diagnosis: the `[stage.params]` of the `diagnosis` stage in
/// pipeline.toml, which is their one home (no defaults in code: tests read
/// them from the same file with [`DiagnoseOptions::from_pipeline_toml`]).
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DiagnoseOptions {
    /// Cross-validation folds over the operating points (stratified by
    /// set-point, then normal force: consecutive runs of one condition go to
    /// different folds).
    pub folds: usize,
    /// A cross-validation fold's model is fitted on its training runs' slip
    /// samples this far apart, s ([`friction::SlipData::from_runs_spaced`];
    /// 0: every sample). Measured (example `fold_thinning` of
    /// rig-virtual-rig, docs/performance.md): the μ residuals of a right
    /// model are white — τ = 1.0 ([`friction::inflation_of`]) on the shipped
    /// campaign's normal-force fit and on nulls, since μ is the force
    /// sensor's reading over N0, not a differentiated speed — and correlated
    /// (τ ≈ 77 samples, 0.15 s) only where the model lacks a modulation. So
    /// thinning by s costs a right model √s in its parameters' errors (the
    /// fits on every run — admissibility, the reported parameters and their
    /// errors — keep every sample). A fold's model only scores its held-out
    /// runs, on every sample, whose expected misfit grows by p/N of the noise
    /// variance for p shared parameters and N kept samples (≈ 10⁻⁴ at
    /// 60 000), far below the selection's 5 % gain; the kept samples stay on
    /// a uniform grid, 62.5 Hz at 16 ms, above twice the 10 Hz scan.
    pub fold_fit_spacing_s: f64,
    /// Rotor speed: centred difference over ±this many seconds (counted in
    /// samples from each run's time column).
    pub rotor_speed_half_window_s: f64,
    /// Motor speed (for the PI error): centred difference over ±this many seconds.
    pub motor_speed_half_window_s: f64,
    /// |Ω1| above which (and away from stuck samples) rotor 1 counts as slipping, rad/s.
    pub slip_speed_rad_s: f64,
    /// Slip samples before this time are not used (start-up), s.
    pub skip_start_s: f64,
    /// Steady state starts at ramp_s + settle_s.
    pub settle_s: f64,
    /// An effect must lower the cross-validated misfit by at least
    /// `min_relative_gain` with a paired run-level t of ln(M_before/M_after) of
    /// at least `min_t` (`[shared.selection]`, the one rule of
    /// `rig_types::select`, shared with the LAVI and slider studies).
    pub selection: rig_types::contract::SelectionRule,
    /// The final model is adequate when its cross-validated misfit is at most
    /// this many times the noise floor (calibrated on effect-free campaigns).
    pub adequacy_ratio: f64,
    /// STLSQ threshold of the residual signature, in standard deviations of the residual.
    pub signature_threshold: f64,
    /// Frequency grid of the normal-force modulation scan, Hz.
    pub freq_min_hz: f64,
    pub freq_max_hz: f64,
    pub freq_step_hz: f64,
    /// Highest order per revolution scanned (angle-periodic friction, order lines).
    pub max_order: u32,
    /// Order-line power over its local floor that counts as a line.
    pub line_ratio: f64,
    /// Checks of every run kind (static twist, voltage steps, free run,
    /// torque balance): `[stage.params.channels]`.
    pub channels: channels::ChannelOptions,
    /// The regime classifier, the one definition of stick-slip
    /// (`[shared.classify]` of pipeline.toml, handed to the stage).
    pub classify: rig_sweep::ClassifyOptions,
    /// The voltage-step fit, as the estimation's (pipeline.toml's
    /// `[shared.voltage_steps]`): the step checks' window and the motor
    /// side refitted under each damping candidate.
    pub voltage_steps: rig_estimate::VoltageStepFit,
    /// Integrator tolerances of every simulation of the checks (free runs,
    /// voltage steps): pipeline.toml's `[shared.integrator]`, as the
    /// simulation, sweeps, spectra and estimation stages.
    pub integrator: rig_model::SimOptions,
    /// How stick episodes and slip are read from the records (the
    /// estimation's μs rules, pipeline.toml's `[shared.stick_episodes]`):
    /// the extended model's break-away level ([`breakaway`]).
    pub stick_episodes: rig_estimate::FrictionOptions,
}

impl DiagnoseOptions {
    /// The `[stage.params]` of the stage named `diagnosis` in a pipeline.toml text.
    pub fn from_pipeline_toml(text: &str) -> Result<Self, String> {
        stage_params(text, "diagnosis")
    }
}

/// The blind chain's options — calibrate → estimate → diagnose, what
/// [`diagnose_campaign`] runs — as the DAG's `campaign-calibration`,
/// `estimation` and `diagnosis` stages run them: their `[stage.params]` in
/// pipeline.toml (the one home of every default), with the `[shared.<name>]`
/// tables each lists. The confusion stage gets them from the runner's parsed
/// config (`params_of`); tests, benches and examples from the same file
/// with [`BlindChain::from_pipeline_toml`]. Field names are the stage names.
#[derive(Debug, Clone, PartialEq, serde::Serialize, serde::Deserialize)]
#[serde(deny_unknown_fields)]
pub struct BlindChain {
    /// `campaign-calibration`'s params.
    #[serde(rename = "campaign-calibration")]
    pub calibration: rig_calibrate::CalibrationSettings,
    /// `estimation`'s params (mapped onto `EstimateOptions` by
    /// [`rig_estimate::EstimateParams::options`], as the stage does).
    pub estimation: rig_estimate::EstimateParams,
    /// `diagnosis`'s params.
    pub diagnosis: DiagnoseOptions,
}

impl BlindChain {
    /// The three stages' params in a pipeline.toml text.
    pub fn from_pipeline_toml(text: &str) -> Result<Self, String> {
        Ok(BlindChain {
            calibration: stage_params(text, "campaign-calibration")?,
            estimation: stage_params(text, "estimation")?,
            diagnosis: stage_params(text, "diagnosis")?,
        })
    }

    /// The chain's first two links: the campaign's calibration and, when the
    /// thesis' Table 4.4 is given to start from, the estimated baseline (or
    /// why the estimate failed: [`diagnose_campaign`] reports that as data).
    pub fn calibrate_and_estimate(
        &self,
        c: &rig_types::Campaign,
        thesis: Option<&rig_calibrate::ThesisData>,
    ) -> Result<Baseline, DiagnoseError> {
        let cal = rig_calibrate::calibrate_campaign_with(c, &self.calibration)
            .map_err(|e| DiagnoseError::Calibration(e.to_string()))?;
        let baseline = thesis.map(|t| {
            let o = self.estimation.options(rig_estimate::InitialValues::from_thesis_data(t));
            rig_estimate::estimate_rig(c, &cal, &o).map(|e| e.params)
        });
        Ok((cal, baseline))
    }
}

/// A campaign's calibration and its estimated baseline (`None`: no thesis
/// values to start from), as [`BlindChain::calibrate_and_estimate`] gives them.
pub type Baseline =
    (rig_calibrate::CampaignCalibration, Option<Result<rig_types::RigParams, rig_estimate::EstimateError>>);

/// Why a diagnosis could not be made.
#[derive(Debug, thiserror::Error)]
pub enum DiagnoseError {
    #[error("campaign {campaign}: needs at least {needed} operating_point runs (has {found}) to fit and hold out")]
    TooFewRuns { campaign: String, needed: usize, found: usize },
    #[error("run {run}: column {column} is missing (operating_point runs need it, recording-format.md)")]
    MissingColumn { run: String, column: &'static str },
    #[error("campaign calibration failed: {0}")]
    Calibration(String),
    #[error("baseline estimation failed: {0}")]
    Estimation(String),
    #[error("the baseline fit is singular: {0}")]
    Singular(&'static str),
    /// The engine refused the folds (`rig_types::select::SelectError`).
    #[error("{0}")]
    Selection(String),
}

/// Diagnosis of a campaign whose calibration is done: prepares the signals
/// with the campaign's force calibration, selects the effects and tests the
/// final model's adequacy. The drive's steady-state balance across the
/// operating points needs no model and always enters the adequacy test. When
/// a baseline `RigParams` is given, the other run kinds are checked too
/// ([`channels`]): static twist, voltage steps (with the estimate, in the
/// structure it was fitted in) and the rotor torque balance enter the
/// adequacy test; every operating point is simulated free-run with the
/// baseline and with the extended model (the baseline plus the findings,
/// [`extended_params`]); the structure (damping placement, channel delay)
/// is selected on the rotor balance and those free runs ([`structure`]),
/// and the free-run checks of the final model
/// (extended model in the selected structure) enter the adequacy test.
/// Their thresholds are calibrated on stick-slipping effect-free campaigns
/// (crates/virtual-rig/tests/free_run_calibration.rs, [`ChannelOptions`]).
pub fn diagnose(
    c: &rig_types::Campaign,
    cal: &rig_calibrate::CampaignCalibration,
    baseline: Option<&rig_types::RigParams>,
    thesis_mu_dynamic: Option<f64>,
    opts: &DiagnoseOptions,
) -> Result<Diagnosis, DiagnoseError> {
    let fc = ForceCal { factor_mv_per_n: cal.force_factor_mv_per_n, offset_mv: cal.force_offset_mv };
    let o = &opts.channels;
    // The force sensor first: when its calibration line fails, the slip
    // channel reads forces through the calibration runs' parabola instead, so
    // the friction laws are fitted to forces and not to the sensor's bend
    // (the failed check still makes the verdict `unexplained`).
    // The model's kinetic level is the estimation's, fitted on these records:
    // its standard error bounds how well any free run can match the slip
    // force, and what a bend of the force sensor must exceed to matter.
    let friction =
        rig_estimate::estimate_friction(c, cal.force_offset_mv, cal.force_factor_mv_per_n, &opts.stick_episodes).ok();
    let mu_k_se = friction.as_ref().and_then(|f| f.mu_kinetic_stderr).unwrap_or(0.0);
    let mu_relative_se = friction.as_ref().and_then(|f| Some(f.mu_kinetic_stderr? / f.mu_kinetic));
    let mut force_check = channels::force_linearity_check(c, o, mu_relative_se);
    let law = match channels::force_parabola(c).filter(|_| force_check.flagged) {
        Some(q) => {
            force_check.detail.push_str(&format!(
                "; the slip channel reads forces through that parabola (mV = {:.2} + {:.3}·F {:+.4}·F²)",
                q[0], q[1], q[2]
            ));
            prepare::SensorLaw::Parabola(q)
        }
        None => prepare::SensorLaw::Line(fc),
    };
    // Every operating point, split by channel (prepare::PreparedRuns, the one
    // home of the rule): the friction selection, its folds, the slip-force,
    // break-away and ageing checks, the second look and the extension read
    // the runs with the brake applied; the drive channel's fits (inside the
    // selection) the runs with the brake open too.
    let prepared = prepare::prepare_units(c, law, opts)?;
    let runs = prepared.friction_units();
    let mut checks: Vec<ChannelCheck> = Vec::new();
    let recorded = baseline.map(|_| channels::Recorded::of(c, cal, opts, o));
    let balance = recorded.as_ref().map(channels::Recorded::balance);
    if let (Some(p), Some(data)) = (baseline, &balance) {
        checks.extend(channels::static_twist_checks(c, cal, o));
        checks.push(channels::torque_balance_check_of(c, data, p, o));
        checks.push(channels::tick_loss_check_of(data, o));
    }
    // The drive balance needs no baseline: it fits its coefficients to the records.
    checks.push(channels::drive_balance_check(c, opts, o));
    // So does the force sensor's linearity: the calibration runs against their own line.
    checks.push(force_check);
    // Contact ageing shows only at break-away (issue 25, item 5): the records'
    // break-away level against the dwell, within runs (extension::dwell).
    // With a model, the record's against the final model's free run (below):
    // a modulated normal force moves the first break-away too.
    if baseline.is_none() {
        checks.push(extension::dwell::breakaway_dwell_check(
            runs,
            opts.slip_speed_rad_s,
            opts.rotor_speed_half_window_s,
            o.breakaway_dwell_ratio,
        ));
    }
    // A fading pad shows as a slow trend of the slip force within a run, which
    // no vocabulary model has (extension::drift).
    checks.push(extension::drift::slip_drift_check(runs, opts.settle_s, o.slip_drift_ratio));
    let flagged_of = |v: &[ChannelCheck]| v.iter().filter(|k| k.flagged).map(ChannelCheck::as_pair).collect::<Vec<_>>();
    // The findings do not depend on the flagged checks (only the adequacy
    // test does): one forward selection, concluded once per set of flags.
    let conclude = |sel: &select::Selection, flagged: &[(String, String)]| {
        sel.conclude(&c.name, c.rig.brake_disc_radius_m, thesis_mu_dynamic, flagged, opts)
    };
    // The selection is concluded on every check that needs no finding —
    // the model-free ones and the voltage steps, which judge the estimate
    // alone — and again only when the final model's free-run checks flag
    // something. The baseline's free runs need no finding either: they run
    // beside the selection.
    let flagged0 = flagged_of(&checks);
    let s = channels::FreeRunSettings::of(opts, o).with_force(law).with_mu_kinetic_stderr(mu_k_se);
    // The voltage steps judge the estimate on the runs it was fitted to, in
    // the structure it was fitted in (rig-estimate fits the twist-rate
    // placement; with another structure its motor-side coefficients absorb
    // the rotor's drag, so the selected structure on top of the estimate
    // would count that drag twice on the steps).
    let steps = baseline
        .map(|p| channels::voltage_step_checks(c, cal, p, o, opts.voltage_steps.residual_window_s, &opts.integrator))
        .unwrap_or_default();
    let mut flagged1 = flagged0.clone();
    flagged1.extend(flagged_of(&steps));
    let (sel, base_pairs) = rayon::join(
        || select::select_effects(&c.name, &prepared, c.rig.supply_voltage_v, opts),
        || {
            // The records' side of every free run, read once and shared by the
            // baseline's, the extended and the final model's runs.
            baseline.map(|p| {
                let m = channels::MeasuredRuns::of(c, &s);
                let pairs = channels::free_run_pairs_measured(c, &s, &m, |_| Some(p.clone()));
                (m, pairs)
            })
        },
    );
    let (measured, base_pairs) = base_pairs.unzip();
    let mut found = sel?;
    // The structural candidates' balances depend on the records alone: built
    // once, though the second look may conclude twice.
    let sdata = std::sync::OnceLock::new();
    // The free-run second look (second_look module docs) may admit one
    // effect and conclude again: at most two passes.
    let mut looked = false;
    let mut second_look_rows: Vec<second_look::SecondLookRow> = Vec::new();
    let mut steps = Some(steps);
    let mut d;
    loop {
        d = conclude(&found, &flagged1);
        if let (Some(p), Some(data), Some(base_pairs)) = (baseline, &balance, base_pairs.as_ref()) {
            let vocab: Vec<(EffectId, std::collections::BTreeMap<String, f64>)> =
                d.findings.iter().filter_map(|f| EffectId::from_id(&f.effect).map(|e| (e, f.params.clone()))).collect();
            // Each run's free run with its own nuisance phases (θ free per run, as
            // the spec's laws and the teacher-forced fit have them).
            let phases: std::collections::BTreeMap<String, (f64, f64)> =
                d.detail.runs.iter().map(|r| (r.id.clone(), r.phases_rad)).collect();
            // The static level the extended model breaks away at, read under its
            // own normal force (breakaway module docs).
            let ext = extended_params(p, &vocab);
            let (ext, level) = breakaway::at_own_level(c, &law, &ext, &phases, &opts.stick_episodes);
            let phased = |m: &rig_types::RigParams, id: &str| {
                channels::with_run_phases(m, phases.get(id).copied().unwrap_or_default())
            };
            let measured = measured.as_ref().expect("measured with the baseline's pairs");
            // Where no finding moves the model (the extended model is the
            // baseline to the bit on a run), its free run is the baseline's.
            let ext_pairs =
                channels::free_run_pairs_reusing(c, &s, measured, |id| Some(phased(&ext, id)), p, base_pairs);
            let sdata = sdata.get_or_init(|| {
                structure::StructureData::of(recorded.as_ref().expect("with the balance"), o, data.clone())
            });
            let rec = recorded.as_ref().expect("with the balance");
            let sel = structure::select_structure(c, sdata, &ext, &ext_pairs, &d.detail.runs, &s, opts, rec, measured);
            let moved = sel.damping != structure::REGISTRY[0].id();
            let final_pairs = if moved {
                channels::free_run_pairs_measured(c, &s, measured, |id| Some(phased(&sel.model, id)))
            } else {
                ext_pairs
            };
            let free_run_baseline = channels::free_run_checks_of(c, base_pairs, &s, o);
            let free_run_final = channels::free_run_checks_of(c, &final_pairs, &s, o);
            // Free run is part of adequacy (issue 25): a flagged free-run check of
            // the final model makes the answer `unexplained` (`where`: free_run);
            // the selection is concluded again with it so the unexplained finding,
            // its signature and the adequacy record come from the one place that makes them.
            // The dwell of the break-aways, record against the final model's free
            // run, run by run (extension::dwell, "Against the model's free run").
            let dwell_pairs: Vec<_> =
                final_pairs.iter().filter_map(|q| Some((q.dwell.0.clone()?, q.dwell.1.clone()?))).collect();
            let dwell = extension::dwell::breakaway_dwell_model_check(&dwell_pairs, o.breakaway_dwell_ratio);
            // Every stick's break-away under the final model's normal force,
            // within runs (extension::dwell, "Every stick").
            let final_model = if moved { &sel.model } else { &ext };
            let ageing = extension::dwell::breakaway_ageing_check(
                runs,
                &|id: &str| phased(final_model, id),
                &opts.stick_episodes,
                o.breakaway_dwell_ratio,
            );
            let mut flagged = flagged1.clone();
            flagged.extend(
                free_run_final
                    .iter()
                    .chain([&dwell, &ageing])
                    .filter(|k| k.flagged)
                    .map(|k| ("free_run".to_string(), k.as_pair().1)),
            );
            // Only a mismatch the motion alone shows (every other check and the
            // teacher-forced adequacy pass: `d` is concluded without the free-run
            // flags): where another check fails, an effect that clears the free
            // run may be compensating that failure (second_look docs).
            if !looked && flagged != flagged1 && !moved && d.adequacy.adequate {
                looked = true;
                let near = found.near_misses(opts);
                if !near.is_empty() {
                    let x =
                        second_look::Inputs { c, runs, law: &law, baseline: p, before: &final_pairs, s: &s, o, opts };
                    let (rows, admitted) = second_look::second_look(&x, &near);
                    second_look_rows = rows;
                    if let Some(k) = admitted {
                        found.admit(near[k].effect, near[k].teacher_forced, opts);
                        continue;
                    }
                }
            }
            if flagged != flagged1 {
                d = conclude(&found, &flagged);
            }
            let at = checks.iter().take_while(|k| k.run_kind == "static_twist").count();
            checks.splice(at..at, steps.take().unwrap_or_default());
            checks.push(dwell);
            checks.push(ageing);
            for row in d.detail.runs.iter_mut() {
                if let Some(q) = base_pairs.iter().find(|q| q.id == row.id) {
                    row.measured = q.measured;
                    row.simulated = q.simulated;
                }
                row.extended = final_pairs.iter().find(|q| q.id == row.id).and_then(|q| q.simulated);
            }
            d.detail.breakaway = level;
            d.detail.free_run_baseline = free_run_baseline;
            d.detail.free_run_extended = free_run_final;
            d.detail.speed_traces = channels::speed_traces(base_pairs, &final_pairs);
            d.detail.motor_speed_tick_rad_s = base_pairs.first().map_or(0.0, |q| q.motor_tick_rad_s);
            // An `unexplained` answer carries the best data-driven extension (issue 25, item 6).
            let model = if moved { &sel.model } else { &ext };
            let inputs =
                extension::Inputs { c, runs, model, before: &final_pairs, phases: &phases, s: &s, measured, opts };
            extension::attach(&mut d, &inputs);
            structure::attach(&mut d, sel);
            d.parameters_at_bounds.extend(extension::vocabulary_bounds(p, &d.findings));
            d.parameters_at_bounds.extend(d.detail.breakaway.as_ref().and_then(|l| breakaway::at_bound(p, l)));
            second_look::attach(&mut d, second_look_rows);
        }
        break;
    }
    d.detail.channel_checks = checks;
    Ok(d)
}

/// The whole blind chain on a campaign, with the DAG's options ([`BlindChain`]):
/// calibrate (`rig_calibrate::calibrate_campaign_with`, as the
/// `campaign-calibration` stage) → estimate the baseline rig model
/// (`rig_estimate::estimate_rig` with [`rig_estimate::EstimateParams::options`]
/// started from the thesis' Table 4.4 when `thesis` is given, as the
/// `estimation` stage) → [`diagnose`] (as the `diagnosis` stage). Reads
/// nothing but the campaign (recordings + campaign.toml) and the published
/// thesis values. The verdict does not depend on the estimate: the
/// candidates are compared on teacher-forced channels whose baseline
/// coefficients are refitted on the same runs (crate docs); the estimated
/// model gives the free-run feature comparison. A failed estimate is
/// reported as data (no free-run features), not an error.
pub fn diagnose_campaign(
    c: &rig_types::Campaign,
    thesis: Option<&rig_calibrate::ThesisData>,
    chain: &BlindChain,
) -> Result<Diagnosis, DiagnoseError> {
    let (cal, baseline) = chain.calibrate_and_estimate(c, thesis)?;
    let baseline = baseline.and_then(Result::ok);
    diagnose(c, &cal, baseline.as_ref(), thesis.map(|t| t.friction.mu_dynamic), &chain.diagnosis)
}
