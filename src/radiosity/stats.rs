//! What pass one measured: how a solve went (stored in solution files) and the figures a run reports
//! (`--stats`, batch manifests).

use super::hierarchy::HierarchyStats;
use crate::scene::SolverKind;

/// How a solve went.
#[derive(Clone, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct SolveStats {
    pub solver: SolverKind,
    /// Sweeps (Gauss-Seidel, Jacobi) or shots (progressive refinement) performed.
    pub iterations: u32,
    /// The convergence measure after each sweep (largest relative change), or after each shot (unshot
    /// power / emitted power for progressive refinement).
    pub residual_history: Vec<f64>,
    pub converged: bool,
}

/// What pass one measured, reported by `--stats` and in batch manifests (flattened into the run's
/// statistics, so the JSON keys are the same as before).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct PassOneStats {
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
    /// What the hierarchical method did (absent for the other methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub hierarchy: Option<HierarchyRunStats>,
}

/// What a hierarchical solve did, for `--stats` and manifests.
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct HierarchyRunStats {
    pub input_triangles: usize,
    pub clusters: usize,
    /// Clusters, input triangles and their subdivisions.
    pub nodes: usize,
    /// Leaf elements (the mesh pass two reads; back sides of two-sided surfaces included).
    pub elements: usize,
    pub links: usize,
    pub refinement_passes: u32,
    pub refinement_rounds: u32,
    pub sweeps: u32,
    pub converged: bool,
    pub links_estimated: u64,
    /// Largest bytes of nodes and links during the solve (the budgeted part).
    pub peak_bytes: usize,
    /// Some refinement was refused to stay within the memory budget.
    pub budget_exceeded: bool,
    /// Σ of link errors (W) after each refinement pass.
    pub error_after_pass_w: Vec<f64>,
}

impl From<&HierarchyStats> for HierarchyRunStats {
    fn from(h: &HierarchyStats) -> Self {
        HierarchyRunStats {
            input_triangles: h.input_triangles,
            clusters: h.clusters,
            nodes: h.nodes,
            elements: h.elements,
            links: h.links,
            refinement_passes: h.refinement_passes,
            refinement_rounds: h.refinement_rounds,
            sweeps: h.sweeps,
            converged: h.converged,
            links_estimated: h.links_estimated,
            peak_bytes: h.peak_bytes,
            budget_exceeded: h.budget_exceeded,
            error_after_pass_w: h.error_after_pass_w.clone(),
        }
    }
}
