//! The cases of the `simulate` and `simulate_system_alloc` benches: one 40 s
//! operating-point run (40 rpm, 15 N) of the rig model, sampled at the
//! campaign's 500 Hz and at its end only, and the thesis model, at the
//! shipped tolerances (pipeline.toml's `[shared.integrator]`), into a fresh trajectory and into a reused one. The two
//! bench binaries differ only in their global allocator (docs/performance.md).

#[path = "../../tests/common/mod.rs"]
mod common;

use criterion::Criterion;
use rig_model::{simulate_into, simulate_with_stats};
use rig_types::RunInput;
use std::hint::black_box;

/// Every case, in the criterion group named after the binary's global allocator.
pub fn bench(c: &mut Criterion, allocator: &str) {
    let p = common::rig_params();
    let input = RunInput::OperatingPoint { motor_rpm_setpoint: 40.0, normal_force_n: 15.0, ramp_s: 2.0 };
    let t = common::grid(40.0, 500.0);
    let o = common::shipped();
    let mut g = c.benchmark_group(allocator);
    g.bench_function("rig model 40 s, 40 rpm, 15 N, default tol", |b| {
        b.iter(|| simulate_with_stats(black_box(&p), black_box(&input), black_box(&t), &o).unwrap())
    });
    // A batch that keeps one trajectory per thread (simulate_into): the samples go into
    // memory it already owns instead of 1.4 MB of freshly faulted pages per run.
    let mut out = rig_types::Trajectory::default();
    g.bench_function("rig model 40 s, 40 rpm, 15 N, default tol, into a reused trajectory", |b| {
        b.iter(|| simulate_into(black_box(&p), black_box(&input), black_box(&t), &o, &mut out).unwrap())
    });
    let last = [40.0];
    g.bench_function("rig model 40 s, 40 rpm, 15 N, default tol, one sample", |b| {
        b.iter(|| simulate_with_stats(black_box(&p), black_box(&input), black_box(&last), &o).unwrap())
    });
    let thesis = common::thesis_params();
    g.bench_function("thesis model 40 s, 40 rpm, 15 N, default tol", |b| {
        b.iter(|| simulate_with_stats(black_box(&thesis), black_box(&input), black_box(&t), &o).unwrap())
    });
    g.finish();
}
