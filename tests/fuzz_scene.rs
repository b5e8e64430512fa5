//! Fuzzing of the scene parser (proptest): whatever the scene text or OBJ file, loading returns a
//! scene or an error that names a file — never a panic — and a scene that loads meshes without NaN.
//!
//! The case counts are small so that the file runs in a few seconds in the test profile. To fuzz for
//! longer, raise them all at once (the count applies to each property):
//!
//! ```text
//! PROPTEST_CASES=100000 cargo test --test fuzz_scene
//! ```

use proptest::prelude::*;
use proptest::test_runner::Config;
use radray::mesh::Mesh;
use radray::scene::{self, SceneError};
use std::path::{Path, PathBuf};

/// `PROPTEST_CASES` from the environment, else `default`.
fn config(default: u32) -> Config {
    let cases = std::env::var("PROPTEST_CASES").ok().and_then(|s| s.parse().ok()).unwrap_or(default);
    Config { cases, failure_persistence: None, ..Config::default() }
}

fn scenes_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes")
}

const SHIPPED: [&str; 4] = ["cornell_box.toml", "cornell_empty.toml", "cornell_specular.toml", "furnace.toml"];

/// Every error names a file: the scene file for scene errors, the OBJ/MTL file for errors inside it.
fn assert_names_a_file(err: &SceneError, scene_path: &Path) {
    let message = err.to_string();
    match err {
        SceneError::Obj(_) => assert!(message.contains(".obj") || message.contains(".mtl"), "{message}"),
        _ => assert!(message.contains(&scene_path.display().to_string()), "error does not name the file: {message}"),
    }
}

/// Meshes a loaded scene and checks what the solver relies on: finite positive areas, unit normals.
fn assert_meshes_cleanly(scene: &scene::SceneDescription) {
    let mesh = Mesh::build(scene, scene.radiosity.max_element_edge);
    for (e, (&area, normal)) in mesh.elements.area.iter().zip(&mesh.elements.normal).enumerate() {
        assert!(area.is_finite() && area > 0.0, "element {e} has area {area}");
        // A unit normal computed in f32: 1e-3 is ~10⁴ ulps, far above rounding, far below an error.
        assert!(normal.is_finite() && (normal.length() - 1.0).abs() < 1e-3, "element {e} has normal {normal}");
    }
    assert!(mesh.positions.iter().all(|p| p.is_finite()), "non-finite mesh position");
}

// ---------------------------------------------------------------------------------------------------
// (a) Random bytes and random strings as scene TOML.

/// Fragments of the scene language, so that random text reaches past the TOML syntax into the checks.
const TOKENS: &[&str] = &[
    "[camera]",
    "[image]",
    "[radiosity]",
    "[render]",
    "[[material]]",
    "[[mesh]]",
    "[[quad]]",
    "[[triangle]]",
    "[[box]]",
    "[[sphere]]",
    "eye = ",
    "look_at = ",
    "up = ",
    "vfov_deg = ",
    "width = ",
    "height = ",
    "samples_per_pixel = ",
    "filter = ",
    "max_element_edge = ",
    "hemicube_resolution = ",
    "solver = ",
    "name = ",
    "kd = ",
    "ke = ",
    "ks = ",
    "ns = ",
    "ni = ",
    "d = ",
    "obj = ",
    "scale = ",
    "translate = ",
    "corners = ",
    "vertices = ",
    "material = ",
    "min = ",
    "max = ",
    "inward = ",
    "center = ",
    "radius = ",
    "segments = ",
    "two_sided = ",
    "\"m\"",
    "\"gauss-seidel\"",
    "\"tent\"",
    "\"none.obj\"",
    "[0, 0, 0]",
    "[1, 1, 1]",
    "[0, 0, -5]",
    "[[0,0,0],[1,0,0],[1,1,0],[0,1,0]]",
    "[[0,0,0],[1,0,0],[0,1,0]]",
    "[]",
    "[[]]",
    "{}",
    "0",
    "1",
    "-1",
    "0.5",
    "40",
    "1e30",
    "nan",
    "inf",
    "-inf",
    "99999999999999999999",
    "9223372036854775807",
    "true",
    "\n",
    "\n",
    " ",
    "#",
    "=",
    ",",
    "\"",
    "é",
    "\u{1F600}",
];

fn token_text() -> impl Strategy<Value = String> {
    prop::collection::vec(prop::sample::select(TOKENS), 0..60).prop_map(|t| t.concat())
}

proptest! {
    #![proptest_config(config(256))]

    #[test]
    fn random_bytes_never_panic(bytes in prop::collection::vec(any::<u8>(), 0..400)) {
        let text = String::from_utf8_lossy(&bytes);
        let path = Path::new("fuzz/scene.toml");
        if let Err(e) = scene::parse_str(&text, path) {
            assert_names_a_file(&e, path);
        }
    }

    #[test]
    fn random_strings_never_panic(text in "\\PC{0,300}") {
        let path = Path::new("fuzz/scene.toml");
        if let Err(e) = scene::parse_str(&text, path) {
            assert_names_a_file(&e, path);
        }
    }

    #[test]
    fn random_scene_fragments_never_panic(text in token_text()) {
        let path = Path::new("fuzz/scene.toml");
        match scene::parse_str(&text, path) {
            Ok(s) => {
                // Inline primitives only (the OBJ does not exist): keep meshing affordable.
                if s.radiosity.max_element_edge > 1e-3 * s.surfaces.iter().flat_map(|s| &s.vertices)
                    .fold(0.0f32, |m, v| m.max(v.abs().max_element())) {
                    assert_meshes_cleanly(&s);
                }
            }
            Err(e) => assert_names_a_file(&e, path),
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// (b) Mutations of the shipped scene texts.

const NASTY: &[&str] = &[
    "nan",
    "+nan",
    "-nan",
    "inf",
    "-inf",
    "-1",
    "0",
    "-0.0",
    "1e30",
    "-1e30",
    "1e-30",
    "1e-9",
    "3.5e38",
    "99999999999999999999",
    "9223372036854775807",
    "-9223372036854775808",
    "4294967296",
    "4294967295",
    "65537",
    "3",
    "[]",
    "[[]]",
    "[1, 2]",
    "[1, 2, 3, 4]",
    "\"text\"",
    "\"\"",
    "true",
    "{}",
];

#[derive(Clone, Debug)]
enum Mutation {
    Delete(usize),
    Duplicate(usize),
    /// Replace line `.0` by line `.1` (of any shipped scene).
    Replace(usize, usize),
    /// Replace the `.1`-th number of line `.0` by `NASTY[.2]`.
    Number(usize, usize, usize),
    /// Replace the value after `=` on line `.0` by `NASTY[.1]`.
    Value(usize, usize),
}

fn mutation() -> impl Strategy<Value = Mutation> {
    let i = any::<prop::sample::Index>();
    prop_oneof![
        i.clone().prop_map(|a| Mutation::Delete(a.index(1 << 20))),
        i.clone().prop_map(|a| Mutation::Duplicate(a.index(1 << 20))),
        (i.clone(), i.clone()).prop_map(|(a, b)| Mutation::Replace(a.index(1 << 20), b.index(1 << 20))),
        (i.clone(), 0..8usize, 0..NASTY.len()).prop_map(|(a, k, n)| Mutation::Number(a.index(1 << 20), k, n)),
        (i, 0..NASTY.len()).prop_map(|(a, n)| Mutation::Value(a.index(1 << 20), n)),
    ]
}

/// Splits a line into tokens and separators, so that numbers can be swapped in place.
fn replace_number(line: &str, which: usize, by: &str) -> String {
    let mut out = String::new();
    let mut numbers = Vec::new();
    let mut token = String::new();
    let mut pieces: Vec<(String, bool)> = Vec::new();
    for c in line.chars() {
        if "[],= {}".contains(c) {
            if !token.is_empty() {
                pieces.push((std::mem::take(&mut token), true));
            }
            pieces.push((c.to_string(), false));
        } else {
            token.push(c);
        }
    }
    if !token.is_empty() {
        pieces.push((token, true));
    }
    for (k, (p, is_token)) in pieces.iter().enumerate() {
        if *is_token && p.trim().parse::<f64>().is_ok() {
            numbers.push(k);
        }
    }
    if numbers.is_empty() {
        return line.to_string();
    }
    let target = numbers[which % numbers.len()];
    for (k, (p, _)) in pieces.iter().enumerate() {
        out.push_str(if k == target { by } else { p });
    }
    out
}

fn mutate(text: &str, all_lines: &[String], mutations: &[Mutation]) -> String {
    let mut lines: Vec<String> = text.lines().map(str::to_string).collect();
    for m in mutations {
        if lines.is_empty() {
            break;
        }
        let n = lines.len();
        match *m {
            Mutation::Delete(i) => {
                lines.remove(i % n);
            }
            Mutation::Duplicate(i) => {
                let l = lines[i % n].clone();
                lines.insert(i % n, l);
            }
            Mutation::Replace(i, j) => lines[i % n] = all_lines[j % all_lines.len()].clone(),
            Mutation::Number(i, k, v) => lines[i % n] = replace_number(&lines[i % n], k, NASTY[v]),
            Mutation::Value(i, v) => {
                if let Some((key, _)) = lines[i % n].split_once('=') {
                    lines[i % n] = format!("{key}= {}", NASTY[v]);
                }
            }
        }
    }
    lines.join("\n")
}

fn shipped_texts() -> Vec<(PathBuf, String)> {
    SHIPPED
        .iter()
        .map(|name| {
            let path = scenes_dir().join(name);
            let text = std::fs::read_to_string(&path).expect("shipped scene is readable");
            (path, text)
        })
        .collect()
}

proptest! {
    #![proptest_config(config(96))]

    #[test]
    fn mutated_shipped_scenes_never_panic(
        which in 0..SHIPPED.len(),
        mutations in prop::collection::vec(mutation(), 1..6),
    ) {
        let texts = shipped_texts();
        let all_lines: Vec<String> = texts.iter().flat_map(|(_, t)| t.lines().map(str::to_string)).collect();
        let (path, text) = &texts[which];
        let mutated = mutate(text, &all_lines, &mutations);
        // Parsed in place so that the OBJ paths resolve; nothing is written.
        match scene::parse_str(&mutated, path) {
            Ok(s) => prop_assert!(!s.surfaces.is_empty()),
            Err(e) => assert_names_a_file(&e, path),
        }
    }
}

// ---------------------------------------------------------------------------------------------------
// (c) Random and mutated OBJ files, loaded through a scene's [[mesh]].

/// The materials of the random OBJs (`white`, `lamp`) and of the shipped ones.
const MTL: &str = "newmtl white\nKd 0.5 0.5 0.5\n\nnewmtl lamp\nKd 0 0 0\nKe 4 4 4\n\nnewmtl red\nKd 0.6 0.1 0.1\n\n\
newmtl green\nKd 0.1 0.5 0.1\n\nnewmtl light\nKe 17 12 4\n\nnewmtl gray_emitter\nKd 0.5 0.5 0.5\nKe 1 1 1\n";

fn coordinate() -> impl Strategy<Value = String> {
    prop_oneof![
        20 => (-4i32..=4).prop_map(|x| x.to_string()),
        12 => (-10.0f64..10.0).prop_map(|x| format!("{x:.3}")),
        // Rarely, so that most files stay loadable and reach the mesher.
        1 => prop::sample::select(&["1e30", "-1e30", "1e-30", "3.5e38", "nan", "inf", "x", "1,5", "", "0x10"][..])
            .prop_map(str::to_string),
    ]
}

fn face_index(vertex_count: usize) -> impl Strategy<Value = String> {
    let n = vertex_count.max(1) as i64;
    prop_oneof![
        24 => (1..=n).prop_map(|i| i.to_string()),
        6 => (-n..=-1).prop_map(|i| i.to_string()),
        1 => (1..=n).prop_map(|i| format!("{i}//1")),
        1 => (1..=n).prop_map(|i| format!("{i}/1/1")),
        1 => prop::sample::select(&["0", "-999", "999", "99999999999999999999", "a", "1/", "/1", "//", "1/-5"][..])
            .prop_map(str::to_string),
    ]
}

fn obj_line(vertex_count: usize) -> impl Strategy<Value = String> {
    prop_oneof![
        6 => (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| format!("v {x} {y} {z}")),
        8 => prop::collection::vec(face_index(vertex_count), 3..8).prop_map(|i| format!("f {}", i.join(" "))),
        1 => prop::collection::vec(face_index(vertex_count), 0..3).prop_map(|i| format!("f {}", i.join(" "))),
        1 => (coordinate(), coordinate(), coordinate()).prop_map(|(x, y, z)| format!("vn {x} {y} {z}")),
        1 => (coordinate(), coordinate()).prop_map(|(u, v)| format!("vt {u} {v}")),
        2 => prop::sample::select(&["usemtl white", "usemtl lamp", "usemtl missing", "usemtl"][..])
            .prop_map(str::to_string),
        1 => prop::sample::select(&["mtllib m.mtl", "mtllib missing.mtl", "mtllib", "mtllib ../m.mtl"][..])
            .prop_map(str::to_string),
        1 => prop::sample::select(&["o part", "g group", "s 1", "s off", "# comment", "", "l 1 2", "p 1", "junk 1 2"][..])
            .prop_map(str::to_string),
    ]
}

/// A texture coordinate, a normal, a cube's eight corners and six quad faces (one of them a lamp), then random lines.
fn obj_text() -> impl Strategy<Value = String> {
    let base =
        "mtllib m.mtl\nvt 0 0\nvn 0 0 1\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nv 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n";
    (prop::collection::vec(obj_line(8), 0..30), any::<bool>(), any::<prop::sample::Index>()).prop_map(
        move |(lines, with_cube, at)| {
            let mut text = String::from(base);
            if with_cube {
                text.push_str("usemtl white\nf 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\nf 4 8 7 3\nf 1 5 8 4\n");
                text.push_str("usemtl lamp\nf 2 3 7 6\n");
            }
            // Random lines go at the end, or (a quarter of the time) anywhere — where faces may name
            // vertices that are not defined yet.
            let mut all: Vec<String> = text.lines().map(str::to_string).collect();
            let k = at.index(4 * (all.len() + 1)).min(all.len());
            for (n, l) in lines.into_iter().enumerate() {
                all.insert((k + n).min(all.len()), l);
            }
            all.join("\n") + "\n"
        },
    )
}

/// Shipped OBJ text with random line edits (as in (b), but on the OBJ). New faces use the first four
/// vertices, which exist from the first face on.
fn mutated_shipped_obj() -> impl Strategy<Value = String> {
    let texts: Vec<String> = ["cornell_original", "cornell_empty", "furnace"]
        .iter()
        .map(|d| std::fs::read_to_string(scenes_dir().join(d).join("scene.obj")).expect("shipped OBJ is readable"))
        .collect();
    (0..texts.len(), prop::collection::vec((any::<prop::sample::Index>(), obj_line(4), 0..3u8), 1..8)).prop_map(
        move |(which, edits)| {
            let mut lines: Vec<String> = texts[which].lines().map(str::to_string).collect();
            for (at, line, kind) in edits {
                let k = at.index(lines.len());
                match kind {
                    0 => lines[k] = line,
                    1 => lines.insert(k, line),
                    _ => {
                        lines.remove(k);
                    }
                }
                if lines.is_empty() {
                    lines.push(String::new());
                }
            }
            // The shipped files name `scene.mtl`; the fuzz directory holds `m.mtl`.
            // One texture coordinate and one normal, for the `i/1/1` and `i//1` face vertices.
            "vt 0 0\nvn 0 0 1\n".to_string() + &lines.join("\n").replace("mtllib scene.mtl", "mtllib m.mtl")
        },
    )
}

fn load_obj_scene(obj: &str, scale: &str) -> (tempfile::TempDir, PathBuf, Result<scene::SceneDescription, SceneError>) {
    let dir = tempfile::tempdir().expect("temp dir");
    std::fs::write(dir.path().join("m.obj"), obj).expect("write OBJ");
    std::fs::write(dir.path().join("m.mtl"), MTL).expect("write MTL");
    let toml = format!("[radiosity]\nmax_element_edge = 0.25\n\n[[mesh]]\nobj = \"m.obj\"\n{scale}");
    let path = dir.path().join("scene.toml");
    std::fs::write(&path, toml).expect("write scene");
    let result = scene::load(&path);
    (dir, path, result)
}

/// An OBJ scene loads or fails with a named file; if it loads, it meshes cleanly. The element size is
/// fixed at 0.25, so a scene spread over 1e30 would mesh into an astronomic count: those are checked
/// at their own default size (1/30 of the diagonal) instead.
fn check_obj(obj: &str, scale: &str) {
    let (_dir, path, result) = load_obj_scene(obj, scale);
    match result {
        Ok(mut s) => {
            let extent = s.surfaces.iter().flat_map(|s| &s.vertices).fold(0.0f32, |m, v| m.max(v.abs().max_element()));
            if extent > 100.0 {
                s.radiosity.max_element_edge = f32::INFINITY;
            }
            assert_meshes_cleanly(&s);
        }
        Err(e) => assert_names_a_file(&e, &path),
    }
}

proptest! {
    #![proptest_config(config(64))]

    #[test]
    fn random_obj_files_never_panic(obj in obj_text(), mirrored in any::<bool>()) {
        check_obj(&obj, if mirrored { "scale = [-1, 1, 1]\n" } else { "" });
    }

    #[test]
    fn mutated_shipped_obj_files_never_panic(obj in mutated_shipped_obj()) {
        check_obj(&obj, "scale = 0.001\n");
    }
}

// ---------------------------------------------------------------------------------------------------
// (d) Random MTL files as exporters write them: illum models, Tr, Tf, texture maps with options,
// unknown statements, Windows line endings and tabs. The random statements apply to `white`, the
// material of the cube's walls, so every case reaches the scene's material checks.

fn mtl_number() -> impl Strategy<Value = String> {
    prop_oneof![
        12 => (0.0f64..1.0).prop_map(|x| format!("{x:.3}")),
        4 => prop::sample::select(&["0", "1", "1.0000", "0.98", "1.2", "2.5"][..]).prop_map(str::to_string),
        1 => prop::sample::select(&["-0.1", "nan", "inf", "x", "", "1e40", "-0"][..]).prop_map(str::to_string),
    ]
}

fn mtl_line() -> impl Strategy<Value = String> {
    let colour = prop_oneof![
        4 => (mtl_number(), mtl_number(), mtl_number()).prop_map(|(r, g, b)| format!("{r} {g} {b}")),
        1 => mtl_number(),
        1 => Just("spectral ident.rfl 1".to_string()),
    ];
    let file = prop::sample::select(&["wood.png", "missing.jpg", "textures/bricks a.tga", "..\\up.png", ""][..]);
    let options = prop::sample::select(
        &["", "-bm 1 ", "-s 2 2 1 ", "-o 0.5 ", "-clamp on ", "-imfchan m ", "-mm 0 1 ", "-x "][..],
    );
    prop_oneof![
        3 => (prop::sample::select(&["Kd", "Ks", "Ke", "Tf", "Ka", "kd"][..]), colour)
            .prop_map(|(k, c)| format!("{k} {c}")),
        3 => (prop::sample::select(&["Ns", "Ni", "d", "Tr", "d -halo"][..]), mtl_number())
            .prop_map(|(k, x)| format!("{k} {x}")),
        3 => prop::sample::select(&["0", "1", "2", "3", "4", "5", "6", "7", "8", "9", "10", "11", "-1", "x", ""][..])
            .prop_map(|n| format!("illum {n}")),
        3 => (prop::sample::select(&["map_Kd", "map_d", "map_Ke", "map_bump", "bump", "map_Ks"][..]), options, file)
            .prop_map(|(k, o, f)| format!("{k} {o}{f}")),
        1 => prop::sample::select(&["Pr 0.5", "Pm 1", "norm n.png", "refl -type sphere s.png", "# c", "", "newmtl"][..])
            .prop_map(str::to_string),
    ]
}

/// `white` with random statements, `lamp` as the emitter; CRLF, tabs or plain.
fn mtl_text() -> impl Strategy<Value = String> {
    (prop::collection::vec(mtl_line(), 0..12), 0..3u8).prop_map(|(lines, style)| {
        let mut text = String::from("newmtl lamp\nKd 0 0 0\nKe 4 4 4\n\nnewmtl white\nKd 0.5 0.5 0.5\n");
        for l in lines {
            text.push_str(if style == 1 { "\t" } else { "" });
            text.push_str(&l);
            text.push('\n');
        }
        if style == 2 {
            text = text.replace('\n', "\r\n");
        }
        text
    })
}

/// The cube of (c), with its walls textured so that map statements meet `vt`.
const TEXTURED_CUBE: &str = "mtllib m.mtl\nvt 0 0\nvt 1 0\nvt 1 1\nvt 0 1\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n\
v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\nusemtl white\nf 1/1 4/2 3/3 2/4\nf 5/1 6/2 7/3 8/4\nf 1/1 2/2 6/3 5/4\n\
f 4/1 8/2 7/3 3/4\nf 1/1 5/2 8/3 4/4\nusemtl lamp\nf 2 3 7 6\n";

proptest! {
    #![proptest_config(config(64))]

    /// Whatever the MTL says, the scene loads with materials `check_material` accepts (reflectances
    /// of 1 or more were clamped, not refused) or fails with the MTL file and line.
    #[test]
    fn random_mtl_statements_never_panic(mtl in mtl_text()) {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join("m.obj"), TEXTURED_CUBE).expect("write OBJ");
        std::fs::write(dir.path().join("m.mtl"), &mtl).expect("write MTL");
        let path = dir.path().join("scene.toml");
        std::fs::write(&path, "[[mesh]]\nobj = \"m.obj\"\n").expect("write scene");
        match scene::load(&path) {
            Ok(s) => {
                for m in &s.materials {
                    prop_assert!(scene::check_material(m).is_ok(), "{m:?}");
                    prop_assert!(m.transmission_filter.is_finite() && m.transmission_filter.max_element() <= 1.0);
                }
                assert_meshes_cleanly(&s);
            }
            Err(e) => {
                let message = e.to_string();
                prop_assert!(message.contains("m.mtl:") || message.contains("m.obj"), "{message}");
            }
        }
    }
}
