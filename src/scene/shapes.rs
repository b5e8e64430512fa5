//! The built-in primitives as polygons ([[box]] faces, [[sphere]] triangles), and the normalisation
//! that turns any parsed polygon into what the mesher takes (triangles and convex quads; other
//! polygons triangulated, concave ones by ear clipping).

use super::Surface;
use glam::Vec3;
use std::path::PathBuf;

/// The six faces of an axis-aligned box, counter-clockwise seen from outside (or inside if `inward`).
pub fn box_faces(lo: Vec3, hi: Vec3, inward: bool) -> Vec<[Vec3; 4]> {
    let p = |x: bool, y: bool, z: bool| {
        Vec3::new(if x { hi.x } else { lo.x }, if y { hi.y } else { lo.y }, if z { hi.z } else { lo.z })
    };
    let mut faces = vec![
        [p(false, false, false), p(false, false, true), p(false, true, true), p(false, true, false)], // x-
        [p(true, false, false), p(true, true, false), p(true, true, true), p(true, false, true)],     // x+
        [p(false, false, false), p(true, false, false), p(true, false, true), p(false, false, true)], // y-
        [p(false, true, false), p(false, true, true), p(true, true, true), p(true, true, false)],     // y+
        [p(false, false, false), p(false, true, false), p(true, true, false), p(true, false, false)], // z-
        [p(false, false, true), p(true, false, true), p(true, true, true), p(false, true, true)],     // z+
    ];
    if inward {
        for f in &mut faces {
            f.reverse();
        }
    }
    faces
}

/// A UV sphere as triangles, counter-clockwise seen from outside, each with its analytic vertex
/// normals n = (p − centre)/r (pointing out; the shading turns them to the side hit, so a sphere seen
/// from inside is smooth too).
pub fn sphere_triangles(centre: Vec3, radius: f32, segments: u32) -> Vec<([Vec3; 3], [Vec3; 3])> {
    let rings = (segments / 2).max(2);
    let direction = |ring: u32, seg: u32| {
        let theta = std::f32::consts::PI * ring as f32 / rings as f32;
        let phi = 2.0 * std::f32::consts::PI * seg as f32 / segments as f32;
        Vec3::new(theta.sin() * phi.cos(), theta.cos(), -theta.sin() * phi.sin())
    };
    let corner = |ring: u32, seg: u32| {
        let n = direction(ring, seg);
        (centre + radius * n, n.normalize())
    };
    let mut tris = Vec::new();
    for ring in 0..rings {
        for seg in 0..segments {
            let (a, b, c, d) =
                (corner(ring, seg), corner(ring + 1, seg), corner(ring + 1, seg + 1), corner(ring, seg + 1));
            if ring > 0 {
                tris.push(([a.0, b.0, d.0], [a.1, b.1, d.1]));
            }
            if ring + 1 < rings {
                tris.push(([b.0, c.0, d.0], [b.1, c.1, d.1]));
            }
        }
    }
    tris
}

/// Makes every surface something the mesher takes: triangles and convex quads stay; larger polygons
/// and non-convex quads are triangulated (`triangulate`); zero-area pieces are dropped and counted,
/// per source file in order of first appearance.
pub(super) fn normalise_surfaces(surfaces: Vec<Surface>) -> (Vec<Surface>, Vec<(PathBuf, usize)>) {
    let mut out = Vec::with_capacity(surfaces.len());
    let mut degenerate: Vec<(PathBuf, usize)> = Vec::new();
    let mut count = |s: &Surface| match degenerate.iter_mut().find(|d| d.0 == s.source.path) {
        Some(d) => d.1 += 1,
        None => degenerate.push((s.source.path.clone(), 1)),
    };
    for s in surfaces {
        let n = polygon_normal(&s.vertices);
        let extent = s.vertices.iter().map(|v| (*v - s.vertices[0]).length()).fold(0.0f32, f32::max);
        if !(n.length() > 1e-6 * extent * extent) || !n.is_finite() {
            count(&s);
            continue;
        }
        if s.vertices.len() == 3 || (s.vertices.len() == 4 && is_convex(&s.vertices, n)) {
            out.push(s);
            continue;
        }
        for [a, b, c] in triangulate(&s.vertices, n) {
            let tri = vec![s.vertices[a], s.vertices[b], s.vertices[c]];
            let tn = (tri[1] - tri[0]).cross(tri[2] - tri[0]);
            if !(tn.length() > 1e-6 * extent * extent) {
                count(&s);
                continue;
            }
            let normals = s.shading_normals.as_ref().map(|n| vec![n[a], n[b], n[c]]);
            let uvs = s.uvs.as_ref().map(|t| vec![t[a], t[b], t[c]]);
            out.push(Surface { vertices: tri, shading_normals: normals, uvs, ..s.clone() });
        }
    }
    (out, degenerate)
}

/// Triangles (corner indices, counter-clockwise about `n`) covering a simple polygon whose Newell
/// normal is `n`. The fan from corner 0 when every fan triangle turns the polygon's way (the winding
/// number of the polygon at a point is the sum of the fan triangles' signed indicators, so then each
/// inside point lies in exactly one triangle and no outside point in any); otherwise ear clipping
/// (Meisters 1975) in the polygon's plane: an L-shaped hexagon fanned from a corner next to its
/// reflex corner would cover ground outside itself with back-facing triangles. A self-intersecting
/// polygon with no ear left has the rest fanned.
pub(crate) fn triangulate(v: &[Vec3], n: Vec3) -> Vec<[usize; 3]> {
    let n_hat = n.normalize();
    let u = n_hat.any_orthonormal_vector();
    let w = n_hat.cross(u);
    let p: Vec<(f64, f64)> = v.iter().map(|&x| ((x - v[0]).dot(u) as f64, (x - v[0]).dot(w) as f64)).collect();
    let extent = p.iter().map(|q| q.0.abs().max(q.1.abs())).fold(0.0f64, f64::max);
    // Twice the signed area of (a, b, c) in the plane: positive when it turns the polygon's way.
    let turn =
        |a: usize, b: usize, c: usize| (p[b].0 - p[a].0) * (p[c].1 - p[a].1) - (p[b].1 - p[a].1) * (p[c].0 - p[a].0);
    let tolerance = 1e-9 * extent * extent;
    let fan: Vec<[usize; 3]> = (1..v.len() - 1).map(|k| [0, k, k + 1]).collect();
    if fan.iter().all(|&[a, b, c]| turn(a, b, c) > -tolerance) {
        return fan;
    }
    let mut ring: Vec<usize> = (0..v.len()).collect();
    let mut triangles = Vec::with_capacity(v.len() - 2);
    let mut start = 0usize;
    while ring.len() > 3 {
        let m = ring.len();
        let ear = (0..m).map(|k| (start + k) % m).find(|&s| {
            let (a, b, c) = (ring[(s + m - 1) % m], ring[s], ring[(s + 1) % m]);
            turn(a, b, c) > tolerance
                && !ring.iter().any(|&j| {
                    let distinct = |k: usize| p[j] != p[k];
                    j != a
                        && j != b
                        && j != c
                        && distinct(a)
                        && distinct(b)
                        && distinct(c)
                        && turn(a, b, j) >= 0.0
                        && turn(b, c, j) >= 0.0
                        && turn(c, a, j) >= 0.0
                })
        });
        let Some(s) = ear else {
            triangles.extend((1..m - 1).map(|k| [ring[0], ring[k], ring[k + 1]]));
            return triangles;
        };
        triangles.push([ring[(s + m - 1) % m], ring[s], ring[(s + 1) % m]]);
        ring.remove(s);
        start = s.saturating_sub(1);
    }
    triangles.push([ring[0], ring[1], ring[2]]);
    triangles
}

/// Newell's normal (twice the vector area) of a polygon, n = Σ (v_k − v₀) × (v_{k+1} − v₀): the same
/// vector as Σ v_k × v_{k+1}, but computed from the polygon's own edges, so a face far from the origin
/// keeps its area. (Summed on absolute coordinates, the products of a face at 3,000 units cancel to
/// ±1 ulp of 10⁷: alcove_hall moved by [1000, 200, −3000] lost 16 faces as "zero-area", a lamp's
/// half among them.)
pub(crate) fn polygon_normal(v: &[Vec3]) -> Vec3 {
    let o = v[0];
    (1..v.len().saturating_sub(1)).map(|k| (v[k] - o).cross(v[k + 1] - o)).sum()
}

fn is_convex(v: &[Vec3], n: Vec3) -> bool {
    (0..v.len()).all(|i| {
        let (a, b, c) = (v[i], v[(i + 1) % v.len()], v[(i + 2) % v.len()]);
        (b - a).cross(c - b).dot(n) > 0.0
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    /// A 0.5 × 0.25 quad (area 0.125) and its copy moved to [1000, 200, −3000] and to 10⁵.
    fn quad_at(offset: Vec3) -> Vec<Vec3> {
        [vec3(0.0, 0.0, 0.0), vec3(0.5, 0.0, 0.0), vec3(0.5, 0.25, 0.0), vec3(0.0, 0.25, 0.0)]
            .map(|v| v + offset)
            .to_vec()
    }

    #[test]
    fn sphere_vertex_normals_are_radial_and_face_out() {
        let centre = vec3(1.0, -2.0, 0.5);
        for (tri, normals) in sphere_triangles(centre, 3.0, 24) {
            let facet = polygon_normal(&tri).normalize();
            for (p, n) in tri.iter().zip(normals) {
                assert!((n.length() - 1.0).abs() < 1e-6);
                assert!(((*p - centre) / 3.0 - n).length() < 1e-5, "{p} {n}");
                // Within half a facet's angle (7.5° around, 15° at the poles' fans) of the facet.
                assert!(n.dot(facet) > 0.95, "{n} vs {facet}");
            }
        }
    }

    #[test]
    fn polygon_normal_keeps_a_face_area_far_from_the_origin() {
        for offset in [Vec3::ZERO, vec3(1000.0, 200.0, -3000.0), vec3(1e5, 0.0, 0.0)] {
            let n = polygon_normal(&quad_at(offset));
            // The corners are exact in f32 at these offsets (multiples of 1/128), so only the
            // products round: two triangles' cross products of coordinates below 1, a few ulps.
            assert!((n - vec3(0.0, 0.0, 0.25)).length() < 1e-6, "{offset}: {n}");
        }
    }

    /// Area of the triangles `triangulate` returns, each signed about the polygon's normal.
    fn signed_areas(v: &[Vec3]) -> Vec<f32> {
        let n = polygon_normal(v);
        triangulate(v, n).iter().map(|&[a, b, c]| 0.5 * (v[b] - v[a]).cross(v[c] - v[a]).dot(n.normalize())).collect()
    }

    #[test]
    fn concave_polygons_are_ear_clipped_into_front_facing_triangles_of_the_same_area() {
        // An L of area 0.75 in the xz plane, starting next to its reflex corner (0.5, 0.5):
        // a fan from there would cover the missing square's quarter with back-facing triangles.
        let l = [
            vec3(1.0, 0.0, 0.5),
            vec3(0.5, 0.0, 0.5),
            vec3(0.5, 0.0, 1.0),
            vec3(0.0, 0.0, 1.0),
            vec3(0.0, 0.0, 0.0),
            vec3(1.0, 0.0, 0.0),
        ];
        // A dart (concave quad) of area 0.35, reflex corner at index 3.
        let dart = [vec3(0.0, 0.0, 0.0), vec3(0.5, 0.0, 1.0), vec3(1.0, 0.0, 0.0), vec3(0.5, 0.0, 0.3)];
        for (polygon, area) in [(&l[..], 0.75), (&dart[..], 0.35)] {
            let areas = signed_areas(polygon);
            assert_eq!(areas.len(), polygon.len() - 2);
            assert!(areas.iter().all(|&a| a > 0.0), "{areas:?}");
            assert!((areas.iter().sum::<f32>() - area).abs() < 1e-6, "{areas:?}");
        }
    }

    #[test]
    fn convex_polygons_keep_the_fan_from_corner_zero() {
        let pentagon =
            [vec3(0.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0), vec3(0.5, 0.0, 1.3), vec3(1.0, 0.0, 1.0), vec3(1.0, 0.0, 0.0)];
        assert_eq!(triangulate(&pentagon, polygon_normal(&pentagon)), vec![[0, 1, 2], [0, 2, 3], [0, 3, 4]]);
    }
}
