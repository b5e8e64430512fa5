//! Where the adaptive mesh is refined: elements whose solution varies across them, measured by how far
//! their corners' interpolated exitance is from their own, relative to the scene's brightest reflected
//! exitance (Cohen, Greenberg, Immel and Brock 1986: subdivide where radiosity gradients are large).

use glam::Vec3;

use crate::mesh::Mesh;

/// The floor f of `elements_to_split`: variation is never measured against less than 5% of the
/// brightest reflected exitance.
pub const FLOOR: f32 = 0.05;

/// The largest exitance (any channel) of an element that does not emit: the scale of the threshold,
/// so that emitters' own exitance does not set it.
pub fn brightest_reflected_exitance(mesh: &Mesh, element_exitance: &[Vec3]) -> f32 {
    (0..mesh.elements.len())
        .filter(|&e| mesh.elements.emission[e].max_element() <= 0.0)
        .map(|e| element_exitance[e].max_element())
        .fold(0.0, f32::max)
}

/// Splits element e when
///   max_k max_channel |B_v(k) − B_e| > τ · max(max_channel B_e, f · B_ref)
/// over its corners k (B_v the vertex exitance, conforming at hanging vertices; B_e its own exitance),
/// τ = `threshold`, B_ref = `brightest_reflected_exitance`, f = `floor`: the variation is measured
/// relative to the element's own exitance (the image's error is judged relative to its brightness),
/// but never below the fraction f of the brightest, so dark corners are not refined for noise. Only
/// when `splittable[e]` and its longest
/// edge is at least twice `min_edge` (its children stay at or above it). A vertex value is the
/// area-weighted mean of the elements around it, so this also measures the differences between
/// neighbours: large at shadow boundaries and in concave corners, nil where the solution is flat.
pub fn elements_to_split(
    mesh: &Mesh,
    element_exitance: &[Vec3],
    vertex_exitance: &[Vec3],
    threshold: f64,
    floor: f32,
    min_edge: f32,
    splittable: &[bool],
) -> Vec<bool> {
    let lowest = floor * brightest_reflected_exitance(mesh, element_exitance);
    (0..mesh.elements.len())
        .map(|e| {
            let limit = threshold as f32 * element_exitance[e].max_element().max(lowest);
            if !splittable[e] || limit <= 0.0 {
                return false;
            }
            let corners: Vec<u32> = mesh.elements.corners[e].into_iter().filter(|&v| v != crate::mesh::NONE).collect();
            let longest = (0..corners.len())
                .map(|k| {
                    let (a, b) = (corners[k], corners[(k + 1) % corners.len()]);
                    (mesh.positions[a as usize] - mesh.positions[b as usize]).length()
                })
                .fold(0.0, f32::max);
            if longest < 2.0 * min_edge {
                return false;
            }
            let variation = corners
                .iter()
                .map(|&v| (vertex_exitance[v as usize] - element_exitance[e]).abs().max_element())
                .fold(0.0, f32::max);
            variation > limit
        })
        .collect()
}
