//! The immutable result of pass one: per-element and per-vertex radiosity (exitance), the direct part
//! of it, and how the solver got there. Pass two reads it; `solution_file` saves and loads it.

use std::sync::Arc;

use glam::{DVec3, Vec3};

use super::adaptive::refinement::Refinement;
use super::fingerprint::fingerprint;
use super::leaf_mesh::LeafGeometry;
use super::smooth_mesh::SmoothMesh;
use crate::mesh::Mesh;
use crate::scene::{Material, SolverKind};

pub use super::stats::SolveStats;

/// Radiosity of every element and vertex of a mesh. Exitance B (W/m²); radiance is B/π.
#[derive(Clone, Debug, PartialEq)]
pub struct Solution {
    /// Total exitance B_i of each element (emission plus all diffuse interreflection).
    pub element_exitance: Vec<Vec3>,
    /// The first-bounce part of B_i: light received straight from emitters and reflected,
    /// ρ_i Σ_j F_ij E_j (emission itself excluded).
    pub element_direct_exitance: Vec<Vec3>,
    /// Vertex values of `element_exitance` (Gouraud interpolation): area-weighted vertex means, linearly
    /// extrapolated at surface boundaries (`boundary_vertices::vertex_values`).
    pub vertex_exitance: Vec<Vec3>,
    /// Vertex values of `element_direct_exitance`, made alike.
    pub vertex_direct_exitance: Vec<Vec3>,
    /// Identifies the mesh and materials the solution belongs to: see `fingerprint`.
    pub mesh_fingerprint: u64,
    pub stats: SolveStats,
    /// For a hierarchical solution: the leaf elements it lives on (pass two's mesh is built from them,
    /// `leaf_mesh::build`); `None` for a solution on the scene's uniform mesh.
    pub leaf_geometry: Option<Arc<LeafGeometry>>,
    /// For an adaptive solution: the levels of splits that made its mesh from the scene's patch mesh
    /// (`adaptive::refinement::mesh_of` rebuilds it); `None` otherwise.
    pub refinement: Option<Arc<Refinement>>,
    /// Whether the exitance holds the light that reached diffuse surfaces from the emitters through
    /// mirrors and glass (LS+D): the uniform and adaptive meshes' solutions do (extended form factors),
    /// and so do hierarchical ones since session 23 (`hierarchy::caustics`); a hierarchical solution
    /// file of an older format (version 3) does not. Pass two then adds all of that light from its
    /// caustic map rather than only the detail the elements miss.
    pub holds_caustic_light: bool,
}

fn to_f32(values: &[DVec3]) -> Vec<Vec3> {
    values.iter().map(|v| v.as_vec3()).collect()
}

impl Solution {
    /// Bytes held by the solution (its four arrays, an adaptive refinement's split indices and the
    /// struct).
    pub fn memory_bytes(&self) -> u64 {
        let values = self.element_exitance.len()
            + self.element_direct_exitance.len()
            + self.vertex_exitance.len()
            + self.vertex_direct_exitance.len();
        let splits = self.refinement.as_ref().map_or(0, |r| r.split_count() * std::mem::size_of::<u32>());
        (values * std::mem::size_of::<Vec3>() + splits + std::mem::size_of::<Solution>()) as u64
    }

    /// A solution from per-element exitance and its direct part (however they were solved): adds the
    /// vertex values (`vertex_step`: `mesh` welded within its smoothing groups, `SmoothMesh::new`;
    /// means inside a group, extrapolated on its outline) and the fingerprint of `mesh` and
    /// `materials`.
    pub fn from_element_values(
        mesh: &Mesh,
        materials: &[Material],
        exitance: &[DVec3],
        direct: &[DVec3],
        vertex_step: &SmoothMesh,
        stats: SolveStats,
    ) -> Solution {
        assert!(exitance.len() == mesh.elements.len() && direct.len() == mesh.elements.len());
        Solution {
            element_exitance: to_f32(exitance),
            element_direct_exitance: to_f32(direct),
            vertex_exitance: vertex_step.vertex_values(exitance),
            vertex_direct_exitance: vertex_step.vertex_values(direct),
            mesh_fingerprint: fingerprint(mesh, materials),
            stats,
            leaf_geometry: None,
            refinement: None,
            holds_caustic_light: true,
        }
    }

    /// The solution of a scene without emitters: everything black, converged without a sweep
    /// (`stats.solver` is Gauss-Seidel, nothing was run).
    pub fn black(mesh: &Mesh, materials: &[Material]) -> Solution {
        Solution {
            element_exitance: vec![Vec3::ZERO; mesh.elements.len()],
            element_direct_exitance: vec![Vec3::ZERO; mesh.elements.len()],
            vertex_exitance: vec![Vec3::ZERO; mesh.positions.len()],
            vertex_direct_exitance: vec![Vec3::ZERO; mesh.positions.len()],
            mesh_fingerprint: fingerprint(mesh, materials),
            stats: SolveStats {
                solver: SolverKind::GaussSeidel,
                iterations: 0,
                residual_history: Vec::new(),
                converged: true,
            },
            leaf_geometry: None,
            refinement: None,
            holds_caustic_light: true,
        }
    }

    /// Radiance leaving element i (diffuse): L = B/π.
    pub fn element_radiance(&self, i: usize) -> Vec3 {
        self.element_exitance[i] * std::f32::consts::FRAC_1_PI
    }

    /// Radiance of the indirect part of element i, (B − E − direct)/π given its emission E: what pass
    /// two adds when it samples direct light per pixel.
    pub fn element_indirect_radiance(&self, i: usize, emission: Vec3) -> Vec3 {
        ((self.element_exitance[i] - emission - self.element_direct_exitance[i]) * std::f32::consts::FRAC_1_PI)
            .max(Vec3::ZERO)
    }

    /// Radiance at vertex v (Gouraud-interpolated by the caller): L = B/π.
    pub fn vertex_radiance(&self, v: usize) -> Vec3 {
        self.vertex_exitance[v] * std::f32::consts::FRAC_1_PI
    }
}
