//! Criterion bench of the hierarchical radiosity solver on a procedural room (spheres and boxes,
//! `hierarchy::procedural`) of 100k input triangles (issue 10) at preview settings, ten samples.

use criterion::{criterion_group, criterion_main, Criterion};
use radray::radiosity::hierarchy::{self, procedural, HierarchyParams};

/// Input triangles of the benched room.
const TRIANGLES: usize = 100_000;

fn bench(c: &mut Criterion) {
    let scene = procedural::room_with_objects(TRIANGLES);
    let params = HierarchyParams::preview();
    let mut group = c.benchmark_group("hierarchy");
    group.sample_size(10);
    group.bench_function("solve_procedural_100k_preview", |b| {
        b.iter(|| hierarchy::solve(&scene, &params, &mut |_| {}).expect("the procedural scene is valid"))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
