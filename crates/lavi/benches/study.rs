//! Criterion bench: the whole LAVI study (issue 23: ≤ 5 s) on run 175 with
//! the `lavi` stage's params of pipeline.toml: read, repairs audit, windows,
//! features, baseline, every candidate's fit and free runs, forward
//! selection, structure lead, signature and the rendered outputs, exactly
//! what the stage computes. Skipped with a message when ../shared is absent.
//!
//! rig-lavi reads through rig-ingest (polars), which the bench profile would
//! rebuild at release settings for many minutes; the crate is optimised in
//! the dev profile (opt-level 3, Cargo.toml), so run it there:
//! `cargo bench --workspace --bench study --profile dev`.

use criterion::{Criterion, criterion_group, criterion_main};
use std::path::{Path, PathBuf};
use std::time::Duration;

fn setup() -> Option<(PathBuf, rig_lavi::StudyParams)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let path = root.join("../../../shared/data/ufrj-lavi-2018/run-175.csv");
    if !path.exists() {
        println!("skipped: {} is absent (../shared not mounted)", path.display());
        return None;
    }
    let text = std::fs::read_to_string(root.join("../../pipeline.toml")).expect("pipeline.toml");
    let v: toml::Value = toml::from_str(&text).expect("pipeline.toml parses");
    let stage = v["stage"].as_array().expect("[[stage]]").iter().find(|s| s["name"].as_str() == Some("lavi"));
    let mut params = stage.expect("a lavi stage")["params"].clone();
    // `[shared.selection]` is merged into the stage's params by the pipeline's runner.
    params.as_table_mut().expect("params").insert("selection".into(), v["shared"]["selection"].clone());
    Some((path, params.try_into().expect("the lavi stage's params")))
}

fn study(c: &mut Criterion) {
    let Some((path, params)) = setup() else { return };
    let mut g = c.benchmark_group("lavi");
    g.sample_size(10).measurement_time(Duration::from_secs(60)).warm_up_time(Duration::from_secs(1));
    g.bench_function("whole_study_run_175", |b| {
        b.iter(|| rig_lavi::run_study(&path, &params).expect("the study runs"));
    });
    g.finish();
}

criterion_group! {
    name = benches;
    // No plots: the plotters backend finds no font on this machine; the numbers are what is recorded.
    config = Criterion::default().without_plots();
    targets = study
}
criterion_main!(benches);
