//! Specification tests of pass two: the camera's conventions and the Whitted tracer on small hand-built
//! scenes with hand-made radiosity solutions. (The accelerator's tests live beside it, in `src/accel.rs`.)

mod common;

use std::f32::consts::PI;

use common::{cornell_camera, emitter, glass, mirror, scene, solution, surface, z_quad, Setup};
use glam::{vec3, Vec3};
use radray::accel::Accel;
use radray::film::Sampler;
use radray::mesh::Mesh;
use radray::rng::Pcg32;
use radray::scene::{Camera, DirectMode, Material, RenderParams, Surface};
use radray::trace::{PinholeCamera, RayCounts, TraceMode, Tracer};

// ---------------------------------------------------------------------------------------------
// Helpers
// ---------------------------------------------------------------------------------------------

fn random_vec(rng: &mut Pcg32) -> Vec3 {
    vec3(rng.next_f32(), rng.next_f32(), rng.next_f32())
}

fn random_unit(rng: &mut Pcg32) -> Vec3 {
    loop {
        let v = random_vec(rng) * 2.0 - Vec3::ONE;
        let l = v.length();
        if l > 0.1 && l <= 1.0 {
            return v / l;
        }
    }
}

/// Element exitance for a scene whose surfaces are single elements: `per_surface[s]` for surface s.
fn per_surface(mesh: &Mesh, values: &[Vec3]) -> Vec<Vec3> {
    mesh.elements.surface.iter().map(|&s| values[s as usize]).collect()
}

fn trace(tracer: &Tracer, origin: Vec3, dir: Vec3, mode: TraceMode) -> Vec3 {
    let mut sampler = Sampler::independent(1, 2);
    let mut counts = RayCounts::default();
    tracer.radiance(origin, dir, mode, &mut sampler, &mut counts)
}

/// |a − b| ≤ tol·max(|b|, 1) per channel.
fn assert_close(a: Vec3, b: Vec3, tol: f32, what: &str) {
    let ok = (a - b).abs().cmple(Vec3::splat(tol) * b.abs().max(Vec3::ONE)).all();
    assert!(ok, "{what}: got {a}, expected {b} (tolerance {tol})");
}

// ---------------------------------------------------------------------------------------------
// Camera
// ---------------------------------------------------------------------------------------------

#[test]
fn centre_of_the_film_looks_at_look_at() {
    let camera = Camera { eye: vec3(1.0, 2.0, 3.0), look_at: vec3(-2.0, 0.5, 7.0), up: Vec3::Y, vfov_deg: 50.0 };
    let pinhole = PinholeCamera::new(&camera, 320, 240);
    let ray = pinhole.ray(160.0, 120.0);
    let expected = (camera.look_at - camera.eye).normalize();
    // Normalised f32 vectors: a few ulps.
    assert!((ray.dir - expected).length() < 1e-6, "{} vs {expected}", ray.dir);
    assert_eq!(ray.origin, camera.eye);
}

#[test]
fn red_wall_is_on_the_left_of_the_cornell_image() {
    // The Cornell box's red wall is at x ≈ 550 and the camera looks down +z: image-right =
    // forward × up = −x, so small film x must look towards +x.
    let pinhole = PinholeCamera::new(&cornell_camera(), 512, 512);
    assert!((pinhole.right() - Vec3::NEG_X).length() < 1e-6);
    let left = pinhole.ray(0.5, 256.0);
    assert!(left.dir.dot(pinhole.right()) < 0.0);
    assert!(left.dir.x > 0.0, "looks towards the red wall at +x");
    // And the top row looks up.
    assert!(pinhole.ray(256.0, 0.5).dir.y > 0.0);
}

#[test]
fn vertical_field_of_view_spans_the_film_height() {
    let pinhole = PinholeCamera::new(&cornell_camera(), 400, 200);
    let forward = pinhole.forward();
    let top = pinhole.ray(200.0, 0.0).dir;
    let bottom = pinhole.ray(200.0, 200.0).dir;
    let full_deg = top.angle_between(bottom).to_degrees();
    // acos of f32 dot products near 1 loses ~1e-3 degrees.
    assert!((full_deg - 39.307_648).abs() < 2e-3, "{full_deg}");
    assert!((top.angle_between(forward) - bottom.angle_between(forward)).abs() < 1e-5);
    // Square pixels: the horizontal extent is aspect × the vertical one at unit distance.
    let right_edge = pinhole.ray(400.0, 100.0).dir;
    let top_edge = pinhole.ray(200.0, 0.0).dir;
    let h = (right_edge.dot(pinhole.right()) / right_edge.dot(forward))
        / (top_edge.dot(pinhole.up()) / top_edge.dot(forward));
    assert!((h - 2.0).abs() < 1e-5, "{h}");
}

// ---------------------------------------------------------------------------------------------
// Whitted tracer
// ---------------------------------------------------------------------------------------------

#[test]
fn emitter_seen_directly_is_exactly_ke_in_every_mode() {
    let ke = vec3(17.0, 12.0, 4.0);
    let scene = scene(vec![emitter("light", ke)], vec![z_quad(0.0, 1.0, true, 0, false)]);
    let setup = Setup::hand_made(&scene, 0.5, |mesh| {
        let e = mesh.elements.emission.clone();
        (e, vec![Vec3::ZERO; mesh.elements.len()])
    });
    for direct in [DirectMode::Radiosity, DirectMode::Pixel] {
        let params = RenderParams { direct, ..RenderParams::default() };
        let tracer = setup.tracer_with(&params);
        for mode in [TraceMode::Final, TraceMode::Radiosity] {
            let l = trace(&tracer, vec3(0.3, -0.2, 2.0), vec3(-0.1, 0.2, -1.0), mode);
            // E = π·Ke then B/π: two f32 roundings, ≤ 2 ulps (2.4e-7 relative).
            assert!((l - ke).abs().cmple(ke * 2.4e-7).all(), "{direct:?} {mode:?}: {l} vs {ke}");
        }
    }
}

#[test]
fn back_face_of_one_sided_surface_is_black_and_two_sided_shows_its_back() {
    let white = Material::diffuse("white", Vec3::splat(0.5));
    let front_exitance = vec3(1.0, 2.0, 3.0);
    let back_exitance = vec3(0.5, 0.25, 0.125);
    for two_sided in [false, true] {
        let scene = scene(vec![white.clone()], vec![z_quad(0.0, 1.0, true, 0, two_sided)]);
        let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
            // Element 0 is the front side, element 1 (if any) the back side.
            let b: Vec<Vec3> =
                (0..mesh.elements.len()).map(|e| if e == 0 { front_exitance } else { back_exitance }).collect();
            (b, vec![Vec3::ZERO; mesh.elements.len()])
        });
        let tracer = setup.tracer();
        for mode in [TraceMode::Final, TraceMode::Radiosity] {
            let front = trace(&tracer, vec3(0.1, 0.1, 1.0), Vec3::NEG_Z, mode);
            let back = trace(&tracer, vec3(0.1, 0.1, -1.0), Vec3::Z, mode);
            // One rounding of B/π.
            assert_close(front, front_exitance / PI, 1e-6, "front");
            if two_sided {
                assert_close(back, back_exitance / PI, 1e-6, "back of a two-sided surface");
            } else {
                assert_eq!(back, Vec3::ZERO, "back of a one-sided surface must be black ({mode:?})");
            }
        }
    }
}

#[test]
fn mirror_shows_ks_times_the_reflected_surface() {
    let mirror = mirror("mirror", 0.9);
    let wall = Material::diffuse("wall", Vec3::splat(0.5));
    let wall_radiance = vec3(1.0, 2.0, 3.0);
    // Mirror in z = 0 facing +z; wall in x = 3 facing −x.
    let wall_surface = surface(
        [vec3(3.0, -10.0, -10.0), vec3(3.0, -10.0, 10.0), vec3(3.0, 10.0, 10.0), vec3(3.0, 10.0, -10.0)],
        1,
        false,
    );
    let scene = scene(vec![mirror, wall], vec![z_quad(0.0, 10.0, true, 0, false), wall_surface]);
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        (per_surface(mesh, &[Vec3::ZERO, wall_radiance * PI]), vec![Vec3::ZERO; mesh.elements.len()])
    });
    let tracer = setup.tracer();
    let dir = vec3(1.0, 0.0, -1.0).normalize();
    let l = trace(&tracer, vec3(0.0, 0.0, 1.0), dir, TraceMode::Final);
    // 0.9 × B/π: three f32 roundings.
    assert_close(l, 0.9 * wall_radiance, 1e-6, "mirror");
    // The radiosity view sees only the mirror's own (zero) radiosity.
    assert_eq!(trace(&tracer, vec3(0.0, 0.0, 1.0), dir, TraceMode::Radiosity), Vec3::ZERO);
    // Seen from behind, a one-sided mirror is black.
    assert_eq!(trace(&tracer, vec3(0.0, 0.0, -1.0), -dir, TraceMode::Final), Vec3::ZERO);
}

#[test]
fn glass_slab_transmits_the_multiple_reflection_series() {
    let glass = glass("glass");
    let ke = vec3(1.0, 2.0, 4.0);
    // Slab between z = −0.1 and z = 0 (outward normals ±z), emitter at z = −1 facing the slab.
    let scene = scene(
        vec![glass, emitter("light", ke)],
        vec![
            z_quad(0.0, 10.0, true, 0, false),
            z_quad(-0.1, 10.0, false, 0, false),
            z_quad(-1.0, 10.0, true, 1, false),
        ],
    );
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        (mesh.elements.emission.clone(), vec![Vec3::ZERO; mesh.elements.len()])
    });
    let params = RenderParams::default();
    let tracer = setup.tracer_with(&params);
    let l = trace(&tracer, vec3(0.5, 0.5, 1.0), Vec3::NEG_Z, TraceMode::Final);
    // Normal incidence: R = 0.04 per face; light crossing the slab after 2k internal reflections
    // carries (1−R)²R^(2k), in all (1−R)²/(1−R²). With max_depth 8 and min_throughput 1e-3 the tracer
    // keeps k ≤ 1 (the k = 2 path falls below 1e-3 of throughput), dropping
    // (1−R)²R⁴/(1−R²) = 2.4e-6 of it; f32 arithmetic adds ~1e-6.
    let r = 0.04f32;
    let expected = (1.0 - r) * (1.0 - r) / (1.0 - r * r);
    let dropped = (1.0 - r) * (1.0 - r) * r.powi(4) / (1.0 - r * r);
    let transmitted = l / ke;
    for c in transmitted.to_array() {
        assert!((c - (expected - dropped)).abs() <= 1e-6, "transmitted {c}, expected {expected} − {dropped}");
    }
    // The pure radiosity view sees the glass's zero radiosity.
    assert_eq!(trace(&tracer, vec3(0.5, 0.5, 1.0), Vec3::NEG_Z, TraceMode::Radiosity), Vec3::ZERO);
}

#[test]
fn total_internal_reflection_keeps_light_inside_glass() {
    // A ray inside a slab hitting its face beyond the critical angle (41.8°) is reflected
    // completely: the emitter behind that face stays invisible along the refracted direction.
    let glass = glass("glass");
    let scene = scene(
        vec![glass, emitter("light", Vec3::ONE)],
        vec![
            z_quad(0.0, 10.0, true, 0, false),
            z_quad(-1.0, 10.0, false, 0, false),
            z_quad(1.0, 50.0, false, 1, false),
        ],
    );
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        (mesh.elements.emission.clone(), vec![Vec3::ZERO; mesh.elements.len()])
    });
    let params = RenderParams { max_depth: 1, ..RenderParams::default() };
    let tracer = setup.tracer_with(&params);
    // From inside the slab at 60° from the normal, upwards: TIR at z = 0; one bounce allowed, so the
    // reflected ray hits the slab's lower face and nothing reaches the emitter above.
    let theta = 60f32.to_radians();
    let l = trace(&tracer, vec3(0.0, 0.0, -0.5), vec3(theta.sin(), 0.0, theta.cos()), TraceMode::Final);
    assert_eq!(l, Vec3::ZERO);
    // At 20° (below the critical angle) light gets in: 1 − R of the emitter's radiance, times n² = 2.25
    // (L/n² is what a path conserves: radiance inside the glass is n² that outside).
    let theta = 20f32.to_radians();
    let l = trace(&tracer, vec3(0.0, 0.0, -0.5), vec3(theta.sin(), 0.0, theta.cos()), TraceMode::Final);
    let expected = (1.0 - radray::transport::optics::fresnel_dielectric(theta.cos(), 1.5, 1.0)) * 2.25;
    assert!((l.x - expected).abs() < 1e-5, "{} vs {expected}", l.x);
}

#[test]
fn diffuse_only_scene_renders_the_same_in_both_modes() {
    // Closed unit cube seen from inside, every face diffuse with a different exitance per element.
    let white = Material::diffuse("white", Vec3::splat(0.5));
    let p = |x: f32, y: f32, z: f32| vec3(x, y, z);
    let faces = [
        [p(0., 0., 0.), p(1., 0., 0.), p(1., 0., 1.), p(0., 0., 1.)], // floor
        [p(0., 1., 0.), p(0., 1., 1.), p(1., 1., 1.), p(1., 1., 0.)], // ceiling
        [p(0., 0., 0.), p(0., 0., 1.), p(0., 1., 1.), p(0., 1., 0.)], // x = 0
        [p(1., 0., 0.), p(1., 1., 0.), p(1., 1., 1.), p(1., 0., 1.)], // x = 1
        [p(0., 0., 0.), p(0., 1., 0.), p(1., 1., 0.), p(1., 0., 0.)], // z = 0
        [p(0., 0., 1.), p(1., 0., 1.), p(1., 1., 1.), p(0., 1., 1.)], // z = 1
    ];
    // Listed clockwise seen from inside: reverse them so that they face into the cube.
    let surfaces: Vec<Surface> = faces.into_iter().map(|[a, b, c, d]| surface([a, d, c, b], 0, false)).collect();
    let scene = scene(vec![white], surfaces);
    let setup = Setup::hand_made(&scene, 0.25, |mesh| {
        let b = mesh.elements.centre.iter().map(|c| *c + Vec3::splat(0.5)).collect();
        (b, vec![Vec3::ZERO; mesh.elements.len()])
    });
    let params = RenderParams::default();
    let tracer = setup.tracer_with(&params);
    for (e, &n) in setup.mesh.elements.normal.iter().enumerate() {
        assert!(n.dot(Vec3::splat(0.5) - setup.mesh.elements.centre[e]) > 0.0, "every face looks into the cube");
    }
    let mut rng = Pcg32::new(3, 9);
    let mut counts = RayCounts::default();
    for _ in 0..2000 {
        let origin = Vec3::splat(0.1) + random_vec(&mut rng) * 0.8;
        let dir = random_unit(&mut rng);
        let a = tracer.radiance(origin, dir, TraceMode::Final, &mut Sampler::Independent(rng.clone()), &mut counts);
        let b = tracer.radiance(origin, dir, TraceMode::Radiosity, &mut Sampler::Independent(rng.clone()), &mut counts);
        assert_eq!(a, b, "ray {origin} {dir}");
        assert!(a.min_element() > 0.0, "a closed box has no escape: {a}");
    }
    assert_eq!(counts, RayCounts { primary: 4000, secondary: 0, shadow: 0 });
}

#[test]
fn pixel_direct_light_matches_the_radiosity_direct_part_on_average() {
    // Floor [−1,1]² at y = 0 facing up (ρ = 0.5, one element) under an emitter of the same size at
    // y = 1 facing down. The floor's first-bounce exitance is ρ·F·E with F the analytic form factor of
    // directly opposed squares, X = Y = 2 (Howell C-11; tests/data/polygon_to_polygon.json case
    // pp_parallel_1x1_sep0p5): F = 0.415253283577.
    let rho = 0.5f32;
    let ke = vec3(2.0, 3.0, 4.0);
    let floor = surface([vec3(-1., 0., -1.), vec3(-1., 0., 1.), vec3(1., 0., 1.), vec3(1., 0., -1.)], 0, false);
    let light = surface([vec3(-1., 1., -1.), vec3(1., 1., -1.), vec3(1., 1., 1.), vec3(-1., 1., 1.)], 1, false);
    let scene = scene(vec![Material::diffuse("floor", Vec3::splat(rho)), emitter("light", ke)], vec![floor, light]);
    let form_factor = 0.415_253_28f32;
    let floor_direct = rho * form_factor * ke * PI;
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        let b = per_surface(mesh, &[floor_direct, ke * PI]);
        let bd = per_surface(mesh, &[floor_direct, Vec3::ZERO]);
        (b, bd)
    });
    assert_eq!(setup.mesh.elements.len(), 2);
    let params = RenderParams { direct: DirectMode::Pixel, light_samples: 4, ..RenderParams::default() };
    let tracer = setup.tracer_with(&params);
    assert!((tracer.emitter_area() - 4.0).abs() < 1e-6);

    // Average the per-pixel estimate over uniformly spread points of the floor.
    let mut sampler = Sampler::independent(11, 0);
    let mut counts = RayCounts::default();
    let n = 20_000;
    let (mut sum, mut sum2) = (0.0f64, 0.0f64);
    for _ in 0..n {
        let origin = vec3(sampler.next_1d() * 2.0 - 1.0, 0.5, sampler.next_1d() * 2.0 - 1.0);
        let l = tracer.radiance(origin, Vec3::NEG_Y, TraceMode::Final, &mut sampler, &mut counts);
        // The three channels scale with Ke: compare one.
        assert!((l.y / l.x - 1.5).abs() < 1e-4 && (l.z / l.x - 2.0).abs() < 1e-4);
        sum += l.x as f64;
        sum2 += (l.x as f64).powi(2);
    }
    let mean = sum / n as f64;
    let std_err = ((sum2 / n as f64 - mean * mean) / n as f64).sqrt();
    let expected = (floor_direct.x / PI) as f64;
    // Monte Carlo: four standard errors of the mean (estimated from the samples), ~0.2 % here.
    assert!((mean - expected).abs() < 4.0 * std_err, "mean {mean} vs radiosity {expected} (σ {std_err})");
    assert!(std_err < 0.01 * expected, "the estimate must be meaningful: σ {std_err}");
    assert_eq!(counts.primary, n as u64);
    assert_eq!(counts.shadow, 4 * n as u64, "every sample point faces the emitter");

    // The emitter itself still shows exactly Ke (up to the rounding of π·Ke/π).
    let l = trace(&tracer, vec3(0.2, 0.5, 0.3), Vec3::Y, TraceMode::Final);
    assert_close(l, ke, 2.4e-7, "emitter in pixel mode");
}

#[test]
fn pixel_direct_light_is_shadowed_by_a_blocker() {
    // Same floor and emitter with an opaque black square between them: the floor's centre sees no
    // light at all; the indirect radiosity (here zero) is all that remains.
    let ke = Vec3::ONE;
    let floor = surface([vec3(-1., 0., -1.), vec3(-1., 0., 1.), vec3(1., 0., 1.), vec3(1., 0., -1.)], 0, false);
    let light = surface([vec3(-1., 1., -1.), vec3(1., 1., -1.), vec3(1., 1., 1.), vec3(-1., 1., 1.)], 1, false);
    let blocker =
        surface([vec3(-10., 0.5, -10.), vec3(10., 0.5, -10.), vec3(10., 0.5, 10.), vec3(-10., 0.5, 10.)], 2, false);
    let scene = scene(
        vec![
            Material::diffuse("floor", Vec3::splat(0.5)),
            emitter("light", ke),
            Material::diffuse("black", Vec3::ZERO),
        ],
        vec![floor, light, blocker],
    );
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        (per_surface(mesh, &[Vec3::ZERO, ke * PI, Vec3::ZERO]), vec![Vec3::ZERO; mesh.elements.len()])
    });
    let params = RenderParams { direct: DirectMode::Pixel, light_samples: 8, ..RenderParams::default() };
    let tracer = setup.tracer_with(&params);
    let l = trace(&tracer, vec3(0.0, 0.25, 0.0), Vec3::NEG_Y, TraceMode::Final);
    assert_eq!(l, Vec3::ZERO);
}

#[test]
fn phong_highlight_follows_its_normalisation() {
    // A glossy floor (Kd 0, Ks 0.5, Ns 4) under a tiny emitter of area A straight above at height 1.
    // Seen at 10° from the vertical, the mirror ray misses the emitter and the highlight alone is
    // L = Ks (n+2)/(2π) · cosⁿα · L_e · cos θ cos θ' A / r² with α = 10°, θ = θ' = 0, r = 1.
    let (ks, n) = (0.5f32, 4.0f32);
    let glossy = Material {
        specular_reflectance: Vec3::splat(ks),
        phong_exponent: Some(n),
        ..Material::diffuse("glossy", Vec3::ZERO)
    };
    let s = 0.01f32;
    let floor = surface([vec3(-1., 0., -1.), vec3(-1., 0., 1.), vec3(1., 0., 1.), vec3(1., 0., -1.)], 0, false);
    let light = surface([vec3(-s, 1., -s), vec3(s, 1., -s), vec3(s, 1., s), vec3(-s, 1., s)], 1, false);
    let scene = scene(vec![glossy, emitter("light", Vec3::ONE)], vec![floor, light]);
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        (per_surface(mesh, &[Vec3::ZERO, Vec3::splat(PI)]), vec![Vec3::ZERO; mesh.elements.len()])
    });
    let params = RenderParams { light_samples: 16, ..RenderParams::default() };
    let tracer = setup.tracer_with(&params);
    let alpha = 10f32.to_radians();
    let dir = vec3(alpha.sin(), -alpha.cos(), 0.0);
    let l = trace(&tracer, -0.5 * dir, dir, TraceMode::Final);
    let area = 4.0 * s * s;
    let expected = ks * (n + 2.0) / (2.0 * PI) * alpha.cos().powf(n) * area;
    // Over the symmetric emitter the first-order variations of cos α, cos θ, cos θ' and 1/r² cancel;
    // the second-order ones are of order n·s² = 4e-4 relative.
    assert!((l.x - expected).abs() < 1e-3 * expected, "{} vs {expected}", l.x);
    // Without an exponent there is no highlight (and the mirror ray sees nothing).
    let plain = Material { phong_exponent: None, ..setup.materials[0].clone() };
    let materials = vec![plain, setup.materials[1].clone()];
    let tracer = Tracer::new(&setup.mesh, &setup.accel, &setup.solution, &materials, &params).unwrap();
    assert_eq!(trace(&tracer, -0.5 * dir, dir, TraceMode::Final), Vec3::ZERO);
}

#[test]
fn tracer_rejects_a_solution_of_another_mesh() {
    let scene = scene(vec![Material::diffuse("w", Vec3::splat(0.5))], vec![z_quad(0.0, 1.0, true, 0, false)]);
    let mesh = Mesh::build(&scene, f32::INFINITY);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let wrong = solution(&mesh, vec![Vec3::ZERO], vec![Vec3::ZERO]);
    let mut shorter = wrong.clone();
    shorter.vertex_exitance.pop();
    assert!(Tracer::new(&mesh, &accel, &wrong, &scene.materials, &RenderParams::default()).is_ok());
    assert!(Tracer::new(&mesh, &accel, &shorter, &scene.materials, &RenderParams::default()).is_err());
}

#[test]
fn shading_normals_bend_mirror_rays() {
    // A flat mirror in z = 0 whose vertex normals all lean 10° towards +x: a ray straight down
    // leaves at 20° from the vertical and reaches a wall strip (x ≥ 1 at z = 5; 5·tan 20° = 1.82)
    // that the geometric reflection (straight up, x = 0) misses.
    let mirror = mirror("mirror", 0.9);
    let wall = Material::diffuse("wall", Vec3::splat(0.5));
    let tilt = 10f32.to_radians();
    let mut mirror_surface = z_quad(0.0, 10.0, true, 0, false);
    mirror_surface.shading_normals = Some(vec![vec3(tilt.sin(), 0.0, tilt.cos()); 4]);
    let wall_surface =
        surface([vec3(1.0, -10.0, 5.0), vec3(1.0, 10.0, 5.0), vec3(10.0, 10.0, 5.0), vec3(10.0, -10.0, 5.0)], 1, false);
    let scene = scene(vec![mirror, wall], vec![mirror_surface, wall_surface]);
    let setup = Setup::hand_made(&scene, f32::INFINITY, |mesh| {
        (per_surface(mesh, &[Vec3::ZERO, Vec3::splat(PI)]), vec![Vec3::ZERO; mesh.elements.len()])
    });
    assert!(setup.mesh.elements.normal[1].z < 0.0, "the wall faces the mirror");
    let params = RenderParams::default();
    let flat = setup.tracer_with(&params);
    let smooth = setup.tracer_with(&params).with_shading_normals(&scene.surfaces);
    let origin = vec3(0.0, 0.0, 1.0);
    assert_eq!(trace(&flat, origin, Vec3::NEG_Z, TraceMode::Final), Vec3::ZERO);
    // 0.9 × the wall's radiance 1, a few f32 roundings.
    assert_close(trace(&smooth, origin, Vec3::NEG_Z, TraceMode::Final), Vec3::splat(0.9), 1e-6, "smooth mirror");
}
