//! Coplanar overlapping faces: two faces in one plane covering the same area, which z-fight (same
//! facing) or hide each other's light (back to back).

use super::Poly;
use glam::DVec3;

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
