//! Batch jobs: many renders from one TOML file, with a JSON manifest. Each `[[job]]` becomes a
//! `run::Job` and runs through the same `run::Runner` as a single render, which keeps a scene's form
//! factors for its later jobs (radiosity is view-independent; jobs that change only emission or
//! reflectance re-solve from them) and shares identical solutions. `--shard K/N` runs every N-th job
//! from K, so a cluster's job array can split a batch with no extra software. The manifest is rewritten
//! after every job (`manifest`), so `--resume` can skip what a killed batch finished; `--report`
//! writes the HTML comparison page (`report`).

use crate::output::{Exposure, ToneCurve};
use crate::progress::Progress;
use crate::run::{self, Failure, Job, Mode, Outcome, PngSettings, Runner, Work};
use crate::scene::overrides::{CameraOverride, MaterialOverride};
use crate::scene::{DirectMode, FinalGatherMode, MethodChoice, Overrides, Quality};
use serde::Deserialize;
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::time::Instant;

mod manifest;
pub mod report;

pub use manifest::{JobRecord, Manifest};

/// A batch to run: the jobs file, where to write the manifest, and which shard of the jobs.
#[derive(Clone, Debug, Default)]
pub struct Settings {
    /// Jobs file (TOML with [[job]] entries).
    pub jobs: PathBuf,
    /// Manifest to write (default: <jobs>.manifest.json beside the jobs file).
    pub manifest: Option<PathBuf>,
    /// `K/N`: every N-th job starting at K (0-based).
    pub shard: Option<String>,
    /// The HTML comparison report to write (`report::page`).
    pub report: Option<PathBuf>,
    /// Skip the jobs the manifest records as finished (after checking it belongs to the jobs file).
    pub resume: bool,
    /// Most bytes the caches kept between jobs may hold (over the jobs file's `cache_memory`).
    pub cache_memory_bytes: Option<u64>,
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JobsFile {
    /// Bound of the caches kept between jobs: bytes, or a size such as "512 MiB".
    cache_memory: Option<toml::Spanned<MemorySize>>,
    #[serde(default)]
    job: Vec<toml::Spanned<JobEntry>>,
}

#[derive(Deserialize)]
#[serde(untagged)]
enum MemorySize {
    Bytes(u64),
    Text(String),
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
    final_gather: Option<FinalGatherMode>,
    quality: Option<Quality>,
    /// The pass-one method, as the scene's `[radiosity] method`.
    #[serde(default)]
    method: Option<MethodChoice>,
    exposure: Option<Exposure>,
    tone: Option<ToneCurve>,
    camera: Option<CameraOverride>,
    /// Per material name: new `kd`, `ke` or `ks` (re-solves from cached form factors).
    #[serde(default)]
    materials: HashMap<String, MaterialOverride>,
    /// An image (EXR, or PNG read as sRGB) the report compares this job's images with.
    reference: Option<PathBuf>,
    /// A layered EXR to write as well (`render --layers`).
    layers: Option<PathBuf>,
}

impl From<manifest::ResumeError> for Failure {
    fn from(e: manifest::ResumeError) -> Self {
        Failure::input(e)
    }
}

/// The 1-based line of byte `offset` in `text`.
fn line_of(text: &str, offset: usize) -> usize {
    text[..offset.min(text.len())].matches('\n').count() + 1
}

/// The `--resume` key of every job (`manifest::job_key`), from the jobs file read as plain TOML.
fn job_keys(text: &str, path: &Path) -> Result<Vec<String>, Failure> {
    let table: toml::Table = toml::from_str(text)
        .map_err(|e| Failure::input(anyhow::anyhow!("{}: {}", path.display(), e.message().trim())))?;
    let jobs = table.get("job").and_then(|j| j.as_array()).cloned().unwrap_or_default();
    Ok(jobs.iter().map(manifest::job_key).collect())
}

/// Runs the jobs file; the exit code is non-zero if any job failed.
pub fn run(args: &Settings, progress: &Progress) -> Result<(), Failure> {
    let text = std::fs::read_to_string(&args.jobs)
        .map_err(|e| Failure::input(anyhow::anyhow!("{}: cannot read jobs file: {e}", args.jobs.display())))?;
    let file: JobsFile = toml::from_str(&text).map_err(|e| {
        let line = e.span().map_or(0, |s| line_of(&text, s.start));
        Failure::input(anyhow::anyhow!("{}:{line}: {}", args.jobs.display(), e.message().trim()))
    })?;
    if file.job.is_empty() {
        return Err(Failure::input(anyhow::anyhow!("{}: no [[job]] entries", args.jobs.display())));
    }
    let keys = job_keys(&text, &args.jobs)?;
    let shard =
        args.shard.as_deref().map(run::parse_shard).transpose().map_err(|e| Failure::input(anyhow::anyhow!(e)))?;
    let manifest_path = args.manifest.clone().unwrap_or_else(|| {
        let stem = args.jobs.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "jobs".into());
        args.jobs.with_file_name(format!("{stem}.manifest.json"))
    });
    run::check_output_directory(&manifest_path)?;
    let base = args.jobs.parent().unwrap_or(Path::new(".")).to_path_buf();
    let report = args.report.as_deref().map(report::ReportPaths::prepare).transpose()?;
    let title = args.jobs.display().to_string();

    let selected: Vec<usize> = (0..file.job.len()).filter(|i| shard.is_none_or(|(k, n)| i % n == k)).collect();
    let mut writer = manifest::ManifestWriter::new(&manifest_path, &title, args.shard.as_deref());
    let mut records: Vec<JobRecord> = Vec::new();
    if args.resume {
        let done = manifest::finished_jobs(&manifest_path, &args.jobs, &keys)?;
        for mut record in done {
            // A job finished without the report's images runs again when a report is asked for.
            if selected.contains(&record.index) && (report.is_none() || record.report.is_some()) {
                record.from_earlier_run = true;
                records.push(record);
            }
        }
        progress.note(&format!(
            "resuming: {} of {} jobs finished in {}",
            records.len(),
            selected.len(),
            manifest_path.display()
        ));
    }
    for record in &records {
        writer.add(record).map_err(Failure::internal)?;
    }
    let write_error =
        |e: std::io::Error| Failure::input(anyhow::anyhow!("{}: cannot write manifest: {e}", manifest_path.display()));
    writer.write().map_err(write_error)?;
    if let Some(paths) = &report {
        report::write(paths, &title, &records)?;
    }

    let cache_memory_bytes = match (args.cache_memory_bytes, &file.cache_memory) {
        (Some(bytes), _) => bytes,
        (None, Some(size)) => match size.get_ref() {
            MemorySize::Bytes(bytes) => *bytes,
            MemorySize::Text(size_text) => crate::cache::parse_bytes(size_text).map_err(|e| {
                Failure::input(anyhow::anyhow!(
                    "{}:{}: cache_memory: {e}",
                    args.jobs.display(),
                    line_of(&text, size.span().start)
                ))
            })?,
        },
        (None, None) => crate::cache::DEFAULT_BUDGET_BYTES,
    };
    let overall = progress.stage("batch", selected.len() as u64, "jobs");
    overall.inc(records.len() as u64);
    let mut runner = Runner::batch_within(cache_memory_bytes);
    for &index in &selected {
        if records.iter().any(|r| r.index == index) {
            continue;
        }
        let entry = file.job[index].get_ref();
        let line = line_of(&text, file.job[index].span().start);
        let start = Instant::now();
        let mut outcome = Outcome::default();
        let mut report_images = None;
        let result = job_of(entry, &base).and_then(|mut job| {
            if let (Some(paths), Work::Render { plan, .. }) = (&report, &mut job.work) {
                plan.extend(paths.plan(index));
            }
            runner.run(&job, progress, &mut outcome)?;
            if let Some(paths) = &report {
                outcome.written.retain(|p| !p.starts_with(&paths.files));
            }
            if let (Some(paths), Work::Render { png, .. }) = (&report, &job.work) {
                let reference = entry.reference.as_ref().map(|r| base.join(r));
                report_images = Some(report::job_images(paths, index, png, reference.as_deref())?);
            }
            Ok(())
        });
        let mut record = JobRecord {
            index,
            job_key: keys.get(index).cloned().unwrap_or_default(),
            scene: entry.scene.display().to_string(),
            status: "ok".into(),
            error: None,
            outputs: Vec::new(),
            seconds: 0.0,
            stats: serde_json::Value::Null,
            reused_form_factors: outcome.reused_form_factors,
            reused_solution: outcome.reused_solution,
            report: report_images,
            from_earlier_run: false,
        };
        match result {
            Ok(()) => record.outputs = outcome.written.iter().map(|p| p.display().to_string()).collect(),
            Err(f) => {
                record.status = "failed".into();
                record.error = Some(format!("{}:{line}: job {index}: {f}", args.jobs.display()));
                progress.note(&format!("error: {}", record.error.as_deref().unwrap_or_default()));
            }
        }
        outcome.stats.peak_memory_bytes = run::peak_memory_bytes();
        record.seconds = start.elapsed().as_secs_f64();
        record.stats = serde_json::to_value(&outcome.stats).map_err(Failure::internal)?;
        writer.add(&record).map_err(Failure::internal)?;
        writer.write().map_err(write_error)?;
        let at = records.partition_point(|r| r.index < index);
        records.insert(at, record);
        overall.inc(1);
    }
    writer.finish().map_err(write_error)?;
    let failed = records.iter().filter(|r| r.status != "ok").count();
    overall.finish(&format!("{} jobs, {failed} failed", records.len()));
    if let Some(paths) = &report {
        report::write(paths, &title, &records)?;
    }
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
        final_gather: entry.final_gather,
        quality: entry.quality,
        method: entry.method,
        camera: entry.camera.clone(),
        materials,
    };
    let png = PngSettings { exposure: entry.exposure, tone: entry.tone.unwrap_or_default() };
    let layers = entry.layers.as_ref().map(|p| base.join(p));
    if let Some(path) = &layers {
        run::check_layers_path(path)?;
    }
    if let Some(reference) = &entry.reference {
        let path = base.join(reference);
        crate::output::ImageFormat::from_path(&path)?;
        if !path.is_file() {
            return Err(Failure::input(anyhow::anyhow!("reference {}: no such file", path.display())));
        }
    }
    Ok(Job { scene: base.join(&entry.scene), overrides, work: Work::Render { plan, png, solution: None, layers } })
}
