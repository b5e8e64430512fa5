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

/// The adaptive mesh's keys are read, and out-of-range values are refused with file:line.
#[test]
fn adaptive_mesh_keys_are_read_and_checked() {
    let text = format!(
        "{CAMERA}\n[radiosity]\nmethod = \"adaptive\"\nadaptive_levels = 3\nadaptive_threshold = 0.2\n{LIGHT_AND_QUAD}"
    );
    let (_dir, ok) = parse_files(&[("scene.toml", &text)]);
    let ok = ok.unwrap();
    assert_eq!(ok.radiosity.method, radray::scene::MethodChoice::Adaptive);
    assert_eq!((ok.radiosity.adaptive.levels, ok.radiosity.adaptive.threshold), (3, 0.2));
    let msg = error_of(&format!("{CAMERA}\n[radiosity]\nadaptive_threshold = 0.0\n{LIGHT_AND_QUAD}"));
    assert!(msg.contains("scene.toml:8:") && msg.contains("adaptive_threshold"), "{msg}");
    let msg = error_of(&format!("{CAMERA}\n[radiosity]\nadaptive_levels = 9\n{LIGHT_AND_QUAD}"));
    assert!(msg.contains("scene.toml:8:") && msg.contains("adaptive_levels"), "{msg}");
}

#[test]
fn malformed_obj_names_file_and_line() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nf 1 2 x\n";
    let (_d, r) = parse_files(&[("scene.toml", &format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("m.obj:4:"), "{msg}");
}

/// Writes `files` (name, bytes) into a fresh directory and parses `scene.toml` from it.
fn parse_bytes(files: &[(&str, &[u8])]) -> (tempfile::TempDir, Result<scene::SceneDescription, SceneError>) {
    let dir = tempfile::tempdir().unwrap();
    for (name, bytes) in files {
        let path = dir.path().join(name);
        std::fs::create_dir_all(path.parent().unwrap()).unwrap();
        std::fs::write(path, bytes).unwrap();
    }
    let result = scene::load(&dir.path().join("scene.toml"));
    (dir, result)
}

/// A floor quad (material `flöor`, facing +y) and a lamp quad (material `lamp`, facing -y), as a
/// plain UTF-8 exporter writes them.
const PLAIN_OBJ: &str = "mtllib m.mtl\nv 0 0 0\nv 0 0 1\nv 1 0 1\nv 1 0 0\nv 0.3 1 0.3\nv 0.7 1 0.3\nv 0.7 1 0.7\n\
v 0.3 1 0.7\nusemtl flöor\nf 1 2 3 4\nusemtl lamp\nf 5 6 7 8\n";
const PLAIN_MTL: &str = "newmtl flöor\nKd 0.8 0.2 0.2\nnewmtl lamp\nKe 5 5 5\n";

/// The materials each surface got, by name, in file order.
fn material_names(s: &scene::SceneDescription) -> Vec<String> {
    s.surfaces.iter().map(|f| s.materials[f.material as usize].name.clone()).collect()
}

#[test]
fn obj_and_mtl_as_windows_and_old_tools_write_them_read_like_the_plain_files() {
    let scene = format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n");
    let (_d, plain) = parse_bytes(&[
        ("scene.toml", scene.as_bytes()),
        ("m.obj", PLAIN_OBJ.as_bytes()),
        ("m.mtl", PLAIN_MTL.as_bytes()),
    ]);
    let plain = plain.unwrap();
    assert_eq!(material_names(&plain), ["flöor", "lamp"]);
    assert!(plain.warnings.is_empty(), "{:?}", plain.warnings);
    let latin1 = |t: &str| t.chars().map(|c| c as u32 as u8).collect::<Vec<u8>>();
    let bom = |t: &str| [&b"\xEF\xBB\xBF"[..], t.as_bytes()].concat();
    let crlf_tabs = |t: &str| t.replace('\n', "\r\n").replace(' ', "\t");
    let continued = PLAIN_OBJ.replace("f 1 2 3 4", "f 1 2 \\\n 3 4");
    let cases: Vec<(&str, Vec<u8>, Vec<u8>)> = vec![
        ("UTF-8 byte-order marks", bom(PLAIN_OBJ), bom(PLAIN_MTL)),
        ("Latin-1 names", latin1(PLAIN_OBJ), latin1(PLAIN_MTL)),
        ("CRLF and tabs", crlf_tabs(PLAIN_OBJ).into_bytes(), crlf_tabs(PLAIN_MTL).into_bytes()),
        ("a face continued with \\", continued.into_bytes(), PLAIN_MTL.as_bytes().to_vec()),
        (
            "vertex colours",
            PLAIN_OBJ.replace("v 0 0 0\n", "v 0 0 0 1 0 0\n").into_bytes(),
            PLAIN_MTL.as_bytes().to_vec(),
        ),
    ];
    for (what, obj, mtl) in cases {
        let (_d, r) = parse_bytes(&[("scene.toml", scene.as_bytes()), ("m.obj", &obj), ("m.mtl", &mtl)]);
        let s = r.unwrap_or_else(|e| panic!("{what}: {e}"));
        assert_eq!(material_names(&s), ["flöor", "lamp"], "{what}");
        assert_eq!(s.surfaces[0].vertices, plain.surfaces[0].vertices, "{what}");
        assert!(s.warnings.is_empty(), "{what}: {:?}", s.warnings);
    }
    // The spec's `mtllib a.mtl b.mtl`: both libraries are read.
    let obj = PLAIN_OBJ.replace("mtllib m.mtl", "mtllib a.mtl b.mtl");
    let (_d, r) = parse_bytes(&[
        ("scene.toml", scene.as_bytes()),
        ("m.obj", obj.as_bytes()),
        ("a.mtl", "newmtl flöor\nKd 0.8 0.2 0.2\n".as_bytes()),
        ("b.mtl", b"newmtl lamp\nKe 5 5 5\n"),
    ]);
    assert_eq!(material_names(&r.unwrap()), ["flöor", "lamp"]);
}

#[test]
fn a_missing_material_library_is_a_warning_and_its_faces_are_grey() {
    let obj = "mtllib nothere.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\nusemtl a\nf 1 2 3\n";
    let (_d, r) =
        parse_files(&[("scene.toml", &format!("{CAMERA}{LIGHT_AND_QUAD}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let s = r.unwrap();
    let grey = s.surfaces.last().unwrap().material as usize;
    assert_eq!(s.materials[grey].diffuse_reflectance, glam::Vec3::splat(0.5));
    let about = |needle: &str| s.warnings.iter().filter(|w| w.contains(needle)).cloned().collect::<Vec<_>>();
    assert_eq!(about("nothere.mtl").len(), 1, "{:?}", s.warnings);
    assert!(about("nothere.mtl")[0].contains("m.obj:1:"), "{:?}", s.warnings);
    assert_eq!(about("`usemtl a`").len(), 1, "{:?}", s.warnings);
    assert!(about("`usemtl a`")[0].contains("m.obj:5:"), "{:?}", s.warnings);
}

#[test]
fn a_nameless_or_undefined_usemtl_warns_once_with_its_line_and_its_faces_are_grey() {
    let mut obj = String::from("mtllib m.mtl\nv 0 0 0\nv 1 0 0\nv 0 1 0\n");
    for _ in 0..1000 {
        obj.push_str("usemtl nosuch\nf 1 2 3\nusemtl\nf 1 2 3\n");
    }
    let (_d, r) = parse_files(&[
        ("scene.toml", &format!("{CAMERA}{LIGHT_AND_QUAD}[[mesh]]\nobj = \"m.obj\"\n")),
        ("m.obj", &obj),
        ("m.mtl", "newmtl white\nKd 0.7 0.7 0.7\n"),
    ]);
    let s = r.unwrap();
    let obj_warnings: Vec<&String> = s.warnings.iter().filter(|w| w.contains("m.obj")).collect();
    assert_eq!(obj_warnings.len(), 3, "{obj_warnings:?}");
    assert!(obj_warnings
        .iter()
        .any(|w| w.contains("m.obj:5:") && w.contains("`usemtl nosuch`") && w.contains("999 more")));
    assert!(obj_warnings.iter().any(|w| w.contains("m.obj:7:") && w.contains("without a name")));
    assert!(obj_warnings.iter().any(|w| w.contains("2000 face(s) have no material")));
}

#[test]
fn a_concave_obj_face_is_ear_clipped_into_front_facing_triangles() {
    // An L-shaped hexagon of area 0.75 facing +y, written from the corner next to its reflex corner:
    // a fan from there puts back-facing triangles over the missing quarter.
    let obj = "v 1 0 0.5\nv 0.5 0 0.5\nv 0.5 0 1\nv 0 0 1\nv 0 0 0\nv 1 0 0\nf 1 6 5 4 3 2\n";
    let (_d, r) =
        parse_files(&[("scene.toml", &format!("{CAMERA}{LIGHT_AND_QUAD}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let s = r.unwrap();
    let triangles: Vec<_> = s.surfaces.iter().filter(|f| f.vertices.iter().all(|v| v.y == 0.0)).collect();
    assert_eq!(triangles.len(), 4);
    let normals: Vec<glam::Vec3> =
        triangles.iter().map(|t| 0.5 * (t.vertices[1] - t.vertices[0]).cross(t.vertices[2] - t.vertices[0])).collect();
    assert!(normals.iter().all(|n| n.y > 0.0), "{normals:?}");
    let area: f32 = normals.iter().map(|n| n.y).sum();
    assert!((area - 0.75).abs() < 1e-6, "{area}");
}

#[test]
fn unusable_normals_are_dropped_and_lines_and_points_are_not_faces() {
    let obj = "v 0 0 0\nv 1 0 0\nv 0 1 0\nvn 0 0 0\nvn nan 0 1\nvn 0 0 1\nf 1//1 2//3 3//3\nf 1//2 2//3 3//3\n\
f 1//3 2//3 3//3\nl 1 2 3\np 1\n";
    let (_d, r) =
        parse_files(&[("scene.toml", &format!("{CAMERA}{LIGHT_AND_QUAD}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let s = r.unwrap();
    let from_obj: Vec<_> = s.surfaces.iter().filter(|f| f.source.path.ends_with("m.obj")).collect();
    assert_eq!(from_obj.len(), 3);
    let kept: Vec<bool> = from_obj.iter().map(|f| f.shading_normals.is_some()).collect();
    assert_eq!(kept, [false, false, true]);
    assert_eq!(s.warnings.iter().filter(|w| w.contains("2 face(s) name a zero-length or non-finite `vn`")).count(), 1);
}

#[test]
fn a_huge_coordinate_is_an_error_with_file_and_line() {
    let obj = "v 0 0 0\nv 1 0 0\nv 1e30 1 0\nf 1 2 3\n";
    let (_d, r) = parse_files(&[("scene.toml", &format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", obj)]);
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("m.obj:3:") && msg.contains("1e30"), "{msg}");
}

#[test]
fn a_primitive_beyond_the_coordinate_limit_is_an_error_not_a_panic() {
    // 2·10¹⁸ wide at 10²⁵: a finite area, but bounds the BVH builder panicked on.
    let quad = "[[quad]]\ncorners = [[1e25, 0, 0], [1.000001e25, 0, 0], [1.000001e25, 1e19, 0], [1e25, 1e19, 0]]\n\
material = \"lamp\"\n";
    let msg = error_of(&format!("{CAMERA}{LIGHT_AND_QUAD}{quad}"));
    assert!(msg.contains("scene.toml:") && msg.contains("beyond"), "{msg}");
}

#[test]
fn an_obj_without_faces_is_named_when_the_scene_is_empty() {
    let (_d, r) =
        parse_files(&[("scene.toml", &format!("{CAMERA}[[mesh]]\nobj = \"m.obj\"\n")), ("m.obj", "# empty\n")]);
    let msg = r.unwrap_err().to_string();
    assert!(msg.contains("no surfaces") && msg.contains("m.obj has no faces"), "{msg}");
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
