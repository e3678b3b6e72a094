//! The [`cases`] of the `simulate` bench with the system allocator (glibc's
//! malloc here): what a program that links rig-model and sets no global
//! allocator gets for the plain `simulate` call (docs/performance.md).

mod cases;

use criterion::{Criterion, criterion_group, criterion_main};

fn bench(c: &mut Criterion) {
    cases::bench(c, "system allocator");
}

criterion_group!(benches, bench);
criterion_main!(benches);
