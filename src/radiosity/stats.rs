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
    pub hierarchy: Option<HierarchyStats>,
    /// What the checkpoint, shard or merge of the matrix method did (absent for plain runs).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub resume: Option<ResumeStats>,
    /// What the adaptive method did (absent for the other methods).
    #[serde(skip_serializing_if = "Option::is_none")]
    pub adaptive: Option<AdaptiveStats>,
}

/// The levels of `method = "adaptive"`: elements solved at each, form-factor rows computed by
/// hemicubes, rows kept from the level before (substructuring) and level 0's rows taken from an
/// earlier job of a batch with the same geometry (a materials-only change).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct AdaptiveStats {
    pub elements_per_level: Vec<usize>,
    pub rows_computed: usize,
    pub rows_kept: usize,
    pub rows_reused: usize,
}

/// Rows taken from a checkpoint or merged parts and rows computed by this run, and the checkpoint
/// writes (`radiosity::resume`).
#[derive(Clone, Debug, Default, serde::Serialize)]
pub struct ResumeStats {
    /// Rows copied from the checkpoint or the merged parts (including empty rows of black elements).
    pub rows_resumed: usize,
    /// Rows this run finished (including empty rows of black elements).
    pub rows_computed: usize,
    /// Reading and checking the checkpoint or the parts.
    pub load_seconds: f64,
    pub checkpoint_writes: u32,
    pub checkpoint_seconds: f64,
}
