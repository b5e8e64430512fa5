//! The one-way flow of a run: scene description → mesh → form factors → radiosity solution →
//! camera rays → film. Each step takes what the previous one made and reports what it measured.

use crate::accel::Accel;
use crate::film::{self, Image};
use crate::mesh::{self, Mesh};
use crate::progress::Progress;
use crate::radiosity::specular::{self, SpecularPaths};
use crate::radiosity::{form_factors, progressive, FormFactors, Solution};
use crate::scene::{RadiosityParams, SceneDescription, SolverKind};
use crate::trace::camera::PinholeCamera;
use crate::trace::whitted::{RayCounts, TraceMode, Tracer};
use crate::transport::photons::{self, Photons};
use std::cell::OnceCell;
use std::time::Instant;

/// Why a run cannot go on (before anything is allocated or written).
#[derive(Debug, thiserror::Error)]
pub enum PipelineError {
    #[error("{scene}: meshing at max_element_edge = {edge} would make {elements} elements, more than radray handles ({limit}); use a larger max_element_edge or a coarser --quality")]
    TooManyElements { scene: String, edge: f32, elements: u64, limit: u64 },
    #[error("{scene}: the form factors of {elements} elements at hemicube resolution {resolution} would need about {needed_gib:.1} GiB, but about {available_gib:.1} GiB is available; use a larger max_element_edge (memory grows with the square of the element count), a lower hemicube_resolution, or solver = \"progressive\" with store_form_factors = false (no stored matrix: O(n) memory, one hemicube per shot; pair it with a looser tolerance such as 1e-2)")]
    OutOfMemory { scene: String, elements: usize, resolution: u32, needed_gib: f64, available_gib: f64 },
}

/// Most elements a mesh may have: beyond this even the per-element arrays and one hemicube pass
/// per element are out of reach of a workstation.
pub const MAX_ELEMENTS: u64 = 2_000_000;

/// What a run measured, written by `--stats` and into batch manifests.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct RunStats {
    pub elements: usize,
    pub hemicube_resolution_px: u32,
    pub form_factor_seconds: f64,
    pub form_factor_nonzeros: usize,
    pub form_factor_bytes: usize,
    pub hemicubes_per_second: f64,
    /// Hemicube pixels that showed a mirror or glass and were followed by rays (0 without them).
    pub specular_pixels: u64,
    /// Rays traced for the extended form factors through specular surfaces.
    pub specular_rays: u64,
    /// Extended form-factor entries (part of `form_factor_nonzeros`).
    pub extended_nonzeros: u64,
    pub solver: Option<String>,
    pub sweeps: u32,
    pub final_residual: f64,
    pub solve_seconds: f64,
    pub render_seconds: f64,
    pub primary_rays: u64,
    pub secondary_rays: u64,
    pub shadow_rays: u64,
    pub rays_per_second: f64,
    pub samples: u64,
    pub adaptive_extra_samples: u64,
    pub peak_memory_bytes: u64,
}

/// Meshes the scene after checking that the element count is sane.
pub fn build_mesh(scene: &SceneDescription, progress: &Progress) -> Result<Mesh, PipelineError> {
    let edge = scene.radiosity.max_element_edge;
    let count = mesh::count_elements(scene, edge);
    if count > MAX_ELEMENTS {
        return Err(PipelineError::TooManyElements {
            scene: scene.path.display().to_string(),
            edge,
            elements: count,
            limit: MAX_ELEMENTS,
        });
    }
    let stage = progress.stage("meshing", scene.surfaces.len() as u64, "surfaces");
    let mesh = Mesh::build(scene, edge);
    stage.finish(&format!(
        "{} surfaces → {} elements, {} triangles",
        scene.surfaces.len(),
        mesh.elements.len(),
        mesh.triangles.len()
    ));
    Ok(mesh)
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

/// Memory the system says is available (Linux `MemAvailable`), if known.
pub fn available_memory_bytes() -> Option<u64> {
    let text = std::fs::read_to_string("/proc/meminfo").ok()?;
    let line = text.lines().find(|l| l.starts_with("MemAvailable:"))?;
    let kib: u64 = line.split_whitespace().nth(1)?.parse().ok()?;
    Some(kib * 1024)
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

/// Refuses a form-factor computation whose matrix could not fit in memory.
pub fn check_memory(scene: &SceneDescription, mesh: &Mesh) -> Result<(), PipelineError> {
    let mut bound = form_factor_bytes_bound(mesh, &scene.radiosity);
    if scene.radiosity.solver == SolverKind::Progressive {
        bound *= 2; // progressive refinement with a stored matrix also keeps its transpose
    }
    if let Some(available) = available_memory_bytes() {
        // The bound is pessimistic by about 2× (an element sees part of the scene), hence the factor.
        if bound / 2 > available {
            const GIB: f64 = (1u64 << 30) as f64;
            return Err(PipelineError::OutOfMemory {
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

/// The ray accelerator pass one needs to follow light through mirrors and glass: built only when
/// some element of the mesh is specular (`None` otherwise, and the form factors are plain).
pub fn specular_accel(scene: &SceneDescription, mesh: &Mesh) -> Option<Accel> {
    specular::mesh_has_specular(mesh, &scene.materials).then(|| Accel::build(&mesh.positions, &mesh.triangles))
}

/// The photons of one run (`transport::photons`): traced by whichever pass needs them first, then read
/// by both, pass one's extended form factors and pass two's caustic map. Make one per scene and mesh.
#[derive(Default)]
pub struct RunPhotons(OnceCell<Option<Photons>>);

impl RunPhotons {
    /// The photons of `scene` meshed as `mesh` (`accel` built from its triangles), traced in parallel
    /// batches on first use; `None` without specular surfaces or emitters.
    pub fn get(&self, scene: &SceneDescription, mesh: &Mesh, accel: &Accel) -> Option<&Photons> {
        self.0
            .get_or_init(|| {
                photons::trace_photons(mesh, accel, &scene.materials, Some(&scene.surfaces), |count, trace| {
                    use rayon::prelude::*;
                    (0..count).into_par_iter().map(trace).collect()
                })
            })
            .as_ref()
    }
}

/// Hemicube form factors of every element (rows only where an element reflects or emits), extended
/// through the scene's specular surfaces when `accel` (from `specular_accel`) is given, with the run's
/// `photons` for the light paths to the emitters.
pub fn compute_form_factors(
    scene: &SceneDescription,
    mesh: &Mesh,
    accel: Option<&Accel>,
    photons: &RunPhotons,
    progress: &Progress,
    stats: &mut RunStats,
) -> FormFactors {
    let params = &scene.radiosity;
    let stage = progress.stage("form factors", mesh.elements.len() as u64, "elements");
    let start = Instant::now();
    let ff = match accel {
        Some(accel) => {
            let paths = SpecularPaths::new(mesh, accel, &scene.materials).with_shading_normals(&scene.surfaces);
            let paths = match photons.get(scene, mesh, accel) {
                Some(photons) => paths.with_light_paths(photons),
                None => paths,
            };
            let (ff, specular_stats) = form_factors::compute_extended(mesh, params, &paths, &|| stage.inc(1));
            stats.specular_pixels = specular_stats.pixels;
            stats.specular_rays = specular_stats.rays;
            stats.extended_nonzeros = specular_stats.entries;
            ff
        }
        None => form_factors::compute(mesh, params, &|| stage.inc(1)),
    };
    let seconds = start.elapsed().as_secs_f64();
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
    stage.finish(&format!(
        "{} elements at {}², {:.0} hemicubes/s, {} non-zeros ({:.1} MiB){specular_note}",
        mesh.elements.len(),
        params.hemicube_resolution_px,
        stats.hemicubes_per_second,
        ff.nnz(),
        ff.memory_bytes() as f64 / (1 << 20) as f64
    ));
    ff
}

/// Solves B = E + ρ·F·B with the scene's solver.
pub fn solve(
    scene: &SceneDescription,
    mesh: &Mesh,
    ff: &FormFactors,
    progress: &Progress,
    stats: &mut RunStats,
) -> Solution {
    let params = &scene.radiosity;
    let stage = progress.stage("solving", params.max_iterations as u64, "sweeps");
    let start = Instant::now();
    let solution = Solution::compute(mesh, &scene.materials, ff, params, &mut |iteration, residual| {
        stage.set_position(iteration as u64);
        stage.set_message(format!("residual {residual:.2e}"));
    });
    stats.solve_seconds = start.elapsed().as_secs_f64();
    stats.solver = Some(params.solver.name().to_string());
    stats.sweeps = solution.stats.iterations;
    stats.final_residual = solution.stats.residual_history.last().copied().unwrap_or(0.0);
    stage.finish(&format!(
        "{}: {} iterations, residual {:.2e}{}",
        params.solver.name(),
        stats.sweeps,
        stats.final_residual,
        if solution.stats.converged { "" } else { " (not converged: iteration cap)" }
    ));
    solution
}

/// Pass one without a stored matrix (`store_form_factors = false`): progressive refinement that
/// rasterises each shooter's hemicube when it shoots (`radiosity::progressive`), extended through
/// mirrors and glass when `accel` is given. Memory stays O(n) whatever the element count.
pub fn solve_matrix_free(
    scene: &SceneDescription,
    mesh: &Mesh,
    accel: Option<&Accel>,
    progress: &Progress,
    stats: &mut RunStats,
) -> Solution {
    let params = &scene.radiosity;
    // Progress in per mille of the emitted power shot (the unshot fraction falls from 1 to 0).
    let stage = progress.stage("shooting (matrix-free)", 1000, "‰ shot");
    let start = Instant::now();
    let paths = accel.map(|a| SpecularPaths::new(mesh, a, &scene.materials).with_shading_normals(&scene.surfaces));
    let solved = progressive::solve(mesh, params, paths.as_ref(), &mut |shots, unshot_fraction| {
        stage.set_position(((1.0 - unshot_fraction).clamp(0.0, 1.0) * 1000.0) as u64);
        stage.set_message(format!("{shots} shots, unshot {unshot_fraction:.2e}"));
    });
    let seconds = start.elapsed().as_secs_f64();
    stats.elements = mesh.elements.len();
    stats.hemicube_resolution_px = params.hemicube_resolution_px;
    stats.solve_seconds = seconds;
    stats.hemicubes_per_second = solved.stats.iterations as f64 / seconds.max(1e-9);
    stats.solver = Some("progressive (matrix-free)".to_string());
    stats.sweeps = solved.stats.iterations;
    stats.final_residual = solved.stats.residual_history.last().copied().unwrap_or(0.0);
    stage.finish(&format!(
        "progressive, matrix-free: {} shots, unshot fraction {:.2e}{}",
        stats.sweeps,
        stats.final_residual,
        if solved.stats.converged { "" } else { " (not converged: shot cap; the ambient term stands in for the rest)" }
    ));
    Solution::from_element_values(mesh, &scene.materials, &solved.exitance, &solved.direct_exitance, solved.stats)
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
) -> Result<Image, crate::trace::TraceError> {
    let image = &scene.image;
    let camera = PinholeCamera::new(&scene.camera, image.width_px, image.height_px);
    let tracer =
        Tracer::new(mesh, accel, solution, &scene.materials, &scene.render)?.with_shading_normals(&scene.surfaces);
    let tracer = match photons.get(scene, mesh, accel) {
        Some(photons) if mode == TraceMode::Final => tracer.with_caustics(photons),
        _ => tracer,
    };
    let tiles = image.width_px.div_ceil(film::TILE_SIZE_PX) * image.height_px.div_ceil(film::TILE_SIZE_PX);
    let stage = progress.stage(
        if mode == TraceMode::Final { "render final" } else { "render radiosity" },
        tiles as u64,
        "tiles",
    );
    let start = Instant::now();
    let (picture, film_stats, counts) = film::render_with(
        image,
        RayCounts::default,
        |counts: &mut RayCounts, x, y, sampler| {
            let ray = camera.ray(x, y);
            tracer.radiance(ray.origin, ray.dir, mode, sampler, counts)
        },
        &|| stage.inc(1),
    );
    let seconds = start.elapsed().as_secs_f64();
    let total: RayCounts = counts.into_iter().sum();
    stats.render_seconds += seconds;
    stats.primary_rays += total.primary;
    stats.secondary_rays += total.secondary;
    stats.shadow_rays += total.shadow;
    stats.samples += film_stats.samples;
    stats.adaptive_extra_samples += film_stats.adaptive_extra_samples;
    let rays = total.primary + total.secondary + total.shadow;
    stats.rays_per_second =
        (stats.primary_rays + stats.secondary_rays + stats.shadow_rays) as f64 / stats.render_seconds.max(1e-9);
    stage.finish(&format!(
        "{}×{} at {} spp: {} rays ({:.2} M rays/s)",
        image.width_px,
        image.height_px,
        image.samples_per_pixel,
        rays,
        rays as f64 / seconds.max(1e-9) / 1e6
    ));
    Ok(picture)
}
