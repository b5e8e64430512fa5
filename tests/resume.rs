//! Resumable and sharded pass one: an interrupted solve resumes from its checkpoint to the bytes of an
//! uninterrupted one, a damaged or stale checkpoint is ignored with a warning, and the parts of a
//! sharded solve merge to the bytes of a single-machine solve, with every shard required once. The
//! hierarchical method resumes the same way from its log of link estimates, and its shards hand their
//! link estimates and the solved state of the pass before to the next round and to a merge that ends
//! with the bytes of a single-machine solve.

mod common;

use std::io::{BufRead, BufReader};
use std::path::{Path, PathBuf};
use std::process::{Command, Stdio};
use std::time::Duration;

use common::radray;
use radray::interrupt::{Cancel, SIGINT, SIGTERM};
use radray::progress::Progress;
use radray::radiosity::hierarchy::estimates::CHUNK_LINKS;
use radray::radiosity::hierarchy::{links_file, part_file};
use radray::radiosity::matrix::rows_file::{self, RowsHeader, RowsKind};
use radray::radiosity::resume::{checkpoint_path, Resume};
use radray::run::{Job, Outcome, Runner, Work};
use radray::scene::{MethodChoice, Overrides, Quality};

fn cornell_box() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_box.toml")
}

/// A solve of the Cornell box at the preview quality (937 elements, four receiver groups) on the
/// stored matrix (`auto` would take the adaptive mesh, which keeps no checkpoint).
fn preview_solve(output: &Path) -> Job {
    Job {
        scene: cornell_box(),
        overrides: Overrides {
            quality: Some(Quality::Preview),
            method: Some(MethodChoice::Matrix),
            ..Default::default()
        },
        work: Work::Solve { output: output.to_path_buf() },
    }
}

/// `solve` of the Cornell box at the preview quality with `more`, on the stored matrix unless `more`
/// names a method (`auto` would take the adaptive mesh, which keeps no checkpoint).
fn preview_args<'a>(output: &'a str, more: &[&'a str]) -> Vec<&'a str> {
    let scene = Box::leak(cornell_box().display().to_string().into_boxed_str());
    let mut args = vec!["solve", scene, "--quality", "preview", "-o", output];
    if !more.contains(&"--method") {
        args.extend(["--method", "matrix"]);
    }
    args.extend_from_slice(more);
    args
}

fn uninterrupted_solution(dir: &Path) -> Vec<u8> {
    let path = dir.join("reference.radsol");
    let mut outcome = Outcome::default();
    Runner::single().run(&preview_solve(&path), &Progress::hidden(), &mut outcome).unwrap();
    std::fs::read(path).unwrap()
}

#[test]
fn a_solve_interrupted_after_300_rows_resumes_to_the_bytes_of_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("cornell.radsol");
    let checkpoint = checkpoint_path(&output);
    // Zero interval: a checkpoint after every batch of rows, as a long run writes them every 30 s.
    let interrupted = Resume {
        checkpoint: Some(checkpoint.clone()),
        interval: Duration::ZERO,
        cancel: Cancel::after_rows(300, SIGTERM),
        ..Default::default()
    };
    let mut outcome = Outcome::default();
    let failure = Runner::resumable(interrupted).run(&preview_solve(&output), &Progress::hidden(), &mut outcome);
    let failure = failure.expect_err("the run is cancelled after 300 rows");
    assert_eq!(failure.exit_code, 143, "{failure}");
    assert!(failure.to_string().contains("cornell.radsol.partial"), "{failure}");
    assert!(!output.exists(), "no solution from an interrupted run");
    let (header, rows) = rows_file::read(&checkpoint).unwrap();
    assert_eq!(header.kind, RowsKind::Checkpoint);
    assert!(!rows.is_complete(), "interrupted part-way: {} of {} rows", rows.done_count(), rows.len());

    let resumed = Resume { checkpoint: Some(checkpoint.clone()), interval: Duration::ZERO, ..Default::default() };
    let mut outcome = Outcome::default();
    Runner::resumable(resumed).run(&preview_solve(&output), &Progress::hidden(), &mut outcome).unwrap();
    let stats = outcome.stats.pass_one.resume.expect("resume statistics");
    assert!(stats.rows_resumed >= 300, "{stats:?}");
    assert!(stats.rows_computed > 0, "{stats:?}");
    assert_eq!(stats.rows_resumed + stats.rows_computed, 937);
    assert!(!checkpoint.exists(), "the checkpoint is removed once the solution is written");
    assert!(std::fs::read(&output).unwrap() == uninterrupted_solution(dir.path()), "resumed bytes differ");
}

#[test]
fn a_damaged_checkpoint_is_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let reference = uninterrupted_solution(dir.path());
    let output = dir.path().join("cornell.radsol");
    let checkpoint = checkpoint_path(&output);
    // A checkpoint cut short: the first half of a real one.
    let resume = Resume {
        checkpoint: Some(checkpoint.clone()),
        interval: Duration::ZERO,
        cancel: Cancel::after_rows(500, SIGINT),
        ..Default::default()
    };
    let failure = Runner::resumable(resume).run(&preview_solve(&output), &Progress::hidden(), &mut Outcome::default());
    assert_eq!(failure.expect_err("cancelled").exit_code, 130);
    let bytes = std::fs::read(&checkpoint).unwrap();
    std::fs::write(&checkpoint, &bytes[..bytes.len() / 2]).unwrap();

    let out = radray(&preview_args(output.to_str().unwrap(), &[]));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("warning: ignoring the checkpoint") && stderr.contains("damaged"), "{stderr}");
    assert!(std::fs::read(&output).unwrap() == reference, "bytes differ after ignoring the checkpoint");
}

#[test]
fn a_checkpoint_of_another_scene_is_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let output = dir.path().join("cornell.radsol");
    let checkpoint = checkpoint_path(&output);
    let other =
        RowsHeader { kind: RowsKind::Checkpoint, fingerprint: 1, form_factor_key: 2, shard_index: 0, shard_count: 1 };
    let rows = radray::radiosity::matrix::PartialRows {
        ff: radray::radiosity::matrix::FormFactors::from_rows(vec![vec![(1, 0.5)], vec![]]),
        done: vec![true, true],
        ..Default::default()
    };
    rows_file::write(&checkpoint, &other, &rows, 2).unwrap();
    let out = radray(&preview_args(output.to_str().unwrap(), &[]));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(stderr.contains("made for another scene"), "{stderr}");
    assert!(std::fs::read(&output).unwrap() == uninterrupted_solution(dir.path()));
}

#[test]
fn three_shards_of_the_cornell_box_merge_to_the_bytes_of_a_single_solve() {
    let dir = tempfile::tempdir().unwrap();
    let part = |k: usize| dir.path().join(format!("part.{k}")).display().to_string();
    for k in 0..3 {
        let shard = format!("{k}/3");
        let out = radray(&preview_args(&part(k), &["--shard", &shard]));
        assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    }
    let merged = dir.path().join("merged.radsol").display().to_string();
    // Parts in any order.
    let out = radray(&preview_args(&merged, &["--merge", &part(2), &part(0), &part(1)]));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read(&merged).unwrap() == uninterrupted_solution(dir.path()), "merged bytes differ");

    let refused = |args: &[&str], expected: &str| {
        let target = dir.path().join("refused.radsol").display().to_string();
        let mut more = vec!["--merge"];
        more.extend_from_slice(args);
        let out = radray(&preview_args(&target, &more));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(expected), "expected `{expected}` in: {stderr}");
        assert!(!Path::new(&target).exists(), "nothing written");
    };
    refused(&[&part(0), &part(1)], "shard(s) [2] of 3 missing");
    refused(&[&part(0), &part(1), &part(1), &part(2)], "shard 1 of 3 given twice");
    refused(&[&merged], "not a radray row-block file");
}

#[test]
fn sigint_to_the_binary_saves_a_checkpoint_exits_130_and_the_rerun_gives_the_same_bytes() {
    let dir = tempfile::tempdir().unwrap();
    // The Cornell box (25 mm elements) with 128² hemicubes on one thread: 3.6 s of rows in the test
    // profile on a quiet machine (session 12), so the signal 0.7 s after meshing lands among them on a
    // machine several times faster too. (At 50 mm the 901 rows took 0.45 s and the signal came after
    // the solve had finished: exit 0.)
    let scene = dir.path().join("cornell.toml");
    let text = std::fs::read_to_string(cornell_box()).unwrap();
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_original/scene.obj");
    let text = text
        .replace("hemicube_resolution = 256", "hemicube_resolution = 128")
        .replace("obj = \"cornell_original/scene.obj\"", &format!("obj = {:?}", obj.display().to_string()));
    std::fs::write(&scene, text).unwrap();
    let run = |output: &Path| {
        let mut command = Command::new(env!("CARGO_BIN_EXE_radray"));
        command.args(["-v", "--threads", "1", "solve", "--method", "matrix"]).arg(&scene).arg("-o").arg(output);
        command
    };
    let output = dir.path().join("int.radsol");
    let mut child = run(&output).stderr(Stdio::piped()).spawn().unwrap();
    // The handlers are in place once meshing is reported; the rows follow at once.
    let mut stderr = BufReader::new(child.stderr.take().unwrap());
    let mut line = String::new();
    while stderr.read_line(&mut line).unwrap() > 0 && !line.contains("meshing") {
        line.clear();
    }
    assert!(line.contains("meshing"), "{line}");
    std::thread::sleep(Duration::from_millis(700));
    let killed = Command::new("kill").args(["-INT", &child.id().to_string()]).status().unwrap();
    assert!(killed.success());
    let status = child.wait().unwrap();
    assert_eq!(status.code(), Some(130));
    let (_, rows) = rows_file::read(&checkpoint_path(&output)).unwrap();
    assert!(!rows.is_complete(), "stopped during the rows");

    let stats = dir.path().join("stats.json");
    let resumed = run(&output).arg("--stats").arg(&stats).output().unwrap();
    let log = String::from_utf8_lossy(&resumed.stderr);
    assert!(resumed.status.success(), "{log}");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    assert_eq!(stats["resume"]["rows_resumed"].as_u64(), Some(rows.done_count() as u64), "{stats}");
    let reference = dir.path().join("reference.radsol");
    let fresh = run(&reference).output().unwrap();
    assert!(fresh.status.success());
    assert!(std::fs::read(&output).unwrap() == std::fs::read(&reference).unwrap(), "resumed bytes differ");
}

/// A hierarchical solve of the Cornell box at the preview quality.
fn hierarchical_solve(output: &Path) -> Job {
    let mut job = preview_solve(output);
    job.overrides.method = Some(MethodChoice::Hierarchical);
    job
}

fn uninterrupted_hierarchical_solution(dir: &Path) -> (Vec<u8>, usize) {
    let path = dir.join("reference_hierarchy.radsol");
    let mut outcome = Outcome::default();
    Runner::single().run(&hierarchical_solve(&path), &Progress::hidden(), &mut outcome).unwrap();
    let estimated = outcome.stats.pass_one.hierarchy.expect("hierarchy statistics").links_estimated;
    (std::fs::read(path).unwrap(), estimated as usize)
}

#[test]
fn a_hierarchical_solve_interrupted_during_refinement_resumes_to_the_bytes_of_an_uninterrupted_one() {
    let dir = tempfile::tempdir().unwrap();
    let (reference, estimated) = uninterrupted_hierarchical_solution(dir.path());
    assert!(estimated > 3 * CHUNK_LINKS, "enough estimates to stop part-way: {estimated}");
    let output = dir.path().join("cornell.radsol");
    let checkpoint = checkpoint_path(&output);
    // Stopped after two chunks of link estimates (the hook counts estimates as the matrix counts rows).
    let interrupted = Resume {
        checkpoint: Some(checkpoint.clone()),
        interval: Duration::ZERO,
        cancel: Cancel::after_rows(2 * CHUNK_LINKS, SIGTERM),
        ..Default::default()
    };
    let mut outcome = Outcome::default();
    let failure = Runner::resumable(interrupted).run(&hierarchical_solve(&output), &Progress::hidden(), &mut outcome);
    let failure = failure.expect_err("the run is cancelled during refinement");
    assert_eq!(failure.exit_code, 143, "{failure}");
    assert!(failure.to_string().contains("cornell.radsol.partial"), "{failure}");
    assert!(!output.exists(), "no solution from an interrupted run");
    let (header, entries) = links_file::read(&checkpoint).unwrap();
    assert_eq!(header.kind, RowsKind::HierarchyCheckpoint);
    assert!(entries.len() >= 2 * CHUNK_LINKS && entries.len() < estimated, "{} of {estimated}", entries.len());

    let resumed = Resume { checkpoint: Some(checkpoint.clone()), interval: Duration::ZERO, ..Default::default() };
    let mut outcome = Outcome::default();
    Runner::resumable(resumed).run(&hierarchical_solve(&output), &Progress::hidden(), &mut outcome).unwrap();
    let stats = outcome.stats.pass_one.resume.expect("resume statistics");
    assert_eq!(stats.rows_resumed, entries.len(), "{stats:?}");
    assert!(stats.rows_computed > 0, "{stats:?}");
    assert!(!checkpoint.exists(), "the checkpoint is removed once the solution is written");
    assert!(std::fs::read(&output).unwrap() == reference, "resumed bytes differ");
}

#[test]
fn a_hierarchical_solve_stopped_during_its_sweeps_resumes_without_estimating_again() {
    let dir = tempfile::tempdir().unwrap();
    let (reference, estimated) = uninterrupted_hierarchical_solution(dir.path());
    let output = dir.path().join("cornell.radsol");
    let checkpoint = checkpoint_path(&output);
    // The budget runs out with the last estimate: the stop is seen at the next sweep.
    let interrupted = Resume {
        checkpoint: Some(checkpoint.clone()),
        interval: Duration::from_secs(3600),
        cancel: Cancel::after_rows(estimated, SIGINT),
        ..Default::default()
    };
    let failure =
        Runner::resumable(interrupted).run(&hierarchical_solve(&output), &Progress::hidden(), &mut Outcome::default());
    assert_eq!(failure.expect_err("cancelled").exit_code, 130);
    let (_, entries) = links_file::read(&checkpoint).unwrap();
    assert_eq!(entries.len(), estimated, "every estimate is in the checkpoint written at the stop");

    let resumed = Resume { checkpoint: Some(checkpoint.clone()), interval: Duration::ZERO, ..Default::default() };
    let mut outcome = Outcome::default();
    Runner::resumable(resumed).run(&hierarchical_solve(&output), &Progress::hidden(), &mut outcome).unwrap();
    let stats = outcome.stats.pass_one.resume.expect("resume statistics");
    assert_eq!((stats.rows_resumed, stats.rows_computed), (estimated, 0), "{stats:?}");
    assert!(std::fs::read(&output).unwrap() == reference, "resumed bytes differ");
}

#[test]
fn a_damaged_or_foreign_hierarchical_checkpoint_is_ignored_with_a_warning() {
    let dir = tempfile::tempdir().unwrap();
    let (reference, _) = uninterrupted_hierarchical_solution(dir.path());
    let output = dir.path().join("cornell.radsol");
    let checkpoint = checkpoint_path(&output);
    let resume = Resume {
        checkpoint: Some(checkpoint.clone()),
        interval: Duration::ZERO,
        cancel: Cancel::after_rows(CHUNK_LINKS, SIGINT),
        ..Default::default()
    };
    let failure =
        Runner::resumable(resume).run(&hierarchical_solve(&output), &Progress::hidden(), &mut Outcome::default());
    assert_eq!(failure.expect_err("cancelled").exit_code, 130);
    let bytes = std::fs::read(&checkpoint).unwrap();
    let args = preview_args(output.to_str().unwrap(), &["--method", "hierarchical"]);
    for (damage, expected) in [(&bytes[..bytes.len() / 2], "damaged"), (&b"RADRAYRW"[..], "damaged")] {
        std::fs::write(&checkpoint, damage).unwrap();
        let out = radray(&args);
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert!(out.status.success(), "{stderr}");
        assert!(stderr.contains("warning: ignoring the checkpoint") && stderr.contains(expected), "{stderr}");
        assert!(std::fs::read(&output).unwrap() == reference, "bytes differ after ignoring the checkpoint");
    }
    // A matrix run's checkpoint beside the same output is another kind of file: ignored too.
    let rows = radray::radiosity::matrix::PartialRows {
        ff: radray::radiosity::matrix::FormFactors::from_rows(vec![vec![(1, 0.5)], vec![]]),
        done: vec![true, true],
        ..Default::default()
    };
    let header =
        RowsHeader { kind: RowsKind::Checkpoint, fingerprint: 1, form_factor_key: 2, shard_index: 0, shard_count: 1 };
    rows_file::write(&checkpoint, &header, &rows, 2).unwrap();
    let out = radray(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert!(out.status.success(), "{stderr}");
    assert!(
        stderr.contains("warning: ignoring the checkpoint") && stderr.contains("form-factor checkpoint"),
        "{stderr}"
    );
    assert!(std::fs::read(&output).unwrap() == reference);
}

/// Both refinement passes of the preview Cornell box sharded three ways (pass two's shards take
/// pass one's parts), then merged.
#[test]
fn three_hierarchical_shards_of_the_cornell_box_merge_to_the_bytes_of_a_single_solve() {
    let dir = tempfile::tempdir().unwrap();
    let (reference, _) = uninterrupted_hierarchical_solution(dir.path());
    let part = |pass: u32, k: usize| dir.path().join(format!("p{pass}.{k}")).display().to_string();
    let first: Vec<String> = (0..3).map(|k| part(1, k)).collect();
    for pass in [1, 2] {
        for k in 0..3 {
            let shard = format!("{k}/3");
            let target = part(pass, k);
            let mut args = vec!["--method", "hierarchical", "--shard", &shard];
            if pass == 2 {
                args.push("--merge");
                args.extend(first.iter().map(String::as_str));
            }
            let out = radray(&preview_args(&target, &args));
            assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
            let (header, written) = part_file::read(Path::new(&target)).unwrap();
            assert_eq!(
                (header.kind, header.shard_index, header.shard_count),
                (RowsKind::HierarchyShardPart, k as u32, 3)
            );
            assert_eq!(written.pass, pass);
            // Round two's parts name the solved state of pass one they refined from; shard 0's carries it.
            assert_eq!(written.state.is_some(), pass == 2 && k == 0, "state in part {pass}.{k}");
            assert_eq!(written.state_hash != 0, pass == 2, "state hash in part {pass}.{k}");
        }
    }
    // A third round has nothing left to shard.
    let all: Vec<String> = (1..=2).flat_map(|pass| (0..3).map(move |k| (pass, k))).map(|(p, k)| part(p, k)).collect();
    let mut args = vec!["--method", "hierarchical", "--shard", "0/3", "--merge"];
    args.extend(all.iter().map(String::as_str));
    let extra = dir.path().join("p3.0").display().to_string();
    let out = radray(&preview_args(&extra, &args));
    assert_eq!(out.status.code(), Some(2));
    assert!(String::from_utf8_lossy(&out.stderr).contains("merge them without --shard"));

    let merged = dir.path().join("merged.radsol").display().to_string();
    let stats = dir.path().join("merged.json").display().to_string();
    // Parts in any order.
    let mut args = vec!["--method", "hierarchical", "--stats", &stats, "--merge"];
    args.extend(all.iter().rev().map(String::as_str));
    let out = radray(&preview_args(&merged, &args));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read(&merged).unwrap() == reference, "merged bytes differ from a single solve's");
    let stats: serde_json::Value = serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let from_parts = stats["resume"]["rows_resumed"].as_u64().unwrap_or(0);
    let computed = stats["resume"]["rows_computed"].as_u64().unwrap_or(u64::MAX);
    // Near links are the merge's own.
    assert!(computed.saturating_mul(20) < from_parts, "the merge computes under 5% of the estimates: {stats}");
    // The last round's parts alone suffice: their state holds what round one solved.
    let last: Vec<String> = (0..3).map(|k| part(2, k)).collect();
    let alone = dir.path().join("alone.radsol").display().to_string();
    let mut args = vec!["--method", "hierarchical", "--merge"];
    args.extend(last.iter().map(String::as_str));
    let out = radray(&preview_args(&alone, &args));
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    assert!(std::fs::read(&alone).unwrap() == reference, "a merge of the last round alone differs");

    // A part refined from another state (another run of round one), or a round whose state is
    // missing, is refused, naming the part.
    let refused = |parts: &[&str], expected: &str| {
        let target = dir.path().join("refused.radsol").display().to_string();
        let mut args = vec!["--method", "hierarchical", "--merge"];
        args.extend_from_slice(parts);
        let out = radray(&preview_args(&target, &args));
        let stderr = String::from_utf8_lossy(&out.stderr);
        assert_eq!(out.status.code(), Some(2), "{stderr}");
        assert!(stderr.contains(expected), "{stderr}");
        assert!(!Path::new(&target).exists(), "nothing written");
    };
    let (header, mut other) = part_file::read(Path::new(&part(2, 1))).unwrap();
    other.state_hash ^= 1;
    let stale = dir.path().join("stale.1").display().to_string();
    part_file::write(Path::new(&stale), &header, &other).unwrap();
    refused(&[&part(2, 0), &stale, &part(2, 2)], "stale.1: refined pass 2 from another solved state");
    let (header, mut stateless) = part_file::read(Path::new(&part(2, 0))).unwrap();
    stateless.state = None;
    let cut = dir.path().join("cut.0").display().to_string();
    part_file::write(Path::new(&cut), &header, &stateless).unwrap();
    refused(&[&cut, &part(2, 1), &part(2, 2)], "no part of pass 2 holds the solved state");
    // Parts of two rounds mixed: the last round given must be whole.
    refused(&[&part(1, 0), &part(1, 1), &part(2, 2)], "shard(s) [0, 1] of 3 missing");

    // A part of another scene (the empty Cornell box) is refused, naming the file.
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_empty.toml").display().to_string();
    let foreign = dir.path().join("foreign.0").display().to_string();
    let args = ["solve", &scene, "--quality", "preview", "--method", "hierarchical", "--shard", "0/3", "-o", &foreign];
    assert!(radray(&args).status.success());
    let target = dir.path().join("refused.radsol").display().to_string();
    let out =
        radray(&preview_args(&target, &["--method", "hierarchical", "--merge", &part(1, 0), &foreign, &part(1, 2)]));
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("foreign.0") && stderr.contains("made for another scene"), "{stderr}");
    assert!(!Path::new(&target).exists(), "nothing written");
}

#[test]
fn a_matrix_free_scene_is_refused_by_shard_with_a_message() {
    let dir = tempfile::tempdir().unwrap();
    let scene = dir.path().join("cornell.toml");
    let obj = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/cornell_original/scene.obj");
    let text = std::fs::read_to_string(cornell_box())
        .unwrap()
        .replace("[radiosity]", "[radiosity]\nstore_form_factors = false")
        .replace("solver = \"gauss-seidel\"", "solver = \"progressive\"")
        .replace("obj = \"cornell_original/scene.obj\"", &format!("obj = {:?}", obj.display().to_string()));
    std::fs::write(&scene, text).unwrap();
    let target = dir.path().join("part.0").display().to_string();
    let args = ["solve", scene.to_str().unwrap(), "--method", "matrix", "--shard", "0/3", "-o", &target];
    let out = radray(&args);
    let stderr = String::from_utf8_lossy(&out.stderr);
    assert_eq!(out.status.code(), Some(2), "{stderr}");
    assert!(stderr.contains("sharding and merging need the stored matrix"), "{stderr}");
    assert!(!Path::new(&target).exists(), "nothing written");
}
