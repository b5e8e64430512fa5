//! Criterion benches of the hemicube stage: one hemicube in the Cornell box (hemicubes/s, with
//! pixels/s as throughput) at N = 128 and 256, and a full form-factor matrix of a coarse Cornell box.
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use radray::mesh::Mesh;
use radray::radiosity::form_factors::{compute, ElementHierarchy};
use radray::radiosity::hemicube::{Hemicube, ItemBuffer};
use radray::scene::{
    Camera, ImageSettings, Material, RadiosityParams, RenderParams, SceneDescription, SourceLoc, Surface,
};

/// The Cornell box (published coordinates, mm; light lowered to y = 548.7; open front), copied from
/// the reference scene.obj: (material, quad) with 0 white, 1 red, 2 green, 3 light.
const CORNELL: &[(u32, [[f32; 3]; 4])] = &[
    (0, [[552.8, 0.0, 0.0], [0.0, 0.0, 0.0], [0.0, 0.0, 559.2], [549.6, 0.0, 559.2]]),
    (0, [[556.0, 548.8, 0.0], [556.0, 548.8, 559.2], [0.0, 548.8, 559.2], [0.0, 548.8, 0.0]]),
    (0, [[549.6, 0.0, 559.2], [0.0, 0.0, 559.2], [0.0, 548.8, 559.2], [556.0, 548.8, 559.2]]),
    (1, [[552.8, 0.0, 0.0], [549.6, 0.0, 559.2], [556.0, 548.8, 559.2], [556.0, 548.8, 0.0]]),
    (2, [[0.0, 0.0, 559.2], [0.0, 0.0, 0.0], [0.0, 548.8, 0.0], [0.0, 548.8, 559.2]]),
    (3, [[343.0, 548.7, 227.0], [343.0, 548.7, 332.0], [213.0, 548.7, 332.0], [213.0, 548.7, 227.0]]),
    (0, [[130.0, 165.0, 65.0], [82.0, 165.0, 225.0], [240.0, 165.0, 272.0], [290.0, 165.0, 114.0]]),
    (0, [[290.0, 0.0, 114.0], [290.0, 165.0, 114.0], [240.0, 165.0, 272.0], [240.0, 0.0, 272.0]]),
    (0, [[130.0, 0.0, 65.0], [130.0, 165.0, 65.0], [290.0, 165.0, 114.0], [290.0, 0.0, 114.0]]),
    (0, [[82.0, 0.0, 225.0], [82.0, 165.0, 225.0], [130.0, 165.0, 65.0], [130.0, 0.0, 65.0]]),
    (0, [[240.0, 0.0, 272.0], [240.0, 165.0, 272.0], [82.0, 165.0, 225.0], [82.0, 0.0, 225.0]]),
    (0, [[423.0, 330.0, 247.0], [265.0, 330.0, 296.0], [314.0, 330.0, 456.0], [472.0, 330.0, 406.0]]),
    (0, [[423.0, 0.0, 247.0], [423.0, 330.0, 247.0], [472.0, 330.0, 406.0], [472.0, 0.0, 406.0]]),
    (0, [[472.0, 0.0, 406.0], [472.0, 330.0, 406.0], [314.0, 330.0, 456.0], [314.0, 0.0, 456.0]]),
    (0, [[314.0, 0.0, 456.0], [314.0, 330.0, 456.0], [265.0, 330.0, 296.0], [265.0, 0.0, 296.0]]),
    (0, [[265.0, 0.0, 296.0], [265.0, 330.0, 296.0], [423.0, 330.0, 247.0], [423.0, 0.0, 247.0]]),
];

fn cornell_box() -> SceneDescription {
    let mut light = Material::diffuse("light", Vec3::ZERO);
    light.emitted_radiance = Vec3::new(17.0, 12.0, 4.0);
    SceneDescription {
        path: "cornell.obj".into(),
        camera: Camera {
            eye: Vec3::new(278.0, 273.0, -800.0),
            look_at: Vec3::new(278.0, 273.0, 0.0),
            up: Vec3::Y,
            vfov_deg: 39.3,
        },
        image: ImageSettings::default(),
        radiosity: RadiosityParams::default(),
        render: RenderParams::default(),
        materials: vec![
            Material::diffuse("white", Vec3::new(0.725, 0.71, 0.68)),
            Material::diffuse("red", Vec3::new(0.63, 0.065, 0.05)),
            Material::diffuse("green", Vec3::new(0.14, 0.45, 0.091)),
            light,
        ],
        surfaces: CORNELL
            .iter()
            .map(|(material, quad)| Surface {
                vertices: quad.iter().map(|&v| Vec3::from(v)).collect(),
                material: *material,
                two_sided: false,
                shading_normals: None,
                object: "cornell".into(),
                source: SourceLoc::default(),
            })
            .collect(),
        warnings: Vec::new(),
    }
}

/// One hemicube from a floor element near the middle of the room, at the meshing of the target run
/// (max edge 14 mm: 10,096 elements). Time per iteration = 1 / (hemicubes/s); throughput = pixels/s.
fn one_hemicube(c: &mut Criterion) {
    let mesh = Mesh::build(&cornell_box(), 14.0);
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
    let mesh = Mesh::build(&cornell_box(), 100.0);
    let params = RadiosityParams { hemicube_resolution_px: 64, ..Default::default() };
    let mut group = c.benchmark_group("form_factor_matrix_cornell_100mm");
    group.sample_size(10);
    group.throughput(Throughput::Elements(mesh.elements.len() as u64));
    group.bench_function("N64", |b| b.iter(|| black_box(compute(&mesh, &params, &|| {}).nnz())));
    group.finish();
}

criterion_group!(benches, one_hemicube, full_matrix);
criterion_main!(benches);
