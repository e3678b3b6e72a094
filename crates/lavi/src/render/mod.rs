//! How the study becomes artifacts: tables, figures (derived, low-passed and
//! thinned series only), `lavi.md` (three rungs: baseline, cause, extension)
//! and `lavi-diagnosis.json` in the schema of ../shared/spec/diagnosis.md.

use crate::data::{Prepared, RPM_TO_RAD_S};
use crate::describe::describe;
use crate::eom::Damping;
use crate::features::{FEATURES, Features, N_FEATURES};
use crate::fit::ChannelBalance;
use crate::score::feature_errors;
use crate::select::{mean, overall, std};
use crate::study::Study;
use crate::{Candidate, LaviError};
use rig_ingest::lavi::LaviRecording;
use rig_spectra::lowpass_fft;
use rig_types::{SeriesStyle, Table, figure, fmt_fixed, series};
use serde_json::{Value, json};
use std::collections::BTreeMap;
use std::fmt::Write as _;

mod json;
mod markdown;
mod paragraphs;
mod plots;

use json::*;
use markdown::*;
use paragraphs::*;
use plots::*;

/// Everything the stage writes, in a fixed order (`lavi.md`, `lavi-diagnosis.json`).
pub type StudyOutput = rig_types::StudyOutput<Value>;

/// Issue 10's target for each feature, in words.
const TARGETS: [&str; N_FEATURES] = [
    "within 10 %",
    "within 10 rpm",
    "within 25 % (tolerance at least 0.01)",
    "within 3 %",
    "within 30 %",
    "within 10 %",
    "within 10 %",
];
/// The effect ids of this rig, as the crate docs list them.
const EFFECT_IDS: [(&str, &str); 15] = [
    ("none", "the baseline explains the held-out windows within the adequacy threshold."),
    (
        "friction_law",
        "another law of the family T_k + (T_s − T_k) exp(−(|Ω|/v_s)^δ) + c_v |Ω|: Coulomb (a jump, `family` 0), exponential (1) or Gaussian (2) Stribeck, with a viscous term; refitted by simulation on the calibration window (`static_nm`, `kinetic_nm`, `stribeck_speed_rad_s`, `viscous_nm_s_rad`).",
    ),
    (
        "wob_normal_force",
        "the measured weight on bit as the contact's normal force, torque = WOB(t)·μ(Ω) (`reference_wob_n`, `mu_static`, `mu_kinetic`).",
    ),
    (
        "sensor_inertia",
        "an inertia between the torque sensor and the contact (the sensor above part of the bit): the sensor reads T_f + J_s Ω'; J_s (J/10 to 10 J) and the law fitted jointly by simulation, J, k, c by least squares on T − J_s Ω' (`sensor_inertia_kgm2` and the law's keys).",
    ),
    ("friction_memory", "the slip friction follows its steady law with a first-order lag (`lag_s`)."),
    (
        "second_dof",
        "a mid inertia on the shaft, a second torsional degree of freedom, then the law refitted by simulation (`mid_inertia_kgm2`, `stiffness_split` and the law's keys).",
    ),
    (
        "compliant_drive",
        "the top speed is not imposed: a PI speed loop on a motor inertia follows the measured top speed's moving mean (`drive_inertia_kgm2`, `kp_nm_s_rad`, `ki_nm_rad`).",
    ),
    (
        "absolute_damping",
        "where the damping acts: c on the twist rate and c_a on the absolute bit speed both free in the least squares of the equation of motion, each pinned at 0 and reported when negative (`damping_nm_s_rad`, `absolute_damping_nm_s_rad`).",
    ),
    (
        "channel_delay",
        "the torque channel late (or early) on the speed channels by τ, chosen by least squares of the equation of motion within ±50 ms; J, k, c refitted with the torque read τ later, the law then refitted by simulation like `friction_law`, and the simulated torque channel read τ late like the measured one (`torque_delay_s` and the law's keys).",
    ),
    (
        "motor_drive",
        "the top answers the bit: a motor under a speed loop, J_m Ω'_top = K_p (Ω_ref − Ω_top) + K_i ∫(Ω_ref − Ω_top) dt + T_0 − T_s (the chapter's Eq. 4-6/4-7 motor row with its PI loop), J_m, K_p, K_i, T_0 identified by linear least squares on the calibration window, Ω_ref the measured top speed's moving mean; the law then decided on the calibration window: the current one or the least-squares law of the torque as the current structure reads it (`drive_inertia_kgm2`, `kp_nm_s_rad`, `ki_nm_rad`, `load_nm`, `law_from_torque` and the law's keys).",
    ),
    (
        "top_delay",
        "the top-speed channel late (or early) on the bit speed by τ_top, jointly with the torque channel's delay: τ_top within ±50 ms where the free run of the least-squares J, k, c and law of each τ_top (the torque delay by least squares for it) fits the calibration window best, then the law refitted by simulation on that structure like `friction_law`, the better of the two on the calibration window kept (`top_delay_s`, `torque_delay_s`, `law_from_torque` and the law's keys).",
    ),
    (
        "wob_level",
        "the contact's normal force is the weight on bit's slow level: the law kept, the friction scaled by W̄(t)/W_ref, W̄ the measured WOB's centred moving mean over a span chosen on the calibration window among 0.5, 1, 2 and 4 s and W_ref its mean over the calibration window (at least a stick-slip cycle: the fast part, in the record's phase rather than the free run's, left out) (`wob_level_window_s`, `reference_wob_n`).",
    ),
    (
        "static_friction",
        "the stuck contact holds more than the kinetic law's zero-speed torque: a static level T(0) + ΔT_s, ΔT_s ≥ 0 on a grid of 1 % of T(0) up to 30 % chosen by the calibration misfit, the law, J, k and c kept; the bit leaves stick with the torque dropping to T(0) (`static_excess_nm`, `breakaway_nm`).",
    ),
    (
        "wob_angle",
        "the contact's normal force follows the bit's angle, not the time: N(θ)/N̄ = 1 + Σ_{h=1..3} (a_h cos hθ + b_h sin hθ) (a face out of flat or square pushing the counter-face back per revolution, as a wobbling brake disc does), a_h, b_h by linear least squares of the relative WOB on the measured bit angle's harmonics over the calibration window, refused when they explain less than half its variance there; the law, J, k, c kept; in the free run θ is the simulated bit's angle (`wob_angle_amplitude_1..3`, `wob_angle_r2`).",
    ),
    (
        "unexplained",
        "a significant mismatch is left after the selected effects (held-out misfit, RMS over the windows, above the adequacy threshold).",
    ),
];
const DECIMALS: [usize; N_FEATURES] = [2, 2, 4, 3, 2, 3, 3];

fn met(meas: &Features, sim: &Features) -> [bool; N_FEATURES] {
    feature_errors(meas, sim).map(|e| e.abs() <= 1.0)
}

/// Renders the study (see the module docs).
pub fn render(s: &Study, d: &Prepared, rec: &LaviRecording) -> Result<StudyOutput, LaviError> {
    let mut out = StudyOutput::default();
    let description = describe(rec, d, &s.params, &s.baseline, &s.derivation, &mut out)?;
    let held: Vec<usize> = (1..s.windows.len()).collect();
    let sel = &s.selection;

    // Features, one row per window and feature.
    let mut ft = Table::new(["window", "split", "feature", "measured", "baseline", "extended"]);
    for (wi, w) in s.windows.iter().enumerate() {
        for (fi, name) in FEATURES.iter().enumerate() {
            let f = |x: &Features| fmt_fixed(x.get(fi), DECIMALS[fi]);
            ft.push([
                w.label.clone(),
                w.split.as_str().to_string(),
                name.to_string(),
                f(&s.measured[wi]),
                f(&s.baseline_features[wi]),
                f(&s.final_features[wi]),
            ]);
        }
    }
    out.tables.push(("tables/lavi-features.csv".into(), ft));

    // Targets met on the held-out windows.
    let count = |sim: &[Features]| -> [usize; N_FEATURES] {
        let mut c = [0; N_FEATURES];
        for &wi in &held {
            for (fi, ok) in met(&s.measured[wi], &sim[wi]).iter().enumerate() {
                c[fi] += *ok as usize;
            }
        }
        c
    };
    let (met_base, met_ext) = (count(&s.baseline_features), count(&s.final_features));
    let worst = |fi: usize, sim: &[Features]| {
        held.iter().map(|&wi| feature_errors(&s.measured[wi], &sim[wi])[fi].abs()).fold(0.0, f64::max)
    };
    let mut tt = Table::new([
        "feature",
        "target",
        "heldout_windows",
        "met_baseline",
        "met_extended",
        "worst_error_over_tolerance_extended",
    ]);
    for (fi, name) in FEATURES.iter().enumerate() {
        tt.push([
            name.to_string(),
            TARGETS[fi].to_string(),
            held.len().to_string(),
            met_base[fi].to_string(),
            met_ext[fi].to_string(),
            fmt_fixed(worst(fi, &s.final_features), 2),
        ]);
    }
    out.tables.push(("tables/lavi-targets.csv".into(), tt));

    // Candidates side by side: every trial of every step.
    let mut ct = Table::new([
        "step",
        "effect",
        "calibration_misfit",
        "heldout_misfit_rms",
        "heldout_misfit_min",
        "heldout_misfit_max",
        "relative_gain",
        "gain_spread",
        "paired_t",
        "wins",
        "earns_place",
        "chosen",
        "params",
    ]);
    for (i, t) in sel.trials.iter().enumerate() {
        let lo = t.heldout.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = t.heldout.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let params: Vec<String> = t.fitted.params.iter().map(|(k, v)| format!("{k}={}", sig(*v))).collect();
        ct.push([
            t.step.to_string(),
            t.candidate.id().to_string(),
            fmt_fixed(t.fitted.calibration_misfit, 3),
            fmt_fixed(t.heldout_misfit, 3),
            fmt_fixed(lo, 3),
            fmt_fixed(hi, 3),
            fmt_fixed(t.relative_gain, 3),
            fmt_fixed(t.gain_spread, 3),
            fmt_fixed(t.paired_t, 2),
            format!("{}/{}", t.wins, t.heldout.len()),
            t.earns_place.to_string(),
            sel.chosen.contains(&i).to_string(),
            t.refused.as_ref().map_or_else(|| params.join(" "), |r| format!("refused: {r}")),
        ]);
    }
    out.tables.push(("tables/lavi-candidates.csv".into(), ct));

    // Held-out misfit per window: baseline, every step-1 candidate, final.
    let step1: Vec<_> = sel.trials.iter().filter(|t| t.step == 1).collect();
    let mut cols = vec!["window".to_string(), "baseline".to_string()];
    cols.extend(step1.iter().map(|t| t.candidate.id().to_string()));
    cols.push("extended".into());
    let mut mt = Table::new(cols);
    for (k, &wi) in held.iter().enumerate() {
        let mut row = vec![s.windows[wi].label.clone(), fmt_fixed(sel.baseline_heldout[k], 3)];
        row.extend(step1.iter().map(|t| fmt_fixed(t.heldout[k], 3)));
        row.push(fmt_fixed(sel.final_heldout[k], 3));
        mt.push(row);
    }
    out.tables.push(("tables/lavi-heldout-misfits.csv".into(), mt));
    let mut cf = Table::new([
        "model",
        "window",
        "split",
        "feature",
        "measured",
        "simulated",
        "error_over_tolerance",
        "within_target",
    ]);
    let mut models: Vec<(String, &Vec<Features>)> = vec![("baseline".into(), &s.baseline_features)];
    models.extend(s.candidate_features.iter().map(|(c, f)| (c.id().to_string(), f)));
    models.push(("extended".into(), &s.final_features));
    for (name, f) in &models {
        for (wi, w) in s.windows.iter().enumerate() {
            let e = feature_errors(&s.measured[wi], &f[wi]);
            for (fi, feat) in FEATURES.iter().enumerate() {
                cf.push([
                    name.clone(),
                    w.label.clone(),
                    w.split.as_str().to_string(),
                    feat.to_string(),
                    fmt_fixed(s.measured[wi].get(fi), DECIMALS[fi]),
                    fmt_fixed(f[wi].get(fi), DECIMALS[fi]),
                    fmt_fixed(e[fi], 2),
                    (e[fi].abs() <= 1.0).to_string(),
                ]);
            }
        }
    }
    out.tables.push(("tables/lavi-candidate-features.csv".into(), cf));
    let mut st = Table::new([
        "structure",
        "damping_nm_s_rad",
        "damping_stderr",
        "absolute_damping_nm_s_rad",
        "absolute_damping_stderr",
        "inertia_kgm2",
        "stiffness_nm_rad",
        "r_squared",
        "pinned_at_0",
        "free_run_heldout_misfit",
    ]);
    for ((name, d), free_run) in s.structures.iter().zip(&s.structure_heldout) {
        let f = &d.free;
        st.push([
            name.clone(),
            sig(f.damping_nm_s_rad),
            sig(f.damping_stderr),
            sig(f.absolute_damping_nm_s_rad),
            sig(f.absolute_damping_stderr),
            sig(f.inertia_kgm2),
            sig(f.stiffness_nm_rad),
            fmt_fixed(f.r_squared, 4),
            d.at_bounds.iter().map(|b| b.parameter).collect::<Vec<_>>().join(" "),
            fmt_fixed(*free_run, 3),
        ]);
    }
    out.tables.push(("tables/lavi-structures.csv".into(), st));
    if let Some(t) = crate::drive::table(s) {
        out.tables.push(("tables/lavi-drive.csv".into(), t));
    }
    let labels: Vec<String> = s.windows.iter().map(|w| w.label.clone()).collect();
    out.tables.push(("tables/lavi-repairs.csv".into(), crate::describe::repairs_table(d, &labels)));

    figures(s, d, &mut out)?;
    out.diagnosis = diagnosis_json(s);
    out.markdown = markdown(s, &met_base, &met_ext, &description);
    Ok(out)
}

fn sig(x: f64) -> String {
    format!("{x:.4e}")
}

fn met_list(m: &[usize; N_FEATURES], n: usize) -> String {
    FEATURES.iter().zip(m).map(|(f, k)| format!("{f} {k}/{n}")).collect::<Vec<_>>().join(", ")
}

fn feature_summary<'a>(s: &'a Study, sim: impl Fn(usize) -> &'a Features) -> String {
    let mut t = String::from(
        "| feature | measured (held-out mean) | simulated (held-out mean) | calibration window measured / simulated |\n|---|---|---|---|\n",
    );
    let held: Vec<usize> = (1..s.windows.len()).collect();
    for (fi, name) in FEATURES.iter().enumerate() {
        let m: Vec<f64> = held.iter().map(|&i| s.measured[i].get(fi)).collect();
        let x: Vec<f64> = held.iter().map(|&i| sim(i).get(fi)).collect();
        let d = DECIMALS[fi];
        let _ = writeln!(
            t,
            "| {name} | {} ± {} | {} ± {} | {} / {} |",
            fmt_fixed(mean(&m), d),
            fmt_fixed(std(&m), d),
            fmt_fixed(mean(&x), d),
            fmt_fixed(std(&x), d),
            fmt_fixed(s.measured[0].get(fi), d),
            fmt_fixed(sim(0).get(fi), d)
        );
    }
    t
}

/// "no, worse on the calibration window …" for a trial the rule admits on the
/// held-out windows but the calibration window refuses (None otherwise).
fn inadmissible(sel: &crate::select::Selection, t: &crate::select::Trial) -> Option<String> {
    let c = rig_types::select::Comparison {
        before: f64::NAN,
        after: t.heldout_misfit,
        gain: t.relative_gain,
        gain_fold_sd: t.gain_spread,
        t: t.paired_t,
    };
    let before = if t.step == 1 {
        sel.baseline_calibration
    } else {
        sel.trials[*sel.chosen.get(t.step - 2)?].fitted.calibration_misfit
    };
    (sel.rule.admits(&c) && t.fitted.calibration_misfit > before + 1e-12).then(|| {
        format!(
            "no: admitted by the rule on the held-out windows, worse on the calibration window it was fitted on ({:.3} > {:.3})",
            t.fitted.calibration_misfit, before
        )
    })
}
