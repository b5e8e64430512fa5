//! One way to run a job: load the scene and lay the overrides over it, mesh it, run pass one with the
//! scene's method (or load a saved solution), then either save the solution or render and write the
//! images. A single `render` or `solve` is a batch of one; a batch reuses form factors and solutions
//! between its jobs. `Failure` carries the exit code each error type chooses (`From` impls).

use std::path::{Path, PathBuf};
use std::sync::Arc;
use std::time::Instant;

use anyhow::Context;

mod film_stages;
mod layers;

pub use layers::check_layers_path;

use crate::accel::Accel;
use crate::cache::Lru;
use crate::compare::CompareError;
use crate::film::{self, Image};
use crate::material::SceneTextures;
use crate::mesh::{self, Mesh};
use crate::output::{self, Exposure, OutputError, ToneCurve};
use crate::progress::{Progress, Verbosity};
use crate::radiosity::adaptive::refinement;
use crate::radiosity::hierarchical;
use crate::radiosity::matrix::rows_file::RowsFileError;
use crate::radiosity::method::{self, MethodError, Reuse, ShardMethod};
use crate::radiosity::resume::{self, Checkpointer, Resume, ShardError};
use crate::radiosity::solution_file::{self, SolutionFileError, SolutionMesh};
use crate::radiosity::{fingerprint, PassOneStats, Solution};
use crate::scene::overrides::OverrideError;
use crate::scene::{
    self, FinalGatherMode, MethodChoice, Overrides, RenderParams, SceneDescription, SceneError, SolutionReader,
};
use crate::trace::camera::PinholeCamera;
use crate::trace::gather;
use crate::trace::whitted::{RayCounts, TraceMode, Tracer};
use crate::trace::TraceError;
use crate::transport::photons::RunPhotons;

/// A failed run: the error chain to print and the exit code (2: bad input or usage, 1: internal).
#[derive(Debug)]
pub struct Failure {
    pub exit_code: i32,
    pub error: anyhow::Error,
}

impl Failure {
    /// Bad input or usage: exit code 2.
    pub fn input(error: impl Into<anyhow::Error>) -> Self {
        Failure { exit_code: 2, error: error.into() }
    }

    /// A bug or an environment failure inside radray: exit code 1.
    pub fn internal(error: impl Into<anyhow::Error>) -> Self {
        Failure { exit_code: 1, error: error.into() }
    }
}

impl std::fmt::Display for Failure {
    /// The error and its chain of causes, `error: cause: …`, leaving out a cause whose text the
    /// message before it already carries (most of radray's errors quote their `source`, and anyhow's
    /// `{:#}` printed it twice: "cannot read scene file: No such file …: No such file …").
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let mut previous = self.error.to_string();
        write!(f, "{previous}")?;
        for cause in self.error.chain().skip(1) {
            let text = cause.to_string();
            if !previous.contains(&text) {
                write!(f, ": {text}")?;
            }
            previous = text;
        }
        Ok(())
    }
}

/// Each error type's exit code: the user's input (2) or radray itself (1).
macro_rules! exit_code_of {
    ($($error:ty => $constructor:ident),* $(,)?) => {
        $(impl From<$error> for Failure {
            fn from(e: $error) -> Self {
                Failure::$constructor(e)
            }
        })*
    };
}

impl From<MethodError> for Failure {
    /// An interrupted run exits with 128 + the signal's number (130 for SIGINT, 143 for SIGTERM).
    fn from(e: MethodError) -> Self {
        match e {
            MethodError::Interrupted { signal, .. } => {
                Failure { exit_code: crate::interrupt::exit_code(signal), error: e.into() }
            }
            e => Failure::input(e),
        }
    }
}

exit_code_of! {
    SceneError => input,
    OverrideError => input,
    MeshError => input,
    RowsFileError => input,
    SolutionFileError => input,
    OutputError => input,
    CompareError => input,
    TraceError => internal,
    serde_json::Error => internal,
}

/// What pass one is asked to refuse before meshing.
#[derive(Debug, thiserror::Error)]
pub enum MeshError {
    #[error("{scene}: meshing at max_element_edge = {edge} would make {elements} elements, more than radray handles ({limit}); use a larger max_element_edge or a coarser --quality")]
    TooManyElements { scene: String, edge: f32, elements: u64, limit: u64 },
}

/// Most elements a mesh may have: beyond this even the per-element arrays and one hemicube pass
/// per element are out of reach of a workstation.
pub const MAX_ELEMENTS: u64 = 2_000_000;

/// What a run measured, written by `--stats` and into batch manifests.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunStats {
    #[serde(flatten)]
    pub pass_one: PassOneStats,
    pub render_seconds: f64,
    pub primary_rays: u64,
    pub secondary_rays: u64,
    pub shadow_rays: u64,
    pub rays_per_second: f64,
    pub samples: u64,
    pub adaptive_extra_samples: u64,
    /// Pixels that took adaptive samples, and the seconds the adaptive pass took (part of
    /// `render_seconds`).
    pub adaptive_pixels: u64,
    pub adaptive_seconds: f64,
    pub peak_memory_bytes: u64,
}

/// What pass two draws.
#[derive(clap::ValueEnum, Clone, Copy, Debug, PartialEq, Eq, serde::Deserialize, serde::Serialize)]
#[serde(rename_all = "kebab-case")]
pub enum Mode {
    /// The two-pass image: radiosity diffuse term plus Whitted specular transport.
    Final,
    /// The pure radiosity output: first hit's interpolated radiosity / π.
    Radiosity,
    /// Both, as NAME.final.EXT and NAME.radiosity.EXT.
    Both,
}

/// How a PNG is encoded from radiance: exposure (stops, or automatic), then the tone curve.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct PngSettings {
    /// Overrides the scene's `[image] exposure` when set.
    pub exposure: Option<Exposure>,
    pub tone: ToneCurve,
}

/// What a job makes.
#[derive(Clone, Debug)]
pub enum Work {
    /// Images, one per planned output (from `output_plan`), from a solved or a loaded solution, and
    /// a layered EXR (`layers::write_layers`) when `layers` names one.
    Render { plan: Vec<(TraceMode, PathBuf)>, png: PngSettings, solution: Option<PathBuf>, layers: Option<PathBuf> },
    /// The solution file; with `Resume::shard` set (`Runner::resumable`), the shard's rows instead
    /// (a part for `solve --merge`).
    Solve { output: PathBuf },
}

impl Work {
    /// What the job's solution is read for (`method = "auto"` weighs it): radiosity-mode images only
    /// when every planned image is one and no layered EXR is asked for; final images otherwise, and for
    /// a solution file, which any later render may read.
    pub fn solution_reader(&self) -> SolutionReader {
        match self {
            Work::Render { plan, layers: None, .. }
                if !plan.is_empty() && plan.iter().all(|(mode, _)| *mode == TraceMode::Radiosity) =>
            {
                SolutionReader::RadiosityImages
            }
            _ => SolutionReader::FinalImages,
        }
    }
}

/// One job: a scene, the settings laid over it, and what to make.
#[derive(Clone, Debug)]
pub struct Job {
    pub scene: PathBuf,
    pub overrides: Overrides,
    pub work: Work,
}

/// What a finished job reports.
#[derive(Debug, Default)]
pub struct Outcome {
    pub written: Vec<PathBuf>,
    pub stats: RunStats,
    /// Whether the form factors / solution came from an earlier job of the batch.
    pub reused_form_factors: bool,
    pub reused_solution: bool,
}

/// A solution a batch keeps, with the mesh of a method that meshes on its own (a uniform mesh is
/// rebuilt from the scene).
type KeptSolution = (Option<Mesh>, Arc<Solution>);

/// Runs jobs one after another, keeping for the later ones what they may reuse.
pub struct Runner {
    reuse: Reuse,
    /// Solutions by `PassOneMethod::solution_key`, with the mesh of a method that meshes on its own,
    /// least recently used out; only kept across jobs.
    solutions: Option<Lru<KeptSolution>>,
}

impl Runner {
    /// A runner for one job, which keeps nothing.
    pub fn single() -> Self {
        Runner { reuse: Reuse::none(), solutions: None }
    }

    /// A runner for one job that keeps a checkpoint, computes a shard or merges parts as `resume`
    /// says, and stops cleanly when its cancellation is requested.
    pub fn resumable(resume: Resume) -> Self {
        Runner { reuse: Reuse::resumable(resume), solutions: None }
    }

    /// A runner for a batch: form factors and solutions are shared between jobs, within the default
    /// cache budget.
    pub fn batch() -> Self {
        Runner::batch_within(crate::cache::DEFAULT_BUDGET_BYTES)
    }

    /// A runner for a batch whose caches hold at most `cache_memory_bytes`: three quarters for form
    /// factors, one quarter for solutions, each least recently used out.
    pub fn batch_within(cache_memory_bytes: u64) -> Self {
        let solutions_bytes = cache_memory_bytes / 4;
        Runner {
            reuse: Reuse::across_jobs_within(cache_memory_bytes - solutions_bytes),
            solutions: Some(Lru::new(solutions_bytes)),
        }
    }

    /// Runs one job; `outcome.stats` holds what was measured, also when the job fails part-way.
    pub fn run(&mut self, job: &Job, progress: &Progress, outcome: &mut Outcome) -> Result<(), Failure> {
        let scene = load_scene(&job.scene, &job.overrides, progress)?;
        let solution_file = match &job.work {
            Work::Render { solution, .. } => solution.as_deref(),
            Work::Solve { .. } => None,
        };
        // One set of photons for both passes of this job (traced only if a pass needs them).
        let photons = RunPhotons::default();
        if let (Work::Solve { output }, Some(shard)) = (&job.work, self.reuse.resume.shard) {
            match shard_method_noted(&scene, progress)? {
                ShardMethod::Matrix(_) if !self.reuse.resume.merge.is_empty() => {
                    return Err(MethodError::from(ShardError::MatrixRounds).into());
                }
                ShardMethod::Matrix(matrix) => {
                    let mesh = build_mesh(&scene, progress)?;
                    let (rows, stats) = matrix.shard_rows(&scene, &mesh, &photons, &self.reuse.resume, progress)?;
                    outcome.stats.pass_one = stats;
                    resume::write_part(output, method::scene_keys(&scene, &mesh), shard, &rows)?;
                }
                ShardMethod::Hierarchy(hierarchy) => {
                    let textures = Arc::new(load_textures(&scene, progress));
                    outcome.stats.pass_one =
                        hierarchy.shard_part(&scene, textures, shard, &self.reuse.resume, output, progress)?;
                }
            }
            outcome.written.push(output.clone());
            self.remove_checkpoint();
            return Ok(());
        }
        let reader = job.work.solution_reader();
        let (mesh, solution) = self.pass_one(&scene, solution_file, reader, &photons, progress, outcome)?;
        // Pass one is done: from here a signal ends the run at once (its checkpoint, if any, is kept);
        // one that came while a solution was loaded ends it here.
        let cancel = &self.reuse.resume.cancel;
        cancel.exit_at_once(true);
        if let Some(signal) = cancel.signal() {
            let checkpoint = self.reuse.resume.checkpoint.clone().filter(|p| p.exists());
            return Err(MethodError::Interrupted { signal, checkpoint }.into());
        }
        match &job.work {
            Work::Solve { output } => {
                solution.save(output)?;
                outcome.written.push(output.clone());
            }
            Work::Render { plan, png, layers, .. } => {
                outcome.written =
                    render_plan(&scene, &mesh, &solution, plan, png, &photons, progress, &mut outcome.stats)?;
                if let Some(path) = layers {
                    layers::write_layers(&scene, &mesh, &solution, path, &photons, progress, &mut outcome.stats)?;
                    outcome.written.push(path.clone());
                }
            }
        }
        self.remove_checkpoint();
        Ok(())
    }

    /// Removes the run's checkpoint once its output is written.
    fn remove_checkpoint(&self) {
        if let Some(path) = &self.reuse.resume.checkpoint {
            Checkpointer::remove(path);
        }
    }

    /// Pass one for a scene: the mesh and its solution, loaded from `solution_file`, reused from an
    /// earlier job, black without emitters, or solved by the scene's method (for `method = "auto"`,
    /// the one for a solution read for `reader`).
    pub fn pass_one(
        &mut self,
        scene: &SceneDescription,
        solution_file: Option<&Path>,
        reader: SolutionReader,
        photons: &RunPhotons,
        progress: &Progress,
        outcome: &mut Outcome,
    ) -> Result<(Mesh, Arc<Solution>), Failure> {
        if let Some(path) = solution_file {
            let (mesh, solution) = load_solution(scene, path, progress)?;
            outcome.stats.pass_one.elements = mesh.elements.len();
            return Ok((mesh, solution));
        }
        let resume = &self.reuse.resume;
        let method: Box<dyn method::PassOneMethod> = if resume.needs_matrix() {
            match shard_method_noted(scene, progress)? {
                ShardMethod::Matrix(matrix) => Box::new(matrix),
                ShardMethod::Hierarchy(hierarchy) => Box::new(hierarchy),
            }
        } else {
            let (method, why) = method::for_scene_with_reason(scene, reader);
            if let (Some(why), Verbosity::Verbose) = (why, progress.verbosity()) {
                progress.note(&format!("pass one: {} (auto: {why})", method.name()));
            }
            method
        };
        if !method.checkpoints() && resume.checkpoint.is_some() {
            // `auto` gives the adaptive mesh (the one method off the uniform mesh without a checkpoint)
            // only scenes that solve in well under a minute (`scene::AUTO_ADAPTIVE_CPU_SECONDS`).
            let small_by_auto = scene.radiosity.method == MethodChoice::Auto && !method.uses_uniform_mesh();
            if !small_by_auto || progress.verbosity() == Verbosity::Verbose {
                progress.note(&format!(
                    "{}the {} method keeps no checkpoint: if this run is interrupted, rerunning it restarts pass \
                     one from the beginning",
                    if small_by_auto { "" } else { "warning: " },
                    method.name()
                ));
            }
            // Nothing to save: a signal ends the run at once (one that came already ends it here).
            resume.cancel.exit_at_once(true);
            if let Some(signal) = resume.cancel.signal() {
                return Err(MethodError::Interrupted { signal, checkpoint: None }.into());
            }
        }
        let mesh = if method.uses_uniform_mesh() {
            build_mesh(scene, progress)?
        } else {
            Mesh { textures: Arc::new(load_textures(scene, progress)), ..Default::default() }
        };
        outcome.stats.pass_one.elements = mesh.elements.len();
        let key = self.solutions.as_ref().map(|_| method.solution_key(scene, &mesh));
        if let (Some(solutions), Some(key)) = (&mut self.solutions, key) {
            if let Some((solved_mesh, solution)) = solutions.get(key) {
                outcome.reused_solution = true;
                outcome.reused_form_factors = true;
                let mesh = solved_mesh.clone().unwrap_or(mesh);
                return Ok((mesh, solution.clone()));
            }
        }
        if !scene.has_emitter() && method.uses_uniform_mesh() {
            let black = Solution::black(&mesh, &scene.materials);
            return Ok((mesh, Arc::new(black)));
        }
        let done = method.solve(scene, mesh, &mut self.reuse, photons, progress)?;
        outcome.stats.pass_one = done.stats;
        outcome.reused_form_factors = done.reused_form_factors;
        let solution = Arc::new(done.solution);
        if let (Some(solutions), Some(key)) = (&mut self.solutions, key) {
            // A method with its own mesh keeps it with the solution (a uniform mesh is rebuilt).
            let own_mesh = (!method.uses_uniform_mesh()).then(|| done.mesh.clone());
            let bytes = solution.memory_bytes() + own_mesh.as_ref().map_or(0, Mesh::memory_bytes);
            solutions.insert(key, (own_mesh, solution.clone()), bytes);
        }
        Ok((done.mesh, solution))
    }
}

/// `method::shard_method`, noting under `-v` why `method = "auto"` chose it (it falls back from the
/// adaptive mesh to the uniform matrix there).
fn shard_method_noted(scene: &SceneDescription, progress: &Progress) -> Result<ShardMethod, MethodError> {
    let (chosen, why) = method::shard_method(scene)?;
    if let (Some(why), Verbosity::Verbose) = (why, progress.verbosity()) {
        let name = match &chosen {
            ShardMethod::Matrix(matrix) => method::PassOneMethod::name(matrix),
            ShardMethod::Hierarchy(hierarchy) => method::PassOneMethod::name(hierarchy),
        };
        progress.note(&format!("pass one: {name} (auto: {why})"));
    }
    Ok(chosen)
}

/// A saved solution and the mesh it lives on: the leaf mesh it carries (hierarchical), the scene's
/// patch mesh refined as it records (adaptive), or the scene's uniform mesh; refused when its
/// fingerprint is not the scene's.
fn load_solution(scene: &SceneDescription, path: &Path, progress: &Progress) -> Result<(Mesh, Arc<Solution>), Failure> {
    let kind = solution_file::solution_mesh(path)?;
    if kind == SolutionMesh::Refined {
        let textures = Arc::new(load_textures(scene, progress));
        let mut mesh = None;
        let solution = Solution::load_with(path, |loaded| {
            let refinement = loaded.refinement.as_deref().cloned().unwrap_or_default();
            let refined = refinement::mesh_of(scene, &refinement, textures)
                .map_err(|source| SolutionFileError::StaleRefinement { path: path.to_path_buf(), source })?;
            let expected = fingerprint::fingerprint(&refined, &scene.materials);
            mesh = Some(refined);
            Ok(expected)
        })?;
        let mesh =
            mesh.ok_or_else(|| Failure::internal(anyhow::anyhow!("{}: refined mesh missing", path.display())))?;
        check_solution_fits(path, &mesh, &solution)?;
        return Ok((mesh, Arc::new(solution)));
    }
    if kind == SolutionMesh::Leaves {
        let textures = Arc::new(load_textures(scene, progress));
        let expected = hierarchical::scene_fingerprint(scene, &hierarchical::hierarchy_params(scene), &textures);
        let solution = Solution::load(path, expected)?;
        let mesh = hierarchical::mesh_of(scene, &solution, textures)
            .ok_or_else(|| Failure::internal(anyhow::anyhow!("{}: leaf mesh missing", path.display())))?;
        check_solution_fits(path, &mesh, &solution)?;
        return Ok((mesh, Arc::new(solution)));
    }
    let mesh = build_mesh(scene, progress)?;
    let solution = Solution::load(path, fingerprint::fingerprint(&mesh, &scene.materials))?;
    Ok((mesh, Arc::new(solution)))
}

/// Refuses a loaded solution whose value counts are not its own mesh's (element and vertex counts).
fn check_solution_fits(path: &Path, mesh: &Mesh, solution: &Solution) -> Result<(), Failure> {
    if mesh.positions.len() != solution.vertex_exitance.len() || mesh.elements.len() != solution.element_exitance.len()
    {
        return Err(Failure::input(anyhow::anyhow!(
            "{}: the mesh it carries does not match its values; re-run `radray solve`",
            path.display()
        )));
    }
    Ok(())
}

/// Pass one of a single run (see `Runner::pass_one`) whose solution is read for final images (both
/// modes may be drawn from it), adding what it measured to `stats`; hand the same `photons` to `render`.
pub fn pass_one(
    scene: &SceneDescription,
    solution_file: Option<&Path>,
    photons: &RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<(Mesh, Arc<Solution>), Failure> {
    let mut outcome = Outcome { stats: std::mem::take(stats), ..Default::default() };
    let reader = SolutionReader::FinalImages;
    let result = Runner::single().pass_one(scene, solution_file, reader, photons, progress, &mut outcome);
    *stats = outcome.stats;
    result
}

/// Loads a scene, prints its warnings, and lays the overrides over it.
pub fn load_scene(path: &Path, overrides: &Overrides, progress: &Progress) -> Result<SceneDescription, Failure> {
    let mut scene = scene::load(path)?;
    for w in &scene.warnings {
        progress.note(&format!("warning: {w}"));
    }
    overrides.apply(&mut scene)?;
    Ok(scene)
}

/// Meshes the scene after checking that the element count is sane. The scene's texture maps are
/// loaded here, once per run (a map that cannot be read is a warning naming the file, and its
/// material keeps Kd); the mesh carries them to pass two.
pub fn build_mesh(scene: &SceneDescription, progress: &Progress) -> Result<Mesh, MeshError> {
    let edge = scene.radiosity.max_element_edge;
    let count = mesh::count_elements(scene, edge);
    if count > MAX_ELEMENTS {
        return Err(MeshError::TooManyElements {
            scene: scene.path.display().to_string(),
            edge,
            elements: count,
            limit: MAX_ELEMENTS,
        });
    }
    let stage = progress.stage("meshing", scene.surfaces.len() as u64, "surfaces");
    let textures = load_textures(scene, progress);
    let mut mesh = Mesh::build_with_textures(scene, edge, Arc::new(textures));
    // Elements buried under the backs of one-sided surfaces stay out of the vertex averages.
    (mesh.element_buried, mesh.element_eye) = crate::burial::bury(&mesh);
    stage.finish(&format!(
        "{} surfaces → {} elements, {} triangles",
        scene.surfaces.len(),
        mesh.elements.len(),
        mesh.triangles.len()
    ));
    Ok(mesh)
}

/// The scene's texture maps, loaded once per run; a map that cannot be read is a warning.
fn load_textures(scene: &SceneDescription, progress: &Progress) -> SceneTextures {
    let (textures, warnings) = SceneTextures::load(&scene.materials);
    for w in &warnings {
        progress.note(&format!("warning: {w}"));
    }
    textures
}

/// Parses a `--shard K/N` argument (0 ≤ K < N) of any front end.
pub fn parse_shard(text: &str) -> Result<(usize, usize), String> {
    let (k, n) = text.split_once('/').ok_or_else(|| format!("--shard must be K/N, got `{text}`"))?;
    let k: usize = k.trim().parse().map_err(|_| format!("--shard: `{k}` is not a job index"))?;
    let n: usize = n.trim().parse().map_err(|_| format!("--shard: `{n}` is not a shard count"))?;
    if n == 0 || k >= n {
        return Err(format!("--shard K/N needs 0 ≤ K < N, got {k}/{n}"));
    }
    Ok((k, n))
}

/// Checks that `output`'s directory exists, before any work.
pub fn check_output_directory(output: &Path) -> Result<(), Failure> {
    let dir = output.parent().filter(|d| !d.as_os_str().is_empty()).unwrap_or(Path::new("."));
    if !dir.is_dir() {
        return Err(Failure::input(anyhow::anyhow!(
            "{}: directory {} does not exist",
            output.display(),
            dir.display()
        )));
    }
    Ok(())
}

/// The files a render writes: `-o` as given, or NAME.final.EXT and NAME.radiosity.EXT for `both`.
pub fn output_plan(outputs: &[PathBuf], mode: Mode) -> Result<Vec<(TraceMode, PathBuf)>, Failure> {
    let mut plan = Vec::new();
    for out in outputs {
        let ext = out.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).unwrap_or_default();
        if ext != "png" && ext != "exr" {
            return Err(Failure::input(anyhow::anyhow!("{}: output must end in .png or .exr", out.display())));
        }
        check_output_directory(out)?;
        let tagged = |tag: &str| {
            let stem = out.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
            out.with_file_name(format!("{stem}.{tag}.{ext}"))
        };
        match mode {
            Mode::Final => plan.push((TraceMode::Final, out.clone())),
            Mode::Radiosity => plan.push((TraceMode::Radiosity, out.clone())),
            Mode::Both => {
                plan.push((TraceMode::Final, tagged("final")));
                plan.push((TraceMode::Radiosity, tagged("radiosity")));
            }
        }
    }
    Ok(plan)
}

/// Writes an image as PNG or EXR by its extension; a PNG takes `png`'s exposure, or 0 stops.
pub fn write_image(image: &Image, path: &Path, png: &PngSettings) -> Result<(), Failure> {
    write_image_exposed(image, path, png, Exposure::default(), &Progress::hidden())
}

/// Writes an image as PNG or EXR by its extension. A PNG takes `png`'s exposure, else the scene's
/// `fallback`; with `-v` the stops chosen are reported (automatic exposure is measured on `image`).
/// EXR stays linear radiance.
pub fn write_image_exposed(
    image: &Image,
    path: &Path,
    png: &PngSettings,
    fallback: Exposure,
    progress: &Progress,
) -> Result<(), Failure> {
    let is_exr = path.extension().is_some_and(|e| e.eq_ignore_ascii_case("exr"));
    if is_exr {
        output::write_exr(image, path)?;
    } else {
        let exposure = png.exposure.unwrap_or(fallback);
        let stops = exposure.stops_for(image);
        if progress.verbosity() == Verbosity::Verbose {
            let how = if exposure == Exposure::Auto { "auto, log-average key 0.18" } else { "fixed" };
            progress.note(&format!("{}: exposure {stops:+.3} stops ({how})", path.display()));
        }
        output::write_png(image, path, stops, png.tone)?;
    }
    Ok(())
}

/// Renders every planned output of one scene (each mode once) and writes them.
#[allow(clippy::too_many_arguments)]
pub fn render_plan(
    scene: &SceneDescription,
    mesh: &Mesh,
    solution: &Solution,
    plan: &[(TraceMode, PathBuf)],
    png: &PngSettings,
    photons: &RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<Vec<PathBuf>, Failure> {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    if let Some(warning) = crate::trace::back_faces::probe_scene(scene, mesh, &accel).warning() {
        progress.note(&format!("warning: {warning}"));
    }
    let mut written = Vec::new();
    let mut rendered: Vec<(TraceMode, Image)> = Vec::new();
    for (mode, path) in plan {
        if !rendered.iter().any(|(m, _)| m == mode) {
            let image = render(scene, mesh, &accel, solution, *mode, photons, progress, stats)?;
            rendered.push((*mode, image));
        }
        let image = &rendered
            .iter()
            .find(|(m, _)| m == mode)
            .map(|(_, i)| i)
            .ok_or_else(|| Failure::internal(anyhow::anyhow!("image missing")))?;
        write_image_exposed(image, path, png, scene.image.exposure, progress)?;
        written.push(path.clone());
    }
    Ok(written)
}

/// Pass two: traces the camera's rays through the scene and develops the film; the final mode shows
/// the run's `photons` as caustics.
#[allow(clippy::too_many_arguments)]
pub fn render(
    scene: &SceneDescription,
    mesh: &Mesh,
    accel: &Accel,
    solution: &Solution,
    mode: TraceMode,
    photons: &RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<Image, TraceError> {
    let image = &scene.image;
    let camera = PinholeCamera::new(&scene.camera, image.width_px, image.height_px);
    let tracer = tracer_for(scene, mesh, accel, solution, mode, photons, progress, stats)?;
    let name = if mode == TraceMode::Final { "render final" } else { "render radiosity" };
    let stages = film_stages::FilmStages::start(progress, name, image);
    let start = Instant::now();
    let (picture, film_stats, counts) = film::render_with(
        image,
        RayCounts::default,
        |counts: &mut RayCounts, x, y, sampler| {
            let ray = camera.ray(x, y);
            tracer.radiance(ray.origin, ray.dir, mode, sampler, counts)
        },
        &stages,
    );
    let seconds = start.elapsed().as_secs_f64();
    let total: RayCounts = counts.into_iter().sum();
    stats.render_seconds += seconds;
    stats.primary_rays += total.primary;
    stats.secondary_rays += total.secondary;
    stats.shadow_rays += total.shadow;
    stats.samples += film_stats.samples;
    stats.adaptive_extra_samples += film_stats.adaptive_extra_samples;
    stats.adaptive_pixels += film_stats.adaptive_pixels;
    let rays = total.primary + total.secondary + total.shadow;
    stats.rays_per_second =
        (stats.primary_rays + stats.secondary_rays + stats.shadow_rays) as f64 / stats.render_seconds.max(1e-9);
    stats.adaptive_seconds += stages.finish(&format!(
        "{}×{} at {} spp, {} adaptive samples in {} pixels: {} rays ({:.2} M rays/s) in {seconds:.1} s",
        image.width_px,
        image.height_px,
        image.samples_per_pixel,
        film_stats.adaptive_extra_samples,
        film_stats.adaptive_pixels,
        rays,
        rays as f64 / seconds.max(1e-9) / 1e6
    ));
    Ok(picture)
}

/// Pass two's tracer for a scene, its mesh and solution: smooth-shading normals, the texture
/// footprint of one pixel, and the run's `photons` as caustics in the final mode.
#[allow(clippy::too_many_arguments)]
pub fn tracer_for<'a>(
    scene: &'a SceneDescription,
    mesh: &'a Mesh,
    accel: &'a Accel,
    solution: &'a Solution,
    mode: TraceMode,
    photons: &RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> Result<Tracer<'a>, TraceError> {
    let image = &scene.image;
    let pixel_angle_rad = scene.camera.vfov_deg.to_radians() / image.height_px.max(1) as f32;
    let tracer = Tracer::new(mesh, accel, solution, &scene.materials, &scene.render)?
        .with_shading_normals(&scene.surfaces)
        .with_pixel_angle(pixel_angle_rad);
    let caustics = match mode {
        TraceMode::Final => photons.get(mesh, accel, &scene.materials, &scene.surfaces),
        TraceMode::Radiosity => None,
    };
    let tracer = match caustics {
        Some(photons) => tracer.with_caustics(photons),
        None => tracer,
    };
    if mode != TraceMode::Final || scene.render.final_gather != FinalGatherMode::On {
        return Ok(tracer);
    }
    let camera = PinholeCamera::new(&scene.camera, image.width_px, image.height_px);
    let stage = progress.stage("final gather prepass", gather::LEVELS as u64, "levels");
    let on_level_done = |records: usize| {
        stage.inc(1);
        stage.set_message(format!("{records} records"));
    };
    let render = RenderParams {
        gather_rays: scene.render.gather_rays_for(solution.leaf_geometry.is_some()),
        ..scene.render.clone()
    };
    let (gather, prepass) = gather::for_image(&tracer, &camera, &render, image, pixel_angle_rad, &on_level_done);
    stats.secondary_rays += prepass.rays.total();
    stage.finish(&format!(
        "{} records ({} refined) from {} gathers",
        prepass.records, prepass.refined, prepass.candidates
    ));
    Ok(tracer.with_final_gather(gather))
}

/// Peak resident memory of this process so far (Linux `VmHWM`), 0 if unknown.
pub fn peak_memory_bytes() -> u64 {
    std::fs::read_to_string("/proc/self/status")
        .ok()
        .and_then(|t| {
            t.lines().find(|l| l.starts_with("VmHWM:")).and_then(|l| l.split_whitespace().nth(1)?.parse::<u64>().ok())
        })
        .map_or(0, |kib| kib * 1024)
}

/// Writes what a run measured as JSON (with the peak memory so far), if asked for.
pub fn write_stats(path: Option<&Path>, stats: &mut RunStats) -> Result<(), Failure> {
    let Some(path) = path else { return Ok(()) };
    stats.peak_memory_bytes = peak_memory_bytes();
    let text = serde_json::to_string_pretty(stats)?;
    output::write_atomically(path, text.as_bytes())
        .with_context(|| format!("{}: cannot write stats", path.display()))
        .map_err(Failure::input)
}
