//! Runs the slider study on a folder and prints its summary and wall time:
//! `cargo run --example study -- DIR` (default ../shared/data/ens-lyon-slider-2019).

use rig_slider::{FeatureOptions, StudyParams, run_study};

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "../shared/data/ens-lyon-slider-2019".into());
    let p = StudyParams {
        folder: dir.clone(),
        mass_kg: 0.0307,
        gravity_m_s2: 9.81,
        calibration_stiffnesses_n_m: vec![168.0, 2254.0],
        sim_periods: 8.0,
        sim_min_window_s: 0.5,
        sim_max_window_s: 20.0,
        warmup_fraction: 0.25,
        steps_per_period: 100.0,
        fit_sweeps: 2,
        fit_evals: 10,
        min_relative_gain: 0.05,
        adequacy_threshold: 1.0,
        features: FeatureOptions {
            median_window_s: 0.0025,
            min_drop: 0.02,
            segments: 5,
            min_events: 3,
            noise_multiple: 3.0,
            stick_regime_fraction: 0.5,
            inertial_ratio: 3.0,
        },
    };
    let t = std::time::Instant::now();
    let s = run_study(std::path::Path::new(&dir), &p).expect("study");
    println!("wall {:.2} s", t.elapsed().as_secs_f64());
    for c in &s.candidates {
        println!(
            "{:?} params {:?} cal {:.3} heldout {:.3} at_bounds {:?}",
            c.fitted.candidate, c.fitted.params, c.fitted.calibration_misfit, c.heldout_mean, c.fitted.at_bounds
        );
        for (i, r) in s.runs.iter().enumerate() {
            let f = &c.predicted[i];
            let h = c.heldout.iter().find(|h| h.0 == i).unwrap();
            println!(
                "  {:12} meas {:?} P={:.3} D={:.3} O={:.3} | fit {:?} P={:.3} D={:.3} O={:.3} | heldout {:?} P={:.3} D={:.3} O={:.3} m={:.2}",
                r.name,
                r.features.regime,
                r.features.period_s.median,
                r.features.drop.median,
                r.features.onset.median,
                f.regime,
                f.period_s.median,
                f.drop.median,
                f.onset.median,
                h.2.regime,
                h.2.period_s.median,
                h.2.drop.median,
                h.2.onset.median,
                h.1
            );
        }
    }
    println!("chosen {:?}", s.chosen);
}
