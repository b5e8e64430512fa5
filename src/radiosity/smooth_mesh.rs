//! The uniform or adaptive `Mesh` as its vertex step sees it: elements grouped into smoothing groups
//! (`smoothing_groups`), and within a group the vertices at one point welded into one. `Mesh` shares
//! vertices only inside one scene surface, and every facet of a tessellated object (a `[[sphere]]`, a
//! statue from an OBJ file) is its own surface: averaged and extrapolated per surface, its values
//! jump at every facet edge and the object renders as flat bands. Welded, a vertex on a smooth facet
//! edge takes the mean of the elements on both sides, and only a group's outline (a crease, a material
//! change, an open edge) is extrapolated. A box's faces are groups of one surface each, so their
//! vertex values do not change. Coplanar pieces of a group (a floor cut along furniture, a quad split
//! into triangles) weld at a point only where their own values agree: a sharp shadow edge lying on
//! their border stays a step (`SmoothMesh::vertex_values`); facets of a curved surface always weld.
//! Pieces of one plane that meet at T-junctions instead of shared edges (a wall written as upright
//! strips beside a stair, or as pieces round a door: `t_junctions`) stay groups of their own, but each
//! element's linear fit reads its neighbours across the junction (`ElementMesh::fit_surface`,
//! `contacts`), so that a strip one element wide still has a slope across it: without it, it shows as
//! a flat band.

use glam::{DVec3, Vec3};
use rustc_hash::FxHashMap;

use super::boundary_vertices::{self, ElementMesh};
use super::smoothing_groups::{join, root, smoothing_groups, Facet};
use super::t_junctions::{t_junction_families, vertices_inside_edges};
use crate::mesh::{Mesh, NONE};

/// Points closer than this fraction of the mesh's extent (per axis) are one point: the mesher puts the
/// grid points on an edge two facets share at their own interpolation of the corners, which agree to
/// a few ulps, not bit for bit.
const WELD_TOLERANCE: f32 = 1e-6;

/// Points as ids, points within `tolerance` of each other (per axis) taking one id: a hash grid of
/// cells ten tolerances wide, a point looked up in every cell its tolerance box touches.
struct PointIds {
    tolerance: f32,
    cell: f32,
    cells: FxHashMap<[i64; 3], Vec<u32>>,
    points: Vec<Vec3>,
}

impl PointIds {
    fn new(extent: f32) -> Self {
        let tolerance = (extent * WELD_TOLERANCE).max(f32::MIN_POSITIVE);
        PointIds { tolerance, cell: tolerance * 10.0, cells: FxHashMap::default(), points: Vec::new() }
    }

    fn cell_of(&self, x: f32) -> i64 {
        (x / self.cell).floor() as i64
    }

    /// The id of a point within the tolerance of `p`, if any.
    fn find(&self, p: Vec3) -> Option<u32> {
        let t = self.tolerance;
        let (lo, hi) = ((p - Vec3::splat(t)).to_array(), (p + Vec3::splat(t)).to_array());
        for x in self.cell_of(lo[0])..=self.cell_of(hi[0]) {
            for y in self.cell_of(lo[1])..=self.cell_of(hi[1]) {
                for z in self.cell_of(lo[2])..=self.cell_of(hi[2]) {
                    if let Some(ids) = self.cells.get(&[x, y, z]) {
                        if let Some(&id) =
                            ids.iter().find(|&&id| (self.points[id as usize] - p).abs().max_element() <= t)
                        {
                            return Some(id);
                        }
                    }
                }
            }
        }
        None
    }

    /// The id of `p`: an existing point's within the tolerance, else a new one.
    fn id(&mut self, p: Vec3) -> u32 {
        if let Some(id) = self.find(p) {
            return id;
        }
        let id = self.points.len() as u32;
        self.points.push(p);
        let key = [self.cell_of(p.x), self.cell_of(p.y), self.cell_of(p.z)];
        self.cells.entry(key).or_default().push(id);
        id
    }
}

/// Per mesh surface (side): the first element of it, and its corners, the vertices only one of its
/// elements uses (the corners of a grid or of a split grid; a vertex on a side or inside has two or
/// more), at most four, in the order found.
struct SurfaceOutlines {
    element: Vec<u32>,
    corners: Vec<Vec<u32>>,
}

fn surface_outlines(mesh: &Mesh) -> SurfaceOutlines {
    let e = &mesh.elements;
    let mut uses = vec![0u32; mesh.positions.len()];
    for c in &e.corners {
        for &v in c.iter().filter(|&&v| v != NONE) {
            uses[v as usize] += 1;
        }
    }
    let count = mesh.surface_source.len().max(e.surface.iter().map(|&s| s as usize + 1).max().unwrap_or(0));
    let mut outline = SurfaceOutlines { element: vec![u32::MAX; count], corners: vec![Vec::new(); count] };
    for (i, c) in e.corners.iter().enumerate() {
        let s = e.surface[i] as usize;
        if outline.element[s] == u32::MAX {
            outline.element[s] = i as u32;
        }
        for &v in c.iter().filter(|&&v| v != NONE && uses[v as usize] == 1) {
            outline.corners[s].push(v);
        }
    }
    outline
}

/// Mesh surface s as a facet for `smoothing_groups`: its outline's corners as point ids, counter-
/// clockwise about its normal (a surface whose outline is not 3 or 4 corners gets no edges and stays a
/// group of its own).
fn surface_facet(mesh: &Mesh, s: usize, outline: &SurfaceOutlines, point: &[u32]) -> Facet<u32> {
    let e = &mesh.elements;
    let first = outline.element[s];
    if first == u32::MAX {
        return Facet { corners: [u32::MAX; 4], corner_count: 0, normal: Vec3::ZERO, material: u32::MAX, back: false };
    }
    let first = first as usize;
    let normal = e.normal[first];
    let mut corners = outline.corners[s].clone();
    let corner_count = if (3..=4).contains(&corners.len()) { corners.len() } else { 0 };
    if corner_count == 4 {
        // Counter-clockwise by angle about the centroid, in the plane of the normal.
        let centre = corners.iter().map(|&v| mesh.positions[v as usize]).sum::<Vec3>() / 4.0;
        let (u, w) = normal.any_orthonormal_pair();
        let angle = |v: u32| {
            let d = mesh.positions[v as usize] - centre;
            d.dot(w).atan2(d.dot(u))
        };
        corners.sort_by(|&a, &b| angle(a).total_cmp(&angle(b)));
    }
    let mut ids = [u32::MAX; 4];
    for (k, &v) in corners.iter().take(corner_count).enumerate() {
        ids[k] = point[v as usize];
    }
    Facet {
        corners: ids,
        corner_count,
        normal,
        material: e.material[first],
        back: mesh.surface_source.get(s).is_some_and(|&source| source as usize != s),
    }
}

/// Coplanar pieces' own values at a shared point agree when, per channel, they differ by at most this
/// fraction of the larger of the two ... A smooth field's extrapolations from two sides differ by its
/// curvature over an element (about 1% of the peak under a lamp half a floor away,
/// `tests/smooth_mesh.rs`); a sharp shadow edge's by most of the lit value. Measured on alcove_hall
/// (2026-12-02, docs/accuracy.md): any value from 0.25 to 0.4 gives the same image, 0.5 welds the
/// pillar's shadow edge again (0.609 against 0.382 beside the pillar's foot).
pub const AGREE_RELATIVE: f64 = 0.3;

/// ... plus this fraction of the brightest reflected value (the largest channel over the elements that
/// emit nothing), so that dark corners, where any difference is a large fraction, still weld.
pub const AGREE_FLOOR: f64 = 0.03;

/// Normals of mesh vertices at one point with n₁·n₂ above this are coplanar pieces of one plane (a floor
/// cut along furniture, a quad split into triangles); below it, facets of a curved surface.
const COPLANAR_COS: f32 = 0.9999;

/// Per-surface values `a` and `b` at one point agree (`AGREE_RELATIVE`, `AGREE_FLOOR`, with `floor`
/// the latter's absolute value): |a − b| ≤ r·max(a, b) + floor in every channel.
pub fn agree(a: Vec3, b: Vec3, floor: f64) -> bool {
    (0..3).all(|k| {
        let (a, b) = (a[k] as f64, b[k] as f64);
        (a - b).abs() <= AGREE_RELATIVE * a.max(b) + floor
    })
}

/// A `Mesh` with its vertices welded within smoothing groups (see module docs), as an `ElementMesh`.
pub struct SmoothMesh<'a> {
    mesh: &'a Mesh,
    /// Per welded vertex: its position and its smoothing group.
    positions: Vec<Vec3>,
    /// Per mesh vertex: its welded vertex.
    welded: Vec<u32>,
    /// Per element: its smoothing group.
    group: Vec<u32>,
    /// Per welded vertex: it lies on its group's outline (`boundary_vertices::boundary_vertices_cut`,
    /// every edge cut at the vertices of its group inside it, `t_junctions`: the adaptive mesh's
    /// T-junctions, a facet edge that its neighbour's finer grid splits).
    boundary: Vec<bool>,
    /// Per mesh vertex: it lies on its surface side's outline (the per-surface step's boundary, a split
    /// edge's midpoint, `Mesh::split_edge_midpoints`, not taken for one).
    surface_boundary: Vec<bool>,
    /// The welded vertices where coplanar pieces meet (two of their mesh vertices have normals within
    /// `COPLANAR_COS`), each with its mesh vertices: `members[start[k]..start[k + 1]]` for `seams[k]`.
    seams: Vec<u32>,
    seam_start: Vec<u32>,
    seam_members: Vec<u32>,
    /// Per mesh vertex: the normal of its surface side, and the area of the unburied elements around it
    /// (its weight where the values of several pieces are averaged).
    vertex_normal: Vec<Vec3>,
    vertex_area: Vec<f64>,
    /// T-junctions (`t_junctions`): (welded vertex, element) where the vertex lies inside one of the
    /// element's edges, on a piece of the element's plane (`family`), and is no vertex of the element's
    /// own surface (a split edge's midpoint is the adaptive mesh's own, `adaptive::hanging`).
    contacts: Vec<(u32, u32)>,
    /// Per element: its fit surface, the smoothing group joined with the groups of the pieces it meets
    /// at T-junctions (`t_junction_families`).
    family: Vec<u32>,
}

impl<'a> SmoothMesh<'a> {
    pub fn new(mesh: &'a Mesh) -> SmoothMesh<'a> {
        let (lo, hi) = mesh
            .positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let mut points = PointIds::new(if mesh.positions.is_empty() { 0.0 } else { (hi - lo).max_element() });
        let point: Vec<u32> = mesh.positions.iter().map(|&p| points.id(p)).collect();
        let outline = surface_outlines(mesh);
        let e = &mesh.elements;
        let facets: Vec<Facet<u32>> =
            (0..mesh.surface_source.len()).map(|s| surface_facet(mesh, s, &outline, &point)).collect();
        let surface_group = smoothing_groups(facets.len(), |s| facets[s]);
        let mut vertex_surface = vec![u32::MAX; mesh.positions.len()];
        for (i, c) in e.corners.iter().enumerate() {
            for &v in c.iter().filter(|&&v| v != NONE) {
                vertex_surface[v as usize] = e.surface[i];
            }
        }
        let class = |s: u32| facets[s as usize].material.wrapping_mul(2) | facets[s as usize].back as u32;
        let t_junctions = vertices_inside_edges(
            &mesh.positions,
            &e.corners,
            |v| class(vertex_surface[v as usize]),
            |element| class(e.surface[element]),
            |_, _| true,
        );
        let surface_family = t_junction_families(&surface_group, &facets, &t_junctions, &vertex_surface, &e.surface);
        let family: Vec<u32> = e.surface.iter().map(|&s| surface_family[s as usize]).collect();
        let vertex_family: Vec<u32> =
            vertex_surface.iter().map(|&s| if s == u32::MAX { u32::MAX } else { surface_family[s as usize] }).collect();
        let group: Vec<u32> = e.surface.iter().map(|&s| surface_group[s as usize]).collect();
        let vertex_group: Vec<u32> =
            vertex_surface.iter().map(|&s| if s == u32::MAX { u32::MAX } else { surface_group[s as usize] }).collect();
        let mut welded_of: FxHashMap<(u32, u32), u32> = FxHashMap::default();
        let mut positions = Vec::new();
        let welded: Vec<u32> = (0..mesh.positions.len())
            .map(|v| {
                *welded_of.entry((vertex_group[v], point[v])).or_insert_with(|| {
                    positions.push(mesh.positions[v]);
                    positions.len() as u32 - 1
                })
            })
            .collect();
        let (vertex_normal, vertex_area) = vertex_normals_and_areas(mesh);
        let (seams, seam_start, seam_members) = coplanar_seams(&welded, positions.len(), &vertex_normal);
        let surface_boundary = boundary_vertices::boundary_vertices(mesh, &|a, b| {
            mesh.split_edge_midpoints.get(&(a.min(b), a.max(b))).copied()
        });
        // The welded vertices of each element's group inside each of its edges (the outline's cuts),
        // and of its family (the T-junctions: vertices of no element of the edge's own surface).
        let mut own_surface: rustc_hash::FxHashSet<(u32, u32)> = Default::default();
        for (v, &w) in welded.iter().enumerate() {
            own_surface.insert((w, vertex_surface[v]));
        }
        let mut inside: FxHashMap<(u32, u32), Vec<u32>> = FxHashMap::default();
        let mut contacts = Vec::new();
        for edge in &t_junctions {
            let element = edge.element as usize;
            let (a, b) = (welded[edge.ends.0 as usize], welded[edge.ends.1 as usize]);
            let mut list: Vec<u32> = Vec::with_capacity(edge.inside.len());
            for &v in &edge.inside {
                let w = welded[v as usize];
                if vertex_family[v as usize] != family[element] || w == a || w == b || list.contains(&w) {
                    continue;
                }
                if vertex_group[v as usize] == group[element] {
                    list.push(w);
                }
                if !own_surface.contains(&(w, e.surface[element])) {
                    contacts.push((w, edge.element));
                }
            }
            if !list.is_empty() {
                if a > b {
                    list.reverse();
                }
                inside.entry((a.min(b), a.max(b))).or_insert(list);
            }
        }
        contacts.sort_unstable();
        contacts.dedup();
        let mut smooth = SmoothMesh {
            mesh,
            positions,
            welded,
            group,
            boundary: Vec::new(),
            surface_boundary,
            seams,
            seam_start,
            seam_members,
            vertex_normal,
            vertex_area,
            contacts,
            family,
        };
        let boundary = boundary_vertices::boundary_vertices_cut(&smooth, &|a, b| {
            let list = inside.get(&(a.min(b), a.max(b)))?;
            Some(if a < b { list.clone() } else { list.iter().rev().copied().collect() })
        });
        smooth.boundary = boundary;
        smooth
    }

    /// Per mesh vertex: the vertex step's value (`boundary_vertices::vertex_values` over the welded
    /// mesh: the area mean of the unburied elements around a vertex inside a smoothing group, the
    /// clamped linear extrapolation on its outline), except where the solution is discontinuous on a
    /// border between coplanar pieces.
    ///
    /// The rule at a point where coplanar pieces of a group meet (a seam, `COPLANAR_COS`): each piece
    /// has its own value there, the per-surface step's (its surface's elements extrapolated to its
    /// outline). Pieces are joined when their own values agree (`agree`: within `AGREE_RELATIVE` of
    /// the larger plus `AGREE_FLOOR` of the brightest reflected value) and always across a curved
    /// facet edge (normals apart), the join taken transitively. If that joins every piece at the
    /// point, the welded value stands: a triangulated quad's halves extrapolate one smooth field to
    /// nearly one value and stay seamless. Else the point is a discontinuity line of the solution
    /// (a sharp shadow edge lying on the border, as the floor cut along a pillar's faces has it) and
    /// each joined set of pieces takes the area-weighted mean of its pieces' own values, so that the
    /// step survives instead of being averaged into a bright shadow and a dark light beside it.
    pub fn vertex_values(&self, element_values: &[DVec3]) -> Vec<Vec3> {
        let welded = boundary_vertices::vertex_values(self, element_values, &self.boundary);
        let mut values: Vec<Vec3> = self.welded.iter().map(|&w| welded[w as usize]).collect();
        if self.seams.is_empty() {
            return values;
        }
        let own = boundary_vertices::vertex_values(self.mesh, element_values, &self.surface_boundary);
        let e = &self.mesh.elements;
        let brightest = (0..e.len().min(element_values.len()))
            .filter(|&i| e.emission[i] == Vec3::ZERO && !self.buried(i))
            .map(|i| element_values[i].max_element())
            .fold(0.0f64, f64::max);
        let floor = AGREE_FLOOR * brightest;
        let mut parent = Vec::new();
        for k in 0..self.seams.len() {
            let members = &self.seam_members[self.seam_start[k] as usize..self.seam_start[k + 1] as usize];
            parent.clear();
            parent.extend(0..members.len() as u32);
            for i in 0..members.len() {
                for j in i + 1..members.len() {
                    let (a, b) = (members[i] as usize, members[j] as usize);
                    let curved = self.vertex_normal[a].dot(self.vertex_normal[b]) <= COPLANAR_COS;
                    if curved || agree(own[a], own[b], floor) {
                        join(&mut parent, i as u32, j as u32);
                    }
                }
            }
            let roots: Vec<u32> = (0..members.len() as u32).map(|i| root(&mut parent, i)).collect();
            if roots.iter().all(|&r| r == 0) {
                continue;
            }
            for (i, &r) in roots.iter().enumerate() {
                let (mut sum, mut weight) = (Vec3::ZERO, 0.0f64);
                for (j, _) in roots.iter().enumerate().filter(|&(_, &s)| s == r) {
                    let m = members[j] as usize;
                    let w = self.vertex_area[m].max(f64::MIN_POSITIVE);
                    sum += own[m] * w as f32;
                    weight += w;
                }
                values[members[i] as usize] = sum / weight as f32;
            }
        }
        values
    }

    /// Number of smoothing groups (a box-like scene: one per surface side).
    pub fn group_count(&self) -> usize {
        let mut groups = self.group.clone();
        groups.sort_unstable();
        groups.dedup();
        groups.len()
    }
}

/// Per mesh vertex: the normal of an element using it (every element of a surface side has its
/// plane's), and the area of the unburied elements using it.
fn vertex_normals_and_areas(mesh: &Mesh) -> (Vec<Vec3>, Vec<f64>) {
    let e = &mesh.elements;
    let mut normal = vec![Vec3::ZERO; mesh.positions.len()];
    let mut area = vec![0.0f64; mesh.positions.len()];
    for (i, c) in e.corners.iter().enumerate() {
        let buried = mesh.element_buried.get(i).copied().unwrap_or(false);
        for &v in c.iter().filter(|&&v| v != NONE) {
            normal[v as usize] = e.normal[i];
            if !buried {
                area[v as usize] += e.area[i] as f64;
            }
        }
    }
    (normal, area)
}

/// The welded vertices (of `welded_count`; `welded`: per mesh vertex its welded vertex) where two mesh
/// vertices with normals within `COPLANAR_COS` meet, in increasing order, and their mesh vertices as
/// one flat list (`start`, `members`, as `SmoothMesh::seams`).
fn coplanar_seams(welded: &[u32], welded_count: usize, normal: &[Vec3]) -> (Vec<u32>, Vec<u32>, Vec<u32>) {
    let mut first = vec![0u32; welded_count + 1];
    for &w in welded {
        first[w as usize + 1] += 1;
    }
    for w in 0..welded_count {
        first[w + 1] += first[w];
    }
    let mut next = first.clone();
    let mut at = vec![0u32; welded.len()];
    for (v, &w) in welded.iter().enumerate() {
        at[next[w as usize] as usize] = v as u32;
        next[w as usize] += 1;
    }
    let (mut seams, mut start, mut members) = (Vec::new(), vec![0u32], Vec::new());
    for w in 0..welded_count {
        let here = &at[first[w] as usize..first[w + 1] as usize];
        let coplanar = here
            .iter()
            .enumerate()
            .any(|(i, &a)| here[i + 1..].iter().any(|&b| normal[a as usize].dot(normal[b as usize]) > COPLANAR_COS));
        if coplanar {
            seams.push(w as u32);
            members.extend_from_slice(here);
            start.push(members.len() as u32);
        }
    }
    (seams, start, members)
}

impl ElementMesh for SmoothMesh<'_> {
    fn positions(&self) -> &[Vec3] {
        &self.positions
    }

    fn element_count(&self) -> usize {
        self.mesh.elements.len()
    }

    fn corners(&self, e: usize) -> [u32; 4] {
        self.mesh.elements.corners[e].map(|v| if v == NONE { NONE } else { self.welded[v as usize] })
    }

    fn centre(&self, e: usize) -> Vec3 {
        self.mesh.elements.centre[e]
    }

    fn normal(&self, e: usize) -> Vec3 {
        self.mesh.elements.normal[e]
    }

    fn weight(&self, e: usize) -> f64 {
        self.mesh.elements.area[e] as f64
    }

    fn surface(&self, e: usize) -> u32 {
        self.group[e]
    }

    fn buried(&self, e: usize) -> bool {
        self.mesh.element_buried.get(e).copied().unwrap_or(false)
    }

    fn contacts(&self) -> &[(u32, u32)] {
        &self.contacts
    }

    fn fit_surface(&self, e: usize) -> u32 {
        self.family[e]
    }

    /// Across a T-junction (another smoothing group of the family) only where the two elements' values
    /// agree (`agree`, without the floor): a sharp shadow edge lying on the junction is not read as a
    /// slope, and each side keeps its own extrapolation to it.
    fn fit_reads(&self, e: usize, n: usize, values: &[Vec3]) -> bool {
        self.group[e] == self.group[n] || agree(values[e], values[n], 0.0)
    }

    /// `Mesh::vertex_average` over the welded vertices: the area mean of the unburied elements around
    /// a vertex, of the buried ones where there are only those.
    fn vertex_mean(&self, element_values: &[DVec3]) -> Vec<DVec3> {
        let n = self.positions.len();
        let (mut sum, mut weight) = (vec![DVec3::ZERO; n], vec![0.0f64; n]);
        let (mut buried_sum, mut buried_weight) = (vec![DVec3::ZERO; n], vec![0.0f64; n]);
        for (e, &value) in element_values.iter().enumerate().take(self.element_count()) {
            let a = self.weight(e);
            let (sum, weight) =
                if self.buried(e) { (&mut buried_sum, &mut buried_weight) } else { (&mut sum, &mut weight) };
            for v in self.corners(e).into_iter().filter(|&v| v != NONE) {
                sum[v as usize] += value * a;
                weight[v as usize] += a;
            }
        }
        (0..n)
            .map(|v| match (weight[v] > 0.0, buried_weight[v] > 0.0) {
                (true, _) => sum[v] * (1.0 / weight[v]),
                (false, true) => buried_sum[v] * (1.0 / buried_weight[v]),
                (false, false) => sum[v],
            })
            .collect()
    }
}
