//! Batch jobs at the command line: the HTML comparison report (`--report`: structure, escaping, every
//! image it shows exists, nothing fetched from elsewhere) and `--resume` after a killed batch.

mod common;

use common::radray;
use std::collections::HashSet;
use std::path::{Path, PathBuf};
use std::process::Output;

fn scene(name: &str) -> String {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(name).display().to_string()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn job(scene: &str, output: &str, extra: &str) -> String {
    format!("[[job]]\nscene = \"{scene}\"\noutput = \"{output}\"\nwidth = 16\nheight = 12\nspp = 1\nquality = \"preview\"\n{extra}\n")
}

/// Elements HTML writes without an end tag.
const VOID: &[&str] = &["meta", "img", "br", "hr", "link", "input"];

/// A parsed tag: name, attributes, and whether it closes an element.
struct Tag {
    name: String,
    attributes: Vec<(String, String)>,
    closing: bool,
}

/// A strict reader of the HTML radray writes: every `<` opens a tag (text holds only escaped `&lt;`),
/// attribute values are double-quoted, and elements nest properly. Returns the tags in order.
fn parse_html(html: &str) -> Vec<Tag> {
    let mut tags = Vec::new();
    let mut stack: Vec<String> = Vec::new();
    let mut rest = html.strip_prefix("<!DOCTYPE html>").expect("the page starts with a doctype");
    while let Some(open) = rest.find('<') {
        let text = &rest[..open];
        assert!(!text.contains('>'), "a raw '>' in text: {text:?}");
        let close = rest[open..].find('>').expect("every tag ends") + open;
        let inside = &rest[open + 1..close];
        rest = &rest[close + 1..];
        let closing = inside.starts_with('/');
        let inside = inside.trim_start_matches('/');
        let name_end = inside.find(|c: char| c.is_whitespace()).unwrap_or(inside.len());
        let name = inside[..name_end].to_ascii_lowercase();
        assert!(!name.is_empty() && name.chars().all(|c| c.is_ascii_alphanumeric()), "tag name {name:?}");
        let mut attributes = Vec::new();
        let mut attrs = inside[name_end..].trim();
        while !attrs.is_empty() {
            let eq = attrs.find("=\"").unwrap_or_else(|| panic!("unquoted attribute in <{inside}>"));
            let key = attrs[..eq].trim().to_string();
            let end = attrs[eq + 2..].find('"').expect("attribute value ends") + eq + 2;
            attributes.push((key, attrs[eq + 2..end].to_string()));
            attrs = attrs[end + 1..].trim();
        }
        if name == "style" && !closing {
            // CSS may hold '>' (child selectors); radray's holds none, but skip to its end tag anyway.
            let end = rest.find("</style>").expect("style ends");
            rest = &rest[end..];
        }
        if closing {
            assert_eq!(stack.pop().as_deref(), Some(name.as_str()), "</{name}> closes the wrong element");
        } else if !VOID.contains(&name.as_str()) {
            stack.push(name.clone());
        }
        tags.push(Tag { name, attributes, closing });
    }
    assert!(stack.is_empty(), "unclosed elements: {stack:?}");
    tags
}

fn attribute<'a>(tag: &'a Tag, key: &str) -> Option<&'a str> {
    tag.attributes.iter().find(|(k, _)| k == key).map(|(_, v)| v.as_str())
}

fn percent_decode(href: &str) -> String {
    let bytes = href.as_bytes();
    let mut out = Vec::new();
    let mut i = 0;
    while i < bytes.len() {
        if bytes[i] == b'%' {
            out.push(u8::from_str_radix(&href[i + 1..i + 3], 16).unwrap());
            i += 3;
        } else {
            out.push(bytes[i]);
            i += 1;
        }
    }
    String::from_utf8(out).unwrap()
}

#[test]
fn report_shows_every_job_with_images_that_exist_and_fetches_nothing() {
    let dir = tempfile::tempdir().unwrap();
    let s = scene("cornell_box.toml");
    // A reference of the same size: the radiosity image of the same scene, on the uniform matrix the
    // batch job's final run solves (a radiosity-only render under `auto` takes the adaptive mesh).
    let reference = dir.path().join("reference.exr");
    let out = radray(&[
        "render",
        &s,
        "-o",
        reference.to_str().unwrap(),
        "--mode",
        "radiosity",
        "--method",
        "matrix",
        "--width",
        "16",
        "--height",
        "12",
        "--spp",
        "1",
        "--quality",
        "preview",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let jobs = [
        job(&s, "a.png", "reference = \"reference.exr\"\ndirect = \"radiosity\""),
        job(&s, "b.exr", "mode = \"radiosity\"\ndirect = \"pixel\"\nmaterials = { light = { ke = [4.0, 8.0, 20.0] } }"),
        job("no<such>&scene.toml", "c.png", ""),
    ]
    .concat();
    let jobs_path = dir.path().join("jobs.toml");
    std::fs::write(&jobs_path, jobs).unwrap();
    std::fs::create_dir(dir.path().join("out dir")).unwrap();
    let page_path = dir.path().join("out dir").join("report.html");
    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--report", page_path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2), "the failed job makes the batch fail: {}", stderr(&out));

    let html = std::fs::read_to_string(&page_path).unwrap();
    let tags = parse_html(&html);
    assert!(!html.contains("http:") && !html.contains("https:") && !html.contains("//"), "no external links");
    assert!(tags.iter().all(|t| !["script", "link", "iframe", "object"].contains(&t.name.as_str())));
    assert!(html.contains("no&lt;such&gt;&amp;scene.toml"), "the scene name is escaped");

    // The table: one row per job, linking to the job's section.
    let ids: HashSet<&str> = tags.iter().filter_map(|t| attribute(t, "id")).collect();
    for i in 0..3 {
        assert!(ids.contains(format!("job-{i}").as_str()), "section of job {i}");
    }
    let table_rows = {
        let start = tags.iter().position(|t| attribute(t, "id") == Some("jobs")).unwrap();
        let end = start + tags[start..].iter().position(|t| t.name == "table" && t.closing).unwrap();
        tags[start..end].iter().filter(|t| t.name == "tr" && !t.closing).count()
    };
    assert_eq!(table_rows, 1 + 3, "a header row and one row per job");

    // Every link and image is a section of the page or a file beside it.
    let page_dir = page_path.parent().unwrap();
    let mut images: Vec<PathBuf> = Vec::new();
    for tag in &tags {
        for key in ["src", "href"] {
            let Some(target) = attribute(tag, key) else { continue };
            if let Some(id) = target.strip_prefix('#') {
                assert!(ids.contains(id), "link to a missing section {id}");
                continue;
            }
            let path = page_dir.join(percent_decode(target));
            assert!(path.is_file(), "{key}={target} does not exist");
            if key == "src" {
                images.push(path);
            }
        }
    }
    // Job 0: final, radiosity, difference, reference, difference with the reference; job 1: three.
    assert_eq!(images.len(), 5 + 3, "{images:?}");
    for image in &images {
        assert_eq!(image.extension().unwrap(), "png");
        assert!(image.starts_with(page_dir.join("report_files")));
        let decoded = radray::output::read_image(image).unwrap();
        assert_eq!((decoded.width_px, decoded.height_px), (16, 12));
    }
    // The metrics of `compare` for each pair, and the radiosity image equals its reference exactly.
    assert!(html.contains("final vs radiosity") && html.contains("radiosity vs reference"));
    let manifest: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(dir.path().join("jobs.manifest.json")).unwrap()).unwrap();
    let job0 = &manifest["jobs"][0];
    assert_eq!(job0["outputs"].as_array().unwrap().len(), 1, "report images are not the job's outputs");
    assert_eq!(job0["report"]["reference"]["radiosity_vs_reference"]["rmse"].as_f64(), Some(0.0));
    // The Cornell box is diffuse: with the radiosity estimator the two-pass image is the radiosity
    // image; with per-pixel direct light (job 1) it is not.
    assert_eq!(job0["report"]["final_vs_radiosity"]["relMSE"].as_f64(), Some(0.0));
    assert!(manifest["jobs"][1]["report"]["final_vs_radiosity"]["relMSE"].as_f64().unwrap() > 0.0);
}

#[test]
fn report_path_that_cannot_be_written_is_refused_before_any_work() {
    let dir = tempfile::tempdir().unwrap();
    let jobs_path = dir.path().join("jobs.toml");
    std::fs::write(&jobs_path, job(&scene("cornell_box.toml"), "a.png", "")).unwrap();
    let missing = dir.path().join("missing").join("report.html");
    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--report", missing.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("missing"), "{}", stderr(&out));
    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--report", dir.path().join("r.txt").to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("must end in .html"), "{}", stderr(&out));
    assert!(!dir.path().join("a.png").exists() && !dir.path().join("jobs.manifest.json").exists());
}

/// `n` quick jobs of one scene, each from another eye point (one solve, then reused).
fn view_jobs(n: usize, width: u32) -> String {
    let s = scene("cornell_box.toml");
    (0..n)
        .map(|i| {
            let eye = format!("camera = {{ eye = [{}.0, 273.0, -800.0] }}\nwidth = {width}", 200 + 10 * i);
            job(&s, &format!("view{i}.png"), &eye).replace("width = 16\n", "")
        })
        .collect()
}

fn manifest_jobs(path: &Path) -> Vec<serde_json::Value> {
    let m: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(path).unwrap()).unwrap();
    m["jobs"].as_array().unwrap().clone()
}

#[test]
fn resume_after_a_kill_skips_the_finished_jobs_and_refuses_another_jobs_file() {
    let dir = tempfile::tempdir().unwrap();
    let jobs_path = dir.path().join("jobs.toml");
    let manifest = dir.path().join("jobs.manifest.json");
    let count = 40;
    std::fs::write(&jobs_path, view_jobs(count, 16)).unwrap();

    // A real kill: SIGKILL as soon as the manifest records a finished job.
    let mut child = std::process::Command::new(env!("CARGO_BIN_EXE_radray"))
        .args(["--quiet", "--threads", "1", "batch", jobs_path.to_str().unwrap()])
        .spawn()
        .unwrap();
    let deadline = std::time::Instant::now() + std::time::Duration::from_secs(120);
    while std::time::Instant::now() < deadline {
        // Every read sees a whole manifest: it is replaced by a rename, never written in place.
        if manifest.is_file() && !manifest_jobs(&manifest).is_empty() {
            break;
        }
        std::thread::sleep(std::time::Duration::from_millis(5));
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let before = manifest_jobs(&manifest);
    assert!(!before.is_empty(), "the batch recorded a job before the kill");
    assert!(before.iter().all(|j| j["status"] == "ok" && j["outputs"].as_array().unwrap().len() == 1));
    let done: HashSet<u64> = before.iter().map(|j| j["index"].as_u64().unwrap()).collect();

    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--resume"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains(&format!("resuming: {} of {count} jobs finished", done.len())), "{}", stderr(&out));
    let after = manifest_jobs(&manifest);
    assert_eq!(after.len(), count);
    for (i, record) in after.iter().enumerate() {
        assert_eq!(record["index"].as_u64(), Some(i as u64));
        assert_eq!(record["from_earlier_run"].as_bool().unwrap_or(false), done.contains(&(i as u64)), "job {i}");
        assert!(dir.path().join(format!("view{i}.png")).is_file());
    }

    // A manifest with some jobs done, from the first jobs of the same file: those are skipped.
    let partial = dir.path().join("partial.toml");
    std::fs::write(&partial, view_jobs(3, 16)).unwrap();
    let m2 = dir.path().join("m2.json");
    let out = radray(&["batch", partial.to_str().unwrap(), "--manifest", m2.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    std::fs::write(&partial, view_jobs(5, 16)).unwrap();
    let out = radray(&["batch", partial.to_str().unwrap(), "--manifest", m2.to_str().unwrap(), "--resume"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let resumed: Vec<bool> =
        manifest_jobs(&m2).iter().map(|j| j["from_earlier_run"].as_bool().unwrap_or(false)).collect();
    assert_eq!(resumed, vec![true, true, true, false, false]);

    // The jobs file changed under the manifest (job 0's width): refused, nothing run.
    std::fs::write(&partial, view_jobs(5, 20)).unwrap();
    let out = radray(&["batch", partial.to_str().unwrap(), "--manifest", m2.to_str().unwrap(), "--resume"]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("does not match") && stderr(&out).contains("job 0"), "{}", stderr(&out));
    assert_eq!(manifest_jobs(&m2).len(), 5, "the refused resume left the manifest alone");
}

#[test]
fn cache_memory_is_read_from_the_jobs_file_with_units() {
    let dir = tempfile::tempdir().unwrap();
    let jobs_path = dir.path().join("jobs.toml");
    std::fs::write(&jobs_path, format!("cache_memory = \"64 MiB\"\n{}", view_jobs(2, 16))).unwrap();
    let out = radray(&["batch", jobs_path.to_str().unwrap()]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(manifest_jobs(&dir.path().join("jobs.manifest.json"))[1]["reused_solution"], true);
    // No room at all: every job solves again.
    let out = radray(&["batch", jobs_path.to_str().unwrap(), "--cache-memory", "0"]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert_eq!(manifest_jobs(&dir.path().join("jobs.manifest.json"))[1]["reused_solution"], false);
    std::fs::write(&jobs_path, format!("\ncache_memory = \"lots\"\n{}", view_jobs(1, 16))).unwrap();
    let out = radray(&["batch", jobs_path.to_str().unwrap()]);
    assert_eq!(out.status.code(), Some(2));
    assert!(stderr(&out).contains("jobs.toml:2: cache_memory"), "{}", stderr(&out));
}
