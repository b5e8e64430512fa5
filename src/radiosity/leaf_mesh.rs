//! The mesh a hierarchical solution lives on, as pass two reads it: the hierarchy's leaf elements
//! (`LeafGeometry`, saved in solution files) turned into a `Mesh` whose traced triangles are the front
//! leaves, so that Gouraud interpolation over them is the hierarchy's conforming interpolation (no
//! T-vertex cracks). The back side of a two-sided surface may be subdivided differently from its
//! front: each front leaf's back vertices sit at its own corners and take the back side's interpolated
//! value there (`BackVertex`), so both sides of one triangle are read on the same triangle.

use std::sync::Arc;

use glam::{Vec2, Vec3};
use rayon::prelude::*;
use rustc_hash::FxHashMap;

use super::hierarchy::texels::SurfaceTexels;
use crate::material::SceneTextures;
use crate::mesh::{surface_uv, Elements, Mesh, NONE};
use crate::scene::SceneDescription;

/// The leaf elements of a hierarchical solution (what a solution file stores in place of the
/// uniform meshing parameters).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LeafGeometry {
    pub positions: Vec<Vec3>,
    /// Per leaf: its corners, counter-clockwise seen from its front.
    pub triangles: Vec<[u32; 3]>,
    /// Per leaf: the scene surface it lies on.
    pub surface: Vec<u32>,
    /// Per leaf: it is the back side of a two-sided surface.
    pub back: Vec<bool>,
}

/// A vertex the conversion adds on a two-sided surface's back side at a front leaf's corner: its value
/// is Σ_k w_k V(c_k) over the corners c_k of the back leaf that holds it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BackVertex {
    pub leaf: u32,
    pub weights: [f32; 3],
}

/// A `Mesh` over the leaves (element i = leaf i) and the back vertices it added after the leaves'
/// own (vertex `geometry.positions.len() + k` is `back_vertices[k]`).
#[derive(Debug)]
pub struct LeafMeshBuild {
    pub mesh: Mesh,
    pub back_vertices: Vec<BackVertex>,
}

/// Barycentric weights of `p` in triangle `t` (projected into its plane).
fn barycentric(t: [Vec3; 3], p: Vec3) -> [f32; 3] {
    let n = (t[1] - t[0]).cross(t[2] - t[0]);
    let inv = 1.0 / n.length_squared();
    let w1 = (p - t[0]).cross(t[2] - t[0]).dot(n) * inv;
    let w2 = (t[1] - t[0]).cross(p - t[0]).dot(n) * inv;
    [1.0 - w1 - w2, w1, w2]
}

/// The leaf among `candidates` that holds `p` (the largest smallest barycentric weight, so a point on
/// an edge or just outside through rounding still finds its leaf), with `p`'s weights in it, clamped
/// to the leaf and renormalised.
fn locate(geometry: &LeafGeometry, candidates: &[u32], p: Vec3) -> Option<BackVertex> {
    let corners = |l: u32| geometry.triangles[l as usize].map(|v| geometry.positions[v as usize]);
    let mut best: Option<(f32, BackVertex)> = None;
    for &leaf in candidates {
        let w = barycentric(corners(leaf), p);
        let inside = w[0].min(w[1]).min(w[2]);
        if inside.is_finite() && best.is_none_or(|(b, _)| inside > b) {
            best = Some((inside, BackVertex { leaf, weights: w }));
        }
    }
    best.map(|(_, mut v)| {
        let w = v.weights.map(|x| x.max(0.0));
        let sum = w[0] + w[1] + w[2];
        v.weights = if sum > 0.0 { w.map(|x| x / sum) } else { [1.0 / 3.0; 3] };
        v
    })
}

/// Builds the pass-two mesh of `geometry` (see module docs): element i is leaf i with its scene
/// surface's material and the reflectance and emission the hierarchy used for it (its texture means,
/// `SurfaceTexels::element_materials`, so pass two's texture ratio divides by the same albedo); mesh
/// surface s is scene surface s's front and `surfaces + s` its back; uv comes from the scene surface
/// at each vertex.
pub fn build(scene: &SceneDescription, geometry: &LeafGeometry, textures: Arc<SceneTextures>) -> LeafMeshBuild {
    let surfaces = scene.surfaces.len() as u32;
    let texels = SurfaceTexels::new(scene, textures.clone());
    let materials: Vec<(Vec3, Vec3)> = (0..geometry.triangles.len())
        .into_par_iter()
        .map(|leaf| {
            let corners = geometry.triangles[leaf].map(|v| geometry.positions[v as usize]);
            texels.element_materials(geometry.surface[leaf], corners).solved()
        })
        .collect();
    let mut mesh = Mesh { positions: geometry.positions.clone(), textures, ..Default::default() };
    let e: &mut Elements = &mut mesh.elements;
    for (leaf, tri) in geometry.triangles.iter().enumerate() {
        let p = tri.map(|v| geometry.positions[v as usize]);
        let cross = (p[1] - p[0]).cross(p[2] - p[0]);
        let s = geometry.surface[leaf];
        let material = scene.surfaces[s as usize].material;
        let (reflectance, emission) = materials[leaf];
        e.corners.push([tri[0], tri[1], tri[2], NONE]);
        e.centre.push((p[0] + p[1] + p[2]) / 3.0);
        e.normal.push(cross.normalize_or_zero());
        e.area.push(0.5 * cross.length());
        e.surface.push(if geometry.back[leaf] { surfaces + s } else { s });
        e.material.push(material);
        e.reflectance.push(reflectance);
        e.emission.push(emission);
    }
    mesh.surface_source = (0..surfaces).chain(0..surfaces).collect();
    mesh.surface_has_uv = scene.surfaces.iter().chain(&scene.surfaces).map(|s| s.uvs.is_some()).collect();
    let back_refracts =
        |s: &crate::scene::Surface| !s.two_sided && scene.materials[s.material as usize].is_dielectric();
    if scene.surfaces.iter().any(back_refracts) {
        mesh.surface_back_refracts =
            scene.surfaces.iter().map(back_refracts).chain(scene.surfaces.iter().map(|_| false)).collect();
    }
    // Back leaves by scene surface, for point location on two-sided surfaces.
    let mut back_leaves: FxHashMap<u32, Vec<u32>> = FxHashMap::default();
    for leaf in 0..geometry.triangles.len() {
        if geometry.back[leaf] {
            back_leaves.entry(geometry.surface[leaf]).or_default().push(leaf as u32);
        }
    }
    let mut back_vertices = Vec::new();
    let mut back_vertex_of: FxHashMap<(u32, [u32; 3]), u32> = FxHashMap::default();
    for (leaf, tri) in geometry.triangles.iter().enumerate() {
        if geometry.back[leaf] {
            continue; // back leaves are read through their front's triangles
        }
        mesh.triangles.push(*tri);
        mesh.triangle_element.push(leaf as u32);
        let s = geometry.surface[leaf];
        let Some(candidates) = back_leaves.get(&s) else {
            mesh.triangle_back_element.push(NONE);
            mesh.triangle_back_vertices.push([NONE; 3]);
            continue;
        };
        let centre = mesh.elements.centre[leaf];
        let back_element = locate(geometry, candidates, centre).map_or(NONE, |v| v.leaf);
        let corners = tri.map(|v| {
            let p = geometry.positions[v as usize];
            let key = (s, p.to_array().map(f32::to_bits));
            *back_vertex_of.entry(key).or_insert_with(|| {
                let located = locate(geometry, candidates, p).unwrap_or(BackVertex { leaf: 0, weights: [0.0; 3] });
                back_vertices.push(located);
                mesh.positions.push(p);
                mesh.positions.len() as u32 - 1
            })
        });
        mesh.triangle_back_element.push(back_element);
        mesh.triangle_back_vertices.push(corners);
    }
    mesh.uvs = vertex_uvs(scene, geometry, &mesh, &back_vertices);
    LeafMeshBuild { mesh, back_vertices }
}

/// Each vertex's uv from the scene surface of the first leaf that uses it (a back vertex: of its back
/// leaf); (0, 0) on surfaces without uv.
fn vertex_uvs(scene: &SceneDescription, geometry: &LeafGeometry, mesh: &Mesh, back: &[BackVertex]) -> Vec<Vec2> {
    let leaf_vertices = geometry.positions.len();
    let mut surface_of = vec![u32::MAX; mesh.positions.len()];
    for (leaf, tri) in geometry.triangles.iter().enumerate() {
        for &v in tri {
            if surface_of[v as usize] == u32::MAX {
                surface_of[v as usize] = geometry.surface[leaf];
            }
        }
    }
    for (k, b) in back.iter().enumerate() {
        surface_of[leaf_vertices + k] = geometry.surface.get(b.leaf as usize).copied().unwrap_or(u32::MAX);
    }
    mesh.positions
        .iter()
        .zip(&surface_of)
        .map(|(&p, &s)| match scene.surfaces.get(s as usize) {
            Some(surface) => match &surface.uvs {
                Some(uvs) if uvs.len() == surface.vertices.len() => surface_uv(&surface.vertices, uvs, p),
                _ => Vec2::ZERO,
            },
            None => Vec2::ZERO,
        })
        .collect()
}

/// Per-vertex values of the built mesh: the leaves' own vertices take `leaf_vertex_values`; each back
/// vertex the interpolation of its back leaf's corner values.
pub fn vertex_values(geometry: &LeafGeometry, leaf_vertex_values: &[Vec3], back: &[BackVertex]) -> Vec<Vec3> {
    let mut values = leaf_vertex_values.to_vec();
    values.extend(back.iter().map(|b| {
        let tri = geometry.triangles.get(b.leaf as usize).copied().unwrap_or([0; 3]);
        (0..3)
            .map(|k| leaf_vertex_values.get(tri[k] as usize).copied().unwrap_or(Vec3::ZERO) * b.weights[k])
            .sum::<Vec3>()
    }));
    values
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn barycentric_weights_rebuild_the_point() {
        let t = [Vec3::ZERO, Vec3::X, Vec3::Y];
        let p = Vec3::new(0.25, 0.5, 0.0);
        let w = barycentric(t, p);
        let back = t[0] * w[0] + t[1] * w[1] + t[2] * w[2];
        assert!((back - p).length() < 1e-6, "{back:?}");
    }

    #[test]
    fn a_back_vertex_takes_the_back_sides_interpolated_value() {
        // Two back leaves splitting the unit square along its diagonal; a point on that diagonal.
        let geometry = LeafGeometry {
            positions: vec![Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::Y],
            triangles: vec![[0, 2, 1], [0, 3, 2]],
            surface: vec![0, 0],
            back: vec![true, true],
        };
        let located = locate(&geometry, &[0, 1], Vec3::new(0.5, 0.5, 0.0)).expect("inside");
        let values = [Vec3::splat(0.0), Vec3::splat(4.0), Vec3::splat(2.0), Vec3::splat(8.0)];
        let v = vertex_values(&geometry, &values, &[located]);
        // Midpoint of corners 0 and 2: (0 + 2)/2 from either leaf.
        assert!((v[4] - Vec3::splat(1.0)).abs().max_element() < 1e-5, "{:?}", v[4]);
    }
}
