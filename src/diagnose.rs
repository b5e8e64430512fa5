//! Suspicious-geometry diagnostics for `radray info`: T-junctions, coplanar overlapping faces,
//! intersecting faces, normals flipped relative to their neighbours and non-planar polygons — the usual
//! sources of radiosity light leaks and cracks, found from the scene's polygons before anything is solved.
//!
//! Every check is a pure function of the surfaces. Candidate pairs come from a uniform grid over the
//! faces' bounding boxes (each pair visited once), so the cost grows with the number of nearby pairs,
//! not with n². Geometry is evaluated in f64. Lengths are compared with one absolute tolerance,
//! `relative_tolerance` × the scene's bounding-box diagonal (never below the f32 spacing of the scene's
//! coordinates): see [`DiagnoseOptions`].

use crate::scene::{SceneDescription, Surface};
use glam::DVec3;
use serde::Serialize;
use std::collections::HashMap;
use std::fmt;

/// Settings of [`diagnose_surfaces`].
#[derive(Clone, Debug, PartialEq)]
pub struct DiagnoseOptions {
    /// Length tolerance as a fraction of the scene's bounding-box diagonal. The default 1e-5 is
    /// ~100 f32 ulps of a scene's extent (far above rounding noise) and ten times finer than the
    /// deliberate 0.1 mm gap between the Cornell box's light and its ceiling (1e-4 of its diagonal).
    pub relative_tolerance: f64,
    /// How many examples of each finding the report keeps (the counts are always complete).
    pub max_examples: usize,
}

impl Default for DiagnoseOptions {
    fn default() -> Self {
        DiagnoseOptions { relative_tolerance: 1e-5, max_examples: 5 }
    }
}

/// A scene surface named in a finding.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct SurfaceRef {
    /// Index into `SceneDescription::surfaces`.
    pub index: usize,
    /// The surface's object (OBJ `o`/`g`) or primitive name.
    pub object: String,
}

/// A vertex of one surface lying strictly inside an edge of another.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct TJunction {
    /// The surface whose edge the vertex splits.
    pub edge_surface: SurfaceRef,
    /// A surface that has the vertex as a corner.
    pub vertex_surface: SurfaceRef,
    /// The vertex.
    pub point: [f32; 3],
}

/// Two faces in one plane whose polygons overlap with positive area.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct CoplanarOverlap {
    pub a: SurfaceRef,
    pub b: SurfaceRef,
    /// Both face the same way (z-fighting) rather than back to back.
    pub same_facing: bool,
    /// Area of the overlap (scene units²).
    pub overlap_area: f64,
    /// Centroid of the overlap.
    pub point: [f32; 3],
}

/// Two non-coplanar faces whose interiors cross.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Intersection {
    pub a: SurfaceRef,
    pub b: SurfaceRef,
    /// Length of the segment along which the faces cross.
    pub length: f64,
    /// Middle of that segment.
    pub point: [f32; 3],
}

/// A face whose winding disagrees with the neighbours it shares edges with.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct FlippedFace {
    pub surface: SurfaceRef,
    /// A neighbour that traverses a shared edge in the same direction.
    pub neighbour: SurfaceRef,
    /// Middle of that shared edge.
    pub point: [f32; 3],
}

/// A polygon whose corners do not lie in one plane.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct NonPlanar {
    pub surface: SurfaceRef,
    /// Largest distance of a corner from the polygon's best plane (Newell normal through the centroid).
    pub deviation: f64,
    /// The corner farthest from that plane.
    pub point: [f32; 3],
}

/// How many findings of one kind, and the first few (ordered by surface index).
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct Findings<T> {
    pub count: usize,
    pub examples: Vec<T>,
}

impl<T> Default for Findings<T> {
    fn default() -> Self {
        Findings { count: 0, examples: Vec::new() }
    }
}

/// Flipped faces of one object.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct ObjectCount {
    pub object: String,
    pub count: usize,
}

/// Faces flipped relative to their neighbours, with a count per object.
#[derive(Clone, Debug, Default, PartialEq, Serialize)]
pub struct FlippedFaces {
    /// Faces whose winding disagrees with the majority of their edge-connected patch.
    pub count: usize,
    /// Shared edges traversed in the same direction by both faces.
    pub inconsistent_edges: usize,
    pub per_object: Vec<ObjectCount>,
    pub examples: Vec<FlippedFace>,
}

/// What [`diagnose`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GeometryReport {
    pub surface_count: usize,
    /// Surfaces left out of every check: fewer than 3 corners, non-finite corners or zero area.
    pub skipped_surfaces: usize,
    /// Diagonal of the scene's bounding box.
    pub scene_diagonal: f64,
    /// The absolute length tolerance every check used.
    pub tolerance: f64,
    /// Pairs of faces whose (tolerance-grown) bounding boxes overlap: the pairs actually examined.
    pub candidate_pairs: usize,
    pub t_junctions: Findings<TJunction>,
    pub coplanar_overlaps: Findings<CoplanarOverlap>,
    pub intersections: Findings<Intersection>,
    pub flipped: FlippedFaces,
    pub non_planar: Findings<NonPlanar>,
}

impl GeometryReport {
    /// No finding of any kind.
    pub fn is_clean(&self) -> bool {
        self.t_junctions.count == 0
            && self.coplanar_overlaps.count == 0
            && self.intersections.count == 0
            && self.flipped.count == 0
            && self.flipped.inconsistent_edges == 0
            && self.non_planar.count == 0
    }
}

/// Checks the scene's surfaces with the default options (see [`diagnose_surfaces`]).
pub fn diagnose(scene: &SceneDescription) -> GeometryReport {
    diagnose_surfaces(&scene.surfaces, &DiagnoseOptions::default())
}

/// Runs every check over `surfaces` (planar convex polygons, counter-clockwise seen from the front):
///
/// - **T-junctions** ([`t_junctions_between`]): a corner of one face closer than the tolerance to the
///   inside of another face's edge and farther than the tolerance from both of its endpoints. Each
///   (vertex position, edge) is counted once.
/// - **Coplanar overlaps** ([`coplanar_overlap`]): parallel faces with every corner of each within the
///   tolerance of the other's plane, whose polygons overlap by more than the tolerance on every
///   separating axis (2-D SAT); touching along an edge or at a corner is not an overlap.
/// - **Intersections** ([`crossing`]): non-coplanar faces, each with corners farther than the
///   tolerance on both sides of the other's plane, whose intervals on the planes' line of intersection
///   overlap by more than the tolerance (Möller 1997, "A fast triangle-triangle intersection test").
/// - **Flipped faces**: faces sharing an edge (both endpoints within the tolerance) that traverse it
///   in the same direction; within each edge-connected patch the minority orientation is reported.
///   Two-sided surfaces and edges shared by more than two faces are left out.
/// - **Non-planar polygons**: a corner farther than the tolerance from the polygon's best plane.
pub fn diagnose_surfaces(surfaces: &[Surface], options: &DiagnoseOptions) -> GeometryReport {
    let polys: Vec<Option<Poly>> = surfaces.iter().map(|s| Poly::new(&s.vertices)).collect();
    let skipped_surfaces = polys.iter().filter(|p| p.is_none()).count();
    let (lo, hi) =
        polys.iter().flatten().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p.lo), hi.max(p.hi)));
    let scene_diagonal = if lo.x <= hi.x { (hi - lo).length() } else { 0.0 };
    let magnitude = if lo.x <= hi.x { lo.abs().max(hi.abs()).max_element() } else { 0.0 };
    let tolerance = (options.relative_tolerance * scene_diagonal).max(8.0 * f32::EPSILON as f64 * magnitude);
    let tolerance = if tolerance > 0.0 { tolerance } else { f32::EPSILON as f64 };

    let surface_ref = |i: usize| SurfaceRef { index: i, object: surfaces[i].object.clone() };
    let vertex_ids = weld_vertices(&polys, tolerance);

    // Pairwise checks over grid candidates.
    let live: Vec<usize> = (0..polys.len()).filter(|&i| polys[i].is_some()).collect();
    let boxes: Vec<(DVec3, DVec3)> = live
        .iter()
        .map(|&i| {
            let p = polys[i].as_ref().expect("live surfaces have a polygon");
            (p.lo - DVec3::splat(tolerance), p.hi + DVec3::splat(tolerance))
        })
        .collect();
    let mut candidate_pairs = 0usize;
    // (edge surface, welded vertex id, welded edge, vertex surface, vertex)
    let mut t_found: Vec<RawTJunction> = Vec::new();
    let mut coplanar: Vec<(usize, usize, bool, f64, DVec3)> = Vec::new();
    let mut crossings: Vec<(usize, usize, f64, DVec3)> = Vec::new();
    for_each_candidate_pair(&boxes, |a, b| {
        candidate_pairs += 1;
        let (i, j) = (live[a], live[b]);
        let (pi, pj) = (polys[i].as_ref().expect("live"), polys[j].as_ref().expect("live"));
        for (v, e, edge) in t_junctions_between(&pi.vertices, &pj.vertices, tolerance) {
            let key = edge_key(vertex_ids[j][edge], vertex_ids[j][(edge + 1) % pj.vertices.len()]);
            t_found.push((j, vertex_ids[i][v], key, i, e));
        }
        for (v, e, edge) in t_junctions_between(&pj.vertices, &pi.vertices, tolerance) {
            let key = edge_key(vertex_ids[i][edge], vertex_ids[i][(edge + 1) % pi.vertices.len()]);
            t_found.push((i, vertex_ids[j][v], key, j, e));
        }
        if let Some(overlap) = coplanar_overlap(pi, pj, tolerance) {
            coplanar.push((i, j, overlap.same_facing, overlap.area, overlap.centroid));
        } else if let Some((length, point)) = crossing(pi, pj, tolerance) {
            crossings.push((i, j, length, point));
        }
    });

    // One T-junction per (vertex position, geometric edge): an edge shared by two faces counts once.
    t_found.sort_by_key(|x| (x.1, x.2, x.0, x.3));
    t_found.dedup_by(|x, y| x.1 == y.1 && x.2 == y.2);
    t_found.sort_by_key(|x| (x.0, x.3, x.1));
    let t_junctions = Findings {
        count: t_found.len(),
        examples: t_found
            .iter()
            .take(options.max_examples)
            .map(|&(edge_s, _, _, vertex_s, p)| TJunction {
                edge_surface: surface_ref(edge_s),
                vertex_surface: surface_ref(vertex_s),
                point: to_f32(p),
            })
            .collect(),
    };
    coplanar.sort_by_key(|x| (x.0, x.1));
    let coplanar_overlaps = Findings {
        count: coplanar.len(),
        examples: coplanar
            .iter()
            .take(options.max_examples)
            .map(|&(a, b, same_facing, overlap_area, p)| CoplanarOverlap {
                a: surface_ref(a),
                b: surface_ref(b),
                same_facing,
                overlap_area,
                point: to_f32(p),
            })
            .collect(),
    };
    crossings.sort_by_key(|x| (x.0, x.1));
    let intersections = Findings {
        count: crossings.len(),
        examples: crossings
            .iter()
            .take(options.max_examples)
            .map(|&(a, b, length, p)| Intersection { a: surface_ref(a), b: surface_ref(b), length, point: to_f32(p) })
            .collect(),
    };

    let flipped = flipped_faces(surfaces, &polys, &vertex_ids, options.max_examples);

    let mut non_planar = Findings::default();
    for (i, p) in polys.iter().enumerate() {
        let Some(p) = p else { continue };
        if p.deviation > tolerance {
            non_planar.count += 1;
            if non_planar.examples.len() < options.max_examples {
                let far = p
                    .vertices
                    .iter()
                    .copied()
                    .max_by(|a, b| p.distance(*a).abs().total_cmp(&p.distance(*b).abs()))
                    .unwrap_or(p.lo);
                non_planar.examples.push(NonPlanar {
                    surface: surface_ref(i),
                    deviation: p.deviation,
                    point: to_f32(far),
                });
            }
        }
    }

    GeometryReport {
        surface_count: surfaces.len(),
        skipped_surfaces,
        scene_diagonal,
        tolerance,
        candidate_pairs,
        t_junctions,
        coplanar_overlaps,
        intersections,
        flipped,
        non_planar,
    }
}

/// A surface's polygon in f64 with its best plane.
#[derive(Clone, Debug)]
pub struct Poly {
    pub vertices: Vec<DVec3>,
    /// Unit normal (Newell's method), by the right-hand rule.
    pub normal: DVec3,
    /// Plane offset: `normal · x = offset` through the corners' centroid.
    pub offset: f64,
    /// Largest distance of a corner from that plane (0 for a triangle, up to rounding).
    pub deviation: f64,
    pub lo: DVec3,
    pub hi: DVec3,
}

impl Poly {
    /// `None` for fewer than 3 corners, non-finite corners or zero area.
    pub fn new(vertices: &[glam::Vec3]) -> Option<Poly> {
        if vertices.len() < 3 || !vertices.iter().all(|v| v.is_finite()) {
            return None;
        }
        let vertices: Vec<DVec3> = vertices.iter().map(|v| v.as_dvec3()).collect();
        let n = vertices.len();
        let centroid = vertices.iter().sum::<DVec3>() / n as f64;
        // Newell's normal about the centroid (better conditioned far from the origin).
        let newell: DVec3 = (0..n).map(|k| (vertices[k] - centroid).cross(vertices[(k + 1) % n] - centroid)).sum();
        let normal = newell.try_normalize()?;
        let offset = normal.dot(centroid);
        let deviation = vertices.iter().map(|v| (normal.dot(*v) - offset).abs()).fold(0.0, f64::max);
        let lo = vertices.iter().fold(DVec3::INFINITY, |a, &v| a.min(v));
        let hi = vertices.iter().fold(DVec3::NEG_INFINITY, |a, &v| a.max(v));
        Some(Poly { vertices, normal, offset, deviation, lo, hi })
    }

    /// Signed distance of `x` from the polygon's plane (positive in front).
    pub fn distance(&self, x: DVec3) -> f64 {
        self.normal.dot(x) - self.offset
    }

    fn centroid(&self) -> DVec3 {
        self.vertices.iter().sum::<DVec3>() / self.vertices.len() as f64
    }
}

/// T-junctions of `vertices` on the edges of `polygon`: `(vertex index, vertex, edge index)` for each
/// vertex closer than `tolerance` to edge k (from corner k to corner k+1) whose foot lies strictly
/// inside the edge and which is farther than `tolerance` from both of the edge's endpoints.
pub fn t_junctions_between(vertices: &[DVec3], polygon: &[DVec3], tolerance: f64) -> Vec<(usize, DVec3, usize)> {
    let mut found = Vec::new();
    for (v, &x) in vertices.iter().enumerate() {
        for k in 0..polygon.len() {
            let (p, q) = (polygon[k], polygon[(k + 1) % polygon.len()]);
            let d = q - p;
            let len2 = d.length_squared();
            if !(len2 > 0.0) {
                continue;
            }
            let t = (x - p).dot(d) / len2;
            if !(t > 0.0 && t < 1.0) {
                continue;
            }
            if (x - (p + d * t)).length() < tolerance && (x - p).length() > tolerance && (x - q).length() > tolerance {
                found.push((v, x, k));
            }
        }
    }
    found
}

/// Overlap of two coplanar faces.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Overlap {
    pub same_facing: bool,
    pub area: f64,
    pub centroid: DVec3,
}

/// `Some` if `a` and `b` lie in one plane and overlap with positive area.
///
/// Coplanar: normals parallel (|nₐ × n_b| < 1e-3, about 0.06°) and every corner of each polygon within
/// `tolerance` (plus that polygon's own non-planarity) of the other's plane. Overlap: the separating
/// axis theorem for convex polygons in 2-D (Gottschalk et al. 1996) over the edge normals of both,
/// projected into a's plane; intervals overlapping by `tolerance` or less count as separated, so faces
/// touching along an edge or at a corner do not overlap. The area and centroid are those of the
/// Sutherland–Hodgman clip of a by b.
pub fn coplanar_overlap(a: &Poly, b: &Poly, tolerance: f64) -> Option<Overlap> {
    if a.normal.cross(b.normal).length() >= 1e-3 {
        return None;
    }
    let near = |p: &Poly, onto: &Poly| {
        let slack = tolerance + p.deviation + onto.deviation;
        p.vertices.iter().all(|&v| onto.distance(v).abs() <= slack)
    };
    if !(near(a, b) && near(b, a)) {
        return None;
    }
    let u = a.normal.any_orthonormal_vector();
    let w = a.normal.cross(u);
    let flat = |p: &Poly| -> Vec<[f64; 2]> {
        let mut q: Vec<[f64; 2]> = p.vertices.iter().map(|v| [v.dot(u), v.dot(w)]).collect();
        if signed_area(&q) < 0.0 {
            q.reverse();
        }
        q
    };
    let (qa, qb) = (flat(a), flat(b));
    for poly in [&qa, &qb] {
        for k in 0..poly.len() {
            let (p, q) = (poly[k], poly[(k + 1) % poly.len()]);
            let (ex, ey) = (q[0] - p[0], q[1] - p[1]);
            let len = (ex * ex + ey * ey).sqrt();
            if !(len > 0.0) {
                continue;
            }
            let axis = [-ey / len, ex / len];
            let (amin, amax) = project(&qa, axis);
            let (bmin, bmax) = project(&qb, axis);
            if amax.min(bmax) - amin.max(bmin) <= tolerance {
                return None;
            }
        }
    }
    let clipped = clip_convex(&qa, &qb);
    let area = signed_area(&clipped);
    let (cu, cw) = polygon_centroid(&clipped).unwrap_or_else(|| {
        let c = a.centroid();
        (c.dot(u), c.dot(w))
    });
    let centroid = u * cu + w * cw + a.normal * a.offset;
    Some(Overlap { same_facing: a.normal.dot(b.normal) > 0.0, area, centroid })
}

/// `Some((length, midpoint))` if the interiors of the non-coplanar faces `a` and `b` cross.
///
/// Möller's interval test (1997), for convex polygons: each polygon must have corners farther than
/// `tolerance` (plus the other polygon's non-planarity) on both sides of the other's plane — so faces
/// meeting along an edge, or one standing on the other, are not crossing; then each polygon's boundary
/// is cut by the other's plane, giving an interval on the planes' common line, and the two intervals
/// must overlap by more than `tolerance`.
pub fn crossing(a: &Poly, b: &Poly, tolerance: f64) -> Option<(f64, DVec3)> {
    let side = |p: &Poly, plane: &Poly| -> Option<Vec<f64>> {
        let slack = tolerance + plane.deviation;
        let d: Vec<f64> = p
            .vertices
            .iter()
            .map(|&v| {
                let d = plane.distance(v);
                if d.abs() <= slack {
                    0.0
                } else {
                    d
                }
            })
            .collect();
        (d.iter().any(|&x| x > 0.0) && d.iter().any(|&x| x < 0.0)).then_some(d)
    };
    let da = side(a, b)?;
    let db = side(b, a)?;
    let line = a.normal.cross(b.normal).try_normalize()?;
    let interval = |p: &Poly, d: &[f64]| -> Option<((f64, DVec3), (f64, DVec3))> {
        let n = p.vertices.len();
        let mut lo: Option<(f64, DVec3)> = None;
        let mut hi: Option<(f64, DVec3)> = None;
        let mut add = |x: DVec3| {
            let t = line.dot(x);
            if lo.is_none_or(|(l, _)| t < l) {
                lo = Some((t, x));
            }
            if hi.is_none_or(|(h, _)| t > h) {
                hi = Some((t, x));
            }
        };
        for k in 0..n {
            let (dk, dn) = (d[k], d[(k + 1) % n]);
            if dk == 0.0 {
                add(p.vertices[k]);
            } else if dk * dn < 0.0 {
                let (x, y) = (p.vertices[k], p.vertices[(k + 1) % n]);
                add(x + (y - x) * (dk / (dk - dn)));
            }
        }
        Some((lo?, hi?))
    };
    let ((a_lo, a_lo_x), (a_hi, a_hi_x)) = interval(a, &da)?;
    let ((b_lo, _), (b_hi, _)) = interval(b, &db)?;
    let (from, to) = (a_lo.max(b_lo), a_hi.min(b_hi));
    let length = to - from;
    if !(length > tolerance) {
        return None;
    }
    // The middle of the common stretch, on a's chord.
    let mid = 0.5 * (from + to);
    let s = if a_hi > a_lo { (mid - a_lo) / (a_hi - a_lo) } else { 0.5 };
    Some((length, a_lo_x + (a_hi_x - a_lo_x) * s))
}

/// Calls `visit(i, j)` (i < j) once for every pair of overlapping boxes `(lo, hi)`. A uniform grid of
/// at most ~4n cells, sized from the boxes' mean extent; a pair found in several cells is visited only
/// in the cell holding the low corner of the boxes' intersection.
fn for_each_candidate_pair(boxes: &[(DVec3, DVec3)], mut visit: impl FnMut(usize, usize)) {
    let n = boxes.len();
    if n < 2 {
        return;
    }
    let glo = boxes.iter().fold(DVec3::INFINITY, |a, b| a.min(b.0));
    let ghi = boxes.iter().fold(DVec3::NEG_INFINITY, |a, b| a.max(b.1));
    let extent = ghi - glo;
    let mean = boxes.iter().map(|b| (b.1 - b.0).max_element()).sum::<f64>() / n as f64;
    let max_cells = (4 * n).clamp(1, 1 << 22);
    let mut cell = if mean > 0.0 { mean } else { extent.max_element().max(1.0) };
    let resolution = |cell: f64| -> [usize; 3] {
        extent.to_array().map(|e| if cell > 0.0 { ((e / cell).ceil() as usize).clamp(1, 1024) } else { 1 })
    };
    let mut res = resolution(cell);
    while res.iter().product::<usize>() > max_cells {
        cell *= 1.25;
        res = resolution(cell);
    }
    let cell_of = |p: DVec3| -> [usize; 3] {
        let mut c = [0usize; 3];
        for a in 0..3 {
            if extent[a] > 0.0 {
                let f = ((p[a] - glo[a]) / extent[a] * res[a] as f64).floor();
                c[a] = if f > 0.0 { (f as usize).min(res[a] - 1) } else { 0 };
            }
        }
        c
    };
    let flat = |c: [usize; 3]| (c[2] * res[1] + c[1]) * res[0] + c[0];
    // Compressed cell lists: count, then fill (boxes in index order within each cell).
    let total = res.iter().product::<usize>();
    let mut start = vec![0usize; total + 1];
    let ranges: Vec<([usize; 3], [usize; 3])> = boxes.iter().map(|b| (cell_of(b.0), cell_of(b.1))).collect();
    let each_cell = |(c0, c1): ([usize; 3], [usize; 3]), f: &mut dyn FnMut(usize)| {
        for z in c0[2]..=c1[2] {
            for y in c0[1]..=c1[1] {
                for x in c0[0]..=c1[0] {
                    f(flat([x, y, z]));
                }
            }
        }
    };
    for &r in &ranges {
        each_cell(r, &mut |c| start[c + 1] += 1);
    }
    for c in 0..total {
        start[c + 1] += start[c];
    }
    let mut fill = start.clone();
    let mut members = vec![0u32; start[total]];
    for (i, &r) in ranges.iter().enumerate() {
        each_cell(r, &mut |c| {
            members[fill[c]] = i as u32;
            fill[c] += 1;
        });
    }
    for c in 0..total {
        let list = &members[start[c]..start[c + 1]];
        for (k, &i) in list.iter().enumerate() {
            let (ilo, ihi) = boxes[i as usize];
            for &j in &list[k + 1..] {
                let (jlo, jhi) = boxes[j as usize];
                if ilo.cmple(jhi).all() && jlo.cmple(ihi).all() && flat(cell_of(ilo.max(jlo))) == c {
                    visit(i as usize, j as usize);
                }
            }
        }
    }
}

/// Gives every corner an id shared by all corners within `tolerance` of the first one seen (a spatial
/// hash with cells of the tolerance's size, searching the 27 cells around).
fn weld_vertices(polys: &[Option<Poly>], tolerance: f64) -> Vec<Vec<u32>> {
    let mut cells: HashMap<[i64; 3], Vec<(DVec3, u32)>> = HashMap::new();
    let mut next = 0u32;
    let key = |v: DVec3| (v / tolerance).floor().to_array().map(|x| x as i64);
    polys
        .iter()
        .map(|p| {
            let Some(p) = p else { return Vec::new() };
            p.vertices
                .iter()
                .map(|&v| {
                    let k = key(v);
                    for dz in -1..=1i64 {
                        for dy in -1..=1i64 {
                            for dx in -1..=1i64 {
                                let c = [k[0].saturating_add(dx), k[1].saturating_add(dy), k[2].saturating_add(dz)];
                                if let Some(list) = cells.get(&c) {
                                    if let Some(&(_, id)) = list.iter().find(|(w, _)| (*w - v).length() <= tolerance) {
                                        return id;
                                    }
                                }
                            }
                        }
                    }
                    let id = next;
                    next += 1;
                    cells.entry(k).or_default().push((v, id));
                    id
                })
                .collect()
        })
        .collect()
}

type RawTJunction = (usize, u32, (u32, u32), usize, DVec3);
type EdgeUse = (usize, bool, usize);

fn edge_key(a: u32, b: u32) -> (u32, u32) {
    (a.min(b), a.max(b))
}

/// Faces whose winding disagrees with their edge neighbours. Two one-sided faces sharing an edge (and
/// no third face sharing it) are consistent when they traverse it in opposite directions. Each
/// edge-connected patch is 2-coloured by orientation from its lowest-index face; the smaller colour
/// class (on a tie, the one without that face) is reported as flipped.
fn flipped_faces(surfaces: &[Surface], polys: &[Option<Poly>], ids: &[Vec<u32>], max_examples: usize) -> FlippedFaces {
    // Welded edge → (face, traversed from the lower id to the higher?, the face's edge index).
    let mut edges: HashMap<(u32, u32), Vec<EdgeUse>> = HashMap::new();
    for (s, p) in polys.iter().enumerate() {
        let Some(p) = p else { continue };
        if surfaces[s].two_sided {
            continue;
        }
        let n = p.vertices.len();
        for k in 0..n {
            let (a, b) = (ids[s][k], ids[s][(k + 1) % n]);
            if a != b {
                edges.entry(edge_key(a, b)).or_default().push((s, a < b, k));
            }
        }
    }
    // neighbours[s]: (other face, same direction?, this face's edge index)
    let mut neighbours: Vec<Vec<(usize, bool, usize)>> = vec![Vec::new(); surfaces.len()];
    let mut inconsistent_edges = 0;
    let mut keys: Vec<&(u32, u32)> = edges.keys().collect();
    keys.sort();
    for key in keys {
        let users = &edges[key];
        if let [(s, fs, ks), (t, ft, kt)] = users[..] {
            if s != t {
                neighbours[s].push((t, fs == ft, ks));
                neighbours[t].push((s, fs == ft, kt));
                inconsistent_edges += usize::from(fs == ft);
            }
        }
    }
    let mut colour: Vec<Option<bool>> = vec![None; surfaces.len()];
    let mut flipped: Vec<usize> = Vec::new();
    for root in 0..surfaces.len() {
        if colour[root].is_some() || neighbours[root].is_empty() {
            continue;
        }
        colour[root] = Some(false);
        let mut patch = vec![root];
        let mut k = 0;
        while k < patch.len() {
            let s = patch[k];
            k += 1;
            let cs = colour[s].expect("coloured when queued");
            for &(t, same_direction, _) in &neighbours[s] {
                if colour[t].is_none() {
                    colour[t] = Some(cs ^ same_direction);
                    patch.push(t);
                }
            }
        }
        let odd = patch.iter().filter(|&&s| colour[s] == Some(true)).count();
        let minority = odd * 2 <= patch.len();
        flipped.extend(patch.into_iter().filter(|&s| colour[s] == Some(minority)));
    }
    flipped.sort_unstable();
    let mut per_object: Vec<ObjectCount> = Vec::new();
    for &s in &flipped {
        match per_object.iter_mut().find(|o| o.object == surfaces[s].object) {
            Some(o) => o.count += 1,
            None => per_object.push(ObjectCount { object: surfaces[s].object.clone(), count: 1 }),
        }
    }
    let examples = flipped
        .iter()
        .filter_map(|&s| {
            let &(t, _, k) = neighbours[s].iter().find(|n| n.1)?;
            let p = polys[s].as_ref()?;
            let mid = 0.5 * (p.vertices[k] + p.vertices[(k + 1) % p.vertices.len()]);
            Some(FlippedFace {
                surface: SurfaceRef { index: s, object: surfaces[s].object.clone() },
                neighbour: SurfaceRef { index: t, object: surfaces[t].object.clone() },
                point: to_f32(mid),
            })
        })
        .take(max_examples)
        .collect();
    FlippedFaces { count: flipped.len(), inconsistent_edges, per_object, examples }
}

fn to_f32(p: DVec3) -> [f32; 3] {
    p.as_vec3().to_array()
}

fn signed_area(q: &[[f64; 2]]) -> f64 {
    0.5 * (0..q.len())
        .map(|k| {
            let (p, r) = (q[k], q[(k + 1) % q.len()]);
            p[0] * r[1] - r[0] * p[1]
        })
        .sum::<f64>()
}

fn polygon_centroid(q: &[[f64; 2]]) -> Option<(f64, f64)> {
    let area = signed_area(q);
    if !(area.abs() > 0.0) {
        return None;
    }
    let (mut cx, mut cy) = (0.0, 0.0);
    for k in 0..q.len() {
        let (p, r) = (q[k], q[(k + 1) % q.len()]);
        let c = p[0] * r[1] - r[0] * p[1];
        cx += (p[0] + r[0]) * c;
        cy += (p[1] + r[1]) * c;
    }
    Some((cx / (6.0 * area), cy / (6.0 * area)))
}

fn project(q: &[[f64; 2]], axis: [f64; 2]) -> (f64, f64) {
    q.iter()
        .map(|p| p[0] * axis[0] + p[1] * axis[1])
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| (lo.min(x), hi.max(x)))
}

/// Sutherland–Hodgman: the part of convex polygon `subject` inside convex polygon `clip` (both
/// counter-clockwise).
fn clip_convex(subject: &[[f64; 2]], clip: &[[f64; 2]]) -> Vec<[f64; 2]> {
    let mut out = subject.to_vec();
    for k in 0..clip.len() {
        if out.is_empty() {
            break;
        }
        let (a, b) = (clip[k], clip[(k + 1) % clip.len()]);
        let inside = |p: [f64; 2]| (b[0] - a[0]) * (p[1] - a[1]) - (b[1] - a[1]) * (p[0] - a[0]);
        let input = std::mem::take(&mut out);
        for m in 0..input.len() {
            let (p, q) = (input[m], input[(m + 1) % input.len()]);
            let (sp, sq) = (inside(p), inside(q));
            if sp >= 0.0 {
                out.push(p);
            }
            if (sp >= 0.0) != (sq >= 0.0) {
                let t = sp / (sp - sq);
                out.push([p[0] + (q[0] - p[0]) * t, p[1] + (q[1] - p[1]) * t]);
            }
        }
    }
    out
}

impl fmt::Display for GeometryReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let point = |p: [f32; 3]| format!("({:.4}, {:.4}, {:.4})", p[0], p[1], p[2]);
        let s = |r: &SurfaceRef| format!("#{} `{}`", r.index, r.object);
        writeln!(
            f,
            "Geometry check: {} surfaces ({} skipped as degenerate), {} nearby pairs examined, tolerance {:.3e} (scene diagonal {:.4})",
            self.surface_count, self.skipped_surfaces, self.candidate_pairs, self.tolerance, self.scene_diagonal
        )?;
        let more = |f: &mut fmt::Formatter<'_>, count: usize, shown: usize| {
            if count > shown {
                writeln!(f, "      ... and {} more", count - shown)
            } else {
                Ok(())
            }
        };
        writeln!(f, "  T-junctions (cracks in interpolated radiosity): {}", self.t_junctions.count)?;
        for t in &self.t_junctions.examples {
            writeln!(
                f,
                "    - corner of {} at {} lies inside an edge of {}",
                s(&t.vertex_surface),
                point(t.point),
                s(&t.edge_surface)
            )?;
        }
        more(f, self.t_junctions.count, self.t_junctions.examples.len())?;
        writeln!(f, "  coplanar overlapping faces: {}", self.coplanar_overlaps.count)?;
        for c in &self.coplanar_overlaps.examples {
            let how = if c.same_facing { "same way (z-fighting)" } else { "opposite ways (back to back)" };
            writeln!(
                f,
                "    - {} and {} overlap by {:.4} around {}, facing {how}",
                s(&c.a),
                s(&c.b),
                c.overlap_area,
                point(c.point)
            )?;
        }
        more(f, self.coplanar_overlaps.count, self.coplanar_overlaps.examples.len())?;
        writeln!(f, "  intersecting faces (light leaks): {}", self.intersections.count)?;
        for x in &self.intersections.examples {
            writeln!(f, "    - {} crosses {} along {:.4} around {}", s(&x.a), s(&x.b), x.length, point(x.point))?;
        }
        more(f, self.intersections.count, self.intersections.examples.len())?;
        writeln!(
            f,
            "  faces flipped against their neighbours: {} ({} shared edges traversed the same way)",
            self.flipped.count, self.flipped.inconsistent_edges
        )?;
        if !self.flipped.per_object.is_empty() {
            let objects: Vec<String> =
                self.flipped.per_object.iter().map(|o| format!("`{}`: {}", o.object, o.count)).collect();
            writeln!(f, "    per object: {}", objects.join(", "))?;
        }
        for x in &self.flipped.examples {
            writeln!(
                f,
                "    - {} disagrees with {} at the edge around {}",
                s(&x.surface),
                s(&x.neighbour),
                point(x.point)
            )?;
        }
        more(f, self.flipped.count, self.flipped.examples.len())?;
        writeln!(f, "  non-planar polygons: {}", self.non_planar.count)?;
        for x in &self.non_planar.examples {
            writeln!(
                f,
                "    - {}: a corner at {} is {:.4} off the polygon's plane",
                s(&x.surface),
                point(x.point),
                x.deviation
            )?;
        }
        more(f, self.non_planar.count, self.non_planar.examples.len())?;
        if self.is_clean() {
            write!(f, "  no suspicious geometry")?;
        } else {
            write!(f, "  see above: these are the usual causes of light leaks and cracks")?;
        }
        Ok(())
    }
}
