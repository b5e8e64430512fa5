//! `method = "adaptive"` as a first-class pass-one method (issue 10, "Keep what works"): its solution
//! file carries the refinement, so `render --solution` renders the same bytes as a one-shot render;
//! stale and damaged files are refused; a batch reuses the solution for new views and re-solves a
//! materials-only change as a fresh run would; `batch --resume`, checkpoints and shards do not break.

mod common;

use std::path::{Path, PathBuf};

use common::{radray, small_batch_job};

fn scene_path(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name)
}

fn stderr(o: &std::process::Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `scenes/cornell_box.toml` on the adaptive method, written to `dir`.
fn adaptive_cornell(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(scene_path("cornell_box.toml")).unwrap();
    let text = text.replacen("[radiosity]\n", "[radiosity]\nmethod = \"adaptive\"\n", 1);
    // Relative OBJ paths are taken from the scene's folder: point them back at the shipped one.
    let text = text.replace("obj = \"", &format!("obj = \"{}/", scene_path("").display()));
    let path = dir.join("cornell.toml");
    std::fs::write(&path, text).unwrap();
    path
}

const SMALL: &[&str] = &["--width", "24", "--height", "24", "--spp", "2"];

/// Runs `radray solve` on `scene` at preview quality into `sol`, asserting success.
fn solve(scene: &str, sol: &Path) {
    let out = radray(&["solve", scene, "-o", sol.to_str().unwrap(), "--quality", "preview"]);
    assert!(out.status.success(), "{}", stderr(&out));
}

/// `render` of `scene` with `args` and the small settings, at preview quality unless `args` say; the
/// output.
fn render(scene: &str, png: &Path, args: &[&str]) -> std::process::Output {
    let mut a = vec!["render", scene, "-o", png.to_str().unwrap()];
    a.extend(args);
    a.extend(SMALL);
    if !args.contains(&"--quality") {
        a.extend(["--quality", "preview"]);
    }
    radray(&a)
}

#[test]
fn a_saved_adaptive_solution_renders_the_same_bytes_as_a_one_shot_render() {
    let dir = tempfile::tempdir().unwrap();
    let scene = adaptive_cornell(dir.path());
    let scene = scene.to_str().unwrap();
    let sol = dir.path().join("a.radsol");
    solve(scene, &sol);
    let bytes = std::fs::read(&sol).unwrap();
    assert_eq!(bytes[8..12], radray::radiosity::solution_file::FILE_VERSION_REFINED_MESH.to_le_bytes());
    for mode in ["final", "radiosity"] {
        let direct = dir.path().join(format!("direct.{mode}.exr"));
        let reused = dir.path().join(format!("reused.{mode}.exr"));
        let out = render(scene, &direct, &["--mode", mode, "--direct", "pixel"]);
        assert!(out.status.success(), "{}", stderr(&out));
        let out = render(scene, &reused, &["--mode", mode, "--direct", "pixel", "--solution", sol.to_str().unwrap()]);
        assert!(out.status.success(), "{}", stderr(&out));
        assert_eq!(std::fs::read(&direct).unwrap(), std::fs::read(&reused).unwrap(), "{mode}");
    }
}

#[test]
fn a_stale_or_damaged_adaptive_solution_is_refused_with_exit_2_and_its_name() {
    let dir = tempfile::tempdir().unwrap();
    let scene = adaptive_cornell(dir.path());
    let scene = scene.to_str().unwrap();
    let sol = dir.path().join("a.radsol");
    solve(scene, &sol);
    let png = dir.path().join("x.png");
    let refused = |scene: &str, file: &Path, extra: &[&str], says: &str| {
        let mut args = vec!["--solution", file.to_str().unwrap()];
        args.extend(extra);
        let out = render(scene, &png, &args);
        assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
        let name = file.file_name().unwrap().to_str().unwrap();
        assert!(stderr(&out).contains(name) && stderr(&out).contains(says), "{}", stderr(&out));
        assert!(!png.exists());
    };
    // Another scene (the empty box): its patch mesh is not the one the refinement was recorded on.
    let other = scene_path("cornell_empty.toml");
    refused(other.to_str().unwrap(), &sol, &[], "re-run `radray solve`");
    // The same scene at another quality (another element size): the recorded levels do not fit its
    // patches.
    refused(scene, &sol, &["--quality", "default"], "does not fit the current scene");
    // One flipped byte in the refinement section: the checksum refuses it.
    let mut bytes = std::fs::read(&sol).unwrap();
    let at = bytes.len() - 12;
    bytes[at] ^= 0x40;
    let damaged = dir.path().join("damaged.radsol");
    std::fs::write(&damaged, &bytes).unwrap();
    refused(scene, &damaged, &[], "corrupted");
    // Cut short.
    let cut = dir.path().join("cut.radsol");
    std::fs::write(&cut, &bytes[..bytes.len() / 2]).unwrap();
    refused(scene, &cut, &[], "truncated");
}

/// Reads the manifest written beside `jobs`.
fn manifest(dir: &Path) -> Vec<serde_json::Value> {
    let text = std::fs::read_to_string(dir.join("jobs.manifest.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    v["jobs"].as_array().unwrap().clone()
}

const BLUE_LIGHT: &str = "materials = { light = { ke = [4.0, 8.0, 20.0] } }";
const SIDE_VIEW: &str = "camera = { eye = [400.0, 300.0, -600.0] }";

/// Writes `dir/jobs.toml` with one adaptive Cornell-box job per (output, height, extra keys), runs
/// `radray batch` on it with `args`, asserts success and returns the manifest's jobs.
fn adaptive_batch(dir: &Path, jobs: &[(&str, u32, &str)], args: &[&str]) -> Vec<serde_json::Value> {
    let s = scene_path("cornell_box.toml").display().to_string();
    let text: String = jobs
        .iter()
        .map(|(output, height, extra)| {
            small_batch_job(&s, &format!("\"{output}\""), *height, &format!("method = \"adaptive\"\n{extra}"))
        })
        .collect();
    let jobs_path = dir.join("jobs.toml");
    std::fs::write(&jobs_path, text).unwrap();
    let mut a = vec!["batch", jobs_path.to_str().unwrap()];
    a.extend(args);
    let out = radray(&a);
    assert!(out.status.success(), "{}", stderr(&out));
    manifest(dir)
}

#[test]
fn a_batch_reuses_an_adaptive_solution_for_a_new_view_and_level_zero_form_factors_for_new_materials() {
    let dir = tempfile::tempdir().unwrap();
    let jobs =
        adaptive_batch(dir.path(), &[("a.png", 16, ""), ("b.png", 12, SIDE_VIEW), ("c.png", 16, BLUE_LIGHT)], &[]);
    assert_eq!(jobs[1]["reused_solution"], true, "a new view reuses the solution and its refined mesh");
    assert_eq!(jobs[2]["reused_solution"], false, "new emission is a new solution");
    // The materials-only job alone, in a fresh batch (nothing cached), gives the same bytes.
    let fresh = tempfile::tempdir().unwrap();
    let alone = adaptive_batch(fresh.path(), &[("c.png", 16, BLUE_LIGHT)], &[]);
    assert_eq!(
        std::fs::read(dir.path().join("c.png")).unwrap(),
        std::fs::read(fresh.path().join("c.png")).unwrap(),
        "the re-solve after a materials-only change is a fresh solve's"
    );
    // ... but it drew no hemicubes for the patches: level 0's rows came from job a, and only the
    // refined level's new rows were computed.
    let (reused, alone) = (&jobs[2]["stats"]["adaptive"], &alone[0]["stats"]["adaptive"]);
    let patches = alone["elements_per_level"][0].as_u64().unwrap();
    assert!(patches > 0, "{alone}");
    assert_eq!(jobs[2]["reused_form_factors"], true);
    assert_eq!(alone["rows_reused"].as_u64(), Some(0), "{alone}");
    assert_eq!(reused["rows_reused"].as_u64(), Some(patches), "{reused}");
    assert_eq!(reused["elements_per_level"], alone["elements_per_level"], "the same refinement");
    assert_eq!(
        reused["rows_computed"].as_u64().unwrap(),
        alone["rows_computed"].as_u64().unwrap() - patches,
        "{reused} against {alone}"
    );
    assert_ne!(
        std::fs::read(dir.path().join("a.png")).unwrap(),
        std::fs::read(dir.path().join("c.png")).unwrap(),
        "the blue light changed the image"
    );
}

#[test]
fn batch_resume_reruns_only_the_missing_adaptive_job_and_gets_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let jobs = [("a.png", 16, ""), ("b.png", 12, SIDE_VIEW)];
    adaptive_batch(dir.path(), &jobs, &[]);
    let b = dir.path().join("b.png");
    let first = std::fs::read(&b).unwrap();
    std::fs::remove_file(&b).unwrap();
    let jobs = adaptive_batch(dir.path(), &jobs, &["--resume"]);
    assert_eq!(jobs[0]["from_earlier_run"], true);
    assert_eq!(jobs[1]["status"], "ok");
    assert_ne!(jobs[1]["from_earlier_run"], true);
    assert_eq!(std::fs::read(&b).unwrap(), first, "the re-run job solves the same adaptive mesh again");
}

#[test]
fn adaptive_runs_warn_that_they_keep_no_checkpoint_and_refuse_shards() {
    let dir = tempfile::tempdir().unwrap();
    let scene = adaptive_cornell(dir.path());
    let scene = scene.to_str().unwrap();
    let sol = dir.path().join("a.radsol");
    let out = radray(&["solve", scene, "-o", sol.to_str().unwrap(), "--quality", "preview"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("keeps no checkpoint"), "{}", stderr(&out));
    assert!(!dir.path().join("a.radsol.partial").exists());
    // A shard of an adaptive solve is refused (each level needs the whole level before it), not run
    // as another method.
    let part = dir.path().join("p0");
    let out = radray(&["solve", scene, "-o", part.to_str().unwrap(), "--quality", "preview", "--shard", "0/2"]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("adaptive"), "{}", stderr(&out));
    assert!(!part.exists());
}

/// `scenes/cornell_box.toml` with `method = "auto"` and `auto_adaptive = true` (whatever the default),
/// written to `dir`.
fn auto_adaptive_cornell(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(scene_path("cornell_box.toml")).unwrap();
    let text = text.replacen("[radiosity]\n", "[radiosity]\nmethod = \"auto\"\nauto_adaptive = true\n", 1);
    let text = text.replace("obj = \"", &format!("obj = \"{}/", scene_path("").display()));
    let path = dir.join("cornell.toml");
    std::fs::write(&path, text).unwrap();
    path
}

#[test]
fn auto_shards_and_merges_on_the_uniform_matrix_where_it_would_take_the_adaptive_mesh_and_says_why() {
    let dir = tempfile::tempdir().unwrap();
    let scene = auto_adaptive_cornell(dir.path());
    let scene = scene.to_str().unwrap();
    let path = |name: &str| dir.path().join(name).to_str().unwrap().to_string();
    let solve = |extra: &[&str]| {
        let mut a = vec!["solve", scene, "--quality", "preview", "-v"];
        a.extend(extra);
        let out = radray(&a);
        assert!(out.status.success(), "{}", stderr(&out));
        stderr(&out)
    };
    const WHY: &str = "--shard/--merge take the uniform matrix";
    // Alone, auto takes the adaptive mesh and -v says so.
    let said = solve(&["-o", &path("auto.radsol")]);
    assert!(said.contains("pass one: adaptive") && !said.contains(WHY), "{said}");
    // A shard and the merge fall back to the matrix, with the reason, instead of refusing.
    for k in ["0/2", "1/2"] {
        let said = solve(&["-o", &path(&format!("part{}", &k[..1])), "--shard", k]);
        assert!(said.contains("pass one: gauss-seidel") && said.contains(WHY), "{said}");
    }
    let said = solve(&["-o", &path("merged.radsol"), "--merge", &path("part0"), &path("part1")]);
    assert!(said.contains(WHY), "{said}");
    // ... and the merged solution is the uniform matrix's, byte for byte.
    solve(&["-o", &path("matrix.radsol"), "--method", "matrix"]);
    let read = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    assert_eq!(read("merged.radsol"), read("matrix.radsol"));
    assert_ne!(read("auto.radsol"), read("matrix.radsol"), "alone, auto solved the adaptive mesh");
    // `info` says what shards take.
    let out = radray(&["info", scene, "--quality", "preview"]);
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().find(|l| l.starts_with("pass one")).unwrap_or_default();
    assert!(line.contains("adaptive") && line.contains("under --shard/--merge gauss-seidel"), "{stdout}");
}

#[test]
fn auto_picks_the_adaptive_mesh_for_final_images_only_when_auto_adaptive_says_so_and_never_through_mirrors_or_glass() {
    use radray::radiosity::method::{auto_method, for_scene};
    use radray::scene::{MethodChoice, AUTO_PREFERS_ADAPTIVE};
    let load = |name: &str| radray::scene::load(&scene_path(name)).unwrap();
    let mut cornell = load("cornell_box.toml");
    assert_eq!(cornell.radiosity.method, MethodChoice::Auto);
    assert_eq!(cornell.radiosity.adaptive.auto, None, "the shipped scene does not say");
    let expected = if AUTO_PREFERS_ADAPTIVE { MethodChoice::Adaptive } else { MethodChoice::Matrix };
    assert_eq!(auto_method(&cornell).0, expected);
    cornell.radiosity.adaptive.auto = Some(false);
    assert_eq!(auto_method(&cornell).0, MethodChoice::Matrix);
    cornell.radiosity.adaptive.auto = Some(true);
    let (choice, reason) = auto_method(&cornell);
    assert_eq!(choice, MethodChoice::Adaptive, "{reason}");
    assert!(for_scene(&cornell).name().starts_with("adaptive"), "{}", for_scene(&cornell).name());
    // A finer mesh whose uniform hemicubes are predicted above AUTO_ADAPTIVE_CPU_SECONDS keeps the
    // matrix, which checkpoints its rows (the adaptive mesh keeps no checkpoint).
    let mut fine = cornell.clone();
    fine.radiosity.max_element_edge = 15.0;
    let (choice, reason) = auto_method(&fine);
    assert_eq!(choice, MethodChoice::Matrix, "{reason}");
    assert!(reason.contains("keeps no checkpoint"), "{reason}");
    // Matrix-free shooting was asked for: the adaptive mesh would store matrices.
    cornell.radiosity.store_form_factors = false;
    assert_eq!(auto_method(&cornell).0, MethodChoice::Matrix);
    let mut specular = load("cornell_specular.toml");
    specular.radiosity.adaptive.auto = Some(true);
    assert_eq!(auto_method(&specular).0, MethodChoice::Matrix, "mirrors and glass stay on the uniform matrix");
}

#[test]
fn auto_takes_the_adaptive_mesh_for_radiosity_mode_images_unless_auto_adaptive_says_otherwise() {
    use radray::radiosity::method::auto_method_for;
    use radray::scene::{MethodChoice, SolutionReader, AUTO_PREFERS_ADAPTIVE_FOR_RADIOSITY_IMAGES};
    let load = |name: &str| radray::scene::load(&scene_path(name)).unwrap();
    let (radiosity, final_images) = (SolutionReader::RadiosityImages, SolutionReader::FinalImages);
    let mut cornell = load("cornell_box.toml");
    const { assert!(AUTO_PREFERS_ADAPTIVE_FOR_RADIOSITY_IMAGES) };
    let (choice, reason) = auto_method_for(&cornell, radiosity);
    assert_eq!(choice, MethodChoice::Adaptive, "{reason}");
    assert!(reason.contains("only radiosity-mode images"), "{reason}");
    assert_eq!(auto_method_for(&cornell, final_images).0, MethodChoice::Matrix);
    // The explicit key wins for every reader.
    cornell.radiosity.adaptive.auto = Some(false);
    let (choice, reason) = auto_method_for(&cornell, radiosity);
    assert_eq!(choice, MethodChoice::Matrix, "{reason}");
    assert!(reason.contains("auto_adaptive is off"), "{reason}");
    cornell.radiosity.adaptive.auto = Some(true);
    assert_eq!(auto_method_for(&cornell, final_images).0, MethodChoice::Adaptive);
    // An explicit method is not auto's to change.
    cornell.radiosity.adaptive.auto = None;
    cornell.radiosity.method = MethodChoice::Matrix;
    let method = radray::radiosity::method::for_scene_with_reason(&cornell, radiosity).0;
    assert_eq!(method.name(), "gauss-seidel");
    // Mirrors and glass stay on the uniform matrix in radiosity mode too.
    let specular = load("cornell_specular.toml");
    assert_eq!(auto_method_for(&specular, radiosity).0, MethodChoice::Matrix);
    // Textured surfaces take the adaptive mesh like the others (its split criterion reads irradiance,
    // not the exitance a texture modulates: textured_box 12% better than the uniform mesh at equal
    // CPU-s), and the key still turns it off or on.
    let mut textured = load("rooms/textured_box.toml");
    let (choice, reason) = auto_method_for(&textured, radiosity);
    assert_eq!(choice, MethodChoice::Adaptive, "{reason}");
    assert_eq!(auto_method_for(&textured, final_images).0, MethodChoice::Matrix);
    textured.radiosity.adaptive.auto = Some(false);
    assert_eq!(auto_method_for(&textured, radiosity).0, MethodChoice::Matrix);
    textured.radiosity.adaptive.auto = Some(true);
    assert_eq!(auto_method_for(&textured, final_images).0, MethodChoice::Adaptive);
}

#[test]
fn only_runs_that_draw_nothing_but_radiosity_images_read_their_solution_for_radiosity_images() {
    use radray::run::{PngSettings, Work};
    use radray::scene::SolutionReader;
    use radray::trace::whitted::TraceMode;
    let render = |modes: &[TraceMode], layers: Option<PathBuf>| Work::Render {
        plan: modes.iter().map(|&m| (m, PathBuf::from("x.exr"))).collect(),
        png: PngSettings::default(),
        solution: None,
        layers,
    };
    assert_eq!(render(&[TraceMode::Radiosity], None).solution_reader(), SolutionReader::RadiosityImages);
    let two = [TraceMode::Radiosity, TraceMode::Radiosity];
    assert_eq!(render(&two, None).solution_reader(), SolutionReader::RadiosityImages, "two -o files");
    assert_eq!(render(&[TraceMode::Final], None).solution_reader(), SolutionReader::FinalImages);
    let both = [TraceMode::Final, TraceMode::Radiosity];
    assert_eq!(render(&both, None).solution_reader(), SolutionReader::FinalImages, "--mode both");
    let layers = Some(PathBuf::from("l.exr"));
    assert_eq!(render(&[TraceMode::Radiosity], layers).solution_reader(), SolutionReader::FinalImages, "--layers");
    let solve = Work::Solve { output: PathBuf::from("s.radsol") };
    assert_eq!(solve.solution_reader(), SolutionReader::FinalImages, "a solution file serves any later render");
}

#[test]
fn a_radiosity_mode_render_under_auto_is_the_adaptive_one_and_auto_adaptive_false_keeps_the_matrix() {
    let dir = tempfile::tempdir().unwrap();
    let cornell = scene_path("cornell_box.toml");
    let cornell = cornell.to_str().unwrap();
    let out = |name: &str| dir.path().join(name);
    let read = |name: &str| std::fs::read(dir.path().join(name)).unwrap();
    let radiosity = ["--mode", "radiosity"];
    let run = |scene: &str, name: &str, args: &[&str]| {
        let o = render(scene, &out(name), &[&radiosity[..], args].concat());
        assert!(o.status.success(), "{}", stderr(&o));
        o
    };
    let o = run(cornell, "auto.exr", &["-v"]);
    assert!(stderr(&o).contains("pass one: adaptive"), "{}", stderr(&o));
    run(cornell, "adaptive.exr", &["--method", "adaptive"]);
    run(cornell, "matrix.exr", &["--method", "matrix"]);
    assert_eq!(read("auto.exr"), read("adaptive.exr"));
    assert_ne!(read("auto.exr"), read("matrix.exr"));
    // The scene's auto_adaptive = false wins over the mode.
    let text = std::fs::read_to_string(cornell).unwrap();
    let text = text.replacen("[radiosity]\n", "[radiosity]\nauto_adaptive = false\n", 1);
    let text = text.replace("obj = \"", &format!("obj = \"{}/", scene_path("").display()));
    let off = out("off.toml");
    std::fs::write(&off, text).unwrap();
    run(off.to_str().unwrap(), "off.exr", &[]);
    assert_eq!(read("off.exr"), read("matrix.exr"));
}

#[test]
fn the_auto_adaptive_key_is_read_and_info_prints_the_choice_and_why() {
    let dir = tempfile::tempdir().unwrap();
    let text = std::fs::read_to_string(scene_path("cornell_box.toml")).unwrap();
    let text = text.replacen("[radiosity]\n", "[radiosity]\nauto_adaptive = true\n", 1);
    let text = text.replace("obj = \"", &format!("obj = \"{}/", scene_path("").display()));
    let scene = dir.path().join("cornell.toml");
    std::fs::write(&scene, &text).unwrap();
    let out = radray(&["info", scene.to_str().unwrap(), "--quality", "preview"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let stdout = String::from_utf8_lossy(&out.stdout);
    let line = stdout.lines().find(|l| l.starts_with("pass one")).unwrap_or_default();
    assert!(line.contains("adaptive") && line.contains("auto_adaptive is on"), "{stdout}");
    // A value that is not a boolean is refused with the file and line.
    std::fs::write(&scene, text.replace("auto_adaptive = true", "auto_adaptive = 3")).unwrap();
    let out = radray(&["info", scene.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("cornell.toml:"), "{}", stderr(&out));
}
