//! diagnosis.md.

use crate::result::{Diagnosis, Features};
use std::fmt::Write as _;

/// diagnosis.md.
pub fn markdown(d: &Diagnosis) -> String {
    let det = &d.detail;
    let mut s = String::new();
    let _ = writeln!(s, "# Diagnosis of campaign `{}`\n", d.campaign);
    let _ = writeln!(s, "**Verdict: `{}`**\n", d.verdict);
    let a = &d.adequacy;
    let _ = writeln!(
        s,
        "**Adequacy of the final model:** cross-validated misfit {:.2}× the noise floor (threshold {:.1}, calibrated \
         on effect-free virtual-rig campaigns; crate docs), {} consistent order line(s), {} significant check(s) of \
         other run kinds, {} flagged free-run check(s) of the final model → {}.\n",
        a.residual_over_noise,
        a.threshold,
        a.order_lines,
        a.channel_checks,
        a.free_run_checks,
        if a.adequate {
            "adequate: nothing significant is left"
        } else {
            "NOT adequate: a significant mismatch is left"
        }
    );
    let _ = writeln!(s, "## Findings, in the order forward selection added them\n");
    if d.findings.is_empty() {
        let _ = writeln!(s, "None: no vocabulary effect earns its place, and nothing significant is left.\n");
    }
    for (i, f) in d.findings.iter().enumerate() {
        let _ = writeln!(s, "### {}. `{}`\n\n{}\n", i + 1, f.effect, f.evidence);
        if !f.params.is_empty() {
            let _ = writeln!(s, "| parameter | value | standard error |\n|---|---|---|");
            for (k, v) in &f.params {
                let _ = writeln!(s, "| {k} | {v} | {} |", f.params_stderr.get(k).copied().unwrap_or(f64::NAN));
            }
            s.push('\n');
        }
        if !f.where_.is_empty() {
            let _ = writeln!(s, "Where: {}.\n", f.where_.join(", "));
        }
        for t in &f.signature {
            let _ = writeln!(s, "- `{}` (held-out gain {}): {}", t.signal, t.heldout_gain, t.description);
        }
        if !f.signature.is_empty() {
            s.push('\n');
        }
        if let Some(x) = &f.extension {
            extension_markdown(&mut s, x, det);
        }
        let _ = writeln!(
            s,
            "Cross-validated misfit (every run held out once, {} folds): {} (model before) → {} (with it), relative \
             gain {} ± {} (sd across folds).\n",
            det.folds, f.heldout_misfit_baseline, f.heldout_misfit_extended, f.relative_gain, f.relative_gain_fold_sd
        );
    }
    let _ = writeln!(
        s,
        "## How it was decided\n\nEach operating point's friction coefficient in slip (μ = F/N0 from the calibrated \
         force sensor) and drive voltage are predicted teacher-forced from the measured speeds and angles. The \
         baseline is the calibrated rig model: {}. The runs are dealt into {} folds stratified by set-point and \
         normal force; every model is fitted without a fold and scored on it, so every run is held out once. Forward \
         selection adds the effect with the largest cross-validated gain while it lowers the misfit of the model that \
         already has the earlier ones by the minimum gain AND its paired run-level t of ln(M_before/M_after) passes \
         the threshold: a criterion on runs, not on 500 Hz samples, so it can say no. The misfit is \
         M = sqrt((e_μ² + e_V²)/2) with e_μ the RMS error of μ relative to its mean and e_V the RMS voltage error \
         relative to the supply (rig-diagnose crate docs). Baseline misfit {:.4}; noise floor {:.4}; final model's \
         friction channel {:.2}× and drive channel {:.2}× their floors.\n",
        det.baseline_text,
        det.folds,
        det.heldout_misfit_baseline,
        det.heldout_misfit_noise_floor,
        det.channel_over_noise.0,
        det.channel_over_noise.1
    );
    let _ = writeln!(
        s,
        "| step | effect | misfit before | misfit after | gain | gain sd (folds) | paired t | accepted |\n|---|---|---|---|---|---|---|---|"
    );
    for r in &det.steps {
        let _ = writeln!(
            s,
            "| {} | {} | {:.4} | {:.4} | {:.3} | {:.3} | {:.1} | {} |",
            r.step, r.effect, r.misfit_before, r.misfit_after, r.gain, r.gain_fold_sd, r.t, r.accepted
        );
    }
    for r in det.steps.iter().filter(|r| r.inadmissible.is_some()) {
        let _ = writeln!(
            s,
            "\nStep {}: `{}` has the largest significant gain but is not accepted: {}. Selection stops there; \
             the adequacy test judges what is left.",
            r.step,
            r.effect,
            r.inadmissible.as_deref().unwrap_or_default()
        );
    }
    if det.lines.is_empty() {
        let _ = writeln!(s, "\nNo order line locked to a shaft angle is significant in most runs.");
    } else {
        let _ = writeln!(s, "\nOrder lines (speed components locked to a shaft angle):\n");
        for l in &det.lines {
            let _ = writeln!(s, "- {l}");
        }
    }
    if !det.channel_checks.is_empty() {
        let _ = writeln!(
            s,
            "\n## Every run kind (tables/diagnosis-checks.csv)\n\nChecks of the runs the slip channels do not see, each a \
             run-level statistic over its noise floor; a flagged check makes the final model inadequate.\n\n| check | \
             ratio | threshold | flagged | detail |\n|---|---|---|---|---|"
        );
        for k in &det.channel_checks {
            let _ =
                writeln!(s, "| {} | {:.2} | {:.1} | {} | {} |", k.channel, k.ratio, k.threshold, k.flagged, k.detail);
        }
    }
    if !d.structure.damping.is_empty() {
        let _ = writeln!(
            s,
            "\n## Structure: where the damping acts, and the channels' alignment\n\n**`{}`.** {}\n\nEach candidate \
             (a damping placement, a delay between recorded channels, a sensor's resonance) is fitted teacher-forced through the rotor \
             torque balance on the training folds and scored on the held-out runs by that balance's misfit and by \
             the free-run misfit of the extended model, and by the balance at the stick↔slip transitions alone \
             (event-locked rows), and by the force's ring after the break-aways at full rate (rig-diagnose \
             `structure` docs).\n\n| structure | fitted (every run) | balance misfit [N·m] | balance gain | balance t \
             | event misfit [N·m] | event gain | event t | ring misfit [N·m] | ring gain | ring t | free-run misfit | gain \
             | gain sd (folds) | paired t | admissible | chosen |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\
             ---|---|---|---|",
            d.structure.damping, d.structure.notes
        );
        for r in &det.structure_scores {
            let _ = writeln!(
                s,
                "| {} | {} | {:.3e} | {:.3} | {:.2} | {:.3e} | {:.3} | {:.2} | {:.3e} | {:.3} | {:.2} | {:.3} | {:.3} | \
                 {:.3} | {:.2} | {} | {} |",
                r.id,
                r.description,
                r.balance_misfit,
                r.balance_gain,
                r.balance_t,
                r.event_misfit,
                r.event_gain,
                r.event_t,
                r.ring_misfit,
                r.ring_gain,
                r.ring_t,
                r.free_run_misfit,
                r.relative_gain,
                r.relative_gain_fold_sd,
                r.t,
                r.admissible,
                r.accepted
            );
        }
    }
    if !d.brake_open_runs.is_empty() {
        let _ = writeln!(
            s,
            "\n## Operating points with the brake open\n\n{} (normal_force_n = 0): no friction coefficient \
             can be read on them (μ = F/N has no N), so the selection's units and the friction fits leave them \
             out; the drive channel's fits read them (the PI loop needs no brake) and the free-run checks \
             simulate them.",
            d.brake_open_runs.join(", ")
        );
    }
    if let Some(dc) = &d.drive_channel {
        let _ = writeln!(
            s,
            "\nThe drive channel's fits read {} operating points, {} with the brake open. Held out of their \
             fold's drive fit, the relative voltage error e_V of each:\n\n| run | baseline drive | final model | \
             noise floor |\n|---|---|---|---|",
            dc.runs, dc.brake_open
        );
        for r in &dc.brake_open_heldout {
            let _ = writeln!(
                s,
                "| {} | {:.4} | {:.4} | {:.4} |",
                r.run, r.relative_voltage_error_baseline, r.relative_voltage_error_final, r.noise_floor
            );
        }
    }
    if !d.parameters_at_bounds.is_empty() {
        let _ = writeln!(
            s,
            "\n## Parameters at bounds\n\n| parameter | bound | unconstrained | meaning |\n|---|---|---|---|"
        );
        for p in &d.parameters_at_bounds {
            let _ = writeln!(s, "| {} | {} | {} | {} |", p.parameter, p.bound, p.unconstrained, p.meaning);
        }
    }
    if !det.free_run_baseline.is_empty() {
        let _ = writeln!(
            s,
            "\n## Free run: baseline and final model\n\nEvery operating point simulated from rest with the baseline \
             and with the final model (baseline + findings with each run's fitted phases, the break-away level read \
             under its normal force, and the selected structure), compared with the record on phase-insensitive features of every recorded channel (rotor and \
             motor speed extremes, fundamental, voltage mean and swing, slip and break-away friction force, stick \
             fraction), each error in units of the run's floor: sensor resolution ⊕ the feature's spread over the \
             record's stick-slip cycles (rig-diagnose `channels::free_run` docs). The final model's checks are part of \
             the adequacy test (thresholds calibrated on stick-slipping effect-free campaigns, rig-diagnose \
             `ChannelOptions`).\n\n\
             | check | baseline ratio | final ratio | threshold | final detail |\n|---|---|---|---|---|"
        );
        for (b, e) in det.free_run_baseline.iter().zip(&det.free_run_extended) {
            let _ =
                writeln!(s, "| {} | {:.2} | {:.2} | {:.1} | {} |", b.channel, b.ratio, e.ratio, e.threshold, e.detail);
        }
        if let Some(l) = &det.breakaway {
            let _ = writeln!(
                s,
                "\nThe final model's {} (rig-diagnose `breakaway`: a finding that modulates the normal force moves \
                 the break-aways to where N is low, so F/N0 under-reads the static level; the slip channels never see it).",
                l.describe()
            );
        }
    }
    if !det.second_look.is_empty() {
        let _ = writeln!(
            s,
            "\n## Second look in free run\n\nThe final model's free run was flagged, so every effect the last \
             selection step refused with a significant paired t (gain below the minimum) was added with its \
             parameters fitted without each fold and every run simulated free (rig-diagnose `second_look`): an \
             effect is admitted when its free-run gain passes the selection's rule and no free-run check is left \
             flagged with it.\n\n\
             | effect | teacher-forced gain | t | free-run misfit before | after | gain | gain sd (folds) | paired t | still flagged | admitted |\n\
             |---|---|---|---|---|---|---|---|---|---|"
        );
        for r in &det.second_look {
            let _ = writeln!(
                s,
                "| {} | {:.3} | {:.1} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {} | {} |",
                r.effect,
                r.teacher_forced_gain,
                r.teacher_forced_t,
                r.free_run_before,
                r.free_run_after,
                r.free_run_gain,
                r.free_run_gain_fold_sd,
                r.free_run_t,
                if r.still_flagged.is_empty() { "none".to_string() } else { r.still_flagged.join(", ") },
                r.admitted
            );
        }
    }
    let _ = writeln!(
        s,
        "\n## The ladder (tables/diagnosis-rungs.csv)\n\n| rung | cross-validated misfit | cause |\n|---|---|---|"
    );
    for (n, m, c) in &det.rungs {
        let _ = writeln!(s, "| {n} | {m:.4} | {c} |");
    }
    let _ = writeln!(
        s,
        "\n## Per run (tables/diagnosis-runs.csv)\n\nMeasured features of the steady state against the free-run baseline \
         and extended simulations over the same window (empty when no baseline was given), and the misfit per run.\n"
    );
    let _ = writeln!(
        s,
        "| run | fold | rpm | N0 | stick-slip meas/base/ext | Ω1 max meas/base/ext | f0 meas/base/ext [Hz] | misfit base | misfit ext | floor |\n|---|---|---|---|---|---|---|---|---|---|"
    );
    for r in &det.runs {
        let (sim, ext) = (r.simulated, r.extended);
        let both = |g: fn(&Features) -> String| {
            format!("{}/{}", sim.as_ref().map(g).unwrap_or("–".into()), ext.as_ref().map(g).unwrap_or("–".into()))
        };
        let _ = writeln!(
            s,
            "| {} | {} | {:.0} | {:.1} | {}/{} | {:.2}/{} | {:.2}/{} | {:.4} | {:.4} | {:.4} |",
            r.id,
            r.fold,
            r.motor_rpm_setpoint,
            r.normal_force_n,
            r.measured.stick_slip(),
            both(|f| f.stick_slip().to_string()),
            r.measured.rotor_max_rad_s,
            both(|f| format!("{:.2}", f.rotor_max_rad_s)),
            r.measured.fundamental_hz,
            both(|f| format!("{:.2}", f.fundamental_hz)),
            r.misfit_baseline,
            r.misfit_extended,
            r.misfit_noise_floor
        );
    }
    s
}

/// The `extension` of an `unexplained` finding: law, terms, free-run gain
/// and the forward selection that chose it (rig-diagnose `extension` docs).
fn extension_markdown(s: &mut String, x: &crate::Extension, det: &crate::result::Detail) {
    let _ = writeln!(
        s,
        "**Extension (simulated in free run).** {}. Cross-validated free-run misfit of the final model {} → {} with \
         it, relative gain {} ± {} (sd across folds); figure diagnosis-extension-free-run.\n",
        x.formula, x.free_run_misfit_before, x.free_run_misfit_after, x.relative_gain, x.relative_gain_sd
    );
    let _ = writeln!(s, "| signal | coefficient | standard error (jackknife over folds) |\n|---|---|---|");
    for t in &x.terms {
        let _ = writeln!(s, "| {} | {} | {} |", t.signal, t.coefficient, t.stderr);
    }
    let _ = writeln!(
        s,
        "\n| step | signal | free-run misfit before | after | gain | gain sd (folds) | paired t | accepted |\n\
         |---|---|---|---|---|---|---|---|"
    );
    for r in &det.extension_steps {
        let _ = writeln!(
            s,
            "| {} | {} | {:.3} | {:.3} | {:.3} | {:.3} | {:.2} | {} |",
            r.step, r.effect, r.misfit_before, r.misfit_after, r.gain, r.gain_fold_sd, r.t, r.accepted
        );
    }
    if !det.extension_free_run.is_empty() {
        let verdict = if x.free_run_flagged.is_empty() {
            "every check passes".to_string()
        } else {
            format!("still flagged: {}", x.free_run_flagged.join("; "))
        };
        let _ = writeln!(
            s,
            "\nThe extended model's free run (held-out runs, each simulated with the coefficients fitted without \
             its fold) against the record, on the adequacy test's checks: {verdict}.\n\n\
             | check | ratio | threshold | flagged |\n|---|---|---|---|"
        );
        for k in &det.extension_free_run {
            let _ = writeln!(s, "| {} | {:.2} | {:.1} | {} |", k.channel, k.ratio, k.threshold, k.flagged);
        }
    }
    s.push('\n');
}
