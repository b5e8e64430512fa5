//! End to end: the real `radray` binary on the shipped scenes at small sizes — outputs, manifests, exit
//! codes and error messages.

mod common;

use common::{radray, small_batch_job};
use std::path::{Path, PathBuf};
use std::process::Output;

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name).display().to_string()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn files_in(dir: &Path) -> Vec<PathBuf> {
    let mut v: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
    v.sort();
    v
}

/// Small, fast settings for the shipped scenes.
const SMALL: &[&str] = &["--width", "24", "--height", "24", "--spp", "2", "--quality", "preview"];

#[test]
fn render_writes_png_and_exr() {
    let cornell_box = scene("cornell_box.toml");
    let dir = tempfile::tempdir().unwrap();
    let png = dir.path().join("c.png");
    let exr = dir.path().join("c.exr");
    let mut args = vec!["render", &cornell_box[..], "-o", png.to_str().unwrap(), "-o", exr.to_str().unwrap()];
    let small = SMALL.to_vec();
    args.extend(small);
    let out = radray(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    let img = radray::output::read_image(&exr).unwrap();
    assert_eq!((img.width_px, img.height_px), (24, 24));
    assert!(img.pixels.iter().all(|p| p.is_finite() && p.min_element() >= 0.0));
    let png_img = radray::output::read_image(&png).unwrap();
    assert_eq!(png_img.width_px, 24);
    // Only the two outputs: no temporary files left behind.
    assert_eq!(files_in(dir.path()).len(), 2);
}

#[test]
fn mode_both_writes_final_and_radiosity_names() {
    let cornell_box = scene("cornell_box.toml");
    let dir = tempfile::tempdir().unwrap();
    let out_path = dir.path().join("pic.exr");
    let mut args = vec!["render", &cornell_box[..], "-o", out_path.to_str().unwrap(), "--mode", "both"];
    args.extend(SMALL);
    let out = radray(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(dir.path().join("pic.final.exr").is_file());
    assert!(dir.path().join("pic.radiosity.exr").is_file());
}

#[test]
fn bad_scene_exits_2_with_file_and_line_and_writes_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let bad = dir.path().join("bad.toml");
    std::fs::write(&bad, "[camera]\neye = [0, 0, -5]\nlook_at = [0, 0, 0]\nvfov_deg = 200\n").unwrap();
    let png = dir.path().join("x.png");
    let out = radray(&["render", bad.to_str().unwrap(), "-o", png.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let msg = stderr(&out);
    assert!(msg.contains("bad.toml:4:") && msg.contains("vfov_deg"), "{msg}");
    assert!(!msg.contains("panicked"), "{msg}");
    assert!(!png.exists());
}

#[test]
fn a_missing_scene_file_is_named_once_with_its_reason_once() {
    let dir = tempfile::tempdir().unwrap();
    let missing = dir.path().join("missing.toml");
    let out = radray(&["render", missing.to_str().unwrap(), "-o", dir.path().join("x.png").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    let msg = stderr(&out);
    assert!(msg.contains("missing.toml: cannot read scene file"), "{msg}");
    let reason = std::fs::read(&missing).unwrap_err().to_string();
    assert_eq!(msg.matches(&reason).count(), 1, "the reason once: {msg}");
}

#[test]
fn unusable_outputs_are_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let out = radray(&["render", &scene("cornell_box.toml"), "-o", dir.path().join("x.jpg").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains(".png or .exr"), "{}", stderr(&out));
    let out =
        radray(&["render", &scene("cornell_box.toml"), "-o", dir.path().join("no/such/dir/x.png").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("does not exist"), "{}", stderr(&out));
}

#[test]
fn usage_errors_exit_2() {
    let out = radray(&["render"]);
    assert_eq!(out.status.code(), Some(2));
    let out = radray(&["frobnicate"]);
    assert_eq!(out.status.code(), Some(2));
    let out = radray(&["render", &scene("cornell_box.toml"), "-o", "x.png", "--spp", "0"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn help_shows_examples() {
    let out = radray(&["--help"]);
    assert!(out.status.success());
    assert!(String::from_utf8_lossy(&out.stdout).contains("Examples:"));
}

#[test]
fn saved_solution_renders_the_same_image() {
    let cornell_box = scene("cornell_box.toml");
    let dir = tempfile::tempdir().unwrap();
    let sol = dir.path().join("c.radsol");
    let out = radray(&["solve", &scene("cornell_box.toml"), "-o", sol.to_str().unwrap(), "--quality", "preview"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let direct = dir.path().join("direct.exr");
    let reused = dir.path().join("reused.exr");
    let mut a = vec!["render", &cornell_box[..], "-o", direct.to_str().unwrap()];
    a.extend(SMALL);
    assert!(radray(&a).status.success());
    let mut b = vec!["render", &cornell_box[..], "-o", reused.to_str().unwrap(), "--solution", sol.to_str().unwrap()];
    b.extend(SMALL);
    let out = radray(&b);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(std::fs::read(&direct).unwrap(), std::fs::read(&reused).unwrap());
}

#[test]
fn stale_or_foreign_solution_is_refused() {
    let cornell_box = scene("cornell_box.toml");
    let dir = tempfile::tempdir().unwrap();
    let sol = dir.path().join("c.radsol");
    let out = radray(&["solve", &scene("cornell_empty.toml"), "-o", sol.to_str().unwrap(), "--quality", "preview"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let png = dir.path().join("x.png");
    let mut a = vec!["render", &cornell_box[..], "-o", png.to_str().unwrap(), "--solution", sol.to_str().unwrap()];
    a.extend(SMALL);
    let out = radray(&a);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
    assert!(stderr(&out).contains("c.radsol"), "{}", stderr(&out));
    assert!(!png.exists());
    let junk = dir.path().join("junk.radsol");
    std::fs::write(&junk, b"not a solution").unwrap();
    a[5] = junk.to_str().unwrap();
    let out = radray(&a);
    assert_eq!(out.status.code(), Some(2), "{}", stderr(&out));
}

#[test]
fn stats_file_records_the_run() {
    let cornell_box = scene("cornell_box.toml");
    let dir = tempfile::tempdir().unwrap();
    let stats = dir.path().join("s.json");
    let png = dir.path().join("x.png");
    let mut a = vec!["render", &cornell_box[..], "-o", png.to_str().unwrap(), "--stats", stats.to_str().unwrap()];
    a.extend(SMALL);
    let out = radray(&a);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert!(v["elements"].as_u64().unwrap() > 100);
    assert_eq!(v["hemicube_resolution_px"], 64);
    assert!(v["sweeps"].as_u64().unwrap() > 1);
    assert!(v["primary_rays"].as_u64().unwrap() >= 24 * 24 * 2);
    assert!(v["peak_memory_bytes"].as_u64().unwrap() > 0);
}

#[test]
fn compare_reports_metrics_and_writes_difference_images() {
    let dir = tempfile::tempdir().unwrap();
    let reference = Path::new(env!("CARGO_MANIFEST_DIR")).join("references/cornell_original/reference.exr");
    let diff = dir.path().join("d.png");
    let sbs = dir.path().join("s.png");
    let r = reference.to_str().unwrap();
    let out =
        radray(&["compare", r, r, "--json", "--diff", diff.to_str().unwrap(), "--side-by-side", sbs.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["rmse"].as_f64().unwrap(), 0.0);
    assert!(diff.is_file() && sbs.is_file());
    let out = radray(&["compare", r, dir.path().join("missing.exr").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("missing.exr"));
}

#[test]
fn batch_reuses_form_factors_and_records_failures() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene("cornell_box.toml");
    let jobs = [
        // Job a draws only radiosity images, for which `auto` would solve the adaptive mesh, a solution
        // apart from the final images' (`SolutionReader`); the matrix keeps it the one job b reuses.
        small_batch_job(&s, r#"["a.png", "a.exr"]"#, 16, "mode = \"radiosity\"\nmethod = \"matrix\""),
        small_batch_job(&s, "\"b.png\"", 12, "camera = { eye = [400.0, 300.0, -600.0] }"),
        small_batch_job(&s, "\"c.png\"", 16, "materials = { light = { ke = [4.0, 8.0, 20.0] } }"),
        "[[job]]\nscene = \"does_not_exist.toml\"\noutput = \"d.png\"\n".to_string(),
    ]
    .concat();
    let jobs_path = dir.path().join("jobs.toml");
    std::fs::write(&jobs_path, jobs).unwrap();
    let out = radray(&["batch", jobs_path.to_str().unwrap()]);
    assert_ne!(out.status.code(), Some(0), "a failed job makes the batch fail");
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("jobs.manifest.json")).unwrap()).unwrap();
    let jobs = manifest["jobs"].as_array().unwrap();
    assert_eq!(jobs.len(), 4);
    assert_eq!(jobs[0]["status"], "ok");
    assert_eq!(jobs[0]["outputs"].as_array().unwrap().len(), 2);
    assert_eq!(jobs[1]["reused_solution"], true, "a new view reuses the solution");
    assert_eq!(jobs[2]["reused_form_factors"], true, "new emission re-solves from cached form factors");
    assert_eq!(jobs[2]["reused_solution"], false);
    assert_eq!(jobs[3]["status"], "failed");
    assert!(jobs[3]["error"].as_str().unwrap().contains("does_not_exist.toml"));
    assert!(
        dir.path().join("a.png").is_file() && dir.path().join("b.png").is_file() && dir.path().join("c.png").is_file()
    );

    // Shards 0/2 and 1/2 split the jobs between them.
    let m0 = dir.path().join("m0.json");
    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--shard", "0/2", "--manifest", m0.to_str().unwrap()]);
    assert!(out.status.success(), "jobs 0 and 2 succeed: {}", stderr(&out));
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&m0).unwrap()).unwrap();
    let idx: Vec<u64> = m["jobs"].as_array().unwrap().iter().map(|j| j["index"].as_u64().unwrap()).collect();
    assert_eq!(idx, vec![0, 2]);
    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--shard", "2/2"]);
    assert_eq!(out.status.code(), Some(2));
}

#[test]
fn info_describes_the_scene_before_solving() {
    let out = radray(&["info", &scene("cornell_box.toml"), "--json"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let v: serde_json::Value = serde_json::from_slice(&out.stdout).unwrap();
    assert_eq!(v["surfaces"], 16);
    assert_eq!(v["elements"], 3292);
    assert_eq!(v["emitters"].as_array().unwrap().len(), 1);
    assert!(v["estimated_form_factor_bytes"].as_u64().unwrap() > 0);
    let out = radray(&["info", &scene("cornell_box.toml")]);
    assert!(String::from_utf8_lossy(&out.stdout).contains("elements"));
}

#[test]
fn every_shipped_scene_renders_as_shipped_at_a_small_size() {
    let dir = tempfile::tempdir().unwrap();
    for name in ["cornell_box", "cornell_empty", "cornell_specular", "furnace", "primitives"] {
        let png = dir.path().join(format!("{name}.png"));
        let path = scene(&format!("{name}.toml"));
        let mut a = vec!["render", &path[..], "-o", png.to_str().unwrap()];
        a.extend(SMALL);
        let out = radray(&a);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
        assert!(png.is_file(), "{name}");
    }
}

#[test]
fn thread_count_does_not_change_a_single_byte() {
    let dir = tempfile::tempdir().unwrap();
    let cornell = scene("cornell_box.toml");
    let mut outputs = Vec::new();
    for threads in ["1", "2"] {
        let exr = dir.path().join(format!("t{threads}.exr"));
        let mut a =
            vec!["render", &cornell[..], "-o", exr.to_str().unwrap(), "--threads", threads, "--direct", "pixel"];
        a.extend(SMALL);
        let out = radray(&a);
        assert!(out.status.success(), "{}", stderr(&out));
        outputs.push(std::fs::read(&exr).unwrap());
    }
    assert!(outputs[0] == outputs[1], "1 and 2 threads gave different images");
}

#[test]
fn auto_exposure_is_printed_with_verbose_and_leaves_exr_linear() {
    let cornell_box = scene("cornell_box.toml");
    let dir = tempfile::tempdir().unwrap();
    let (png, exr) = (dir.path().join("auto.png"), dir.path().join("auto.exr"));
    let mut args = vec!["-v", "render", &cornell_box[..], "-o", png.to_str().unwrap(), "-o", exr.to_str().unwrap()];
    args.extend(SMALL);
    args.extend(["--exposure", "auto"]);
    let out = radray(&args);
    assert!(out.status.success(), "{}", stderr(&out));
    // The stops printed are those of the EXR's radiance (which auto exposure leaves alone).
    let radiance = radray::output::read_image(&exr).unwrap();
    let stops = radray::output::auto_exposure_stops(&radiance);
    let expected = format!("exposure {stops:+.3} stops (auto");
    assert!(stderr(&out).contains(&expected), "{expected:?} not in {}", stderr(&out));
    // The PNG is the EXR's radiance encoded with those stops, byte for byte.
    let encoded = radray::output::encode_png(&radiance, &png, stops, radray::output::ToneCurve::Clamp).unwrap();
    assert_eq!(std::fs::read(&png).unwrap(), encoded);
}

#[test]
fn image_exposure_key_takes_stops_or_auto_and_names_the_line_of_anything_else() {
    let dir = tempfile::tempdir().unwrap();
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_original/scene.obj");
    let write = |name: &str, exposure: &str| {
        let path = dir.path().join(name);
        let text = format!("[image]\nwidth = 8\nheight = 8\nexposure = {exposure}\n\n[[mesh]]\nobj = {:?}\n", obj);
        std::fs::write(&path, text).unwrap();
        path
    };
    for (name, exposure) in [("stops.toml", "-1.5"), ("auto.toml", "\"auto\"")] {
        let path = write(name, exposure);
        let png = dir.path().join(format!("{name}.png"));
        let out = radray(&["render", path.to_str().unwrap(), "-o", png.to_str().unwrap(), "--quality", "preview"]);
        assert!(out.status.success(), "{name}: {}", stderr(&out));
    }
    let bad = write("bad.toml", "\"sideways\"");
    let out = radray(&["render", bad.to_str().unwrap(), "-o", dir.path().join("bad.png").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("bad.toml:4:"), "{}", stderr(&out));
    assert!(stderr(&out).contains("\"auto\""), "{}", stderr(&out));
}
