//! Whole-pipeline benches on the shipped scenes: a small complete render (scene file → image) and the
//! issue's pass-two target, the specular Cornell box at 512×512 with 16 samples per pixel from an
//! already solved scene (pass two alone, each mode).

use criterion::{criterion_group, criterion_main, Criterion};
use radray::accel::Accel;
use radray::progress::Progress;
use radray::run::{self, RunStats};
use radray::scene::{Overrides, Quality};
use radray::trace::TraceMode;
use radray::transport::photons::RunPhotons;
use std::hint::black_box;
use std::path::Path;

fn scene_path(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn whole_small_render(c: &mut Criterion) {
    let progress = Progress::hidden();
    let overrides =
        Overrides { quality: Some(Quality::Preview), width_px: Some(128), height_px: Some(128), ..Default::default() };
    let mut group = c.benchmark_group("render");
    group.sample_size(10);
    group.bench_function("cornell_box preview 128x128 (parse, mesh, form factors, solve, trace)", |b| {
        b.iter(|| {
            let scene = run::load_scene(&scene_path("cornell_box.toml"), &overrides, &progress).unwrap();
            let mut stats = RunStats::default();
            let photons = RunPhotons::default();
            let (mesh, solution) = run::pass_one(&scene, None, &photons, &progress, &mut stats).unwrap();
            let accel = Accel::build(&mesh.positions, &mesh.triangles);
            black_box(
                run::render(&scene, &mesh, &accel, &solution, TraceMode::Final, &photons, &progress, &mut stats)
                    .unwrap(),
            )
        })
    });
    group.finish();
}

fn pass_two_specular_512(c: &mut Criterion) {
    let progress = Progress::hidden();
    let overrides =
        Overrides { width_px: Some(512), height_px: Some(512), samples_per_pixel: Some(16), ..Default::default() };
    let mut scene = run::load_scene(&scene_path("cornell_specular.toml"), &overrides, &progress).unwrap();
    let mut stats = RunStats::default();
    // The run's photons are traced once (by pass one) and shared by every render below.
    let photons = RunPhotons::default();
    let (mesh, solution) = run::pass_one(&scene, None, &photons, &progress, &mut stats).unwrap();
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let mut group = c.benchmark_group("pass two, cornell_specular 512x512 16 spp");
    group.sample_size(10);
    for (name, mode, direct) in [
        ("final (radiosity direct)", TraceMode::Final, radray::scene::DirectMode::Radiosity),
        ("final (pixel direct)", TraceMode::Final, radray::scene::DirectMode::Pixel),
        ("radiosity", TraceMode::Radiosity, radray::scene::DirectMode::Radiosity),
    ] {
        scene.render.direct = direct;
        group.bench_function(name, |b| {
            b.iter(|| {
                black_box(run::render(&scene, &mesh, &accel, &solution, mode, &photons, &progress, &mut stats).unwrap())
            })
        });
    }
    group.finish();
}

criterion_group!(benches, whole_small_render, pass_two_specular_512);
criterion_main!(benches);
