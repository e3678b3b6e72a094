//! One 40 s operating-point run (40 rpm, 15 N) of the rig model and the
//! thesis model ([`cases`]), in a binary whose global allocator is mimalloc:
//! freed trajectories' pages are reused instead of returned to the kernel and
//! faulted in again, so the plain `simulate` into a fresh trajectory costs
//! what the reused path costs (docs/performance.md; `simulate_system_alloc`
//! times the same cases with the system allocator, what a program that sets
//! none gets). Targets (issues 12, 23): rig ≤ 0.4 ms, thesis ≤ 1 ms, the
//! plain call ≥ 300× scipy LSODA (scripts/peer_scipy.py --criterion, same run).

mod cases;

use criterion::{Criterion, criterion_group, criterion_main};

#[global_allocator]
static GLOBAL: mimalloc::MiMalloc = mimalloc::MiMalloc;

fn bench(c: &mut Criterion) {
    cases::bench(c, "mimalloc");
}

criterion_group!(benches, bench);
criterion_main!(benches);
