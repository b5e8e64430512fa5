//! Criterion benches for the trace stage: BVH build, closest-hit and any-hit ray throughput, and the
//! Whitted tracer per sample, on a generated Cornell-like box (mm) holding a mirror sphere and a glass
//! sphere, about 20k triangles. Everything is generated here; nothing is read from disk.

#[path = "../tests/common/mod.rs"]
mod common;

use std::f32::consts::PI;
use std::hint::black_box;
use std::time::Instant;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{vec3, Vec3};
use radray::accel::Accel;
use radray::film::Sampler;
use radray::mesh::Mesh;
use radray::radiosity::solution::Solution;
use radray::rng::Pcg32;
use radray::scene::{DirectMode, RenderParams, SceneDescription, Surface};
use radray::trace::{PinholeCamera, RayCounts, TraceMode, Tracer};

const ROOM_CENTRE: Vec3 = Vec3::new(278.0, 274.0, 280.0);

fn surface(mut vertices: Vec<Vec3>, material: u32, inside_point: Option<Vec3>, outward_from: Option<Vec3>) -> Surface {
    // Orient the polygon: towards `inside_point` (room walls) or away from `outward_from` (spheres).
    let n = (vertices[1] - vertices[0]).cross(vertices[2] - vertices[0]);
    let c = vertices.iter().copied().sum::<Vec3>() / vertices.len() as f32;
    let flip = match (inside_point, outward_from) {
        (Some(p), _) => n.dot(p - c) < 0.0,
        (_, Some(o)) => n.dot(c - o) < 0.0,
        _ => false,
    };
    if flip {
        vertices.reverse();
    }
    common::surface(vertices, material, false)
}

/// A UV sphere of `rings` × `segments`: quads, with triangles at the poles.
fn sphere(centre: Vec3, radius: f32, rings: u32, segments: u32, material: u32, out: &mut Vec<Surface>) {
    let point = |i: u32, j: u32| {
        let theta = PI * i as f32 / rings as f32;
        let phi = 2.0 * PI * j as f32 / segments as f32;
        centre + radius * vec3(theta.sin() * phi.cos(), theta.cos(), theta.sin() * phi.sin())
    };
    for i in 0..rings {
        for j in 0..segments {
            let (a, b, c, d) = (point(i, j), point(i, j + 1), point(i + 1, j + 1), point(i + 1, j));
            let polygon = if i == 0 {
                vec![a, c, d]
            } else if i + 1 == rings {
                vec![a, b, c]
            } else {
                vec![a, b, c, d]
            };
            out.push(surface(polygon, material, None, Some(centre)));
        }
    }
}

fn cornell_spheres() -> SceneDescription {
    let mut materials = common::cornell_materials();
    materials.extend([common::mirror("mirror", 0.9), common::glass("glass")]);
    let q = |a: [f32; 3], b: [f32; 3], c: [f32; 3], d: [f32; 3]| vec![a.into(), b.into(), c.into(), d.into()];
    let room = Some(ROOM_CENTRE);
    let mut surfaces = vec![
        surface(q([0., 0., 0.], [556., 0., 0.], [556., 0., 559.], [0., 0., 559.]), 0, room, None),
        surface(q([0., 548.8, 0.], [556., 548.8, 0.], [556., 548.8, 559.], [0., 548.8, 559.]), 0, room, None),
        surface(q([0., 0., 559.], [556., 0., 559.], [556., 548.8, 559.], [0., 548.8, 559.]), 0, room, None),
        surface(q([556., 0., 0.], [556., 0., 559.], [556., 548.8, 559.], [556., 548.8, 0.]), 1, room, None),
        surface(q([0., 0., 0.], [0., 0., 559.], [0., 548.8, 559.], [0., 548.8, 0.]), 2, room, None),
        surface(q([213., 548.7, 227.], [343., 548.7, 227.], [343., 548.7, 332.], [213., 548.7, 332.]), 3, room, None),
    ];
    sphere(vec3(185.0, 100.0, 170.0), 100.0, 50, 100, 4, &mut surfaces);
    sphere(vec3(380.0, 100.0, 360.0), 100.0, 50, 100, 5, &mut surfaces);
    SceneDescription { camera: common::cornell_camera(), ..common::scene(materials, surfaces) }
}

/// A plausible hand-made solution: B = E + ρ·100, direct part ρ·60.
fn fake_solution(mesh: &Mesh) -> Solution {
    let e = &mesh.elements;
    let b: Vec<Vec3> = (0..e.len()).map(|i| e.emission[i] + e.reflectance[i] * 100.0).collect();
    let bd: Vec<Vec3> = e.reflectance.iter().map(|r| *r * 60.0).collect();
    common::solution(mesh, b, bd)
}

fn camera_rays(scene: &SceneDescription, size_px: u32) -> Vec<(Vec3, Vec3)> {
    let camera = PinholeCamera::new(&scene.camera, size_px, size_px);
    let mut rng = Pcg32::new(5, 0);
    (0..size_px * size_px)
        .map(|i| {
            let r = camera.ray((i % size_px) as f32 + rng.next_f32(), (i / size_px) as f32 + rng.next_f32());
            (r.origin, r.dir)
        })
        .collect()
}

/// Rays between random points inside the room (diffuse-bounce-like, incoherent).
fn incoherent_rays(count: usize) -> Vec<(Vec3, Vec3)> {
    let mut rng = Pcg32::new(9, 1);
    let mut point = || vec3(rng.next_f32() * 556.0, rng.next_f32() * 548.0, rng.next_f32() * 559.0);
    (0..count)
        .map(|_| {
            let o = point();
            (o, (point() - o).normalize_or(Vec3::Y))
        })
        .collect()
}

/// CPU time of the calling thread (seconds), from /proc (Linux; clock ticks of 1/100 s): on a machine
/// shared with other jobs, wall time overstates the cost.
fn thread_cpu_seconds() -> Option<f64> {
    let stat = std::fs::read_to_string("/proc/thread-self/stat").ok()?;
    let fields: Vec<&str> = stat.rsplit_once(')')?.1.split_whitespace().collect();
    let ticks: f64 = fields.get(11)?.parse::<f64>().ok()? + fields.get(12)?.parse::<f64>().ok()?;
    Some(ticks / 100.0)
}

/// Runs `f` (which traces `rays_per_call` rays) repeatedly for about a second of CPU time and prints
/// rays per CPU second.
fn report_cpu_rate(name: &str, rays_per_call: u64, mut f: impl FnMut()) {
    let (Some(start), wall) = (thread_cpu_seconds(), Instant::now()) else {
        return;
    };
    let mut calls = 0u64;
    let mut cpu = 0.0;
    while cpu < 1.0 && wall.elapsed().as_secs_f64() < 20.0 {
        f();
        calls += 1;
        cpu = thread_cpu_seconds().unwrap_or(start) - start;
    }
    if cpu > 0.0 {
        eprintln!("{name}: {:.2} M rays per CPU second", (calls * rays_per_call) as f64 / cpu / 1e6);
    }
}

fn bench_trace(c: &mut Criterion) {
    let scene = cornell_spheres();
    let mesh = Mesh::build(&scene, f32::INFINITY);
    eprintln!("bench scene: {} triangles, {} elements", mesh.triangles.len(), mesh.elements.len());

    let mut group = c.benchmark_group("accel");
    group.throughput(Throughput::Elements(mesh.triangles.len() as u64));
    group.bench_function("build_cwbvh", |b| b.iter(|| Accel::build(black_box(&mesh.positions), &mesh.triangles)));

    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let primary = camera_rays(&scene, 256);
    group.throughput(Throughput::Elements(primary.len() as u64));
    let trace_all = |rays: &[(Vec3, Vec3)]| {
        black_box(rays.iter().filter(|(o, d)| accel.closest_hit(*o, *d, 0.0, f32::INFINITY).is_some()).count());
    };
    report_cpu_rate("closest_hit_camera_rays", primary.len() as u64, || trace_all(&primary));
    group.bench_function("closest_hit_camera_rays", |b| {
        b.iter(|| primary.iter().filter(|(o, d)| accel.closest_hit(*o, *d, 0.0, f32::INFINITY).is_some()).count())
    });
    let incoherent = incoherent_rays(65_536);
    group.throughput(Throughput::Elements(incoherent.len() as u64));
    report_cpu_rate("closest_hit_incoherent_rays", incoherent.len() as u64, || trace_all(&incoherent));
    report_cpu_rate("occluded_incoherent_rays", incoherent.len() as u64, || {
        black_box(incoherent.iter().filter(|(o, d)| accel.occluded(*o, *d, 300.0)).count());
    });
    group.bench_function("closest_hit_incoherent_rays", |b| {
        b.iter(|| incoherent.iter().filter(|(o, d)| accel.closest_hit(*o, *d, 0.0, f32::INFINITY).is_some()).count())
    });
    group.bench_function("occluded_incoherent_rays", |b| {
        b.iter(|| incoherent.iter().filter(|(o, d)| accel.occluded(*o, *d, 300.0)).count())
    });
    group.finish();

    // The whole tracer per film sample: 128 × 128 pixels, one sample each.
    let solution = fake_solution(&mesh);
    let samples = camera_rays(&scene, 128);
    let mut group = c.benchmark_group("whitted");
    group.throughput(Throughput::Elements(samples.len() as u64));
    for (name, direct) in [("final_radiosity_direct", DirectMode::Radiosity), ("final_pixel_direct", DirectMode::Pixel)]
    {
        let params = RenderParams { direct, ..RenderParams::default() };
        let tracer = Tracer::new(&mesh, &accel, &solution, &scene.materials, &params).expect("consistent");
        // Rays per sample, reported once (criterion reports samples/s).
        let mut counts = RayCounts::default();
        for (i, (o, d)) in samples.iter().enumerate() {
            let mut sampler = Sampler::independent(0, i as u64);
            black_box(tracer.radiance(*o, *d, TraceMode::Final, &mut sampler, &mut counts));
        }
        eprintln!("{name}: {:.3} rays/sample ({counts:?})", counts.total() as f64 / samples.len() as f64);
        report_cpu_rate(name, counts.total(), || {
            let mut counts = RayCounts::default();
            for (i, (o, d)) in samples.iter().enumerate() {
                let mut sampler = Sampler::independent(0, i as u64);
                black_box(tracer.radiance(*o, *d, TraceMode::Final, &mut sampler, &mut counts));
            }
        });
        group.bench_function(name, |b| {
            b.iter(|| {
                let mut counts = RayCounts::default();
                let mut sum = Vec3::ZERO;
                for (i, (o, d)) in samples.iter().enumerate() {
                    let mut sampler = Sampler::independent(0, i as u64);
                    sum += tracer.radiance(*o, *d, TraceMode::Final, &mut sampler, &mut counts);
                }
                sum
            })
        });
    }
    group.finish();
}

criterion_group!(benches, bench_trace);
criterion_main!(benches);
