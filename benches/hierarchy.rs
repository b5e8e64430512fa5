//! Criterion bench of the hierarchical radiosity solver on a ~100k-triangle procedural room (spheres
//! and boxes, `hierarchy::procedural`), at preview settings; ten samples so that it runs in about a
//! minute on two cores.

use criterion::{criterion_group, criterion_main, Criterion};
use radray::radiosity::hierarchy::{self, procedural, HierarchyParams};

fn bench(c: &mut Criterion) {
    let scene = procedural::room_with_objects(100_000);
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
