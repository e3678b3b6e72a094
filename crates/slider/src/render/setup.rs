//! The set-up and the channel, read from the measured runs: the inertial
//! periods against T0, the force read as the spring's extension, what the
//! channel resolves, and the static level above the law (slider.md's prose).

use super::*;

/// What the measured inertial periods say about the set-up. An undamped
/// Coulomb cycle lasts T0 (1 − atan(r)/π) + 2r/ω ≥ T0 (r = ω (μs − μk) m g/(k V):
/// a slip from rest, then a stick of 2r/ω; the bound is reached at r = 0);
/// linearised about steady sliding, rate and state adds N a iω/V (damping)
/// and −N b ω² Dc/(V² + ω² Dc²) (a negative stiffness) to the spring
/// (Rice & Ruina 1983's linear analysis, ageing law): no friction law on one
/// mass m and one spring k oscillates faster than 1/T0. A spring's own mass
/// and a compliance in series both slow the oscillation further; only a
/// lighter mass that oscillates or a stiffer spring than stated speed it up.
/// Then the set-up models' fitted parameters, fold by fold (a set-up
/// parameter is one number for every spring: folds that disagree say it is
/// not one).
pub(super) fn inertial_note(s: &Study) -> String {
    let inertial: Vec<&crate::study::Measured> = s
        .runs
        .iter()
        .filter(|r| r.features.regime == Regime::InertialOscillation && r.features.period_s.n > 0)
        .collect();
    let mut out = String::from("## The set-up: what the inertial oscillations say\n\n");
    if inertial.is_empty() {
        out.push_str(
            "No run oscillates in the inertial regime: the records say nothing of the mass that oscillates.\n",
        );
        return out;
    }
    let list: Vec<String> = inertial
        .iter()
        .map(|r| {
            let f = &r.features;
            // (P/T0)² and its standard error from the median's, 1.253 sd/√n.
            let ratio = f.period_s.median / f.natural_period_s;
            let se = 2.0 * ratio * ratio * 1.253 * f.period_s.sd / (f.period_s.n as f64).sqrt() / f.period_s.median;
            format!(
                "{} {:.4} ± {:.4} s = {:.2} T0 (spectrum {:.2} T0), (P/T0)² = {:.3} ± {:.3}",
                r.name,
                f.period_s.median,
                f.period_s.sd,
                ratio,
                r.spectral_period_s / f.natural_period_s,
                ratio * ratio,
                se
            )
        })
        .collect();
    // The spectrum against the turning points: whether the short period is the
    // oscillation's or the feature's reading of a short, noisy record (within
    // 5 %: one oscillation, read alike both ways).
    let diff = |r: &crate::study::Measured| r.spectral_period_s / r.features.period_s.median - 1.0;
    let (agree, apart): (Vec<&crate::study::Measured>, Vec<&crate::study::Measured>) =
        inertial.iter().partition(|r| diff(r).abs() <= 0.05);
    let mut spectral = String::new();
    if !agree.is_empty() {
        let names: Vec<String> = agree.iter().map(|r| format!("{} ({:+.0} %)", r.name, 100.0 * diff(r))).collect();
        let _ = write!(
            spectral,
            " The spectrum reads the period without the turning points (the largest line of the filtered force between \
             half and twice 1/T0, the mains line at {} Hz skipped) and agrees with their median within 5 % at {}: the short period is the oscillation's, \
             not the feature's reading of a short, noisy record.",
            s.params.mains_hz,
            names.join(", ")
        );
    }
    for r in &apart {
        let f = &r.features;
        let _ = write!(
            spectral,
            " At {} the spectrum's line is at {:.2} T0 and the turning points' median at {:.2} T0 (sd {:.0} % of the \
             median): its cycles spread, and the median is no one oscillation's period, so a ±15 % check on it is a \
             check on a mixture of cycles.",
            r.name,
            r.spectral_period_s / f.natural_period_s,
            f.period_s.median / f.natural_period_s,
            100.0 * f.period_s.sd / f.period_s.median
        );
    }
    let _ = writeln!(
        out,
        "Measured inertial periods (median ± sd over cycles; (P/T0)² ± the standard error of the median) against \
         T0 = 2π√(m/k) with the README's m = {} kg and the file names' k: {}. An undamped Coulomb cycle lasts T0 (1 − atan(r)/π) + 2r/ω ≥ T0 (a slip from rest, \
         r = ω(μs − μk) m g/(k V), then a stick of 2r/ω), and linearised about steady sliding rate and state adds damping \
         (N a iω/V) and a negative stiffness (−N b ω² Dc/(V² + ω² Dc²); Rice & Ruina 1983, ageing law) to the spring: no \
         friction law on one mass m and one spring k oscillates faster than 1/T0. A spring's own mass (m + m_s/3, \
         Rayleigh) and a compliance in series (1/k + 1/k_s) both make it slower still. What is left is a lighter mass that \
         oscillates or springs stiffer than stated, by (P/T0)², the same factor at stiffnesses 13 × apart — a set-up \
         number, not a friction one — which the period alone cannot tell apart (nor, when the force is read from the \
         spring's extension, the force's rise in stick: below).{}\n",
        s.params.mass_kg,
        list.join(", "),
        spectral
    );
    // Whether the stiffnesses can tell their (P/T0)² apart: the fastest
    // inertial run of each (the nearest the limit r → 0, where a cycle lasts
    // the natural period: at lower V a stick phase lengthens it), the
    // extremes against twice their combined standard error.
    let r2: Vec<(f64, f64, &str)> = inertial
        .iter()
        .filter(|r| {
            !inertial.iter().any(|q| q.stiffness_n_m == r.stiffness_n_m && q.drive_speed_um_s > r.drive_speed_um_s)
        })
        .map(|r| {
            let f = &r.features;
            let ratio = f.period_s.median / f.natural_period_s;
            let se = 2.0 * ratio * ratio * 1.253 * f.period_s.sd / (f.period_s.n as f64).sqrt() / f.period_s.median;
            (ratio * ratio, se, r.name.as_str())
        })
        .collect();
    let lo = r2.iter().min_by(|a, b| a.0.total_cmp(&b.0)).expect("an inertial run");
    let hi = r2.iter().max_by(|a, b| a.0.total_cmp(&b.0)).expect("an inertial run");
    if r2.len() > 1 {
        let z = (hi.0 - lo.0) / (lo.1 * lo.1 + hi.1 * hi.1).sqrt();
        let _ = writeln!(
            out,
            "Fastest inertial run of each stiffness (the nearest the limit where a cycle lasts the natural period; at lower V a \
             stick phase lengthens it): the extremes, {} ({:.3}) and {} ({:.3}), differ by {:.1} combined standard errors: {}.\n",
            lo.2,
            lo.0,
            hi.2,
            hi.0,
            z,
            if z > 2.0 {
                "resolved within these runs, so one set-up number does not hold for every spring (or the friction shifts these periods)"
            } else {
                "not resolved, so one set-up number for every spring is what the data allow"
            }
        );
    }
    // The drive: a ripple of the stage at the screw's pitch (V/pitch) or any
    // line of the drive is one frequency at one V whatever the spring; the
    // mass on its spring oscillates at a frequency ∝ √k. Inertial runs at one
    // V on two springs tell them apart (the spectrum's reading).
    let pairs: Vec<String> = inertial
        .iter()
        .flat_map(|a| inertial.iter().map(move |b| (a, b)))
        .filter(|(a, b)| a.drive_speed_um_s == b.drive_speed_um_s && a.stiffness_n_m < b.stiffness_n_m)
        .filter(|(a, b)| a.spectral_period_s.is_finite() && b.spectral_period_s.is_finite())
        .map(|(a, b)| {
            format!(
                "at {} µm/s, {:.1} Hz at {} N/m and {:.1} Hz at {} N/m, a ratio of {:.2} against √(k ratio) = {:.2}",
                a.drive_speed_um_s,
                1.0 / a.spectral_period_s,
                a.stiffness_n_m,
                1.0 / b.spectral_period_s,
                b.stiffness_n_m,
                a.spectral_period_s / b.spectral_period_s,
                (b.stiffness_n_m / a.stiffness_n_m).sqrt()
            )
        })
        .collect();
    if !pairs.is_empty() {
        let _ = writeln!(
            out,
            "The drive (the README names neither motor, screw nor stage, and the drive speed is not recorded): a speed ripple \
             of the stage (at V/pitch of a screw) or any line of the drive has one frequency at one V whatever the spring, \
             and a drive compliance in series slows the oscillation (above). The spectrum's inertial lines: {}. The spring \
             sets them, not the drive.\n",
            pairs.join("; ")
        );
    }
    // The loading rate where the slider rests (stick-slip runs) and what
    // the channel reads: a spring r times stiffer read by a load cell
    // (r k (V t − x)) raises it to r L; read through its extension and the
    // stated k it stays at L, and a lighter mass leaves it at L.
    let stick_runs: Vec<&crate::study::Measured> =
        s.runs.iter().filter(|r| r.features.regime == Regime::StickSlip && r.features.load_rate.n > 0).collect();
    if !stick_runs.is_empty() {
        let want = 1.0 / (lo.0 + hi.0) * 2.0;
        let resting: Vec<String> = stick_runs
            .iter()
            .map(|r| format!("{} {:.3} ± {:.3} L", r.name, r.features.load_rate.median, r.features.load_rate.sd))
            .collect();
        // Standard errors of the median by which r L sits above each run's.
        let z_scale: Vec<String> = stick_runs
            .iter()
            .map(|r| {
                let l = &r.features.load_rate;
                let se = 1.253 * l.sd / (l.n as f64).sqrt();
                format!("{:.1} ({})", (want - l.median) / se, r.name)
            })
            .collect();
        let _ = writeln!(
            out,
            "The force's rise where the slider rests (stick-slip runs; median ± sd over loading phases, in units of \
             L = k V/(m g)): {}; the inertial periods alone would want springs r ≈ {want:.2} times the stated ones \
             (1/(P/T0)², fastest runs) or a mass 1/r of the weighed one.\n",
            resting.join(", "),
        );
        let weight_n = s.params.mass_kg * s.params.gravity_m_s2;
        match extension_reading(s) {
            Some(grid) => {
                let _ = writeln!(
                    out,
                    "What the channel reads: {grid}. A load cell would put every spring's force on one grid in F/(m g); \
                     this grid is one length of spring extension ({:.2} µm) whatever the spring, so the force is the \
                     spring's extension read through the stated k. Read so, the force rises at V k/(m g) = 1 L wherever the \
                     slider rests, whatever the spring's true stiffness, and a spring r times stiffer than stated obeys \
                     m ẍ = r k (V t − x) − m g μ while recording k (V t − x)/(m g): divided by r, the equation of a mass \
                     m/r under the law's coefficients over r. A lighter mass and stiffer springs are one candidate \
                     (`effective_mass`), and the resting load rate cannot tell them apart; it refutes only a spring \
                     read as r k (V t − x) (a load cell's reading: {want:.2} L would sit {} standard errors of the \
                     median above the measured rises), which is not tried.\n",
                    1e6 * Spread::of(
                        &s.runs.iter().map(|r| r.force_step * weight_n / r.stiffness_n_m).collect::<Vec<_>>()
                    )
                    .median,
                    z_scale.join(", "),
                );
            }
            None => {
                let _ = writeln!(
                    out,
                    "A spring as mounted r times the stated one, its force read by a load cell, raises the rise to r L \
                     ({want:.2} L would sit {} standard errors of the median above the measured ones); a lighter mass \
                     leaves it at L, and so does a stiffer spring read through its extension and the stated k.\n",
                    z_scale.join(", "),
                );
            }
        }
        // Which of the set-up's elements the numbers leave: a contact
        // stiffness in parallel with the spring (k_p = k (T0²/P² − 1), one
        // number only if it comes out the same at every spring), the ratio
        // m/k the oscillation sees ((P/T0)², the same factor).
        let parallel: Vec<String> = r2
            .iter()
            .filter_map(|(ratio2, _, name)| {
                let r = s.runs.iter().find(|r| r.name == *name)?;
                Some(format!("{:.0} N/m at k = {} N/m", r.stiffness_n_m * (1.0 / ratio2 - 1.0), r.stiffness_n_m))
            })
            .collect();
        let mean_r2 = r2.iter().map(|x| x.0).sum::<f64>() / r2.len() as f64;
        let _ = writeln!(
            out,
            "Which element, by the numbers: a contact stiffness in parallel with the spring (the pinned micro-contacts' \
             elasticity acting on the slider beside the spring) would need {} — not one interface; a \
             velocity-strengthening term or the state's relaxation adds damping or a negative stiffness (above), so the \
             law's stiffness at high speed shortens nothing. What is left is the ratio m/k the oscillation sees, {:.2} of \
             the stated (the mean (P/T0)² of the fastest runs): a mass of {:.1} g oscillating, or springs {:.2} × stiffer \
             than stated — one number for both springs, an element the README's set-up (slider, spring, drive) does not \
             state (a spring's own mass adds to m), so it stays a set-up finding for the data's authors.\n",
            parallel.join(" and "),
            mean_r2,
            1e3 * mean_r2 * s.params.mass_kg,
            1.0 / mean_r2
        );
    }
    for c in s.candidates.iter().filter(|c| c.model.setup != SetupCandidate::Stated) {
        let n = c.model.friction.params().len();
        let specs = c.model.setup.params();
        let per_fold: Vec<String> = c
            .fold_fits
            .iter()
            .map(|f| {
                let ks = distinct(f.train.iter().map(|&i| s.runs[i].stiffness_n_m));
                format!("{:.3} fitted on k = {:?} N/m", f.params[n], ks)
            })
            .collect();
        let all = c.fitted.as_ref().map_or(String::new(), |f| format!("{:.3} on all calibration runs; ", f.params[n]));
        let _ = writeln!(
            out,
            "- {}: {} = {}{}{}.",
            c.model.id(),
            specs[0].name,
            all,
            per_fold.join(", "),
            if at_bounds(c).contains(&specs[0].name) { " (at its bound in a fit)" } else { "" }
        );
    }
    out
}

/// Whether the channel reads the spring's extension rather than its force:
/// with two stiffnesses or more, the grid (`features::channel_step`) of each
/// stiffness (the median over its runs) spans a range in µm of extension
/// (step × m g/k) at most a quarter of its range in F/(m g), on the log
/// scale (a load cell's grid is one force step whatever the spring; a
/// displacement gauge's one length). Some(the grids, as text) when it does.
pub(super) fn extension_reading(s: &Study) -> Option<String> {
    let weight_n = s.params.mass_kg * s.params.gravity_m_s2;
    let ks = distinct(s.runs.iter().map(|r| r.stiffness_n_m));
    if ks.len() < 2 {
        return None;
    }
    let grids: Vec<(f64, f64, f64)> = ks
        .iter()
        .map(|&k| {
            let steps: Vec<f64> = s.runs.iter().filter(|r| r.stiffness_n_m == k).map(|r| r.force_step).collect();
            let step = Spread::of(&steps).median;
            (k, step, step * weight_n / k)
        })
        .collect();
    let span = |v: &mut dyn Iterator<Item = f64>| {
        let (lo, hi) = v.fold((f64::INFINITY, 0.0f64), |(a, b), x| (a.min(x), b.max(x)));
        (hi / lo).ln()
    };
    let force_span = span(&mut grids.iter().map(|g| g.1));
    let extension_span = span(&mut grids.iter().map(|g| g.2));
    (force_span.is_finite() && extension_span <= 0.25 * force_span).then(|| {
        let list: Vec<String> =
            grids.iter().map(|(k, f, x)| format!("{f:.5} F/(m g) = {:.2} µm at {k} N/m", 1e6 * x)).collect();
        format!("the force's grid is {}", list.join(", "))
    })
}

/// What the records can show: each run's grid (the channel's step, in
/// F/(m g) and in µm of spring extension), noise and hysteresis (the
/// smallest slip that is an event), and for each creeping run whether the
/// Coulomb fit that did not see its spring would show its slips there
/// through the run's own channel ([`crate::study::through_channel`]).
pub(super) fn channel_note(s: &Study) -> String {
    let weight_n = s.params.mass_kg * s.params.gravity_m_s2;
    let mut out = String::from(
        "## What the channel resolves

",
    );
    let list: Vec<String> = s
        .runs
        .iter()
        .map(|r| {
            let f = &r.features;
            let um = |x: f64| 1e6 * x * weight_n / r.stiffness_n_m;
            // A robust deviation of 0: most samples sit on their running median's step.
            let noise = if f.noise_sd > 0.0 {
                format!("noise sd {:.4} ({:.1} steps)", f.noise_sd, f.noise_sd / r.force_step)
            } else {
                "noise below one step (most samples on their running median)".to_string()
            };
            format!(
                "{} step {:.5} ({:.2} µm), {noise}, hysteresis {:.4} ({:.1} steps, a slip of {:.1} µm)",
                r.name,
                r.force_step,
                um(r.force_step),
                f.hysteresis,
                f.hysteresis / r.force_step,
                um(f.hysteresis)
            )
        })
        .collect();
    let _ = writeln!(
        out,
        "The force is digitised: its values sit on a grid (`rig_slider::features::channel_step`, the median spacing of a \
         record's distinct values), about one micrometre of spring extension at every spring, so the step in F/(m g) \
         grows with k. The turning points' hysteresis is the larger of `min_drop` and `noise_multiple` robust noise \
         deviations: a slip smaller than it is no event, and a run that slips only by less reads as creep or steady \
         sliding. Per run: {}.\n",
        list.join("; ")
    );
    for c in &s.channel_checks {
        let r = &s.runs[c.run];
        let m = &r.features;
        let read = |f: &Features| {
            format!(
                "{} ({} events, period {:.3} s, drop {:.4}, stick fraction {:.2}, load rate {:.2} L)",
                f.regime.label(),
                f.events,
                f.period_s.median,
                f.drop.median,
                f.stick_fraction.median,
                f.load_rate.median
            )
        };
        let verdict = if c.channel.regime == c.clean.regime {
            format!(
                "the channel resolves its slips ({:.1} steps, {:.1} µm, against a hysteresis of {:.1} steps), so the \
                 record's {} (load rate {:.2} L) is not this stick-slip lost in the noise",
                c.clean.drop.median / r.force_step,
                1e6 * c.clean.drop.median * weight_n / r.stiffness_n_m,
                m.hysteresis / r.force_step,
                m.regime.label(),
                m.load_rate.median
            )
        } else {
            format!(
                "the channel loses its slips ({:.1} steps against a hysteresis of {:.1} steps): at this run the record \
                 cannot tell them from its {}",
                c.clean.drop.median / r.force_step,
                m.hysteresis / r.force_step,
                m.regime.label()
            )
        };
        let _ = writeln!(
            out,
            "- {}: {} with {} fitted on the other runs reads {} noiseless; its first {:.0} s rounded onto the run's grid \
             with the record's own noise added (`rig_slider::study::through_channel`) read {}: {}.",
            r.name,
            c.model.id(),
            c.model
                .params()
                .iter()
                .zip(&c.params)
                .map(|(p, v)| format!("{}={:.4}", p.name, v))
                .collect::<Vec<_>>()
                .join(" "),
            read(&c.clean),
            c.seconds,
            read(&c.channel),
            verdict
        );
    }
    out
}

/// The friction level against V and k, run by run, from the one feature
/// function ([`crate::level`]): whether a law of the speed, of the spring,
/// or neither can carry it, and what a velocity-strengthening kinetic term
/// fitted by the study (`static_ageing`'s α) makes of it.
pub(super) fn level_note(s: &Study) -> String {
    use crate::level::LevelCause;
    let lv = &s.level;
    let mut out = String::from("## The friction level against the drive speed and the stiffness\n\n");
    out.push_str(
        "Per run, from the one feature function: the mean force over the record, its mean over each of the record's \
         parts (median ± sd over the parts: how far the level wanders along the paper within the run), the force at slip \
         onset and where a slip ends (median ± sd over slip events), all in F/(m g).\n\n",
    );
    out.push_str("| run | k [N/m] | V [µm/s] | regime | mean force | over the parts | onset | slip end |\n|---|---|---|---|---|---|---|---|\n");
    let pm = |x: &Spread| format!("{:.3} ± {:.3}", x.median, x.sd);
    for r in &s.runs {
        let f = &r.features;
        let _ = writeln!(
            out,
            "| {} | {} | {} | {} | {:.3} | {} | {} | {} |",
            r.name,
            r.stiffness_n_m,
            r.drive_speed_um_s,
            f.regime.label(),
            f.mean_force,
            pm(&f.level_parts),
            pm(&f.onset),
            pm(&f.trough)
        );
    }
    let list = |a: &crate::level::Across| {
        let v: Vec<String> =
            a.runs.iter().map(|&i| format!("{} {:.3}", s.runs[i].name, s.runs[i].features.mean_force)).collect();
        format!("{} (apart by {:.3})", v.join(", "), a.range)
    };
    let speeds: Vec<String> = lv.at_speed.iter().map(|a| format!("at {} µm/s {}", a.at, list(a))).collect();
    let springs: Vec<String> = lv.at_stiffness.iter().map(|a| format!("at {} N/m {}", a.at, list(a))).collect();
    let _ = writeln!(
        out,
        "\nThe yardstick is twice the largest sd of a run's level over its parts: {:.3}. Across the springs at one drive \
         speed: {}. Across the speeds at one spring: {}.\n",
        lv.yardstick,
        if speeds.is_empty() { "no speed has two springs".to_string() } else { speeds.join("; ") },
        if springs.is_empty() { "no spring has two speeds".to_string() } else { springs.join("; ") },
    );
    let worst = |a: &[crate::level::Across]| a.iter().max_by(|x, y| x.range.total_cmp(&y.range)).cloned();
    let verdict = match lv.cause {
        LevelCause::Untested => "No speed was run at two springs and a spring at two speeds: the records cannot say \
            what the level depends on."
            .to_string(),
        LevelCause::Constant => {
            "One level everywhere, within the yardstick: nothing for a law of the speed to carry.".into()
        }
        LevelCause::Speed => {
            "The level is one at every speed across the springs and differs across the speeds: a law of \
            the speed can carry it (a candidate for the selection, fitted on the calibration stiffnesses)."
                .into()
        }
        LevelCause::Stiffness => {
            "The level is one at every spring across the speeds and differs across the springs: not a \
            friction law of the speed; a set-up number of the spring (or another strip of paper per spring)."
                .into()
        }
        LevelCause::Neither => {
            let (a, b) = (worst(&lv.at_speed).expect("tested"), worst(&lv.at_stiffness).expect("tested"));
            format!(
                "Neither a law of the speed nor one of the spring: at {} µm/s the springs differ by {:.3} ({:.1} \
                 yardsticks), at {} N/m the speeds by {:.3} ({:.1} yardsticks). A steady drive moves the slider at V on \
                 average, so a law of the sliding speed — the velocity-strengthening steady state of paper on paper at \
                 high V (Heslot, Baumberger, Perrin, Caroli & Caroli, Phys. Rev. E 49, 4973 (1994); its generality: \
                 Bar-Sinai, Spatschek, Brener & Bouchbinder, J. Geophys. Res. Solid Earth 119, 1738 (2014)) — gives one \
                 level per V at both springs, and a law of the spring one level per k at every V. With one run per \
                 (k, V), a level that depends on both at one cell cannot be told from another strip of paper: the data \
                 cannot tell, so no law of the speed is offered to the selection.",
                a.at,
                a.range,
                a.range / lv.yardstick,
                b.at,
                b.range,
                b.range / lv.yardstick
            )
        }
    };
    let _ = writeln!(out, "{verdict}");
    // The velocity-strengthening kinetic term the study did fit: static ageing's α ln(1 + v/v1).
    let vs = distinct(s.runs.iter().map(|r| r.drive_speed_um_s));
    let (v_lo, v_hi) = (vs[0], vs[vs.len() - 1]);
    let at = |v_um_s: f64| (1.0 + 1e-6 * v_um_s / crate::fit::V1_M_S).ln();
    let fits: Vec<(Vec<f64>, f64, f64)> = s
        .candidates
        .iter()
        .filter(|c| c.model.friction == Candidate::StaticAgeing && c.model.setup == SetupCandidate::Stated)
        .flat_map(|c| c.fold_fits.iter())
        .map(|f| {
            let ks = distinct(f.train.iter().map(|&i| s.runs[i].stiffness_n_m));
            (ks, f.params[4], f.params[4] * (at(v_hi) - at(v_lo)))
        })
        .collect();
    let largest = lv.at_speed.iter().chain(&lv.at_stiffness).map(|a| a.range).fold(0.0, f64::max);
    if !fits.is_empty() && largest > 0.0 {
        let each: Vec<String> = fits
            .iter()
            .map(|(ks, alpha, rise)| format!("α = {alpha:.1e} fitted on k = {ks:?} N/m, a rise of {rise:.4}"))
            .collect();
        let most = fits.iter().map(|f| f.2).fold(0.0, f64::max);
        let _ = writeln!(
            out,
            "\nThe study's one velocity-strengthening kinetic term, `static_ageing`'s μk(v) = μk0 + α ln(1 + v/v1), \
             fitted with every run of its springs, the fastest included, raises the kinetic level from {v_lo} to {v_hi} \
             µm/s by: {}; at most {:.0} % of the largest difference above ({largest:.3}).",
            each.join("; "),
            100.0 * most / largest
        );
    }
    out
}
