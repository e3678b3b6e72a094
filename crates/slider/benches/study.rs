//! The whole slider study (read the folder, measure, fit every candidate on
//! every split, predict, render) on the shipped folder with pipeline.toml's
//! settings: issue 23 asks ≤ 5 s here, and the `slider` stage ≤ 1.5 s wall
//! on 2 cores. Skipped with a message when ../shared is absent.
//! `cargo bench --workspace --bench study`.

use criterion::{Criterion, criterion_group, criterion_main};
use rig_slider::{StudyParams, render, run_study};
use std::path::Path;

fn study(c: &mut Criterion) {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let dir = root.join("../shared/data/ens-lyon-slider-2019");
    if !dir.join("runs").is_dir() {
        eprintln!("skipped: {} absent", dir.display());
        return;
    }
    let text = std::fs::read_to_string(root.join("pipeline.toml")).expect("pipeline.toml");
    let p = StudyParams::from_pipeline_toml(&text).expect("the slider stanza");
    let mut g = c.benchmark_group("slider");
    g.sample_size(10);
    g.bench_function("study", |b| b.iter(|| render(&run_study(&dir, &p).expect("the shipped folder"))));
    g.finish();
}

// No plots: criterion's PDF/SVG plotter needs a system font this machine may lack.
criterion_group! {
    name = benches;
    config = Criterion::default().without_plots();
    targets = study
}
criterion_main!(benches);
