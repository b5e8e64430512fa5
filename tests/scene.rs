//! Scene files: the documented format loads, and every kind of bad input gives its error with file and
//! line instead of a panic.

use radray::mesh::Mesh;
use radray::scene::{self, SceneError};
use std::path::{Path, PathBuf};

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

/// Writes `files` (name, text) into a fresh directory and parses `scene.toml` from it.
fn parse_files(files: &[(&str, &str)]) -> (tempfile::TempDir, Result<scene::SceneDescription, SceneError>) {
    let dir = tempfile::tempdir().unwrap();
    for (name, text) in files {
        std::fs::write(dir.path().join(name), text).unwrap();
    }
    let result = scene::load(&dir.path().join("scene.toml"));
    (dir, result)
}

fn error_of(toml: &str) -> String {
    let (_dir, result) = parse_files(&[("scene.toml", toml)]);
    match result {
        Ok(_) => panic!("expected an error for:\n{toml}"),
        Err(e) => e.to_string(),
    }
}

const CAMERA: &str = "[camera]\neye = [0, 0, -5]\nlook_at = [0, 0, 0]\nup = [0, 1, 0]\nvfov_deg = 40\n";
const LIGHT_AND_QUAD: &str = r#"
[[material]]
name = "lamp"
ke = [1, 1, 1]

[[quad]]
corners = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
material = "lamp"
"#;

#[test]
fn shipped_scenes_load_with_their_materials() {
    let s = scene::load(&scenes_dir().join("cornell_box.toml")).unwrap();
    assert_eq!(s.surfaces.len(), 6 + 10);
    let light = s.materials.iter().find(|m| m.name == "light").unwrap();
    assert_eq!(light.emitted_radiance.to_array(), [17.0, 12.0, 4.0]);
    assert_eq!(s.radiosity.max_element_edge, 25.0);
    assert_eq!(s.radiosity.hemicube_resolution_px, 256);
    assert!(s.warnings.is_empty(), "{:?}", s.warnings);
    let glass = scene::load(&scenes_dir().join("cornell_specular.toml")).unwrap();
    let g = glass.materials.iter().find(|m| m.name == "glass").unwrap();
    assert!(g.is_dielectric() && (g.ior - 1.5).abs() < 1e-6);
}

#[test]
fn camera_and_one_mesh_are_enough() {
    let (_d, r) = parse_files(&[("scene.toml", &format!("{CAMERA}{LIGHT_AND_QUAD}"))]);
    let s = r.unwrap();
    assert_eq!(s.image.width_px, 256);
    assert!(s.radiosity.max_element_edge.is_finite() && s.radiosity.max_element_edge > 0.0);
}

#[test]
fn meshing_respects_max_element_edge_and_preserves_area() {
    let s = scene::load(&scenes_dir().join("cornell_box.toml")).unwrap();
    let mesh = Mesh::build(&s, 25.0);
    let e = &mesh.elements;
    for i in 0..e.len() {
        let poly: Vec<_> = e.polygon(&mesh.positions, i).collect();
        for k in 0..poly.len() {
            let len = (poly[(k + 1) % poly.len()] - poly[k]).length();
            // Bilinear grid pieces of an edge are at most max_edge long; 1e-3 mm is f32 rounding.
            assert!(len <= 25.0 + 1e-3, "element {i} edge {len}");
        }
    }
    // Quad grids of planar quads tile them exactly: the floor is 552.8 (front) / 549.6 (back) by 559.2.
    let floor_area: f64 = (0..e.len()).filter(|&i| e.surface[i] == 0).map(|i| e.area[i] as f64).sum();
    let exact = 0.5 * (552.8 + 549.6) * 559.2;
    assert!((floor_area - exact).abs() / exact < 1e-5, "{floor_area} vs {exact}");
}

#[test]
fn unknown_key_names_its_line() {
    let msg = error_of(&format!("{CAMERA}\n[radiosity]\nhemicube_res = 64\n{LIGHT_AND_QUAD}"));
    assert!(msg.contains("scene.toml:8:") && msg.contains("hemicube_res"), "{msg}");
}

#[test]
fn syntax_error_names_its_line() {
    let msg = error_of(&format!("{CAMERA}\n[image]\nwidth = = 3\n"));
    assert!(msg.contains("scene.toml:8:"), "{msg}");
}

#[test]
fn missing_obj_is_an_error_with_its_line() {
    let msg = error_of(&format!("{CAMERA}\n[[mesh]]\nobj = \"nope.obj\"\n"));
    assert!(msg.contains("scene.toml:8:") && msg.contains("nope.obj"), "{msg}");
}

#[test]
fn non_finite_numbers_are_refused() {
    let msg = error_of(&format!("{CAMERA}{LIGHT_AND_QUAD}").replace("[1, -1, 0]", "[inf, -1, 0]"));
    assert!(msg.contains("finite"), "{msg}");
    let msg = error_of(&format!("{CAMERA}{LIGHT_AND_QUAD}").replace("ke = [1, 1, 1]", "ke = [nan, 1, 1]"));
    assert!(msg.contains("scene.toml:") && msg.contains("finite"), "{msg}");
}

#[test]
fn kd_of_one_or_more_is_clamped_with_one_warning_and_negative_kd_is_refused() {
    let toml = format!("{CAMERA}{LIGHT_AND_QUAD}\n[[material]]\nname = \"bad\"\nkd = [1.0, 0.5, 0.5]\n");
    let (_d, r) = parse_files(&[("scene.toml", &toml)]);
    let s = r.unwrap();
    let m = s.materials.iter().find(|m| m.name == "bad").unwrap();
    assert_eq!(m.diffuse_reflectance.x, radray::material::ALBEDO_CEILING);
    let clamped: Vec<&String> = s.warnings.iter().filter(|w| w.contains("clamped")).collect();
    assert_eq!(clamped.len(), 1, "{:?}", s.warnings);
    assert!(clamped[0].contains("scene.toml:17:") && clamped[0].contains("`bad`") && clamped[0].contains("Kd"));
    let msg = error_of(&toml.replace("kd = [1.0, 0.5, 0.5]", "kd = [-0.1, 0.5, 0.5]"));
    assert!(msg.contains("scene.toml:17:") && msg.contains("Kd"), "{msg}");
}

#[test]
fn material_scalars_out_of_range_name_their_key_and_line() {
    let bad = |key: &str| format!("{CAMERA}{LIGHT_AND_QUAD}\n[[material]]\nname = \"bad\"\n{key}\n");
    for (key, expected) in [
        ("ns = -2", "scene.toml:17: ns (Phong exponent) must be a positive number, got -2"),
        ("ni = 0", "scene.toml:17: ni (index of refraction) must be a positive number, got 0"),
        ("d = 1.5", "scene.toml:17: d (dissolve) must be in [0, 1], got 1.5"),
        ("d = nan", "scene.toml:17: d (dissolve) must be in [0, 1], got NaN"),
    ] {
        let msg = error_of(&bad(key));
        assert!(msg.ends_with(expected), "{key}: {msg}");
    }
}

#[test]
fn energy_creating_material_is_refused() {
    let toml =
        format!("{CAMERA}{LIGHT_AND_QUAD}\n[[material]]\nname = \"bad\"\nkd = [0.6, 0.6, 0.6]\nks = [0.5, 0.5, 0.5]\n");
    assert!(error_of(&toml).contains("exceeds 1"));
    let toml = format!("{CAMERA}{LIGHT_AND_QUAD}\n[[material]]\nname = \"bad\"\nkd = [0.5, 0.5, 0.5]\nd = 0.3\n");
    assert!(error_of(&toml).contains("exceeds 1"));
}

#[test]
fn impossible_cameras_are_refused() {
    let base = format!("{CAMERA}{LIGHT_AND_QUAD}");
    for (from, to, expect) in [
        ("vfov_deg = 40", "vfov_deg = 180", "vfov_deg"),
        ("vfov_deg = 40", "vfov_deg = 0", "vfov_deg"),
        ("look_at = [0, 0, 0]", "look_at = [0, 0, -5]", "look_at"),
        ("up = [0, 1, 0]", "up = [0, 0, 2]", "parallel"),
    ] {
        let msg = error_of(&base.replace(from, to));
        assert!(msg.contains(expect) && msg.contains("scene.toml:"), "{to}: {msg}");
    }
}

#[test]
fn impossible_image_sizes_are_refused() {
    let msg = error_of(&format!("{CAMERA}\n[image]\nwidth = 0\n{LIGHT_AND_QUAD}"));
    assert!(msg.contains("scene.toml:8:") && msg.contains("width"), "{msg}");
    let msg = error_of(&format!("{CAMERA}\n[image]\nsamples_per_pixel = -4\n{LIGHT_AND_QUAD}"));
    assert!(msg.contains("samples_per_pixel"), "{msg}");
    let msg = error_of(&format!("{CAMERA}\n[image]\nadaptive_budget = -0.5\n{LIGHT_AND_QUAD}"));
    assert!(msg.contains("scene.toml:8:") && msg.contains("adaptive_budget"), "{msg}");
}

#[test]
fn malformed_obj_names_file_and_line() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n";
    let (_d, r) = parse_files(&[("scene.toml", &format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("m.obj:4:"), "{msg}");
}

#[test]
fn missing_mtl_is_a_clear_error() {
    let obj = "mtllib nothere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let (_d, r) = parse_files(&[("scene.toml", &format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("m.obj") && msg.contains("material"), "{msg}");
}

#[test]
fn degenerate_faces_are_skipped_and_counted() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 2 0 0\nf 1 2 3\nf 1 2 4\nf 1 1 3\n";
    let (_d, r) = parse_files(&[("scene.toml", &format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let s = r.unwrap();
    assert_eq!(s.surfaces.len(), 1);
    assert!(s.warnings.iter().any(|w| w.contains("skipped 2 degenerate")), "{:?}", s.warnings);
}

#[test]
fn scene_without_emitter_is_a_warning() {
    let toml = format!("{CAMERA}{LIGHT_AND_QUAD}").replace("ke = [1, 1, 1]", "kd = [0.5, 0.5, 0.5]");
    let (_d, r) = parse_files(&[("scene.toml", &toml)]);
    let s = r.unwrap();
    assert!(s.warnings.iter().any(|w| w.contains("no emitter")), "{:?}", s.warnings);
}

#[test]
fn unknown_material_name_is_an_error() {
    let msg = error_of(&format!("{CAMERA}{LIGHT_AND_QUAD}").replace("material = \"lamp\"", "material = \"lmap\""));
    assert!(msg.contains("lmap") && msg.contains("scene.toml:"), "{msg}");
}

#[test]
fn inline_box_faces_point_the_chosen_way() {
    let toml = format!(
        "{CAMERA}{LIGHT_AND_QUAD}\n[[material]]\nname = \"w\"\nkd = [0.5, 0.5, 0.5]\n[[box]]\nmin = [0, 0, 0]\nmax = [1, 2, 3]\nmaterial = \"w\"\n[[box]]\nmin = [0, 0, 0]\nmax = [1, 2, 3]\nmaterial = \"w\"\ninward = true\n"
    );
    let (_d, r) = parse_files(&[("scene.toml", &toml)]);
    let s = r.unwrap();
    let centre = glam::Vec3::new(0.5, 1.0, 1.5);
    for (k, surf) in s.surfaces.iter().skip(1).enumerate() {
        let v = &surf.vertices;
        let n = (v[1] - v[0]).cross(v[2] - v[0]);
        let outward = n.dot(v[0] - centre) > 0.0;
        assert_eq!(outward, k < 6, "face {k}");
    }
}

#[test]
fn two_sided_surfaces_get_a_back_side() {
    let toml =
        format!("{CAMERA}{LIGHT_AND_QUAD}").replace("material = \"lamp\"", "material = \"lamp\"\ntwo_sided = true");
    let (_d, r) = parse_files(&[("scene.toml", &toml)]);
    let s = r.unwrap();
    let mesh = Mesh::build(&s, 0.5);
    let front = 16;
    assert_eq!(mesh.elements.len(), 2 * front);
    for i in 0..front {
        assert!((mesh.elements.normal[i] + mesh.elements.normal[front + i]).length() < 1e-6);
    }
    assert!(mesh.triangle_back_element.iter().all(|&b| b != radray::mesh::NONE));
}

#[test]
fn element_count_is_known_before_meshing() {
    let s = scene::load(&scenes_dir().join("cornell_box.toml")).unwrap();
    for edge in [100.0, 25.0, 20.0] {
        let mesh = Mesh::build(&s, edge);
        assert_eq!(radray::mesh::count_elements(&s, edge), mesh.elements.len() as u64, "edge {edge}");
    }
    // A count far beyond any machine is computed without allocating it.
    assert!(radray::mesh::count_elements(&s, 1e-3) > 1_000_000_000);
}
