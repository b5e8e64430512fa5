//! Elements buried under one-sided surfaces: the floor under a block, the ceiling behind a lamp that
//! hangs just below it. Pass one sees the backs of one-sided surfaces as opaque, so such elements get
//! (correctly) almost no light; but they share vertices with visible neighbours, and Gouraud averaging
//! would pull those vertices dark. `Mesh::vertex_average` leaves buried elements out. An element
//! buried at its centre but partly open (it straddles the outline of what rests on it, or an object
//! pierces it) measures its value at an open point of it instead (`Mesh::element_eye`): otherwise the
//! light its open part receives and reflects is lost to the room.

use glam::Vec3;
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

/// Above this share of its hemisphere hidden (seen from its centre) an element that is not buried still
/// looks for an open point to measure at (`bury`): a quarter, 4 rays of 16. The floor element that
/// straddles the front of a bookcase whose open back stands against a wall sees the wall's front
/// through the back, so less than `BURIED_SHARE` of it is hidden, yet its centre lies inside and is
/// dark; measured there, the vertices on the outline took the mean of that and the lit floor, a dark
/// line along the bookcase's foot (living_room: 0.61 of the reference, docs/accuracy.md session 36).
/// At a sixteenth, stair_hall's radiosity view came out 1.7% worse; at a quarter it is unchanged.
pub const PARTLY_HIDDEN_SHARE: f32 = 0.25;

/// At most this share of the hemisphere hidden makes a point of a buried element open enough to
/// measure the element there (`bury`, unless a stranded vertex asks for less): one ray of 16. Strict on
/// purpose: inside a box whose open side stands against a wall, the floor near the wall sees the wall's
/// front through that side and only half its hemisphere ends on the box's backs, though no light gets
/// in (gap_room's cabinet).
pub const OPEN_SHARE: f32 = 1.0 / 16.0;

/// The share of element i's cosine-weighted hemisphere, seen from `point` on it lifted by 10⁻³ of its
/// size along the normal (where its hemicube's eye sits), that ends on the back of a one-sided opaque
/// surface (a one-sided dielectric's back lets light through, `Mesh::back_refracts`):
/// the fraction of 16 stratified cosine-distributed rays (u₁, u₂) ∈ {(a + ½)/4, (b + ½)/4} with
/// direction (√u₁ cos 2πu₂, √u₁ sin 2πu₂, √(1 − u₁)) in the element's frame. Deterministic.
pub fn hidden_share_at(mesh: &Mesh, accel: &Accel, i: usize, point: Vec3) -> f32 {
    let e = &mesh.elements;
    let n = e.normal[i];
    let origin = leave_surface(point, n, 1e-3 * e.area[i].sqrt());
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
                let element = mesh.triangle_element[tri] as usize;
                let front = e.normal[element];
                if dir.dot(front) > 0.0 && mesh.triangle_back_element[tri] == NONE && !mesh.back_refracts(element) {
                    hidden += 1;
                }
            }
        }
    }
    hidden as f32 / (RAYS_SIDE * RAYS_SIDE) as f32
}

/// `hidden_share_at` every element's centre; parallel over elements.
pub fn hidden_share(mesh: &Mesh, accel: &Accel) -> Vec<f32> {
    (0..mesh.elements.len()).into_par_iter().map(|i| hidden_share_at(mesh, accel, i, mesh.elements.centre[i])).collect()
}

/// How far from the centre towards a corner or an edge's midpoint the other eyes an element may take
/// lie (`open_eye`): inside the element, clear of its edges.
const EYE_REACH: f32 = 0.75;

/// An open point of element i, whose centre is buried: of the points c + 0.75·(q − c) for q its
/// corners and edge midpoints (c its centre), the first least hidden one, if at most `open_share`
/// of its hemisphere is hidden.
fn open_eye(mesh: &Mesh, accel: &Accel, i: usize, open_share: f32) -> Option<Vec3> {
    let centre = mesh.elements.centre[i];
    let corners: Vec<Vec3> = mesh.elements.polygon(&mesh.positions, i).collect();
    let midpoints = (0..corners.len()).map(|k| (corners[k] + corners[(k + 1) % corners.len()]) * 0.5);
    let candidates = corners.iter().copied().chain(midpoints).map(|q| centre + (q - centre) * EYE_REACH);
    let (share, point) = candidates
        .map(|p| (hidden_share_at(mesh, accel, i, p), p))
        .fold((f32::INFINITY, centre), |best, next| if next.0 < best.0 { next } else { best });
    (share <= open_share).then_some(point)
}

/// `Mesh::element_buried` and `Mesh::element_eye` for `mesh`. An element is buried when more than
/// `BURIED_SHARE` of its hemisphere, seen from its centre, is hidden (`hidden_share`). Where every
/// element at a vertex is buried, the vertex takes the buried values (`Mesh::vertex_average`); that is
/// right inside a block's footprint, which nobody sees, but where the vertex itself is open the
/// surface's visible part around it draws as dark as the inside of what buries it: a capital whose
/// underside is pierced by its column at every element's centre. A buried element with such an open,
/// stranded vertex (open: `hidden_share_at` a point 2% of the way from it to the centre) measures its
/// value at a point of it where at most `BURIED_SHARE` is hidden instead (`open_eye`) and is not
/// buried. So does any other buried element with a point where at most `OPEN_SHARE` is hidden: one
/// that straddles the outline of what rests on it. Its centre sees no light, but its open part lies in
/// the seam beside the object, often the brightest strip of the surface (a ceiling beside a fixture's
/// glowing sides); measured at the centre, that strip's reflected light was lost to the whole room
/// (fixture_room's uniform mesh 3.7% dark; docs/accuracy.md, session 32). So, too, does an element
/// that is not buried but more than `PARTLY_HIDDEN_SHARE` hidden at its centre (it straddles the
/// outline of a box open at the back against a wall, whose inside sees the wall's front). Elements
/// wholly under a block have no such point and stay as they are. `element_eye` is empty when no eye
/// moved.
pub fn bury(mesh: &Mesh) -> (Vec<bool>, Vec<Vec3>) {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    let shares = hidden_share(mesh, &accel);
    let mut buried: Vec<bool> = shares.iter().map(|&s| s > BURIED_SHARE).collect();
    let mut open_at_vertex = vec![false; mesh.positions.len()];
    for (e, corners) in mesh.elements.corners.iter().enumerate() {
        for &v in corners.iter().filter(|&&v| v != NONE) {
            open_at_vertex[v as usize] |= !buried[e];
        }
    }
    let stranded = |e: usize| {
        let centre = mesh.elements.centre[e];
        mesh.elements.corners[e].iter().filter(|&&v| v != NONE && !open_at_vertex[v as usize]).any(|&v| {
            let corner = mesh.positions[v as usize];
            hidden_share_at(mesh, &accel, e, corner + (centre - corner) * 0.02) <= BURIED_SHARE
        })
    };
    let candidates: Vec<usize> = (0..buried.len()).filter(|&e| shares[e] > PARTLY_HIDDEN_SHARE).collect();
    let eyes: Vec<(usize, Vec3)> = candidates
        .par_iter()
        .filter_map(|&e| {
            let open_share = if buried[e] && stranded(e) { BURIED_SHARE } else { OPEN_SHARE };
            open_eye(mesh, &accel, e, open_share).map(|p| (e, p))
        })
        .collect();
    if eyes.is_empty() {
        return (buried, Vec::new());
    }
    let mut eye = mesh.elements.centre.clone();
    for (e, p) in eyes {
        eye[e] = p;
        buried[e] = false;
    }
    (buried, eye)
}

/// `Mesh::element_buried` for `mesh`: elements whose `hidden_share` exceeds `BURIED_SHARE`.
/// (Centres only, no eyes moved: `bury` is what the methods use.)
pub fn buried_elements(mesh: &Mesh) -> Vec<bool> {
    let accel = Accel::build(&mesh.positions, &mesh.triangles);
    hidden_share(mesh, &accel).into_iter().map(|s| s > BURIED_SHARE).collect()
}
