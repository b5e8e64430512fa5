//! Triangle pairs meshed as quads. Exporters write every quad as two triangles, and the mesher cuts a
//! triangle into n² pieces with n set by its longest edge, the diagonal: a rectangle w × l written as
//! two triangles gets about 2·(w² + l²)/(w·l) times the elements of the same rectangle as a quad
//! (4× for a square, 80× for a 1:40 skirting board, all of them slivers), and its two halves share no
//! vertices, so their values jump along the diagonal. `pair_triangles` finds the triangles that are
//! halves of one planar convex quad with one material and one texture mapping and hands the mesher
//! that quad instead. What pass two sees does not change: the traced triangles are the quad's grid
//! cells, uv is the pair's one affine map, and shading normals are each triangle's own over its half
//! (`Mesh::interpolated_normal` through `Mesh::surface_partner`).

use super::surface_uv;
use crate::scene::Surface;
use glam::Vec3;

/// How the mesher takes one scene surface.
#[derive(Clone, Debug, PartialEq)]
pub enum Meshing {
    /// As it is.
    Own,
    /// As this planar convex quad, counter-clockwise like the surface, that it forms with the scene
    /// triangle `partner` (which is `Absorbed`). Texture coordinates over the quad are this surface's
    /// affine map, extended over the partner (they agree there: see `pair_triangles`).
    Quad { corners: [Vec3; 4], partner: u32 },
    /// Meshed as part of another surface's `Quad`.
    Absorbed,
}

/// The fourth corner of a pair may lie off the first triangle's plane by at most this fraction of the
/// quad's longest edge: a quad written flat, up to exporters' rounding of coordinates far from the
/// origin, not a fold. The meshed quad keeps the pair's outline exactly (its grid's outer edges are
/// the triangles' outer edges); inside, its bilinear surface lies within a quarter of that off the
/// two triangles (0.35 mm on a 1 m square, whose halves then fold by 0.1°).
const PLANAR_TOLERANCE: f32 = 1e-3;

/// Corner angles of a paired quad lie within 45°–135° (|cos| ≤ this): its grid cells are then no worse
/// shaped than the triangles' pieces, and a fan of a circle or a strip of slivers is not paired along
/// its short edges.
const MAX_CORNER_COS: f32 = std::f32::consts::FRAC_1_SQRT_2;

/// Texture coordinates of the partner's corners must match the first triangle's affine uv map within
/// this many uv units (a fifth of a texel of a 1024² map; exporters round uv to 4–6 digits, and the
/// extrapolation to the fourth corner triples that), plus `f32` rounding of the coordinates
/// themselves: one mapping, not a seam along the diagonal.
const UV_TOLERANCE: f32 = 2e-4;

/// A point's coordinates bit for bit (−0 taken as +0).
type PointKey = [u32; 3];

/// Pairs of scene triangles that form one quad, greedily from the most rectangular. Two triangles
/// pair across an edge they share with opposite windings (the same two points, compared bit for bit)
/// when they have the same material, sidedness and object; both or neither have uv, and then one
/// affine uv map (`UV_TOLERANCE`); and the quad they form is planar (`PLANAR_TOLERANCE`) and convex
/// with every corner angle within 45°–135°. Candidates are ranked by their largest |cos| of a corner
/// angle (ties by index), so a rectangle's halves pair across its diagonal before either pairs with a
/// neighbour. Deterministic, O(n log n) in triangles.
pub fn pair_triangles(surfaces: &[Surface]) -> Vec<Meshing> {
    let mut plan = vec![Meshing::Own; surfaces.len()];
    let key = |p: Vec3| -> PointKey { (p + Vec3::ZERO).to_array().map(f32::to_bits) };
    // Every directed edge (from, to) of a pairable triangle as bit patterns, with its triangle and edge
    // index, sorted so that the triangles running along an edge are one range.
    let mut edges: Vec<(PointKey, PointKey, u32, u8)> = Vec::new();
    for (s, surface) in surfaces.iter().enumerate().filter(|(_, surface)| pairable(surface)) {
        let v = &surface.vertices;
        for k in 0..3 {
            edges.push((key(v[k]), key(v[(k + 1) % 3]), s as u32, k as u8));
        }
    }
    edges.sort_unstable();
    let mut candidates: Vec<(f32, u32, u32, [Vec3; 4])> = Vec::new();
    for &(from, to, s, k) in &edges {
        // The triangles running the other way along this edge.
        let first = edges.partition_point(|e| (e.0, e.1) < (to, from));
        for &(_, _, t, m) in edges[first..].iter().take_while(|e| (e.0, e.1) == (to, from)) {
            if t > s {
                if let Some((score, corners)) =
                    quad_of(&surfaces[s as usize], k as usize, &surfaces[t as usize], m as usize)
                {
                    candidates.push((score, s, t, corners));
                }
            }
        }
    }
    candidates.sort_by(|a, b| a.0.total_cmp(&b.0).then(a.1.cmp(&b.1)).then(a.2.cmp(&b.2)));
    for (_, s, t, corners) in candidates {
        if plan[s as usize] == Meshing::Own && plan[t as usize] == Meshing::Own {
            plan[s as usize] = Meshing::Quad { corners, partner: t };
            plan[t as usize] = Meshing::Absorbed;
        }
    }
    plan
}

/// A triangle that may pair: three corners spanning an area.
fn pairable(surface: &Surface) -> bool {
    let v = &surface.vertices;
    v.len() == 3 && (v[1] - v[0]).cross(v[2] - v[0]).length_squared() > 0.0
}

/// The quad triangle `a` (across its edge `ka`, from corner ka to ka + 1) forms with triangle `b` (whose
/// edge `kb` is the same edge reversed), and its largest |cos| of a corner angle; `None` when the two
/// may not pair (see `pair_triangles`).
///
/// With a = (p₀, p₁, p₂) and the shared edge p_k → p_{k+1}, b runs p_{k+1} → p_k → q, and the quad
/// counter-clockwise is (p_{k+1}, p_{k+2}, p_k, q).
fn quad_of(a: &Surface, ka: usize, b: &Surface, kb: usize) -> Option<(f32, [Vec3; 4])> {
    if a.material != b.material || a.two_sided != b.two_sided || a.object != b.object {
        return None;
    }
    let p = &a.vertices;
    let q = b.vertices[(kb + 2) % 3];
    let corners = [p[(ka + 1) % 3], p[(ka + 2) % 3], p[ka], q];
    let normal = (p[1] - p[0]).cross(p[2] - p[0]).normalize();
    let longest = (0..4).map(|i| (corners[(i + 1) % 4] - corners[i]).length()).fold(0.0, f32::max);
    if (q - p[0]).dot(normal).abs() > PLANAR_TOLERANCE * longest {
        return None;
    }
    let mut worst_cos = 0.0f32;
    for i in 0..4 {
        let (before, here, after) = (corners[(i + 3) % 4], corners[i], corners[(i + 1) % 4]);
        let (into, out) = (here - before, after - here);
        if into.cross(out).dot(normal) <= 0.0 {
            return None; // not convex
        }
        let cos = (before - here).normalize_or_zero().dot((after - here).normalize_or_zero());
        worst_cos = worst_cos.max(cos.abs());
    }
    if worst_cos > MAX_CORNER_COS {
        return None;
    }
    match (&a.uvs, &b.uvs) {
        (None, None) => {}
        (Some(uv_a), Some(uv_b)) if uv_a.len() == 3 && uv_b.len() == 3 => {
            for (k, &point) in b.vertices.iter().enumerate() {
                let expected = surface_uv(p, uv_a, point);
                let magnitude = expected.abs().max_element().max(uv_b[k].abs().max_element());
                let tolerance = UV_TOLERANCE + 4.0 * f32::EPSILON * magnitude;
                if (expected - uv_b[k]).abs().max_element() > tolerance {
                    return None;
                }
            }
        }
        _ => return None,
    }
    Some((worst_cos, corners))
}
