//! Ray queries against the scene's triangles: the only user of obvhs. A compressed wide BVH8 (CWBVH,
//! Ylitie et al. 2017) over the mesh's tracing triangles, with a watertight ray/triangle test.

use std::time::Duration;

use glam::{UVec2, Vec3, Vec3A};
use obvhs::{
    aabb::Aabb,
    cwbvh::{builder::build_cwbvh, CwBvh},
    ray::{Ray as BvhRay, RayHit},
    traverse,
    triangle::Triangle,
    Boundable, BvhBuildParams,
};

/// The closest intersection of a ray with the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Hit {
    /// Ray parameter of the hit: the point is `origin + t·dir`.
    pub t: f32,
    /// Index into the triangle list the accelerator was built from (`Mesh::triangles`).
    pub triangle: u32,
    /// Barycentrics: p = (1 − u − v)·v0 + u·v1 + v·v2.
    pub u: f32,
    pub v: f32,
}

/// obvhs' node test ignores `Ray::tmin` and culls every box the ray leaves before t = 1e-4 (in units of
/// the ray direction). We hand obvhs a ray whose origin is moved back by `BVH_ORIGIN_SHIFT` so that no
/// box near the true origin is lost; triangle distances are measured from the true origin.
const BVH_ORIGIN_SHIFT: f32 = 1e-3;

/// obvhs' node test is a plain slab test, not a conservative one (Ize 2013): a ray that enters a flat
/// node (an axis-aligned wall's triangles have zero extent across the wall) exactly on a boundary it
/// shares with its neighbour can be rejected by both, and the hit is lost (see docs/performance.md,
/// "Measurements behind the code"). Every triangle's box is therefore
/// widened by this fraction of the scene's largest extent along an axis (about 70 f32 ulps of a scene
/// that touches the origin); the watertight triangle test still decides the hit.
const BOX_PADDING: f32 = 1e-6 * 8.0;

/// ... and by at least this many ε (`f32::EPSILON`) of the triangle's own largest coordinate magnitude,
/// the resolution of its coordinates. The padding used to be `BOX_PADDING` × the scene's largest
/// coordinate magnitude: l_room (6 m) moved to x = 10⁵ padded every box by 0.8 m, the boxes all
/// overlapped and rays slowed down 50-fold (hierarchical radiosity's direct part: 0.19 s → 13.6 s).
const BOX_PADDING_EPSILONS: f32 = 8.0;

/// A triangle's bounding box, widened by `BOX_PADDING`: what the BVH is built from.
struct PaddedBox(Aabb);

impl Boundable for PaddedBox {
    fn aabb(&self) -> Aabb {
        self.0
    }
}

/// A bounding volume hierarchy over triangles: closest-hit and any-hit queries. Both sides of every
/// triangle are hit (no culling).
pub struct Accel {
    bvh: CwBvh,
    /// Triangle corners in BVH primitive order (so leaves read contiguous memory).
    vertices: Vec<[Vec3; 3]>,
    /// The original triangle index of each BVH primitive.
    triangle_id: Vec<u32>,
}

impl Accel {
    /// Builds the hierarchy over `triangles` (indices into `positions`).
    pub fn build(positions: &[Vec3], triangles: &[[u32; 3]]) -> Accel {
        if triangles.is_empty() {
            return Accel { bvh: CwBvh::default(), vertices: Vec::new(), triangle_id: Vec::new() };
        }
        let (lo, hi) = positions
            .iter()
            .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let extent_pad = BOX_PADDING * (hi - lo).max_element().max(f32::MIN_POSITIVE);
        let boxes: Vec<PaddedBox> = triangles
            .iter()
            .map(|t| {
                let tri = Triangle {
                    v0: positions[t[0] as usize].into(),
                    v1: positions[t[1] as usize].into(),
                    v2: positions[t[2] as usize].into(),
                };
                let aabb = tri.aabb();
                let magnitude = aabb.min.abs().max(aabb.max.abs()).max_element();
                let pad = Vec3A::splat(extent_pad.max(magnitude * (BOX_PADDING_EPSILONS * f32::EPSILON)));
                PaddedBox(Aabb::new(aabb.min - pad, aabb.max + pad))
            })
            .collect();
        // medium_build does not pre-split triangles, so building from boxes loses nothing.
        let bvh = build_cwbvh(&boxes, BvhBuildParams::medium_build(), &mut Duration::default());
        let triangle_id = bvh.primitive_indices.clone();
        let vertices = triangle_id
            .iter()
            .map(|&i| {
                let t = triangles[i as usize];
                t.map(|v| positions[v as usize])
            })
            .collect();
        Accel { bvh, vertices, triangle_id }
    }

    /// Number of triangles.
    pub fn len(&self) -> usize {
        self.triangle_id.len()
    }

    pub fn is_empty(&self) -> bool {
        self.triangle_id.is_empty()
    }

    /// The ray handed to obvhs. Its direction has no negative zeros: obvhs picks a child's near and far
    /// planes by `dir < 0` (false for −0.0) but inverts −0.0 to −1/ε, so a component of −0.0 swaps
    /// the planes, empties the slab, and an axis-aligned ray such as (0, −1, 0) written as −n misses
    /// the floor under it. Adding +0.0 turns −0.0 into +0.0 and leaves every other value alone.
    fn bvh_ray(origin: Vec3, dir: Vec3, t_max: f32) -> BvhRay {
        let dir = dir + Vec3::ZERO;
        let shifted = Vec3A::from(origin - dir * BVH_ORIGIN_SHIFT);
        BvhRay::new(shifted, dir.into(), 0.0, t_max + BVH_ORIGIN_SHIFT)
    }

    /// The closest hit with t in (`t_min`, `t_max`], front or back side. `dir` need not be unit
    /// length; `t` is in units of it.
    pub fn closest_hit(&self, origin: Vec3, dir: Vec3, t_min: f32, t_max: f32) -> Option<Hit> {
        if self.is_empty() || !valid_ray(origin, dir) || t_max.is_nan() || t_min.is_nan() || t_max <= t_min {
            return None;
        }
        let ray = WatertightRay::new(origin, dir);
        let mut best: Option<(u32, TriangleHit)> = None;
        let mut hit = RayHit::none();
        self.bvh.ray_traverse(Self::bvh_ray(origin, dir, t_max), &mut hit, |bvh_ray, id| {
            let [v0, v1, v2] = self.vertices[id];
            match ray.intersect(v0, v1, v2, t_min, bvh_ray.tmax - BVH_ORIGIN_SHIFT) {
                Some(h) => {
                    let t_shifted = h.t + BVH_ORIGIN_SHIFT;
                    if t_shifted < bvh_ray.tmax {
                        best = Some((id as u32, h));
                    }
                    t_shifted
                }
                None => f32::INFINITY,
            }
        });
        best.map(|(id, h)| Hit { t: h.t, triangle: self.triangle_id[id as usize], u: h.u, v: h.v })
    }

    /// Whether anything lies on the ray with t in (0, `t_max`] (any hit, either side).
    pub fn occluded(&self, origin: Vec3, dir: Vec3, t_max: f32) -> bool {
        if self.is_empty() || !valid_ray(origin, dir) || t_max.is_nan() || t_max <= 0.0 {
            return false;
        }
        let ray = WatertightRay::new(origin, dir);
        !self.bvh.ray_traverse_miss(Self::bvh_ray(origin, dir, t_max), |_, id| {
            let [v0, v1, v2] = self.vertices[id];
            match ray.intersect(v0, v1, v2, 0.0, t_max) {
                Some(_) => 0.0,
                None => f32::INFINITY,
            }
        })
    }
}

impl Accel {
    /// Calls `visit` with the corners of every triangle whose box in the hierarchy (padded, see
    /// `BOX_PADDING`) overlaps the box [`lo`, `hi`], and possibly of a few more (the CWBVH's child
    /// boxes are quantized outwards), in no particular order, until `visit` returns false. Returns
    /// false when `visit` stopped it, true when every such triangle was visited. A superset query:
    /// no triangle that meets the box is left out, so a caller may conclude from the triangles
    /// visited that nothing else lies in the box.
    pub fn visit_triangles_in_box(&self, lo: Vec3, hi: Vec3, mut visit: impl FnMut(&[Vec3; 3]) -> bool) -> bool {
        if self.is_empty() {
            return true;
        }
        let query = Aabb::new(Vec3A::from(lo), Vec3A::from(hi));
        let mut stopped = false;
        let mut state = self.bvh.new_traversal(Vec3A::ONE);
        let mut node;
        traverse!(self.bvh, node, state, if stopped { 0 } else { node.intersect_aabb(&query, state.oct_inv4) }, {
            if !stopped && !visit(&self.vertices[state.primitive_id as usize]) {
                stopped = true;
            }
        });
        !stopped
    }
}

/// A finite origin and a finite, non-zero direction (anything else hits nothing).
fn valid_ray(origin: Vec3, dir: Vec3) -> bool {
    origin.is_finite() && dir.is_finite() && dir != Vec3::ZERO
}

/// A ray/triangle intersection: distance and barycentrics (p = (1 − u − v)·v0 + u·v1 + v·v2).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TriangleHit {
    pub t: f32,
    pub u: f32,
    pub v: f32,
}

/// A ray prepared for the watertight ray/triangle test of Woop, Benthin and Wald (2013): the
/// coordinate axes are permuted so that the ray's dominant axis is z, and the triangle is sheared so
/// that the ray becomes the +z axis. Edge functions computed in that frame are exactly consistent
/// between triangles sharing an edge, so rays never slip through shared edges or vertices.
#[derive(Clone, Copy, Debug)]
pub struct WatertightRay {
    origin: Vec3,
    dir: Vec3,
    kx: usize,
    ky: usize,
    kz: usize,
    shear_x: f32,
    shear_y: f32,
    shear_z: f32,
}

impl WatertightRay {
    pub fn new(origin: Vec3, dir: Vec3) -> Self {
        let a = dir.abs();
        let kz = if a.x > a.y {
            if a.x > a.z {
                0
            } else {
                2
            }
        } else if a.y > a.z {
            1
        } else {
            2
        };
        let mut kx = (kz + 1) % 3;
        let mut ky = (kx + 1) % 3;
        let d = dir.to_array();
        if d[kz] < 0.0 {
            std::mem::swap(&mut kx, &mut ky);
        }
        WatertightRay { origin, dir, kx, ky, kz, shear_x: d[kx] / d[kz], shear_y: d[ky] / d[kz], shear_z: 1.0 / d[kz] }
    }

    /// Intersection with triangle (v0, v1, v2) for t in (`t_min`, `t_max`], either side.
    ///
    /// With A, B, C the corners relative to the origin, permuted and sheared
    /// (x' = x − S_x z, y' = y − S_y z), the scaled barycentrics are the 2D edge functions
    /// U = C'x B'y − C'y B'x, V = A'x C'y − A'y C'x, W = B'x A'y − B'y A'x; the ray hits when U, V, W have
    /// one sign, and t = (U A_z + V B_z + W C_z)·S_z / (U + V + W). Exact zeros are re-evaluated in
    /// double precision, as in the paper. (Woop, Benthin, Wald, "Watertight Ray/Triangle
    /// Intersection", JCGT 2013.)
    #[inline(always)]
    pub fn intersect(&self, v0: Vec3, v1: Vec3, v2: Vec3, t_min: f32, t_max: f32) -> Option<TriangleHit> {
        let a = (v0 - self.origin).to_array();
        let b = (v1 - self.origin).to_array();
        let c = (v2 - self.origin).to_array();
        let (kx, ky, kz) = (self.kx, self.ky, self.kz);
        let ax = a[kx] - self.shear_x * a[kz];
        let ay = a[ky] - self.shear_y * a[kz];
        let bx = b[kx] - self.shear_x * b[kz];
        let by = b[ky] - self.shear_y * b[kz];
        let cx = c[kx] - self.shear_x * c[kz];
        let cy = c[ky] - self.shear_y * c[kz];
        let mut u = cx * by - cy * bx;
        let mut v = ax * cy - ay * cx;
        let mut w = bx * ay - by * ax;
        if u == 0.0 || v == 0.0 || w == 0.0 {
            let (cx, cy, bx, by, ax, ay) = (cx as f64, cy as f64, bx as f64, by as f64, ax as f64, ay as f64);
            u = (cx * by - cy * bx) as f32;
            v = (ax * cy - ay * cx) as f32;
            w = (bx * ay - by * ax) as f32;
        }
        if (u < 0.0 || v < 0.0 || w < 0.0) && (u > 0.0 || v > 0.0 || w > 0.0) {
            return None;
        }
        let det = u + v + w;
        if det == 0.0 {
            return None;
        }
        let az = self.shear_z * a[kz];
        let bz = self.shear_z * b[kz];
        let cz = self.shear_z * c[kz];
        let t_scaled = u * az + v * bz + w * cz;
        // t = t_scaled / det, compared without dividing: flip signs so that det > 0.
        let (t_scaled, abs_det) = if det < 0.0 { (-t_scaled, -det) } else { (t_scaled, det) };
        if !(t_scaled > t_min * abs_det && t_scaled <= t_max * abs_det) {
            return None;
        }
        let inv_det = 1.0 / det;
        Some(TriangleHit { t: t_scaled / abs_det, u: v * inv_det, v: w * inv_det })
    }

    pub fn origin(&self) -> Vec3 {
        self.origin
    }

    pub fn dir(&self) -> Vec3 {
        self.dir
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::Pcg32;
    use glam::{vec3, DVec3};

    /// Uniform in [0, 1)³.
    fn random_vec(rng: &mut Pcg32) -> Vec3 {
        vec3(rng.next_f32(), rng.next_f32(), rng.next_f32())
    }

    /// Uniform over directions: points of [−1, 1)³ drawn until one lies in the shell 0.1 < |v| ≤ 1.
    fn random_unit(rng: &mut Pcg32) -> Vec3 {
        std::iter::repeat_with(|| random_vec(rng) * 2.0 - Vec3::ONE)
            .find(|v| v.length() > 0.1 && v.length() <= 1.0)
            .map(|v| v / v.length())
            .expect("an endless stream of candidates")
    }

    /// Möller–Trumbore in double precision, for tests that need a reference independent of the
    /// watertight test: t and barycentrics (u on v1, v on v2) of the hit, either side, no range check.
    fn intersect_triangle_f64(origin: Vec3, dir: Vec3, v0: Vec3, v1: Vec3, v2: Vec3) -> Option<(f64, f64, f64)> {
        let (o, d) = (origin.as_dvec3(), dir.as_dvec3());
        let (p0, p1, p2): (DVec3, DVec3, DVec3) = (v0.as_dvec3(), v1.as_dvec3(), v2.as_dvec3());
        let e1 = p1 - p0;
        let e2 = p2 - p0;
        let p = d.cross(e2);
        let det = e1.dot(p);
        if det == 0.0 {
            return None;
        }
        let inv = 1.0 / det;
        let s = o - p0;
        let u = s.dot(p) * inv;
        let q = s.cross(e1);
        let v = d.dot(q) * inv;
        if u < 0.0 || v < 0.0 || u + v > 1.0 {
            return None;
        }
        Some((e2.dot(q) * inv, u, v))
    }

    fn triangle_soup(rng: &mut Pcg32, count: usize) -> (Vec<Vec3>, Vec<[u32; 3]>) {
        let mut positions = Vec::new();
        let mut triangles = Vec::new();
        for i in 0..count {
            let centre = random_vec(rng) * 10.0;
            for _ in 0..3 {
                positions.push(centre + (random_vec(rng) - Vec3::splat(0.5)) * 1.5);
            }
            let b = 3 * i as u32;
            triangles.push([b, b + 1, b + 2]);
        }
        (positions, triangles)
    }

    fn brute_force_closest(positions: &[Vec3], triangles: &[[u32; 3]], origin: Vec3, dir: Vec3) -> Option<(u32, f32)> {
        let ray = WatertightRay::new(origin, dir);
        let mut best: Option<(u32, f32)> = None;
        for (i, t) in triangles.iter().enumerate() {
            let [a, b, c] = t.map(|v| positions[v as usize]);
            if let Some(h) = ray.intersect(a, b, c, 0.0, best.map_or(f32::INFINITY, |b| b.1)) {
                if best.is_none_or(|b| h.t < b.1) {
                    best = Some((i as u32, h.t));
                }
            }
        }
        best
    }

    #[test]
    fn bvh_closest_hit_matches_brute_force_on_random_soup() {
        let mut rng = Pcg32::new(42, 0);
        let (positions, triangles) = triangle_soup(&mut rng, 3000);
        let accel = Accel::build(&positions, &triangles);
        let mut hits = 0;
        for _ in 0..3000 {
            let origin = random_vec(&mut rng) * 14.0 - Vec3::splat(2.0);
            let dir = random_unit(&mut rng);
            let bvh = accel.closest_hit(origin, dir, 0.0, f32::INFINITY);
            let brute = brute_force_closest(&positions, &triangles, origin, dir);
            match (bvh, brute) {
                (None, None) => {}
                (Some(h), Some((tri, t))) => {
                    hits += 1;
                    // The same watertight test runs in both: identical distances. The triangle may differ
                    // only on an exact tie.
                    assert_eq!(h.t, t, "ray {origin} {dir}");
                    if h.triangle != tri {
                        let other = triangles[h.triangle as usize].map(|v| positions[v as usize]);
                        let t2 = WatertightRay::new(origin, dir).intersect(other[0], other[1], other[2], 0.0, f32::MAX);
                        assert_eq!(t2.map(|h| h.t), Some(t), "tie expected");
                    }
                    // Independent double-precision reference for distance and barycentrics: f32
                    // coordinates of order 10 carry ~1e-6 absolute error, amplified by at most a few
                    // hundred at grazing incidence in random soups.
                    let [a, b, c] = triangles[h.triangle as usize].map(|v| positions[v as usize]);
                    if let Some((t64, u64, v64)) = intersect_triangle_f64(origin, dir, a, b, c) {
                        assert!((h.t as f64 - t64).abs() < 1e-3 * t64.max(1.0), "t {} vs {t64}", h.t);
                        assert!((h.u as f64 - u64).abs() < 1e-3 && (h.v as f64 - v64).abs() < 1e-3);
                    }
                }
                (a, b) => panic!("ray {origin} {dir}: bvh {a:?} vs brute force {b:?}"),
            }
        }
        assert!(hits > 500, "the soup should be hit often, got {hits}");
    }

    #[test]
    fn bvh_occlusion_matches_brute_force() {
        let mut rng = Pcg32::new(7, 3);
        let (positions, triangles) = triangle_soup(&mut rng, 2000);
        let accel = Accel::build(&positions, &triangles);
        let (mut blocked, mut free) = (0, 0);
        for _ in 0..3000 {
            let origin = random_vec(&mut rng) * 14.0 - Vec3::splat(2.0);
            let dir = random_unit(&mut rng);
            let t_max = rng.next_f32() * 8.0;
            let brute = brute_force_closest(&positions, &triangles, origin, dir).is_some_and(|(_, t)| t < t_max);
            // The any-hit query accepts t ≤ t_max; exclude rays whose closest hit sits within rounding of t_max.
            if brute_force_closest(&positions, &triangles, origin, dir).is_some_and(|(_, t)| (t - t_max).abs() < 1e-5) {
                continue;
            }
            assert_eq!(accel.occluded(origin, dir, t_max), brute, "ray {origin} {dir} t_max {t_max}");
            if brute {
                blocked += 1;
            } else {
                free += 1;
            }
        }
        assert!(blocked > 200 && free > 200, "both outcomes exercised: {blocked} blocked, {free} free");
    }

    #[test]
    fn closest_hit_respects_t_min_and_t_max() {
        // Two parallel triangles at z = 0 and z = −1 under a ray going down from z = 1.
        let positions = [
            vec3(-1.0, -1.0, 0.0),
            vec3(1.0, -1.0, 0.0),
            vec3(0.0, 1.0, 0.0),
            vec3(-1.0, -1.0, -1.0),
            vec3(1.0, -1.0, -1.0),
            vec3(0.0, 1.0, -1.0),
        ];
        let accel = Accel::build(&positions, &[[0, 1, 2], [3, 4, 5]]);
        let o = vec3(0.0, 0.0, 1.0);
        assert_eq!(accel.closest_hit(o, Vec3::NEG_Z, 0.0, 10.0).map(|h| h.triangle), Some(0));
        assert_eq!(accel.closest_hit(o, Vec3::NEG_Z, 1.5, 10.0).map(|h| h.triangle), Some(1));
        assert_eq!(accel.closest_hit(o, Vec3::NEG_Z, 0.0, 0.5), None);
        // Back sides are hit too.
        assert_eq!(accel.closest_hit(vec3(0.0, 0.0, -2.0), Vec3::Z, 0.0, 10.0).map(|h| h.triangle), Some(1));
    }

    #[test]
    fn watertight_test_hits_both_sides_with_barycentrics() {
        let (v0, v1, v2) = (vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0));
        let p = vec3(0.2, 0.3, 0.0);
        for dir in [vec3(0.0, 0.0, -1.0), vec3(0.0, 0.0, 1.0), vec3(0.3, -0.2, 1.0).normalize()] {
            let origin = p - dir * 2.0;
            let h = WatertightRay::new(origin, dir).intersect(v0, v1, v2, 0.0, f32::INFINITY).expect("hit");
            // Single-precision arithmetic on values of order 1: a few ulps.
            assert!((h.t - 2.0).abs() < 1e-5, "{h:?}");
            assert!((h.u - 0.2).abs() < 1e-5 && (h.v - 0.3).abs() < 1e-5, "{h:?}");
        }
    }

    #[test]
    fn shared_edge_is_never_missed() {
        // Two triangles sharing the diagonal of the unit square; rays aimed exactly at the diagonal
        // must hit at least one of them (watertightness).
        let q = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(1.0, 1.0, 0.0), vec3(0.0, 1.0, 0.0)];
        let origin = vec3(0.123, 0.777, 1.0);
        for i in 0..=1000 {
            let s = i as f32 / 1000.0;
            let dir = vec3(s, s, 0.0) - origin;
            let ray = WatertightRay::new(origin, dir);
            let a = ray.intersect(q[0], q[1], q[2], 0.0, f32::INFINITY);
            let b = ray.intersect(q[0], q[2], q[3], 0.0, f32::INFINITY);
            assert!(a.is_some() || b.is_some(), "ray to ({s}, {s}) slipped through the shared edge");
        }
    }

    #[test]
    fn empty_accel_misses() {
        let accel = Accel::build(&[], &[]);
        assert!(accel.closest_hit(Vec3::ZERO, Vec3::X, 0.0, f32::INFINITY).is_none());
        assert!(!accel.occluded(Vec3::ZERO, Vec3::X, f32::INFINITY));
    }

    #[test]
    fn degenerate_rays_hit_nothing() {
        let positions = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)];
        let accel = Accel::build(&positions, &[[0, 1, 2]]);
        for dir in [Vec3::ZERO, Vec3::NAN, vec3(0.0, 0.0, f32::INFINITY)] {
            assert!(accel.closest_hit(vec3(0.2, 0.2, 1.0), dir, 0.0, f32::INFINITY).is_none());
            assert!(!accel.occluded(vec3(0.2, 0.2, 1.0), dir, 10.0));
        }
    }

    #[test]
    fn single_triangle_accel_hits_near_origin() {
        let positions = [vec3(0.0, 0.0, 0.0), vec3(1.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0)];
        let accel = Accel::build(&positions, &[[0, 1, 2]]);
        // A hit closer than obvhs' internal 1e-4 box epsilon is still found.
        let h = accel.closest_hit(vec3(0.25, 0.25, 1e-5), Vec3::NEG_Z, 0.0, f32::INFINITY).expect("hit");
        assert_eq!(h.triangle, 0);
        assert!((h.t - 1e-5).abs() < 1e-7, "{h:?}");
        assert!(accel.occluded(vec3(0.25, 0.25, 1e-5), Vec3::NEG_Z, 1.0));
        assert!(!accel.occluded(vec3(0.25, 0.25, 1.0), Vec3::NEG_Z, 0.5));
    }

    #[test]
    fn axis_aligned_rays_with_negative_zero_components_hit() {
        // A floor quad of a unit box; rays straight down written as −n = (−0, −1, −0), from several
        // heights and over interior points, including ones on the quad's diagonal.
        let positions = [vec3(0.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0)];
        let accel = Accel::build(&positions, &[[0, 1, 2], [0, 2, 3]]);
        let down = -Vec3::Y;
        assert!(down.x.is_sign_negative() && down.z.is_sign_negative());
        for &(x, z) in &[(0.1f32, 0.02f32), (0.5, 0.5), (0.9, 0.3), (0.02, 0.7)] {
            for height in [1e-3f32, 1e-2, 0.5] {
                let h = accel.closest_hit(vec3(x, height, z), down, 0.0, 1.0);
                let h = h.unwrap_or_else(|| panic!("({x}, {height}, {z}) straight down missed the floor"));
                assert!((h.t - height).abs() < 1e-6, "{h:?}");
                assert!(accel.occluded(vec3(x, height, z), down, 1.0));
            }
        }
    }
}
