//! Criterion benches of the hemicube stage: one hemicube in the Cornell box (hemicubes/s, with
//! pixels/s as throughput) at N = 128 and 256, and a full form-factor matrix of a coarse Cornell box.

#[path = "../tests/common/mod.rs"]
mod common;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use radray::mesh::Mesh;
use radray::radiosity::form_factors::{compute, ElementHierarchy};
use radray::radiosity::hemicube::{Hemicube, ItemBuffer};
use radray::scene::RadiosityParams;

/// One hemicube from a floor element near the middle of the room, at the meshing of the target run
/// (max edge 14 mm: 10,096 elements). Time per iteration = 1 / (hemicubes/s); throughput = pixels/s.
fn one_hemicube(c: &mut Criterion) {
    let mesh = Mesh::build(&common::cornell(), 14.0);
    let hierarchy = ElementHierarchy::new(&mesh);
    let e = &mesh.elements;
    let target = Vec3::new(278.0, 0.0, 400.0);
    let element = (0..e.len())
        .filter(|&i| e.surface[i] == 0)
        .min_by(|&a, &b| (e.centre[a] - target).length().total_cmp(&(e.centre[b] - target).length()))
        .expect("the floor has elements");
    let mut group = c.benchmark_group("one_hemicube_cornell_10k_elements");
    for n in [128u32, 256] {
        let params = RadiosityParams { hemicube_resolution_px: n, ..Default::default() };
        let hc = Hemicube::new(n);
        let mut buffers = ItemBuffer::new(&hc);
        let mut row = Vec::new();
        group.throughput(Throughput::Elements(hc.pixel_count() as u64));
        group.bench_with_input(BenchmarkId::from_parameter(n), &n, |b, _| {
            b.iter(|| {
                row.clear();
                hierarchy.element_row(&mesh, &params, &hc, &mut buffers, black_box(element), &mut row);
                black_box(row.len())
            })
        });
    }
    group.finish();
}

/// The whole matrix of a coarse Cornell box (max edge 100 mm) at N = 64, on all threads.
fn full_matrix(c: &mut Criterion) {
    let mesh = Mesh::build(&common::cornell(), 100.0);
    let params = RadiosityParams { hemicube_resolution_px: 64, ..Default::default() };
    let mut group = c.benchmark_group("form_factor_matrix_cornell_100mm");
    group.sample_size(10);
    group.throughput(Throughput::Elements(mesh.elements.len() as u64));
    group.bench_function("N64", |b| b.iter(|| black_box(compute(&mesh, &params, &|| {}).nnz())));
    group.finish();
}

criterion_group!(benches, one_hemicube, full_matrix);
criterion_main!(benches);
