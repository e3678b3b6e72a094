//! lavi.md's readings of the structure, the channels and the torque level:
//! the structural candidates, the channels' clocks, the friction level
//! against the measured torque and the stick torque.

use super::*;

/// The negative damping and the structures tried (tables/lavi-structures.csv), and every parameter at a bound.
pub(super) fn structure_paragraph(s: &Study) -> String {
    let mut t = String::from(
        "**Structure.** The equation of motion fitted on the calibration window under each structure the negative damping may \
         point at (unconstrained; rig_lavi::eom), and the free run of that structure with its least-squares J, k, c and law (the \
         law fitted to the torque as the structure reads it, no simulation fit):\n\n| structure | c on the twist rate [N m s/rad] | \
         c_a on the bit speed [N m s/rad] | J [kg m²] | k [N m/rad] | R² | pinned at 0 | free run: held-out misfit |\n\
         |---|---|---|---|---|---|---|---|\n",
    );
    for ((name, d), free_run) in s.structures.iter().zip(&s.structure_heldout) {
        let f = &d.free;
        let pm = |x: f64, e: f64, used: bool| if used { format!("{x:.4} ± {e:.4}") } else { "—".into() };
        let _ = writeln!(
            t,
            "| {name} | {} | {} | {:.4} | {:.3} | {:.3} | {} | {free_run:.3} |",
            pm(f.damping_nm_s_rad, f.damping_stderr, matches!(d.structure.damping, Damping::TwistRate | Damping::Both)),
            pm(
                f.absolute_damping_nm_s_rad,
                f.absolute_damping_stderr,
                matches!(d.structure.damping, Damping::Absolute | Damping::Both)
            ),
            f.inertia_kgm2,
            f.stiffness_nm_rad,
            f.r_squared,
            if d.at_bounds.is_empty() {
                "none".to_string()
            } else {
                d.at_bounds.iter().map(|b| format!("`{}`", b.parameter)).collect::<Vec<_>>().join(", ")
            }
        );
    }
    let positive =
        s.structures.iter().filter(|(_, d)| d.at_bounds.is_empty()).map(|(n, _)| n.as_str()).collect::<Vec<_>>();
    let _ = writeln!(
        t,
        "\n{}\n",
        if positive.is_empty() {
            "No structure tried gives a non-negative damping: the energy input the least squares asks for is not explained by where \
             the damping acts, by a channel delay or by a sensor inertia; it stays a reported symptom (`parameters_at_bounds`)."
                .to_string()
        } else {
            format!("A non-negative damping comes out with: {}.", positive.join("; "))
        }
    );
    let free_run: Vec<String> = s
        .selection
        .trials
        .iter()
        .filter(|tr| {
            tr.step == 1
                && matches!(
                    tr.candidate,
                    Candidate::AbsoluteDamping | Candidate::ChannelDelay | Candidate::SensorInertia
                )
        })
        .map(|tr| format!("`{}` {:.3}", tr.candidate.id(), tr.heldout_misfit))
        .collect();
    let [raw, eom, narrow] = s.loop_spread;
    t.push_str(&channel_paragraph(s));
    let _ = writeln!(
        t,
        "Run free as step-1 candidates (`channel_delay` with its law refitted by simulation, the others with the least-squares \
         law), their held-out misfits (RMS over the windows) are {} (baseline {:.3}).\n",
        free_run.join(", "),
        overall(&s.selection.baseline_heldout)
    );
    let _ = writeln!(
        t,
        "**The delay and the loop.** Read {:.0} ms later (the equation of motion's delay), the torque against the bit speed is not a \
         curve: the spread of the torque within {} bit-speed bins of the slip samples is {:.3} N m RMS (largest {:.3}), against {:.3} \
         (largest {:.3}) as recorded; the narrowest cloud within ±50 ms is at {:+.0} ms with {:.3} N m RMS. So the delay that makes the \
         equation of motion hold does not turn the loop into a law of the bit speed alone: the aligned friction still depends on \
         something else, and a single-valued law fitted to it (the structure table's free run) {}.\n",
        1e3 * eom.shift_s,
        s.params.bins,
        eom.rms_bin_std_nm,
        eom.max_bin_std_nm,
        raw.rms_bin_std_nm,
        raw.max_bin_std_nm,
        1e3 * narrow.shift_s,
        narrow.rms_bin_std_nm,
        match s.structures.iter().zip(&s.structure_heldout).find(|((_, d), _)| d.structure.torque_delay_s != 0.0) {
            Some((_, m)) if *m > overall(&s.selection.baseline_heldout) => {
                format!("runs further from the record than the baseline (held-out misfit {m:.3})")
            }
            Some((_, m)) => format!("reaches a held-out misfit of {m:.3}"),
            None => "was not tried".to_string(),
        }
    );
    if !s.parameters_at_bounds.is_empty() {
        let _ = writeln!(t, "Parameters of the final model at a bound (lavi-diagnosis.json `parameters_at_bounds`):\n");
        for b in &s.parameters_at_bounds {
            let _ = writeln!(
                t,
                "- `{}` held at {} (unconstrained {}{}): {}.",
                b.parameter,
                sig(b.bound),
                sig(b.unconstrained),
                if b.stderr.is_finite() { format!(" ± {}", sig(b.stderr)) } else { String::new() },
                b.meaning
            );
        }
        let _ = writeln!(t);
    }
    t
}

/// What the torque channel reads (issue 26): the bit's Newton balance against
/// the channel, teacher-forced on every held-out window, as recorded and read late.
pub(super) fn channel_paragraph(s: &Study) -> String {
    let held = &s.channel_balance[1..];
    let range = |k: usize, f: &dyn Fn(&ChannelBalance) -> f64| {
        let v: Vec<f64> = held.iter().map(|b| f(&b[k])).collect();
        (v.iter().cloned().fold(f64::INFINITY, f64::min), v.iter().cloned().fold(f64::NEG_INFINITY, f64::max))
    };
    let Some(i) = s.structures.iter().position(|(_, d)| d.structure.torque_delay_s != 0.0) else {
        return String::new();
    };
    let tau_ms = 1e3 * s.structures[i].1.structure.torque_delay_s;
    let (r_lo, r_hi) = range(1, &|b| b.r_squared);
    let (e_lo, e_hi) = range(1, &|b| b.residual_rms_nm);
    let (r0_lo, r0_hi) = range(0, &|b| b.r_squared);
    let (e0_lo, e0_hi) = range(0, &|b| b.residual_rms_nm);
    let both = s
        .structures
        .iter()
        .find(|(_, d)| d.structure.torque_delay_s != 0.0 && d.structure.damping == Damping::Both)
        .map(|(_, d)| d.free);
    let slip = mean(&(1..s.windows.len()).map(|w| s.measured[w].slip_torque_nm).collect::<Vec<f64>>());
    let top_rad_s = s.measured[0].bit_speed_max_rpm * RPM_TO_RAD_S;
    format!(
        "**What the torque channel reads.** The record's README calls it the torque on bit, the friction torque at the bottom. \
         Tested on the record (rig_lavi::fit::channel_balance): with the calibration window's J, k, c of the torque read {tau_ms:.0} ms \
         later, the bit's Newton balance k Δφ + c (Ω_top − Ω) − J Ω̇ (one constant per window: the twist at its start) draws the \
         torque channel read {tau_ms:.0} ms later with R² {r_lo:.3}-{r_hi:.3} on the held-out windows (residual {e_lo:.3}-{e_hi:.3} N m \
         RMS, against a mean slip torque of {slip:.2} N m); read as recorded, with the baseline's J, k, c, R² {r0_lo:.3}-{r0_hi:.3} \
         (residual {e0_lo:.3}-{e0_hi:.3} N m). So the channel is the contact torque of the bit's equation of motion on a clock \
         {tau_ms:.0} ms late, and nothing the balance lacks lies between it and the contact: {}. An inertia J_s between sensor and \
         contact is the one term the balance cannot see (it would lower the fitted J by J_s; the `sensor_inertia` candidate tries it \
         in free run). The torque the sensor reads and the friction the free run needs are, on this record, one torque.\n\n",
        match both {
            Some(f) => format!(
                "with the damping free on both the twist rate and the bit speed, c = {:.4} ± {:.4} and c_a = {:.4} ± {:.4} N m s/rad \
                 (structure table), a drag outside the contact of {:.2} N m (two standard errors: {:.2} N m) at the calibration \
                 window's mean cycle maximum",
                f.damping_nm_s_rad,
                f.damping_stderr,
                f.absolute_damping_nm_s_rad,
                f.absolute_damping_stderr,
                (f.absolute_damping_nm_s_rad * top_rad_s).abs(),
                ((f.absolute_damping_nm_s_rad.abs() + 2.0 * f.absolute_damping_stderr) * top_rad_s)
            ),
            None => "the damping on both was not fitted".to_string(),
        }
    )
}

/// The friction level of the extended model against the measured one (the two torque features).
pub(super) fn torque_level(s: &Study) -> String {
    let held: Vec<usize> = (1..s.windows.len()).collect();
    let avg = |f: &dyn Fn(usize) -> f64| mean(&held.iter().map(|&i| f(i)).collect::<Vec<f64>>());
    let fr = &s.selection.final_model.friction;
    format!(
        "Friction level (judged on every recorded channel, bit speed and bit torque): the extended model's law has T_s = {:.3} N m, \
         T_k = {:.3} N m; the least-squares law on the measured torque has T_s = {:.3} N m. Held-out means: break-away torque \
         measured {:.3} N m, extended {:.3} N m, baseline {:.3} N m; mean slip torque measured {:.3} N m, extended {:.3} N m, baseline \
         {:.3} N m.\n",
        fr.static_nm,
        fr.kinetic_nm,
        s.baseline.friction.static_nm,
        avg(&|i| s.measured[i].breakaway_torque_nm),
        avg(&|i| s.final_features[i].breakaway_torque_nm),
        avg(&|i| s.baseline_features[i].breakaway_torque_nm),
        avg(&|i| s.measured[i].slip_torque_nm),
        avg(&|i| s.final_features[i].slip_torque_nm),
        avg(&|i| s.baseline_features[i].slip_torque_nm),
    )
}

/// Why the torque features miss: the law the free run needs against the law
/// of the torque as recorded, read on the equation of motion's time base.
pub(super) fn torque_level_hypothesis(s: &Study) -> String {
    let v_rpm = s.measured[0].bit_speed_max_rpm;
    let v = v_rpm * RPM_TO_RAD_S;
    let ext = &s.selection.final_model.friction;
    let Some(i) = s.structures.iter().position(|(_, d)| d.structure.torque_delay_s != 0.0) else {
        return String::new();
    };
    let aligned = &s.structure_laws[i];
    let held: Vec<usize> = (1..s.windows.len()).collect();
    let rel = |f: &dyn Fn(&Features) -> f64| {
        100.0 * mean(&held.iter().map(|&w| f(&s.final_features[w]) / f(&s.measured[w]) - 1.0).collect::<Vec<f64>>())
    };
    let top_delay_s = s.selection.final_model.structure.top_delay_s;
    // The two laws from 0 to the cycle maximum, the delay, and the least-squares law's free run.
    let (e0, ev_, tau_ms, a0, av, free) = (
        ext.slip_nm(0.0),
        ext.slip_nm(v),
        1e3 * s.structures[i].1.structure.torque_delay_s,
        aligned.slip_nm(0.0),
        aligned.slip_nm(v),
        s.structure_heldout[i],
    );
    if top_delay_s != 0.0 && ev_ < e0 {
        return format!(
            "- The torque level (`slip_torque_nm`, `breakaway_torque_nm`): from 0 to {v_rpm:.0} rpm (the calibration window's mean \
             cycle maximum) the extended model's law falls from {:.3} to {:.3} N m, as the torque channel does (the least-squares law \
             of the torque read {:.0} ms later on the top's recorded clock: {:.3} to {:.3} N m, whose free run leaves the held-out \
             misfit at {:.3}, the structure table): with the top speed read {:.0} ms later, the falling law runs free in stick-slip \
             (The top speed's clock, below). The free run's slip torque is {:+.0} % and its break-away torque {:+.0} % of the \
             measured ones (held-out means).",
            e0,
            ev_,
            tau_ms,
            a0,
            av,
            free,
            1e3 * top_delay_s,
            rel(&|f| f.slip_torque_nm),
            rel(&|f| f.breakaway_torque_nm),
        );
    }
    format!(
        "- Leading hypothesis for the torque level (`slip_torque_nm`, `breakaway_torque_nm`): from 0 to {v_rpm:.0} rpm (the \
         calibration window's mean cycle maximum) the extended model's law goes from {:.3} to {:.3} N m, while the least-squares law of \
         the recorded torque read {:.0} ms later goes from {:.3} to {:.3} N m; run free, that falling law takes the bit far from the \
         record (held-out misfit {:.3}, the structure table). The motion is reproduced by a law that falls less (or rises) with speed, \
         so the free run's slip torque is {:+.0} % and its break-away torque {:+.0} % of the measured ones (held-out means). Not in the \
         sensor: the channel reads the contact torque (What the torque channel reads, rung 2). A falling law is unstable under an \
         imposed top speed (its slope beats the damping). The hypothesis that the real top answers the bit as a motor under a \
         speed loop, a feedback the imposed top speed cannot give, is tested by `motor_drive` (The drive that answers the bit, \
         below): {}",
        e0,
        ev_,
        tau_ms,
        a0,
        av,
        free,
        rel(&|f| f.slip_torque_nm),
        rel(&|f| f.breakaway_torque_nm),
        match &s.drive {
            None => "not tried.".to_string(),
            Some(d) => format!(
                "identified on the calibration window (motor inertia {:.4} kg m², unconstrained), run with {}, it leaves the \
                 held-out misfit at {:.3}.",
                d.fit.inertia_kgm2,
                if d.law_from_torque { "the falling law" } else { "the model's own law" },
                crate::select::overall(
                    &s.selection
                        .trials
                        .iter()
                        .find(|t| t.step == d.step && t.candidate == Candidate::MotorDrive)
                        .map_or(Vec::new(), |t| t.heldout.clone())
                ),
            ),
        }
    )
}

/// What the break-away target reads: the torque through the stick phases,
/// recorded and in the free runs (held-out windows pooled), and which
/// step-1 candidates draw its shape.
pub(super) fn stick_torque_finding(s: &Study) -> String {
    let pool = |held: &[&crate::StickTorque]| {
        let n: usize = held.iter().map(|w| w.phases).sum();
        let falling: usize = held.iter().map(|w| w.falling).sum();
        let avg = |f: &dyn Fn(&crate::StickTorque) -> f64| {
            held.iter().filter(|w| w.phases > 0).map(|w| f(w) * w.phases as f64).sum::<f64>() / n.max(1) as f64
        };
        (n, falling, avg(&|x| x.entry_nm), avg(&|x| x.exit_nm), avg(&|x| x.peak_position))
    };
    // A law that does not fall over the calibration window's cycle is the one the motion forced (leading hypothesis).
    let law = &s.selection.final_model.friction;
    let rises = law.slip_nm(s.measured[0].bit_speed_max_rpm * RPM_TO_RAD_S) >= law.slip_nm(0.0);
    let m = pool(&s.stick_torque[1..].iter().map(|w| &w[0]).collect::<Vec<_>>());
    let f = pool(&s.stick_torque[1..].iter().map(|w| &w[1]).collect::<Vec<_>>());
    let each: Vec<String> = s
        .candidate_stick_torque
        .iter()
        .map(|(c, per)| {
            let p = pool(&per.iter().collect::<Vec<_>>());
            format!("`{}` {} of {}", c.id(), p.1, p.0)
        })
        .collect();
    format!(
        "- What `breakaway_torque_nm` reads (rig_lavi::features::stick_torque: the same low-pass and stick speed): in the record \
         the torque falls through a stick phase, from {:.3} N m at its first sample to {:.3} N m at its last ({} of the {} complete \
         phases of the held-out windows end lower; the largest torque sits at {:.2} of a phase's length, 0 its start): the measured \
         break-away level is the torque as the bit arrives in stick, not as it leaves. A bit held by a shaft that the turning top \
         winds up sees its holding torque rise through the stick; a torque channel read late shows, during the stick, the slip \
         torque of the deceleration before it. The extended model's free runs go from {:.3} to {:.3} N m ({} of {} phases end \
         lower, largest torque at {:.2}). Phases ending lower, per step-1 candidate's free runs: {}. The shape follows the \
         channel's delay; the level does not: the torque at the stick's entry is the law's low-speed torque, {:.3} N m in the \
         extended model against {:.3} N m recorded ({:+.0} %){}.",
        m.2,
        m.3,
        m.1,
        m.0,
        m.4,
        f.2,
        f.3,
        f.1,
        f.0,
        f.4,
        each.join(", "),
        f.2,
        m.2,
        100.0 * (f.2 / m.2 - 1.0),
        if rises {
            ", the law's low-speed level the free run's motion does not allow (leading hypothesis above)"
        } else {
            ""
        }
    )
}
