//! Batch jobs: many renders from one TOML file, with a JSON manifest. Each `[[job]]` becomes a
//! `run::Job` and runs through the same `run::Runner` as a single render, which keeps a scene's form
//! factors for its later jobs (radiosity is view-independent; jobs that change only emission or
//! reflectance re-solve from them) and shares identical solutions. `--shard K/N` runs every N-th job
//! from K, so a cluster's job array can split a batch with no extra software.

use crate::output::{Exposure, ToneCurve};
use crate::progress::Progress;
use crate::run::{self, Failure, Job, Mode, Outcome, PngSettings, RunStats, Runner, Work};
use crate::scene::overrides::{CameraOverride, MaterialOverride};
use crate::scene::{DirectMode, Overrides, Quality};
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

/// A batch to run: the jobs file, where to write the manifest, and which shard of the jobs.
#[derive(Clone, Debug)]
pub struct Settings {
    /// Jobs file (TOML with [[job]] entries).
    pub jobs: PathBuf,
    /// Manifest to write (default: <jobs>.manifest.json beside the jobs file).
    pub manifest: Option<PathBuf>,
    /// `K/N`: every N-th job starting at K (0-based).
    pub shard: Option<String>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JobsFile {
    #[serde(default)]
    job: Vec<toml::Spanned<JobEntry>>,
}

#[derive(Deserialize, Clone, Debug)]
#[serde(untagged)]
enum Outputs {
    One(PathBuf),
    Many(Vec<PathBuf>),
}

/// One `[[job]]`: a scene, its outputs, and settings laid over the scene's.
#[derive(Deserialize, Clone, Debug)]
#[serde(deny_unknown_fields)]
struct JobEntry {
    scene: PathBuf,
    output: Outputs,
    #[serde(default)]
    mode: Option<Mode>,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
    seed: Option<u64>,
    direct: Option<DirectMode>,
    quality: Option<Quality>,
    exposure: Option<Exposure>,
    tone: Option<ToneCurve>,
    camera: Option<CameraOverride>,
    /// Per material name: new `kd`, `ke` or `ks` (re-solves from cached form factors).
    #[serde(default)]
    materials: HashMap<String, MaterialOverride>,
}

/// One job's line in the manifest.
#[derive(Serialize, Debug)]
pub struct JobRecord {
    pub index: usize,
    pub scene: String,
    pub status: &'static str,
    pub error: Option<String>,
    pub outputs: Vec<String>,
    pub seconds: f64,
    pub stats: RunStats,
    /// Whether the form factors / solution came from an earlier job of this batch.
    pub reused_form_factors: bool,
    pub reused_solution: bool,
}

#[derive(Serialize, Debug)]
pub struct Manifest {
    pub jobs_file: String,
    pub shard: Option<String>,
    pub jobs: Vec<JobRecord>,
}

/// Parses `K/N` (0 ≤ K < N).
pub fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let (k, n) = text.split_once('/').ok_or_else(|| format!("--shard must be K/N, got `{text}`"))?;
    let k: usize = k.trim().parse().map_err(|_| format!("--shard: `{k}` is not a job index"))?;
    let n: usize = n.trim().parse().map_err(|_| format!("--shard: `{n}` is not a shard count"))?;
    if n == 0 || k >= n {
        return Err(format!("--shard K/N needs 0 ≤ K < N, got {k}/{n}"));
    }
    Ok((k, n))
}

/// Runs the jobs file; the exit code is non-zero if any job failed.
pub fn run(args: &Settings, progress: &Progress) -> Result<(), Failure> {
    let text = std::fs::read_to_string(&args.jobs)
        .map_err(|e| Failure::input(anyhow::anyhow!("{}: cannot read jobs file: {e}", args.jobs.display())))?;
    let file: JobsFile = toml::from_str(&text).map_err(|e| {
        let line = e.span().map_or(0, |s| text[..s.start.min(text.len())].matches('\n').count() + 1);
        Failure::input(anyhow::anyhow!("{}:{line}: {}", args.jobs.display(), e.message().trim()))
    })?;
    if file.job.is_empty() {
        return Err(Failure::input(anyhow::anyhow!("{}: no [[job]] entries", args.jobs.display())));
    }
    let shard = args.shard.as_deref().map(parse_shard).transpose().map_err(|e| Failure::input(anyhow::anyhow!(e)))?;
    let manifest_path = args.manifest.clone().unwrap_or_else(|| {
        let stem = args.jobs.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "jobs".into());
        args.jobs.with_file_name(format!("{stem}.manifest.json"))
    });
    let base = args.jobs.parent().unwrap_or(Path::new(".")).to_path_buf();

    let selected: Vec<usize> = (0..file.job.len()).filter(|i| shard.is_none_or(|(k, n)| i % n == k)).collect();
    let overall = progress.stage("batch", selected.len() as u64, "jobs");
    let mut runner = Runner::batch();
    let mut records = Vec::new();
    for &index in &selected {
        let job = file.job[index].get_ref();
        let start = Instant::now();
        let mut outcome = Outcome::default();
        let result = job_of(job, &base).and_then(|job| runner.run(&job, progress, &mut outcome));
        let mut record = JobRecord {
            index,
            scene: job.scene.display().to_string(),
            status: "ok",
            error: None,
            outputs: Vec::new(),
            seconds: 0.0,
            stats: RunStats::default(),
            reused_form_factors: outcome.reused_form_factors,
            reused_solution: outcome.reused_solution,
        };
        match result {
            Ok(()) => record.outputs = outcome.written.iter().map(|p| p.display().to_string()).collect(),
            Err(f) => {
                record.status = "failed";
                let line = text[..file.job[index].span().start].matches('\n').count() + 1;
                record.error = Some(format!("{}:{line}: job {index}: {f}", args.jobs.display()));
                progress.note(&format!("error: {}", record.error.as_deref().unwrap_or_default()));
            }
        }
        outcome.stats.peak_memory_bytes = run::peak_memory_bytes();
        record.seconds = start.elapsed().as_secs_f64();
        record.stats = outcome.stats;
        records.push(record);
        overall.inc(1);
    }
    let failed = records.iter().filter(|r| r.status != "ok").count();
    overall.finish(&format!("{} jobs, {failed} failed", records.len()));
    let manifest = Manifest { jobs_file: args.jobs.display().to_string(), shard: args.shard.clone(), jobs: records };
    let json = serde_json::to_string_pretty(&manifest).map_err(Failure::internal)?;
    crate::output::write_atomically(&manifest_path, json.as_bytes())
        .map_err(|e| Failure::input(anyhow::anyhow!("{}: cannot write manifest: {e}", manifest_path.display())))?;
    if failed > 0 {
        return Err(Failure::input(anyhow::anyhow!(
            "{failed} of {} jobs failed; see {}",
            selected.len(),
            manifest_path.display()
        )));
    }
    Ok(())
}

/// The `run::Job` of a `[[job]]`: paths relative to the jobs file, the output plan checked before any
/// work, materials in name order (so that the first unknown one is always the one reported).
fn job_of(entry: &JobEntry, base: &Path) -> Result<Job, Failure> {
    let outputs: Vec<PathBuf> = match &entry.output {
        Outputs::One(p) => vec![base.join(p)],
        Outputs::Many(v) => v.iter().map(|p| base.join(p)).collect(),
    };
    let plan = run::output_plan(&outputs, entry.mode.unwrap_or(Mode::Final))?;
    let mut materials: Vec<(String, MaterialOverride)> =
        entry.materials.iter().map(|(name, o)| (name.clone(), o.clone())).collect();
    materials.sort_by(|a, b| a.0.cmp(&b.0));
    let overrides = Overrides {
        width_px: entry.width,
        height_px: entry.height,
        samples_per_pixel: entry.spp,
        seed: entry.seed,
        direct: entry.direct,
        quality: entry.quality,
        camera: entry.camera.clone(),
        materials,
    };
    let png = PngSettings { exposure: entry.exposure, tone: entry.tone.unwrap_or_default() };
    Ok(Job { scene: base.join(&entry.scene), overrides, work: Work::Render { plan, png, solution: None } })
}
