//! The pass-one interface: every way of solving B = E + ρ·F·B is a `PassOneMethod`, which takes the
//! scene and its mesh and returns the mesh (a hierarchical method may refine it), the `Solution` and
//! what it measured. Each method owns its memory check and the keys under which a batch may reuse
//! its work; `for_params` picks the scene's method.

use std::sync::Arc;
use std::time::Instant;

use super::fingerprint;
use super::fingerprint::form_factor_key;
use super::hierarchical::Hierarchical;
use super::hierarchy::{HierarchyError, LinkStructure};
use super::matrix::{form_factors, FormFactors, PartialRows, RowPlan};
use super::matrix_free;
use super::resume::{self, Checkpointer, Resume, SceneKeys, ShardError};
use super::smooth_mesh::SmoothMesh;
use super::solution::Solution;
use super::solver;
use super::specular::{self, SpecularPaths};
use super::stats::{PassOneStats, ResumeStats};
use crate::accel::Accel;
use crate::cache::Lru;
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::scene::{
    MethodChoice, RadiosityParams, SceneDescription, SolutionReader, SolverKind, AUTO_ADAPTIVE_CPU_SECONDS,
    AUTO_MATRIX_CPU_SECONDS, AUTO_MATRIX_CPU_SECONDS_SPECULAR,
};
use crate::transport::photons::RunPhotons;

/// Why a method refuses a scene (before anything large is allocated).
#[derive(Debug, thiserror::Error)]
pub enum MethodError {
    #[error("{scene}: the form factors of {elements} elements at hemicube resolution {resolution} would need about {needed_gib:.1} GiB, but about {available_gib:.1} GiB is available; use a larger max_element_edge (memory grows with the square of the element count), a lower hemicube_resolution, or solver = \"progressive\" with store_form_factors = false (no stored matrix: O(n) memory, one hemicube per shot; pair it with a looser tolerance such as 1e-2)")]
    OutOfMemory { scene: String, elements: usize, resolution: u32, needed_gib: f64, available_gib: f64 },
    #[error("{scene}: the hierarchy needs at least {needed_gib:.2} GiB for its {triangles} input triangles before any refinement, over three quarters of the memory budget of {budget_gib:.2} GiB; raise [radiosity] memory or simplify the scene")]
    HierarchyOverBudget { scene: String, triangles: usize, needed_gib: f64, budget_gib: f64 },
    #[error("{scene}: {source}")]
    Hierarchy { scene: String, source: HierarchyError },
    #[error("interrupted by {}{}", crate::interrupt::signal_name(*signal), match checkpoint {
        Some(path) => format!("; the finished pass-one work (form-factor rows or link estimates) is saved in {}: run the same command again to resume", path.display()),
        None => String::new(),
    })]
    Interrupted { signal: usize, checkpoint: Option<std::path::PathBuf> },
    #[error(transparent)]
    Shard(#[from] ShardError),
}

/// What pass one made: the mesh the solution belongs to, the solution, and what was measured.
#[derive(Debug)]
pub struct PassOne {
    pub mesh: Mesh,
    pub solution: Solution,
    pub stats: PassOneStats,
    /// Whether the form factors came from an earlier job (`Reuse`).
    pub reused_form_factors: bool,
}

/// Work that later jobs of a batch may reuse, keyed by what it depends on
/// (`fingerprint::form_factor_key`, `hierarchical::link_key`), and work that earlier or parallel runs
/// left (`Resume`: a checkpoint, merged shard parts). `Reuse::none()` keeps nothing, for a single run.
#[derive(Debug, Default)]
pub struct Reuse {
    keep: bool,
    /// Form factors of earlier scenes, least recently used out beyond the budget: matrices are large.
    form_factors: Lru<Arc<FormFactors>>,
    /// Refined hierarchies (nodes, links, form factors) of earlier scenes, under the same budget.
    hierarchy_links: Lru<Arc<LinkStructure>>,
    /// The checkpoint, shard and merged parts of a single run, and its cancellation.
    pub resume: Resume,
}

impl Reuse {
    /// Keeps nothing: a single run frees its matrix as soon as it is solved.
    pub fn none() -> Self {
        Reuse { keep: false, form_factors: Lru::default(), hierarchy_links: Lru::default(), resume: Resume::default() }
    }

    /// Keeps nothing across jobs, but resumes from and keeps a checkpoint, computes a shard or solves
    /// merged parts as `resume` says.
    pub fn resumable(resume: Resume) -> Self {
        Reuse { resume, ..Reuse::none() }
    }

    /// True when this keeps work for later jobs (a batch).
    pub fn keeps(&self) -> bool {
        self.keep
    }

    /// The refined hierarchy an earlier job left under `key`, if still kept.
    pub fn hierarchy_links(&mut self, key: u64) -> Option<Arc<LinkStructure>> {
        self.hierarchy_links.get(key).cloned()
    }

    /// Keeps a refined hierarchy for later jobs (nothing when this keeps nothing), charging its
    /// bytes to the budget both caches share (kept matrices are evicted first). Returns whether it
    /// was kept.
    pub fn keep_hierarchy_links(&mut self, key: u64, links: Arc<LinkStructure>) -> bool {
        let bytes = links.memory_bytes();
        if !self.keep {
            return false;
        }
        self.form_factors.make_room(self.hierarchy_links.used_bytes() + bytes);
        self.hierarchy_links.insert(key, links, bytes)
    }

    /// The form factors an earlier job left under `key` (`fingerprint::form_factor_key`), if still kept.
    pub fn form_factors(&mut self, key: u64) -> Option<Arc<FormFactors>> {
        self.form_factors.get(key).cloned()
    }

    /// Keeps form factors for later jobs (nothing when this keeps nothing), charging their bytes to
    /// the budget both caches share (kept hierarchies are evicted first). Returns whether they were
    /// kept.
    pub fn keep_form_factors(&mut self, key: u64, ff: Arc<FormFactors>) -> bool {
        if !self.keep {
            return false;
        }
        let bytes = ff.memory_bytes() as u64;
        self.hierarchy_links.make_room(self.form_factors.used_bytes() + bytes);
        self.form_factors.insert(key, ff, bytes)
    }

    /// Keeps scenes' form factors for the jobs after them, within the default budget.
    pub fn across_jobs() -> Self {
        Reuse::across_jobs_within(crate::cache::DEFAULT_BUDGET_BYTES)
    }

    /// Keeps scenes' form factors for the jobs after them, at most `budget_bytes` of them.
    pub fn across_jobs_within(budget_bytes: u64) -> Self {
        Reuse {
            keep: true,
            form_factors: Lru::new(budget_bytes),
            hierarchy_links: Lru::new(budget_bytes),
            resume: Resume::default(),
        }
    }
}

/// One way of running pass one.
pub trait PassOneMethod {
    /// The name reported in statistics.
    fn name(&self) -> String;

    /// Whether `solve` works on the scene's uniform mesh (`run::build_mesh`). A method that meshes
    /// adaptively (`Hierarchical`) returns `false`: it is handed an empty mesh that carries only the
    /// scene's textures, and returns the mesh it solved on.
    fn uses_uniform_mesh(&self) -> bool {
        true
    }

    /// Whether `solve` keeps a checkpoint and stops cleanly on `Reuse::resume`'s cancellation. A
    /// method that does not restarts from the beginning when its run is interrupted.
    fn checkpoints(&self) -> bool {
        false
    }

    /// Refuses a scene whose working memory could not fit, before it is allocated.
    fn check_memory(&self, scene: &SceneDescription, mesh: &Mesh) -> Result<(), MethodError>;

    /// Everything the solution depends on: equal keys give equal solutions, so a batch may share one.
    fn solution_key(&self, scene: &SceneDescription, mesh: &Mesh) -> u64 {
        fingerprint::solution_key(mesh, &scene.materials, &scene.radiosity)
    }

    /// Solves the scene's radiosity on `mesh` (of `scene`, with emitters), reusing and leaving in
    /// `reuse` what later jobs may share; light paths through mirrors and glass read the run's
    /// `photons`, which pass two shares.
    fn solve(
        &self,
        scene: &SceneDescription,
        mesh: Mesh,
        reuse: &mut Reuse,
        photons: &RunPhotons,
        progress: &Progress,
    ) -> Result<PassOne, MethodError>;
}

/// The uniform mesh's method: matrix-free shooting when `store_form_factors = false`, else the stored
/// matrix with the scene's solver.
pub fn for_params(params: &RadiosityParams) -> Box<dyn PassOneMethod> {
    if params.store_form_factors {
        Box::new(FullMatrix { solver: params.solver })
    } else {
        Box::new(MatrixFree)
    }
}

/// The scene's method (`[radiosity] method`): `matrix` is `for_params`; `hierarchical` is
/// `Hierarchical`; `adaptive` is `Adaptive`; `auto` is what `auto_method` picks (for final images).
pub fn for_scene(scene: &SceneDescription) -> Box<dyn PassOneMethod> {
    for_scene_with_reason(scene, SolutionReader::FinalImages).0
}

/// The scene's method for a solution read for `reader` (`auto_method_for`), with `auto`'s reason
/// when the scene says `method = "auto"`.
pub fn for_scene_with_reason(
    scene: &SceneDescription,
    reader: SolutionReader,
) -> (Box<dyn PassOneMethod>, Option<String>) {
    let (choice, why) = match scene.radiosity.method {
        MethodChoice::Auto => {
            let (choice, why) = auto_method_for(scene, reader);
            (choice, Some(why))
        }
        chosen => (chosen, None),
    };
    let method: Box<dyn PassOneMethod> = match choice {
        MethodChoice::Hierarchical => Box::new(Hierarchical),
        MethodChoice::Adaptive => Box::new(super::adaptive::Adaptive { solver: scene.radiosity.solver }),
        MethodChoice::Matrix | MethodChoice::Auto => for_params(&scene.radiosity),
    };
    (method, why)
}

/// What `method = "auto"` picks for `scene` when its solution is read for final images or saved
/// (`auto_method_for` with `SolutionReader::FinalImages`), and why.
pub fn auto_method(scene: &SceneDescription) -> (MethodChoice, String) {
    auto_method_for(scene, SolutionReader::FinalImages)
}

/// What `method = "auto"` picks for `scene` whose solution is read for `reader`, and why: the
/// hierarchy when `auto_prefers_hierarchy` says the uniform mesh is out of reach, else the adaptive
/// mesh when `adaptive_choice` says so (by default only for radiosity-mode images:
/// `AdaptiveSettings::auto_for`), else the uniform mesh's matrix (`MethodChoice::Matrix`:
/// `for_params`).
pub fn auto_method_for(scene: &SceneDescription, reader: SolutionReader) -> (MethodChoice, String) {
    let [final_images, radiosity_images] = auto_methods(scene);
    match reader {
        SolutionReader::FinalImages => final_images,
        SolutionReader::RadiosityImages => radiosity_images,
    }
}

/// `auto_method_for` for final images and for radiosity images, in that order, from one look at the
/// uniform mesh (it meshes the scene and draws a sample of hemicubes; `radray info` shows both).
pub fn auto_methods(scene: &SceneDescription) -> [(MethodChoice, String); 2] {
    let outlook = uniform_outlook(scene);
    [SolutionReader::FinalImages, SolutionReader::RadiosityImages].map(|reader| match &outlook {
        Err(reason) => (MethodChoice::Hierarchical, reason.clone()),
        Ok(outlook) => match adaptive_choice(&scene.radiosity, outlook.as_ref(), reader) {
            Ok(reason) => (MethodChoice::Adaptive, reason),
            Err(why_not) => (MethodChoice::Matrix, format!("the uniform mesh fits; {why_not}")),
        },
    })
}

/// What `method = "auto"` picks under `--shard` or `--merge` (which make solution files, read for final
/// images: `auto_method`), and why: `auto_method`'s choice, except
/// that the adaptive mesh falls back to the uniform matrix (its levels each need the whole solve of
/// the level before, so they cannot be sharded), with the reason saying so.
pub fn auto_method_for_shards(scene: &SceneDescription) -> (MethodChoice, String) {
    match auto_method(scene) {
        (MethodChoice::Adaptive, reason) => (
            MethodChoice::Matrix,
            format!(
                "{reason}, but --shard/--merge take the uniform matrix: the adaptive mesh's levels each need the \
                 whole solve of the level before"
            ),
        ),
        other => other,
    }
}

/// The uniform mesh as `auto` sees it once it fits: its matrix's predicted hemicube CPU time and
/// whether it has mirrors or glass (`None` with `store_form_factors = false`: nothing is predicted).
struct UniformOutlook {
    cpu_seconds: f64,
    specular: bool,
}

/// `Err(why)` when `auto` leaves the uniform mesh for the hierarchy (`auto_prefers_hierarchy`), else
/// what it predicted for the uniform matrix.
fn uniform_outlook(scene: &SceneDescription) -> Result<Option<UniformOutlook>, String> {
    let params = &scene.radiosity;
    let elements = crate::mesh::count_elements(scene, params.max_element_edge);
    if elements > crate::run::MAX_ELEMENTS {
        return Err(format!("{elements} uniform elements, over the limit of {}", crate::run::MAX_ELEMENTS));
    }
    if params.store_form_factors {
        let bytes = form_factors::matrix_bytes_from_counts(elements as usize, elements as usize, params);
        let budget = params.hierarchy.memory_bytes.min(available_memory_bytes().unwrap_or(u64::MAX));
        if bytes > budget {
            return Err(format!(
                "the full matrix of {elements} elements would take about {:.1} GB, over the budget of {:.1} GB",
                bytes as f64 / 1e9,
                budget as f64 / 1e9
            ));
        }
    }
    if !params.store_form_factors {
        return Ok(None);
    }
    let mesh = Mesh::build(scene, params.max_element_edge);
    let estimate = matrix_estimate(scene, &mesh);
    let specular = specular::mesh_has_specular(&mesh, &scene.materials);
    let (limit, kind) = if specular {
        (AUTO_MATRIX_CPU_SECONDS_SPECULAR, " for a scene with mirrors or glass")
    } else {
        (AUTO_MATRIX_CPU_SECONDS, "")
    };
    if estimate.cpu_seconds > limit {
        return Err(format!(
            "the full matrix of {elements} elements would take about {:.0} CPU-s of hemicubes, over the limit of {limit} CPU-s{kind}",
            estimate.cpu_seconds
        ));
    }
    Ok(Some(UniformOutlook { cpu_seconds: estimate.cpu_seconds, specular }))
}

/// `Ok(why)` when `auto` takes the adaptive mesh for a scene whose uniform matrix fits (`outlook`)
/// and whose solution is read for `reader`, else `Err(why not)`: only when `auto_adaptive` is on for
/// that reader (`AdaptiveSettings::auto_for`: the scene's key, else on for radiosity-mode images and
/// off for final images and solution files), the matrix is stored (`store_form_factors`), the uniform
/// mesh has no mirrors or glass (the adaptive levels before the last are solved without extended form
/// factors, so their splits miss light through them), and its hemicubes are predicted at most `AUTO_ADAPTIVE_CPU_SECONDS` (the adaptive method keeps no checkpoint, so it takes only scenes
/// that solve in well under a minute).
fn adaptive_choice(
    params: &RadiosityParams,
    outlook: Option<&UniformOutlook>,
    reader: SolutionReader,
) -> Result<String, String> {
    let why_on = match (params.adaptive.auto, reader) {
        (Some(_), _) => "auto_adaptive is on",
        (None, SolutionReader::FinalImages) => "the solution is read for final images or saved",
        (None, SolutionReader::RadiosityImages) => "only radiosity-mode images read the solution",
    };
    let on = params.adaptive.auto_for(reader);
    if !on {
        return Err(match params.adaptive.auto {
            Some(_) => "auto_adaptive is off".to_string(),
            None => "final images and solution files keep the uniform matrix (as good a final image for less \
                     time; auto_adaptive = true opts in)"
                .to_string(),
        });
    }
    let Some(outlook) = outlook else {
        return Err("store_form_factors = false asks for matrix-free shooting".to_string());
    };
    if outlook.specular {
        return Err("mirrors or glass keep the uniform matrix (extended form factors on every level)".to_string());
    }
    if outlook.cpu_seconds > AUTO_ADAPTIVE_CPU_SECONDS {
        return Err(format!(
            "about {:.0} CPU-s of hemicubes, over the adaptive mesh's limit of {AUTO_ADAPTIVE_CPU_SECONDS} CPU-s \
             (it keeps no checkpoint; the matrix does)",
            outlook.cpu_seconds
        ));
    }
    Ok(format!(
        "the uniform mesh fits (about {:.0} CPU-s of hemicubes, at most {AUTO_ADAPTIVE_CPU_SECONDS}), no mirrors or \
         glass, and {why_on}",
        outlook.cpu_seconds
    ))
}

/// Why `method = "auto"` takes the adaptive mesh for a scene the uniform matrix can take, whose
/// solution is read for `reader` (`adaptive_choice`), or `None` when it keeps the uniform mesh or
/// leaves it for the hierarchy.
pub fn auto_prefers_adaptive(scene: &SceneDescription, reader: SolutionReader) -> Option<String> {
    match auto_method_for(scene, reader) {
        (MethodChoice::Adaptive, reason) => Some(reason),
        _ => None,
    }
}

/// Why `method = "auto"` leaves the uniform mesh for the hierarchy, or `None` to keep it. With
/// `store_form_factors = false` (matrix-free, O(n) memory) only above `run::MAX_ELEMENTS` elements.
/// With the stored matrix also when its size from the element count alone
/// (`form_factors::matrix_bytes_from_counts`, every element a row) exceeds the `memory` budget or the
/// memory available, or when its hemicubes, predicted from a sample of them drawn on the uniform mesh
/// (`matrix_estimate`), would take more than `AUTO_MATRIX_CPU_SECONDS` of CPU time
/// (`AUTO_MATRIX_CPU_SECONDS_SPECULAR` when the mesh has mirrors or glass: the hierarchy carries the
/// light through them less completely, by photons).
pub fn auto_prefers_hierarchy(scene: &SceneDescription) -> Option<String> {
    uniform_outlook(scene).err()
}

/// The full matrix of `mesh` predicted from a sample of its hemicubes (`form_factors::estimate`),
/// followed through the scene's mirrors and glass as `FullMatrix` does, but without the photons' light
/// paths (no photons are traced for an estimate; with them, hemicube paths stop at emitters).
pub fn matrix_estimate(scene: &SceneDescription, mesh: &Mesh) -> form_factors::FormFactorEstimate {
    let accel = specular_accel(scene, mesh);
    let paths = accel
        .as_ref()
        .map(|accel| SpecularPaths::new(mesh, accel, &scene.materials).with_shading_normals(&scene.surfaces));
    form_factors::estimate(mesh, &scene.radiosity, paths.as_ref())
}

/// Bytes the form-factor matrix may take at most: each stored row holds at most one entry per other
/// element and at most one per hemicube pixel (3N² pixels), 8 bytes per entry.
pub fn form_factor_bytes_bound(mesh: &Mesh, params: &RadiosityParams) -> u64 {
    let n = mesh.elements.len() as u64;
    let pixels = 3 * (params.hemicube_resolution_px as u64).pow(2);
    let rows = (0..mesh.elements.len())
        .filter(|&i| mesh.elements.reflectance[i].max_element() > 0.0 || mesh.elements.emission[i].max_element() > 0.0)
        .count() as u64;
    rows * n.min(pixels) * 8
}

/// Refuses a matrix of `mesh` whose bound (`form_factor_bytes_bound`, pessimistic by about 2×, hence
/// halved) exceeds the memory available.
pub fn check_matrix_fits(scene: &SceneDescription, mesh: &Mesh, bound: u64) -> Result<(), MethodError> {
    if let Some(available) = available_memory_bytes() {
        if bound / 2 > available {
            const GIB: f64 = (1u64 << 30) as f64;
            return Err(MethodError::OutOfMemory {
                scene: scene.path.display().to_string(),
                elements: mesh.elements.len(),
                resolution: scene.radiosity.hemicube_resolution_px,
                needed_gib: bound as f64 / 2.0 / GIB,
                available_gib: available as f64 / GIB,
            });
        }
    }
    Ok(())
}

/// Memory the system says is available (Linux `MemAvailable`), if known.
pub fn available_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
}

/// The ray accelerator pass one needs to follow light through mirrors and glass: built only when
/// some element of the mesh is specular (`None` otherwise, and the form factors are plain).
pub fn specular_accel(scene: &SceneDescription, mesh: &Mesh) -> Option<Accel> {
    specular::mesh_has_specular(mesh, &scene.materials).then(|| Accel::build(&mesh.positions, &mesh.triangles))
}

/// How every method follows light through the scene's mirrors and glass: with the surfaces' shading
/// normals, and with the run's photons (traced from the emitters) for the light paths.
pub fn specular_paths<'a>(
    scene: &'a SceneDescription,
    mesh: &'a Mesh,
    accel: &'a Accel,
    photons: &RunPhotons,
) -> SpecularPaths<'a> {
    let paths = SpecularPaths::new(mesh, accel, &scene.materials).with_shading_normals(&scene.surfaces);
    match photons.get(mesh, accel, &scene.materials, &scene.surfaces) {
        Some(photons) => paths.with_light_paths(photons),
        None => paths,
    }
}

/// Today's full matrix: hemicube form factors of every element stored as sparse rows (extended
/// through mirrors and glass), then solved by Gauss-Seidel/SOR, Jacobi or shooting
/// (`solver::solve_f64`). The form factors depend on geometry only, so a batch job that changes only
/// materials re-solves from the previous job's matrix.
#[derive(Clone, Copy, Debug)]
pub struct FullMatrix {
    pub solver: SolverKind,
}

impl FullMatrix {
    /// Hemicube form factors of every element (rows only where an element reflects or emits),
    /// extended through the scene's specular surfaces when it has any: the rows `resume` asks for
    /// (one shard's, or all), starting from its merged parts or checkpoint and keeping the checkpoint
    /// up to date. Stops early, saving the checkpoint, when the run is cancelled.
    fn compute_form_factors(
        &self,
        scene: &SceneDescription,
        mesh: &Mesh,
        photons: &RunPhotons,
        resume: &Resume,
        progress: &Progress,
        stats: &mut PassOneStats,
    ) -> Result<PartialRows, MethodError> {
        let params = &scene.radiosity;
        let shard = resume.shard();
        let keys = scene_keys(scene, mesh);
        let load_start = Instant::now();
        let known = if !resume.merge.is_empty() {
            Some(resume::merge_parts(&resume.merge, keys)?)
        } else {
            resume.checkpoint.as_ref().and_then(|path| resume::load_checkpoint(path, keys, shard, progress))
        };
        let known = known.as_ref();
        let load_seconds = load_start.elapsed().as_secs_f64();
        let mut checkpointer = resume
            .checkpoint
            .as_ref()
            .map(|path| Checkpointer::new(path.clone(), keys, shard, mesh.elements.len(), resume.interval));
        let accel = specular_accel(scene, mesh);
        let stage = progress.stage("form factors", mesh.elements.len() as u64, "elements");
        let start = Instant::now();
        let cancel = &resume.cancel;
        let paths = accel.as_ref().map(|accel| specular_paths(scene, mesh, accel, photons));
        let mut after_batch = |rows: &PartialRows| {
            if let Some(checkpointer) = checkpointer.as_mut() {
                checkpointer.maybe_write(rows);
            }
        };
        let plan = RowPlan {
            known,
            selected: &|i| shard.selects(i),
            stop: &|| cancel.is_requested(),
            after_batch: Some(&mut after_batch),
            cut: None,
        };
        let on_element_done = || {
            stage.inc(1);
            cancel.row_done();
        };
        let rows = form_factors::compute_planned(mesh, params, paths.as_ref(), plan, &on_element_done);
        let seconds = start.elapsed().as_secs_f64();
        let resumed = known.map_or(0, PartialRows::done_count);
        stats.resume = (resume.checkpoint.is_some() || resume.needs_matrix()).then(|| ResumeStats {
            rows_resumed: resumed,
            rows_computed: rows.done_count() - resumed,
            load_seconds,
            ..Default::default()
        });
        if let Some(checkpointer) = checkpointer.as_mut() {
            // A run long enough for one periodic write keeps its finished rows for the stages after.
            if cancel.is_requested() || (checkpointer.due() && rows.done_count() > resumed) {
                checkpointer.write(&rows);
            }
            if let Some(e) = checkpointer.error.take() {
                progress.note(&format!("warning: cannot write the checkpoint: {e}"));
            }
            if let Some(r) = stats.resume.as_mut() {
                r.checkpoint_writes = checkpointer.writes;
                r.checkpoint_seconds = checkpointer.write_seconds;
            }
        }
        if let Some(signal) = cancel.signal() {
            return Err(MethodError::Interrupted { signal, checkpoint: resume.checkpoint.clone() });
        }
        let ff = &rows.ff;
        stats.specular_pixels = rows.specular.pixels;
        stats.specular_rays = rows.specular.rays;
        stats.extended_nonzeros = rows.specular.entries;
        stats.elements = mesh.elements.len();
        stats.hemicube_resolution_px = params.hemicube_resolution_px;
        stats.form_factor_seconds = seconds;
        stats.form_factor_nonzeros = ff.nnz();
        stats.form_factor_bytes = ff.memory_bytes();
        stats.hemicubes_per_second = mesh.elements.len() as f64 / seconds.max(1e-9);
        let specular_note = if stats.specular_rays > 0 {
            format!(
                "; through specular surfaces: {} pixels, {} rays, {} extended entries",
                stats.specular_pixels, stats.specular_rays, stats.extended_nonzeros
            )
        } else {
            String::new()
        };
        let resumed_note = if resumed > 0 { format!(" ({resumed} rows resumed)") } else { String::new() };
        stage.finish(&format!(
            "{} elements at {}², {:.0} hemicubes/s, {} non-zeros ({:.1} MiB){specular_note}{resumed_note}",
            mesh.elements.len(),
            params.hemicube_resolution_px,
            stats.hemicubes_per_second,
            ff.nnz(),
            ff.memory_bytes() as f64 / (1 << 20) as f64
        ));
        Ok(rows)
    }

    /// Shard `resume.shard`'s rows of the matrix (`solve --shard K/N`), for `resume::merge_parts`.
    pub fn shard_rows(
        &self,
        scene: &SceneDescription,
        mesh: &Mesh,
        photons: &RunPhotons,
        resume: &Resume,
        progress: &Progress,
    ) -> Result<(PartialRows, PassOneStats), MethodError> {
        self.check_memory(scene, mesh)?;
        let mut stats = PassOneStats { elements: mesh.elements.len(), ..Default::default() };
        let rows = self.compute_form_factors(scene, mesh, photons, resume, progress, &mut stats)?;
        Ok((rows, stats))
    }

    /// Solves B = E + ρ·F·B over `ff` with this method's solver and adds the direct part, the vertex
    /// averages and the fingerprint.
    /// `None` when `stop` ended the solve.
    fn solve_matrix(
        &self,
        scene: &SceneDescription,
        mesh: &Mesh,
        ff: &FormFactors,
        stop: &dyn Fn() -> bool,
        progress: &Progress,
        stats: &mut PassOneStats,
    ) -> Option<Solution> {
        let params = RadiosityParams { solver: self.solver, ..scene.radiosity.clone() };
        let stage = progress.stage("solving", params.max_iterations as u64, "sweeps");
        let start = Instant::now();
        let mut on_iteration = |iteration: u32, residual: f64| {
            stage.set_position(iteration as u64);
            stage.set_message(format!("residual {residual:.2e}"));
        };
        let vertex_step = SmoothMesh::new(mesh);
        let solution =
            solver::solve_solution_until(mesh, &scene.materials, ff, &params, &vertex_step, &mut on_iteration, stop)?;
        stats.solve_seconds = start.elapsed().as_secs_f64();
        stats.solver = Some(self.name());
        stats.sweeps = solution.stats.iterations;
        stats.final_residual = solution.stats.residual_history.last().copied().unwrap_or(0.0);
        stage.finish(&format!(
            "{}: {} iterations, residual {:.2e}{}",
            self.name(),
            stats.sweeps,
            stats.final_residual,
            if solution.stats.converged { "" } else { " (not converged: iteration cap)" }
        ));
        Some(solution)
    }
}

impl PassOneMethod for FullMatrix {
    fn name(&self) -> String {
        self.solver.name().to_string()
    }

    fn checkpoints(&self) -> bool {
        true
    }

    /// The matrix's bound (`form_factor_bytes_bound`), twice for shooting, which also keeps the
    /// transpose; the bound is pessimistic by about 2× (an element sees part of the scene), hence
    /// the halving before comparing with the available memory.
    fn check_memory(&self, scene: &SceneDescription, mesh: &Mesh) -> Result<(), MethodError> {
        let mut bound = form_factor_bytes_bound(mesh, &scene.radiosity);
        if self.solver == SolverKind::Progressive {
            bound *= 2;
        }
        check_matrix_fits(scene, mesh, bound)
    }

    fn solve(
        &self,
        scene: &SceneDescription,
        mesh: Mesh,
        reuse: &mut Reuse,
        photons: &RunPhotons,
        progress: &Progress,
    ) -> Result<PassOne, MethodError> {
        let mut stats = PassOneStats { elements: mesh.elements.len(), ..Default::default() };
        // Only a batch keeps form factors, so only a batch needs their key.
        let key = reuse.keep.then(|| fingerprint::form_factor_key(&mesh, &scene.materials, &scene.radiosity));
        let cached = key.and_then(|key| reuse.form_factors.get(key).cloned());
        let (ff, reused) = match cached {
            Some(ff) => (ff, true),
            None => {
                // Free older scenes' matrices first, as far as the new one (the halved bound, as in
                // `check_memory`) would not fit beside them.
                reuse.form_factors.make_room(form_factor_bytes_bound(&mesh, &scene.radiosity) / 2);
                self.check_memory(scene, &mesh)?;
                let rows = self.compute_form_factors(scene, &mesh, photons, &reuse.resume, progress, &mut stats)?;
                let ff = Arc::new(rows.ff);
                if let Some(key) = key {
                    // The budget is shared with kept hierarchies (none in a matrix-only batch).
                    reuse.keep_form_factors(key, ff.clone());
                }
                (ff, false)
            }
        };
        let resume = &reuse.resume;
        let cancel = &resume.cancel;
        let solution = self.solve_matrix(scene, &mesh, &ff, &|| cancel.is_requested(), progress, &mut stats);
        // From here on nothing is left to save: a signal ends the run at once. One that came after
        // the solver last looked is handled as if it came during the solve.
        cancel.exit_at_once(true);
        match (solution, cancel.signal()) {
            (Some(solution), None) => Ok(PassOne { mesh, solution, stats, reused_form_factors: reused }),
            (_, signal) => {
                if let Some(path) = &resume.checkpoint {
                    let keys = scene_keys(scene, &mesh);
                    let mut checkpointer =
                        Checkpointer::new(path.clone(), keys, resume.shard(), ff.len(), resume.interval);
                    checkpointer.write_matrix(&ff, &vec![true; ff.len()]);
                    if let Some(e) = checkpointer.error {
                        progress.note(&format!("warning: cannot write the checkpoint: {e}"));
                    }
                }
                let signal = signal.unwrap_or(crate::interrupt::SIGINT);
                Err(MethodError::Interrupted { signal, checkpoint: resume.checkpoint.clone() })
            }
        }
    }
}

/// The keys a checkpoint or a shard part of this scene's matrix carries.
pub fn scene_keys(scene: &SceneDescription, mesh: &Mesh) -> SceneKeys {
    SceneKeys {
        fingerprint: fingerprint::fingerprint(mesh, &scene.materials),
        form_factor_key: form_factor_key(mesh, &scene.materials, &scene.radiosity),
    }
}

/// A method that computes shards of pass one and solves merged parts.
pub enum ShardMethod {
    /// The stored matrix: a shard computes every N-th group of rows.
    Matrix(FullMatrix),
    /// The hierarchy: a shard refines pass one for its receiver groups (`hierarchy::shards`).
    Hierarchy(Hierarchical),
}

/// The scene's method for `--shard` and `--merge`: the stored matrix on the uniform mesh, or the
/// hierarchy; else `ShardError::NotMatrix` (matrix-free shooting, and an explicit `method =
/// "adaptive"`, whose levels each need the whole solve of the level before). `method = "auto"` takes
/// the uniform matrix where it would have taken the adaptive mesh (`auto_method_for_shards`); the
/// reason is returned for `-v`.
pub fn shard_method(scene: &SceneDescription) -> Result<(ShardMethod, Option<String>), ShardError> {
    let (method, why): (Box<dyn PassOneMethod>, _) = match scene.radiosity.method {
        MethodChoice::Auto => match auto_method_for_shards(scene) {
            (MethodChoice::Hierarchical, why) => (Box::new(Hierarchical), Some(why)),
            (_, why) => (for_params(&scene.radiosity), Some(why)),
        },
        _ => (for_scene(scene), None),
    };
    // The full matrix is the one method on the uniform mesh that checkpoints, the hierarchy the one
    // off it.
    if method.uses_uniform_mesh() && method.checkpoints() && scene.radiosity.store_form_factors {
        Ok((ShardMethod::Matrix(FullMatrix { solver: scene.radiosity.solver }), why))
    } else if !method.uses_uniform_mesh() && method.checkpoints() {
        Ok((ShardMethod::Hierarchy(Hierarchical), why))
    } else {
        Err(ShardError::NotMatrix { scene: scene.path.display().to_string(), method: method.name() })
    }
}

/// Progressive refinement without a stored matrix (`matrix_free`): one hemicube per shot, O(n)
/// memory whatever the element count, so it has no memory check and nothing for a batch to reuse but
/// the solution.
#[derive(Clone, Copy, Debug)]
pub struct MatrixFree;

impl PassOneMethod for MatrixFree {
    fn name(&self) -> String {
        "progressive (matrix-free)".to_string()
    }

    fn check_memory(&self, _scene: &SceneDescription, _mesh: &Mesh) -> Result<(), MethodError> {
        Ok(())
    }

    fn solve(
        &self,
        scene: &SceneDescription,
        mesh: Mesh,
        _reuse: &mut Reuse,
        photons: &RunPhotons,
        progress: &Progress,
    ) -> Result<PassOne, MethodError> {
        let params = &scene.radiosity;
        let mut stats = PassOneStats::default();
        let accel = specular_accel(scene, &mesh);
        // Progress in per mille of the emitted power shot (the unshot fraction falls from 1 to 0).
        let stage = progress.stage("shooting (matrix-free)", 1000, "‰ shot");
        let start = Instant::now();
        let paths = accel.as_ref().map(|a| specular_paths(scene, &mesh, a, photons));
        let solved = matrix_free::solve(&mesh, params, paths.as_ref(), &mut |shots, unshot_fraction| {
            stage.set_position(((1.0 - unshot_fraction).clamp(0.0, 1.0) * 1000.0) as u64);
            stage.set_message(format!("{shots} shots, unshot {unshot_fraction:.2e}"));
        });
        let seconds = start.elapsed().as_secs_f64();
        stats.elements = mesh.elements.len();
        stats.hemicube_resolution_px = params.hemicube_resolution_px;
        stats.solve_seconds = seconds;
        stats.hemicubes_per_second = solved.stats.iterations as f64 / seconds.max(1e-9);
        stats.solver = Some(self.name());
        stats.sweeps = solved.stats.iterations;
        stats.final_residual = solved.stats.residual_history.last().copied().unwrap_or(0.0);
        stage.finish(&format!(
            "progressive, matrix-free: {} shots, unshot fraction {:.2e}{}",
            stats.sweeps,
            stats.final_residual,
            if solved.stats.converged {
                ""
            } else {
                " (not converged: shot cap; the ambient term stands in for the rest)"
            }
        ));
        let solution = Solution::from_element_values(
            &mesh,
            &scene.materials,
            &solved.exitance,
            &solved.direct_exitance,
            &SmoothMesh::new(&mesh),
            solved.stats,
        );
        Ok(PassOne { mesh, solution, stats, reused_form_factors: false })
    }
}
