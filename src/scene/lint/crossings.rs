//! Intersecting faces: non-coplanar faces whose interiors cross, the classic radiosity light leak.

use super::Poly;
use glam::DVec3;

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
