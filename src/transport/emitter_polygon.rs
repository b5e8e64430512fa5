//! One emitting polygon: the coplanar emitting triangles cut from one scene surface, sampled as the
//! polygon they tile (a parallelogram by its bilinear map, otherwise a fan over its convex hull), then
//! the mesh triangle under the point found in a small grid over the polygon's plane. A unit-square
//! point maps onto the polygon continuously (at most one seam per fan diagonal), so a stratified pattern
//! stays stratified over the whole lamp however finely the mesher cut it.

use glam::{Vec2, Vec3};

use super::emitters::uniform_triangle_point;

/// A convex planar polygon tiled exactly by a set of triangles, with a point location over them.
#[derive(Clone, Debug, PartialEq)]
pub struct EmitterPolygon {
    /// Corners of the convex hull, in order around it.
    corners: Vec<Vec3>,
    /// Σ of the fan triangles' areas (c₀, cₖ₊₁, cₖ₊₂) up to and including k; empty for a parallelogram.
    fan_cumulative_area: Vec<f32>,
    area: f32,
    locator: TriangleLocator,
}

impl EmitterPolygon {
    /// The polygon tiled by `triangles` (corner positions, all in the plane through their first
    /// corner with unit normal `normal`), when they are coplanar and tile their convex hull (their
    /// areas sum to the hull's); `None` otherwise (a non-planar quad, a concave outline, a textured
    /// emitter with dark elements left out), and the caller samples the triangles one by one.
    pub fn new(triangles: &[[Vec3; 3]], normal: Vec3) -> Option<EmitterPolygon> {
        let first = triangles.first()?[0];
        let (tangent, bitangent) = normal.any_orthonormal_pair();
        let plane = Plane { origin: first, tangent, bitangent };
        let points: Vec<Vec3> = triangles.iter().flatten().copied().collect();
        let (lo, hi) = points.iter().fold((Vec3::INFINITY, Vec3::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let extent = (hi - lo).length();
        if !(extent.is_finite() && extent > 0.0)
            || points.iter().any(|&p| (p - first).dot(normal).abs() > 1e-5 * extent)
        {
            return None;
        }
        let corners: Vec<Vec3> = convex_hull(&points, &plane, extent);
        let fan_area = |k: usize| triangle_area([corners[0], corners[k + 1], corners[k + 2]]);
        let hull_area: f64 = (0..corners.len().saturating_sub(2)).map(|k| fan_area(k) as f64).sum();
        let tiled_area: f64 = triangles.iter().map(|&t| triangle_area(t) as f64).sum();
        if corners.len() < 3 || !(tiled_area > 0.0) || (hull_area - tiled_area).abs() > 1e-4 * tiled_area {
            return None;
        }
        let parallelogram =
            corners.len() == 4 && (corners[0] + corners[2] - corners[1] - corners[3]).length() <= 1e-5 * extent;
        let fan_cumulative_area = if parallelogram {
            Vec::new()
        } else {
            (0..corners.len() - 2)
                .scan(0.0f32, |sum, k| {
                    *sum += fan_area(k);
                    Some(*sum)
                })
                .collect()
        };
        let locator = TriangleLocator::new(plane, triangles);
        Some(EmitterPolygon { corners, fan_cumulative_area, area: hull_area as f32, locator })
    }

    /// Corners of the convex hull, in order around it.
    pub fn corners(&self) -> &[Vec3] {
        &self.corners
    }

    /// Area A of the polygon (scene units²).
    pub fn area(&self) -> f32 {
        self.area
    }

    /// The point of the polygon for (u, v) ∈ [0, 1)², uniform by area: for a parallelogram
    /// x = c₀ + u(c₁ − c₀) + v(c₃ − c₀); otherwise u picks fan triangle k by its share of the area and,
    /// rescaled to u', places the point with v (`uniform_triangle_point`).
    pub fn point(&self, [u, v]: [f32; 2]) -> Vec3 {
        let c = &self.corners;
        let Some(&total) = self.fan_cumulative_area.last() else {
            return c[0] + (c[1] - c[0]) * u + (c[3] - c[0]) * v;
        };
        let x = u * total;
        let k = self.fan_cumulative_area.partition_point(|&a| a <= x).min(self.fan_cumulative_area.len() - 1);
        let below = if k == 0 { 0.0 } else { self.fan_cumulative_area[k - 1] };
        let share = self.fan_cumulative_area[k] - below;
        let s = if share > 0.0 { ((x - below) / share).clamp(0.0, 1.0) } else { 0.5 };
        uniform_triangle_point([c[0], c[k + 1], c[k + 2]], s, v)
    }

    /// Index (into the `triangles` the polygon was built from) of the triangle containing point `p`
    /// of the polygon: the candidate whose smallest barycentric coordinate is largest, so a point on
    /// a shared edge (or rounded just outside) goes to a triangle it touches.
    pub fn triangle_at(&self, p: Vec3) -> usize {
        self.locator.locate(p)
    }
}

fn triangle_area([a, b, c]: [Vec3; 3]) -> f32 {
    0.5 * (b - a).cross(c - a).length()
}

/// Coordinates in a plane: (p − o)·t, (p − o)·b.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Plane {
    origin: Vec3,
    tangent: Vec3,
    bitangent: Vec3,
}

impl Plane {
    fn coordinates(&self, p: Vec3) -> Vec2 {
        let d = p - self.origin;
        Vec2::new(d.dot(self.tangent), d.dot(self.bitangent))
    }
}

/// The convex hull of `points` in `plane` by Andrew's monotone chain (Andrew 1979), counter-clockwise
/// in plane coordinates; points within 10⁻⁶·extent² (a cross product, units²) of collinear with their
/// neighbours are dropped, so the grid vertices along a lamp's edges do not become corners.
fn convex_hull(points: &[Vec3], plane: &Plane, extent: f32) -> Vec<Vec3> {
    let mut p: Vec<(Vec2, Vec3)> = points.iter().map(|&x| (plane.coordinates(x), x)).collect();
    p.sort_by(|a, b| a.0.x.total_cmp(&b.0.x).then(a.0.y.total_cmp(&b.0.y)));
    let tolerance = 1e-6 * extent * extent;
    let cross = |o: Vec2, a: Vec2, b: Vec2| (a - o).perp_dot(b - o);
    let mut hull: Vec<(Vec2, Vec3)> = Vec::with_capacity(p.len() + 1);
    for pass in 0..2 {
        let start = hull.len();
        let ordered: Box<dyn Iterator<Item = &(Vec2, Vec3)>> =
            if pass == 0 { Box::new(p.iter()) } else { Box::new(p.iter().rev()) };
        for &q in ordered {
            while hull.len() >= start + 2 && cross(hull[hull.len() - 2].0, hull[hull.len() - 1].0, q.0) <= tolerance {
                hull.pop();
            }
            hull.push(q);
        }
        hull.pop(); // the chain's last point starts the other chain
    }
    hull.into_iter().map(|(_, x)| x).collect()
}

/// A uniform grid over the triangles' bounding box in the plane, about one cell per triangle, each
/// cell listing the triangles whose bounding boxes overlap it.
#[derive(Clone, Debug, PartialEq)]
struct TriangleLocator {
    plane: Plane,
    triangles: Vec<[Vec2; 3]>,
    lo: Vec2,
    /// Cells per unit length along each plane axis.
    cells_per_unit: Vec2,
    cells: [usize; 2],
    /// CSR lists: the triangles of cell c are `members[first[c]..first[c + 1]]`.
    first: Vec<u32>,
    members: Vec<u32>,
}

impl TriangleLocator {
    fn new(plane: Plane, triangles: &[[Vec3; 3]]) -> TriangleLocator {
        let flat: Vec<[Vec2; 3]> = triangles.iter().map(|t| t.map(|p| plane.coordinates(p))).collect();
        let (lo, hi) =
            flat.iter().flatten().fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(lo, hi), &p| (lo.min(p), hi.max(p)));
        let side = ((flat.len() as f64).sqrt().ceil() as usize).clamp(1, 1024);
        let size = (hi - lo).max(Vec2::splat(f32::MIN_POSITIVE));
        let cells = [side, side];
        let cells_per_unit = Vec2::splat(side as f32) / size;
        let mut locator = TriangleLocator {
            plane,
            triangles: Vec::new(),
            lo,
            cells_per_unit,
            cells,
            first: Vec::new(),
            members: Vec::new(),
        };
        let ranges: Vec<[[usize; 2]; 2]> = flat
            .iter()
            .map(|t| {
                let (a, b) = t.iter().fold((Vec2::INFINITY, Vec2::NEG_INFINITY), |(a, b), &p| (a.min(p), b.max(p)));
                let (ca, cb) = (locator.cell(a), locator.cell(b));
                [[ca[0], cb[0]], [ca[1], cb[1]]]
            })
            .collect();
        let mut count = vec![0u32; side * side + 1];
        for [[x0, x1], [y0, y1]] in &ranges {
            for y in *y0..=*y1 {
                for x in *x0..=*x1 {
                    count[y * side + x + 1] += 1;
                }
            }
        }
        for c in 1..count.len() {
            count[c] += count[c - 1];
        }
        let mut fill = count.clone();
        let mut members = vec![0u32; count[side * side] as usize];
        for (t, [[x0, x1], [y0, y1]]) in ranges.iter().enumerate() {
            for y in *y0..=*y1 {
                for x in *x0..=*x1 {
                    let c = y * side + x;
                    members[fill[c] as usize] = t as u32;
                    fill[c] += 1;
                }
            }
        }
        locator.triangles = flat;
        locator.first = count;
        locator.members = members;
        locator
    }

    /// The cell (clamped to the grid) of plane point `q`.
    fn cell(&self, q: Vec2) -> [usize; 2] {
        let c = (q - self.lo) * self.cells_per_unit;
        [0, 1].map(|k| (c[k].max(0.0) as usize).min(self.cells[k] - 1))
    }

    fn locate(&self, p: Vec3) -> usize {
        let q = self.plane.coordinates(p);
        let [x, y] = self.cell(q);
        let c = y * self.cells[0] + x;
        let candidates = &self.members[self.first[c] as usize..self.first[c + 1] as usize];
        let inside = |t: &[Vec2; 3]| {
            let [a, b, c] = *t;
            let area = (b - a).perp_dot(c - a);
            let w1 = (q - a).perp_dot(c - a) / area;
            let w2 = (b - a).perp_dot(q - a) / area;
            (1.0 - w1 - w2).min(w1).min(w2)
        };
        // A candidate that holds q strictly inside is the one (the triangles tile without overlap);
        // else, for q on an edge or rounded just outside, the nearest by its smallest coordinate.
        let mut best = (0, f32::NEG_INFINITY);
        for &t in candidates {
            let w = inside(&self.triangles[t as usize]);
            if w > 0.0 {
                return t as usize;
            }
            if w > best.1 {
                best = (t as usize, w);
            }
        }
        best.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    /// A w × h rectangle at z = 0 cut into an n × m grid of quads, each split into two triangles.
    fn grid(w: f32, h: f32, n: usize, m: usize) -> Vec<[Vec3; 3]> {
        let p = |i: usize, j: usize| vec3(w * i as f32 / n as f32, h * j as f32 / m as f32, 0.0);
        let mut t = Vec::new();
        for j in 0..m {
            for i in 0..n {
                t.push([p(i, j), p(i + 1, j), p(i + 1, j + 1)]);
                t.push([p(i, j), p(i + 1, j + 1), p(i, j + 1)]);
            }
        }
        t
    }

    #[test]
    fn a_grid_of_triangles_is_sampled_as_its_rectangle_and_each_point_finds_its_triangle() {
        let triangles = grid(2.0, 1.0, 5, 3);
        let polygon = EmitterPolygon::new(&triangles, Vec3::Z).expect("a rectangle");
        assert!((polygon.area() - 2.0).abs() < 1e-5);
        let (origin, along_u, along_v) =
            (polygon.point([0.0, 0.0]), polygon.point([1.0, 0.0]), polygon.point([0.0, 1.0]));
        assert!(((along_u - origin).cross(along_v - origin).length() - 2.0).abs() < 1e-5);
        let m = 64;
        for i in 0..m {
            for j in 0..m {
                let uv = [(i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32];
                let p = polygon.point(uv);
                // One affine map of the whole rectangle (no seams): the strata of the square are
                // strata of the lamp.
                let affine = origin + (along_u - origin) * uv[0] + (along_v - origin) * uv[1];
                assert!((p - affine).length() < 1e-5, "{uv:?} -> {p} vs {affine}");
                assert!(p.x >= -1e-6 && p.x <= 2.0 + 1e-6 && p.y >= -1e-6 && p.y <= 1.0 + 1e-6, "{p}");
                let t = triangles[polygon.triangle_at(p)];
                let b = barycentric_2d(t, p);
                assert!(b.min_element() >= -1e-5, "{p} not in its triangle {t:?}: {b}");
            }
        }
    }

    fn barycentric_2d([a, b, c]: [Vec3; 3], p: Vec3) -> Vec3 {
        let n = (b - a).cross(c - a);
        let w1 = (p - a).cross(c - a).dot(n) / n.length_squared();
        let w2 = (b - a).cross(p - a).dot(n) / n.length_squared();
        Vec3::new(1.0 - w1 - w2, w1, w2)
    }

    #[test]
    fn a_trapezoid_is_sampled_uniformly_by_area_over_its_fan() {
        // Corners (0, 0), (4, 0), (3, 2), (1, 2), area 6: the mean of uniform points is the centroid,
        // the area-weighted mean of its two triangles' centroids.
        let (a, b, c, d) = (vec3(0.0, 0.0, 0.0), vec3(4.0, 0.0, 0.0), vec3(3.0, 2.0, 0.0), vec3(1.0, 2.0, 0.0));
        let triangles = [[a, b, c], [a, c, d]];
        let polygon = EmitterPolygon::new(&triangles, Vec3::Z).expect("convex");
        assert!((polygon.area() - 6.0).abs() < 1e-5);
        let centroid = |t: [Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
        let expected = (centroid(triangles[0]) * triangle_area(triangles[0])
            + centroid(triangles[1]) * triangle_area(triangles[1]))
            / 6.0;
        let m = 256;
        let mut sum = Vec3::ZERO;
        for i in 0..m {
            for j in 0..m {
                sum += polygon.point([(i as f32 + 0.5) / m as f32, (j as f32 + 0.5) / m as f32]);
            }
        }
        let mean = sum / (m * m) as f32;
        // Midpoint rule on a piecewise smooth map: error O(1/m).
        assert!((mean - expected).length() < 4.0 / m as f32, "{mean} vs {expected}");
    }

    #[test]
    fn concave_or_non_planar_triangle_sets_are_not_one_polygon() {
        // An L of three unit squares: its hull is larger than the triangles' union.
        let l: Vec<[Vec3; 3]> = grid(2.0, 2.0, 2, 2).into_iter().take(6).collect();
        assert!(EmitterPolygon::new(&l, Vec3::Z).is_none());
        let mut bent = grid(1.0, 1.0, 1, 1);
        bent[1][2].z = 0.3;
        assert!(EmitterPolygon::new(&bent, Vec3::Z).is_none());
    }
}
