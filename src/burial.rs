//! Elements buried under one-sided surfaces: the floor under a block, the ceiling behind a lamp that
//! hangs just below it. Pass one sees the backs of one-sided surfaces as opaque, so such elements get
//! (correctly) almost no light; but they share vertices with visible neighbours, and Gouraud averaging
//! would pull those vertices dark. `Mesh::vertex_average` leaves buried elements out.

use rayon::prelude::*;

use crate::accel::Accel;
use crate::mesh::{Mesh, NONE};
use crate::transport::hit::leave_surface;

/// Rays per element: a stratified 4 × 4 cosine-weighted grid over its hemisphere.
const RAYS_SIDE: usize = 4;

/// Above this share of its cosine-weighted hemisphere hidden by back faces an element counts as
/// buried (`Mesh::element_buried`): it is then mostly inside or under something, and its radiosity
/// does not describe the visible surface around it.
pub const BURIED_SHARE: f32 = 0.5;

/// The share of each element's cosine-weighted hemisphere, seen from its centre lifted by 10⁻³ of its
/// size along the normal (where its hemicube's eye sits), that ends on the back of a one-sided surface:
/// the fraction of 16 stratified cosine-distributed rays (u₁, u₂) ∈ {(a + ½)/4, (b + ½)/4} with
/// direction (√u₁ cos 2πu₂, √u₁ sin 2πu₂, √(1 − u₁)) in the element's frame. Deterministic; parallel
/// over elements.
pub fn hidden_share(mesh: &Mesh, accel: &Accel) -> Vec<f32> {
    let e = &mesh.elements;
    (0..e.len())
        .into_par_iter()
        .map(|i| {
            let n = e.normal[i];
            let origin = leave_surface(e.centre[i], n, 1e-3 * e.area[i].sqrt());
            let (t, b) = n.any_orthonormal_pair();
            let mut hidden = 0usize;
            for a in 0..RAYS_SIDE {
                for c in 0..RAYS_SIDE {
                    let u1 = (a as f32 + 0.5) / RAYS_SIDE as f32;
                    let u2 = (c as f32 + 0.5) / RAYS_SIDE as f32;
                    let (r, phi) = (u1.sqrt(), std::f32::consts::TAU * u2);
                    let dir = (t * (r * phi.cos()) + b * (r * phi.sin()) + n * (1.0 - u1).sqrt()).normalize();
                    if let Some(hit) = accel.closest_hit(origin, dir, 0.0, f32::INFINITY) {
                        let tri = hit.triangle as usize;
                        let front = e.normal[mesh.triangle_element[tri] as usize];
                        if dir.dot(front) > 0.0 && mesh.triangle_back_element[tri] == NONE {
                            hidden += 1;
                        }
                    }
                }
            }
            hidden as f32 / (RAYS_SIDE * RAYS_SIDE) as f32
        })
        .collect()
}

/// `Mesh::element_buried` for `mesh`: elements whose `hidden_share` exceeds `BURIED_SHARE`.
pub fn buried_elements(mesh: &Mesh) -> Vec<bool> {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    hidden_share(mesh, &accel).into_iter().map(|s| s > BURIED_SHARE).collect()
}
