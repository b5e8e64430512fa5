//! Suspicious-geometry checks for `radray info`: T-junctions, coplanar overlapping faces, intersecting
//! faces, normals flipped relative to their neighbours and non-planar polygons — the usual sources of
//! radiosity light leaks and cracks, found from the scene's polygons before anything is solved.
//!
//! Every check is a pure function of the surfaces, one per file. Candidate pairs come from a uniform
//! grid over the faces' bounding boxes (`grid`, each pair visited once), so the cost grows with the
//! number of nearby pairs, not with n²; pairs are examined in parallel (rayon) and their findings
//! gathered in the pairs' order, so the report does not depend on the thread count. Geometry is evaluated in f64 (`polygon`). Lengths are compared
//! with one absolute tolerance, `relative_tolerance` × the scene's bounding-box diagonal along its principal frame (never below
//! the f32 spacing of the scene's coordinates): see [`LintOptions`]. This file holds the report's types
//! and runs the checks; `report` prints it.

pub mod crossings;
pub mod flipped;
mod grid;
pub mod overlaps;
pub mod planarity;
pub mod polygon;
mod report;
pub mod t_junctions;
mod weld;

pub use polygon::Poly;

use crate::scene::{frame, SceneDescription, Surface};
use glam::DVec3;
use rayon::prelude::*;
use serde::Serialize;

/// Settings of [`check_surfaces`].
#[derive(Clone, Debug, PartialEq)]
pub struct LintOptions {
    /// Length tolerance as a fraction of the scene's bounding-box diagonal. The default 1e-5 is
    /// ~100 f32 ulps of a scene's extent (far above rounding noise) and ten times finer than the
    /// deliberate 0.1 mm gap between the Cornell box's light and its ceiling (1e-4 of its diagonal).
    pub relative_tolerance: f64,
    /// How many examples of each finding the report keeps (the counts are always complete).
    pub max_examples: usize,
}

impl Default for LintOptions {
    fn default() -> Self {
        LintOptions { relative_tolerance: 1e-5, max_examples: 5 }
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

impl SurfaceRef {
    /// Names `surfaces[index]`.
    pub fn of(surfaces: &[Surface], index: usize) -> SurfaceRef {
        SurfaceRef { index, object: surfaces[index].object.clone() }
    }
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

impl<T> Findings<T> {
    /// All findings of one kind, already in report order: counted, the first `max_examples` kept.
    pub fn new(mut all: Vec<T>, max_examples: usize) -> Self {
        let count = all.len();
        all.truncate(max_examples);
        Findings { count, examples: all }
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

/// What [`check`] found.
#[derive(Clone, Debug, PartialEq, Serialize)]
pub struct GeometryReport {
    pub surface_count: usize,
    /// Surfaces left out of every check: fewer than 3 corners, non-finite corners or zero area.
    pub skipped_surfaces: usize,
    /// Diagonal of the scene's bounding box along its principal frame (`scene::frame`).
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

/// The diagonal of the surfaces' bounding box along the scene's principal frame (`frame::of_polygons`,
/// as `SceneDescription::diagonal` measures the scene), so that a room built at an angle to the world
/// axes gets the tolerance it gets built along them; 0 without a checkable polygon.
fn frame_diagonal(surfaces: &[Surface], polys: &[Option<Poly>]) -> f64 {
    let frame = frame::of_polygons(surfaces.iter().map(|s| s.vertices.as_slice()));
    let (lo, hi) = polys.iter().flatten().flat_map(|p| p.vertices.iter()).fold(
        (DVec3::INFINITY, DVec3::NEG_INFINITY),
        |(lo, hi), &v| {
            let q = frame.to_frame_f64(v);
            (lo.min(q), hi.max(q))
        },
    );
    if lo.x <= hi.x {
        (hi - lo).length()
    } else {
        0.0
    }
}

/// The pairs (i, j) of surfaces with polygons whose bounding boxes, grown by `tolerance`, meet, from a
/// uniform grid over the boxes (`grid::candidate_pairs`, each pair once, O(nearby pairs)).
fn nearby_pairs(polys: &[Option<Poly>], tolerance: f64) -> Vec<(usize, usize)> {
    let live: Vec<usize> = (0..polys.len()).filter(|&i| polys[i].is_some()).collect();
    let boxes: Vec<(DVec3, DVec3)> = live
        .iter()
        .map(|&i| {
            let p = polys[i].as_ref().expect("live surfaces have a polygon");
            (p.lo - DVec3::splat(tolerance), p.hi + DVec3::splat(tolerance))
        })
        .collect();
    grid::candidate_pairs(&boxes).into_iter().map(|(a, b)| (live[a as usize], live[b as usize])).collect()
}

/// Checks the scene's surfaces with the default options (see [`check_surfaces`]).
pub fn check(scene: &SceneDescription) -> GeometryReport {
    check_surfaces(&scene.surfaces, &LintOptions::default())
}

/// Runs every check over `surfaces` (planar convex polygons, counter-clockwise seen from the front):
///
/// - **T-junctions** ([`t_junctions::between`]): a corner of one face closer than the tolerance to the
///   inside of another face's edge and farther than the tolerance from both of its endpoints. Each
///   (vertex position, edge) is counted once.
/// - **Coplanar overlaps** ([`overlaps::coplanar_overlap`]): parallel faces with every corner of each within the
///   tolerance of the other's plane, whose polygons overlap by more than the tolerance on every
///   separating axis (2-D SAT); touching along an edge or at a corner is not an overlap.
/// - **Intersections** ([`crossings::crossing`]): non-coplanar faces, each with corners farther than the
///   tolerance on both sides of the other's plane, whose intervals on the planes' line of intersection
///   overlap by more than the tolerance (Möller 1997, "A fast triangle-triangle intersection test").
/// - **Flipped faces** ([`flipped::flipped_faces`]): faces sharing an edge (both endpoints within the tolerance) that traverse it
///   in the same direction; within each edge-connected patch the minority orientation is reported.
///   Two-sided surfaces and edges shared by more than two faces are left out.
/// - **Non-planar polygons** ([`planarity::non_planar`]): a corner farther than the tolerance from the polygon's best plane.
pub fn check_surfaces(surfaces: &[Surface], options: &LintOptions) -> GeometryReport {
    let polys: Vec<Option<Poly>> = surfaces.iter().map(|s| Poly::new(&s.vertices)).collect();
    let skipped_surfaces = polys.iter().filter(|p| p.is_none()).count();
    let (lo, hi) =
        polys.iter().flatten().fold((DVec3::INFINITY, DVec3::NEG_INFINITY), |(lo, hi), p| (lo.min(p.lo), hi.max(p.hi)));
    let scene_diagonal = frame_diagonal(surfaces, &polys);
    let magnitude = if lo.x <= hi.x { lo.abs().max(hi.abs()).max_element() } else { 0.0 };
    let tolerance = (options.relative_tolerance * scene_diagonal).max(8.0 * f32::EPSILON as f64 * magnitude);
    let tolerance = if tolerance > 0.0 { tolerance } else { f32::EPSILON as f64 };
    let vertex_ids = weld::weld_vertices(&polys, tolerance);

    // Pairwise checks over grid candidates. Each pair is examined on its own (in parallel); the
    // findings are gathered in the pairs' order, so the report is the same for any number of threads.
    let pairs = nearby_pairs(&polys, tolerance);
    let candidate_pairs = pairs.len();
    let mut t_junctions = t_junctions::Collector::new(surfaces, &vertex_ids, tolerance);
    let collector = &t_junctions;
    let per_pair: Vec<PairFindings> = pairs
        .par_iter()
        .filter_map(|&(i, j)| {
            let (pi, pj) = (polys[i].as_ref().expect("live"), polys[j].as_ref().expect("live"));
            let t_junctions = collector.pair((i, pi), (j, pj));
            let mut found = PairFindings { t_junctions, overlap: None, intersection: None };
            if let Some(overlap) = overlaps::coplanar_overlap(pi, pj, tolerance) {
                found.overlap = Some(CoplanarOverlap {
                    a: SurfaceRef::of(surfaces, i),
                    b: SurfaceRef::of(surfaces, j),
                    same_facing: overlap.same_facing,
                    overlap_area: overlap.area,
                    point: to_f32(overlap.centroid),
                });
            } else if let Some((length, point)) = crossings::crossing(pi, pj, tolerance) {
                found.intersection = Some(Intersection {
                    a: SurfaceRef::of(surfaces, i),
                    b: SurfaceRef::of(surfaces, j),
                    length,
                    point: to_f32(point),
                });
            }
            let empty = found.t_junctions.is_empty() && found.overlap.is_none() && found.intersection.is_none();
            (!empty).then_some(found)
        })
        .collect();
    let mut coplanar_overlaps: Vec<CoplanarOverlap> = Vec::new();
    let mut intersections: Vec<Intersection> = Vec::new();
    for found in per_pair {
        t_junctions.extend(found.t_junctions);
        coplanar_overlaps.extend(found.overlap);
        intersections.extend(found.intersection);
    }
    coplanar_overlaps.sort_by_key(|c| (c.a.index, c.b.index));
    intersections.sort_by_key(|x| (x.a.index, x.b.index));

    GeometryReport {
        surface_count: surfaces.len(),
        skipped_surfaces,
        scene_diagonal,
        tolerance,
        candidate_pairs,
        t_junctions: Findings::new(t_junctions.finish(), options.max_examples),
        coplanar_overlaps: Findings::new(coplanar_overlaps, options.max_examples),
        intersections: Findings::new(intersections, options.max_examples),
        flipped: flipped::flipped_faces(surfaces, &polys, &vertex_ids, options.max_examples),
        non_planar: Findings::new(planarity::non_planar(surfaces, &polys, tolerance), options.max_examples),
    }
}

/// What one candidate pair showed.
struct PairFindings {
    t_junctions: Vec<t_junctions::Candidate>,
    overlap: Option<CoplanarOverlap>,
    intersection: Option<Intersection>,
}

fn to_f32(p: DVec3) -> [f32; 3] {
    p.as_vec3().to_array()
}
