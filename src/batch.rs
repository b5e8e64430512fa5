//! Batch jobs: many renders from one TOML file, with a JSON manifest. A scene's form factors are
//! computed once and reused by all its jobs (radiosity is view-independent); jobs that change only
//! emission or reflectance re-solve from the cached form factors. `--shard K/N` runs every N-th job
//! from K, so a cluster's job array can split a batch with no extra software.

use crate::cli::{self, BatchArgs, Failure, Mode, Overrides};
use crate::mesh::Mesh;
use crate::pipeline::{self, RunStats};
use crate::progress::Progress;
use crate::radiosity::solution::{self, Fnv1a64};
use crate::radiosity::{FormFactors, Solution};
use crate::scene::{self, SceneDescription};
use glam::Vec3;
use serde::{Deserialize, Serialize};
use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JobsFile {
    #[serde(default)]
    job: Vec<toml::Spanned<Job>>,
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
struct Job {
    scene: PathBuf,
    output: Outputs,
    #[serde(default)]
    mode: Option<Mode>,
    width: Option<u32>,
    height: Option<u32>,
    spp: Option<u32>,
    seed: Option<u64>,
    direct: Option<cli::DirectArg>,
    quality: Option<cli::QualityArg>,
    exposure: Option<f32>,
    tone: Option<cli::ToneArg>,
    camera: Option<CameraOverride>,
    /// Per material name: new `kd`, `ke` or `ks` (re-solves from cached form factors).
    #[serde(default)]
    materials: HashMap<String, MaterialOverride>,
}

#[derive(Deserialize, Clone, Debug)]
#[serde(deny_unknown_fields)]
struct CameraOverride {
    eye: Option<[f32; 3]>,
    look_at: Option<[f32; 3]>,
    up: Option<[f32; 3]>,
    vfov_deg: Option<f32>,
}

#[derive(Deserialize, Clone, Debug)]
#[serde(deny_unknown_fields)]
struct MaterialOverride {
    kd: Option<[f32; 3]>,
    ke: Option<[f32; 3]>,
    ks: Option<[f32; 3]>,
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

/// What pass one's results depend on, so they can be shared between jobs.
#[derive(Default)]
struct Cache {
    /// Geometry key → form factors (only the most recent scene's: matrices are large).
    form_factors: Option<(u64, Arc<FormFactors>)>,
    /// Mesh fingerprint (geometry + materials) and solver settings → solution.
    solutions: HashMap<u64, Arc<Solution>>,
}

/// FNV-1a over the bytes that decide form factors: positions, corners, hemicube settings and, since
/// extended form factors follow light through mirrors and glass, each element's specular material
/// (Ks, Ni, 1 − d) and its diffuse/emissive flags (which decide where specular paths end).
fn geometry_key(mesh: &Mesh, scene: &SceneDescription) -> u64 {
    let mut h = Fnv1a64::default();
    h.write_f32s(mesh.positions.iter().flat_map(|p| p.to_array()));
    for c in &mesh.elements.corners {
        for v in c {
            h.write(&v.to_le_bytes());
        }
    }
    solution::hash_specular_materials(&mut h, mesh, &scene.materials);
    let r = &scene.radiosity;
    h.write(&r.hemicube_resolution_px.to_le_bytes());
    h.write(&[r.rotate_hemicubes as u8]);
    h.write(&r.seed.to_le_bytes());
    h.finish()
}

fn solution_key(mesh: &Mesh, scene: &SceneDescription) -> u64 {
    let r = &scene.radiosity;
    let mut h = solution::fingerprint(mesh, &scene.materials) ^ geometry_key(mesh, scene).rotate_left(17);
    for x in [
        r.relaxation.to_bits(),
        r.tolerance.to_bits(),
        r.max_iterations as u64,
        r.solver as u64,
        r.store_form_factors as u64,
    ] {
        h = (h ^ x).wrapping_mul(0x100000001b3);
    }
    h
}

/// Runs the jobs file; the exit code is non-zero if any job failed.
pub fn run(args: &BatchArgs, progress: &Progress) -> Result<(), Failure> {
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
    let mut cache = Cache::default();
    let mut records = Vec::new();
    for &index in &selected {
        let job = file.job[index].get_ref();
        let start = Instant::now();
        let mut stats = RunStats::default();
        let mut record = JobRecord {
            index,
            scene: job.scene.display().to_string(),
            status: "ok",
            error: None,
            outputs: Vec::new(),
            seconds: 0.0,
            stats: RunStats::default(),
            reused_form_factors: false,
            reused_solution: false,
        };
        match run_job(job, &base, progress, &mut cache, &mut stats, &mut record) {
            Ok(outputs) => record.outputs = outputs.iter().map(|p| p.display().to_string()).collect(),
            Err(f) => {
                record.status = "failed";
                let line = text[..file.job[index].span().start].matches('\n').count() + 1;
                record.error = Some(format!("{}:{line}: job {index}: {f}", args.jobs.display()));
                progress.note(&format!("error: {}", record.error.as_deref().unwrap_or_default()));
            }
        }
        stats.peak_memory_bytes = pipeline::peak_memory_bytes();
        record.seconds = start.elapsed().as_secs_f64();
        record.stats = stats;
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

fn run_job(
    job: &Job,
    base: &Path,
    progress: &Progress,
    cache: &mut Cache,
    stats: &mut RunStats,
    record: &mut JobRecord,
) -> Result<Vec<PathBuf>, Failure> {
    let overrides = Overrides {
        width: job.width,
        height: job.height,
        spp: job.spp,
        seed: job.seed,
        direct: job.direct,
        quality: job.quality,
        exposure: job.exposure,
        tone: job.tone,
    };
    let outputs: Vec<PathBuf> = match &job.output {
        Outputs::One(p) => vec![base.join(p)],
        Outputs::Many(v) => v.iter().map(|p| base.join(p)).collect(),
    };
    let plan = cli::output_plan(&outputs, job.mode.unwrap_or(Mode::Final))?;
    let mut scene = cli::load_scene(&base.join(&job.scene), &overrides, progress)?;
    apply_job_settings(&mut scene, job)?;

    let mesh = pipeline::build_mesh(&scene, progress).map_err(Failure::input)?;
    stats.elements = mesh.elements.len();
    let key = solution_key(&mesh, &scene);
    let photons = pipeline::RunPhotons::default();
    let solution = if let Some(s) = cache.solutions.get(&key) {
        record.reused_solution = true;
        record.reused_form_factors = true;
        s.clone()
    } else if !scene.has_emitter() {
        Arc::new(Solution::black(&mesh, &scene.materials))
    } else if !scene.radiosity.store_form_factors {
        let accel = pipeline::specular_accel(&scene, &mesh);
        let solution = Arc::new(pipeline::solve_matrix_free(&scene, &mesh, accel.as_ref(), progress, stats));
        cache.solutions.insert(key, solution.clone());
        solution
    } else {
        let gkey = geometry_key(&mesh, &scene);
        let ff = match &cache.form_factors {
            Some((k, ff)) if *k == gkey => {
                record.reused_form_factors = true;
                ff.clone()
            }
            _ => {
                cache.form_factors = None; // free the previous scene's matrix first
                pipeline::check_memory(&scene, &mesh).map_err(Failure::input)?;
                let accel = pipeline::specular_accel(&scene, &mesh);
                let ff =
                    Arc::new(pipeline::compute_form_factors(&scene, &mesh, accel.as_ref(), &photons, progress, stats));
                cache.form_factors = Some((gkey, ff.clone()));
                ff
            }
        };
        let solution = Arc::new(pipeline::solve(&scene, &mesh, &ff, progress, stats));
        cache.solutions.insert(key, solution.clone());
        solution
    };
    cli::render_scene(&scene, &mesh, &solution, &plan, &overrides, &photons, progress, stats)
}

/// Applies a job's camera and material overrides, checking materials as the scene parser does.
fn apply_job_settings(scene: &mut SceneDescription, job: &Job) -> Result<(), Failure> {
    if let Some(c) = &job.camera {
        let cam = &mut scene.camera;
        if let Some(v) = c.eye {
            cam.eye = Vec3::from(v);
        }
        if let Some(v) = c.look_at {
            cam.look_at = Vec3::from(v);
        }
        if let Some(v) = c.up {
            cam.up = Vec3::from(v);
        }
        if let Some(v) = c.vfov_deg {
            cam.vfov_deg = v;
        }
        scene::check_camera(cam).map_err(|(_, e)| Failure::input(anyhow::anyhow!("camera override: {e}")))?;
    }
    for (name, o) in &job.materials {
        let Some(m) = scene.materials.iter_mut().find(|m| &m.name == name) else {
            return Err(Failure::input(anyhow::anyhow!("materials.{name}: the scene has no material `{name}`")));
        };
        if let Some(v) = o.kd {
            m.diffuse_reflectance = Vec3::from(v);
        }
        if let Some(v) = o.ke {
            m.emitted_radiance = Vec3::from(v);
        }
        if let Some(v) = o.ks {
            m.specular_reflectance = Vec3::from(v);
        }
        scene::parse::check_material(m).map_err(|(_, e)| Failure::input(anyhow::anyhow!("materials.{name}: {e}")))?;
    }
    Ok(())
}
