//! Each calibration fit the `converge` example prints (its `cal` lines, on
//! stdin) read at its point and as the local mean misfit over MOVES fixed
//! random moves of relative size REL (`rig_slider::study::local_misfit`,
//! issue 26: a law with a chaotic sample path, the track law, has a misfit
//! that is one noisy draw at its point; two fits of it compare on the mean).
//! `cargo run -p rig-slider --example converge -- 0 8 DIR 400 | cargo run -p rig-slider --example local_misfit -- DIR 40 0.0005`
//! from the workspace root (pipeline.toml's `[slider]` settings).

use rig_slider::StudyParams;
use rig_slider::fit::{CANDIDATES, Model, SETUPS, SetupCandidate};
use rig_slider::study::{Measured, local_misfit, measure};
use std::io::BufRead;

fn main() {
    let a: Vec<String> = std::env::args().collect();
    let usage = "DIR MOVES REL < converge's output";
    let arg = |i: usize| a.get(i).unwrap_or_else(|| panic!("usage: {usage}"));
    let moves: usize = arg(2).parse().expect("MOVES: a count");
    let rel: f64 = arg(3).parse().expect("REL: a number");
    let p = StudyParams::from_pipeline_toml(
        &std::fs::read_to_string("pipeline.toml").expect("run from the workspace root"),
    )
    .expect("the slider stanza");
    let raw = rig_ingest::slider::read_slider_folder(std::path::Path::new(arg(1))).expect("the folder");
    let runs: Vec<Measured> = raw.iter().map(|r| measure(r, &p)).collect();
    let models: Vec<Model> = CANDIDATES
        .iter()
        .flat_map(|&friction| {
            std::iter::once(SetupCandidate::Stated).chain(SETUPS).map(move |setup| Model { friction, setup })
        })
        .collect();
    println!("moves {moves} rel {rel}");
    for line in std::io::stdin().lock().lines() {
        let line = line.expect("stdin");
        let Some(rest) = line.strip_prefix("cal ") else { continue };
        let word = |key: &str| {
            let w: Vec<&str> = rest.split_whitespace().collect();
            w[w.iter().position(|&s| s == key).unwrap_or_else(|| panic!("no {key} in {line}")) + 1].to_string()
        };
        let id = word("model");
        let model = *models.iter().find(|m| m.id() == id).unwrap_or_else(|| panic!("no model {id}"));
        let (t0, t1) = (rest.find('[').expect("train ["), rest.find(']').expect("train ]"));
        let train: Vec<f64> =
            rest[t0 + 1..t1].split(',').map(|v| v.trim().parse().expect("train: stiffnesses, N/m")).collect();
        let x: Vec<f64> = word("params").split(',').map(|v| v.parse().expect("params: numbers")).collect();
        let on: Vec<&Measured> =
            runs.iter().filter(|r| train.iter().any(|&k| (k - r.stiffness_n_m).abs() < 1e-9 * k)).collect();
        let l = local_misfit(model, &x, &on, &p, moves, rel);
        println!(
            "{:<36} train {:<16} at {:.4} local mean {:.4} sd {:.4} (se {:.4})",
            id,
            format!("{train:?}"),
            l.at,
            l.mean,
            l.sd,
            l.sd / (moves as f64).sqrt()
        );
    }
}
