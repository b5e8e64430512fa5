//! Where the adaptive mesh is refined: elements whose light varies across them, measured by how far
//! their corners' interpolated irradiance is from their own, scaled by their albedo into the exitance
//! the image shows, relative to the element's own exitance (Cohen, Greenberg, Immel and Brock 1986:
//! subdivide where radiosity gradients are large). Irradiance, not exitance, so that a texture's
//! contrast between neighbouring elements is not taken for a gradient of the light.

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

/// The length of element e's longest edge.
fn longest_edge(mesh: &Mesh, e: usize) -> f32 {
    let p: Vec<Vec3> = mesh.elements.polygon(&mesh.positions, e).collect();
    (0..p.len()).map(|k| (p[k] - p[(k + 1) % p.len()]).length()).fold(0.0, f32::max)
}

/// Per element e, how far the values V interpolated at its corners k are from its own, each channel c
/// scaled by `scale`ₑ (1 when `scale` is `None`):
///   δₑ = max_k max_c sₑ,c · |V_v(k),c − Vₑ,c|.
/// With V the exitance B and no scale this is the exitance variation |B_v − Bₑ|; with V the irradiance
/// H (`reflected_irradiance`) and s the albedo ρ̄ₑ it is the irradiance variation ρ̄ₑ·|H_v − Hₑ| (see
/// `irradiance_variation`). Corners `NONE` are skipped.
pub fn variation(mesh: &Mesh, element_values: &[Vec3], vertex_values: &[Vec3], scale: Option<&[Vec3]>) -> Vec<f32> {
    (0..mesh.elements.len())
        .map(|e| {
            let s = scale.map_or(Vec3::ONE, |s| s[e]);
            mesh.elements.corners[e]
                .iter()
                .filter(|&&v| v != crate::mesh::NONE)
                .map(|&v| (s * (vertex_values[v as usize] - element_values[e]).abs()).max_element())
                .fold(0.0, f32::max)
        })
        .collect()
}

/// The variation (`variation`) of the light across each element of `mesh`, in exitance units:
///   δₑ = max_k max_c ρ̄ₑ,c · |H_v(k),c − Hₑ,c|,   Hₑ = (Bₑ − Eₑ)/ρ̄ₑ  (0 where ρ̄ₑ,c = 0),
/// Hₑ the irradiance element e reflected (`irradiance::element_irradiance`, ρ̄ₑ its mean albedo) and
/// H_v its vertex values made by the vertex step the exitance takes (`hanging::conforming_vertex_values`:
/// `vertex_step`'s means within smoothing groups and extrapolated outline, then the `hanging` vertices
/// given their edge's value).
/// On a textured surface Bₑ = Eₑ + ρ̄ₑ·Hₑ differs between neighbours by the texture's contrast even
/// where the light is flat; Hₑ does not. The image shows ρ(x)·H(p), so ρ̄ₑ·|H_v − Hₑ| is the error
/// the element's interpolation makes in the exitance it shows, and relative to that exitance it is
/// |H_v − Hₑ|/Hₑ whatever the albedo. Where ρ and E are uniform over a smoothing group (a group never
/// crosses a change of material), Hₑ = (Bₑ − E)/ρ and the vertex step is linear and positively
/// homogeneous per channel (means, least-squares gradients, range limits), so H_v = (B_v − E)/ρ and
/// δₑ = |B_v − Bₑ|: the exitance variation, to rounding (up to the B ≥ 0 limit of an extrapolated
/// vertex, which reads B − E ≥ 0 on an emitter).
pub fn irradiance_variation(
    mesh: &Mesh,
    element_exitance: &[Vec3],
    vertex_step: &crate::radiosity::smooth_mesh::SmoothMesh,
    hanging: &[super::hanging::Hanging],
) -> Vec<f32> {
    let element = crate::radiosity::irradiance::element_irradiance(mesh, element_exitance, true);
    let vertex = super::hanging::conforming_vertex_values(vertex_step, &element, hanging);
    let element: Vec<Vec3> = element.iter().map(|h| h.as_vec3()).collect();
    variation(mesh, &element, &vertex, Some(&mesh.elements.reflectance))
}

/// Splits element e when its variation (`variation`, in exitance units: `irradiance_variation`)
///   δₑ > τ · max(max_channel Bₑ, f · B_ref)
/// (Bₑ its own exitance, τ = `threshold`, B_ref = `brightest_reflected_exitance`, f = `floor`): the
/// variation is measured relative to the element's own exitance (the image's error is judged relative
/// to its brightness), but never below the fraction f of the brightest, so dark corners are not
/// refined for noise. Only when `splittable[e]` and its longest edge is at least twice `min_edge`
/// (its children stay at or above it). A vertex value is the area-weighted mean of the elements
/// around it, so this also measures the differences between neighbours: large at shadow boundaries
/// and in concave corners, nil where the light is flat.
pub fn elements_to_split(
    mesh: &Mesh,
    element_exitance: &[Vec3],
    variation: &[f32],
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
            if longest_edge(mesh, e) < 2.0 * min_edge {
                return false;
            }
            variation[e] > limit
        })
        .collect()
}

/// Refinement carried across concave edges: marks for splitting every element e that may be split
/// (`splittable`, longest edge at least twice `min_edge`) and faces, across a concave corner, an
/// element s of another surface that `split` already marks — the two touch (their bounding spheres
/// about their centres overlap), are not coplanar (|nₑ·nₛ| < 0.99) and each lies in front of the
/// other ((cₛ − cₑ)·nₑ > 0 and (cₑ − cₛ)·nₛ > 0). Where a surface's exitance runs steeply into a
/// concave edge (the ceiling above a wall lamp, dark at the wall), the surface across the edge sees it
/// at grazing angles and its exitance dips within a fraction of an element of the edge, though its
/// own elements' values are flat; only smaller elements there show the dip. One step: elements
/// marked here do not carry the marking further. It reads no solution values (only the marks and
/// the geometry), so it follows whatever criterion made `split`.
pub fn across_concave_edges(mesh: &Mesh, split: &[bool], min_edge: f32, splittable: &[bool]) -> Vec<bool> {
    let e = &mesh.elements;
    let radius: Vec<f32> = (0..e.len())
        .map(|i| e.polygon(&mesh.positions, i).map(|p| (p - e.centre[i]).length()).fold(0.0, f32::max))
        .collect();
    let cell = 2.0 * radius.iter().copied().fold(0.0, f32::max);
    let mut out = split.to_vec();
    if !(cell > 0.0) || !split.iter().any(|&s| s) {
        return out;
    }
    let key = |p: Vec3| (p / cell).floor().as_ivec3();
    let mut grid: rustc_hash::FxHashMap<glam::IVec3, Vec<u32>> = Default::default();
    for s in (0..e.len()).filter(|&s| split[s]) {
        grid.entry(key(e.centre[s])).or_default().push(s as u32);
    }
    for i in 0..e.len() {
        if split[i] || !splittable[i] || longest_edge(mesh, i) < 2.0 * min_edge {
            continue;
        }
        let k = key(e.centre[i]);
        let touches = (-1..=1).flat_map(|x| (-1..=1).flat_map(move |y| (-1..=1).map(move |z| glam::ivec3(x, y, z))));
        let facing = touches.filter_map(|o| grid.get(&(k + o))).flatten().any(|&s| {
            let s = s as usize;
            let d = e.centre[s] - e.centre[i];
            e.surface[s] != e.surface[i]
                && d.length() < radius[i] + radius[s]
                && e.normal[i].dot(e.normal[s]).abs() < 0.99
                && d.dot(e.normal[i]) > 0.0
                && d.dot(e.normal[s]) < 0.0
        });
        if facing {
            out[i] = true;
        }
    }
    out
}

/// `across_concave_edges` seeded with the emitting elements too: an element that faces an emitter
/// across a concave edge (a table top at the foot of a glowing lamp standing on it) is split, since
/// its light runs steeply up to the emitter's foot though its own value, measured at its centre, and
/// its neighbours' may agree: living_room's side table was four elements of one value beside the lamp,
/// which drew its visible rim 2× too bright (radiosity mode 8.7e-4 → 5.2e-4 with this rule, at the
/// same CPU time; docs/accuracy.md, session 33). Emitters themselves are split only where `split`
/// says.
pub fn across_concave_edges_and_emitters(mesh: &Mesh, split: &[bool], min_edge: f32, splittable: &[bool]) -> Vec<bool> {
    let emitting: Vec<bool> = mesh.elements.emission.iter().map(|x| x.max_element() > 0.0).collect();
    let seeds: Vec<bool> = split.iter().zip(&emitting).map(|(&s, &lit)| s || lit).collect();
    let carried = across_concave_edges(mesh, &seeds, min_edge, splittable);
    carried.iter().zip(split).zip(&emitting).map(|((&c, &s), &lit)| s || (c && !lit)).collect()
}
