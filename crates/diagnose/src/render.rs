//! The diagnosis for people: diagnosis.md, the tables and the evidence
//! figures (as rig_types data; the pipeline stage writes them).

use crate::ChannelCheck;
use crate::result::{Diagnosis, Features, round_sig};
use rig_types::{AxisScale, FigureSpec, MarkerShape, Panel, Series, SeriesStyle, Sheet, Table, band, fmt_fixed};
use std::fmt::Write as _;

fn f4(x: f64) -> String {
    if x.is_finite() { fmt_fixed(x, 4) } else { "nan".into() }
}

/// tables/diagnosis-runs.csv: per operating point, measured vs simulated
/// features and the misfits (crate docs define the misfit).
pub fn runs_table(d: &Diagnosis) -> Table {
    let mut t = Table::new([
        "run",
        "fold",
        "motor_rpm_setpoint",
        "normal_force_n",
        "slip_samples",
        "meas_stick_slip",
        "sim_stick_slip",
        "ext_stick_slip",
        "meas_rotor_min_rad_s",
        "sim_rotor_min_rad_s",
        "ext_rotor_min_rad_s",
        "meas_rotor_max_rad_s",
        "sim_rotor_max_rad_s",
        "ext_rotor_max_rad_s",
        "meas_fundamental_hz",
        "sim_fundamental_hz",
        "ext_fundamental_hz",
        "meas_motor_dip_rad_s",
        "sim_motor_dip_rad_s",
        "misfit_baseline",
        "misfit_extended",
        "misfit_noise_floor",
    ]);
    let opt = |f: &Option<Features>, g: fn(&Features) -> String| f.as_ref().map(g).unwrap_or_else(|| "".into());
    for r in &d.detail.runs {
        t.push([
            r.id.clone(),
            r.fold.to_string(),
            fmt_fixed(r.motor_rpm_setpoint, 1),
            fmt_fixed(r.normal_force_n, 2),
            r.slip_samples.to_string(),
            r.measured.stick_slip().to_string(),
            opt(&r.simulated, |f| f.stick_slip().to_string()),
            opt(&r.extended, |f| f.stick_slip().to_string()),
            fmt_fixed(r.measured.rotor_min_rad_s, 2),
            opt(&r.simulated, |f| fmt_fixed(f.rotor_min_rad_s, 2)),
            opt(&r.extended, |f| fmt_fixed(f.rotor_min_rad_s, 2)),
            fmt_fixed(r.measured.rotor_max_rad_s, 2),
            opt(&r.simulated, |f| fmt_fixed(f.rotor_max_rad_s, 2)),
            opt(&r.extended, |f| fmt_fixed(f.rotor_max_rad_s, 2)),
            fmt_fixed(r.measured.fundamental_hz, 2),
            opt(&r.simulated, |f| fmt_fixed(f.fundamental_hz, 2)),
            opt(&r.extended, |f| fmt_fixed(f.fundamental_hz, 2)),
            fmt_fixed(r.measured.motor_dip_rad_s, 2),
            opt(&r.simulated, |f| fmt_fixed(f.motor_dip_rad_s, 2)),
            f4(r.misfit_baseline),
            f4(r.misfit_extended),
            f4(r.misfit_noise_floor),
        ]);
    }
    t
}

/// tables/diagnosis-checks.csv: every check of the other run kinds and the
/// free-run checks of the baseline and the extended model.
pub fn checks_table(d: &Diagnosis) -> Table {
    let mut t = Table::new([
        "model",
        "channel",
        "run_kind",
        "statistic",
        "noise_floor",
        "ratio",
        "threshold",
        "flagged",
        "in_adequacy",
    ]);
    let det = &d.detail;
    // With a free run, the break-away dwell is the record's against the final
    // model's (lib.rs, extension::dwell); the other run kinds judge the baseline.
    let model_of = |k: &ChannelCheck| match [crate::extension::dwell::CHECK, crate::extension::dwell::STICKS_CHECK]
        .contains(&k.channel.as_str())
        && !det.free_run_extended.is_empty()
    {
        true => "extended",
        false => "baseline",
    };
    let rows = det
        .channel_checks
        .iter()
        .map(|k| (model_of(k), k, true))
        .chain(det.free_run_baseline.iter().map(|k| ("baseline", k, false)))
        .chain(det.free_run_extended.iter().map(|k| ("extended", k, false)));
    for (model, k, adequacy) in rows {
        t.push([
            model.to_string(),
            k.channel.clone(),
            k.run_kind.clone(),
            format!("{}", round_sig(k.statistic, 4)),
            format!("{}", round_sig(k.noise_floor, 4)),
            fmt_fixed(k.ratio, 3),
            if k.threshold.is_finite() { fmt_fixed(k.threshold, 2) } else { "".into() },
            k.flagged.to_string(),
            adequacy.to_string(),
        ]);
    }
    t
}

/// tables/diagnosis-candidates.csv: every effect tried in every forward-selection
/// step, with its cross-validated misfit, gain (and its spread over folds) and
/// the paired run-level t (crate docs).
pub fn candidates_table(d: &Diagnosis) -> Table {
    let mut t = Table::new([
        "step",
        "effect",
        "misfit_before",
        "misfit_after",
        "relative_gain",
        "relative_gain_fold_sd",
        "paired_t",
        "accepted",
    ]);
    for r in &d.detail.steps {
        t.push([
            r.step.to_string(),
            r.effect.clone(),
            f4(r.misfit_before),
            f4(r.misfit_after),
            f4(r.gain),
            f4(r.gain_fold_sd),
            if r.t.is_finite() { fmt_fixed(r.t, 2) } else { "inf".into() },
            r.accepted.to_string(),
        ]);
    }
    t
}

/// tables/diagnosis-rungs.csv: thesis model → recalibrated rig model → extended model.
pub fn rungs_table(d: &Diagnosis) -> Table {
    let mut t = Table::new(["rung", "heldout_misfit", "gain_vs_previous", "cause"]);
    let mut prev: Option<f64> = None;
    for (name, m, cause) in &d.detail.rungs {
        let gain = prev.map(|p| f4(1.0 - m / p)).unwrap_or_default();
        t.push([name.clone(), f4(*m), gain, cause.clone()]);
        prev = Some(*m);
    }
    t
}

/// The evidence figures.
pub fn figures(d: &Diagnosis) -> Vec<FigureSpec> {
    let mut out = Vec::new();
    let det = &d.detail;
    if !det.mu_vs_speed.is_empty() {
        let s = |name: &str, k: usize, style| Series {
            name: name.into(),
            x: det.mu_vs_speed.iter().map(|r| r.speed_rad_s).collect(),
            y: det.mu_vs_speed.iter().map(|r| [r.measured, r.baseline, r.extended][k]).collect(),
            style,
        };
        out.push(FigureSpec {
            id: "diagnosis-friction-vs-slip".into(),
            title: "Friction coefficient against slip speed (training runs)".into(),
            caption: format!(
                "Mean observed μ = F/N0 over slip samples binned by |Ω1| (30 bins), with the baseline (Coulomb) and the \
                 verdict's model ({}) averaged over the same samples. A speed law shows as a trend; a time or angle \
                 modulation averages out here. Shaded: 95 % interval of the measured mean, Student t over the \
                 runs' own bin means (the run is the independent unit; samples within a run are correlated); no band \
                 where fewer than two runs slip that fast.",
                d.verdict
            ),
            x_label: "slip speed |Ω1| [rad/s]".into(),
            y_label: "friction coefficient μ [-]".into(),
            series: vec![
                band(
                    "measured, 95 % interval over runs",
                    &det.mu_vs_speed.iter().map(|r| r.speed_rad_s).collect::<Vec<_>>(),
                    &det.mu_vs_speed.iter().map(|r| r.measured - r.measured_half_width_95).collect::<Vec<_>>(),
                    &det.mu_vs_speed.iter().map(|r| r.measured + r.measured_half_width_95).collect::<Vec<_>>(),
                ),
                s("measured", 0, SeriesStyle::Points),
                s("baseline", 1, SeriesStyle::Dashed),
                s("extended", 2, SeriesStyle::Line),
            ],
            x_decimals: 2,
            y_decimals: 4,
            heatmap: None,
        });
    }
    if !det.freq_scan.is_empty() {
        out.push(FigureSpec {
            id: "diagnosis-frequency-scan".into(),
            title: "Residual spectrum of the friction coefficient (normal-force scan)".into(),
            caption: "Fraction of the baseline's weighted residual sum of squares explained by a sinusoid in time at each \
                      frequency (shared frequency, own amplitude and phase per run) over the training runs' slip samples. \
                      A narrow peak is a time-periodic normal force."
                .into(),
            x_label: "frequency [Hz]".into(),
            y_label: "explained fraction of RSS [-]".into(),
            series: vec![Series {
                name: "scan".into(),
                x: det.freq_scan.iter().map(|r| r.0).collect(),
                y: det.freq_scan.iter().map(|r| r.1).collect(),
                style: SeriesStyle::Line,
            }],
            x_decimals: 2,
            y_decimals: 4,
            heatmap: None,
        });
    }
    if let Some(f) = residual_vs_angle_figure(d) {
        out.push(f);
    }
    if let Some(f) = extension_figure(d) {
        out.push(f);
    }
    let dips: Vec<_> = det.runs.iter().collect();
    if !dips.is_empty() {
        let mut series = vec![Series {
            name: "measured".into(),
            x: dips.iter().map(|r| r.motor_rpm_setpoint).collect(),
            y: dips.iter().map(|r| r.measured.motor_dip_rad_s).collect(),
            style: SeriesStyle::Marker { shape: MarkerShape::Circle, filled: true },
        }];
        let sim: Vec<_> =
            dips.iter().filter_map(|r| r.simulated.map(|f| (r.motor_rpm_setpoint, f.motor_dip_rad_s))).collect();
        if !sim.is_empty() {
            series.push(Series {
                name: "baseline simulation".into(),
                x: sim.iter().map(|p| p.0).collect(),
                y: sim.iter().map(|p| p.1).collect(),
                style: SeriesStyle::Markers,
            });
        }
        out.push(motor_dips_figure(series, det.motor_speed_tick_rad_s));
    }
    if !det.signature_curve.is_empty() {
        let best = &det.signature[0];
        let part = |held: bool| Series {
            name: if held { "held-out fold".into() } else { "training folds".into() },
            x: det.signature_curve.iter().filter(|p| p.2 == held).map(|p| p.0).collect(),
            y: det.signature_curve.iter().filter(|p| p.2 == held).map(|p| p.1).collect(),
            style: if held { SeriesStyle::Markers } else { SeriesStyle::Points },
        };
        out.push(FigureSpec {
            id: "diagnosis-residual-signature".into(),
            title: format!("What the leftover mismatch follows: {} ({} channel)", best.signal, best.channel),
            caption: format!(
                "Mean residual of the final model ({} channel; relative) in 24 bins of {}, training folds and the \
                 held-out fold apart (bins with at least 10 samples). A term in this signal removes {:.0} % of the \
                 held-out residual (rig-diagnose signature module).",
                best.channel,
                best.signal,
                100.0 * best.heldout_gain
            ),
            x_label: best.signal.into(),
            y_label: "mean residual [-]".into(),
            series: vec![part(false), part(true)],
            x_decimals: 3,
            y_decimals: 4,
            heatmap: None,
        });
    }
    out
}

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

/// The extension's free run beside the record and the final model's, for
/// the operating point whose rotor-speed extremes the extension moves most
/// towards the record's (held-out: that run's extension was fitted without it).
fn extension_figure(d: &Diagnosis) -> Option<FigureSpec> {
    let x = d.findings.iter().find_map(|f| f.extension.as_ref())?;
    let span = |y: &[f64]| {
        let lo = y.iter().copied().fold(f64::INFINITY, f64::min);
        let hi = y.iter().copied().fold(f64::NEG_INFINITY, f64::max);
        (lo, hi)
    };
    let miss = |m: (f64, f64), y: &Option<Vec<f64>>| {
        y.as_ref().map(|y| {
            let (lo, hi) = span(y);
            (lo - m.0).abs() + (hi - m.1).abs()
        })
    };
    let t = d
        .detail
        .extension_traces
        .iter()
        .filter_map(|t| {
            let m = span(&t.measured_rad_s);
            Some((t, miss(m, &t.baseline_rad_s)? - miss(m, &t.extended_rad_s)?))
        })
        .max_by(|a, b| a.1.total_cmp(&b.1))?
        .0;
    let line = |name: &str, y: &[f64], style| Series { name: name.into(), x: t.time_s.clone(), y: y.to_vec(), style };
    Some(FigureSpec {
        id: "diagnosis-extension-free-run".into(),
        title: format!("The extension's free run beside the record ({})", t.id),
        caption: format!(
            "Rotor speed Ω1 of {} over its steady window: measured, the final model's free run and the final model \
             with the data-driven extension ({}), each simulated from rest under the run's protocol; the extension's \
             coefficients were fitted without this run's fold. The run shown is the one whose extremes the extension \
             moves most towards the record's. Cross-validated free-run misfit over every run {} → {}.",
            t.id, x.formula, x.free_run_misfit_before, x.free_run_misfit_after
        ),
        x_label: "time [s]".into(),
        y_label: "Ω1 [rad/s]".into(),
        series: vec![
            line("measured", &t.measured_rad_s, SeriesStyle::Line),
            line("final model", t.baseline_rad_s.as_deref()?, SeriesStyle::Dashed),
            line("with the extension", t.extended_rad_s.as_deref()?, SeriesStyle::Line),
        ],
        x_decimals: 2,
        y_decimals: 3,
        heatmap: None,
    })
}

/// μ residual against rotor angle for the run with most slip: the mean over
/// revolutions in each angle bin with its 95 % interval as a band (select.rs
/// says why revolutions are the unit), so a reader sees whether a wave
/// stands out of its own uncertainty.
fn residual_vs_angle_figure(d: &Diagnosis) -> Option<FigureSpec> {
    let r = &d.detail.residual_vs_angle;
    if r.is_empty() {
        return None;
    }
    let x: Vec<f64> = r.iter().map(|r| r.0).collect();
    let revs = (r.iter().map(|r| r.4).min()?, r.iter().map(|r| r.4).max()?);
    Some(FigureSpec {
        id: "diagnosis-residual-vs-angle".into(),
        title: "Friction residual against rotor angle (training run with most slip)".into(),
        caption: format!(
            "μ_obs − μk over slip samples in 72 bins of the rotor angle φ1 mod 2π: in each bin the mean over the \
             revolutions that pass through it ({}–{} per bin) of the per-revolution mean, with its 95 % interval \
             (±1.96 standard errors over revolutions; samples within one pass are correlated, so a pass is the \
             unit). A warped or eccentric disc shows n periods per revolution standing out of the band; a wave \
             inside it is not evidence.",
            revs.0, revs.1
        ),
        x_label: "rotor angle mod 2π [rad]".into(),
        y_label: "μ residual [-]".into(),
        series: vec![
            band(
                "95 % interval of the mean",
                &x,
                &r.iter().map(|r| r.2).collect::<Vec<_>>(),
                &r.iter().map(|r| r.3).collect::<Vec<_>>(),
            ),
            Series {
                name: "mean over revolutions".into(),
                x: x.clone(),
                y: r.iter().map(|r| r.1).collect(),
                style: SeriesStyle::Line,
            },
            Series {
                name: "zero".into(),
                x: vec![0.0, 2.0 * std::f64::consts::PI],
                y: vec![0.0, 0.0],
                style: SeriesStyle::Dashed,
            },
        ],
        x_decimals: 3,
        y_decimals: 4,
        heatmap: None,
    })
}

/// The motor-speed dips with the resolution of the speed they are read from:
/// a dip of one encoder tick over the differentiator window is quantisation,
/// so that level is drawn as a shaded band from 0 and named in the caption.
fn motor_dips_figure(mut series: Vec<Series>, tick_rad_s: f64) -> FigureSpec {
    let xs: Vec<f64> = series.iter().flat_map(|s| s.x.iter().copied()).filter(|x| x.is_finite()).collect();
    let (lo, hi) = xs.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(a, b), &x| (a.min(x), b.max(x)));
    if tick_rad_s > 0.0 && lo.is_finite() {
        series.push(band(
            &format!("below 1 encoder tick per differentiator window ({tick_rad_s:.3} rad/s)"),
            &[lo, hi],
            &[0.0, 0.0],
            &[tick_rad_s, tick_rad_s],
        ));
    }
    FigureSpec {
        id: "diagnosis-motor-dips".into(),
        title: "Deepest motor-speed dip below the set-point, per operating point".into(),
        caption: format!(
            "Largest Ω_set − Ω2 over each run's steady state (after ramp + settle). A drive that saturates lets the \
             motor slow while the rotor is stuck; the PI loop of the baseline holds it. Ω2 comes from encoder ticks \
             through a centred difference, so it moves in steps of one tick over the differentiator window \
             ({tick_rad_s:.3} rad/s, the grey band): a dip inside the band is quantisation, not a slow-down."
        ),
        x_label: "motor set-point [rpm]".into(),
        y_label: "motor speed dip [rad/s]".into(),
        series,
        x_decimals: 1,
        y_decimals: 3,
        heatmap: None,
    }
}

/// Every operating point's rotor speed, measured against the baseline's and
/// the extended model's free runs, one panel per run on one sheet: where the
/// models fail is seen in one look.
pub fn speed_sheet(d: &Diagnosis) -> Option<Sheet> {
    let traces = &d.detail.speed_traces;
    if traces.is_empty() {
        return None;
    }
    let panels = traces
        .iter()
        .map(|t| {
            let row = d.detail.runs.iter().find(|r| r.id == t.id);
            let title = match row {
                Some(r) => format!("{} · {:.0} rpm · {:.1} N", t.id, r.motor_rpm_setpoint, r.normal_force_n),
                None => t.id.clone(),
            };
            let nan = vec![f64::NAN; t.time_s.len()];
            let line = |name: &str, y: &Option<Vec<f64>>, style| Series {
                name: name.into(),
                x: t.time_s.clone(),
                y: y.clone().unwrap_or_else(|| nan.clone()),
                style,
            };
            let spec = FigureSpec {
                id: format!("diagnosis-speed-{}", t.id),
                title,
                caption: String::new(),
                x_label: "time [s]".into(),
                y_label: "Ω1 [rad/s]".into(),
                series: vec![
                    Series {
                        name: "measured".into(),
                        x: t.time_s.clone(),
                        y: t.measured_rad_s.clone(),
                        style: SeriesStyle::Line,
                    },
                    line("baseline", &t.baseline_rad_s, SeriesStyle::Dashed),
                    line("extended", &t.extended_rad_s, SeriesStyle::Line),
                ],
                x_decimals: 2,
                y_decimals: 3,
                heatmap: None,
            };
            Panel { spec, x_scale: AxisScale::Linear }
        })
        .collect();
    Some(Sheet {
        id: "diagnosis-speed-small-multiples".into(),
        title: format!("Rotor speed per operating point: measured, baseline and extended ({})", d.verdict),
        caption: "Ω1 over each operating point's steady window (after ramp + settle), measured (encoder, centred \
                  difference) and simulated from rest under the run's protocol by the baseline rig model and by the \
                  extended model of the verdict (the free runs of the diagnosis' free-run checks), sampled at 20 Hz. \
                  A panel where the dashed or the second solid line leaves the measured one is an operating point \
                  that model gets wrong; a missing line is a simulation that failed."
            .into(),
        columns: 6,
        panels,
    })
}

/// The traces of [`speed_sheet`] as one long table, one row per sample:
/// what a reader loads to redo the comparison (written with a Parquet twin).
pub fn speed_traces_table(d: &Diagnosis) -> Table {
    let mut t = Table::new(["run", "time_s", "measured_rotor_rad_s", "baseline_rotor_rad_s", "extended_rotor_rad_s"]);
    let cell = |v: Option<&Vec<f64>>, i: usize| v.and_then(|v| v.get(i)).map_or(String::new(), |x| fmt_fixed(*x, 3));
    for tr in &d.detail.speed_traces {
        for (i, &time) in tr.time_s.iter().enumerate() {
            t.push([
                tr.id.clone(),
                fmt_fixed(time, 3),
                fmt_fixed(tr.measured_rad_s[i], 3),
                cell(tr.baseline_rad_s.as_ref(), i),
                cell(tr.extended_rad_s.as_ref(), i),
            ]);
        }
    }
    t
}
