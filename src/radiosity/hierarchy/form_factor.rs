//! Link form-factor estimators of the hierarchy: pure functions, no rays (visibility is `visibility`).
//!
//! Which estimator serves which link (no link is measured by a hemicube; the hemicube cut of issue 10
//! measures only the indirect light a leaf gathers, for the correction: `hemicube_cut`):
//! - element ← element: Lambert's exact unoccluded point-to-polygon form factor, averaged over the
//!   receiver's three-point quadrature rule, or a 48-point rule for near pairs (`element_to_element`),
//!   times the ray visibility fraction;
//! - far links with a cluster at either end: the three-point rule over member pairs when the ends
//!   hold at most 64 (`links::member_pair_form_factor`, `triangle_to_polygon`), else the
//!   point-to-point form factor of Sillion (1995) with each cluster's exact projected area Σ A_i
//!   max(0, n_i·ω) over its members (`Nodes::projected_area`; `cluster_form_factor`); times the ray
//!   visibility fraction;
//! - near links with a cluster end: see `links::near_form_factor` (leaf pairs or rays).

use glam::{DVec3, Vec3};

use super::edge_angle::edge_angle_rad;

/// Lambert's exact, unoccluded form factor from a differential area at `point` (unit normal
/// `normal`) to a planar polygon, counter-clockwise seen from its front:
///
/// F = (1 / 2π) · |Σ_i γ_i · n · (R_i × R_{i+1}) / |R_i × R_{i+1}||,  R_i = v_i − p,
/// γ_i = ∠(R_i, R_{i+1}),
///
/// over the polygon clipped to the point's upper half-space n·(x − p) ≥ 0 (Lambert 1760; Baum, Rushmeier
/// and Winget 1989, eq. 6). The polygon is one-sided: a point on or behind its plane sees nothing (0).
/// Exact up to f64 rounding and the edge angles' relative error (`edge_angle::edge_angle_rad`, at most
/// 4e-15); at most 8 vertices after clipping.
pub fn point_to_polygon(point: Vec3, normal: Vec3, polygon: &[Vec3]) -> f64 {
    if polygon.len() < 3 {
        return 0.0;
    }
    point_to_source(point, normal, &Source::new(polygon))
}

/// A source polygon in f64 with its Newell normal, made once for the many receiver points of an
/// element link (`element_to_element`: 6 or 54 points) rather than once per point.
pub struct Source {
    /// The vertices (the first `count`; at most 7 are read, as `clip_to_half_space` clips).
    vertices: [DVec3; 7],
    count: usize,
    newell: DVec3,
}

impl Source {
    /// `polygon` (at least three vertices, counter-clockwise seen from its front).
    pub fn new(polygon: &[Vec3]) -> Source {
        let count = polygon.len().min(7);
        let mut vertices = [DVec3::ZERO; 7];
        for (v, p) in vertices.iter_mut().zip(polygon) {
            *v = p.as_dvec3();
        }
        Source { vertices, count, newell: newell_normal(polygon) }
    }
}

/// `point_to_polygon` to a `Source` (the same value, bit for bit).
pub fn point_to_source(point: Vec3, normal: Vec3, source: &Source) -> f64 {
    let p = point.as_dvec3();
    let n = normal.as_dvec3();
    // One-sided source: its Newell normal must face the point.
    if source.newell.dot(p - source.vertices[0]) <= 0.0 {
        return 0.0;
    }
    // R_i = v_i − p once per vertex (each is the end of two edges). A source wholly above the
    // point's plane (the usual case) is its own clip (`clip_to_half_space` copies it as it is).
    let mut rays = [DVec3::ZERO; 8];
    let mut count = source.count;
    let mut above = true;
    for (ray, vertex) in rays.iter_mut().zip(&source.vertices[..count]) {
        *ray = *vertex - p;
        above &= n.dot(*ray) >= 0.0;
    }
    if !above {
        let mut clipped = [DVec3::ZERO; 8];
        count = clip_to_half_space(&source.vertices[..count], p, n, &mut clipped);
        if count < 3 {
            return 0.0;
        }
        for (ray, vertex) in rays.iter_mut().zip(&clipped[..count]) {
            *ray = *vertex - p;
        }
    }
    let mut sum = 0.0;
    for i in 0..count {
        sum += edge_term(rays[i], rays[if i + 1 == count { 0 } else { i + 1 }], n);
    }
    lambert_value(sum)
}

/// One edge's term of Lambert's sum, γ · n · (a × b) / |a × b| with γ = ∠(a, b), for the rays a, b
/// from the point to the edge's ends; 0 for a degenerate edge (|a × b| = 0). Reversing the edge
/// negates it exactly (a × b and b × a are exact negatives in floating point, a · b = b · a), which
/// `point_to_quarters` relies on.
#[inline]
fn edge_term(a: DVec3, b: DVec3, n: DVec3) -> f64 {
    let cross = a.cross(b);
    let len = cross.length();
    if len <= 0.0 {
        return 0.0;
    }
    edge_angle_rad(len, a.dot(b)) * n.dot(cross) / len
}

/// F = |Σ edge terms| / 2π, at most 1.
#[inline]
fn lambert_value(sum: f64) -> f64 {
    (sum.abs() / (2.0 * std::f64::consts::PI)).min(1.0)
}

/// The four midpoint quarters of a source triangle (`nodes::quarters`: [a, ab, ca], [ab, b, bc],
/// [ca, bc, c], [ab, bc, ca]) for `point_to_quarters`: their six distinct vertices in f64 and each
/// quarter as a `Source`.
pub struct Quarters {
    /// a, b, c, ab, bc, ca.
    vertices: [DVec3; 6],
    quarters: [Source; 4],
}

impl Quarters {
    /// `None` unless the four triangles are the quarters of one triangle in `nodes::quarters`'
    /// order, their shared corners equal bit for bit.
    pub fn new(quarters: &[[Vec3; 3]; 4]) -> Option<Quarters> {
        let [[a, ab, ca], [ab1, b, bc], [ca2, bc2, c], [ab3, bc3, ca3]] = *quarters;
        let shared = ab1 == ab && ab3 == ab && bc2 == bc && bc3 == bc && ca2 == ca && ca3 == ca;
        shared.then(|| Quarters {
            vertices: [a, b, c, ab, bc, ca].map(|v| v.as_dvec3()),
            quarters: quarters.each_ref().map(|q| Source::new(q)),
        })
    }
}

/// `point_to_source` from one point to each of four quarters, the same values bit for bit, with the
/// nine distinct edges' terms computed once: the six half-edges of the outline each belong to one
/// corner quarter, and each of the three inner edges to a corner quarter and, reversed (its term
/// negated exactly, `edge_term`), to the middle one. A point that sees a quarter's vertex below its
/// plane takes the clipping path of `point_to_source` for every quarter. Serves the source weights
/// of a link (`source_weights::child_weights`), which read a subdivided source's four children at
/// up to 12 receiver points.
pub fn point_to_quarters(point: Vec3, normal: Vec3, quarters: &Quarters) -> [f64; 4] {
    let p = point.as_dvec3();
    let n = normal.as_dvec3();
    let mut rays = [DVec3::ZERO; 6];
    let mut above = true;
    for (ray, vertex) in rays.iter_mut().zip(&quarters.vertices) {
        *ray = *vertex - p;
        above &= n.dot(*ray) >= 0.0;
    }
    if !above {
        return quarters.quarters.each_ref().map(|q| point_to_source(point, normal, q));
    }
    // Vertex indices: a 0, b 1, c 2, ab 3, bc 4, ca 5.
    let t = |i: usize, j: usize| edge_term(rays[i], rays[j], n);
    let (a_ab, ab_b, b_bc, bc_c, c_ca, ca_a) = (t(0, 3), t(3, 1), t(1, 4), t(4, 2), t(2, 5), t(5, 0));
    let (ab_ca, bc_ab, ca_bc) = (t(3, 5), t(4, 3), t(5, 4));
    let sums = [
        0.0 + a_ab + ab_ca + ca_a,
        0.0 + ab_b + b_bc + bc_ab,
        0.0 + ca_bc + bc_c + c_ca,
        0.0 + -bc_ab + -ca_bc + -ab_ca,
    ];
    let mut out = [0.0; 4];
    for ((value, sum), quarter) in out.iter_mut().zip(sums).zip(&quarters.quarters) {
        // One-sided, as in `point_to_source` (whose test this is, NaN included): each quarter's own
        // Newell normal must face the point.
        if !(quarter.newell.dot(p - quarter.vertices[0]) <= 0.0) {
            *value = lambert_value(sum);
        }
    }
    out
}

/// `polygon` (at most 7 vertices, convex) clipped to the half-space n·(x − p) ≥ 0 above the plane
/// of `point` and `normal`; empty when less than a polygon remains (Sutherland–Hodgman).
pub fn clip_above(polygon: &[Vec3], point: Vec3, normal: Vec3) -> Vec<Vec3> {
    let source = Source::new(polygon);
    let mut clipped = [DVec3::ZERO; 8];
    let count = clip_to_half_space(&source.vertices[..source.count], point.as_dvec3(), normal.as_dvec3(), &mut clipped);
    if count < 3 {
        return Vec::new();
    }
    clipped[..count].iter().map(|v| v.as_vec3()).collect()
}

/// A point of `polygon` in the half-space above the plane of `point` and `normal`: the mean of the
/// vertices of `clip_above`; `None` when less than a polygon remains. The part of a source element
/// that a receiver point sees, for a visibility ray where a uniform point of the element lies below
/// the point's plane (`visibility::sampled_form_factor`).
pub fn point_above(polygon: &[Vec3], point: Vec3, normal: Vec3) -> Option<Vec3> {
    let clipped = clip_above(polygon, point, normal);
    (!clipped.is_empty()).then(|| clipped.iter().sum::<Vec3>() / clipped.len() as f32)
}

/// Newell's (unnormalised, twice the area) normal of a polygon.
fn newell_normal(polygon: &[Vec3]) -> DVec3 {
    let mut n = DVec3::ZERO;
    for i in 0..polygon.len() {
        let a = polygon[i].as_dvec3();
        let b = polygon[(i + 1) % polygon.len()].as_dvec3();
        n += a.cross(b);
    }
    n
}

/// Sutherland–Hodgman clip of `vertices` (at most 7) to n·(x − p) ≥ 0; writes the clipped
/// polygon into `out` and returns its vertex count. Each vertex's height n·(v − p) is computed once;
/// a polygon wholly in the half-space (the usual case) is copied as it is, which is what the clip
/// loop would write.
fn clip_to_half_space(vertices: &[DVec3], p: DVec3, n: DVec3, out: &mut [DVec3; 8]) -> usize {
    let m = vertices.len().min(7);
    let mut heights = [0.0f64; 7];
    for i in 0..m {
        heights[i] = n.dot(vertices[i] - p);
    }
    if heights[..m].iter().all(|&h| h >= 0.0) {
        out[..m].copy_from_slice(&vertices[..m]);
        return m;
    }
    let mut count = 0;
    for i in 0..m {
        let j = if i + 1 == m { 0 } else { i + 1 };
        let (a, b, da, db) = (vertices[i], vertices[j], heights[i], heights[j]);
        if da >= 0.0 && count < 8 {
            out[count] = a;
            count += 1;
        }
        if (da >= 0.0) != (db >= 0.0) {
            let t = da / (da - db);
            if count < 8 {
                out[count] = a + (b - a) * t;
                count += 1;
            }
        }
    }
    count
}

/// The three interior points of the degree-2 triangle quadrature rule with equal weights 1/3:
/// barycentrics (2/3, 1/6, 1/6) and permutations (Strang and Fix 1973).
pub fn quadrature_points(triangle: &[Vec3; 3]) -> [Vec3; 3] {
    let [a, b, c] = *triangle;
    let big = 2.0 / 3.0;
    let small = 1.0 / 6.0;
    [a * big + (b + c) * small, b * big + (a + c) * small, c * big + (a + b) * small]
}

/// The unoccluded element-to-element form factor and an estimate of its error:
///
/// F_RS ≈ Q₃ = (1/3) Σ_k F(x_k → S), x_k the receiver's three quadrature points (degree 2, Strang
/// and Fix 1973), F(x → S) Lambert's exact `point_to_polygon`. The source is integrated exactly; the
/// error is the receiver-side quadrature and the constant value the element takes, which the spread of
/// F over the quadrature points *and the corners* of the receiver bounds in practice:
///
/// ΔF = max_k F(p_k → S) − min_k F(p_k → S) over those six points.
///
/// (The corners catch a source near one corner only. A curvature-only estimate, |Q₃ − F(centroid)| +
/// |Q₃ − corner mean|, was tried and rejected: it accepts coarse links between adjacent faces whose
/// quadrature error is large, and the furnace's leaf form-factor sums drifted by 9%.)
///
/// Returns (Q₃, ΔF); Q₃ is `near_quadrature` for near pairs (see `element_six_points`).
pub fn element_to_element(receiver: &[Vec3; 3], receiver_normal: Vec3, source: &[Vec3; 3]) -> (f64, f64) {
    let (q3, error, near) = element_six_points(receiver, receiver_normal, source);
    if near {
        return (near_quadrature(receiver, receiver_normal, source), error);
    }
    (q3, error)
}

/// The six-point part of `element_to_element`: (Q₃ of the three-point rule, ΔF over the six
/// points, whether the pair is near: centre distance below 1.5 × the sum of the bounding radii).
/// For a near pair the form factor is `near_quadrature`'s, which `links::estimate` skips for a link
/// that its error ΔF alone already sends to be split.
pub fn element_six_points(receiver: &[Vec3; 3], receiver_normal: Vec3, source: &[Vec3; 3]) -> (f64, f64, bool) {
    let mut q3 = 0.0;
    let mut lo = f64::INFINITY;
    let mut hi = 0.0f64;
    let polygon = Source::new(source);
    for (k, x) in quadrature_points(receiver).into_iter().chain(receiver.iter().copied()).enumerate() {
        let f = point_to_source(x, receiver_normal, &polygon);
        lo = lo.min(f);
        hi = hi.max(f);
        if k < 3 {
            q3 += f;
        }
    }
    let centre = |t: &[Vec3; 3]| (t[0] + t[1] + t[2]) / 3.0;
    let radius = |t: &[Vec3; 3], c: Vec3| t.iter().map(|p| p.distance(c)).fold(0.0f32, f32::max);
    let (cr, cs) = (centre(receiver), centre(source));
    let near = cr.distance(cs) < 1.5 * (radius(receiver, cr) + radius(source, cs));
    (q3 / 3.0, hi - lo, near)
}

/// The unoccluded form factor from a receiver triangle to a source polygon by the receiver's
/// three-point rule alone, F ≈ (1/3) Σ_k F(x_k → S) (`quadrature_points`, Lambert's exact
/// `point_to_polygon` in the source): the cheap member-pair estimator of cluster links
/// (`links::member_pair_form_factor`, `gather::ArrivalScales`), whose ends are far apart next to
/// their size, so the near rule's 48 points are not needed.
pub fn triangle_to_polygon(receiver: &[Vec3; 3], receiver_normal: Vec3, source: &[Vec3]) -> f64 {
    if source.len() < 3 {
        return 0.0;
    }
    let polygon = Source::new(source);
    quadrature_points(receiver).into_iter().map(|x| point_to_source(x, receiver_normal, &polygon)).sum::<f64>() / 3.0
}

/// The receiver quadrature for element pairs that are near each other (centre distance below 1.5 ×
/// the sum of their bounding radii, which includes every pair that shares an edge or a corner): the
/// three-point rule on each of the receiver's 16 midpoint sub-triangles (48 points). Where the two
/// elements share an edge the integrand is log-singular and the plain rule's relative error does not
/// shrink with the elements' size (27.5% on the worst analytic case at every scale); this rule's is
/// 0.43% there (`tests/hierarchy.rs`), whatever the size, so refinement need not chase it.
pub fn near_quadrature(receiver: &[Vec3; 3], receiver_normal: Vec3, source: &[Vec3; 3]) -> f64 {
    let mut tris = [[Vec3::ZERO; 3]; 16];
    tris[0] = *receiver;
    let mut count = 1;
    for _ in 0..2 {
        for k in (0..count).rev() {
            let [a, b, c] = tris[k];
            let (ab, bc, ca) = ((a + b) * 0.5, (b + c) * 0.5, (c + a) * 0.5);
            tris[4 * k] = [a, ab, ca];
            tris[4 * k + 1] = [ab, b, bc];
            tris[4 * k + 2] = [ca, bc, c];
            tris[4 * k + 3] = [ab, bc, ca];
        }
        count *= 4;
    }
    let polygon = Source::new(source);
    let mut sum = 0.0;
    for t in &tris {
        for x in quadrature_points(t) {
            sum += point_to_source(x, receiver_normal, &polygon);
        }
    }
    sum / 48.0
}

/// Sillion's (1995) point-to-point form factor for links with a cluster at either end:
///
/// F_RS = P_S(ω_SR) · P_R(ω_RS) / (π d² A_R),
///
/// with d the centre distance, P the projected area of each end seen from the other, D(ω) = Σ_i A_i
/// max(0, n_i·ω) over its members (`Nodes::projected_area`: A cos θ for an element). It satisfies
/// reciprocity A_R F_RS = A_S F_SR and is the far-field limit of the exact form factor; clamped to
/// [0, 1]. With the receiver's P_R = D_R(ω), the link's power A_R·F_RS·B_S is exactly what the push
/// spreads over the members facing ω (`gather::gather`): a member of normal n gets irradiance
/// P_S·B_S·max(0, n·ω)/(π d²), that of a point source of intensity P_S·B_S/π.
///
/// (Until session 13 a cluster's P was a six-bin model, Σ_k |ω_k|·bin(k, sign ω_k) with bins Σ A_i
/// max(0, ±n_ik)², and the push split a link's power among the bins facing ω: a member turned away
/// from ω still received light through a bin it shares with members that face ω.)
pub fn cluster_form_factor(projected_source: f64, projected_receiver: f64, receiver_area: f32, distance: f32) -> f64 {
    let d2 = distance as f64 * distance as f64;
    if !(d2 > 0.0) || !(receiver_area > 0.0) {
        return 0.0;
    }
    let f = projected_source * projected_receiver / (std::f64::consts::PI * d2 * receiver_area as f64);
    f.clamp(0.0, 1.0)
}

/// Upper bound used as the error of a cluster link: the same formula with the distance shrunk by both
/// bounding radii, F_up = F · (d / (d − r_R − r_S))², and 1 when the bounding spheres overlap (the
/// estimate is then meaningless and the link must be refined).
pub fn cluster_form_factor_bound(form_factor: f64, distance: f32, radius_sum: f32) -> f64 {
    let gap = distance - radius_sum;
    if !(gap > 0.0) {
        return 1.0;
    }
    let ratio = distance as f64 / gap as f64;
    (form_factor * ratio * ratio).min(1.0)
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    #[test]
    fn unit_square_straight_above_matches_closed_form() {
        // tests/data/point_to_polygon.json, case ptp_par_unitsq_centered_h1 (40-digit reference); f32
        // inputs and f64 arithmetic agree to about 1e-8.
        let sq = [vec3(-0.5, 0.5, 1.0), vec3(0.5, 0.5, 1.0), vec3(0.5, -0.5, 1.0), vec3(-0.5, -0.5, 1.0)];
        let f = point_to_polygon(Vec3::ZERO, Vec3::Z, &sq);
        assert!((f - 0.23945647046077354).abs() < 1e-7, "{f}");
    }

    #[test]
    fn a_source_seen_from_behind_gives_nothing() {
        // Same square with its front facing up (+z): the point below sees its back.
        let sq = [vec3(-0.5, -0.5, 1.0), vec3(0.5, -0.5, 1.0), vec3(0.5, 0.5, 1.0), vec3(-0.5, 0.5, 1.0)];
        assert_eq!(point_to_polygon(Vec3::ZERO, Vec3::Z, &sq), 0.0);
    }

    #[test]
    fn the_quarters_at_once_give_each_quarter_bit_for_bit() {
        // Points above, straddling, in the plane of and behind a source triangle, with normals
        // facing it, grazing it and turned away: every path (shared edges, clipping, one-sided).
        let sources = [
            [vec3(0.0, 2.0, 0.0), vec3(1.3, 2.1, 0.2), vec3(0.1, 2.4, 1.7)],
            [vec3(0.0, 0.0, 0.0), vec3(0.0, 1.0, 0.0), vec3(0.0, 0.0, 1.0)],
            [vec3(5.0, -1.0, 3.0), vec3(-2.0, 0.5, 3.5), vec3(0.3, 4.0, 2.0)],
        ];
        let normals = [Vec3::Y, Vec3::new(0.3, 0.9, -0.2).normalize(), Vec3::X, -Vec3::Y, Vec3::Z];
        let mut compared = 0;
        for source in &sources {
            let parts = crate::radiosity::hierarchy::nodes::quarters(source);
            let quarters = Quarters::new(&parts).expect("the quarters of one triangle");
            let singles = parts.each_ref().map(|q| Source::new(q));
            for i in 0..9 {
                for j in 0..9 {
                    for k in 0..5 {
                        let point = vec3(i as f32 * 0.4 - 1.0, k as f32 * 0.6 - 0.5, j as f32 * 0.4 - 1.0);
                        for &normal in &normals {
                            let together = point_to_quarters(point, normal, &quarters);
                            let one_by_one = singles.each_ref().map(|q| point_to_source(point, normal, q));
                            assert_eq!(together.map(f64::to_bits), one_by_one.map(f64::to_bits), "{point} {normal}");
                            compared += together.iter().filter(|&&f| f > 0.0).count();
                        }
                    }
                }
            }
        }
        assert!(compared > 1000, "only {compared} nonzero values compared");
        // Four triangles that are not one triangle's quarters are refused.
        let mut parts = crate::radiosity::hierarchy::nodes::quarters(&sources[0]);
        parts[3][1].x += 1e-3;
        assert!(Quarters::new(&parts).is_none());
    }

    #[test]
    fn cluster_form_factor_obeys_reciprocity() {
        let (pa, pb, aa, ab, d) = (0.3f64, 0.7f64, 1.5f32, 2.5f32, 4.0f32);
        let fab = cluster_form_factor(pb, pa, aa, d);
        let fba = cluster_form_factor(pa, pb, ab, d);
        assert!((aa as f64 * fab - ab as f64 * fba).abs() < 1e-12);
    }
}
