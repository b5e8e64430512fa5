//! Every shipped scene renders and solves to the same bytes as when this table was approved.
//!
//! The table (`tests/data/golden_bytes.txt`) holds an FNV-1a 64 hash of each output of the real
//! binary at small settings: the solution file, and the final and radiosity EXRs with both direct
//! estimators. A refactor must leave every line unchanged. A change that is meant to alter the images
//! re-approves the table on purpose, with `RADRAY_BLESS=1 cargo test --test golden_bytes`, and says in
//! its commit which lines moved and why.

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};
use std::process::Command;

const SCENES: &[&str] = &["cornell_box", "cornell_empty", "cornell_specular", "furnace", "primitives", "showcase"];
const SMALL: &[&str] = &["--width", "32", "--height", "24", "--spp", "4", "--quality", "preview", "--quiet"];

fn table_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/data/golden_bytes.txt")
}

/// FNV-1a, 64 bit: h ← (h ⊕ byte) · 0x100000001b3, from 0xcbf29ce484222325.
fn fnv1a64(bytes: &[u8]) -> u64 {
    bytes.iter().fold(0xcbf2_9ce4_8422_2325, |h, &b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3))
}

fn radray(args: &[&str]) {
    let out = Command::new(env!("CARGO_BIN_EXE_radray")).args(args).output().expect("the radray binary runs");
    assert!(out.status.success(), "radray {args:?} failed: {}", String::from_utf8_lossy(&out.stderr));
}

/// Runs every scene at the small settings and hashes each output file, keyed `scene.output`.
fn measure(dir: &Path) -> BTreeMap<String, u64> {
    let mut hashes = BTreeMap::new();
    for name in SCENES {
        let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes").join(format!("{name}.toml"));
        let scene = scene.to_str().unwrap();
        let solution = dir.join(format!("{name}.radsol"));
        radray(&["solve", scene, "-o", solution.to_str().unwrap(), "--quality", "preview", "--quiet"]);
        // The first render solves again; the second reads the saved solution, which renders the
        // same bytes (tests/cli.rs), so pass one runs twice per scene instead of three times and
        // both paths stay pinned.
        for (direct, saved) in [("radiosity", None), ("pixel", Some(&solution))] {
            let image = dir.join(format!("{name}.{direct}.exr"));
            let mut args = vec!["render", scene, "-o", image.to_str().unwrap(), "--mode", "both", "--direct", direct];
            if let Some(solution) = saved {
                args.extend(["--solution", solution.to_str().unwrap()]);
            }
            args.extend(SMALL);
            radray(&args);
        }
        let mut files: Vec<PathBuf> = std::fs::read_dir(dir).unwrap().map(|e| e.unwrap().path()).collect();
        files.sort();
        for file in files {
            let key = file.file_name().unwrap().to_str().unwrap().to_owned();
            if key.starts_with(&format!("{name}.")) {
                hashes.insert(key, fnv1a64(&std::fs::read(&file).unwrap()));
            }
        }
    }
    hashes
}

#[test]
fn shipped_scenes_render_to_the_approved_bytes() {
    let dir = tempfile::tempdir().unwrap();
    let measured = measure(dir.path());
    if std::env::var_os("RADRAY_BLESS").is_some() {
        let text: String = measured.iter().map(|(k, h)| format!("{k} {h:016x}\n")).collect();
        std::fs::write(table_path(), text).unwrap();
        return;
    }
    let table = std::fs::read_to_string(table_path()).expect("tests/data/golden_bytes.txt exists");
    let approved: BTreeMap<String, u64> = table
        .lines()
        .filter_map(|l| l.split_once(' '))
        .map(|(k, h)| (k.to_owned(), u64::from_str_radix(h, 16).unwrap()))
        .collect();
    let moved: Vec<&String> = approved.keys().filter(|k| measured.get(*k) != approved.get(*k)).collect();
    let added: Vec<&String> = measured.keys().filter(|k| !approved.contains_key(*k)).collect();
    assert!(
        moved.is_empty() && added.is_empty(),
        "outputs whose bytes changed: {moved:?}; not in the table: {added:?}"
    );
}
