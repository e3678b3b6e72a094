//! A 100 × 100 severity map of the rig model on 2 threads: 100 friction rows
//! (0.5–25 N), each swept up over 100 motor speeds (10–130 rpm) by
//! continuation, every point a 40 s run (20 s transient + 20 s classified at
//! 100 Hz) — 10 000 runs of 40 s. Target ≤ 3 s wall on two cores (issue 12;
//! rig-model's exact steps between events make a run ≈ 0.3 ms of CPU).
//! rig-params.json is the estimation stage's output on data/emulated-rig-2026
//! (Coulomb brake μs 1.46 / μk 1.10, n = 8, PI 4.49 V·s/rad, 49.4 V/rad).

use criterion::{Criterion, criterion_group, criterion_main};
use rig_model::SimOptions;
use rig_sweep::{ClassifyOptions, Direction, MapSpec, SweepSettings, WindowSpec, linspace, run_chains};
use rig_types::RigParams;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    let params: RigParams =
        serde_json::from_str(include_str!("rig-params.json")).expect("benches/rig-params.json is a RigParams");
    let map = MapSpec { speeds_rpm: linspace(10.0, 130.0, 100), forces_n: linspace(0.5, 25.0, 100) };
    let chains: Vec<_> = map.chains().into_iter().filter(|c| c.direction == Direction::Up).collect();
    let s = SweepSettings {
        window: WindowSpec { first_transient_s: 20.0, transient_s: 20.0, window_s: 20.0, sample_rate_hz: 100.0 },
        // The shipped integrator: pipeline.toml's [shared.integrator].
        sim: SimOptions::from_pipeline_toml(include_str!("../../../pipeline.toml")).expect("pipeline.toml"),
        classify: ClassifyOptions::default(),
    };
    let pool = rayon::ThreadPoolBuilder::new().num_threads(2).build().expect("thread pool");
    let mut group = c.benchmark_group("severity map");
    group.sample_size(10);
    group.bench_function("rig model 100 x 100, 40 s per point, 2 threads", |b| {
        b.iter(|| pool.install(|| run_chains(black_box(&params), black_box(&chains), &s, &|| {})))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
