//! What the calibrated model gets wrong outside the teacher-forced slip
//! channels: every run kind and channel of the campaign (issue 9, item 4).
//!
//! Each check reduces one channel to a run-level statistic, divides it by a
//! noise floor computed from the data's own sensor resolution, and flags the
//! channel when the ratio exceeds a threshold calibrated on effect-free
//! campaigns of the virtual rig ([`ChannelOptions`], `[stage.params.channels]` of pipeline.toml; test
//! `crates/virtual-rig/tests/channel_calibration.rs`). Run-level (never
//! sample-level) statistics, because model-mismatch residuals are correlated
//! over thousands of samples and a per-sample floor would be far too small.
//!
//! | channel | run kind | statistic | floor |
//! |---|---|---|---|
//! | `static_twist.linearity` | static_twist | RMS of quadratic − linear fit of angle vs torque, rad | σ_θ/√n |
//! | `static_twist.dead_zone` | static_twist | \|intercept\| of angle vs torque, rad | √(se² + (tick/2)²) |
//! | `static_twist.hysteresis` | static_twist | loading − unloading mean residual, rad | σ_θ √(1/n_l + 1/n_u) |
//! | `voltage_step.frequency` | voltage_step | spread of ω_d over the steps, rad/s | RMS standard error |
//! | `voltage_step.decay` | voltage_step | spread of δ over the steps | RMS standard error |
//! | `voltage_step.residual` | voltage_step | RMS of window-speed residual, rad/s | quantisation |
//! | `operating_point.regime` | operating_point | runs whose stick-slip/pure-slip differs at the end of the run and over the features' window | 1 run |
//! | `operating_point.rotor_max`, `.rotor_min` | operating_point | RMS over runs, rad/s | speed resolution |
//! | `operating_point.fundamental` | operating_point | RMS relative error | frequency resolution |
//! | `operating_point.torque_balance` | operating_point | RMS of the rotor torque balance, N·m | sensor noise |
//! | `operating_point.drive_balance` | operating_point | RMS the motor-constant drift explains in ⟨V⟩, V | √(2σ̂²/n) of the drift fit (ratio² = F) |
//! | `operating_point.breakaway_dwell` | operating_point | slope of the break-away level on the log dwell within runs, record minus the final model's free run (one rule for both sides; the record alone without a model; [`crate::extension::dwell`]) | its standard error ⊕ 0.006 |
//! | `operating_point.breakaway_ageing` | operating_point | slope of every break-away's ln F/N(t, φ1) on the log dwell within runs, N the final model's normal force, pooled over runs (with a model only; [`crate::extension::dwell`], "Every stick") | its cluster-robust standard error ⊕ 0.003 |
//! | `operating_point.slip_drift` | operating_point | RMS over runs of each run's relative slip-force drift after the settle ([`crate::extension::drift`]) | the scatter of its 1 s block means ⊕ 0.5 % |
//! | `force_calibration.linearity` | force_calibration | residual SD of the line mV vs load through the runs' means, mV | half-run difference of the means / 2 |
//!
//! σ_θ, the uncertainty of a held angle's mean, is the encoder quantisation
//! tick/√12 (the held angle is arbitrary within a tick) plus the measured
//! in-run wander over √samples.

mod balance;
mod drive_balance;
mod force_linearity;
mod free_run;
mod step;
mod twist;

pub use balance::{
    BalanceData, BalanceFit, Channels, MIN_EVENTS, Recorded, RecordedRun, TICK_LOSS_CHECK, advanced, balance_data,
    tick_loss_check_of, torque_balance_check, torque_balance_check_of,
};
pub use drive_balance::drive_balance_check;
pub use force_linearity::{force_linearity_check, force_parabola};
pub use free_run::{
    FreeRunSettings, FreeRunThresholds, MeasuredRuns, Pair as FreeRunPair, free_run_channel_misfits_measured,
    free_run_check_names, free_run_checks, free_run_checks_of, free_run_misfit, free_run_misfit_channels,
    free_run_misfit_measured, free_run_pairs, free_run_pairs_by, free_run_pairs_measured, free_run_pairs_reusing,
    speed_floor_rad_s, speed_traces, stuck_stretches,
};
pub use step::voltage_step_checks;
pub use twist::static_twist_checks;

use crate::effects::{EffectId, REGISTRY, VocabularyEffect};
use rig_types::RigParams;
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;

/// One channel of one run kind, tested against its noise floor.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct ChannelCheck {
    /// `run_kind.check`, e.g. `static_twist.hysteresis`.
    pub channel: String,
    pub run_kind: String,
    /// The runs the statistic is computed from.
    pub runs: Vec<String>,
    /// The run-level statistic (unit in the table of the module docs).
    pub statistic: f64,
    /// What sensor resolution and noise alone give for it (same unit).
    pub noise_floor: f64,
    /// statistic / noise_floor.
    pub ratio: f64,
    /// The ratio above which the channel is flagged (calibrated).
    pub threshold: f64,
    pub flagged: bool,
    /// One sentence a person can check.
    pub detail: String,
}

impl ChannelCheck {
    fn new(channel: &str, runs: Vec<String>, statistic: f64, noise_floor: f64, threshold: f64, detail: String) -> Self {
        let ratio = if noise_floor > 0.0 && statistic.is_finite() { statistic / noise_floor } else { 0.0 };
        ChannelCheck {
            channel: channel.to_string(),
            run_kind: channel.split('.').next().unwrap_or(channel).to_string(),
            runs,
            statistic,
            noise_floor,
            ratio,
            threshold,
            flagged: ratio > threshold,
            detail,
        }
    }

    /// A check the campaign's protocol cannot make (never flagged).
    pub(crate) fn not_testable(channel: &str, runs: Vec<String>, why: String) -> Self {
        let mut c = ChannelCheck::new(channel, runs, 0.0, 0.0, f64::INFINITY, why);
        c.flagged = false;
        c
    }

    /// (run kind, sentence) as [`crate::diagnose`] takes `channel_checks`.
    pub fn as_pair(&self) -> (String, String) {
        (
            self.run_kind.clone(),
            format!(
                "{}: {:.1}× its noise floor (threshold {:.1}); {}",
                self.channel, self.ratio, self.threshold, self.detail
            ),
        )
    }
}

/// Thresholds (ratio to the noise floor) of every check and the free-run
/// settings: `[stage.params.channels]` of the diagnosis stage in pipeline.toml,
/// their one home.
///
/// Calibration: thresholds set on effect-free virtual-rig campaigns so that all
/// checks together flag at most 5 % of them
/// (crates/virtual-rig/tests/channel_calibration.rs): 30 null draws (small
/// protocol, seeds 9000–9029, blind baseline) gave maximum ratios rotor_max
/// 1.88, rotor_min 1.64, torque_balance 1.05, dead_zone 1.06, linearity 0.43,
/// step frequency 0.91, decay 0.18, step residual 1.12, drive balance 1.97,
/// force-sensor linearity 2.69 (threshold 6: its ratio² is F(3, 5) with 5 loads);
/// 0/30 campaigns flagged
/// (one-sided 95 % upper bound 9.5 %). Each threshold is about twice the null
/// maximum. No null run of that protocol sticks and slips, so the free-run
/// checks were calibrated again (issue 25) on 24 stick-slipping nulls
/// (crates/virtual-rig/tests/free_run_calibration.rs: seeds 9100–9123, the
/// virtual rig's draw with the shaft damped at the shipped rig's ξ ≈ 0.02–0.04,
/// a protocol of 12 points mostly in the stick-slip region; 161 of 288 runs
/// stick and slip, every campaign 3–9 of 12), diagnosed end to end with the
/// final model (findings + selected structure): maximum ratios rotor_max
/// 1.81, rotor_min 1.37, regime 0 runs, fundamental 0.01; 0/24 campaigns
/// flagged (95 % Clopper–Pearson 0–14.2 %), 24/24 verdict `none`, 24/24
/// structure `twist_rate`. The thresholds stay (rotor_max and rotor_min 4,
/// ≈ 2× the null maximum; regime 2.5 runs; fundamental 4). Every other
/// channel in free run (issue 25, item 3; [`FreeRunThresholds`]) and the
/// per-run floors with the spread over cycles: calibrated on the same 24
/// nulls (numbers in `channels::free_run`'s docs and pipeline.toml), 0/24
/// flagged (95 % Clopper–Pearson 0–14.2 %, in-sample). Right models
/// (`free_run_right_models`: each vocabulary effect drawn four times on those
/// stick-slipping rigs, seeds 9300–9343, the effect found in 20/20): 0/20
/// have a free-run check of the final model above these thresholds (95 %
/// Clopper–Pearson 0–16.8 %) since the break-away level is read under the
/// extended model's normal force ([`crate::breakaway`]) and the slip-force
/// floor carries N0·se(μk); before those two: 8/20 (19–64 %; normal-force modulation 4/4, angle-periodic 3/4,
/// velocity weakening 1/4, viscous 0/4, drive limit 0/4), 4/20 by the
/// regime, rotor-extreme and fundamental checks alone (6–44 %); the new
/// ones that add flags: slip friction (up to 27× for the modulations) and
/// stick fraction. The voltage mean and swing are reported but not in the
/// adequacy test (thresholds unset): right drive-limit models give 81–116×
/// on the mean (the fitted limit a few % off the record's saturated
/// voltage), because their floors — sensor noise and the spread over cycles
/// — lack the fitted drive's uncertainty; the same holds, less, for the
/// friction levels of a modulation simulated from rest, which does not lock
/// onto the stick-slip cycle as the record did. Open (issue 25).
///
/// Since the regime is the attractor's (`free_run::attractor_stick_slip`: a
/// change counts when the end of the run and the features' window both
/// differ) and the break-away level is the estimation's stick episodes
/// (`free_run::breakaway_peaks`), rerun on the same campaigns: nulls 0/24
/// flagged (95 % Clopper–Pearson 0–14.2 %), break-away ratio 0.21 / 0.93 /
/// 1.35 (min / median / max; 0.9–13.6 with the stretches of |Ω1| below the
/// slip speed, most of them encoder chatter of a creeping rotor), regime 0;
/// right models 0/20 (0–16.8 %), break-away at most 1.41, regime at most 2
/// runs (seed 9312, angle-periodic; the end of the run alone would give 3).
/// The break-away threshold is 4 (≈ 2× the larger maximum, at least 4; it
/// was 27.5).
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChannelOptions {
    pub twist_linearity_ratio: f64,
    pub twist_dead_zone_ratio: f64,
    pub twist_hysteresis_ratio: f64,
    pub step_frequency_ratio: f64,
    pub step_decay_ratio: f64,
    pub step_residual_ratio: f64,
    /// Runs whose regime may differ (the floor is one run).
    pub regime_ratio: f64,
    pub rotor_max_ratio: f64,
    pub rotor_min_ratio: f64,
    pub fundamental_ratio: f64,
    pub torque_balance_ratio: f64,
    /// The drive-balance drift test (ratio² is its F statistic).
    pub drive_balance_ratio: f64,
    /// Linearity of the force sensor over its calibration runs (ratio² is F-distributed, (n − 2, n) dof).
    pub force_linearity_ratio: f64,
    /// The break-away level's dependence on the dwell within runs
    /// ([`crate::extension::dwell`]: slope over its floor), both readings:
    /// the first break-away against the steady ones and every stick under
    /// the final model's normal force.
    pub breakaway_dwell_ratio: f64,
    /// Does an encoder lose ticks? The twist's drift with the angle travelled
    /// ([`tick_loss_check_of`]: mean over runs over its standard error ⊕
    /// a minimum).
    pub tick_loss_ratio: f64,
    /// Does the slip force trend within a run? RMS over runs of each run's
    /// relative drift over its floor ([`crate::extension::drift`]).
    pub slip_drift_ratio: f64,
    /// Window of the torque balance, s (long enough that the
    /// quantisation of Ω̇1 does not swamp the balance).
    pub balance_window_s: f64,
    /// Steady-state seconds of each free-run simulation (after ramp + settle).
    pub free_run_steady_s: f64,
    /// Thresholds of the free-run checks of the other channels (motor speed,
    /// voltage, friction level, stick fraction): `[stage.params.channels.free_run]`.
    pub free_run: FreeRunThresholds,
}

/// The extended model for the simulator: the baseline plus the vocabulary
/// findings, each effect applied by its own file
/// ([`crate::effects::VocabularyEffect::apply`]: diagnosis.md's table mapped
/// onto rig_types' forms), in the findings' order.
///
/// Per-run phases θ are free nuisance parameters of the diagnosis and are not
/// reported, so every phase is set to 0 here ([`with_run_phases`] sets one
/// run's). The free-run statistics compared
/// ([`free_run_checks`]: regime, rotor speed extrema and fundamental over a
/// steady window of many modulation periods) do not depend on θ beyond the
/// noise of the window, which is what the calibrated thresholds cover.
pub fn extended_params(baseline: &RigParams, findings: &[(EffectId, BTreeMap<String, f64>)]) -> RigParams {
    let mut p = baseline.clone();
    for (e, params) in findings {
        e.apply(&mut p, baseline, &|k: &str| params.get(k).copied().unwrap_or(0.0));
    }
    p
}

/// `p` with one run's nuisance phases (θ_t, θ_φ) in its time- and
/// angle-modulation effects: N(t) = N0 (1 + a sin(2π f t + θ_t)) and
/// N(φ1) = N0 (1 + a sin(n φ1 + θ_φ)) with t and φ1 the run's own (both
/// start at 0 with the record), each effect of the registry setting its own
/// ([`crate::effects::VocabularyEffect::set_phases`]). The spec leaves θ free
/// per run; a free run with θ = 0 forces a different run than the one
/// recorded, and near a regime boundary that alone changes the regime.
pub fn with_run_phases(p: &RigParams, phases_rad: (f64, f64)) -> RigParams {
    with_run_phases_of(REGISTRY, p, phases_rad)
}

/// [`with_run_phases`] with the effects of `registry`.
pub fn with_run_phases_of(registry: &[&dyn VocabularyEffect], p: &RigParams, phases_rad: (f64, f64)) -> RigParams {
    let mut q = p.clone();
    for e in &mut q.effects {
        for v in registry {
            v.set_phases(e, phases_rad);
        }
    }
    q
}

/// Every check that needs no model to simulate (static twist, voltage steps,
/// torque balance) plus the free-run checks of `model`; campaign order of
/// the table in the module docs.
pub fn all_checks(
    c: &rig_types::Campaign,
    cal: &rig_calibrate::CampaignCalibration,
    baseline: &RigParams,
    model: &RigParams,
    opts: &crate::DiagnoseOptions,
    o: &ChannelOptions,
) -> Vec<ChannelCheck> {
    let mut v = static_twist_checks(c, cal, o);
    v.extend(voltage_step_checks(c, cal, baseline, o, opts.voltage_steps.residual_window_s, &opts.integrator));
    v.extend(free_run_checks(c, model, &FreeRunSettings::of(opts, o), o));
    v.push(torque_balance_check(c, cal, baseline, opts, o));
    v.push(drive_balance_check(c, opts, o));
    let mu_relative_se =
        rig_estimate::estimate_friction(c, cal.force_offset_mv, cal.force_factor_mv_per_n, &opts.stick_episodes)
            .ok()
            .and_then(|f| Some(f.mu_kinetic_stderr? / f.mu_kinetic));
    v.push(force_linearity_check(c, o, mu_relative_se));
    v
}

/// Least squares of `y` on the rows `x` (the workspace's one solver,
/// `rig_estimate::linear::ols`): (coefficients, residual sum of squares).
fn ols(x: &[Vec<f64>], y: &[f64]) -> Option<(Vec<f64>, f64)> {
    rig_estimate::linear::ols(x, y, "channel check").ok().map(|f| (f.beta, f.ssr))
}

/// Root mean square (0 for an empty slice).
fn rms(x: &[f64]) -> f64 {
    if x.is_empty() { 0.0 } else { (x.iter().map(|v| v * v).sum::<f64>() / x.len() as f64).sqrt() }
}

#[cfg(test)]
pub(crate) mod tests {
    use super::*;
    use rig_types::FrictionLaw;

    pub(crate) fn base_params() -> RigParams {
        RigParams {
            kind: rig_types::ModelKind::Rig,
            rotor_inertia_kgm2: 0.03,
            shaft_stiffness_nm_rad: 0.27,
            shaft_damping_nm_s_rad: 0.005,
            rotor_damping_nm_s_rad: 0.0,
            motor: rig_types::MotorParams {
                inertia_kgm2: 4.7e-4,
                inductance_h: 8.4e-4,
                resistance_ohm: 0.53,
                torque_constant_nm_a: 0.126,
                voltage_constant_v_s_rad: 0.0588,
                friction_torque_nm: 0.1,
                speed_regulation_nm_s_rad: 1.8e-4,
                gear_ratio: 8.0,
            },
            drive: rig_types::DriveParams { kp_v_s_rad: 2.0, ki_v_rad: 10.0, limit_v: 24.0 },
            friction: FrictionLaw::Coulomb { mu_static: 0.6, mu_kinetic: 0.4 },
            brake_disc_radius_m: 0.062,
            effects: vec![],
            harmonic: None,
        }
    }

    #[test]
    fn extended_params_maps_every_effect() {
        use crate::effects::{drive_voltage_limit, normal_force_modulation, viscous_brake_friction};
        use rig_types::Effect;
        let base = base_params();
        let id = |s: &str| EffectId::from_id(s).expect("a registry id");
        let m = |kv: &[(&str, f64)]| kv.iter().map(|(k, v)| (k.to_string(), *v)).collect::<BTreeMap<_, _>>();
        let p = extended_params(
            &base,
            &[
                (id(normal_force_modulation::ID), m(&[("amplitude_ratio", 0.1), ("frequency_hz", 1.5)])),
                (id(drive_voltage_limit::ID), m(&[("limit_v", 12.0)])),
                (id(viscous_brake_friction::ID), m(&[("mu_kinetic", 0.38), ("viscous_per_rad_s", 0.01)])),
            ],
        );
        assert_eq!(p.drive.limit_v, 12.0);
        assert_eq!(
            p.effects,
            vec![Effect::NormalForceModulation { amplitude_ratio: 0.1, frequency_hz: 1.5, phase_rad: 0.0 }]
        );
        assert_eq!(p.friction, FrictionLaw::Viscous { mu_static: 0.6, mu_kinetic: 0.38, viscous_per_rad_s: 0.01 });
        assert_eq!(extended_params(&base, &[]), base);
    }

    #[test]
    fn a_check_flags_above_its_threshold_only() {
        let c = ChannelCheck::new("static_twist.linearity", vec![], 3.0, 1.0, 4.0, String::new());
        assert!(!c.flagged && c.run_kind == "static_twist" && c.ratio == 3.0);
        let c = ChannelCheck::new("static_twist.linearity", vec![], 5.0, 1.0, 4.0, String::new());
        assert!(c.flagged);
    }
}
