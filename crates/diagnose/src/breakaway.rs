//! The break-away level of the extended model (issue 25: "break-away friction
//! level", a feature the teacher-forced slip channel cannot see).
//!
//! The baseline's static coefficient is the estimation's: the peak of
//! μ = F/N0 of each stick episode up to its break-away, median over
//! episodes (rig_estimate::friction, Eq. 4-10 with T1 = μ·N·r). That reads
//! the static threshold correctly only when the normal force is the constant
//! N0 of the baseline. A finding that modulates the normal force
//! (`normal_force_modulation`, `angle_periodic_friction`: N(t, φ1) of
//! rig_model::friction::normal_force_n) changes what a break-away is: the
//! rotor lets go when the pad force reaches μs·N(t, φ1), so break-aways fall
//! where N is low and F/N0 at break-away under-reads μs by up to the
//! modulation's amplitude. The extended model therefore re-reads μs from the
//! same episodes, with the same rules (`[shared.stick_episodes]`), as the
//! peak of F/N(t, φ1) with each run's fitted nuisance phases: one estimator,
//! evaluated under the model that is simulated. Without such a finding the
//! level is the baseline's, unchanged (nothing is refitted).
//!
//! The level enters the free run only (the teacher-forced channels are slip
//! samples and never see μs), so its effect is judged there: the report gives
//! both levels, and the free-run table shows what the re-read changes.

use crate::channels::with_run_phases;
use crate::prepare::SensorLaw;
use rig_estimate::FrictionOptions;
use rig_estimate::friction::{analyse_trace_normal, static_level};
use rig_types::sensor::ticks_to_rad;
use rig_types::{Campaign, Effect, FrictionLaw, RigParams, RunKind};
use std::collections::BTreeMap;

/// The static coefficient before (baseline) and under the extended model.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BreakAwayLevel {
    /// The baseline's μs (estimation: F/N0 at break-away).
    pub baseline_mu_static: f64,
    /// μs under the extended model's normal force, F/N(t, φ1) at break-away.
    pub mu_static: f64,
    pub mu_static_stderr: Option<f64>,
    /// Stick episodes that ended in a break-away.
    pub episodes: usize,
}

impl BreakAwayLevel {
    /// One sentence for the report.
    pub fn describe(&self) -> String {
        let se = self.mu_static_stderr.map_or(String::new(), |s| format!(" ± {s:.3}"));
        format!(
            "break-away level under the extended model's normal force: μs = {:.3}{se} (peak of F/N(t, φ1) over {} stick episodes), against the baseline's {:.3} read as F/N0",
            self.mu_static, self.episodes, self.baseline_mu_static
        )
    }
}

/// True when an effect of `p` makes the normal force vary along a run.
fn modulates_normal_force(p: &RigParams) -> bool {
    p.effects.iter().any(|e| matches!(e, Effect::NormalForceModulation { .. } | Effect::AnglePeriodicFriction { .. }))
}

/// μs of `model` (module docs); `None` when the model's normal force is the
/// constant N0 (the baseline's level stands), its friction law carries its
/// own fitted static level (Stribeck), or no episode breaks away.
pub fn breakaway_level(
    c: &Campaign,
    law: &SensorLaw,
    model: &RigParams,
    phases_rad: &BTreeMap<String, (f64, f64)>,
    o: &FrictionOptions,
) -> Option<BreakAwayLevel> {
    if !modulates_normal_force(model) {
        return None;
    }
    let baseline_mu_static = match model.friction {
        FrictionLaw::Coulomb { mu_static, .. } | FrictionLaw::Viscous { mu_static, .. } => mu_static,
        _ => return None,
    };
    let mut peaks = Vec::new();
    for run in c.runs_of("operating_point") {
        let RunKind::OperatingPoint { normal_force_n, .. } = run.kind else { continue };
        if normal_force_n < o.min_normal_force_n {
            continue;
        }
        let d = &run.data;
        let (Some(ticks), Some(mv)) = (&d.rotor_ticks, &d.brake_force_mv) else { continue };
        let phi1 = ticks_to_rad(ticks, c.rig.encoder_ticks_per_rev);
        let force = law.force_n(mv);
        let p = with_run_phases(model, phases_rad.get(&run.id).copied().unwrap_or_default());
        let n_of =
            |i: usize| rig_model::friction::normal_force_n(normal_force_n, &p.effects, None, d.time_s[i], phi1[i]);
        peaks.extend(analyse_trace_normal(&d.time_s, &phi1, &force, &n_of, o).breakaway_peaks);
    }
    let (mu_static, mu_static_stderr) = static_level(&peaks)?;
    Some(BreakAwayLevel { baseline_mu_static, mu_static, mu_static_stderr, episodes: peaks.len() })
}

/// `model` with its static coefficient set to `level` (never below μk: the
/// law's break-away needs μs ≥ μk, rig_model's validation; [`at_bound`]
/// reports a level held there).
pub fn with_static_level(model: &RigParams, level: &BreakAwayLevel) -> RigParams {
    let mut p = model.clone();
    match &mut p.friction {
        FrictionLaw::Coulomb { mu_static, mu_kinetic } | FrictionLaw::Viscous { mu_static, mu_kinetic, .. } => {
            *mu_static = level.mu_static.max(*mu_kinetic);
        }
        _ => {}
    }
    p
}

/// `model` at the static level it breaks away at under its own normal force
/// ([`breakaway_level`], then [`with_static_level`]), and that level (`None`:
/// the model as given).
pub fn at_own_level(
    c: &Campaign,
    law: &SensorLaw,
    model: &RigParams,
    phases_rad: &BTreeMap<String, (f64, f64)>,
    o: &FrictionOptions,
) -> (RigParams, Option<BreakAwayLevel>) {
    let level = breakaway_level(c, law, model, phases_rad, o);
    (level.as_ref().map_or_else(|| model.clone(), |l| with_static_level(model, l)), level)
}

/// The level as a parameter at its bound when it reads below the model's μk
/// (issue 25, item 4: reported, never silently fixed).
pub fn at_bound(model: &RigParams, level: &BreakAwayLevel) -> Option<crate::ParamAtBound> {
    let mu_k = match model.friction {
        FrictionLaw::Coulomb { mu_kinetic, .. } | FrictionLaw::Viscous { mu_kinetic, .. } => mu_kinetic,
        _ => return None,
    };
    (level.mu_static < mu_k).then(|| crate::ParamAtBound {
        parameter: "breakaway.mu_static".into(),
        bound: crate::result::round_sig(mu_k, 4),
        unconstrained: crate::result::round_sig(level.mu_static, 4),
        meaning: "the break-away level read under the extended model's normal force is below its slip level: the \
                  model's stick cannot hold it, so μs is held at μk (the modulation found may not act on the static \
                  threshold as the model has it)"
            .into(),
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A trace built from the law itself: the pad force holds the rotor
    /// (F = spring load) until it reaches μs·N(t), then slips at μk·N(t).
    /// With N modulated, F/N0 at break-away under-reads μs; F/N(t) reads it.
    #[test]
    fn the_level_under_a_modulated_normal_force_is_the_law_s() {
        let (mu_s, mu_k, n0, a, f_hz) = (1.6, 1.1, 10.0, 0.15, 1.9);
        let dt = 0.002;
        let n_of = |t: f64| n0 * (1.0 + a * (2.0 * std::f64::consts::PI * f_hz * t).sin());
        let (mut t, mut phi, mut load, mut slipping) = (0.0, 0.0, 0.0, false);
        let (mut time, mut angle, mut force) = (vec![], vec![], vec![]);
        let rate_n_s = 8.0; // spring load rises while stuck
        while t < 40.0 {
            let n = n_of(t);
            if slipping {
                phi += 3.0 * dt; // slips at 3 rad/s while the spring unloads
                load -= 40.0 * dt;
                if load <= mu_k * n * 0.7 {
                    slipping = false;
                }
                force.push(mu_k * n);
            } else {
                load += rate_n_s * dt;
                if load >= mu_s * n {
                    slipping = true;
                }
                force.push(load.min(mu_s * n));
            }
            time.push(t);
            angle.push(phi);
            t += dt;
        }
        let o = FrictionOptions::default();
        let direct = analyse_trace_normal(&time, &angle, &force, &|i| n_of(time[i]), &o).breakaway_peaks;
        let naive = rig_estimate::friction::analyse_trace(&time, &angle, &force, n0, &o).breakaway_peaks;
        assert!(direct.len() >= 5, "{} episodes", direct.len());
        let (level, _) = static_level(&direct).unwrap();
        let (naive_level, _) = static_level(&naive).unwrap();
        assert!((level - mu_s).abs() < 0.01, "level {level}");
        assert!(naive_level < mu_s - 0.05, "F/N0 reads {naive_level}: the bias this module removes");
    }
}
