//! `map_Kd` textures end to end: OBJ `vt` → mesh uv → pass one's element mean albedo → pass two's
//! texture ratio, with the fallbacks (missing file, face without `vt`) and the fingerprint.

mod common;

use glam::{Vec2, Vec3};
use radray::accel::Accel;
use radray::film::Sampler;
use radray::material::texture::srgb_to_linear;
use radray::material::{SceneTextures, ALBEDO_CEILING};
use radray::mesh::Mesh;
use radray::progress::Progress;
use radray::radiosity::fingerprint::fingerprint;
use radray::run::{self, RunStats};
use radray::scene;
use radray::trace::{RayCounts, TraceMode, Tracer};
use radray::transport::cut_outs::OpaqueRay;
use radray::transport::photons::RunPhotons;
use std::f64::consts::PI;
use std::path::Path;
use std::sync::Arc;

fn png_bytes(width: u32, height: u32, grey: &[u8]) -> Vec<u8> {
    let image = image::GrayImage::from_raw(width, height, grey.to_vec()).expect("size matches");
    let mut bytes = Vec::new();
    image.write_to(&mut std::io::Cursor::new(&mut bytes), image::ImageFormat::Png).expect("encode PNG");
    bytes
}

/// A floor quad [−1, 1]² at z = 0 facing +z, uv over the unit square (u along x, v along y), material
/// `floor`; above it at height `lamp_height` a lamp quad [−a, a]² facing down (Ke 1, Kd 0). Written to
/// a temporary folder with `mtl_floor` (the floor material's statements) and `files`.
fn write_scene(
    mtl_floor: &str,
    files: &[(&str, &[u8])],
    lamp_half: f32,
    lamp_height: f32,
    edge: f32,
    floor_vt: bool,
) -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let (a, h) = (lamp_half, lamp_height);
    let floor = if floor_vt { "f 1/1 2/2 3/3 4/4" } else { "f 1 2 3 4" };
    let obj = format!(
        "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\nv {a} -{a} {h}\nv -{a} -{a} {h}\nv -{a} {a} {h}\n\
         v {a} {a} {h}\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl floor\n{floor}\nusemtl lamp\nf 5 6 7 8\n"
    );
    std::fs::write(dir.path().join("m.obj"), obj).expect("write OBJ");
    let mtl = format!("newmtl lamp\nKd 0 0 0\nKe 1 1 1\n\nnewmtl floor\n{mtl_floor}\n");
    std::fs::write(dir.path().join("m.mtl"), mtl).expect("write MTL");
    for (name, bytes) in files {
        std::fs::write(dir.path().join(name), bytes).expect("write file");
    }
    let toml = format!(
        "[camera]\neye = [0.0, 0.0, {e}]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 60.0\n\n\
         [image]\nwidth = 8\nheight = 8\nsamples_per_pixel = 1\n\n[radiosity]\nmax_element_edge = {edge}\n\n\
         [[mesh]]\nobj = \"m.obj\"\n",
        e = 0.5 * lamp_height
    );
    std::fs::write(dir.path().join("scene.toml"), toml).expect("write scene");
    dir
}

fn load(dir: &Path) -> scene::SceneDescription {
    scene::load(&dir.join("scene.toml")).expect("scene loads")
}

/// Point-to-parallel-rectangle form factor with the rectangle's corner straight above the point
/// (Howell's catalogue, C-11): X = w/h, Y = d/h,
/// F = 1/(2π) [X/√(1+X²) atan(Y/√(1+X²)) + Y/√(1+Y²) atan(X/√(1+Y²))].
fn corner_form_factor(w: f64, d: f64, h: f64) -> f64 {
    let (x, y) = (w / h, d / h);
    let (sx, sy) = ((1.0 + x * x).sqrt(), (1.0 + y * y).sqrt());
    (x / sx * (y / sx).atan() + y / sy * (x / sy).atan()) / (2.0 * PI)
}

/// Form factor from a point (x, y) on the floor to the lamp [−a, a]² at height h: four corner pieces.
fn form_factor_to_lamp(x: f64, y: f64, a: f64, h: f64) -> f64 {
    let mut f = 0.0;
    for w in [a - x, a + x] {
        for d in [a - y, a + y] {
            f += corner_form_factor(w, d, h);
        }
    }
    f
}

#[test]
fn element_mean_albedo_is_the_exact_average_of_its_texels() {
    // 4×4 texture on the 2×2 floor, elements of edge 0.5: each element covers exactly one texel, so its
    // mean albedo is that texel's min(Kd·srgb⁻¹(g), 0.98). Texel rows run top (v = 1, y = +1) down.
    let grey: Vec<u8> = (0..16).map(|k| (k * 17) as u8).collect();
    let png = png_bytes(4, 4, &grey);
    let dir = write_scene("Kd 0.9 0.8 1.2\nmap_Kd t.png", &[("t.png", &png)], 1.0, 1.0, 0.5, true);
    let s = load(dir.path());
    let (textures, warnings) = SceneTextures::load(&s.materials);
    assert!(warnings.is_empty(), "{warnings:?}");
    let mesh = Mesh::build_with_textures(&s, 0.5, Arc::new(textures));
    let floor = s.materials.iter().position(|m| m.name == "floor").expect("floor") as u32;
    let mut checked = 0;
    for e in 0..mesh.elements.len() {
        if mesh.elements.material[e] != floor {
            continue;
        }
        let c = mesh.elements.centre[e];
        let column = ((c.x + 1.0) * 2.0).floor() as usize;
        let row = 3 - ((c.y + 1.0) * 2.0).floor() as usize;
        let t = srgb_to_linear(grey[row * 4 + column] as f32 / 255.0);
        let expected = (Vec3::new(0.9, 0.8, 1.2) * t).min(Vec3::splat(ALBEDO_CEILING));
        // f32 sums of a few products of order 1: 1e-5 relative is ~100 ulps.
        let got = mesh.elements.reflectance[e];
        assert!(
            (got - expected).abs().max_element() <= 1e-5 * expected.max_element().max(1e-3),
            "{e}: {got} {expected}"
        );
        checked += 1;
    }
    assert_eq!(checked, 16);
}

#[test]
fn a_textured_floor_under_a_large_lamp_shows_the_texture_times_the_analytic_irradiance() {
    // Grey checker of sRGB 200 and 60 on a 4×4 texture, 2×2 elements of 2×2 texels: every element has
    // the same mean albedo, so pass one's irradiance H is smooth and the texture ratio alone must make
    // the pattern. The floor sees only the lamp (Kd 0, Ke 1): H(x) = π·Le·F(x) with F the analytic
    // form factor to the lamp, and the radiance at x is L = ρ(x)·H(x)/π = ρ(x)·F(x).
    let (a, h) = (4.0f32, 0.5f32);
    let grey: Vec<u8> = (0..16).map(|k| if (k % 4 + k / 4) % 2 == 0 { 200 } else { 60 }).collect();
    let png = png_bytes(4, 4, &grey);
    let dir = write_scene("Kd 0.9 0.9 0.9\nmap_Kd c.png", &[("c.png", &png)], a, h, 1.0, true);
    let s = load(dir.path());
    let progress = Progress::hidden();
    let photons = RunPhotons::default();
    let mut stats = RunStats::default();
    let (mesh, solution) = run::pass_one(&s, None, &photons, &progress, &mut stats).expect("pass one");
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let tracer = Tracer::new(&mesh, &accel, &solution, &s.materials, &s.render).expect("tracer");
    let mut sampler = Sampler::independent(1, 1);
    let mut counts = RayCounts::default();
    let mut worst = 0.0f64;
    for j in 0..4 {
        for i in 0..4 {
            // Texel centres away from the floor's rim (where Gouraud reads only the rim elements).
            let uv = Vec2::new((i as f32 + 0.5) / 4.0, (j as f32 + 0.5) / 4.0);
            let (x, y) = (2.0 * uv.x - 1.0, 2.0 * uv.y - 1.0);
            let origin = Vec3::new(x, y, 0.25 * h);
            let l = tracer.radiance(origin, Vec3::NEG_Z, TraceMode::Radiosity, &mut sampler, &mut counts);
            let row = 3 - j;
            let rho = (0.9 * srgb_to_linear(grey[row * 4 + i] as f32 / 255.0)) as f64;
            let expected = rho * form_factor_to_lamp(x as f64, y as f64, a as f64, h as f64);
            let error = (l.x as f64 - expected).abs() / expected;
            worst = worst.max(error);
        }
    }
    // Tolerance 1%: the hemicube's form factor to a lamp that fills most of the hemisphere and the
    // Gouraud-interpolated element irradiance agree with F(x) to 0.1% here (measured); the checker's
    // 1:4 contrast would show as a ≥ 50% error without the texture ratio.
    assert!(worst < 0.01, "worst relative error {worst}");
}

#[test]
fn a_missing_texture_warns_with_its_file_and_renders_with_kd() {
    let dir = write_scene("Kd 0.5 0.4 0.3\nmap_Kd nowhere.png", &[], 1.0, 1.0, 1.0, true);
    let out = dir.path().join("out.exr");
    let scene_path = dir.path().join("scene.toml");
    let output = common::radray(&[
        "render",
        scene_path.to_str().expect("utf-8 path"),
        "-o",
        out.to_str().expect("utf-8 path"),
        "--quality",
        "preview",
    ]);
    let stderr = String::from_utf8_lossy(&output.stderr);
    assert!(output.status.success(), "{stderr}");
    assert!(stderr.contains("warning") && stderr.contains("nowhere.png") && stderr.contains("Kd"), "{stderr}");
    assert!(out.exists());
    // Pass one sees Kd on every floor element.
    let s = load(dir.path());
    let (textures, warnings) = SceneTextures::load(&s.materials);
    assert_eq!(warnings.len(), 1);
    let mesh = Mesh::build_with_textures(&s, 1.0, Arc::new(textures));
    let floor = s.materials.iter().position(|m| m.name == "floor").expect("floor") as u32;
    for e in (0..mesh.elements.len()).filter(|&e| mesh.elements.material[e] == floor) {
        assert_eq!(mesh.elements.reflectance[e], Vec3::new(0.5, 0.4, 0.3));
    }
}

#[test]
fn a_textured_face_without_vt_warns_once_and_uses_kd() {
    let png = png_bytes(1, 1, &[255]);
    let dir = write_scene("Kd 0.5 0.4 0.3\nmap_Kd w.png", &[("w.png", &png)], 1.0, 1.0, 1.0, false);
    let s = load(dir.path());
    let notes: Vec<&String> = s.warnings.iter().filter(|w| w.contains("texture coordinates")).collect();
    assert_eq!(notes.len(), 1, "{:?}", s.warnings);
    let (textures, _) = SceneTextures::load(&s.materials);
    let mesh = Mesh::build_with_textures(&s, 1.0, Arc::new(textures));
    let floor = s.materials.iter().position(|m| m.name == "floor").expect("floor") as u32;
    for e in (0..mesh.elements.len()).filter(|&e| mesh.elements.material[e] == floor) {
        assert_eq!(mesh.elements.reflectance[e], Vec3::new(0.5, 0.4, 0.3));
    }
}

#[test]
fn the_fingerprint_changes_with_the_texture_contents_and_path() {
    let fingerprint_of = |dir: &Path| {
        let s = load(dir);
        let (textures, _) = SceneTextures::load(&s.materials);
        fingerprint(&Mesh::build_with_textures(&s, 1.0, Arc::new(textures)), &s.materials)
    };
    // Two textures with the same mean over each element (a 2×2 checker and its mirror image): the
    // element albedos agree, only the texels differ.
    let (p1, p2) = (png_bytes(2, 2, &[200, 60, 60, 200]), png_bytes(2, 2, &[60, 200, 200, 60]));
    let dir = write_scene("Kd 0.5 0.5 0.5\nmap_Kd t.png", &[("t.png", &p1), ("u.png", &p1)], 1.0, 1.0, 2.0, true);
    let first = fingerprint_of(dir.path());
    assert_eq!(first, fingerprint_of(dir.path()), "stable");
    std::fs::write(dir.path().join("t.png"), &p2).expect("rewrite texture");
    let edited = fingerprint_of(dir.path());
    assert_ne!(first, edited, "texture contents");
    let mtl = std::fs::read_to_string(dir.path().join("m.mtl")).expect("MTL").replace("t.png", "u.png");
    std::fs::write(dir.path().join("m.mtl"), mtl).expect("rewrite MTL");
    assert_ne!(edited, fingerprint_of(dir.path()), "texture path");
}

#[test]
fn rays_pass_through_a_cut_out_and_stop_where_it_is_opaque() {
    // map_d of 2×1 texels: transparent (0) for u < ½ (x < 0), opaque (255) for u > ½. Rays from below
    // the one-sided floor, going up: through the cut-out they reach the lamp (radiance Ke = 1); where
    // the floor is opaque they meet its back side, which is black.
    let mask = png_bytes(2, 1, &[0, 255]);
    let dir = write_scene("Kd 0.5 0.5 0.5\nmap_d m.png", &[("m.png", &mask)], 1.0, 1.0, 1.0, true);
    let s = load(dir.path());
    let progress = Progress::hidden();
    let photons = RunPhotons::default();
    let mut stats = RunStats::default();
    let (mesh, solution) = run::pass_one(&s, None, &photons, &progress, &mut stats).expect("pass one");
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let tracer = Tracer::new(&mesh, &accel, &solution, &s.materials, &s.render).expect("tracer");
    let mut sampler = Sampler::independent(1, 1);
    let mut counts = RayCounts::default();
    let mut up_from =
        |x: f32| tracer.radiance(Vec3::new(x, 0.3, -0.5), Vec3::Z, TraceMode::Radiosity, &mut sampler, &mut counts);
    // The lamp's radiance is its Ke exactly (E/π with E = π·Ke): f32 rounding only.
    assert!((up_from(-0.5) - Vec3::ONE).abs().max_element() < 1e-5, "{}", up_from(-0.5));
    assert_eq!(up_from(0.5), Vec3::ZERO);
}

#[test]
fn an_emission_map_shows_ke_times_the_texel_and_pass_one_emits_each_elements_exact_mean() {
    // The floor emits (Kd 0, Ke 2 × a 4×4 grey checker of sRGB 200 and 60); 2×2 elements of 2×2
    // texels each. Pass one: every element emits E = π·Ke·(mean of its texels), the exact uv mean.
    // Pass two: the EXR convention, an emitter's pixel is its radiance, now Ke × texel, in both modes.
    let grey: Vec<u8> = (0..16).map(|k| if (k % 4 + k / 4) % 2 == 0 { 200 } else { 60 }).collect();
    let png = png_bytes(4, 4, &grey);
    let dir = write_scene("Kd 0 0 0\nKe 2 2 2\nmap_Ke e.png", &[("e.png", &png)], 0.5, 1.0, 1.0, true);
    let s = load(dir.path());
    assert!(s.materials.iter().find(|m| m.name == "floor").expect("floor").is_emitter());
    let (mesh, solution) =
        run::pass_one(&s, None, &RunPhotons::default(), &Progress::hidden(), &mut RunStats::default())
            .expect("pass one");
    let floor = s.materials.iter().position(|m| m.name == "floor").expect("floor") as u32;
    let texel = |v: u8| srgb_to_linear(v as f32 / 255.0);
    let mean = 2.0 * 0.5 * (texel(200) + texel(60));
    let floor_elements: Vec<usize> = (0..mesh.elements.len()).filter(|&e| mesh.elements.material[e] == floor).collect();
    assert_eq!(floor_elements.len(), 4);
    for &e in &floor_elements {
        let emission = mesh.elements.emission[e];
        // f32 sums over 4 texels: 1e-5 relative.
        assert!((emission / (std::f32::consts::PI * mean) - Vec3::ONE).abs().max_element() < 1e-5, "{emission}");
    }
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let tracer = Tracer::new(&mesh, &accel, &solution, &s.materials, &s.render).expect("tracer");
    let (mut sampler, mut counts) = (Sampler::independent(1, 1), RayCounts::default());
    for mode in [TraceMode::Radiosity, TraceMode::Final] {
        for j in 0..4 {
            for i in 0..4 {
                let (u, v) = ((i as f32 + 0.5) / 4.0, (j as f32 + 0.5) / 4.0);
                let origin = Vec3::new(2.0 * u - 1.0, 2.0 * v - 1.0, 0.25);
                let l = tracer.radiance(origin, Vec3::NEG_Z, mode, &mut sampler, &mut counts);
                let expected = 2.0 * texel(grey[(3 - j) * 4 + i]);
                // Kd 0: nothing reflected, the radiance is the texel's Ke·t exactly (f32 rounding).
                assert!((l - Vec3::splat(expected)).abs().max_element() < 1e-5, "{mode:?} texel ({i}, {j}): {l}");
            }
        }
        // The untextured lamp keeps showing its Ke.
        let lamp = tracer.radiance(Vec3::new(0.0, 0.0, 0.5), Vec3::Z, mode, &mut sampler, &mut counts);
        assert!((lamp - Vec3::ONE).abs().max_element() < 1e-5, "{mode:?} lamp {lamp}");
    }
}

/// A grey floor [−1, 1]² at z = 0 facing up (Kd 0.5), a black sheet over it at z = 0.5 facing down whose
/// `map_d` (2×1 texels) is transparent for x < 0 and opaque for x > 0, and a small lamp (half-size
/// 0.05, Ke 1) at z = 1 facing down. Elements of edge 1 (the sheet's 2×2 elements are each all
/// transparent or all opaque); per-pixel direct light with 64 shadow rays.
fn sheet_scene() -> tempfile::TempDir {
    let dir = tempfile::tempdir().expect("temp dir");
    let obj = "mtllib m.mtl\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nv -1 1 0\n\
               v -1 -1 0.5\nv 1 -1 0.5\nv 1 1 0.5\nv -1 1 0.5\n\
               v 0.05 -0.05 1\nv -0.05 -0.05 1\nv -0.05 0.05 1\nv 0.05 0.05 1\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\n\
               usemtl floor\nf 1 2 3 4\nusemtl sheet\nf 5/1 8/4 7/3 6/2\nusemtl lamp\nf 9 10 11 12\n";
    std::fs::write(dir.path().join("m.obj"), obj).expect("write OBJ");
    let mtl =
        "newmtl lamp\nKd 0 0 0\nKe 1 1 1\n\nnewmtl floor\nKd 0.5 0.5 0.5\n\nnewmtl sheet\nKd 0 0 0\nmap_d m.png\n";
    std::fs::write(dir.path().join("m.mtl"), mtl).expect("write MTL");
    std::fs::write(dir.path().join("m.png"), png_bytes(2, 1, &[0, 255])).expect("write mask");
    let toml = "[camera]\neye = [0.0, 0.0, 3.0]\nlook_at = [0.0, 0.0, 0.0]\nup = [0.0, 1.0, 0.0]\nvfov_deg = 60.0\n\n\
                [image]\nwidth = 8\nheight = 8\nsamples_per_pixel = 1\n\n[radiosity]\nmax_element_edge = 1.0\n\n\
                [render]\ndirect = \"pixel\"\nlight_samples = 64\n\n[[mesh]]\nobj = \"m.obj\"\n";
    std::fs::write(dir.path().join("scene.toml"), toml).expect("write scene");
    dir
}

/// Irradiance at (x, 0, 0) on the floor from the small lamp, as a point source of area A = 0.01:
/// E ≈ Le·A·cos θ·cos θ′/d² with d² = x² + 1 and both cosines 1/d.
fn small_lamp_irradiance(x: f32) -> f32 {
    let d2 = x * x + 1.0;
    0.01 / (d2 * d2)
}

#[test]
fn pass_one_sees_through_elements_that_are_mostly_cut_out_and_is_blocked_by_the_rest() {
    let dir = sheet_scene();
    let s = scene::load(&dir.path().join("scene.toml")).expect("scene loads");
    let (mesh, solution) =
        run::pass_one(&s, None, &RunPhotons::default(), &Progress::hidden(), &mut RunStats::default())
            .expect("pass one");
    let sheet = s.materials.iter().position(|m| m.name == "sheet").expect("sheet") as u32;
    let floor = s.materials.iter().position(|m| m.name == "floor").expect("floor") as u32;
    for e in 0..mesh.elements.len() {
        if mesh.elements.material[e] == sheet {
            let left = mesh.elements.centre[e].x < 0.0;
            assert_eq!(mesh.element_coverage[e], if left { 0.0 } else { 1.0 }, "sheet element {e}");
            assert_eq!(mesh.hidden_from_hemicubes(e), left);
        }
    }
    for e in (0..mesh.elements.len()).filter(|&e| mesh.elements.material[e] == floor) {
        let c = mesh.elements.centre[e];
        let direct = solution.element_direct_exitance[e].x;
        if c.x < 0.0 {
            // ρ·E at the element's centre (−0.5, ±0.5): d² = 1.5; hemicube and point-source error ~2%.
            let expected = 0.5 * 0.01 / (1.5 * 1.5);
            assert!((direct / expected - 1.0).abs() < 0.05, "floor element {e} at {c}: {direct} vs {expected}");
        } else {
            assert_eq!(direct, 0.0, "floor element {e} at {c} is under the opaque half");
        }
    }
}

/// The one rule every ray kind uses (camera, gather, shadow, highlight and photon rays): the closest
/// opaque hit passes the cut-out half of the sheet and stops at its opaque half, and the shadow query
/// agrees with it.
#[test]
fn every_ray_kind_shares_one_walk_through_cut_outs() {
    let dir = sheet_scene();
    let s = scene::load(&dir.path().join("scene.toml")).expect("scene loads");
    let (mesh, _) = run::pass_one(&s, None, &RunPhotons::default(), &Progress::hidden(), &mut RunStats::default())
        .expect("pass one");
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let ray = OpaqueRay { mesh: &mesh, accel: &accel, offset: 1e-4, spread_rad: 0.0 };
    let material = |name: &str| s.materials.iter().position(|m| m.name == name).expect("material") as u32;
    // From the floor at x = −0.5 to the lamp's centre: the ray crosses the sheet at x ≈ −0.25, in the
    // hole, and reaches the lamp |(0.5, 0, 0.99)| away.
    let from = Vec3::new(-0.5, 0.0, 0.01);
    let to_lamp = Vec3::new(0.0, 0.0, 1.0) - from;
    let (hit, distance) = ray.closest_hit(from, to_lamp.normalize(), f32::INFINITY).expect("lamp");
    assert_eq!(hit.material, material("lamp"));
    assert!((distance - to_lamp.length()).abs() < 1e-3, "{distance}");
    assert!(ray.blocked(from, to_lamp.normalize(), 2.0), "the lamp itself blocks");
    assert!(!ray.blocked(Vec3::new(-0.5, 0.0, 0.01), Vec3::Z, 0.9), "the hole lets the ray through");
    // Under the opaque half the sheet at z = 0.5 stops it.
    let (hit, distance) = ray.closest_hit(Vec3::new(0.5, 0.0, 0.01), Vec3::Z, f32::INFINITY).expect("sheet");
    assert_eq!(hit.material, material("sheet"));
    assert!((distance - 0.49).abs() < 1e-3, "{distance}");
    assert!(ray.blocked(Vec3::new(0.5, 0.0, 0.01), Vec3::Z, 0.9));
    // A t_max short of the lamp: nothing opaque on the way through the hole.
    assert!(ray.closest_hit(Vec3::new(-0.5, 0.0, 0.01), Vec3::Z, 0.9).is_none());
}

#[test]
fn shadow_rays_pass_through_cut_outs_so_a_leafs_shadow_has_its_holes() {
    let dir = sheet_scene();
    let s = scene::load(&dir.path().join("scene.toml")).expect("scene loads");
    let (mesh, solution) =
        run::pass_one(&s, None, &RunPhotons::default(), &Progress::hidden(), &mut RunStats::default())
            .expect("pass one");
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let tracer = Tracer::new(&mesh, &accel, &solution, &s.materials, &s.render).expect("tracer");
    let (mut sampler, mut counts) = (Sampler::independent(1, 1), RayCounts::default());
    let mut at =
        |x: f32| tracer.radiance(Vec3::new(x, 0.0, 0.25), Vec3::NEG_Z, TraceMode::Final, &mut sampler, &mut counts);
    // Under the hole: L = ρ/π·E. Tolerance 3%: the point-source formula against the 0.1-wide lamp
    // (≈0.5%) and 64 stratified shadow rays over it.
    let hole = at(-0.5).x;
    let expected = 0.5 / std::f32::consts::PI * small_lamp_irradiance(-0.5);
    assert!((hole / expected - 1.0).abs() < 0.03, "under the hole {hole}, expected {expected}");
    // Under the opaque half the lamp is hidden and nothing else is lit: black, up to the f32 rounding
    // of the interpolated B − B_direct (measured 1.4e-6, 0.1% of the lit side).
    let shadow = at(0.5).max_element();
    assert!(shadow < 1e-2 * hole, "under the opaque half {shadow}, under the hole {hole}");
}

#[test]
fn an_object_whose_faces_only_partly_have_vt_keeps_uv_on_those_that_do() {
    // One object, one textured material (Kd 0.5 × a 2×1 texture of sRGB 255 | 0): the first quad has
    // `vt` over the unit square, the second (beside it) none. The first keeps its uv, so its left and
    // right elements see white and black texels (ρ̄ = 0.5 and 0); the second warns once and uses Kd.
    let dir = tempfile::tempdir().expect("temp dir");
    let obj = "mtllib m.mtl\no wall\nv 0 0 0\nv 2 0 0\nv 2 1 0\nv 0 1 0\nv 3 0 0\nv 5 0 0\nv 5 1 0\nv 3 1 0\n\
               vt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nusemtl wall\nf 1/1 2/2 3/3 4/4\nf 5 6 7 8\n\
               usemtl lamp\nf 5 8 4 1\n";
    std::fs::write(dir.path().join("m.obj"), obj).expect("write OBJ");
    let mtl = "newmtl lamp\nKd 0 0 0\nKe 1 1 1\n\nnewmtl wall\nKd 0.5 0.5 0.5\nmap_Kd t.png\n";
    std::fs::write(dir.path().join("m.mtl"), mtl).expect("write MTL");
    std::fs::write(dir.path().join("t.png"), png_bytes(2, 1, &[255, 0])).expect("write texture");
    let toml = "[radiosity]\nmax_element_edge = 1.0\n\n[[mesh]]\nobj = \"m.obj\"\n";
    std::fs::write(dir.path().join("scene.toml"), toml).expect("write scene");
    let s = load(dir.path());
    let notes: Vec<&String> = s.warnings.iter().filter(|w| w.contains("texture coordinates")).collect();
    assert_eq!(notes.len(), 1, "{:?}", s.warnings);
    assert!(notes[0].contains("1 face(s)"), "{}", notes[0]);
    let material = s.materials.iter().position(|m| m.name == "wall").expect("wall") as u32;
    let wall: Vec<&scene::Surface> = s.surfaces.iter().filter(|f| f.material == material).collect();
    assert_eq!(wall.len(), 2);
    assert_eq!(wall[0].uvs.as_deref(), Some(&[Vec2::ZERO, Vec2::X, Vec2::ONE, Vec2::Y][..]));
    assert_eq!(wall[1].uvs, None);
    let (textures, _) = SceneTextures::load(&s.materials);
    let mesh = Mesh::build_with_textures(&s, 1.0, Arc::new(textures));
    for e in (0..mesh.elements.len()).filter(|&e| mesh.elements.material[e] == material) {
        let x = mesh.elements.centre[e].x;
        let expected = match x {
            x if x < 1.0 => Vec3::splat(0.5),
            x if x < 2.0 => Vec3::ZERO,
            _ => Vec3::splat(0.5),
        };
        // The exact texel mean in f32: 1e-6.
        assert!((mesh.elements.reflectance[e] - expected).abs().max_element() < 1e-6, "element at x = {x}");
    }
}
