//! Light through mirrors and glass in the hierarchy's pass one (issue 10's "keep extended form
//! factors"): photons traced from the emitters land in the leaves as reflected caustic light
//! (`radiosity::hierarchy::caustics`), which the links then carry on. Specifications: a receiver that
//! sees an emitter only in a plane mirror takes ρ·Ks·π·L·F(image) (the mirror image's form factor, and
//! its own image's light: DS+D), a room lit only through a glass pane takes what the full matrix's
//! extended form factors give it, neither depends on the thread count, and a batch's re-solve after
//! new materials traces that light again.

mod common;

use glam::Vec3;
use radray::mesh::Mesh;
use radray::progress::Progress;
use radray::radiosity::hierarchy::form_factor::point_to_polygon;
use radray::radiosity::Solution;
use radray::run::{self, RunStats};
use radray::scene::{Material, MethodChoice, SceneDescription};
use radray::transport::photons::RunPhotons;

const GREY: u32 = 0;
const EMITTER: u32 = 1;
const MIRROR: u32 = 2;
const GLASS: u32 = 3;
const KS: f32 = 0.8;
const RHO: f32 = 0.5;

fn materials() -> Vec<Material> {
    vec![
        Material::diffuse("grey", Vec3::splat(RHO)),
        common::emitter("light", Vec3::ONE),
        common::mirror("mirror", KS),
        common::glass("glass"),
    ]
}

/// Axis-aligned rectangle at height y over [x0, x1] × [z0, z1], facing +y (`up`) or −y.
fn horizontal(y: f32, (x0, x1): (f32, f32), (z0, z1): (f32, f32), up: bool) -> Vec<Vec3> {
    let mut v = vec![Vec3::new(x0, y, z0), Vec3::new(x0, y, z1), Vec3::new(x1, y, z1), Vec3::new(x1, y, z0)];
    if !up {
        v.reverse();
    }
    v
}

fn scene_of(surfaces: Vec<(Vec<Vec3>, u32)>) -> SceneDescription {
    let surfaces = surfaces.into_iter().map(|(v, m)| common::surface(v, m, false)).collect();
    common::scene(materials(), surfaces)
}

/// Pass one of `scene` with `method` (the uniform mesh's elements at most 20 cm): the mesh it lives on and its solution.
fn solve(scene: &SceneDescription, method: MethodChoice) -> (Mesh, std::sync::Arc<Solution>) {
    let mut scene = scene.clone();
    scene.radiosity.method = method;
    scene.radiosity.max_element_edge = 0.2;
    let mut stats = RunStats::default();
    run::pass_one(&scene, None, &RunPhotons::default(), &Progress::hidden(), &mut stats).expect("pass one")
}

/// Area-weighted mean exitance (red channel) of scene surface `surface` (one-sided: mesh surface
/// `surface`) over the solution's elements.
fn surface_mean(mesh: &Mesh, solution: &Solution, surface: u32) -> f64 {
    let e = &mesh.elements;
    let (mut sum, mut area) = (0.0f64, 0.0f64);
    for i in 0..e.len() {
        if e.surface[i] == surface {
            sum += solution.element_exitance[i].x as f64 * e.area[i] as f64;
            area += e.area[i] as f64;
        }
    }
    sum / area
}

/// A 1 m² emitter (L = 1) at y = 1.5 facing down beside a square receiver (surface 0) at y = 1 facing
/// down onto an 8 m plane mirror (Ks = 0.8) at y = 0: the scene and the emitter's corners.
fn mirror_scene() -> (SceneDescription, Vec<Vec3>) {
    let emitter = horizontal(1.5, (1.0, 2.0), (-0.5, 0.5), false);
    let surfaces = vec![
        (horizontal(1.0, (-0.5, 0.5), (-0.5, 0.5), false), GREY),
        (horizontal(0.0, (-4.0, 4.0), (-4.0, 4.0), true), MIRROR),
        (emitter.clone(), EMITTER),
    ];
    (scene_of(surfaces), emitter)
}

/// The receiver sees the emitter only in the mirror, and nothing diffuse but its own image, so its
/// exact exitance is B(p) = ρ·(Ks·π·L·F(p → emitter's image) + Ks·∫F(p → own image)·B): with the
/// means over the receiver, B̄ = ρ·Ks·π·L·F̄_e / (1 − ρ·Ks·F̄_r) (the self-term is 3 % of B, so
/// taking it at the mean is exact to well within the tolerance). The hierarchy's leaves within 5 %
/// (a few thousand photons land on the receiver; before session 23 the hierarchy gave it 0).
#[test]
fn a_receiver_lit_only_through_a_mirror_takes_the_mirror_images_light() {
    let (scene, emitter) = mirror_scene();
    // Mirrored, an image's corners turn the other way round.
    let image_of =
        |polygon: &[Vec3]| -> Vec<Vec3> { polygon.iter().rev().map(|v| Vec3::new(v.x, -v.y, v.z)).collect() };
    let (emitter_image, own_image) = (image_of(&emitter), image_of(&scene.surfaces[0].vertices));
    let steps = 40;
    let (mut f_emitter, mut f_own) = (0.0f64, 0.0f64);
    for a in 0..steps {
        for b in 0..steps {
            let p = Vec3::new(-0.5 + (a as f32 + 0.5) / steps as f32, 1.0, -0.5 + (b as f32 + 0.5) / steps as f32);
            f_emitter += point_to_polygon(p, -Vec3::Y, &emitter_image) / (steps * steps) as f64;
            f_own += point_to_polygon(p, -Vec3::Y, &own_image) / (steps * steps) as f64;
        }
    }
    let (rho_ks, pi) = ((RHO * KS) as f64, std::f64::consts::PI);
    let exact = rho_ks * pi * f_emitter / (1.0 - rho_ks * f_own);
    let (mesh, solution) = solve(&scene, MethodChoice::Hierarchical);
    assert!(solution.holds_caustic_light);
    let got = surface_mean(&mesh, &solution, 0);
    println!("receiver lit through the mirror: hierarchy {got:.5}, exact {exact:.5} (F to the emitter's image {f_emitter:.5}, to its own {f_own:.5})");
    assert!((got / exact - 1.0).abs() <= 0.05, "hierarchy {got}, exact {exact}");
}

/// A closed room (4 × 3 × 4 m, grey walls) lit only through a glass pane in one wall by an emitter
/// outside: every bit of its light comes through the glass (LS+D) and then bounces over the links
/// (LS+DD*). The hierarchy's mean exitance on the floor, the ceiling and the far wall within 5 % of
/// the full matrix's (extended form factors); before session 23 the hierarchy left the room black.
#[test]
fn a_room_lit_through_a_window_pane_matches_the_full_matrix() {
    let v = Vec3::new;
    let (w, h) = (4.0, 3.0);
    // The window: x = 0, y in [1, 2], z in [1.5, 2.5]; the wall x = 0 is four quads around it.
    let (y0, y1, z0, z1) = (1.0, 2.0, 1.5, 2.5);
    let wall_x0 =
        |ya: f32, yb: f32, za: f32, zb: f32| vec![v(0.0, ya, za), v(0.0, yb, za), v(0.0, yb, zb), v(0.0, ya, zb)];
    let mut surfaces = vec![
        (horizontal(0.0, (0.0, w), (0.0, w), true), GREY),
        (horizontal(h, (0.0, w), (0.0, w), false), GREY),
        // x = w (the far wall, facing −x), z = 0 (facing +z), z = w (facing −z).
        (vec![v(w, 0.0, 0.0), v(w, 0.0, w), v(w, h, w), v(w, h, 0.0)], GREY),
        (vec![v(0.0, 0.0, 0.0), v(w, 0.0, 0.0), v(w, h, 0.0), v(0.0, h, 0.0)], GREY),
        (vec![v(0.0, 0.0, w), v(0.0, h, w), v(w, h, w), v(w, 0.0, w)], GREY),
        (wall_x0(0.0, y0, 0.0, w), GREY),
        (wall_x0(y1, h, 0.0, w), GREY),
        (wall_x0(y0, y1, 0.0, z0), GREY),
        (wall_x0(y0, y1, z1, w), GREY),
    ];
    // The pane: a 2 cm slab, its outer face facing −x, its inner face facing +x.
    let t = 0.02;
    surfaces.push((vec![v(-t, y0, z0), v(-t, y0, z1), v(-t, y1, z1), v(-t, y1, z0)], GLASS));
    surfaces.push((vec![v(0.0, y0, z0), v(0.0, y1, z0), v(0.0, y1, z1), v(0.0, y0, z1)], GLASS));
    // The emitter 1 m outside, facing the window.
    surfaces.push((vec![v(-1.0, 0.5, 1.0), v(-1.0, 2.5, 1.0), v(-1.0, 2.5, 3.0), v(-1.0, 0.5, 3.0)], EMITTER));
    let scene = scene_of(surfaces);
    let (hm, hs) = solve(&scene, MethodChoice::Hierarchical);
    let (mm, ms) = solve(&scene, MethodChoice::Matrix);
    for (surface, name) in [(0, "floor"), (1, "ceiling"), (2, "far wall")] {
        let (got, want) = (surface_mean(&hm, &hs, surface), surface_mean(&mm, &ms, surface));
        println!("{name}: hierarchy {got:.5}, matrix {want:.5}");
        assert!(want > 0.0 && (got / want - 1.0).abs() <= 0.05, "{name}: hierarchy {got}, matrix {want}");
    }
}

/// The caustic light's photons, their binning and the sweeps are the same for any thread count: the
/// mirror scene's hierarchical solution (both sets of photons) on one thread and on two, bit for bit.
#[test]
fn caustic_light_does_not_depend_on_the_thread_count() {
    let (scene, _) = mirror_scene();
    let on = |threads: usize| {
        let pool = rayon::ThreadPoolBuilder::new().num_threads(threads).build().unwrap();
        pool.install(|| solve(&scene, MethodChoice::Hierarchical).1.to_bytes())
    };
    assert!(on(1) == on(2), "the solution's bytes differ between one and two threads");
}

/// A batch re-solve after a materials-only change starts from the kept links but traces the
/// photons again with the new materials: doubling the lamp's Ke in cornell_specular doubles the
/// hierarchy's radiosity-mode image within 0.5 %. The light through the mirror and glass balls is
/// 7 % of that image's sum (without it, session 22: 22,221 against 23,977 at 256²), so a stale
/// caustic source term, which would keep that part at its old value, would give about 1.93.
#[test]
fn a_batch_re_solve_after_new_materials_traces_the_caustic_light_again() {
    let dir = tempfile::tempdir().unwrap();
    let scene = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_specular.toml");
    let s = scene.display().to_string();
    let m = "method = \"hierarchical\"\nmode = \"radiosity\"\n";
    let jobs = [
        common::small_batch_job(&s, "\"a.exr\"", 16, m),
        common::small_batch_job(
            &s,
            "\"b.exr\"",
            16,
            &format!("{m}materials = {{ light = {{ ke = [34.0, 24.0, 8.0] }} }}"),
        ),
    ]
    .concat();
    let jobs_path = dir.path().join("jobs.toml");
    std::fs::write(&jobs_path, jobs).unwrap();
    let out = common::radray(&["batch", jobs_path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("jobs.manifest.json")).unwrap()).unwrap();
    assert_eq!(
        manifest["jobs"][1]["reused_form_factors"], true,
        "a materials-only change re-solves from the kept links"
    );
    let sum = |name: &str| -> f64 {
        let image = radray::output::read_image(&dir.path().join(name)).unwrap();
        image.pixels.iter().map(|p| p.element_sum() as f64).sum()
    };
    let ratio = sum("b.exr") / sum("a.exr");
    println!("image ratio after doubling the lamp: {ratio:.5}");
    assert!((ratio - 2.0).abs() <= 0.01, "ratio {ratio}");
}
