//! `method = "adaptive"`: the full matrix on a mesh refined where the solution needs it (Cohen,
//! Greenberg, Immel and Brock 1986; Ashdown, *Radiosity: A Programmer's Perspective*, ch. 7). The
//! scene is meshed into patches at `max_element_edge` and solved with hemicubes and the scene's
//! solver; elements whose light varies across them (`criterion`: their irradiance, so that a
//! texture's contrast does not count; also the light of emitters and of bright reflectors that shadow
//! rays find blocked at some corners and not at others on the patches, or not linear across the
//! element on the level below, `shadow_boundaries`),
//! and the elements facing them across
//! concave edges, are split
//! into four (`subdivide`); the finer mesh is solved again, up to
//! `adaptive_levels` times. Each level keeps the form-factor rows of the elements it did not split
//! (`substructure`), so it draws hemicubes only for the new children, and those hemicubes draw the
//! split patches far from them whole, their form factor shared among the leaves by area
//! (`matrix::patch_cut`), so a hemicube draws about as many polygons as there are patches plus the
//! leaves near it. Boundary vertices are
//! extrapolated from the elements inside (`boundary_vertices`) and a hanging vertex takes its edge's
//! interpolated value (`hanging`), so the image has no T-vertex cracks. Every level is a plain
//! row-independent matrix solve, so the bytes are the same at any thread count; light through
//! mirrors and glass (extended form factors, photons) is followed on the final mesh only: with them,
//! the levels before it are plain, at half the hemicube resolution, and no rows are kept. A batch
//! keeps level 0's plain rows (`level_zero_key`): they depend on geometry only, so a job that changes
//! only materials solves its patches from them and draws hemicubes only for the refined levels.

pub mod criterion;
pub mod hanging;
pub mod refinement;
pub mod reflectors;
pub mod shadow_boundaries;
pub mod subdivide;
pub mod substructure;

use std::sync::Arc;
use std::time::Instant;

use super::matrix::patch_cut::PatchCut;
use super::matrix::{form_factors, FormFactors, PartialRows, RowPlan};
use super::method::{
    check_matrix_fits, form_factor_bytes_bound, specular_accel, specular_paths, MethodError, PassOne, PassOneMethod,
    Reuse,
};
use super::solution::Solution;
use super::solver;
use super::stats::PassOneStats;
use crate::accel::Accel;
use crate::mesh::Mesh;
use crate::progress::{Progress, Verbosity};
use crate::scene::{RadiosityParams, SceneDescription, SolverKind};
use crate::transport::photons::RunPhotons;
use refinement::Refinement;
use shadow_boundaries::BlockedLightTest;
use subdivide::EdgeMidpoints;

/// Changes whenever the method refines or solves differently, so that a cached solution of an
/// older revision is not taken for this one's (2: substructuring, extrapolated boundary vertices,
/// refinement carried across concave edges; 3: the split criterion on irradiance; 4: shadow rays at
/// the patches' corners; 5: those rays also to the reflecting elements; 6: far split patches drawn
/// whole by the refined levels' hemicubes; 7: the blocked light's interpolation error on the levels
/// below the patches; 8: kept rows share a split element's form factor among its open children).
const REVISION: u64 = 8;

/// Hemicube resolution the deciding levels never go below.
const MIN_PROBE_RESOLUTION_PX: u32 = 32;

/// The adaptive-mesh method (see module docs) with the scene's solver.
#[derive(Clone, Copy, Debug)]
pub struct Adaptive {
    pub solver: SolverKind,
}

/// The solved mesh of one level, with its form factors and its hanging vertices (given their edge's
/// value by its vertex step).
struct Level {
    mesh: Mesh,
    solution: Solution,
    ff: Arc<FormFactors>,
    hanging: Vec<hanging::Hanging>,
}

/// Mixed into level 0's form-factor key (`level_zero_key`), so that a batch never takes the patch
/// mesh's plain rows for the full matrix's (extended through mirrors and glass) or the other way.
const LEVEL_ZERO_TAG: u64 = 0x6164_6170_7469_7630; // "adaptiv0"

/// Elements no refinement may split: both sides of two-sided surfaces (the back side mirrors the
/// front's grid) and elements buried under the back of a one-sided surface (never seen).
fn splittable(mesh: &Mesh) -> Vec<bool> {
    let mut sides = vec![0u8; mesh.surface_source.iter().map(|&s| s as usize + 1).max().unwrap_or(0)];
    for &source in &mesh.surface_source {
        sides[source as usize] = sides[source as usize].saturating_add(1);
    }
    (0..mesh.elements.len())
        .map(|e| {
            let source = mesh.surface_source[mesh.elements.surface[e] as usize] as usize;
            sides[source] < 2 && !mesh.element_buried.get(e).copied().unwrap_or(false)
        })
        .collect()
}

impl Adaptive {
    fn params(&self, scene: &SceneDescription) -> RadiosityParams {
        RadiosityParams { solver: self.solver, ..scene.radiosity.clone() }
    }

    /// The settings a level is solved with: the scene's, or, for levels that only decide where to
    /// split (`full_resolution` false), half its hemicube resolution.
    fn level_params(&self, scene: &SceneDescription, full_resolution: bool) -> RadiosityParams {
        let mut params = self.params(scene);
        if !full_resolution {
            params.hemicube_resolution_px = (params.hemicube_resolution_px / 2).max(MIN_PROBE_RESOLUTION_PX);
        }
        params
    }

    /// The key under which a batch keeps level 0's form factors of `patches`, solved plain (without
    /// the photons' paths through mirrors and glass) with `level_params(full_resolution)`: what they
    /// depend on (`fingerprint::form_factor_key`: geometry, specular materials, which elements reflect
    /// or emit, hemicube settings), so a materials-only change (Kd, Ke) finds them.
    fn level_zero_key(&self, scene: &SceneDescription, patches: &Mesh, full_resolution: bool) -> u64 {
        let params = self.level_params(scene, full_resolution);
        super::fingerprint::form_factor_key(patches, &scene.materials, &params) ^ LEVEL_ZERO_TAG
    }

    /// Hemicube form factors of `mesh` (through mirrors and glass when `photons` is given; `reused`
    /// when an earlier job of a batch left them) and the solve, with conforming values at the hanging
    /// vertices.
    #[allow(clippy::too_many_arguments)]
    fn solve_level(
        &self,
        scene: &SceneDescription,
        mesh: Mesh,
        midpoints: &EdgeMidpoints,
        photons: Option<&RunPhotons>,
        kept: Option<&PartialRows>,
        cut: Option<&PatchCut>,
        reused: Option<Arc<FormFactors>>,
        level: u32,
        full_resolution: bool,
        progress: &Progress,
        stats: &mut PassOneStats,
    ) -> Result<Level, MethodError> {
        // Levels that only decide where to split see the scene at half the hemicube resolution.
        let params = self.level_params(scene, full_resolution);
        let adaptive = stats.adaptive.get_or_insert_with(Default::default);
        adaptive.elements_per_level.push(mesh.elements.len());
        let ff = match reused {
            Some(ff) => {
                adaptive.rows_reused += ff.len();
                if progress.verbosity() == Verbosity::Verbose {
                    progress.note(&format!(
                        "form factors (adaptive level {level}): {} elements, {} non-zeros reused from an earlier job",
                        mesh.elements.len(),
                        ff.nnz()
                    ));
                }
                ff
            }
            None => {
                check_matrix_fits(scene, &mesh, form_factor_bytes_bound(&mesh, &scene.radiosity))?;
                let stage = progress.stage(
                    &format!("form factors (adaptive level {level})"),
                    mesh.elements.len() as u64,
                    "elements",
                );
                let start = Instant::now();
                let accel = photons.and_then(|_| specular_accel(scene, &mesh));
                let paths = match (&accel, photons) {
                    (Some(accel), Some(photons)) => Some(specular_paths(scene, &mesh, accel, photons)),
                    _ => None,
                };
                let plan = RowPlan { known: kept, selected: &|_| true, stop: &|| false, after_batch: None, cut };
                let rows = form_factors::compute_planned(&mesh, &params, paths.as_ref(), plan, &|| stage.inc(1));
                adaptive.rows_kept += kept.map_or(0, PartialRows::done_count);
                adaptive.rows_computed += rows.done.len() - kept.map_or(0, PartialRows::done_count);
                let ff = rows.ff;
                stage.finish(&format!(
                    "level {level}: {} elements, {} non-zeros ({:.1} MiB)",
                    mesh.elements.len(),
                    ff.nnz(),
                    ff.memory_bytes() as f64 / (1 << 20) as f64
                ));
                stats.form_factor_seconds += start.elapsed().as_secs_f64();
                stats.specular_pixels = rows.specular.pixels;
                stats.specular_rays = rows.specular.rays;
                stats.extended_nonzeros = rows.specular.entries;
                Arc::new(ff)
            }
        };
        stats.form_factor_nonzeros = ff.nnz();
        stats.form_factor_bytes = stats.form_factor_bytes.max(ff.memory_bytes());
        // The uniform mesh's vertex step (`SmoothMesh`: welded within smoothing groups, boundary
        // vertices extrapolated from the elements inside, a split edge's midpoint found by position so
        // that a T-junction is not a boundary), then the hanging ones given their edge's value.
        let vertex_step = super::smooth_mesh::SmoothMesh::new(&mesh);
        let start = Instant::now();
        let mut solution = solver::solve_solution(&mesh, &scene.materials, &ff, &params, &vertex_step, &mut |_, _| {});
        stats.solve_seconds += start.elapsed().as_secs_f64();
        stats.sweeps += solution.stats.iterations;
        stats.final_residual = solution.stats.residual_history.last().copied().unwrap_or(0.0);
        let hanging = hanging::hanging_vertices(&mesh, midpoints);
        hanging::conform(&mut solution.vertex_exitance, &hanging);
        hanging::conform(&mut solution.vertex_direct_exitance, &hanging);
        Ok(Level { mesh, solution, ff, hanging })
    }
}

impl PassOneMethod for Adaptive {
    fn name(&self) -> String {
        format!("adaptive ({})", self.solver.name())
    }

    /// The mesh is the method's own (patches refined by the solution), not the scene's uniform one.
    fn uses_uniform_mesh(&self) -> bool {
        false
    }

    /// The patch mesh's key (geometry, materials, hemicube and solver settings) with the refinement's
    /// settings: equal keys refine and solve alike.
    fn solution_key(&self, scene: &SceneDescription, mesh: &Mesh) -> u64 {
        let patches = Mesh::build_with_textures(scene, scene.radiosity.max_element_edge, mesh.textures.clone());
        let a = &scene.radiosity.adaptive;
        let min_edge = scene.radiosity.hierarchy.min_element_size.unwrap_or(scene.diagonal() / 200.0);
        let mut h = super::fingerprint::solution_key(&patches, &scene.materials, &self.params(scene));
        for x in [
            a.levels as u64,
            a.threshold.to_bits(),
            min_edge.to_bits() as u64,
            u64::from(criterion::FLOOR.to_bits()),
            REVISION,
        ] {
            h = (h ^ x).wrapping_mul(0x100000001b3);
        }
        h
    }

    /// Checked per level, on the mesh about to be solved.
    fn check_memory(&self, _scene: &SceneDescription, _mesh: &Mesh) -> Result<(), MethodError> {
        Ok(())
    }

    fn solve(
        &self,
        scene: &SceneDescription,
        mesh: Mesh,
        reuse: &mut Reuse,
        photons: &RunPhotons,
        progress: &Progress,
    ) -> Result<PassOne, MethodError> {
        let settings = &scene.radiosity.adaptive;
        let mut stats =
            PassOneStats { hemicube_resolution_px: scene.radiosity.hemicube_resolution_px, ..Default::default() };
        let mut current = refinement::patch_mesh(scene, mesh.textures.clone());
        // Each patch's leaves in the current level's mesh (contiguous: `substructure::new_indices`).
        let patches = current.clone();
        let mut leaves: Vec<std::ops::Range<u32>> = (0..patches.elements.len() as u32).map(|p| p..p + 1).collect();
        let specular = crate::radiosity::specular::mesh_has_specular(&current, &scene.materials);
        let min_edge = scene.radiosity.hierarchy.min_element_size.unwrap_or(scene.diagonal() / 200.0);
        let mut midpoints = EdgeMidpoints::default();
        // Substructuring: every level is solved at full resolution and the next keeps the rows of
        // the elements it did not split. Not with mirrors or glass: their extended rows are made on
        // the final mesh only.
        let substructure = !specular;
        let mut kept: Option<PartialRows> = None;
        let mut record = Refinement::default();
        let mut level = 0;
        let mut reused_form_factors = false;
        let solved = loop {
            let last = level == settings.levels;
            let with_photons = (last && specular).then_some(photons);
            let full = last || substructure;
            // A batch keeps level 0's plain rows (they depend on geometry, not on Kd or Ke), so a
            // materials-only job draws no patch hemicubes; rows made with the photons' paths are not kept.
            let level_zero_key = (level == 0 && with_photons.is_none() && reuse.keeps())
                .then(|| self.level_zero_key(scene, &current, full));
            let cached = level_zero_key.and_then(|key| reuse.form_factors(key));
            reused_form_factors |= cached.is_some();
            let fresh = level_zero_key.filter(|_| cached.is_none());
            // Hemicubes draw the split patches far from them whole (`PatchCut`).
            let resolution_px = self.level_params(scene, full).hemicube_resolution_px;
            let cut = (level > 0).then(|| PatchCut::new(&patches, &leaves, &current, resolution_px));
            let solved = self.solve_level(
                scene,
                current,
                &midpoints,
                with_photons,
                kept.as_ref(),
                cut.as_ref(),
                cached,
                level,
                full,
                progress,
                &mut stats,
            )?;
            if let Some(key) = fresh {
                reuse.keep_form_factors(key, solved.ff.clone());
            }
            if last {
                break solved;
            }
            // The criterion reads the light (irradiance), not the exitance a texture modulates.
            let exitance = &solved.solution.element_exitance;
            let vertex_step = super::smooth_mesh::SmoothMesh::new(&solved.mesh);
            let mut variation = criterion::irradiance_variation(&solved.mesh, exitance, &vertex_step, &solved.hanging);
            // Shadows narrower than two elements, which their centres miss: between the patches'
            // corners; on the next level, where the children's corners do not interpolate them.
            let test = if level == 0 { BlockedLightTest::CornerSpread } else { BlockedLightTest::Interpolation };
            let accel = Accel::build(&solved.mesh.positions, &solved.mesh.triangles);
            let blocked = shadow_boundaries::blocked_light_variation(
                &solved.mesh,
                &scene.materials,
                exitance,
                &accel,
                &splittable(&solved.mesh),
                scene.radiosity.seed,
                test,
            );
            for (v, b) in variation.iter_mut().zip(blocked) {
                *v = v.max(b);
            }
            let split = criterion::elements_to_split(
                &solved.mesh,
                exitance,
                &variation,
                settings.threshold,
                criterion::FLOOR,
                min_edge,
                &splittable(&solved.mesh),
            );
            let split =
                criterion::across_concave_edges_and_emitters(&solved.mesh, &split, min_edge, &splittable(&solved.mesh));
            let count = split.iter().filter(|&&s| s).count();
            let over_limit = solved.mesh.elements.len() as u64 + 3 * count as u64 > crate::run::MAX_ELEMENTS;
            if count == 0 || over_limit {
                if substructure {
                    break solved; // already solved in full
                }
                // That level was solved only to decide where to split (plain, at half resolution):
                // solve the final mesh once more, in full, with its paths through mirrors and glass.
                let photons = specular.then_some(photons);
                break self.solve_level(
                    scene,
                    solved.mesh,
                    &midpoints,
                    photons,
                    None,
                    None,
                    None,
                    level,
                    true,
                    progress,
                    &mut stats,
                )?;
            }
            current = refinement::split_level(&solved.mesh, &split, &mut midpoints);
            let index = substructure::new_indices(&split);
            for range in &mut leaves {
                *range = index[range.start as usize].start..index[range.end as usize - 1].end;
            }
            record.record(&split);
            kept = substructure.then(|| substructure::kept_rows(&solved.mesh, &solved.ff, &split, &current));
            level += 1;
        };
        stats.elements = solved.mesh.elements.len();
        stats.solver = Some(self.name());
        stats.hemicubes_per_second = stats.elements as f64 / stats.form_factor_seconds.max(1e-9);
        // The file carries the refinement, so `render --solution` rebuilds this mesh (`refinement`).
        let solution = Solution { refinement: Some(Arc::new(record)), ..solved.solution };
        Ok(PassOne { mesh: solved.mesh, solution, stats, reused_form_factors })
    }
}
