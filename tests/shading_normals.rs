//! Smooth shading of diffuse surfaces, as specifications: a tessellated sphere's direct light and final
//! gather change across its facet edges no faster than within its facets (the flat-shaded sphere
//! jumps there), a flat surface's own vertex normals render the bytes of no normals, light below a
//! facet's plane never lights it whatever its shading normal leans towards, and a furnace with a
//! smooth sphere inside stays exact.

mod common;

use std::f32::consts::PI;

use common::{emitter, scene, surface, Setup};
use glam::{vec3, Vec3};
use proptest::prelude::*;
use radray::accel::Accel;
use radray::film::Sampler;
use radray::mesh::Mesh;
use radray::progress::Progress;
use radray::run::{self, RunStats};
use radray::scene::shapes::{box_faces, sphere_triangles};
use radray::scene::{Camera, DirectMode, FinalGatherMode, Material, RenderParams, SceneDescription, Surface};
use radray::trace::direct_light::DirectLight;
use radray::trace::gather::Strata;
use radray::trace::{RayCounts, TraceMode, Tracer};
use radray::transport::emitters::Emitters;
use radray::transport::photons::RunPhotons;
use radray::transport::SurfaceNormals;

/// Materials of the lit box: 0 walls, 1 floor, 2 lamp, 3 sphere.
const WALL: u32 = 0;
const FLOOR: u32 = 1;
const LAMP: u32 = 2;
const BALL: u32 = 3;
const SEGMENTS: u32 = 24;

/// The triangles of a `segments`-segment sphere of material `material`, each with its analytic vertex
/// normals as `[[sphere]]` gives them.
fn sphere(centre: Vec3, radius: f32, segments: u32, material: u32) -> Vec<Surface> {
    sphere_triangles(centre, radius, segments)
        .into_iter()
        .map(|(tri, normals)| Surface { shading_normals: Some(normals.to_vec()), ..surface(tri, material, false) })
        .collect()
}

/// A closed 8 × 8 × 8 box around the origin (inward faces, the floor y = −4 of its own material), a
/// 1 × 1 lamp 0.1 under the ceiling facing down, and a unit sphere of `SEGMENTS` segments (12 rings of
/// 15°) at the origin.
fn lit_box() -> SceneDescription {
    let materials = vec![
        Material::diffuse("wall", Vec3::splat(0.5)),
        Material::diffuse("floor", Vec3::splat(0.5)),
        emitter("lamp", Vec3::splat(20.0)),
        Material::diffuse("ball", Vec3::splat(0.8)),
    ];
    let mut surfaces: Vec<Surface> = box_faces(Vec3::splat(-4.0), Vec3::splat(4.0), true)
        .into_iter()
        .map(|face| {
            let material = if face.iter().all(|v| v.y == -4.0) { FLOOR } else { WALL };
            surface(face.to_vec(), material, false)
        })
        .collect();
    let (h, y) = (0.5, 3.9);
    surfaces.push(surface([vec3(-h, y, -h), vec3(h, y, -h), vec3(h, y, h), vec3(-h, y, h)], LAMP, false));
    surfaces.extend(sphere(Vec3::ZERO, 1.0, SEGMENTS, BALL));
    scene(materials, surfaces)
}

/// The unit sphere's surface direction at polar angle θ from +y and azimuth φ (the parametrisation of
/// `sphere_triangles`).
fn direction(theta_deg: f32, phi_deg: f32) -> Vec3 {
    let (t, p) = (theta_deg.to_radians(), phi_deg.to_radians());
    Vec3::new(t.sin() * p.cos(), t.cos(), -t.sin() * p.sin())
}

/// A probe ray from 3 units out towards the sphere's centre along `direction(θ, φ)`: it hits the facet
/// holding that direction, from outside.
fn probe(theta_deg: f32, phi_deg: f32) -> (Vec3, Vec3) {
    let d = direction(theta_deg, phi_deg);
    (d * 3.0, -d)
}

/// The diffuse radiance the tracer sees along a probe ray: the mean of 64 samples of a pixel sampler
/// with the same seed for every probe, so that neighbouring probes share their light samples and
/// differ only by where they are and how they are shaded.
fn probe_radiance(tracer: &Tracer, theta_deg: f32, phi_deg: f32) -> f32 {
    let (origin, dir) = probe(theta_deg, phi_deg);
    let mut sampler = Sampler::pixel(7, 0);
    let mut counts = RayCounts::default();
    let spp = 64;
    let mut sum = 0.0;
    for s in 0..spp {
        sampler.start_sample(s);
        sum += tracer.radiance(origin, dir, TraceMode::Final, &mut sampler, &mut counts).x;
    }
    sum / spp as f32
}

/// The gathered indirect irradiance at a probe's hit with the normals the tracer shades it with, from
/// the same stream for every probe.
fn probe_gather(tracer: &Tracer, theta_deg: f32, phi_deg: f32) -> f32 {
    let (origin, dir) = probe(theta_deg, phi_deg);
    let (hit, _) = tracer.closest_opaque_hit(origin, dir).expect("the probe hits the sphere");
    let hit = hit.with_shading_normal(tracer.mesh(), tracer.surfaces(), dir);
    let mut sampler = Sampler::independent(11, 0);
    tracer
        .gather(hit.position, hit.normals(), Strata::for_rays(4096), &mut sampler, &mut RayCounts::default())
        .irradiance
        .x
}

/// How a quantity f(θ) behaves across the ring edge at θ_e: the step over the edge, f(θ_e + 1°) −
/// f(θ_e − 1°), and the larger of the steps of the same 2° within the facets on either side.
fn edge_and_facet_steps(f: impl Fn(f32) -> f32, edge_deg: f32) -> (f32, f32) {
    let at = |offset: f32| f(edge_deg + offset);
    let (a, b, c, d) = (at(-3.0), at(-1.0), at(1.0), at(3.0));
    ((c - b).abs(), (b - a).abs().max((d - c).abs()))
}

#[test]
fn a_tessellated_sphere_shades_smoothly_across_its_facet_edges() {
    // The lamp is straight above, so the light changes with the polar angle θ: across a ring edge (every
    // 15°) the flat facets' normals turn by 15° at once, within a facet not at all. With the smooth
    // normal the cosine turns 1° per degree everywhere: the step over an edge is then about the step
    // within the facets (the interpolated normal's rate differs between the two facets by up to the
    // ratio of their heights, and the light's distance adds a little), so 1.5× bounds it. Flat, the
    // step over the edge is many times the facets' own. Probes sit at a segment's centre (φ = 7.5°,
    // 97.5°) at the edges θ = 30°, 45°, 60° (direct light from the lamp; the hand-made solution holds
    // only the emission, so the image is the direct light alone) and θ = 120°, 135° (the gather: the
    // floor's exitance 1 is the only indirect light).
    let scene = lit_box();
    let setup = Setup::hand_made(&scene, 1.0, |mesh| {
        let e = &mesh.elements;
        let floor = |i: usize| e.material[i] == FLOOR;
        let exitance = (0..e.len()).map(|i| if floor(i) { Vec3::ONE } else { e.emission[i] }).collect();
        (exitance, vec![Vec3::ZERO; e.len()])
    });
    let params = RenderParams { direct: DirectMode::Pixel, near_bounce: Some(0.0), ..RenderParams::default() };
    let flat = setup.tracer_with(&params);
    let smooth = setup.tracer_with(&params).with_shading_normals(&scene.surfaces);
    let mut figures = String::new();
    for phi in [7.5, 97.5] {
        for (edge, gather) in [(30.0, false), (45.0, false), (60.0, false), (120.0, true), (135.0, true)] {
            let steps = |tracer: &Tracer| {
                if gather {
                    edge_and_facet_steps(|theta| probe_gather(tracer, theta, phi), edge)
                } else {
                    edge_and_facet_steps(|theta| probe_radiance(tracer, theta, phi), edge)
                }
            };
            let (flat_edge, flat_facet) = steps(&flat);
            let (smooth_edge, smooth_facet) = steps(&smooth);
            figures += &format!(
                "θ {edge}° φ {phi}° ({}): flat edge {flat_edge:.4} facet {flat_facet:.4}; smooth edge \
                 {smooth_edge:.4} facet {smooth_facet:.4}\n",
                if gather { "gather" } else { "direct" }
            );
            assert!(flat_edge > 4.0 * flat_facet, "the flat sphere jumps at its edges:\n{figures}");
            assert!(smooth_edge <= 1.5 * smooth_facet, "no jump with smooth normals:\n{figures}");
        }
    }
    println!("{figures}");
}

/// A lit room (0.5 reflectance, a lamp under the ceiling) around `quads`, seen from the front, at 24 ×
/// 18 pixels with the final gather, its cache and per-pixel direct light on.
fn room_with(quads: Vec<Surface>) -> SceneDescription {
    let materials = vec![Material::diffuse("wall", Vec3::splat(0.5)), emitter("lamp", Vec3::splat(10.0))];
    let mut surfaces: Vec<Surface> = box_faces(vec3(-2.0, 0.0, -2.0), vec3(2.0, 2.5, 2.0), true)
        .into_iter()
        .map(|face| surface(face.to_vec(), 0, false))
        .collect();
    let (h, y) = (0.4, 2.49);
    surfaces.push(surface([vec3(-h, y, -h), vec3(h, y, -h), vec3(h, y, h), vec3(-h, y, h)], 1, false));
    surfaces.extend(quads);
    let mut scene = scene(materials, surfaces);
    scene.camera = Camera { eye: vec3(0.0, 1.2, -1.9), look_at: vec3(0.0, 0.6, 0.5), up: Vec3::Y, vfov_deg: 70.0 };
    (scene.image.width_px, scene.image.height_px, scene.image.samples_per_pixel) = (24, 18, 2);
    scene.radiosity.max_element_edge = 0.5;
    scene.radiosity.hemicube_resolution_px = 32;
    scene.render.direct = DirectMode::Pixel;
    scene.render.final_gather = FinalGatherMode::On;
    scene.render.gather_rays = 64;
    scene
}

/// The final image's pixels' bits, pass one run as `radray render` runs it.
fn final_image_bits(scene: &SceneDescription) -> Vec<u32> {
    let setup = Setup::solved(scene);
    let mut stats = RunStats::default();
    let image = run::render(
        scene,
        &setup.mesh,
        &setup.accel,
        &setup.solution,
        TraceMode::Final,
        &RunPhotons::default(),
        &Progress::hidden(),
        &mut stats,
    )
    .unwrap();
    image.pixels.iter().flat_map(|p| p.to_array().map(f32::to_bits)).collect()
}

#[test]
fn flat_quads_with_their_own_normals_render_the_bytes_of_no_normals() {
    // A quad on the floor (exact vertex normals +y) and one tilted by 30° about x whose vertex normals
    // are its normal rounded to 4 digits, as an OBJ exporter writes them: both are flat, so the image
    // must be the one without vertex normals, bit for bit (direct light, gather, cache and all).
    let floor =
        surface([vec3(-0.6, 0.01, -0.2), vec3(-0.6, 0.01, 0.6), vec3(0.2, 0.01, 0.6), vec3(0.2, 0.01, -0.2)], 0, false);
    let (c, s) = (30f32.to_radians().cos(), 30f32.to_radians().sin());
    // Spanned by x and (0, s, −c): facing x × (0, s, −c) = (0, c, s).
    let tilted = surface(
        [
            vec3(0.3, 0.2, 0.3),
            vec3(1.1, 0.2, 0.3),
            vec3(1.1, 0.2 + 0.8 * s, 0.3 - 0.8 * c),
            vec3(0.3, 0.2 + 0.8 * s, 0.3 - 0.8 * c),
        ],
        0,
        true,
    );
    let rounded = Vec3::new(0.0, 0.8660, 0.5000);
    assert!((rounded.normalize() - Vec3::new(0.0, c, s)).length() < 1e-4 && rounded != Vec3::new(0.0, c, s));
    let plain = room_with(vec![floor.clone(), tilted.clone()]);
    let with_normals = room_with(vec![
        Surface { shading_normals: Some(vec![Vec3::Y; 4]), ..floor },
        Surface { shading_normals: Some(vec![rounded; 4]), ..tilted },
    ]);
    let a = final_image_bits(&plain);
    let b = final_image_bits(&with_normals);
    assert!(a.iter().any(|&v| f32::from_bits(v) > 0.0), "the room is lit");
    assert_eq!(a, b);
}

/// A square emitter of side 0.2 centred on `centre`, facing the origin.
fn emitter_facing_origin(centre: Vec3) -> Surface {
    let n = -centre.normalize();
    let u = n.any_orthonormal_vector();
    let v = n.cross(u); // u × v = u × (n × u) = n
    let (u, v) = (u * 0.1, v * 0.1);
    surface([centre - u - v, centre + u - v, centre + u + v, centre - u + v], 0, false)
}

/// The direct irradiance at the origin with `normals` from the one emitter `light`, 16 shadow rays.
fn irradiance_from(light: Surface, normals: SurfaceNormals) -> f32 {
    let scene = scene(vec![emitter("lamp", Vec3::splat(5.0))], vec![light]);
    let mesh = Mesh::build(&scene, 1.0);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let direct = DirectLight::new(&mesh, &accel, Emitters::new(&mesh, &scene.materials), 16, 1e-4);
    let mut sampler = Sampler::independent(3, 0);
    direct.estimate(16, Vec3::ZERO, normals, None, &mut sampler, &mut RayCounts::default()).irradiance.x
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// A light entirely below the facet's plane gives no irradiance even when the shading normal leans
    /// towards it: the shading normal is tilted 5°–70° towards the light, whose centre lies β below the
    /// plane with β short of the tilt (so n_s sees it: n_s·ω = sin(tilt − β) > 0) and far enough that
    /// the 0.2-wide square stays at least 0.15 below the plane. The same light mirrored above the plane does
    /// light the point.
    #[test]
    fn light_below_the_geometric_plane_never_lights_the_facet(
        normal in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
        azimuth in 0.0f32..std::f32::consts::TAU,
        tilt_deg in 5.0f32..70.0,
        below_share in 0.05f32..0.95,
        farther in 0.0f32..1.0,
    ) {
        let geometric = Vec3::from(normal).try_normalize().unwrap_or(Vec3::Y);
        let (t, b) = geometric.any_orthonormal_pair();
        let side = t * azimuth.cos() + b * azimuth.sin();
        let tilt = tilt_deg.to_radians();
        let shading = geometric * tilt.cos() + side * tilt.sin();
        let normals = SurfaceNormals { geometric, shading };
        let beta = (2.0 + below_share * (tilt_deg - 3.0)).to_radians();
        let distance = (0.3 + farther) / beta.sin();
        let below = (side * beta.cos() - geometric * beta.sin()) * distance;
        prop_assert!(shading.dot(below) > 0.0, "the shading normal sees the light");
        prop_assert_eq!(irradiance_from(emitter_facing_origin(below), normals), 0.0);
        let above = (side * beta.cos() + geometric * beta.sin()) * distance;
        prop_assert!(irradiance_from(emitter_facing_origin(above), normals) > 0.0);
    }
}

#[test]
fn a_furnace_with_a_smooth_sphere_inside_stays_exact() {
    // The unit cube seen from inside with a coarse 8-segment sphere (radius 0.25, 4 rings of 45°) at its
    // centre, whose vertex normals lean up to about 30° off their facets, every surface emitting
    // radiance 1 (E = π) and reflecting ρ = 0.5: L = Ke/(1 − ρ) = 2 everywhere, with the exact solution
    // by hand (B = E/(1 − ρ), direct part ρE). Counting the lobe below a facet's plane as lost, without
    // dividing by its share c = (1 + cos α)/2 above, would darken the sphere by up to 7% of the light
    // the shading normal weighs.
    let rho = 0.5;
    let material = Material { emitted_radiance: Vec3::ONE, ..Material::diffuse("furnace", Vec3::splat(rho)) };
    let mut surfaces: Vec<Surface> =
        box_faces(Vec3::ZERO, Vec3::ONE, true).into_iter().map(|f| surface(f.to_vec(), 0, false)).collect();
    surfaces.extend(sphere(Vec3::splat(0.5), 0.25, 8, 0));
    let mut scene = scene(vec![material], surfaces);
    scene.camera = Camera { eye: vec3(0.5, 0.55, 0.04), look_at: Vec3::splat(0.5), up: Vec3::Y, vfov_deg: 60.0 };
    (scene.image.width_px, scene.image.height_px, scene.image.samples_per_pixel) = (24, 24, 1);
    let setup = Setup::hand_made(&scene, 0.25, |mesh| {
        let e = &mesh.elements.emission;
        (e.iter().map(|&e| e / (1.0 - rho)).collect(), e.iter().map(|&e| e * rho).collect())
    });

    // The final image with the gather and its cache, direct light from the solution: the gather's
    // cells below a facet's plane count as dark and the estimate is divided by the lobe's share
    // above it, so only the cells the plane cuts vary (a few of 256). 0.5%, half the shipped furnace's
    // tolerance (whose 1% covers the hemicube's row sums, which the hand-made solution does not have).
    scene.render = RenderParams {
        direct: DirectMode::Radiosity,
        near_bounce: Some(0.0),
        gather_rays: 256,
        ..RenderParams::default()
    };
    let mut stats = RunStats::default();
    let image = run::render(
        &scene,
        &setup.mesh,
        &setup.accel,
        &setup.solution,
        TraceMode::Final,
        &RunPhotons::default(),
        &Progress::hidden(),
        &mut stats,
    )
    .unwrap();
    let worst = image.pixels.iter().flat_map(|p| p.to_array()).map(|c| (c - 2.0).abs()).fold(0.0, f32::max);
    println!("furnace with a smooth sphere: worst pixel off by {worst}");
    assert!(worst <= 0.01, "a pixel is off by {worst}");

    // Per-pixel direct light on the sphere where the shading normal leans furthest from the facet's (a
    // triangle's corner): E_direct = ∫ L_e w(ω) dω = π with the normalised weight. Its mean over K
    // seeds lies within 4 standard errors, about 2.5% of π at K = 20000; the lobe lost below the
    // facet's plane without the normalisation, (1 − cos α)/2, is 6% of it at this α (29°).
    let tracer = setup.tracer().with_shading_normals(&scene.surfaces);
    let d = direction(45.0 + 1.0, 1.0);
    let (hit, _) = tracer.closest_opaque_hit(Vec3::splat(0.5) + d * 0.4, -d).unwrap();
    let hit = hit.with_shading_normal(&setup.mesh, tracer.surfaces(), -d);
    let normals = hit.normals();
    let tilt_deg = normals.shading.dot(normals.geometric).acos().to_degrees();
    assert!(tilt_deg > 15.0, "the point is smooth-shaded, {tilt_deg}° off its facet");
    let k = 20000;
    let values: Vec<f32> = (0..k)
        .map(|s| {
            let mut sampler = Sampler::independent(s, 5);
            tracer
                .direct_light()
                .estimate(8, hit.position, normals, None, &mut sampler, &mut RayCounts::default())
                .irradiance
                .x
        })
        .collect();
    let mean = values.iter().sum::<f32>() / k as f32;
    let var = values.iter().map(|v| (v - mean).powi(2)).sum::<f32>() / (k - 1) as f32;
    let bound = 4.0 * (var / k as f32).sqrt();
    println!("direct irradiance {mean} at {tilt_deg}° (π, bound {bound})");
    assert!((mean - PI).abs() <= bound, "direct irradiance {mean} against π (bound {bound})");
}
