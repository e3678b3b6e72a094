//! Prints the measured features of every run of a slider folder (default:
//! ../shared/data/ens-lyon-slider-2019) with pipeline.toml's settings:
//! `cargo build --workspace --examples && ./target/debug/examples/measure DIR`
//! from the workspace root.

use rig_slider::{StudyParams, study::measure};

fn main() {
    let dir = std::env::args().nth(1).unwrap_or_else(|| "../shared/data/ens-lyon-slider-2019".into());
    let p = StudyParams::from_pipeline_toml(
        &std::fs::read_to_string("pipeline.toml").expect("run from the workspace root"),
    )
    .expect("the slider stanza");
    let runs = rig_ingest::slider::read_slider_folder(std::path::Path::new(&dir)).unwrap_or_else(|e| panic!("{e}"));
    for r in &runs {
        let f = measure(r, &p).features;
        println!(
            "{} {} events={} T0={:.4} period={:.4}±{:.4} drop={:.4}±{:.4} onset={:.4}±{:.4} stick={:.3}±{:.3} creep={:.3}±{:.3} noise={:.4} h={:.4}",
            r.name,
            f.regime.label(),
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
            f.noise_sd,
            f.hysteresis
        );
    }
}
