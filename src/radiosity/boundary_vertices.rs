//! Vertex values on the boundary of a surface, extrapolated from the elements inside instead of
//! averaged: Gouraud's area-weighted vertex mean is the value half an element in from the boundary, so
//! wherever the solution runs to a surface's edge with a slope (the ceiling beside a wall lamp, whose
//! direct light falls to zero at the wall) the boundary row of the image is too bright or too dark by
//! half an element's change. The extrapolation is exact for a linear solution (Cohen and Wallace,
//! *Radiosity and Realistic Image Synthesis*, 1993, §9.2: nodal values at boundaries by extrapolation).
//! Inside a surface the mean is corrected to first order where its elements do not sit symmetrically
//! about the vertex (`centroid_correction`: refinement boundaries of the adaptive mesh, triangles beside
//! quads), so a linear solution is exact at every vertex of any mesh. `vertex_values` is the one
//! vertex-interpolation step of the element meshes: the uniform and adaptive `Mesh`, and the
//! hierarchy's leaf mesh (`hierarchy::interpolate::LeafMesh`), each through `ElementMesh`.

use glam::{DMat3, DVec3, Vec3};

use crate::mesh::{Mesh, NONE};

/// What the vertex step reads of an element mesh: shared vertices, and per element its corners,
/// plane, weight and surface side.
pub trait ElementMesh {
    /// Vertex positions (shared by the elements of one surface side).
    fn positions(&self) -> &[Vec3];
    fn element_count(&self) -> usize;
    /// Element e's corners (indices into `positions`), counter-clockwise, `NONE` past the last.
    fn corners(&self, e: usize) -> [u32; 4];
    /// Element e's centroid: where its value is taken to hold.
    fn centre(&self, e: usize) -> Vec3;
    /// Element e's unit normal.
    fn normal(&self, e: usize) -> Vec3;
    /// Element e's weight in a vertex's mean and extrapolation: its area (m²), or the part of it light
    /// can reach.
    fn weight(&self, e: usize) -> f64;
    /// The surface side element e lies on: a fit reads only neighbours on the same side.
    fn surface(&self, e: usize) -> u32;
    /// Element e is never seen (buried under the back of a one-sided surface, or inside an object
    /// resting on it): its value is not the surface's light, so it stays out of fits and limits.
    fn buried(&self, e: usize) -> bool;
    /// Every weight is its element's whole area, so that the weighted mean of the centres is the
    /// centroid of the light the mean reads (`centroid_correction` needs it). Not where weights are
    /// open parts of elements (the hierarchy's leaves), whose centroids are not known.
    fn weights_are_areas(&self) -> bool {
        true
    }
    /// T-junctions between the pieces of one plane (`t_junctions`): (vertex, element) pairs where the
    /// vertex lies inside one of the element's edges and is no vertex of the element's own surface.
    /// Only the fits read them: the element counts the elements at those vertices as its neighbours,
    /// and they count it. Means, extrapolation and pass two's interpolation keep to corners.
    fn contacts(&self) -> &[(u32, u32)] {
        &[]
    }
    /// The surface whose elements element e's fit reads (`surface`, or wider: pieces of one plane that
    /// meet at T-junctions, `contacts`).
    fn fit_surface(&self, e: usize) -> u32 {
        self.surface(e)
    }
    /// Element e's fit reads neighbour n (on its fit surface), whose value is `values[n]`: always on
    /// e's own surface; across a T-junction only where the two agree (no step lies on the junction).
    fn fit_reads(&self, _e: usize, _n: usize, _values: &[Vec3]) -> bool {
        true
    }
    /// Interior vertex values: the `weight`-weighted mean of the unburied elements around each vertex
    /// (Gouraud), the mean of the buried ones where there are only those.
    fn vertex_mean(&self, element_values: &[DVec3]) -> Vec<DVec3>;
}

impl ElementMesh for Mesh {
    fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    fn element_count(&self) -> usize {
        self.elements.len()
    }

    fn corners(&self, e: usize) -> [u32; 4] {
        self.elements.corners[e]
    }

    fn centre(&self, e: usize) -> Vec3 {
        self.elements.centre[e]
    }

    fn normal(&self, e: usize) -> Vec3 {
        self.elements.normal[e]
    }

    fn weight(&self, e: usize) -> f64 {
        self.elements.area[e] as f64
    }

    fn surface(&self, e: usize) -> u32 {
        self.elements.surface[e]
    }

    fn buried(&self, e: usize) -> bool {
        self.element_buried.get(e).copied().unwrap_or(false)
    }

    fn vertex_mean(&self, element_values: &[DVec3]) -> Vec<DVec3> {
        self.vertex_average(element_values)
    }
}

/// Per vertex: it lies on the boundary of its surface side. An element edge is a boundary edge when no
/// other element of the mesh uses it. Edges are first cut at their split midpoints (`midpoint(a, b)`,
/// recursively; `|_, _| None` on a mesh without T-vertices), so that an unsplit element's edge and its
/// split neighbour's two half edges count as one shared edge.
pub fn boundary_vertices<M: ElementMesh + ?Sized>(mesh: &M, midpoint: &dyn Fn(u32, u32) -> Option<u32>) -> Vec<bool> {
    let mut uses: rustc_hash::FxHashMap<(u32, u32), u32> = Default::default();
    let mut stack = Vec::new();
    for e in 0..mesh.element_count() {
        let c = mesh.corners(e);
        let n = c.iter().take_while(|&&v| v != NONE).count();
        for k in 0..n {
            stack.push((c[k], c[(k + 1) % n]));
            while let Some((a, b)) = stack.pop() {
                match midpoint(a, b) {
                    Some(m) => {
                        stack.push((a, m));
                        stack.push((m, b));
                    }
                    None => *uses.entry((a.min(b), a.max(b))).or_insert(0) += 1,
                }
            }
        }
    }
    once_used(uses, mesh.positions().len())
}

/// Per vertex: it lies on the boundary of its surface side, with every element edge cut at the
/// vertices `inside(a, b)` lists strictly inside it (all of them, ordered from a to b; `None` for
/// none): two pieces whose corners lie inside each other's edges then cut their shared line at the
/// same points, and each piece of it is used twice.
pub fn boundary_vertices_cut<M: ElementMesh + ?Sized>(
    mesh: &M,
    inside: &dyn Fn(u32, u32) -> Option<Vec<u32>>,
) -> Vec<bool> {
    let mut uses: rustc_hash::FxHashMap<(u32, u32), u32> = Default::default();
    for e in 0..mesh.element_count() {
        let c = mesh.corners(e);
        let n = c.iter().take_while(|&&v| v != NONE).count();
        for k in 0..n {
            let (a, b) = (c[k], c[(k + 1) % n]);
            let mut from = a;
            for to in inside(a, b).unwrap_or_default().into_iter().chain(std::iter::once(b)) {
                *uses.entry((from.min(to), from.max(to))).or_insert(0) += 1;
                from = to;
            }
        }
    }
    once_used(uses, mesh.positions().len())
}

/// Per vertex (of `count`): it ends a segment of `uses` used once.
fn once_used(uses: rustc_hash::FxHashMap<(u32, u32), u32>, count: usize) -> Vec<bool> {
    let mut boundary = vec![false; count];
    for ((a, b), count) in uses {
        if count == 1 {
            boundary[a as usize] = true;
            boundary[b as usize] = true;
        }
    }
    boundary
}

/// The boundary vertices of a mesh without T-vertices (the uniform mesh: one shared-vertex grid per
/// surface side, `Mesh::build`): `boundary_vertices` with no split edges.
pub fn conforming_boundary<M: ElementMesh + ?Sized>(mesh: &M) -> Vec<bool> {
    boundary_vertices(mesh, &|_, _| None)
}

/// Per-vertex values of per-element values B_e, as pass two interpolates them: the weighted mean over
/// the unburied elements around a vertex (`ElementMesh::vertex_mean`, Gouraud) inside each surface
/// side, corrected for the lean of their centroid (`centroid_correction`), and the clamped linear
/// extrapolation of `extrapolate` at the vertices marked `boundary`.
/// Every pass-one method on element meshes (matrix, matrix-free, adaptive, hierarchical) makes its
/// vertex values here.
pub fn vertex_values<M: ElementMesh + ?Sized>(mesh: &M, element_values: &[DVec3], boundary: &[bool]) -> Vec<Vec3> {
    let mut vertex: Vec<Vec3> = mesh.vertex_mean(element_values).iter().map(|v| v.as_vec3()).collect();
    let element: Vec<Vec3> = element_values.iter().map(|v| v.as_vec3()).collect();
    centroid_correction(mesh, &element, boundary, &mut vertex);
    extrapolate(mesh, &element, boundary, &mut vertex);
    vertex
}

/// Below this offset of a vertex's element centroid (a fraction of the distance to its farthest
/// element centre) the mean is taken as centred: a symmetric star (a grid's inside) to rounding.
const CENTRED: f64 = 1e-3;

/// Corrects the weighted mean at every interior vertex (not `boundary`) for where its elements sit:
///   B_v = B̄ − ḡ·(c̄ − p_v),  limited to [lo, hi] of the elements around v and to B ≥ 0,
/// with B̄ = Σₑ wₑBₑ / Σₑ wₑ the `vertex_mean` over the unburied elements e around v, c̄ = Σₑ wₑcₑ / Σₑ wₑ
/// their weighted centroid, and ḡ the weighted mean of their least-squares gradients (`linear_fit`).
/// The mean of a linear field is its value at c̄, not at p_v: where the elements around a vertex are
/// alike (inside a grid) c̄ = p_v and the mean stands, but where sizes change (an adaptive mesh's
/// refinement boundary, where a coarse element's centre lies twice as far as a fine one's and weighs
/// four times as much; a triangle beside a quad) c̄ leans towards the larger elements and the mean is
/// off by the slope times that lean: a ridge along every refinement boundary. The correction is
/// exact for linear fields on any mesh and leaves the mean's treatment of curvature alone (the
/// final gather reads these values, and a full per-element extrapolation at every vertex, tried in
/// session 34, made final images 6–20% worse while it improved the radiosity view).
pub fn centroid_correction<M: ElementMesh + ?Sized>(
    mesh: &M,
    element_values: &[Vec3],
    boundary: &[bool],
    vertex_values: &mut [Vec3],
) {
    if !mesh.weights_are_areas() {
        return;
    }
    let at_vertex = ElementsAtVertex::new(mesh);
    let mut fits: Vec<Option<Option<(DMat3, DVec3, DVec3)>>> = vec![None; mesh.element_count()];
    for v in (0..mesh.positions().len()).filter(|&v| !boundary[v]) {
        let around = at_vertex.elements[at_vertex.start[v] as usize..at_vertex.start[v + 1] as usize]
            .iter()
            .map(|&e| e as usize)
            .filter(|&e| !mesh.buried(e));
        let p = mesh.positions()[v].as_dvec3();
        let (mut centroid, mut weight, mut reach) = (DVec3::ZERO, 0.0f64, 0.0f64);
        let (mut lo, mut hi) = (DVec3::splat(f64::MAX), DVec3::splat(f64::MIN));
        for e in around.clone() {
            let (c, b) = (mesh.centre(e).as_dvec3(), element_values[e].as_dvec3());
            centroid += c * mesh.weight(e);
            weight += mesh.weight(e);
            reach = reach.max(c.distance(p));
            lo = lo.min(b);
            hi = hi.max(b);
        }
        if !(weight > 0.0) {
            continue;
        }
        let lean = centroid / weight - p;
        if lean.length() <= CENTRED * reach {
            continue;
        }
        let (mut change, mut fitted) = (DVec3::ZERO, 0.0f64);
        for e in around {
            let fit =
                fits[e].get_or_insert_with(|| linear_fit(mesh, element_values, e, &at_vertex.neighbours(mesh, e)));
            if let Some((gradient, _, _)) = fit {
                change += gradient.transpose() * lean * mesh.weight(e);
                fitted += mesh.weight(e);
            }
        }
        if fitted > 0.0 {
            let mean = vertex_values[v].as_dvec3();
            vertex_values[v] = (mean - change / fitted).clamp(lo, hi).max(DVec3::ZERO).as_vec3();
        }
    }
}

/// The elements at each vertex, in increasing order, as flat lists: vertex v's are
/// `elements[start[v]..start[v + 1]]`, those it is a corner of; `fit_*` the same with the elements whose
/// edge it lies on (`ElementMesh::contacts`), for the fits; and each element's T-junction vertices,
/// `touching[touch_start[e]..touch_start[e + 1]]`.
struct ElementsAtVertex {
    start: Vec<u32>,
    elements: Vec<u32>,
    fit_start: Vec<u32>,
    fit_elements: Vec<u32>,
    touch_start: Vec<u32>,
    touching: Vec<u32>,
}

/// Pairs (key, item) as a flat list grouped by key (`count` keys): key k's items, in increasing order,
/// are `items[start[k]..start[k + 1]]`.
fn grouped(mut pairs: Vec<(u32, u32)>, count: usize) -> (Vec<u32>, Vec<u32>) {
    pairs.sort_unstable();
    pairs.dedup();
    let mut start = vec![0u32; count + 1];
    for &(k, _) in &pairs {
        start[k as usize + 1] += 1;
    }
    for k in 0..count {
        start[k + 1] += start[k];
    }
    (start, pairs.into_iter().map(|(_, item)| item).collect())
}

impl ElementsAtVertex {
    fn new<M: ElementMesh + ?Sized>(mesh: &M) -> Self {
        let corners: Vec<(u32, u32)> = (0..mesh.element_count())
            .flat_map(|e| mesh.corners(e).into_iter().filter(|&v| v != NONE).map(move |v| (v, e as u32)))
            .collect();
        let vertices = mesh.positions().len();
        let with_contacts = corners.iter().chain(mesh.contacts()).copied().collect();
        let (start, elements) = grouped(corners, vertices);
        let (fit_start, fit_elements) = grouped(with_contacts, vertices);
        let (touch_start, touching) =
            grouped(mesh.contacts().iter().map(|&(v, e)| (e, v)).collect(), mesh.element_count());
        ElementsAtVertex { start, elements, fit_start, fit_elements, touch_start, touching }
    }

    /// Element e's corners, then the vertices of other pieces on its edges.
    fn vertices_of<M: ElementMesh + ?Sized>(&self, mesh: &M, e: usize) -> impl Iterator<Item = u32> + '_ {
        let touching = &self.touching[self.touch_start[e] as usize..self.touch_start[e + 1] as usize];
        mesh.corners(e).into_iter().filter(|&v| v != NONE).chain(touching.iter().copied())
    }

    /// The elements of element e's fit surface (`ElementMesh::fit_surface`) that share a vertex with it,
    /// or touch it at a T-junction (itself and buried elements excluded: they are never seen and their
    /// values are not the surface's light), in increasing order.
    fn neighbours<M: ElementMesh + ?Sized>(&self, mesh: &M, e: usize) -> Vec<u32> {
        let surface = mesh.fit_surface(e);
        let mut around: Vec<u32> = self
            .vertices_of(mesh, e)
            .flat_map(|v| {
                self.fit_elements[self.fit_start[v as usize] as usize..self.fit_start[v as usize + 1] as usize].iter()
            })
            .copied()
            .filter(|&n| n as usize != e && mesh.fit_surface(n as usize) == surface && !mesh.buried(n as usize))
            .collect();
        around.sort_unstable();
        around.dedup();
        around
    }
}

/// The linear reconstruction of element e's neighbourhood: the in-plane gradient g (one per channel,
/// as the columns of a matrix) minimising Σₙ (Bₙ − Bₑ − g·(cₙ − cₑ))² over the neighbours n (centres
/// cₙ), with no component along the normal; and the range [lo, hi] of B over e and its neighbours.
/// `None` when the neighbours do not span the plane (fewer than two directions).
fn linear_fit<M: ElementMesh + ?Sized>(
    mesh: &M,
    values: &[Vec3],
    e: usize,
    around: &[u32],
) -> Option<(DMat3, DVec3, DVec3)> {
    let centre = mesh.centre(e).as_dvec3();
    let normal = mesh.normal(e).as_dvec3();
    let own = values[e].as_dvec3();
    let (mut m, mut r) = (DMat3::ZERO, DMat3::ZERO);
    let (mut lo, mut hi) = (own, own);
    for &n in around.iter().filter(|&&n| mesh.fit_reads(e, n as usize, values)) {
        let d = mesh.centre(n as usize).as_dvec3() - centre;
        let d = d - normal * d.dot(normal);
        let b = values[n as usize].as_dvec3();
        lo = lo.min(b);
        hi = hi.max(b);
        m += DMat3::from_cols(d * d.x, d * d.y, d * d.z);
        let db = b - own;
        r += DMat3::from_cols(d * db.x, d * db.y, d * db.z);
    }
    // The normal direction carries no data: pin it with the trace, so that M is invertible exactly
    // when the neighbours span the plane.
    let trace = m.x_axis.x + m.y_axis.y + m.z_axis.z;
    let m = m + DMat3::from_cols(normal * normal.x, normal * normal.y, normal * normal.z) * trace;
    let det = m.determinant();
    if !(det > 1e-9 * trace * trace * trace) {
        return None;
    }
    Some((m.inverse() * r, lo, hi))
}

/// Replaces the value of every boundary vertex (`boundary`) by the weighted (`ElementMesh::weight`) mean, over its
/// elements e that are not buried, of e's linear extrapolation
///   B_v = Bₑ + gₑ·(p_v − cₑ),  limited to [lo − (hi − lo)/2, hi + (hi − lo)/2] and to B ≥ 0,
/// with gₑ, lo and hi from `linear_fit`. The limit allows exactly the half-element overshoot of a
/// linear solution beyond its neighbours' range and stops a shadow boundary's step from being
/// extrapolated into a spike. Elements whose neighbours do not span their plane give their own value.
/// Interior vertices keep their value.
pub fn extrapolate<M: ElementMesh + ?Sized>(
    mesh: &M,
    element_values: &[Vec3],
    boundary: &[bool],
    vertex_values: &mut [Vec3],
) {
    assert_eq!(element_values.len(), mesh.element_count());
    assert_eq!(vertex_values.len(), mesh.positions().len());
    if !boundary.iter().any(|&b| b) {
        return;
    }
    let at_vertex = ElementsAtVertex::new(mesh);
    let mut sum = vec![DVec3::ZERO; mesh.positions().len()];
    let mut weight = vec![0.0f64; mesh.positions().len()];
    for e in 0..mesh.element_count() {
        if mesh.buried(e) {
            continue;
        }
        let corners = mesh.corners(e);
        if !corners.iter().any(|&v| v != NONE && boundary[v as usize]) {
            continue;
        }
        let fit = linear_fit(mesh, element_values, e, &at_vertex.neighbours(mesh, e));
        let own = element_values[e].as_dvec3();
        let area = mesh.weight(e);
        for &v in corners.iter().filter(|&&v| v != NONE && boundary[v as usize]) {
            let value = match fit {
                Some((gradient, lo, hi)) => {
                    let d = mesh.positions()[v as usize].as_dvec3() - mesh.centre(e).as_dvec3();
                    let spread = (hi - lo) * 0.5;
                    (own + gradient.transpose() * d).clamp(lo - spread, hi + spread).max(DVec3::ZERO)
                }
                None => own,
            };
            sum[v as usize] += value * area;
            weight[v as usize] += area;
        }
    }
    for v in 0..vertex_values.len() {
        if boundary[v] && weight[v] > 0.0 {
            vertex_values[v] = (sum[v] / weight[v]).as_vec3();
        }
    }
}
