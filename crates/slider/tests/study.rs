//! The slider study end to end: a round trip (simulate a known law, recover
//! it), the study on the shipped folder and the "unseen stiffness" check
//! (calibrate on one stiffness, predict the other). The last two read
//! ../shared and are skipped with a message when it is absent.

use rig_slider::fit::{Candidate, fit, run_misfit};
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

fn synthetic(k: f64, v_um_s: f64, duration_s: f64, f: rig_slider::Features) -> Measured {
    Measured {
        name: format!("k{k}-v{v_um_s}"),
        stiffness_n_m: k,
        drive_speed_um_s: v_um_s,
        duration_s,
        sample_rate_hz: 2000.0,
        features: f,
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
        let f = predict(Candidate::Coulomb, &truth, &probe, &q);
        assert_eq!(f.regime, Regime::StickSlip, "{k} {v}: {f:?}");
        runs.push(synthetic(k, v, 30.0, f));
    }
    let cost = |x: &[f64]| {
        runs.iter().map(|r| run_misfit(&r.features, &predict(Candidate::Coulomb, x, r, &p))).sum::<f64>() / 3.0
    };
    let (x, c) = fit(Candidate::Coulomb, &[0.35, 0.03], 80, cost);
    assert!((x[0] - truth[0]).abs() < 0.01, "mu_static {} (truth {})", x[0], truth[0]);
    assert!((x[1] / truth[1] - 1.0).abs() < 0.1, "mu_drop {} (truth {})", x[1], truth[1]);
    assert!(c < 0.1, "misfit at the recovered law {c}");
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
    let out = render(&s);
    let verdict = out.diagnosis["verdict"].as_str().unwrap();
    assert!(["none", "unexplained", "static_ageing", "rate_state_ageing"].contains(&verdict), "{verdict}");
    assert_eq!(out.diagnosis["candidates"].as_array().unwrap().len(), 2);
    assert!(out.markdown.contains("leave one stiffness out"));
}

#[test]
fn unseen_stiffness_is_predicted() {
    let Some(dir) = shipped() else { return };
    // A folder with a subset of the runs: calibrate on 168 N/m, predict 2254 N/m.
    let tmp = tempfile::tempdir().unwrap();
    std::fs::create_dir(tmp.path().join("runs")).unwrap();
    for name in ["k168-v42", "k168-v1100", "k168-v4300", "k2254-v1100", "k2254-v4300"] {
        std::fs::copy(dir.join(format!("runs/{name}.csv")), tmp.path().join(format!("runs/{name}.csv"))).unwrap();
    }
    let mut p = params();
    p.calibration_stiffnesses_n_m = vec![168.0];
    let s = run_study(tmp.path(), &p).unwrap();
    assert!(!s.leave_one_out);
    let base = &s.candidates[0];
    let held: Vec<&str> = base.heldout.iter().map(|h| s.runs[h.0].name.as_str()).collect();
    assert_eq!(held, ["k2254-v1100", "k2254-v4300"]);
    for c in &s.candidates {
        for (i, _, f) in &c.heldout {
            let b = rig_slider::render::bounds(&s.runs[*i].features, f);
            eprintln!("{} {}: {:?}", c.fitted.candidate.id(), s.runs[*i].name, b);
        }
    }
    // What holds at the unseen stiffness: the Coulomb baseline and rate and
    // state get the regime (an inertial oscillation at both speeds), and the
    // inertial period and the force at slip onset at 1100 µm/s. (Static
    // ageing fitted on 168 N/m alone predicts steady sliding at
    // k2254-v1100: slider.md reports it.) The inertial period at 4300 µm/s
    // is measured 22 % below 2π√(m/k), and no law of one mass on one spring
    // oscillates faster than that (a Coulomb cycle lasts at least
    // 2π√(m/k)): the ±15 % bound fails there for every candidate.
    let judged = |c: &&rig_slider::study::CandidateResult| c.fitted.candidate != Candidate::StaticAgeing;
    for c in s.candidates.iter().filter(judged) {
        for (i, _, f) in &c.heldout {
            let b = rig_slider::render::bounds(&s.runs[*i].features, f);
            assert!(b.regime, "{} {}: regime", c.fitted.candidate.id(), s.runs[*i].name);
        }
    }
    for c in s.candidates.iter().filter(judged) {
        let (i, _, f) = &c.heldout[0];
        let b = rig_slider::render::bounds(&s.runs[*i].features, f);
        assert_eq!(b.inertial_period, Some(true), "{} at k2254-v1100: {b:?}", c.fitted.candidate.id());
        assert_eq!(b.onset, Some(true), "{} at k2254-v1100: {b:?}", c.fitted.candidate.id());
        let (i, _, f) = &c.heldout[1];
        let b = rig_slider::render::bounds(&s.runs[*i].features, f);
        assert_eq!(b.inertial_period, Some(false), "{} at k2254-v4300: {b:?}", c.fitted.candidate.id());
    }
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
    let laws: [(Candidate, &[f64]); 3] = [
        (Candidate::Coulomb, &[0.3588, 0.024]),
        (Candidate::RateState, &[0.336, 0.00106, 0.00238, 1.05e-6]),
        (Candidate::RateState, &[0.35, 0.01, 0.004, 0.5e-6]),
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
