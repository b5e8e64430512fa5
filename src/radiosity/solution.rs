//! The immutable result of pass one: per-element and per-vertex radiosity (exitance), the direct part
//! of it, and how the solver got there. Pass two reads it; `radray solve` saves it to a file.

use glam::Vec3;

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

/// Radiosity of every element and vertex of a mesh. Exitance B (W/m²); radiance is B/π.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Total exitance B_i of each element (emission plus all diffuse interreflection).
    pub element_exitance: Vec<Vec3>,
    /// The first-bounce part of B_i: light received straight from emitters and reflected,
    /// ρ_i Σ_j F_ij E_j (emission itself excluded).
    pub element_direct_exitance: Vec<Vec3>,
    /// Area-weighted vertex averages of `element_exitance` (Gouraud interpolation).
    pub vertex_exitance: Vec<Vec3>,
    /// Area-weighted vertex averages of `element_direct_exitance`.
    pub vertex_direct_exitance: Vec<Vec3>,
    /// Identifies the mesh (geometry, materials) the solution belongs to: see `fingerprint`.
    pub mesh_fingerprint: u64,
    pub stats: SolveStats,
}
