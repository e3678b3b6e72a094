//! Prints the measured features of every run of a slider folder (default:
//! ../shared/data/ens-lyon-slider-2019): `cargo run --example measure -- DIR`.

use rig_slider::{FeatureOptions, RunConstants, features};

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "../shared/data/ens-lyon-slider-2019".into());
    let runs = rig_ingest::slider::read_slider_folder(std::path::Path::new(&dir)).expect("a slider folder");
    let o = FeatureOptions {
        median_window_s: 0.0025,
        min_drop: 0.02,
        segments: 5,
        min_events: 3,
        noise_multiple: 3.0,
        stick_regime_fraction: 0.5,
        inertial_ratio: 3.0,
    };
    for r in &runs {
        let c = RunConstants {
            stiffness_n_m: r.stiffness_n_m,
            drive_speed_m_s: r.drive_speed_um_s * 1e-6,
            mass_kg: 0.0307,
            gravity_m_s2: 9.81,
        };
        let f = features(&r.time_s, &r.force_over_weight, &c, &o);
        println!(
            "{} {:?} ev={} T0={:.4} P={:.4}±{:.4} drop={:.4}±{:.4} onset={:.4}±{:.4} stick={:.3}±{:.3} creep={:.3}±{:.3} mean={:.3} noise={:.4} h={:.4}",
            r.name,
            f.regime,
            f.events,
            f.natural_period_s,
            f.period_s.median,
            f.period_s.sd,
            f.drop.median,
            f.drop.sd,
            f.onset.median,
            f.onset.sd,
            f.stick_fraction.median,
            f.stick_fraction.sd,
            f.creep.median,
            f.creep.sd,
            f.mean_force,
            f.noise_sd,
            f.hysteresis
        );
    }
}
