//! Bulk-ingest speed: 1 M readings into a fresh temp-file database.
use criterion::{Criterion, criterion_group, criterion_main};
fn bench(_c: &mut Criterion) {}
criterion_group!(benches, bench);
criterion_main!(benches);
