//! Conforming interpolation on a mesh with T-vertices: a hanging vertex (the midpoint of a split
//! edge whose element on the other side was not split) takes its edge's interpolated value, the mean
//! of the edge's two ends, so Gouraud shading is continuous across the edge and shows no crack.

use glam::{DVec3, Vec3};

use super::subdivide::EdgeMidpoints;
use crate::mesh::Mesh;
use crate::radiosity::smooth_mesh::SmoothMesh;

/// One hanging vertex and the ends of the unsplit element edge it lies on (its value is their mean).
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub struct Hanging {
    pub vertex: u32,
    pub ends: (u32, u32),
}

/// Every hanging vertex of `mesh`: walking each element edge (a, b) down the split edges
/// (`midpoints`), every midpoint m found is hanging on (a, b), and so are the midpoints of (a, m) and
/// (m, b) in turn (nested T-vertices, when a neighbour was split more than once). Sorted by vertex, so
/// that the ends of each (made earlier, hence lower indices) come first.
pub fn hanging_vertices(mesh: &Mesh, midpoints: &EdgeMidpoints) -> Vec<Hanging> {
    let mut found = Vec::new();
    if midpoints.is_empty() {
        return found;
    }
    let mut stack = Vec::new();
    for c in &mesh.elements.corners {
        let n = if c[3] == crate::mesh::NONE { 3 } else { 4 };
        for k in 0..n {
            stack.push((c[k], c[(k + 1) % n]));
            while let Some((a, b)) = stack.pop() {
                if let Some(m) = midpoints.get(a, b) {
                    found.push(Hanging { vertex: m, ends: (a.min(b), a.max(b)) });
                    stack.push((a, m));
                    stack.push((m, b));
                }
            }
        }
    }
    found.sort_unstable();
    found.dedup();
    found
}

/// Gives every hanging vertex its edge's interpolated value, v_m = (v_a + v_b)/2, in vertex order
/// (the ends of a nested one are resolved before it), so values are linear along each unsplit edge.
pub fn conform<T>(values: &mut [T], hanging: &[Hanging])
where
    T: Copy + std::ops::Add<Output = T> + std::ops::Mul<f32, Output = T>,
{
    for h in hanging {
        let (a, b) = h.ends;
        values[h.vertex as usize] = (values[a as usize] + values[b as usize]) * 0.5;
    }
}

/// The adaptive mesh's vertex step for any per-element quantity (exitance, irradiance): the uniform
/// mesh's (`SmoothMesh::vertex_values`: means within smoothing groups, the outline extrapolated, a
/// split edge's midpoint not taken for a boundary), then the `hanging` vertices given their edge's
/// value (`conform`). With no hanging vertices it is the uniform mesh's step.
pub fn conforming_vertex_values(vertex_step: &SmoothMesh, element_values: &[DVec3], hanging: &[Hanging]) -> Vec<Vec3> {
    let mut vertex = vertex_step.vertex_values(element_values);
    conform(&mut vertex, hanging);
    vertex
}
