//! Criterion bench of the hierarchy's element form-factor kernels (`radiosity::hierarchy::form_factor`),
//! which take a quarter to a half of a hierarchical solve's CPU (docs/performance.md): Lambert's
//! point-to-polygon form factor, the six-point rule of a far element pair, the 48-point rule of a
//! pair that shares an edge, and a subdivided source's four children seen from one point.

use criterion::{criterion_group, criterion_main, Criterion};
use glam::{vec3, Vec3};
use radray::radiosity::hierarchy::form_factor::{
    element_six_points, near_quadrature, point_to_polygon, point_to_quarters, point_to_source, Quarters, Source,
};
use radray::radiosity::hierarchy::nodes::quarters;
use std::hint::black_box;

fn bench(c: &mut Criterion) {
    // A floor triangle and a wall triangle that share the edge x = 0..1 on the z = 0 line.
    let floor = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0)];
    let wall = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)];
    // A ceiling triangle 2.5 above the floor, facing down.
    let ceiling = [vec3(0.2, 2.5, 0.2), vec3(0.9, 2.5, 0.2), vec3(0.2, 2.5, 0.9)];
    // Each case is one the kernels integrate (no early exit for a source seen from behind).
    assert!(point_to_polygon(vec3(0.3, 0.0, 0.3), Vec3::Y, &ceiling) > 0.0);
    assert!(near_quadrature(&floor, Vec3::Y, &wall) > 0.0);
    let mut group = c.benchmark_group("form_factor");
    group.bench_function("point_to_polygon", |b| {
        b.iter(|| point_to_polygon(black_box(vec3(0.3, 0.0, 0.3)), Vec3::Y, black_box(&ceiling)))
    });
    group.bench_function("six_points_far_pair", |b| {
        b.iter(|| element_six_points(black_box(&floor), Vec3::Y, black_box(&ceiling)))
    });
    group.bench_function("near_quadrature_shared_edge", |b| {
        b.iter(|| near_quadrature(black_box(&floor), Vec3::Y, black_box(&wall)))
    });
    // A subdivided source's four children read from one receiver point, one at a time and at once
    // (`source_weights::child_weights`).
    let parts = quarters(&ceiling);
    let singles = parts.each_ref().map(|q| Source::new(q));
    let together = Quarters::new(&parts).expect("one triangle's quarters");
    let point = vec3(0.3, 0.0, 0.3);
    group.bench_function("four_children_one_at_a_time", |b| {
        b.iter(|| singles.each_ref().map(|q| point_to_source(black_box(point), Vec3::Y, q)))
    });
    group.bench_function("four_children_at_once", |b| {
        b.iter(|| point_to_quarters(black_box(point), Vec3::Y, black_box(&together)))
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
