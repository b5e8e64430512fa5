//! The hierarchical pass-one method (issue 10): `hierarchy::solve` behind the `PassOneMethod`
//! interface. It meshes adaptively, so it ignores the uniform mesh and returns the mesh of its leaf
//! elements (`leaf_mesh`), with the hierarchy's conforming vertex exitance; the direct part pass two
//! needs for `direct = "pixel"` is estimated per leaf with shadow rays to the emitters.
//!
//! Mirrors and glass: the links carry diffuse light only; a specular surface takes part in them with
//! its diffuse Kd (often 0: it absorbs what reaches it) and blocks visibility. Light that reaches
//! diffuse surfaces from the emitters through mirrors and glass (LS+D) comes from photons traced over
//! the input triangles (`caustic_tracer`, the same tracer as the full matrix's extended form factors
//! to the emitters) and enters the solve as each leaf's reflected caustic light, which the links then
//! carry on (`hierarchy::caustics`). Light between diffuse surfaces by way of mirrors and glass (DS+D,
//! which the full matrix follows from its hemicubes) comes from a second set of photons sent from
//! every surface's reflected light once the solve has converged.

use std::sync::Arc;
use std::time::Instant;

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::fingerprint::Fnv1a64;
use super::hierarchy::caustics::{CausticLight, CausticSources};
use super::hierarchy::clusters::InputTriangles;
use super::hierarchy::estimates::{EstimateHooks, EstimateLog};
use super::hierarchy::nodes::Nodes;
use super::hierarchy::part_file::{self, HierarchyPart};
use super::hierarchy::shards::SharedEstimates;
use super::hierarchy::{
    self, interpolate::LeafMesh, links::LINK_BYTES, nodes::NODE_BYTES, solve::SweepOrder, HierarchyError,
    HierarchyParams, HierarchyProgress,
};
use super::leaf_mesh::{self, LeafGeometry, LeafMeshBuild};
use super::method::{MethodError, PassOne, PassOneMethod, Reuse};
use super::resume::{self, Checkpointer, Resume, SceneKeys, Shard};
use super::sampled_direct::sampled_direct_exitance;
use super::solution::Solution;
use super::stats::{PassOneStats, ResumeStats, SolveStats};
use crate::accel::Accel;
use crate::material::SceneTextures;
use crate::mesh::Mesh;
use crate::progress::Progress;
use crate::scene::{Material, Quality, SceneDescription, SolverKind};
use crate::transport::photons::{trace_photons, RunPhotons};

/// Shadow rays per leaf for the direct part of its exitance.
pub const DIRECT_SAMPLES: u32 = 16;

/// The hierarchy's parameters from the scene: the preset's (`HierarchyParams::preview()`, `default()`
/// or `final_quality()` for `quality`), then the `[radiosity]` keys: ε, minimum element size (as the
/// diagonal's divisor; unset, `hierarchy::scene_min_element_divisor` of the scene's shortest input
/// edge, at most the preset's), visibility rays (unset, `hierarchy::scene_visibility_rays`: twice the
/// preset's below 10,000 input triangles), passes, the scene's tolerance and seed, and three quarters of
/// `memory` for nodes and links (the rest is the scene, the ray accelerators and the output mesh).
pub fn hierarchy_params(scene: &SceneDescription) -> HierarchyParams {
    let h = &scene.radiosity.hierarchy;
    let defaults = match h.preset {
        Quality::Preview => HierarchyParams::preview(),
        Quality::Default => HierarchyParams::default(),
        Quality::High => HierarchyParams::final_quality(),
    };
    let diagonal = scene.diagonal();
    let min_element_divisor = match h.min_element_size {
        Some(size) if size > 0.0 && diagonal > 0.0 => (diagonal / size).max(1.0),
        _ => {
            hierarchy::scene_min_element_divisor(diagonal, shortest_input_edge(scene)).min(defaults.min_element_divisor)
        }
    };
    HierarchyParams {
        error_threshold: h.error_threshold.unwrap_or(defaults.error_threshold),
        min_element_divisor,
        visibility_rays: h.visibility_rays.unwrap_or_else(|| {
            hierarchy::scene_visibility_rays(defaults.visibility_rays, hierarchy::count_input_triangles(scene))
        }),
        refinement_passes: h.refinement_passes.unwrap_or(defaults.refinement_passes),
        dark_receiver_floor: h.dark_receiver_floor.unwrap_or(defaults.dark_receiver_floor),
        correction_rays: h.correction_rays.unwrap_or(defaults.correction_rays),
        correction: h.correction.unwrap_or(defaults.correction),
        link_form_factors: h.link_form_factors.unwrap_or(defaults.link_form_factors),
        sweep_order: sweep_order(scene.radiosity.solver),
        tolerance: scene.radiosity.tolerance,
        memory_bytes: usize::try_from(h.memory_bytes / 4 * 3).unwrap_or(usize::MAX),
        seed: scene.radiosity.seed,
        ..defaults
    }
}

/// The hierarchy's sweeps for the scene's `solver`: Jacobi for `jacobi`, Gauss-Seidel otherwise.
/// Progressive shooting has no form over the links here (they are stored at their receivers, and
/// shooting needs them by source); `Hierarchical::solve` says so and sweeps with Gauss-Seidel.
pub fn sweep_order(solver: SolverKind) -> SweepOrder {
    match solver {
        SolverKind::Jacobi => SweepOrder::Jacobi,
        SolverKind::GaussSeidel | SolverKind::Progressive => SweepOrder::GaussSeidel,
    }
}

/// The shortest edge of any input polygon (its outline, not a quad's diagonal; infinite without
/// surfaces).
pub fn shortest_input_edge(scene: &SceneDescription) -> f32 {
    scene
        .surfaces
        .iter()
        .flat_map(|s| s.vertices.iter().zip(s.vertices.iter().cycle().skip(1)).map(|(a, b)| a.distance(*b)))
        .fold(f32::INFINITY, f32::min)
}

/// Bytes the hierarchy needs before any refinement (the input triangles, their clusters and the
/// first links: `hierarchy::solve`'s own check), known from the scene alone.
pub fn minimum_bytes(scene: &SceneDescription) -> u64 {
    let triangles = hierarchy::count_input_triangles(scene) as u64;
    2 * triangles * NODE_BYTES as u64 + 4 * triangles * LINK_BYTES as u64
}

/// What the hierarchy's links depend on: every surface's corners, sidedness and material index (which
/// decides the smoothing groups), and the refinement settings. Material values are not in it.
pub fn geometry_key(scene: &SceneDescription, params: &HierarchyParams) -> u64 {
    let mut h = Fnv1a64::default();
    h.write(b"hierarchy-geometry");
    h.write_u64(scene.surfaces.len() as u64);
    for s in &scene.surfaces {
        h.write_u64(s.vertices.len() as u64);
        h.write_f32s(s.vertices.iter().flat_map(|v| v.to_array()));
        h.write(&[s.two_sided as u8]);
        h.write(&s.material.to_le_bytes());
    }
    h.write_u64(params.error_threshold.to_bits());
    h.write_f32s([params.min_element_divisor]);
    h.write(&params.visibility_rays.to_le_bytes());
    h.write(&params.refinement_passes.to_le_bytes());
    h.write_u64(params.tolerance.to_bits());
    h.write_u64(params.relaxation.to_bits());
    h.write_u64(params.max_sweeps as u64);
    h.write_u64(params.memory_bytes as u64);
    h.write_u64(params.seed);
    // Only when set, so that the keys of kept links and solution files from before it stay valid.
    if params.dark_receiver_floor != 1.0 {
        h.write_u64(params.dark_receiver_floor.to_bits());
    }
    if params.link_form_factors != crate::scene::LinkFormFactors::Formulas {
        h.write(b"link-hemicubes");
    }
    if params.sweep_order == SweepOrder::Jacobi {
        h.write(b"jacobi");
    }
    h.finish()
}

/// What a kept hierarchy (`hierarchy::LinkStructure`: nodes, links, form factors) depends on: the
/// geometry key, and with cut-outs the texture digest (cut-out triangles do not occlude, so the maps
/// decide visibility). A batch job with the same key re-solves from the kept links.
pub fn link_key(scene: &SceneDescription, params: &HierarchyParams, textures: &SceneTextures) -> u64 {
    let mut h = Fnv1a64::default();
    h.write_u64(geometry_key(scene, params));
    if textures.has_cut_outs() {
        h.write_u64(textures.digest());
    }
    h.finish()
}

/// Identifies a hierarchical solution's scene: the geometry key and every material's Kd, Ke, Ks, Ni
/// and transmittance (and the texture digest of a textured scene). A materials-only change keeps the
/// geometry key and changes this.
pub fn scene_fingerprint(scene: &SceneDescription, params: &HierarchyParams, textures: &SceneTextures) -> u64 {
    let mut h = Fnv1a64::default();
    h.write_u64(geometry_key(scene, params));
    h.write_u64(scene.materials.len() as u64);
    for m in &scene.materials {
        h.write_f32s(material_values(m));
    }
    if textures.is_textured() {
        h.write_u64(textures.digest());
    }
    // The ray correction changes the solution, not the links; only a setting other than the
    // default's is hashed, so that solution files from before it stay valid.
    if params.correction_rays != hierarchy::CORRECTION_RAYS {
        h.write_u64(params.correction_rays as u64);
    }
    if params.correction != crate::scene::CorrectionEstimator::Rays {
        h.write_u64(0xc0);
    }
    h.finish()
}

fn material_values(m: &Material) -> [f32; 11] {
    let (kd, ke, ks) = (m.diffuse_reflectance, m.emitted_radiance, m.specular_reflectance);
    [kd.x, kd.y, kd.z, ke.x, ke.y, ke.z, ks.x, ks.y, ks.z, m.ior, m.transmittance]
}

/// Pass two's mesh and solution from a hierarchical solve: the leaf mesh, its conforming vertex values,
/// and the direct part estimated with shadow rays and interpolated by the same vertex step
/// (`LeafMesh::vertex_values`), so that total and direct agree where pass two subtracts them.
pub fn solution_on_leaves(
    scene: &SceneDescription,
    geometry: LeafGeometry,
    leaf_exitance: &[Vec3],
    leaves: &LeafMesh,
    textures: Arc<SceneTextures>,
    fingerprint: u64,
    stats: SolveStats,
) -> (Mesh, Solution) {
    let LeafMeshBuild { mesh, back_vertices } = leaf_mesh::build(scene, &geometry, textures);
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let direct = sampled_direct_exitance(&mesh, &scene.materials, &accel, DIRECT_SAMPLES, scene.radiosity.seed);
    let direct_f32: Vec<Vec3> = direct.iter().map(|v| v.as_vec3()).collect();
    // Element i of the pass-two mesh is leaf i; the back vertices then take their back leaf's
    // interpolation, as for the total.
    let leaf_direct_vertex = leaves.vertex_values(&direct);
    let solution = Solution {
        element_exitance: leaf_exitance.to_vec(),
        element_direct_exitance: direct_f32,
        vertex_exitance: leaf_mesh::vertex_values(&geometry, &leaves.vertex_exitance, &back_vertices),
        vertex_direct_exitance: leaf_mesh::vertex_values(&geometry, &leaf_direct_vertex, &back_vertices),
        mesh_fingerprint: fingerprint,
        stats,
        leaf_geometry: Some(Arc::new(geometry)),
        refinement: None,
        holds_caustic_light: true,
    };
    (mesh, solution)
}

/// The hierarchy's source of caustic light (`hierarchy::caustics`): photons traced from the sources
/// through the scene's mirrors and glass (`transport::photons::trace_photons`, the full matrix's and
/// pass two's tracer, with its fixed seed) over a mesh whose elements are the input triangles (leaf
/// geometry of one leaf per input triangle, so that a photon's element is its input triangle), each
/// landing with flux Φ = (S/π)·throughput, S the exitance its source sends: the emission E, or for
/// `CausticSources::ReflectedLight` the reflected exitance B − E of the input triangle's node.
/// `None` when the scene has no mirror or glass (no mesh is built then) or nothing sends light.
pub fn caustic_tracer(
    scene: &SceneDescription,
    textures: Arc<SceneTextures>,
) -> impl Fn(&Nodes, &InputTriangles, CausticSources) -> Option<CausticLight> + Sync + '_ {
    move |nodes, inputs, sources| {
        if !scene.materials.iter().any(Material::is_specular) {
            return None;
        }
        let corners: Vec<[Vec3; 3]> = inputs.node.iter().map(|&n| nodes.corners[n as usize]).collect();
        let geometry = LeafGeometry {
            positions: corners.iter().flatten().copied().collect(),
            triangles: (0..corners.len() as u32).map(|i| [3 * i, 3 * i + 1, 3 * i + 2]).collect(),
            surface: inputs.surface.clone(),
            back: inputs.back.clone(),
        };
        let mut mesh = leaf_mesh::build(scene, &geometry, textures.clone()).mesh;
        if sources == CausticSources::ReflectedLight {
            for (i, &n) in inputs.node.iter().enumerate() {
                let n = n as usize;
                let reflected = (nodes.exitance[n] - nodes.emission[n].as_dvec3()).max(DVec3::ZERO);
                mesh.elements.emission[i] = reflected.as_vec3();
            }
        }
        let accel = Accel::build(&mesh.positions, &mesh.triangles);
        let photons = trace_photons(&mesh, &accel, &scene.materials, Some(&scene.surfaces), |count, trace| {
            (0..count).into_par_iter().map(trace).collect()
        })?;
        let e = &mesh.elements;
        let landings = photons
            .landings
            .iter()
            .map(|l| (l.element, l.position, l.throughput * e.emission[l.source as usize] / std::f32::consts::PI))
            .collect();
        Some(CausticLight::new(landings, photons.rays))
    }
}

/// What the progress line says while `caustic_tracer` traces photons from `sources`.
fn photons_message(sources: CausticSources) -> &'static str {
    match sources {
        CausticSources::Emitters => "tracing photons from the emitters through mirrors and glass",
        CausticSources::ReflectedLight => "tracing photons from reflected light through mirrors and glass",
    }
}

/// The mesh of a loaded hierarchical solution (its leaf geometry), or `None` for a uniform one.
pub fn mesh_of(scene: &SceneDescription, solution: &Solution, textures: Arc<SceneTextures>) -> Option<Mesh> {
    solution.leaf_geometry.as_ref().map(|g| leaf_mesh::build(scene, g, textures).mesh)
}

/// Hierarchical radiosity with clustering and adaptive subdivision (`radiosity::hierarchy`).
#[derive(Clone, Copy, Debug)]
pub struct Hierarchical;

impl PassOneMethod for Hierarchical {
    fn name(&self) -> String {
        "hierarchical".to_string()
    }

    fn uses_uniform_mesh(&self) -> bool {
        false
    }

    /// The log of link estimates (`hierarchy::estimates`) is the checkpoint: a resumed solve replays
    /// the refinement from it and computes only the estimates it lacks.
    fn checkpoints(&self) -> bool {
        true
    }

    /// The hierarchy's minimum (input triangles, clusters, first links) against its share of
    /// `memory`, from the scene alone; refinement then stays within the budget by keeping coarser
    /// links.
    fn check_memory(&self, scene: &SceneDescription, _mesh: &Mesh) -> Result<(), MethodError> {
        let params = hierarchy_params(scene);
        let needed = minimum_bytes(scene);
        if needed > params.memory_bytes as u64 {
            const GIB: f64 = (1u64 << 30) as f64;
            return Err(MethodError::HierarchyOverBudget {
                scene: scene.path.display().to_string(),
                triangles: hierarchy::count_input_triangles(scene),
                needed_gib: needed as f64 / GIB,
                budget_gib: scene.radiosity.hierarchy.memory_bytes as f64 / GIB,
            });
        }
        Ok(())
    }

    fn solution_key(&self, scene: &SceneDescription, mesh: &Mesh) -> u64 {
        scene_fingerprint(scene, &hierarchy_params(scene), &mesh.textures)
    }

    fn solve(
        &self,
        scene: &SceneDescription,
        mesh: Mesh,
        reuse: &mut Reuse,
        _photons: &RunPhotons,
        progress: &Progress,
    ) -> Result<PassOne, MethodError> {
        self.check_memory(scene, &mesh)?;
        let params = hierarchy_params(scene);
        if scene.radiosity.solver == SolverKind::Progressive {
            progress.note(
                "warning: solver = \"progressive\" has no form over the hierarchy's links (they are stored at their \
                 receivers; shooting needs them by source): the hierarchy sweeps with Gauss-Seidel",
            );
        }
        let stage = progress.stage("hierarchy", params.refinement_passes as u64, "passes");
        let start = Instant::now();
        let mut memory_bytes = 0usize;
        // Only a batch keeps hierarchies, so only a batch needs their key.
        let key = reuse.keeps().then(|| link_key(scene, &params, &mesh.textures));
        let kept = key.and_then(|key| reuse.hierarchy_links(key));
        let resume = reuse.resume.clone();
        let keys = SceneKeys {
            fingerprint: scene_fingerprint(scene, &params, &mesh.textures),
            form_factor_key: link_key(scene, &params, &mesh.textures),
        };
        let load_start = Instant::now();
        let mut log = match &resume.checkpoint {
            Some(path) => resume::load_hierarchy_checkpoint(path, keys, progress)
                .map_or_else(EstimateLog::recording, EstimateLog::resumed),
            None => EstimateLog::default(),
        };
        let logged = log.entries.len();
        // A merge (`--merge`): the whole solve, with the shards' estimates (`hierarchy::shards`).
        let shared = match resume.merge.is_empty() {
            true => None,
            false => {
                let round = resume::merge_hierarchy_parts(&resume.merge, keys)?;
                Some(SharedEstimates::for_merge(round.entries, round.state))
            }
        };
        let load_seconds = load_start.elapsed().as_secs_f64();
        let mut checkpointer =
            resume.checkpoint.as_ref().map(|path| Checkpointer::for_hierarchy(path.clone(), keys, resume.interval));
        let cancel = &resume.cancel;
        let stop = || cancel.is_requested();
        let mut after_chunk = |log: &EstimateLog, computed: usize| {
            (0..computed).for_each(|_| cancel.row_done());
            if let Some(checkpointer) = checkpointer.as_mut() {
                if checkpointer.due() {
                    checkpointer.write_log(log);
                }
            }
        };
        let mut hooks =
            EstimateHooks { log: &mut log, stop: &stop, after_chunk: &mut after_chunk, shared: shared.as_ref() };
        let tracer = caustic_tracer(scene, mesh.textures.clone());
        let correction = params.correction;
        let solved = hierarchy::solve_logged(
            scene,
            mesh.textures.clone(),
            &params,
            kept.as_deref(),
            Some(&tracer),
            &mut hooks,
            &mut |p| match p {
                HierarchyProgress::Refining { pass, round, links, nodes } => {
                    memory_bytes = nodes * NODE_BYTES + links * LINK_BYTES;
                    stage.set_position(pass.saturating_sub(1) as u64);
                    stage.set_message(format!(
                        "pass {pass} refining, round {round}: {nodes} nodes, {links} links, {:.0} MiB",
                        memory_bytes as f64 / (1 << 20) as f64
                    ));
                }
                HierarchyProgress::TracingPhotons { pass, sources } => {
                    stage.set_message(format!("pass {pass}: {}", photons_message(sources)));
                }
                HierarchyProgress::MeasuringLinks { pass, receivers } => {
                    stage.set_message(format!(
                        "pass {pass}: measuring the far links of {receivers} receivers with hemicubes"
                    ));
                }
                HierarchyProgress::Correcting { pass, round } => {
                    let rounds = hierarchy::CORRECTION_ROUNDS;
                    let by = match correction {
                        crate::scene::CorrectionEstimator::Rays => "rays",
                        crate::scene::CorrectionEstimator::Hemicube => "hemicubes",
                    };
                    stage
                        .set_message(format!("pass {pass}: measuring the indirect light with {by} ({round}/{rounds})"));
                }
                HierarchyProgress::Sweeping { pass, sweep, max_change, max_exitance } => {
                    let relative = if max_exitance > 0.0 { max_change / max_exitance } else { 0.0 };
                    stage.set_message(format!(
                        "pass {pass} sweep {sweep}: change {relative:.2e}, {:.0} MiB",
                        memory_bytes as f64 / (1 << 20) as f64
                    ));
                }
            },
        );
        if log.diverged {
            progress.note(&format!(
                "warning: the checkpoint's link estimates disagree with this refinement after {} of {logged}; \
                 computing the rest afresh",
                log.replayed().saturating_sub(log.computed)
            ));
        }
        let solved = match solved {
            Err(HierarchyError::Stopped) => {
                if let Some(checkpointer) = checkpointer.as_mut() {
                    checkpointer.write_log(&log);
                    if let Some(e) = checkpointer.error.take() {
                        progress.note(&format!("warning: cannot write the checkpoint: {e}"));
                    }
                }
                let signal = cancel.signal().unwrap_or(crate::interrupt::SIGINT);
                return Err(MethodError::Interrupted { signal, checkpoint: resume.checkpoint.clone() });
            }
            other => {
                other.map_err(|source| MethodError::Hierarchy { scene: scene.path.display().to_string(), source })?
            }
        };
        let (solved, structure) = solved;
        let reused = kept.is_some();
        drop(kept);
        // Kept for later jobs, or freed now (before the leaf mesh and its direct part are built).
        match key {
            Some(key) => _ = reuse.keep_hierarchy_links(key, Arc::new(structure)),
            None => drop(structure),
        }
        let solve_seconds = start.elapsed().as_secs_f64();
        let h = &solved.stats;
        stage.finish(&format!(
            "{} input triangles, {} clusters → {} elements, {} links ({} estimated{}), {} passes, {} sweeps, peak {:.1} MiB{}{}",
            h.input_triangles,
            h.clusters,
            h.elements,
            h.links,
            h.links_estimated,
            if reused { ", the rest kept from an earlier job" } else { "" },
            h.refinement_passes,
            h.sweeps,
            h.peak_bytes as f64 / (1 << 20) as f64,
            if h.budget_exceeded { " (memory budget reached: coarser links kept)" } else { "" },
            if h.bounded_leaves > 0 {
                format!(
                    "; the sweeps diverged: {} leaves' links summed to more than they reflect (row sums up to {:.2}), \
                     scaled to their hemisphere",
                    h.bounded_leaves, h.max_row_sum
                )
            } else {
                String::new()
            }
        ));
        let geometry = LeafGeometry {
            positions: solved.mesh.positions.clone(),
            triangles: solved.mesh.triangles.clone(),
            surface: solved.leaf_surface.clone(),
            back: solved.leaf_back.clone(),
        };
        let solve_stats = SolveStats {
            solver: match params.sweep_order {
                SweepOrder::GaussSeidel => SolverKind::GaussSeidel,
                SweepOrder::Jacobi => SolverKind::Jacobi,
            },
            iterations: h.sweeps,
            residual_history: h.error_after_pass_w.clone(),
            converged: h.converged,
        };
        let fingerprint = scene_fingerprint(scene, &params, &mesh.textures);
        let direct_stage = progress.stage("direct part", 1, "leaves");
        let (leaf_mesh, solution) = solution_on_leaves(
            scene,
            geometry,
            &solved.leaf_exitance,
            &solved.mesh,
            mesh.textures.clone(),
            fingerprint,
            solve_stats,
        );
        direct_stage.finish(&format!("{DIRECT_SAMPLES} shadow rays per leaf"));
        let mut resume_stats = None;
        if let Some(checkpointer) = checkpointer.as_mut() {
            // A run long enough for one periodic write (or stopped now) keeps its estimates for the
            // stages after pass one.
            if cancel.is_requested() || checkpointer.writes > 0 || checkpointer.due() {
                checkpointer.write_log(&log);
            }
            if let Some(e) = checkpointer.error.take() {
                progress.note(&format!("warning: cannot write the checkpoint: {e}"));
            }
            resume_stats = Some(ResumeStats {
                rows_resumed: log.replayed().saturating_sub(log.computed),
                rows_computed: log.computed,
                load_seconds,
                checkpoint_writes: checkpointer.writes,
                checkpoint_seconds: checkpointer.write_seconds,
            });
        }
        if let Some(shared) = &shared {
            let hits = shared.hits() as usize;
            progress.note(&format!(
                "merge: {hits} of {} link estimates from the {} parts ({} held), {} computed here ({} not in \
                 the parts; the rest near links to split or kept, not looked up)",
                log.computed,
                resume.merge.len(),
                shared.known_len(),
                log.computed - hits,
                shared.misses()
            ));
            resume_stats = Some(ResumeStats {
                rows_resumed: hits,
                rows_computed: log.computed - hits,
                load_seconds,
                ..Default::default()
            });
        }
        let stats = PassOneStats {
            elements: leaf_mesh.elements.len(),
            solver: Some(self.name()),
            sweeps: h.sweeps,
            solve_seconds,
            hierarchy: Some(h.clone()),
            specular_rays: h.caustic_rays,
            resume: resume_stats,
            ..Default::default()
        };
        Ok(PassOne { mesh: leaf_mesh, solution, stats, reused_form_factors: reused })
    }
}

impl Hierarchical {
    /// Shard `shard` of a hierarchical solve (`solve --shard K/N [--merge PARTS]`): with the parts of
    /// round p (none for p = 0), starts from the solved state of pass p − 1 they carry, refines and
    /// solves pass p whole (taking its pure estimates from the parts), refines pass p + 1 for the
    /// shard's receiver groups (`hierarchy::shards`) and writes its pure link estimates, with the
    /// state of pass p, to `output` as a part for the next round or `--merge`. A shard keeps no
    /// checkpoint (an interrupted shard starts again).
    pub fn shard_part(
        &self,
        scene: &SceneDescription,
        textures: Arc<SceneTextures>,
        shard: Shard,
        resume: &Resume,
        output: &std::path::Path,
        progress: &Progress,
    ) -> Result<PassOneStats, MethodError> {
        self.check_memory(scene, &Mesh::default())?;
        let params = hierarchy_params(scene);
        let keys = SceneKeys {
            fingerprint: scene_fingerprint(scene, &params, &textures),
            form_factor_key: link_key(scene, &params, &textures),
        };
        let (done, earlier, from_state) = match resume.merge.is_empty() {
            true => (0, Vec::new(), None),
            false => {
                let round = resume::merge_hierarchy_parts(&resume.merge, keys)?;
                (round.pass, round.entries, round.state)
            }
        };
        let pass = done + 1;
        if pass > params.refinement_passes {
            return Err(resume::ShardError::EveryPassDone { passes: params.refinement_passes }.into());
        }
        let stage = progress.stage("hierarchy shard", 1, "passes");
        let start = Instant::now();
        let shared = SharedEstimates::for_shard(shard.index, shard.count, pass, earlier, from_state);
        let mut log = EstimateLog::default();
        let cancel = &resume.cancel;
        let stop = || cancel.is_requested();
        let mut after_chunk = |_: &EstimateLog, computed: usize| (0..computed).for_each(|_| cancel.row_done());
        let mut hooks =
            EstimateHooks { log: &mut log, stop: &stop, after_chunk: &mut after_chunk, shared: Some(&shared) };
        let tracer = caustic_tracer(scene, textures.clone());
        let solved =
            hierarchy::solve_logged(scene, textures, &params, None, Some(&tracer), &mut hooks, &mut |p| match p {
                HierarchyProgress::Refining { pass, round, links, nodes } => stage.set_message(format!(
                    "shard {}/{} pass {pass} round {round}: {nodes} nodes, {links} links",
                    shard.index, shard.count
                )),
                HierarchyProgress::TracingPhotons { pass, sources } => stage.set_message(format!(
                    "shard {}/{} pass {pass}: {}",
                    shard.index,
                    shard.count,
                    photons_message(sources)
                )),
                HierarchyProgress::Sweeping { .. }
                | HierarchyProgress::Correcting { .. }
                | HierarchyProgress::MeasuringLinks { .. } => {}
            });
        let (solved, _) = match solved {
            Err(HierarchyError::Stopped) => {
                let signal = cancel.signal().unwrap_or(crate::interrupt::SIGINT);
                return Err(MethodError::Interrupted { signal, checkpoint: None });
            }
            other => {
                other.map_err(|source| MethodError::Hierarchy { scene: scene.path.display().to_string(), source })?
            }
        };
        // Every part names the state its pass was refined from; shard 0's carries it for the next round.
        let state = shared.take_captured();
        let state_hash = state.as_ref().map_or(0, part_file::state_hash);
        let state = state.filter(|_| shard.index == 0);
        let part = HierarchyPart { pass, entries: shared.take_recorded(), state_hash, state };
        resume::write_hierarchy_part(output, keys, shard, &part).map_err(resume::ShardError::from)?;
        stage.finish(&format!(
            "shard {}/{} of pass {pass}: {} links estimated ({} from the parts, {} not in them), {} shared",
            shard.index,
            shard.count,
            log.computed,
            shared.hits(),
            shared.misses(),
            part.entries.len()
        ));
        Ok(PassOneStats {
            solver: Some(self.name()),
            solve_seconds: start.elapsed().as_secs_f64(),
            hierarchy: Some(solved.stats),
            ..Default::default()
        })
    }
}
