//! Criterion bench of `radray info` (loading excluded): the geometry check and the element/form-factor
//! estimate on a ~100k-triangle procedural room, two-sided like real exported scenes, with the defects
//! the check looks for (furniture corners on tiled floor edges, spheres cutting into walls); and the
//! pairing of its triangles into quads that meshing and the element count run.
use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::Vec3;
use radray::scene::shapes::{box_faces, sphere_triangles};
use radray::scene::{self, lint};
use std::fmt::Write as _;
use std::hint::black_box;

/// Room side (scene units), tiles per wall side, spheres and their segments: 6·64²·2 = 49 152 wall
/// triangles, 12 spheres of 64·62 = 3 968 triangles, 24 blocks of 6 quads ≈ 97k surfaces.
const ROOM: f32 = 20.0;
const TILES: u32 = 64;
const SPHERES: u32 = 12;
const SPHERE_SEGMENTS: u32 = 64;
const BLOCKS: u32 = 24;

/// The room as OBJ text: tiled walls (triangles), blocks standing on the floor with corners on tile
/// edges (T-junctions), spheres touching or cutting into the walls (contacts and crossings).
fn room_obj() -> String {
    let mut obj = String::from("mtllib m.mtl\nusemtl white\n");
    let mut vertices = 0usize;
    let mut face = |obj: &mut String, corners: &[Vec3]| {
        for v in corners {
            writeln!(obj, "v {} {} {}", v.x, v.y, v.z).unwrap();
        }
        let ids: Vec<String> = (1..=corners.len()).map(|k| (vertices + k).to_string()).collect();
        writeln!(obj, "f {}", ids.join(" ")).unwrap();
        vertices += corners.len();
    };
    obj.push_str("o walls\n");
    let step = ROOM / TILES as f32;
    for wall in box_faces(Vec3::ZERO, Vec3::splat(ROOM), true) {
        let (o, u, v) = (wall[0], (wall[1] - wall[0]) / TILES as f32, (wall[3] - wall[0]) / TILES as f32);
        for j in 0..TILES {
            for i in 0..TILES {
                let p = |a: u32, b: u32| o + u * a as f32 + v * b as f32;
                face(&mut obj, &[p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                face(&mut obj, &[p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
    }
    obj.push_str("o blocks\n");
    for b in 0..BLOCKS {
        // A corner at half a tile: on a tile edge, inside it.
        let x = 1.0 + (b % 6) as f32 * 3.0 + 0.5 * step;
        let z = 2.0 + (b / 6) as f32 * 4.0;
        for quad in box_faces(Vec3::new(x, 0.0, z), Vec3::new(x + 1.5, 1.0 + 0.1 * b as f32, z + 1.0), false) {
            face(&mut obj, &quad);
        }
    }
    obj.push_str("o spheres\n");
    for s in 0..SPHERES {
        let radius = 1.0 + 0.05 * s as f32;
        // Alternately touching the x = 0 wall and sunk 0.1 into it.
        let sunk = if s % 2 == 0 { 0.0 } else { 0.1 };
        let centre = Vec3::new(radius - sunk, 2.0 + 1.4 * (s / 2) as f32 * 1.6, 3.0 + 6.0 * (s % 2) as f32);
        for (tri, _) in sphere_triangles(centre, radius, SPHERE_SEGMENTS) {
            face(&mut obj, &tri);
        }
    }
    obj
}

fn info(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("m.obj"), room_obj()).expect("write OBJ");
    std::fs::write(dir.path().join("m.mtl"), "newmtl white\nKd 0.5 0.5 0.5\nKe 1 1 1\n").expect("write MTL");
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, "[[mesh]]\nobj = \"m.obj\"\ntwo_sided = true\n").expect("write scene");
    let scene = scene::load(&path).expect("the procedural room loads");
    let report = lint::check(&scene);
    eprintln!(
        "procedural room: {} surfaces, {} candidate pairs, {} T-junctions, {} crossings",
        report.surface_count, report.candidate_pairs, report.t_junctions.count, report.intersections.count
    );
    let mut group = c.benchmark_group("info_room");
    group.sample_size(10);
    group.throughput(Throughput::Elements(scene.surfaces.len() as u64));
    group.bench_function("geometry_check", |b| b.iter(|| lint::check(black_box(&scene))));
    group.bench_function("describe", |b| b.iter(|| radray::info::describe(black_box(&scene))));
    // The tiles' triangle pairs meshed as quads (`mesh::pair_triangles`): the pairing alone, and the
    // element count that runs it before anything is meshed.
    group.bench_function("pair_triangles", |b| b.iter(|| radray::mesh::pair_triangles(black_box(&scene.surfaces))));
    let edge = scene.radiosity.max_element_edge;
    group.bench_function("count_elements", |b| b.iter(|| radray::mesh::count_elements(black_box(&scene), edge)));
    group.finish();
}

criterion_group!(benches, info);
criterion_main!(benches);
