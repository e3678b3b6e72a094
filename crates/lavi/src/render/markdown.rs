//! `lavi.md`: the study's report, and the candidates side by side.

use super::*;

pub(super) fn markdown(
    s: &Study,
    met_base: &[usize; N_FEATURES],
    met_ext: &[usize; N_FEATURES],
    description: &str,
) -> String {
    let sel = &s.selection;
    let nh = s.windows.len() - 1;
    let b = &s.baseline;
    let mut md = String::new();
    let _ = writeln!(md, "# UFRJ LAVI 2018, run 175: what the simulation gets wrong, why, and the gain of the fix\n");
    let _ = writeln!(
        md,
        "Data: Real, Lobo, Ritto, Pinto (2018), J. Petroleum Sci. Eng. 170, 755-762 (doi:10.1016/j.petrol.2018.07.008); read from \
         ../shared, never copied. Models are fitted on the authors' window {} s only (Lobo et al. 2020, doi:10.1016/j.ijmecsci.2020.105578) \
         and judged on {} held-out windows ({}), whose mean top speeds differ. Features (rig_lavi::features, one function for \
         measurement and simulation, {} Hz low-pass): the mean over stick-slip cycles of the bit-speed maximum and minimum, the \
         fraction of time below {} rpm, the fundamental from the line analysis, and the mean torque-bit-speed loop area per cycle. \
         Every simulation runs free from the measured state {} s before its window, driven by the top speed as measured (the drives \
         `compliant_drive` and `motor_drive` simulate the top instead, their reference from the record). Two torque \
         features judge the friction level (issue 26): the mean torque while the bit slips and the break-away torque (mean of the \
         complete stick phases' largest torque). Misfit, joint in motion and torque level (issue 26: a law that reproduces the \
         motion with a friction level off the measured one is no explanation): each feature's error in units of its target (10 %, \
         10 rpm, 25 %, 3 %, 30 %, 10 %, 10 %), capped at 10, the five motion features and the two torque features weighing half \
         each, M = √(½ mean_motion e² + ½ mean_torque e²) (rig_lavi::score; a plain RMS over the seven let the motion outvote the \
         torque level 5 to 2); 1 means motion and torque level within their targets in that RMS.\n",
        s.windows[0].label,
        nh,
        s.windows[1..].iter().map(|w| w.label.as_str()).collect::<Vec<_>>().join(", "),
        s.params.cutoff_hz,
        s.params.stick_speed_rpm,
        s.params.warmup_s
    );
    let _ = writeln!(md, "## Rung 1: the baseline and what it gets wrong\n");
    let _ = writeln!(
        md,
        "1-DOF model J Ω' = k φ + c (Ω_top − Ω) − T(Ω) (Real et al. 2018) with J = {:.4} kg m², k = {:.3} N m/rad, c = {:.3} N m s/rad \
         (linear least squares on the equation of motion; the unconstrained c was {:.4}{}), friction T = {:.3} + {:.3} exp(−(Ω/{:.2} rad/s)^{}) N m \
         (fitted to the slip samples). Held-out misfit {:.3} (RMS over the windows; calibration window {:.3}). Held-out targets met by the baseline: {}.\n",
        b.inertia_kgm2,
        b.stiffness_nm_rad,
        b.damping_nm_s_rad,
        s.derivation.free.damping_nm_s_rad,
        if s.derivation.at_bounds.is_empty() {
            ""
        } else {
            ", negative: pinned at its bound 0 and reported as a parameter at its bound, a symptom the structural candidates below examine"
        },
        b.friction.kinetic_nm,
        b.friction.static_nm - b.friction.kinetic_nm,
        b.friction.stribeck_speed_rad_s,
        b.friction.shape_exponent,
        overall(&sel.baseline_heldout),
        sel.baseline_calibration,
        met_list(met_base, nh)
    );
    let _ = writeln!(md, "{}", feature_summary(s, |i| &s.baseline_features[i]));
    let _ = writeln!(md, "## Rung 2: the cause\n");
    let _ = writeln!(
        md,
        "{} candidate causes (rig_lavi crate docs), each fitted on the calibration window on top of the current model and scored on the \
         held-out windows, selected by the one forward-selection engine of every rig (rig_types::select) and its one rule \
         (`[shared.selection]`): an effect is added when it has the largest held-out gain of its step, lowers the held-out misfit \
         (RMS over the windows) by at least {:.0} %, has a paired t of ln(M_before/M_after) over the {} held-out windows of at least {} \
         and is admissible: no worse on the calibration window it was fitted on (tables/lavi-candidates.csv, tables/lavi-heldout-misfits.csv).\n",
        s.selection.trials.iter().filter(|t| t.step == 1).count(),
        100.0 * s.params.selection.min_relative_gain,
        nh,
        s.params.selection.min_t
    );
    let _ = writeln!(md, "Effect ids of this rig (lavi-diagnosis.json; parameters as its JSON keys):\n");
    for (id, what) in EFFECT_IDS {
        let _ = writeln!(md, "- `{id}`: {what}");
    }
    let _ = writeln!(md);
    let _ = writeln!(
        md,
        "| step | effect | calibration misfit | held-out misfit (RMS, min-max) | gain (± spread) | paired t | wins | earns its place |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for (i, t) in sel.trials.iter().enumerate() {
        let lo = t.heldout.iter().cloned().fold(f64::INFINITY, f64::min);
        let hi = t.heldout.iter().cloned().fold(f64::NEG_INFINITY, f64::max);
        let _ = writeln!(
            md,
            "| {} | {}{} | {:.3} | {:.3} ({:.3}-{:.3}) | {:.3} ± {:.3} | {:.2} | {}/{} | {} |",
            t.step,
            t.candidate.id(),
            if sel.chosen.contains(&i) { " **(added)**" } else { "" },
            t.fitted.calibration_misfit,
            t.heldout_misfit,
            lo,
            hi,
            t.relative_gain,
            t.gain_spread,
            t.paired_t,
            t.wins,
            t.heldout.len(),
            match (&t.refused, t.earns_place) {
                (Some(r), _) => format!("no, refused: {r}"),
                (None, true) => "yes".into(),
                (None, false) => inadmissible(sel, t).unwrap_or_else(|| "no".into()),
            }
        );
    }
    let _ = writeln!(md);
    let chosen: Vec<Candidate> = sel.chosen.iter().map(|&i| sel.trials[i].candidate).collect();
    if let (Some(d), Some(l)) = (
        chosen.iter().position(|c| *c == Candidate::ChannelDelay),
        chosen.iter().position(|c| *c == Candidate::FrictionLaw),
    ) && d < l
    {
        let _ = writeln!(
            md,
            "`channel_delay` already refits the law by simulation; `friction_law` at step {} refits the same three families from \
             that law: what it gains is the law's fit continued from a better start, not a second effect.\n",
            l + 1
        );
    }
    if let Some(d) = chosen.iter().position(|c| *c == Candidate::ChannelDelay) {
        let at = |step: usize, c: Candidate| sel.trials.iter().find(|t| t.step == step && t.candidate == c);
        if let (Some(law), Some(delay)) = (at(d + 1, Candidate::FrictionLaw), at(d + 1, Candidate::ChannelDelay)) {
            let _ = writeln!(
                md,
                "The delay's own share, side by side with the same law fit: the law refitted by simulation on the baseline's \
                 structure (J, k, c of the torque as recorded; `friction_law`, step {}) reaches {:.3}; on J, k, c of the torque \
                 read {:.0} ms later (`channel_delay`) {:.3}, better on {} of {} held-out windows.\n",
                d + 1,
                law.heldout_misfit,
                1e3 * delay.fitted.model.torque_delay_s,
                delay.heldout_misfit,
                law.heldout.iter().zip(&delay.heldout).filter(|(a, b)| b < a).count(),
                law.heldout.len()
            );
        }
        let memory =
            |step: usize| sel.trials.iter().find(|t| t.step == step && t.candidate == Candidate::FrictionMemory);
        if let (Some(first), Some(after)) = (memory(1), memory(d + 2).filter(|t| !t.earns_place)) {
            let _ = writeln!(
                md,
                "Was `friction_memory` compensating the delay? Alone (step 1) it reaches {:.3} with its lag at {} s; on top of \
                 `channel_delay` (step {}) it gains {:.3} (paired t {:.2}) and does not earn its place: once the torque is read on \
                 the speeds' time base and the law is fitted by simulation, no memory is needed. Its frozen slip level stood in for a \
                 law that does not fall with speed, the law the free run accepts (rung 3).\n",
                first.heldout_misfit,
                first.fitted.params.get("lag_s").map_or("?".to_string(), |x| format!("{x:.3}")),
                d + 2,
                after.relative_gain,
                after.paired_t
            );
        }
    }
    let _ = writeln!(md, "{}", side_by_side(s));
    let _ = writeln!(md, "{}", structure_paragraph(s));
    match sel.chosen.first() {
        Some(&i) => {
            let t = &sel.trials[i];
            let others = sel
                .trials
                .iter()
                .filter(|o| o.step == 1 && o.candidate != t.candidate)
                .map(|o| o.heldout_misfit)
                .fold(f64::INFINITY, f64::min);
            let _ = writeln!(
                md,
                "**Cause: `{}`** ({}). Held-out misfit {:.3} → {:.3} (gain {:.2}); the next best candidate of step 1 reaches {:.3}. \
                 Window by window it beats every other step-1 candidate on {} of {} held-out windows.\n",
                t.candidate.id(),
                t.fitted.params.iter().map(|(k, v)| format!("{k} = {}", sig(*v))).collect::<Vec<_>>().join(", "),
                overall(&sel.baseline_heldout),
                t.heldout_misfit,
                t.relative_gain,
                others,
                (0..t.heldout.len())
                    .filter(|&k| sel
                        .trials
                        .iter()
                        .filter(|o| o.step == 1 && o.candidate != t.candidate)
                        .all(|o| t.heldout[k] < o.heldout[k]))
                    .count(),
                t.heldout.len()
            );
            // The cause against each rival by the selection's own rule (rig_types::select::compare): the
            // rival as "before", the cause as "after", every window its own fold.
            let n = t.heldout.len();
            let rivals: Vec<String> = sel
                .trials
                .iter()
                .filter(|o| o.step == 1 && o.candidate != t.candidate && o.refused.is_none())
                .map(|o| {
                    let c = rig_types::select::compare(&o.heldout, &t.heldout, &(0..n).collect::<Vec<_>>(), n);
                    format!(
                        "`{}` {:.3}, gain {:.2}, t {:.2}{}",
                        o.candidate.id(),
                        o.heldout_misfit,
                        c.gain,
                        c.t,
                        if sel.rule.admits(&c) { "" } else { " (not significant)" }
                    )
                })
                .collect();
            let _ = writeln!(
                md,
                "Side by side by the selection's own rule (the cause against each other step-1 candidate, gain and paired t of \
                 ln(M_rival/M_cause) over the held-out windows, admitted at gain >= {:.0} % and t >= {}): {}.\n",
                100.0 * sel.rule.min_relative_gain,
                sel.rule.min_t,
                rivals.join("; ")
            );
            let _ = writeln!(md, "{}", torque_level(s));
        }
        None => {
            let _ = writeln!(md, "No candidate earns its place.\n");
        }
    }
    let _ = writeln!(md, "## Rung 3: the extension and its gain\n");
    let _ = writeln!(
        md,
        "Extended model: baseline + {}. Held-out misfit (RMS over the windows) {:.3} (baseline {:.3}, relative gain {:.2}); spread over the windows {:.3}-{:.3}. \
         Held-out targets met: {} (baseline: {}). Verdict: **{}**.\n",
        effects_label(s),
        overall(&sel.final_heldout),
        overall(&sel.baseline_heldout),
        1.0 - overall(&sel.final_heldout) / overall(&sel.baseline_heldout),
        sel.final_heldout.iter().cloned().fold(f64::INFINITY, f64::min),
        sel.final_heldout.iter().cloned().fold(f64::NEG_INFINITY, f64::max),
        met_list(met_ext, nh),
        met_list(met_base, nh),
        s.verdict()
    );
    let _ = writeln!(md, "{}", feature_summary(s, |i| &s.final_features[i]));
    for (fi, name) in FEATURES.iter().enumerate() {
        if met_ext[fi] < nh {
            let errs: Vec<String> = (1..s.windows.len())
                .map(|wi| format!("{:.2}", feature_errors(&s.measured[wi], &s.final_features[wi])[fi]))
                .collect();
            let _ = writeln!(
                md,
                "- Target not reached: `{name}` ({}) on {} of {nh} held-out windows; error/tolerance per window: {}.",
                TARGETS[fi],
                nh - met_ext[fi],
                errs.join(", ")
            );
        }
    }
    if met_ext[2] < nh {
        // What the stick fraction is made of, on each window where it misses.
        let missed: Vec<String> = (1..s.windows.len())
            .filter(|&wi| !met(&s.measured[wi], &s.final_features[wi])[2])
            .map(|wi| {
                let (m, x) = (&s.measured[wi], &s.final_features[wi]);
                format!(
                    "{}: {} phases of {:.0} ms measured, {} of {:.0} ms simulated",
                    s.windows[wi].label,
                    m.stick_phases,
                    1e3 * m.stick_phase_s,
                    x.stick_phases,
                    1e3 * x.stick_phase_s
                )
            })
            .collect();
        let _ = writeln!(
            md,
            "- What `stick_fraction` is made of where it misses (complete stick phases, measured and simulated bit speed through the \
             same one {} Hz low-pass and the same {} rpm threshold): {}.",
            s.params.cutoff_hz,
            s.params.stick_speed_rpm,
            missed.join("; ")
        );
    }
    if met_ext.iter().any(|m| *m < nh) {
        let _ = writeln!(md, "{}", resolution_of_misses(s));
    }
    if met_ext[5] < nh || met_ext[6] < nh {
        let _ = writeln!(md, "{}", torque_level_hypothesis(s));
        let _ = writeln!(md, "{}", stick_torque_finding(s));
    }
    let _ = writeln!(md);
    if !s.adequate {
        let _ = writeln!(
            md,
            "**Adequacy.** The held-out misfit (RMS over the windows) {:.3} is above the threshold {} (motion and torque level within their targets in the joint RMS): a significant \
             mismatch is left, so the verdict is `unexplained` with the effects above kept as a partial explanation. Residual signature \
             (STLSQ on the calibration window's leftover slip torque, each term scored alone on the held-out windows):\n",
            overall(&sel.final_heldout),
            s.params.adequacy_threshold
        );
        for t in &s.signature {
            let _ = writeln!(md, "- `{}`: held-out gain {:.2}: {}.", t.signal, t.heldout_gain, t.description);
        }
        if s.signature.is_empty() {
            let _ = writeln!(md, "- no library signal lowers the held-out residual.");
        }
        let missed: Vec<&str> = FEATURES.iter().zip(met_ext).filter(|(_, k)| **k < nh).map(|(f, _)| *f).collect();
        let missed = if missed.is_empty() { "none".to_string() } else { missed.join(", ") };
        let top = s.signature.first().map_or("no library signal", |t| t.signal.as_str());
        if top == "bit_speed_rad_s" {
            let _ = writeln!(
                md,
                "\nWhat would reach the missed targets ({missed}): the leftover torque follows the bit speed most, i.e. the recorded \
                 torque falls with speed more steeply than the law the free run accepts (the torque-level hypothesis above). A steeper \
                 law inside the contact is what runs away in free run, and the bit's balance leaves no room for a drag along the shaft \
                 (What the torque channel reads). {}\n",
                if s.drive.as_ref().is_some_and(|d| s
                    .selection
                    .trials
                    .iter()
                    .any(|t| t.step == d.step && t.candidate == Candidate::MotorDrive && t.earns_place))
                {
                    "The drive that answers the bit (below) earns its place."
                } else {
                    "The drive that answers the bit, identified on the record and run with the law the calibration window chose (below), is not kept: \
                     what holds the real rig's falling torque in stick-slip is not a motor answering the string torque as the \
                     record's top speed allows."
                }
            );
        } else {
            let _ = writeln!(
                md,
                "\nWhat would reach the missed targets ({missed}): the leftover torque follows `{top}` most, so the next rung is a model \
                 term in that signal inside the simulated contact, fitted on the calibration window like the candidates above.\n"
            );
        }
    }
    md.push_str(&crate::top_delay::section(s));
    md.push_str(&crate::wob_level::section(s));
    md.push_str(&crate::static_friction::section(s));
    md.push_str(&crate::wob_angle::section(s));
    md.push_str(&crate::drive::section(s));
    let h = &s.wob;
    let _ = writeln!(md, "## The chapter's hypothesis: a varying normal force\n");
    let _ = writeln!(
        md,
        "The thesis blamed a vibrating normal force (Eq. 4-11). This rig measures it: in the calibration window the weight on bit varies by \
         {:.1} % (std/mean). Teacher-forced, the torque WOB(t)·μ(Ω_meas(t)) with μ fitted on T/WOB draws a loop of {:.0} % of the measured \
         loop area on the held-out windows (per window: {}; a single-valued T(Ω) draws none). In free simulation, adding the measured WOB \
         to the baseline lowers the held-out misfit by {:.1} %. So the normal-force variation explains {} of the torque-speed \
         loop but only {:.0} % of the simulation error.\n",
        100.0 * h.wob_relative_std,
        100.0 * h.loop_fraction_heldout_mean,
        h.loop_fraction[1..].iter().map(|x| format!("{:.0} %", 100.0 * x)).collect::<Vec<_>>().join(", "),
        100.0 * h.misfit_gain,
        if h.loop_fraction_heldout_mean > 0.5 { "most" } else { "a minor part" },
        100.0 * h.misfit_gain.max(0.0)
    );
    let _ = writeln!(md, "## Description of the calibration window\n");
    md.push_str(description.trim_start_matches(|c| c != '\n').trim_start());
    md
}

/// Every step-1 candidate (and the baseline and the extended model) on every
/// feature: held-out windows within the target, and the held-out misfit (RMS over the windows).
pub(super) fn side_by_side(s: &Study) -> String {
    let held: Vec<usize> = (1..s.windows.len()).collect();
    let nh = held.len();
    let mut t = String::from(
        "Side by side, every step-1 candidate fitted on the calibration window alone and judged on every held-out window \
         (tables/lavi-candidate-features.csv): held-out windows within the target, per feature.\n\n| model | ",
    );
    t.push_str(&FEATURES.join(" | "));
    t.push_str(" | held-out misfit |\n|---|");
    t.push_str(&"---|".repeat(N_FEATURES + 1));
    t.push('\n');
    let mut row = |name: &str, f: &[Features], misfit: f64| {
        let mut c = [0usize; N_FEATURES];
        for &wi in &held {
            for (fi, ok) in met(&s.measured[wi], &f[wi]).iter().enumerate() {
                c[fi] += *ok as usize;
            }
        }
        let cells: Vec<String> = c.iter().map(|k| format!("{k}/{nh}")).collect();
        let _ = writeln!(t, "| {name} | {} | {misfit:.3} |", cells.join(" | "));
    };
    row("baseline", &s.baseline_features, overall(&s.selection.baseline_heldout));
    for ((cand, f), tr) in s.candidate_features.iter().zip(s.selection.trials.iter().filter(|t| t.step == 1)) {
        row(cand.id(), f, tr.heldout_misfit);
    }
    row(&format!("extended ({})", effects_label(s)), &s.final_features, overall(&s.selection.final_heldout));
    // The torque level (issue 26): every step-1 candidate that meets the two torque targets on more windows
    // than the extended model, and the motion it loses for it.
    let count = |f: &[Features], fi: usize| held.iter().filter(|&&wi| met(&s.measured[wi], &f[wi])[fi]).count();
    let torque = |f: &[Features]| count(f, N_FEATURES - 2) + count(f, N_FEATURES - 1);
    let motion = |f: &[Features]| (0..N_FEATURES - 2).map(|fi| count(f, fi)).sum::<usize>();
    let ext = &s.final_features;
    let clauses: Vec<String> = s
        .candidate_features
        .iter()
        .zip(s.selection.trials.iter().filter(|t| t.step == 1))
        .filter(|((_, f), _)| torque(f) > torque(ext))
        .map(|((c, f), tr)| {
            let lost: Vec<String> = (0..N_FEATURES - 2)
                .filter(|&fi| count(f, fi) < count(ext, fi))
                .map(|fi| format!("`{}` {}/{nh}", FEATURES[fi], count(f, fi)))
                .collect();
            format!(
                "`{}` {}/{} (slip {}/{nh}, break-away {}/{nh}; motion {}/{}, losing {}; held-out misfit {:.3})",
                c.id(),
                torque(f),
                2 * nh,
                count(f, N_FEATURES - 2),
                count(f, N_FEATURES - 1),
                motion(f),
                (N_FEATURES - 2) * nh,
                if lost.is_empty() { "nothing".into() } else { lost.join(", ") },
                tr.heldout_misfit
            )
        })
        .collect();
    if !clauses.is_empty() {
        let all = s.candidate_features.iter().map(|(_, f)| f).chain([ext]);
        let _ = writeln!(
            t,
            "\nThe torque level side by side (window-features within the two torque targets; the extended model: {}/{}, \
             motion {}/{}, held-out misfit {:.3}): {}.{}",
            torque(ext),
            2 * nh,
            motion(ext),
            (N_FEATURES - 2) * nh,
            overall(&s.selection.final_heldout),
            clauses.join("; "),
            if all.into_iter().any(|f| torque(f) + motion(f) == N_FEATURES * nh) {
                ""
            } else {
                " Neither a step-1 candidate nor the extended model meets the torque level and the motion together."
            }
        );
    }
    t
}

/// What the record resolves of each miss of the extended model: the miss against how far the
/// window's own two halves lie apart, both in units of the whole window's tolerance.
fn resolution_of_misses(s: &Study) -> String {
    let mut rows = Vec::new();
    let (mut misses, mut unresolved) = (0, 0);
    for wi in 1..s.windows.len() {
        let (m, x) = (&s.measured[wi], &s.final_features[wi]);
        let e = feature_errors(m, x);
        let (h1, h2) = (feature_errors(m, &s.halves[wi][0]), feature_errors(m, &s.halves[wi][1]));
        for (fi, ei) in e.iter().enumerate() {
            if ei.abs() <= 1.0 {
                continue;
            }
            misses += 1;
            let apart = (h2[fi] - h1[fi]).abs();
            let resolved = ei.abs() > apart;
            if !resolved {
                unresolved += 1;
            }
            rows.push(format!(
                "{} `{}` {:+.2} (halves {:.2} apart{})",
                s.windows[wi].label,
                FEATURES[fi],
                ei,
                apart,
                if resolved { "" } else { ": not resolved" }
            ));
        }
    }
    format!(
        "- What the record resolves of each miss: the error over tolerance against how far the window's two halves (2 s each, the \
         same features of the record) lie apart in the same units: {}. {unresolved} of the {misses} misses are no larger than their \
         window's own halves differ by: the record does not resolve them.",
        rows.join("; ")
    )
}
