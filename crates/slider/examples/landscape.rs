//! A model's calibration misfit along one search axis about a parameter
//! vector (issue 26: is the misfit smooth at the scale a search's
//! convergence criterion asks for?): the vector's parameter AXIS scaled by
//! 1 + i·REL for i = −STEPS..=STEPS, each point's mean misfit over the
//! runs at the stiffnesses K1,K2,... (default: pipeline.toml's
//! `calibration_stiffnesses_n_m`) and each run's, through the library's
//! `rig_slider::study::landscape` (the study's own `predict` and
//! `run_misfit`: the mean the fits minimise; the report's roughness reads
//! the same function one step each way).
//! `cargo run -p rig-slider --example landscape -- DIR MODEL AXIS REL STEPS X1,X2,... [K1,K2,...]`
//! from the workspace root (pipeline.toml's `[slider]` settings), e.g. the
//! 8 × 400 reference's track law: `../shared/data/ens-lyon-slider-2019
//! track_threshold 2 0.002 10 0.36123411571726216,0.008030806638286463,0.011686546673694533,5.143858137785933e-6`.

use rig_slider::StudyParams;
use rig_slider::fit::{CANDIDATES, Model, SetupCandidate};
use rig_slider::study::{Measured, landscape, measure};

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let usage = "DIR MODEL AXIS REL STEPS X1,X2,...";
    let arg = |i: usize| a.get(i).unwrap_or_else(|| panic!("usage: {usage}"));
    let p = StudyParams::from_pipeline_toml(
        &std::fs::read_to_string("pipeline.toml").expect("run from the workspace root"),
    )
    .expect("the slider stanza");
    let setups = [SetupCandidate::Stated, SetupCandidate::EffectiveMass, SetupCandidate::SeriesCompliance];
    let model = CANDIDATES
        .iter()
        .flat_map(|&friction| setups.iter().map(move |&setup| Model { friction, setup }))
        .find(|m| m.id() == *arg(2))
        .unwrap_or_else(|| panic!("MODEL: no model {}", arg(2)));
    let axis: usize = arg(3).parse().expect("AXIS: an index");
    let rel: f64 = arg(4).parse().expect("REL: a number");
    let steps: i32 = arg(5).parse().expect("STEPS: a count");
    let x0: Vec<f64> = arg(6).split(',').map(|v| v.parse().expect("X: numbers")).collect();
    assert_eq!(x0.len(), model.params().len(), "X: one value per parameter of {}", model.id());
    let train: Vec<f64> = a.get(7).map_or_else(
        || p.calibration_stiffnesses_n_m.clone(),
        |k| k.split(',').map(|v| v.parse().expect("K: stiffnesses, N/m")).collect(),
    );
    let raw = rig_ingest::slider::read_slider_folder(std::path::Path::new(arg(1))).expect("the folder");
    let runs: Vec<_> = raw
        .iter()
        .filter(|r| train.iter().any(|&k| (k - r.stiffness_n_m).abs() < 1e-9 * k))
        .map(|r| measure(r, &p))
        .collect();
    println!("{} axis {} ({}), runs {}", model.id(), axis, model.params()[axis].name, {
        let names: Vec<&str> = runs.iter().map(|r| r.name.as_str()).collect();
        names.join(" ")
    });
    let on: Vec<&Measured> = runs.iter().collect();
    for pt in landscape(model, &x0, axis, rel, steps, &on, &p) {
        let per: Vec<String> = pt.per_run.iter().map(|v| format!("{v:.4}")).collect();
        println!("{:>4} {:.6e} misfit {:.4} runs {}", pt.step, pt.value, pt.misfit, per.join(" "));
    }
}
