//! The slider study end to end: a round trip (simulate a known law, recover
//! it), the study on the shipped folder and the "unseen stiffness" check
//! (calibrate on one stiffness, predict the other). The last two read
//! ../shared and are skipped with a message when it is absent.

use rig_slider::fit::{Candidate, FitTolerance, Model, SetupCandidate, dispersion, fit, repeats, run_misfit};
use rig_slider::study::{Measured, predict};
use rig_slider::{Regime, StudyParams, render, run_study};
use std::path::{Path, PathBuf};

fn params() -> StudyParams {
    // The values of pipeline.toml's `slider` stanza.
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../pipeline.toml")).unwrap();
    StudyParams::from_pipeline_toml(&text).unwrap()
}

fn shipped() -> Option<PathBuf> {
    let d = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../../shared/data/ens-lyon-slider-2019");
    if d.join("runs").is_dir() {
        Some(d)
    } else {
        eprintln!("skipped: {} absent", d.display());
        None
    }
}

/// pipeline.toml's settings and the shipped runs measured with them.
fn shipped_runs() -> Option<(StudyParams, Vec<Measured>)> {
    let dir = shipped()?;
    let p = params();
    let raw = rig_ingest::slider::read_slider_folder(&dir).unwrap();
    let runs = raw.iter().map(|r| rig_slider::study::measure(r, &p)).collect();
    Some((p, runs))
}

fn synthetic(k: f64, v_um_s: f64, duration_s: f64, f: rig_slider::Features) -> Measured {
    Measured {
        name: format!("k{k}-v{v_um_s}"),
        stiffness_n_m: k,
        drive_speed_um_s: v_um_s,
        duration_s,
        sample_rate_hz: 2000.0,
        features: f,
        spectral_period_s: f64::NAN,
        force_step: f64::NAN,
    }
}

#[test]
fn round_trip_recovers_a_coulomb_law() {
    let p = params();
    let truth = [0.40, 0.05]; // μs, μs − μk
    let mut runs = Vec::new();
    for (k, v) in [(168.0, 42.0), (168.0, 1100.0), (2254.0, 42.0)] {
        let probe = synthetic(k, v, 30.0, rig_slider::Features::default_steady());
        // Measure the truth through the study's own simulation and feature function, at a window of 20 s.
        let mut q = p.clone();
        q.sim_min_window_s = 20.0;
        let f = predict(Model::BASELINE, &truth, &probe, &q);
        assert_eq!(f.regime, Regime::StickSlip, "{k} {v}: {f:?}");
        runs.push(synthetic(k, v, 30.0, f));
    }
    let cost = |x: &[f64]| {
        runs.iter().map(|r| run_misfit(&r.features, &predict(Model::BASELINE, x, r, &p))).sum::<f64>() / 3.0
    };
    // To convergence (pipeline.toml ships the fixed count: this is the criterion's round trip).
    let tol = FitTolerance { tolerance: 0.01, max_evals: 2000 };
    let r = fit(&Model::BASELINE.params(), &[0.35, 0.03], &tol, cost);
    assert!(r.converged, "{r:?}");
    let (x, c) = (r.x, r.cost);
    assert!((x[0] - truth[0]).abs() < 0.01, "mu_static {} (truth {})", x[0], truth[0]);
    assert!((x[1] / truth[1] - 1.0).abs() < 0.1, "mu_drop {} (truth {})", x[1], truth[1]);
    assert!(c < 0.1, "misfit at the recovered law {c}");
}

/// The report's roughness is the `landscape` scan one step each way: its
/// centre the mean of each run's `run_misfit` of `predict`, its largest
/// move the largest |M(±1) − M(0)| over every axis (Coulomb at its fit on
/// both shipped stiffnesses, rounded: cheap to simulate).
#[test]
fn the_roughness_is_the_landscape_one_step_each_way() {
    use rig_slider::study::{landscape, roughness};
    let Some((p, runs)) = shipped_runs() else { return };
    let cal: Vec<&Measured> =
        runs.iter().filter(|r| p.calibration_stiffnesses_n_m.contains(&r.stiffness_n_m)).collect();
    assert_eq!(cal.len(), 6);
    let model = Model::BASELINE;
    let x = [0.3595, 0.0209];
    let by_hand = cal.iter().map(|r| run_misfit(&r.features, &predict(model, &x, r, &p))).sum::<f64>() / 6.0;
    let r = roughness(model, &x, &cal, &p);
    assert_eq!(r.misfit, by_hand);
    let mut largest = (0.0, "");
    for axis in 0..x.len() {
        let l = landscape(model, &x, axis, p.roughness_rel_step, 1, &cal, &p);
        assert_eq!((l.len(), l[1].step, l[1].misfit), (3, 0, r.misfit));
        for k in [0, 2] {
            let d = (l[k].misfit - l[1].misfit).abs();
            if d > largest.0 {
                largest = (d, model.params()[axis].name);
            }
        }
    }
    assert_eq!((r.max_change, r.axis), largest);
    assert!(r.max_change > 0.0, "the misfit moves at all: {r:?}");
}

#[test]
fn study_on_the_shipped_folder() {
    let Some(dir) = shipped() else { return };
    let p = params();
    let s = run_study(&dir, &p).unwrap();
    assert_eq!(s.runs.len(), 6);
    assert!(s.leave_one_out, "the default list holds both shipped stiffnesses");
    let regimes: Vec<Regime> = s.runs.iter().map(|r| r.features.regime).collect();
    // k168: 42, 1100, 4300 µm/s; k2254: the same.
    assert_eq!(
        regimes,
        [
            Regime::StickSlip,
            Regime::StickSlip,
            Regime::InertialOscillation,
            Regime::Creep,
            Regime::InertialOscillation,
            Regime::InertialOscillation
        ]
    );
    // Every feature carries its spread over many events.
    assert!(s.runs.iter().all(|r| r.features.events >= 50 && r.features.drop.sd > 0.0));
    // The forward selection starts from Coulomb on the stated set-up and tries every memory law and every set-up.
    assert_eq!(s.candidates[0].model, Model::BASELINE);
    let first: Vec<Model> = s.steps[0].tried.iter().map(|&i| s.candidates[i].model).collect();
    assert_eq!(first.len(), 7, "{first:?}");
    let out = render(&s);
    let verdict = out.diagnosis["verdict"].as_str().unwrap();
    let ids = [
        "none",
        "unexplained",
        "static_ageing",
        "rate_state_ageing",
        "rate_state_slip",
        "heslot_creep",
        "track_threshold",
        "effective_mass",
        "series_compliance",
    ];
    assert!(ids.contains(&verdict), "{verdict}");
    assert_eq!(out.diagnosis["candidates"].as_array().unwrap().len(), s.candidates.len() - 1);
    assert!(out.markdown.contains("leave one stiffness out"));
    // The set-up as a set-up: the effective mass fitted on either stiffness
    // alone agrees within 15 % (one number for every spring, not one per
    // spring), below the README's m (a lighter mass oscillates, or stiffer
    // springs: the period cannot tell); a compliance in series can only
    // slow the oscillation, and its fit goes rigid (k_s ≫ both springs).
    let setup_fits = |setup: SetupCandidate| -> Vec<f64> {
        let c = s.candidates.iter().find(|c| c.model == Model { friction: Candidate::Coulomb, setup }).unwrap();
        c.fold_fits.iter().map(|f| f.params[2]).collect()
    };
    let r = setup_fits(SetupCandidate::EffectiveMass);
    assert!(r.iter().all(|&r| r < 0.8) && (r[0] / r[1]).ln().abs() < 1.15f64.ln(), "mass ratios {r:?}");
    assert!(setup_fits(SetupCandidate::SeriesCompliance).iter().all(|&k| k > 2e4), "series stiffnesses");
    // The misfit's roughness is read at the baseline's and every step's
    // best fit on all calibration runs, its centre the fit's own misfit
    // (the same simulations), and every step's gain is set against it.
    for st in &s.steps {
        for i in [st.from, st.best] {
            let c = &s.candidates[i];
            let r = c.roughness.as_ref().unwrap_or_else(|| panic!("{} scanned", c.model.id()));
            assert_eq!(r.misfit, c.fitted.as_ref().unwrap().calibration_misfit, "{}", c.model.id());
            assert!(r.max_change >= r.mean_change && r.mean_change >= 0.0, "{r:?}");
        }
    }
    // Each step's gain among neighbouring fold fits is recomputed from the
    // same held-out misfits: unmoved, the engine's `compare` gives the step's own gain.
    for st in &s.steps {
        let (from, best) = (&s.candidates[st.from], &s.candidates[st.best]);
        let fold_of: Vec<usize> =
            from.heldout.iter().map(|h| s.folds.iter().position(|f| f.held_out.contains(&h.0)).unwrap()).collect();
        let before: Vec<f64> = from.heldout.iter().map(|h| h.1).collect();
        let after: Vec<f64> = best.heldout.iter().map(|h| h.1).collect();
        let c = rig_types::select::compare(&before, &after, &fold_of, s.folds.len());
        assert!((c.gain - st.gain.gain).abs() < 1e-12 && (c.t - st.gain.t).abs() < 1e-9, "{c:?} {:?}", st.gain);
        let g = st.gain_spread.as_ref().unwrap();
        let fits = best.fold_fits.len() * best.model.params().len() * 2;
        // A noisy best's neighbours are the fixed moves its local means average.
        assert_eq!(g.neighbours, if g.over_moves { p.local_moves } else { fits }, "{g:?}");
        assert_eq!(g.over_moves, best.fold_fits.iter().any(|f| f.noisy));
        assert!(g.gain_min <= g.gain_max && g.t_min <= g.t_max && g.admitted <= g.neighbours, "{g:?}");
    }
    // Which fits are noisy (the lead's decision, issue 26): every fit read
    // over the fixed moves on its own training runs, its point the fit's own
    // misfit (the same simulations); noisy exactly when the sd exceeds
    // `noisy_sd`. Coulomb's fold fit on 168 N/m is smooth (sd 0.0005; on
    // all six runs 0.00014, h/slider11; on 2254 N/m alone 0.0019, noisy by
    // the rule) and the track law's fits noisy (0.008–0.037): the rule can
    // say either. A noisy fit's held-out misfit is its run's local mean, the
    // same as `local_misfit` on that run alone; a smooth fit's its point.
    for c in &s.candidates {
        // The report's fits on all six runs are not the selection's (leave one stiffness out): not read.
        assert!(c.fitted.as_ref().is_none_or(|f| f.local.is_none()), "{}", c.model.id());
        for f in &c.fold_fits {
            let l = f.local.as_ref().expect("every fit the selection reads read for noise");
            assert_eq!(l.at.to_bits(), f.calibration_misfit.to_bits(), "{}", c.model.id());
            assert_eq!(f.noisy, l.sd > p.noisy_sd, "{} {l:?}", c.model.id());
        }
        for (h, l) in c.heldout.iter().zip(&c.heldout_local) {
            let fold = s.folds.iter().find(|fo| fo.held_out.contains(&h.0)).unwrap();
            let fit = c.fold_fits.iter().find(|f| f.train == fold.train).unwrap();
            assert_eq!(l.is_some(), fit.noisy, "{} {}", c.model.id(), h.0);
            if let Some(l) = l {
                assert_eq!(h.1.to_bits(), l.mean.to_bits());
                let again = rig_slider::study::local_misfit(
                    c.model,
                    &fit.params,
                    &[&s.runs[h.0]],
                    &p,
                    p.local_moves,
                    p.local_rel_step,
                );
                assert_eq!(again.mean.to_bits(), l.mean.to_bits(), "{} {}", c.model.id(), h.0);
            }
        }
    }
    let on_168 = |f: &&rig_slider::study::Fitted| f.train.iter().all(|&i| s.runs[i].stiffness_n_m == 168.0);
    assert!(s.candidates[0].fold_fits.iter().filter(on_168).all(|f| !f.noisy), "Coulomb on 168 N/m smooth");
    let track = s.candidates.iter().find(|c| c.model.id() == "track_threshold").unwrap();
    assert!(track.fold_fits.iter().all(|f| f.noisy), "the track law noisy");
    let res = out.diagnosis["misfit_resolution"].as_array().unwrap();
    assert_eq!(res.len(), s.steps.len());
    assert!(res.iter().all(|r| r["resolution"].as_f64().is_some()), "{res:?}");
    for st in &s.steps {
        eprintln!(
            "step from {}: best {} {:.3} (gain {:.3}, t {:.2}) kept {}",
            s.candidates[st.from].model.id(),
            s.candidates[st.best].model.id(),
            s.candidates[st.best].heldout_mean,
            st.gain.gain,
            st.gain.t,
            st.kept
        );
    }
}

#[test]
fn each_shipped_stiffness_held_out() {
    // The Done-when at a stiffness not seen: calibrate on one shipped
    // stiffness (the pipeline's list set to it), select and fit there,
    // predict every run of the other, check the bounds (regime;
    // inertial period ±15 %; stick-slip period and drop ×2; onset ±0.05).
    let Some(dir) = shipped() else { return };
    let mut passed = Vec::new();
    let mut failed = Vec::new();
    for (cal, other) in [(168.0, 2254.0), (2254.0, 168.0)] {
        let mut p = params();
        p.calibration_stiffnesses_n_m = vec![cal];
        let s = run_study(&dir, &p).unwrap();
        assert!(!s.leave_one_out);
        for st in &s.steps {
            eprintln!(
                "calibrated on {cal}: step {} from {}: best {} (RMS {:.3} -> {:.3}, gain {:.3}, t {:.2}) kept {}",
                st.step,
                s.candidates[st.from].model.id(),
                s.candidates[st.best].model.id(),
                st.gain.before,
                st.gain.after,
                st.gain.gain,
                st.gain.t,
                st.kept
            );
            for (&t, g) in st.tried.iter().zip(&st.compared) {
                eprintln!(
                    "calibrated on {cal}:   tried {} (gain {:.3}, t {:.2})",
                    s.candidates[t].model.id(),
                    g.gain,
                    g.t
                );
            }
        }
        let fin = &s.candidates[s.chosen.unwrap_or(0)];
        let held: Vec<f64> = fin.heldout.iter().map(|h| s.runs[h.0].stiffness_n_m).collect();
        assert_eq!(held, [other; 3], "every run at {other} N/m is held out");
        for (i, m, f) in &fin.heldout {
            let b = rig_slider::render::bounds(&s.runs[*i].features, f);
            eprintln!("calibrated on {cal}: {} {} misfit {m:.2}: {b:?}", fin.model.id(), s.runs[*i].name);
            let name = &s.runs[*i].name;
            let mg = rig_slider::render::margins(&s.runs[*i].features, f);
            for (check, ok, margin) in [
                ("regime", Some(b.regime), None),
                ("inertial period", b.inertial_period, mg[0]),
                ("period", b.period, mg[1]),
                ("drop", b.drop, mg[2]),
                ("onset", b.onset, mg[3]),
            ] {
                // Each check's margin (> 0 inside its bound, in the check's units) and
                // whether the run's events resolve the verdict (margin > 2 se).
                if let (Some(ok), Some(m)) = (ok, margin) {
                    eprintln!(
                        "calibrated on {cal}: {name} {check}: {} error {:+.4} of ±{:.4}, margin {:+.4}, se {:.4}{}",
                        if ok { "pass" } else { "FAIL" },
                        m.error,
                        m.limit,
                        m.margin,
                        m.se,
                        if m.resolved() { "" } else { " (unresolved by the events)" }
                    );
                    assert_eq!(ok, m.margin >= 0.0, "{name} {check}: the margin and the verdict agree");
                }
                match ok {
                    Some(true) => passed.push(format!("{name} {check}")),
                    Some(false) => failed.push(format!("{name} {check}")),
                    None => {}
                }
            }
        }
    }
    eprintln!("passed: {passed:?}\nfailed: {failed:?}");
    // What holds today (slider.md and docs/findings.md give the numbers),
    // with the misfit's spread term (`fit::spread_term`). The selection is
    // the workspace's one engine (`rig_types::select::forward_select_from`,
    // its pair step on, which since the fourteenth session pairs the step's
    // best with every member of the other group, not only the best-scoring
    // one). Calibrated on 168 N/m step 1's best is the effective mass (gain
    // 11.5 %, t 0.38; static_ageing the best law alone, 4.8 %, t 1.28), and
    // of its five pairs track_threshold+effective_mass gains 58.8 % at t 2.51
    // and is kept (static_ageing+effective_mass, the one pair tried before,
    // loses 8.3 %, t −0.99; the three rate-and-state pairs lose 39–41 %):
    // held out it gets every 2254 N/m check — k2254-v42's creep (a stiff
    // spring follows the track), its period (×0.54 against ×0.5, margin
    // 0.070 ln units, se 0.028) and k2254-v4300's inertial period (+2.8 %).
    // (Until this session Coulomb was kept there and missed those three.)
    // Calibrated on 2254 N/m the step's best is track_threshold (gain
    // 5.1 %, t 0.59) and its two pairs track_threshold+series_compliance
    // (5.6 %, t 0.33) and track_threshold+effective_mass (3.6 %, t 1.07):
    // Coulomb is kept, and it gets 168 N/m's stick-slip runs within every
    // bound, not k168-v4300's inertial period (+29.4 %) nor its onset (the
    // level 0.55 of that run). (Until the twelfth session the pair
    // track_threshold+spring_scale was kept there, gain 17.2 %, t 4.49, and
    // held k168-v4300's period at +11.0 %: its spring was read as a load
    // cell reads, r k (V t − x), which drives the recorded force at r V —
    // 1.35 L in stick where the records rise at 1.10–1.14 L. The channel
    // reads the spring's extension (`render::extension_reading`), and a
    // stiffer spring read so is `effective_mass`: spring_scale is gone.)
    for want in [
        "k2254-v42 regime",
        "k2254-v42 period",
        "k2254-v1100 regime",
        "k2254-v1100 inertial period",
        "k2254-v1100 onset",
        "k2254-v4300 regime",
        "k2254-v4300 inertial period",
        "k2254-v4300 onset",
        "k2254-v42 drop",
        "k2254-v42 onset",
        "k168-v42 regime",
        "k168-v42 period",
        "k168-v42 drop",
        "k168-v42 onset",
        "k168-v1100 regime",
        "k168-v1100 period",
        "k168-v1100 drop",
        "k168-v1100 onset",
        "k168-v4300 regime",
    ] {
        assert!(passed.iter().any(|p| p == want), "{want}: passed {passed:?}");
    }
    // What does not: calibrated on 2254 N/m, k168-v4300's inertial period
    // with a Coulomb law on the stated m and k, which cannot oscillate
    // faster than 2π√(m/k) (the force's spectrum confirms 0.76 T0 at both
    // stiffnesses; a ratio m/k of 0.62 the stated one — a lighter mass or
    // stiffer springs read through their extension, one candidate — is the
    // one element the numbers leave, and its pair with track_threshold is
    // not admitted on that fold: above), and its onset: Coulomb slips at μs
    // where the record slips at 0.55 (its mean force 0.50, every other
    // run's 0.30–0.37).
    assert_eq!(failed, ["k168-v4300 inertial period", "k168-v4300 onset"]);
}

#[test]
fn the_shipped_simulated_stretch_has_converged_features() {
    // pipeline.toml simulates 4 measured periods (at least 0.25 s) at 50 steps
    // per natural period, where the study used to simulate 8 (at least 0.5 s)
    // at 100: at the Coulomb baseline and two rate-and-state laws (one that
    // stick-slips slowly, one near its stability boundary), the regime is the
    // same and no median feature moves by more than the measured spread
    // (sd over the slip events) of that run.
    let Some(dir) = shipped() else { return };
    let p = params();
    let mut reference = p.clone();
    reference.sim_periods = 8.0;
    reference.sim_min_window_s = 0.5;
    reference.steps_per_period = 100.0;
    let raw = rig_ingest::slider::read_slider_folder(&dir).unwrap();
    let rate_state = Model { friction: Candidate::RateState, setup: SetupCandidate::Stated };
    let light = Model { friction: Candidate::Coulomb, setup: SetupCandidate::EffectiveMass };
    let laws: [(Model, &[f64]); 4] = [
        (Model::BASELINE, &[0.3588, 0.024]),
        (rate_state, &[0.336, 0.00106, 0.00238, 1.05e-6]),
        (rate_state, &[0.35, 0.01, 0.004, 0.5e-6]),
        (light, &[0.3588, 0.024, 0.6]),
    ];
    for r in &raw {
        let m = rig_slider::study::measure(r, &p);
        for (cand, x) in laws {
            let (a, b) = (predict(cand, x, &m, &p), predict(cand, x, &m, &reference));
            assert_eq!(a.regime, b.regime, "{} {cand:?}", m.name);
            for (name, fa, fb, sd) in [
                ("period", a.period_s.median, b.period_s.median, m.features.period_s.sd),
                ("drop", a.drop.median, b.drop.median, m.features.drop.sd),
                ("onset", a.onset.median, b.onset.median, m.features.onset.sd),
            ] {
                if fa.is_nan() && fb.is_nan() {
                    continue;
                }
                assert!((fa - fb).abs() <= sd, "{} {cand:?} {name}: {fa} vs {fb} (measured sd {sd})", m.name);
            }
        }
    }
}

#[test]
fn a_description_that_does_not_fit_the_files_names_the_field() {
    // docs/your-rig.md, section 2: the errors a lab gets, each naming what to fix.
    let text = std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../pipeline.toml")).unwrap();
    let misspelt = text.replacen("mass_kg = ", "mas_kg = ", 1);
    let e = StudyParams::from_pipeline_toml(&misspelt).unwrap_err();
    assert!(e.contains("stage slider") && e.contains("mas_kg"), "{e}");
    let missing = text.replacen("gravity_m_s2 = 9.81", "", 1);
    let e = StudyParams::from_pipeline_toml(&missing).unwrap_err();
    assert!(e.contains("gravity_m_s2"), "{e}");
    // A folder whose stiffnesses are none of the calibration list.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir(tmp.path().join("runs")).unwrap();
    let rows: String = (0..400).map(|i| format!("{},{}\n", i as f64 / 2000.0, 0.3)).collect();
    std::fs::write(tmp.path().join("runs/k500-v42.csv"), format!("time_s,force_over_weight\n{rows}")).unwrap();
    let e = run_study(tmp.path(), &params()).unwrap_err().to_string();
    assert!(e.contains("calibration_stiffnesses_n_m") && e.contains("[168.0, 2254.0]"), "{e}");
    // A run file whose name does not say k and V.
    std::fs::write(tmp.path().join("runs/slider-3.csv"), "time_s,force_over_weight\n0,0.3\n0.1,0.3\n").unwrap();
    let e = run_study(tmp.path(), &params()).unwrap_err().to_string();
    assert!(e.contains("slider-3.csv") && e.contains("k<k>-v<V>.csv"), "{e}");
}

#[test]
fn rate_and_state_creeps_at_the_creeping_run_only_as_a_start_up_transient() {
    // Why no fitted model gets k2254-v42's regime (creep: the slider moves
    // through the loading phase at 0.67 V, stick fraction 0.21, drop 0.042,
    // period 0.323 s = 13.9 T0, P V = 13.6 µm). `study::boundary_scan`: the
    // Dieterich–Ruina law with the ageing law, b − a putting the quasi-static
    // critical stiffness k_c = m g (b − a)/Dc from 0.85 to 1.15 × 2254 N/m.
    // With a = 0.003 or 0.01 and Dc = 0.3 or 1 µm (the literature's range for
    // paper) it goes from steady sliding to stick-slip with no creep between.
    // On the run's own Hopf point (`fit::hopf_starts`: ω_c = (V/Dc)
    // √((b − a)/a) at the measured period, a = 0.035 at Dc = 1 µm) it used to
    // read as creep in a band (k_c = 1.1–1.15 k) over the study's old
    // stretch of three measured periods (1.2 s with the warm-up): that was
    // the start from a preloaded spring, the oscillation still growing. Its
    // events do not repeat there, so the stretch is now lengthened to
    // `spread_periods` periods (`study::predict`), and over it, as over a
    // plain 30 s, the same law stick-slips (load rate above 0.9 L, stick
    // fraction 0.9): rate and state with the ageing law has no creep regime
    // at this (k, V) in the scanned range.
    let Some((p, runs)) = shipped_runs() else { return };
    let i = runs.iter().position(|r| r.name == "k2254-v42").expect("the creeping run");
    assert_eq!(runs[i].features.regime, Regime::Creep);
    // The study's own scan (slider.md prints it).
    let scan = rig_slider::study::boundary_scan(&runs, i, &p);
    assert_eq!(scan.scans.len(), 5);
    for (a, dc, regimes) in &scan.scans {
        eprintln!("a {a} Dc {dc:e}: {regimes:?}");
        assert!(regimes.iter().all(|r| r.1 != Regime::Creep), "a {a} Dc {dc}: {regimes:?}");
        assert_eq!(regimes[0].1, Regime::SteadySliding, "a {a} Dc {dc}: steady below the boundary");
        assert_eq!(regimes[12].1, Regime::StickSlip, "a {a} Dc {dc}: stick-slip above it");
    }
    let (a, dc, _) = &scan.scans[4];
    assert!((a / 0.035 - 1.0).abs() < 0.05 && *dc == 1e-6, "the Hopf start at Dc = 1 µm: a {a}");
    assert!(scan.creeping_law.is_none());
    // The transient: k_c = 1.1 k on the Hopf point, over the old stretch and over 30 s.
    let weight_n = p.mass_kg * p.gravity_m_s2;
    let x = [runs[i].features.mean_force, *a, 1.1 * runs[i].stiffness_n_m * dc / weight_n, *dc];
    let rs = Model { friction: Candidate::RateState, setup: SetupCandidate::Stated };
    let mut short = p.clone();
    short.spread_periods = 0;
    let mut long = short.clone();
    long.sim_min_window_s = 30.0;
    long.sim_max_window_s = 30.0;
    let (f_short, f_now, f_long) =
        (predict(rs, &x, &runs[i], &short), predict(rs, &x, &runs[i], &p), predict(rs, &x, &runs[i], &long));
    eprintln!("short {f_short:?}\nnow {f_now:?}\nlong {f_long:?}");
    assert_eq!(f_short.regime, Regime::Creep, "the old stretch reads the transient");
    for f in [f_now, f_long] {
        assert_eq!(f.regime, Regime::StickSlip, "{f:?}");
        assert!(f.load_rate.median > 0.9 && f.stick_fraction.median > 0.85, "{f:?}");
    }
    assert!(f_long.events >= 50 && f_now.period_s.n >= p.spread_periods, "{f_long:?} {f_now:?}");
}

#[test]
fn heslots_law_rests_through_every_loading_phase() {
    // `heslot_creep` (Heslot et al. 1994's cut-offs, rig_slider::heslot) at
    // k2254-v42 from each of its starts on that spring: a speed term that
    // vanishes at v = 0 gives a static threshold, so whenever it slips the
    // slider rests while the spring loads (load rate within 10 % of
    // k V/(m g)): it never creeps, whatever the start.
    let Some((p, runs)) = shipped_runs() else { return };
    let m = runs.iter().find(|r| r.name == "k2254-v42").unwrap();
    let kc = 1.2 * m.stiffness_n_m / (p.mass_kg * p.gravity_m_s2);
    let model = Model { friction: Candidate::Heslot, setup: SetupCandidate::Stated };
    let mut slipping = 0;
    for x in rig_slider::heslot::Heslot::starts(m.features.mean_force, kc) {
        let f = predict(model, &x, m, &p);
        assert_ne!(f.regime, Regime::Creep, "{x:?}: {f:?}");
        if f.load_rate.n > 0 {
            slipping += 1;
            assert!(f.load_rate.median > 0.9, "{x:?}: load rate {:?}", f.load_rate);
        }
    }
    assert!(slipping >= 2, "starts that slip: {slipping}");
}

#[test]
fn the_channel_resolves_coulombs_slips_where_the_record_creeps() {
    // Is k2254-v42's "creep" the model's creep, or stick-slip the record
    // cannot show? The force sits on a grid of 0.0070 F/(m g) at 2254 N/m
    // (0.93 µm of spring; 0.00059 and 1.06 µm at 168 N/m) with a noise of
    // 1.5 steps, and the turning points need 4.5 steps. A Coulomb law slips by
    // 2 (μs − μk) whatever k: the held-out Coulomb fit (μs − μk = 0.021)
    // slips by 6 steps there, and read through the run's own channel (on its
    // grid, with its own noise: `study::through_channel`) it stays stick-slip
    // loading at L, where the record loads at 0.33 L; the study prints the
    // check (slider.md, "What the channel resolves"). The same law with
    // slips of two steps reads as no stick-slip: the limit the data set.
    let Some(dir) = shipped() else { return };
    let p = params();
    let raw = rig_ingest::slider::read_slider_folder(&dir).unwrap();
    let i = raw.iter().position(|r| r.name == "k2254-v42").unwrap();
    let m = rig_slider::study::measure(&raw[i], &p);
    assert_eq!(m.features.regime, Regime::Creep);
    let um = |x: f64| 1e6 * x * p.mass_kg * p.gravity_m_s2 / m.stiffness_n_m;
    assert!((m.force_step / 0.006989 - 1.0).abs() < 1e-3 && (um(m.force_step) - 0.93).abs() < 0.01, "{}", m.force_step);
    let k168 = rig_slider::study::measure(&raw[raw.iter().position(|r| r.name == "k168-v42").unwrap()], &p);
    assert!((um(k168.force_step) * m.stiffness_n_m / k168.stiffness_n_m - 1.06).abs() < 0.01, "{}", k168.force_step);
    let resolved = rig_slider::study::through_channel(Model::BASELINE, &[0.3528, 0.0209], &m, &raw[i], &p, 20.0);
    eprintln!("Coulomb through the channel: {resolved:?}");
    assert_eq!(resolved.regime, Regime::StickSlip);
    assert!((resolved.load_rate.median - 1.0).abs() < 0.15, "{:?}", resolved.load_rate);
    assert!(m.features.load_rate.median < 0.5, "the record creeps: {:?}", m.features.load_rate);
    let lost = rig_slider::study::through_channel(Model::BASELINE, &[0.3528, m.force_step], &m, &raw[i], &p, 20.0);
    eprintln!("slips of two steps through the channel: {lost:?}");
    assert_ne!(lost.regime, Regime::StickSlip, "{lost:?}");
    // The study's own check (what slider.md prints) is the held-out baseline's.
    let s = run_study(&dir, &p).unwrap();
    let c = s.channel_checks.iter().find(|c| c.run == s.runs.iter().position(|r| r.name == "k2254-v42").unwrap());
    let c = c.expect("a channel check at the creeping run");
    assert_eq!((c.clean.regime, c.channel.regime), (Regime::StickSlip, Regime::StickSlip), "{c:?}");
}

#[test]
fn the_track_law_fitted_on_the_stiff_spring_gets_every_regime() {
    // `track_threshold` (rig_slider::track: Coulomb whose threshold varies
    // along the paper) fitted on 2254 N/m alone creeps at k2254-v42 — the
    // stiff spring follows the track and slips only where the threshold
    // falls faster than it unloads — oscillates inertially at 1100 and
    // 4300 µm/s, and stick-slips at 168 N/m, a stiffness it has not seen:
    // every regime of the six runs, the first law here that creeps at
    // k2254-v42 and oscillates at k2254-v1100 at once. Fitted on 168 N/m
    // alone it stick-slips at k2254-v42: the soft spring's slips (its
    // static-to-kinetic drop) hide the track from the medians the misfit
    // reads, so the selection, which needs both folds, does not keep it.
    let Some(dir) = shipped() else { return };
    let mut p = params();
    p.calibration_stiffnesses_n_m = vec![2254.0];
    let s = run_study(&dir, &p).unwrap();
    let model = Model { friction: Candidate::Track, setup: SetupCandidate::Stated };
    let c = s.candidates.iter().find(|c| c.model == model).expect("the track law is a candidate");
    let fit = &c.fold_fits[0];
    eprintln!("track law fitted on 2254 N/m: {:?} calibration misfit {:.3}", fit.params, fit.calibration_misfit);
    for r in &s.runs {
        let f = predict(model, &fit.params, r, &p);
        eprintln!("{}: {:?} -> {:?}", r.name, r.features.regime, f.regime);
        assert_eq!(f.regime, r.features.regime, "{}: {f:?}", r.name);
    }
    let coulomb = &s.candidates[0].fold_fits[0];
    assert!(
        fit.calibration_misfit < 0.8 * coulomb.calibration_misfit,
        "{} vs {}",
        fit.calibration_misfit,
        coulomb.calibration_misfit
    );
    let mut q = params();
    q.calibration_stiffnesses_n_m = vec![168.0];
    let s = run_study(&dir, &q).unwrap();
    let c = s.candidates.iter().find(|c| c.model == model).unwrap();
    let creeping = c.heldout.iter().find(|h| s.runs[h.0].name == "k2254-v42").unwrap();
    assert_eq!(creeping.2.regime, Regime::StickSlip, "fitted on 168 N/m");
}

#[test]
fn the_channel_adds_little_spread_to_a_cycle_that_repeats() {
    // The misfit's spread term compares a record's dispersion (the
    // interquartile widths of ln P, ln D over ln 2 and of the onset over
    // 0.05, `fit::dispersion`) with a noiseless simulation's. What the channel
    // alone adds: a Coulomb law (one cycle that repeats, width 0) at each
    // run's (k, V), read through the run's own channel (its grid and its
    // noise, `study::through_channel`), against the record's own widths.
    let Some(dir) = shipped() else { return };
    let p = params();
    let raw = rig_ingest::slider::read_slider_folder(&dir).unwrap();
    for r in &raw {
        let m = rig_slider::study::measure(r, &p);
        let mu = m.features.mean_force;
        let clean = predict(Model::BASELINE, &[mu + 0.02, 0.04], &m, &p);
        let seconds = 20.0f64.min(m.duration_s);
        let through = rig_slider::study::through_channel(Model::BASELINE, &[mu + 0.02, 0.04], &m, r, &p, seconds);
        let (d0, d1, dm) =
            (dispersion(&clean), dispersion(&through), dispersion(&m.features).expect("every run has periods"));
        eprintln!("{}: measured {dm:.3?}; Coulomb clean {d0:.3?}, through the channel {d1:.3?}", m.name);
        assert!(repeats(&clean), "{}: a Coulomb cycle repeats: {d0:?}", m.name);
        if let Some(d1) = d1 {
            // The channel's share is below half of what the record shows, feature by feature.
            for k in 0..3 {
                assert!(d1[k] < 0.5 * dm[k].max(0.2), "{} feature {k}: channel {d1:?} record {dm:?}", m.name);
            }
        }
    }
}

#[test]
fn the_local_misfit_tells_a_smooth_law_from_a_chaotic_one() {
    // At the shipped search's fits on all six calibration runs (2 × 60, the
    // `converge` example's `cal` lines): Coulomb's slips repeat one cycle and
    // its misfit is smooth — 20 moves of 0.05 % move it by little (sd
    // 0.00014) —; the track law's slips land on a threshold that varies over
    // 5 µm, far below a slip (≈ 70 µm at 168 N/m): its sample path is chaotic
    // and its misfit a noisy draw (sd 0.0134 over the same 20 moves), and the
    // search's point, the lowest draw it found, lies below the local mean
    // (0.6567 against 0.6707, 4.7 standard errors; h/slider11). The bounds:
    // Coulomb's sd and offset at a tenth of the track law's sd, the track
    // law's sd and deficit at less than half of what they are.
    let Some((p, runs)) = shipped_runs() else { return };
    let on: Vec<&Measured> = runs.iter().collect();
    let coulomb = [3.5947884344838477e-1, 2.090888696084687e-2];
    let c = rig_slider::study::local_misfit(Model::BASELINE, &coulomb, &on, &p, 20, 5e-4);
    assert!(c.sd < 0.002 && (c.mean - c.at).abs() < 0.002, "Coulomb: {c:?}");
    let track = Model { friction: Candidate::Track, setup: SetupCandidate::Stated };
    let x = [3.6091027852585056e-1, 8.251429357502418e-3, 1.1494797238514745e-2, 5.144258552095865e-6];
    let t = rig_slider::study::local_misfit(track, &x, &on, &p, 20, 5e-4);
    eprintln!("Coulomb {c:?}\nthe track law {t:?}");
    assert!(t.sd > 0.005 && t.mean - t.at > 0.006, "the track law: {t:?}");
    // The same moves at every call: the same bits.
    let again = rig_slider::study::local_misfit(track, &x, &on, &p, 20, 5e-4);
    assert_eq!((t.mean.to_bits(), t.sd.to_bits()), (again.mean.to_bits(), again.sd.to_bits()));
}

#[test]
fn runs_at_a_stiffness_not_seen_are_held_out_and_checked() {
    // Issue 26's Done-when: runs at other stiffnesses will be added to the
    // folder and predicted. A test-only fixture in the shipped layout: the six
    // shipped runs, and the three k168 records copied under a third label,
    // k500 (a relabelling: the physics of those records is the 168 N/m
    // spring's, so the checks' verdicts say nothing of a 500 N/m spring; what
    // is tested is the path). With the default calibration list the study
    // fits and selects on the six shipped runs only, holds out every run at
    // 500 N/m, and reports every check that applies with its margin.
    let Some(dir) = shipped() else { return };
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir(tmp.path().join("runs")).unwrap();
    for e in std::fs::read_dir(dir.join("runs")).unwrap() {
        let path = e.unwrap().path();
        let name = path.file_name().unwrap().to_string_lossy().into_owned();
        std::fs::copy(&path, tmp.path().join("runs").join(&name)).unwrap();
        if let Some(v) = name.strip_prefix("k168-") {
            std::fs::copy(&path, tmp.path().join("runs").join(format!("k500-{v}"))).unwrap();
        }
    }
    let p = params();
    assert_eq!(p.calibration_stiffnesses_n_m, [168.0, 2254.0], "the shipped list");
    // A new run the README layout does not describe (the force in newtons):
    // refused with the file, the line and the field.
    let newtons = tmp.path().join("runs/k500-v4300.csv");
    let text = std::fs::read_to_string(&newtons).unwrap();
    std::fs::write(&newtons, text.replacen("force_over_weight", "force_n", 1)).unwrap();
    let e = run_study(tmp.path(), &p).unwrap_err().to_string();
    assert!(e.contains("k500-v4300.csv:1") && e.contains("force_n") && e.contains("force_over_weight"), "{e}");
    std::fs::write(&newtons, text).unwrap();
    let s = run_study(tmp.path(), &p).unwrap();
    assert!(!s.leave_one_out);
    let names = |idx: &[usize]| idx.iter().map(|&i| s.runs[i].name.clone()).collect::<Vec<_>>();
    assert_eq!(s.folds.len(), 1);
    assert_eq!(names(&s.folds[0].held_out), ["k500-v42", "k500-v1100", "k500-v4300"]);
    assert!(names(&s.folds[0].train).iter().all(|n| !n.starts_with("k500")) && s.folds[0].train.len() == 6);
    let out = render(&s);
    assert!(out.markdown.contains("every run at a stiffness outside the calibration list"), "the study says which");
    // Every model the selection tried predicts every held-out run, from the fit on the six shipped runs.
    for c in &s.candidates {
        assert_eq!(names(&c.heldout.iter().map(|h| h.0).collect::<Vec<_>>()), ["k500-v42", "k500-v1100", "k500-v4300"]);
        assert!(c.fold_fits.iter().all(|f| f.train == s.folds[0].train), "{}", c.model.id());
        for (i, _, f) in &c.heldout {
            let (b, mg) = (
                rig_slider::render::bounds(&s.runs[*i].features, f),
                rig_slider::render::margins(&s.runs[*i].features, f),
            );
            let checks = [b.inertial_period, b.period, b.drop, b.onset];
            for (ok, m) in checks.iter().zip(&mg) {
                // A check applies exactly where it has a margin, and the two agree.
                assert_eq!(ok.is_some(), m.is_some(), "{} {}", c.model.id(), s.runs[*i].name);
                if let (Some(ok), Some(m)) = (ok, m) {
                    assert_eq!(*ok, m.margin >= 0.0);
                    assert!(m.margin.is_finite() && m.se.is_finite(), "{m:?}");
                }
            }
            // The report's row of the held-out table: the regime, and each applicable check with its margin.
            let row = out
                .markdown
                .lines()
                .find(|l| l.starts_with(&format!("| {} | {} |", c.model.id(), s.runs[*i].name)))
                .unwrap_or_else(|| panic!("no held-out row for {} at {}", c.model.id(), s.runs[*i].name));
            assert!(row.contains(" → "), "{row}");
            let shown = row.matches(" of ±").count() + row.matches(" of ×2").count();
            assert_eq!(shown, checks.iter().filter(|x| x.is_some()).count(), "{row}");
        }
    }
    // The verdict names what the final model cannot explain: a held-out run
    // whose regime is wrong or whose check fails by more than the run's events
    // resolve makes the answer `unexplained`, whatever the mean misfit (the
    // mean alone once averaged a resolved 23 % period miss at ±15 % away and
    // answered `none`). Recomputed here from the public bounds and margins.
    let final_c = &s.candidates[s.chosen.unwrap_or(0)];
    let missed: Vec<String> = final_c
        .heldout
        .iter()
        .filter(|(i, _, f)| {
            let meas = &s.runs[*i].features;
            let b = rig_slider::render::bounds(meas, f);
            let mg = rig_slider::render::margins(meas, f);
            !b.regime
                || [b.inertial_period, b.period, b.drop, b.onset]
                    .iter()
                    .zip(&mg)
                    .any(|(ok, m)| *ok == Some(false) && m.is_some_and(|m| m.resolved()))
        })
        .map(|(i, _, _)| s.runs[*i].name.clone())
        .collect();
    let verdict = out.diagnosis["verdict"].as_str().unwrap();
    if !missed.is_empty() {
        assert_eq!(verdict, "unexplained", "the final model misses {missed:?} held out");
        let unexplained = out.diagnosis["findings"]
            .as_array()
            .unwrap()
            .iter()
            .find(|f| f["effect"] == "unexplained")
            .expect("an unexplained finding");
        for run in &missed {
            assert!(unexplained["where"].as_array().unwrap().iter().any(|w| w == run.as_str()), "{run}");
        }
    }
    // The measured features of a relabelled record are its own at the new
    // label's k: the natural period and the load rate's unit move with k, the
    // force does not.
    let (a, b) = (
        &s.runs.iter().find(|r| r.name == "k168-v42").unwrap().features,
        &s.runs.iter().find(|r| r.name == "k500-v42").unwrap().features,
    );
    assert_eq!(a.mean_force, b.mean_force);
    assert!((a.natural_period_s / b.natural_period_s - (500.0f64 / 168.0).sqrt()).abs() < 1e-12);
    // The held-out table carries every held-out run of every model.
    let (_, table) =
        out.tables.iter().find(|(name, _)| name == "tables/slider-heldout.csv").expect("the held-out table");
    let csv = table.to_csv();
    for run in ["k500-v42", "k500-v1100", "k500-v4300"] {
        assert_eq!(csv.lines().filter(|l| l.contains(run)).count(), s.candidates.len(), "{run}");
    }
}
