//! Shaft culling of a link's visibility rays (Haines and Wallace 1994, "Shaft culling for efficient
//! ray-traced radiosity"): a conservative test that no occluding triangle can meet any ray the
//! visibility estimate would trace between a link's two ends. When it holds, every one of those rays
//! would report "unoccluded", so none is traced and the estimate is the same.

use glam::{DVec3, Vec3};

use super::nodes::Nodes;
use crate::accel::Accel;
use crate::transport::hit::offset_at;

/// Candidate triangles (those whose box overlaps the shaft's box) a shaft test examines before it
/// gives up and the link's rays are traced. Past a dozen or so candidates (a tessellated object
/// beside the link) the rays are cheaper: procedural:16000 took 25.0 CPU-s at 32, about 21 at 16
/// and 8, 20.0 without shafts; cornell_original the same time at 16 as at 32 and more at 8
/// (docs/performance.md, 2026-12-02).
pub const MAX_SHAFT_TRIANGLES: usize = 16;

/// The test's allowance for rounding, in units of `f32::EPSILON` times the largest coordinate
/// magnitude involved: the rays' ends are computed in f32 (a few ulps off the exact end hulls) and
/// the watertight ray/triangle test works in f32 on coordinates relative to the ray origin (a few
/// ulps of coordinates up to twice that magnitude). 32 ulps is several times both; the offset that
/// lifts each end off its own surface (1e-5 of the scene diagonal) is still larger, so an end's own
/// plane still separates.
pub const SLACK_EPSILONS: f64 = 32.0;

/// Points whose convex hull holds every ray end a link's visibility estimate may put on one node
/// (`visibility::link_visibility`, `visibility::sampled_form_factor`): a point of the node moved
/// off its element along that element's normal by `offset_at` (`transport::hit::leave_surface`).
///
/// - An element: its three corners moved along its normal by the least and the largest offset its
///   points take (offset_at is max(offset, k·ε·max|pᵢ|), convex in p, so its largest value on the
///   triangle is at a corner): six points (three when the two offsets agree).
/// - A cluster: the eight corners of its bounding sphere's box grown by the largest offset.
#[derive(Clone, Copy, Debug)]
pub struct EndHull {
    points: [DVec3; 8],
    count: usize,
}

impl EndHull {
    /// The hull of node `node`'s ray ends for rays leaving surfaces by `offset` (scene units).
    pub fn of_node(nodes: &Nodes, node: usize, offset: f32) -> EndHull {
        let mut points = [DVec3::ZERO; 8];
        if nodes.is_cluster[node] {
            let (c, r) = (nodes.centre[node], nodes.radius[node]);
            let far = c.abs() + Vec3::splat(r);
            let grow = (r + offset_at(far, offset)) as f64;
            let c = c.as_dvec3();
            for (k, p) in points.iter_mut().enumerate() {
                let sign = |bit: usize| if k & bit != 0 { 1.0 } else { -1.0 };
                *p = c + DVec3::new(sign(1), sign(2), sign(4)) * grow;
            }
            return EndHull { points, count: 8 };
        }
        let corners = nodes.corners[node];
        let n = nodes.normal[node].as_dvec3();
        let low = offset as f64;
        let high = corners.iter().map(|&p| offset_at(p, offset)).fold(offset, f32::max) as f64;
        for (k, p) in corners.iter().enumerate() {
            points[k] = p.as_dvec3() + n * low;
            points[k + 3] = p.as_dvec3() + n * high;
        }
        EndHull { points, count: if high > low { 6 } else { 3 } }
    }

    /// The hull of `points` (at most 8; the rest are ignored).
    pub fn from_points(points: &[DVec3]) -> EndHull {
        let count = points.len().min(8);
        let mut hull = EndHull { points: [DVec3::ZERO; 8], count };
        hull.points[..count].copy_from_slice(&points[..count]);
        hull
    }

    /// The hull's points.
    pub fn points(&self) -> &[DVec3] {
        &self.points[..self.count]
    }

    fn centroid(&self) -> DVec3 {
        self.points().iter().copied().sum::<DVec3>() / self.count as f64
    }
}

/// Whether no triangle of `accel` can meet a segment from a point of `a`'s hull to a point of
/// `b`'s (the shaft: the convex hull of both), to within the rounding of the rays that would test it.
///
/// Conservative: `false` whenever it cannot prove it, in particular when more than
/// `MAX_SHAFT_TRIANGLES` triangles overlap the shaft's box. Triangles come from the accelerator's
/// box query (`Accel::visit_triangles_in_box`, a superset of those meeting the shaft's bounding
/// box, which is the coordinate axes' separation test); each is then tested by
/// `triangle_outside_shaft`. A triangle the shaft merely touches (an end's edge on a neighbouring
/// wall) counts as a possible occluder.
pub fn shaft_clear(accel: &Accel, a: &EndHull, b: &EndHull) -> bool {
    let (mut lo, mut hi) = (DVec3::splat(f64::INFINITY), DVec3::splat(f64::NEG_INFINITY));
    for &p in a.points().iter().chain(b.points()) {
        lo = lo.min(p);
        hi = hi.max(p);
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return false;
    }
    let magnitude = lo.abs().max(hi.abs()).max_element();
    let slack = SLACK_EPSILONS * f32::EPSILON as f64 * magnitude;
    let axis = b.centroid() - a.centroid();
    let grow = DVec3::splat(2.0 * slack);
    // The candidates are collected before any is tested: a crowded shaft (a tessellated surface
    // beside the link) is then given up after the box query alone, not after up to
    // `MAX_SHAFT_TRIANGLES` triangle tests. The verdict is the same either way.
    let mut candidates = [[Vec3::ZERO; 3]; MAX_SHAFT_TRIANGLES];
    let mut seen = 0usize;
    let complete = accel.visit_triangles_in_box((lo - grow).as_vec3(), (hi + grow).as_vec3(), |triangle| {
        if seen == MAX_SHAFT_TRIANGLES {
            return false;
        }
        candidates[seen] = *triangle;
        seen += 1;
        true
    });
    complete
        && candidates[..seen].iter().all(|triangle| {
            let t = triangle.map(|p| p.as_dvec3());
            let t_magnitude = t.iter().fold(0.0f64, |m, p| m.max(p.abs().max_element()));
            let slack = slack.max(SLACK_EPSILONS * f32::EPSILON as f64 * t_magnitude);
            triangle_outside_shaft(&t, a, b, axis, slack)
        })
}

/// Whether triangle `t` cannot block a segment of the convex hull of `a` and `b` (the shaft) by
/// more than `slack` (scene units), proven in one of three ways:
///
/// 1. The triangle's plane has the whole shaft on one side: every hull point p has
///    n·(p − t₀) ≥ −`slack` (or every one ≤ `slack`), n the unit normal. Walls and the ends' own
///    surfaces; an end that touches the plane (its edge on a neighbouring wall) still counts as
///    on one side: a segment then meets the plane only where it ends on it, which is the
///    neighbour's edge, not a blocker between the two ends.
/// 2. A separating axis m = e_k × w, e_k a triangle edge and w = `axis` the direction between the
///    ends (a plane through the edge along the shaft: an occluder beside the rays): the
///    projections of the hull's points and of the triangle's corners onto m are apart by more than
///    `slack`.
/// 3. One end wholly above the plane and the other wholly below (by more than `slack`): every
///    segment crosses the plane inside the convex hull of the crossings of the segments between
///    the two ends' hull points (`crossing_outside_triangle`), and that polygon is separated from
///    the triangle within the plane.
///
/// None proves nothing, and the answer is false (conservative). A degenerate triangle is never
/// proven outside.
pub fn triangle_outside_shaft(t: &[DVec3; 3], a: &EndHull, b: &EndHull, axis: DVec3, slack: f64) -> bool {
    let normal = (t[1] - t[0]).cross(t[2] - t[0]);
    let length = normal.length();
    if !(length > 0.0) || !length.is_finite() {
        return false;
    }
    let n = normal / length;
    let range = |end: &EndHull| {
        end.points().iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), &p| {
            let d = n.dot(p - t[0]);
            (lo.min(d), hi.max(d))
        })
    };
    let ((a_lo, a_hi), (b_lo, b_hi)) = (range(a), range(b));
    if a_lo.min(b_lo) >= -slack || a_hi.max(b_hi) <= slack {
        return true;
    }
    let separated = |m: DVec3| {
        let Some(m) = unit_axis(m) else {
            return false;
        };
        let (tlo, thi) = projected_range(t, m);
        let (mut above, mut below) = (true, true);
        for &p in a.points().iter().chain(b.points()) {
            let h = m.dot(p);
            above &= h > thi + slack;
            below &= h < tlo - slack;
            if !(above || below) {
                return false;
            }
        }
        true
    };
    if (0..3).any(|k| separated((t[(k + 1) % 3] - t[k]).cross(axis))) {
        return true;
    }
    if a_lo > slack && b_hi < -slack {
        crossing_outside_triangle(t, n, a, b, slack)
    } else if b_lo > slack && a_hi < -slack {
        crossing_outside_triangle(t, -n, b, a, slack)
    } else {
        false
    }
}

/// For ends `up` (every point above the plane of `t`, unit normal `n`, by more than `slack`) and
/// `down` (every point below it by more than `slack`): whether the crossings of the shaft's segments
/// with the plane miss the triangle by more than a rounding margin.
///
/// A segment from x ∈ conv(up) to y ∈ conv(down) crosses the plane at x + (y − x)·d_x/(d_x − d_y),
/// d the signed distance: a point of the plane's section of the shaft, the convex hull of the
/// crossings c_ij of the segments between hull points u_i and v_j. Moving a segment's ends by δ
/// moves its crossing by at most δ·(1 + 2L/S) (L the segment's length, S = d_x − d_y its
/// height across the plane), so the crossings of rays computed within `slack` of the exact ones
/// lie within margin = 2·`slack`·(1 + 2·L_max/S_min) of that polygon; it must be apart from the
/// triangle by more than the margin along one in-plane axis: the triangle's three edge normals,
/// or the two directions of its first edge's frame and their diagonals.
fn crossing_outside_triangle(t: &[DVec3; 3], n: DVec3, up: &EndHull, down: &EndHull, slack: f64) -> bool {
    let mut crossings = [DVec3::ZERO; 64];
    let mut count = 0;
    let (mut s_min, mut l_max) = (f64::INFINITY, 0.0f64);
    for &u in up.points() {
        let du = n.dot(u - t[0]);
        for &v in down.points() {
            let dv = n.dot(v - t[0]);
            let height = du - dv;
            s_min = s_min.min(height);
            l_max = l_max.max(u.distance(v));
            crossings[count] = u + (v - u) * (du / height);
            count += 1;
        }
    }
    let crossings = &crossings[..count];
    if !(s_min > 0.0) {
        return false;
    }
    let margin = 2.0 * slack * (1.0 + 2.0 * l_max / s_min);
    let u = (t[1] - t[0]).normalize();
    let v = n.cross(u);
    let axes = [n.cross(t[1] - t[0]), n.cross(t[2] - t[1]), n.cross(t[0] - t[2]), u, v, u + v, u - v];
    axes.iter().any(|&m| {
        let Some(m) = unit_axis(m) else {
            return false;
        };
        let (tlo, thi) = projected_range(t, m);
        let (clo, chi) = projected_range(crossings, m);
        clo > thi + margin || chi < tlo - margin
    })
}

/// `m` scaled to unit length, `None` when it has no finite direction (a degenerate axis).
fn unit_axis(m: DVec3) -> Option<DVec3> {
    let len = m.length();
    (len > 0.0 && len.is_finite()).then(|| m / len)
}

/// The range [min, max] of m·p over `points`.
fn projected_range(points: &[DVec3], m: DVec3) -> (f64, f64) {
    points.iter().fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), p| {
        let h = m.dot(*p);
        (lo.min(h), hi.max(h))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hull(points: &[DVec3]) -> EndHull {
        EndHull::from_points(points)
    }

    /// Two parallel unit squares one apart (as triangles' hulls) and a triangle between them in
    /// the middle plane: the middle triangle blocks; the same triangle moved far to the side, a
    /// wall behind one end, or a wall both ends touch, does not.
    #[test]
    fn a_triangle_between_the_ends_blocks_and_one_beside_or_behind_does_not() {
        let a = hull(&[DVec3::new(0.0, 0.0, 0.0), DVec3::new(1.0, 0.0, 0.0), DVec3::new(0.0, 1.0, 0.0)]);
        let b = hull(&[DVec3::new(0.0, 0.0, 1.0), DVec3::new(1.0, 0.0, 1.0), DVec3::new(0.0, 1.0, 1.0)]);
        let axis = DVec3::Z;
        let between = [DVec3::new(0.1, 0.1, 0.5), DVec3::new(0.3, 0.1, 0.5), DVec3::new(0.1, 0.3, 0.5)];
        assert!(!triangle_outside_shaft(&between, &a, &b, axis, 1e-9));
        let beside = between.map(|p| p + DVec3::new(3.0, 0.0, 0.0));
        assert!(triangle_outside_shaft(&beside, &a, &b, axis, 1e-9));
        let behind = [DVec3::new(-5.0, -5.0, -0.1), DVec3::new(5.0, -5.0, -0.1), DVec3::new(0.0, 5.0, -0.1)];
        assert!(triangle_outside_shaft(&behind, &a, &b, axis, 1e-9));
        // A wall both ends touch with an edge (the plane x = 0) has the whole shaft on one side: a
        // segment meets it only where it ends on it, so it is not an occluder.
        let touching = [DVec3::new(0.0, 0.0, -1.0), DVec3::new(0.0, 5.0, -1.0), DVec3::new(0.0, 0.0, 5.0)];
        assert!(triangle_outside_shaft(&touching, &a, &b, axis, 1e-9));
    }
}
