//! Occluder contact: the parts of elements that lie inside a closed object resting on them (the floor
//! under a block, the ceiling behind a lamp panel hung just below it). No light reaches them, so they
//! must neither darken what their element sends (the link's visibility already counts them as
//! blocked) nor be averaged into the vertices beside the object. `split_at_contacts` splits every
//! element that a contact line crosses down to the minimum element size and records each leaf's open
//! area (`Nodes::open_area`).

use glam::Vec3;
use rayon::prelude::*;

use super::clusters::TracingTriangles;
use super::nodes::{quarters, Nodes};
use crate::accel::Accel;
use crate::transport::hit::leave_surface;

/// Probe points per element are the centroids of its 4^k midpoint sub-triangles, k at most this
/// (64 points): fine enough to find a block's footprint on a floor triangle 6× its area.
pub const MAX_PROBE_LEVELS: u32 = 3;

/// A leaf a contact line crosses (too small to split) measures its open share with the centroids of
/// its 4^k midpoint sub-triangles, k at least this (16 points).
pub const LEAF_PROBE_LEVELS: u32 = 2;

/// cos 60°: the four side rays of `enclosed` lean this far from the normal.
const SIDE_RAY_COS: f32 = 0.5;

/// What the contact test needs: the scene's occluders and the distances it works at.
pub struct ContactProbe<'a> {
    pub accel: &'a Accel,
    pub tracing: &'a TracingTriangles,
    /// Rays start this far off the surface (scene units; the visibility rays' offset).
    pub offset: f32,
    /// A hit closer than this counts as touching whatever its side (an object's base on the surface).
    pub contact_distance: f32,
}

impl ContactProbe<'_> {
    /// Whether the point `p` of a surface with unit normal `n` lies inside a closed object: each of
    /// five rays, along n and leaning 60° from it towards ±t, ±b (any tangent frame), first hits the
    /// back of a one-sided triangle or anything within `contact_distance`. One ray escaping, or
    /// hitting a front (or a two-sided surface), means light can come in from that side.
    pub fn enclosed(&self, p: Vec3, n: Vec3) -> bool {
        let origin = leave_surface(p, n, self.offset);
        let (t, b) = n.any_orthonormal_pair();
        let side = (1.0 - SIDE_RAY_COS * SIDE_RAY_COS).sqrt();
        let directions = [
            n,
            n * SIDE_RAY_COS + t * side,
            n * SIDE_RAY_COS - t * side,
            n * SIDE_RAY_COS + b * side,
            n * SIDE_RAY_COS - b * side,
        ];
        directions.iter().all(|&d| self.blocked_from_inside(origin, d))
    }

    /// The first hit along `d` from `origin` touches (within `contact_distance`) or is the back of a
    /// one-sided triangle.
    fn blocked_from_inside(&self, origin: Vec3, d: Vec3) -> bool {
        let Some(hit) = self.accel.closest_hit(origin, d, 0.0, f32::INFINITY) else {
            return false;
        };
        if hit.t * d.length() < self.contact_distance {
            return true;
        }
        let k = hit.triangle as usize;
        if self.tracing.two_sided.get(k).copied().unwrap_or(true) {
            return false;
        }
        let [a, b, c] = self.tracing.triangles[k].map(|v| self.tracing.positions[v as usize]);
        (b - a).cross(c - a).dot(d) > 0.0
    }

    /// Open probes of a triangle (unit normal `n`): (open, all) over the centroids of its 4^levels
    /// midpoint sub-triangles.
    pub fn open_probes(&self, corners: &[Vec3; 3], n: Vec3, levels: u32) -> (u32, u32) {
        if levels == 0 {
            let centroid = (corners[0] + corners[1] + corners[2]) / 3.0;
            return (u32::from(!self.enclosed(centroid, n)), 1);
        }
        quarters(corners).iter().fold((0, 0), |(open, all), q| {
            let (o, a) = self.open_probes(q, n, levels - 1);
            (open + o, all + a)
        })
    }
}

/// How one element is treated: a leaf with its open share, or split 1→4 (`Nodes::subdivide`'s
/// child order) with a plan per quarter.
#[derive(Clone, Debug, PartialEq)]
pub enum ContactPlan {
    Leaf { open_share: f32 },
    Split(Box<[ContactPlan; 4]>),
}

impl ContactPlan {
    /// The open share of the element the plan is for (quarters have equal areas).
    pub fn open_share(&self) -> f32 {
        match self {
            ContactPlan::Leaf { open_share } => *open_share,
            ContactPlan::Split(children) => children.iter().map(ContactPlan::open_share).sum::<f32>() * 0.25,
        }
    }
}

/// Levels of probes an element of `area` gets: as many as keep each probe's sub-triangle at least
/// `min_area`, at most `MAX_PROBE_LEVELS`.
fn probe_levels(area: f32, min_area: f32) -> u32 {
    let mut levels = 0;
    let mut a = area;
    while levels < MAX_PROBE_LEVELS && a * 0.25 >= min_area {
        a *= 0.25;
        levels += 1;
    }
    levels
}

/// The plan for one element: split while its probes are partly open and partly enclosed and its
/// quarters keep at least `min_area`; a leaf's open share is its probes' open fraction. A pure
/// function of the corners, so the plans of all input triangles are made in parallel. A contact line
/// that only clips an element's corner can pass between its probes, so such an element may stay one
/// level above the minimum size, all open or all enclosed.
pub fn plan(probe: &ContactProbe, corners: &[Vec3; 3], n: Vec3, min_area: f32) -> ContactPlan {
    plan_piece(probe, corners, n, min_area, false)
}

/// `plan` for an element, or (`split_piece`) for a quarter of an element the contact line crosses:
/// such a quarter too small to split again takes its open share from at least 4^`LEAF_PROBE_LEVELS`
/// probes, not from the one or four its size gives, so a leaf half under the object is neither
/// counted all open nor all hidden.
fn plan_piece(probe: &ContactProbe, corners: &[Vec3; 3], n: Vec3, min_area: f32, split_piece: bool) -> ContactPlan {
    let area = 0.5 * (corners[1] - corners[0]).cross(corners[2] - corners[0]).length();
    let splittable = area * 0.25 >= min_area;
    let levels = if split_piece && !splittable {
        probe_levels(area, min_area).max(LEAF_PROBE_LEVELS)
    } else {
        probe_levels(area, min_area)
    };
    let (open, all) = probe.open_probes(corners, n, levels);
    let straddles = open > 0 && open < all;
    if straddles && splittable {
        let q = quarters(corners);
        return ContactPlan::Split(Box::new(q.map(|c| plan_piece(probe, &c, n, min_area, true))));
    }
    ContactPlan::Leaf { open_share: open as f32 / all.max(1) as f32 }
}

/// What `split_at_contacts` did.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct ContactStats {
    /// Elements split because a contact line crosses them.
    pub split: usize,
    /// Leaves with some of their area enclosed.
    pub hidden_leaves: usize,
    /// Σ (area − open area) over the leaves.
    pub hidden_area: f64,
}

/// Splits the leaf elements `elements` (input triangles before any refinement) where an object
/// resting on them begins (`plan`, down to `min_area`), sets every leaf's `open_area` to its open
/// share of its area and every inner node's to the sum below it. Plans are made in parallel and
/// applied in order, so the nodes are the same for any thread count.
/// At most `max_nodes` nodes in all (the memory budget): past it, an element planned to split stays
/// a leaf with its plan's open share.
pub fn split_at_contacts(
    nodes: &mut Nodes,
    elements: &[u32],
    probe: &ContactProbe,
    min_area: f32,
    max_nodes: usize,
) -> ContactStats {
    let plans: Vec<ContactPlan> = {
        let nodes: &Nodes = nodes;
        elements
            .par_iter()
            .map(|&e| plan(probe, &nodes.corners[e as usize], nodes.normal[e as usize], min_area))
            .collect()
    };
    let mut stats = ContactStats::default();
    let mut stack: Vec<(usize, &ContactPlan)> = Vec::new();
    for (&e, p) in elements.iter().zip(&plans) {
        stack.push((e as usize, p));
        while let Some((n, p)) = stack.pop() {
            let over_budget = nodes.len() + 4 > max_nodes;
            match p {
                ContactPlan::Split(children) if !over_budget => {
                    let first = nodes.subdivide(n) as usize;
                    stats.split += 1;
                    for (k, c) in children.iter().enumerate().rev() {
                        stack.push((first + k, c));
                    }
                }
                _ => {
                    let open_share = p.open_share();
                    if open_share < 1.0 {
                        nodes.open_area[n] = nodes.area[n] * open_share;
                        stats.hidden_leaves += 1;
                        stats.hidden_area += (nodes.area[n] - nodes.open_area[n]) as f64;
                    }
                }
            }
        }
    }
    nodes.sum_open_areas();
    stats
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::vec3;

    /// Tracing triangles of quads (fanned, each one-sided, counter-clockwise from its front).
    fn tracing_of(quads: &[[Vec3; 4]]) -> TracingTriangles {
        let mut t = TracingTriangles::default();
        for q in quads {
            for tri in [[q[0], q[1], q[2]], [q[0], q[2], q[3]]] {
                let base = t.positions.len() as u32;
                t.positions.extend_from_slice(&tri);
                t.triangles.push([base, base + 1, base + 2]);
                t.two_sided.push(false);
            }
        }
        t
    }

    /// A 0.4 m box without a bottom, its faces facing out, standing on y = 0 over x, z ∈ [0.3, 0.7].
    fn open_bottom_box() -> Vec<[Vec3; 4]> {
        let (lo, hi, h) = (0.3f32, 0.7f32, 0.4f32);
        let centre = vec3(0.5, 0.2, 0.5);
        let outwards = |q: [Vec3; 4]| {
            let n = (q[1] - q[0]).cross(q[2] - q[0]);
            if n.dot(q[0] - centre) > 0.0 {
                q
            } else {
                [q[3], q[2], q[1], q[0]]
            }
        };
        let faces = vec![
            [vec3(lo, h, lo), vec3(lo, h, hi), vec3(hi, h, hi), vec3(hi, h, lo)], // top, +y
            [vec3(lo, 0.0, lo), vec3(hi, 0.0, lo), vec3(hi, h, lo), vec3(lo, h, lo)], // −z
            [vec3(hi, 0.0, hi), vec3(lo, 0.0, hi), vec3(lo, h, hi), vec3(hi, h, hi)], // +z
            [vec3(lo, 0.0, hi), vec3(lo, 0.0, lo), vec3(lo, h, lo), vec3(lo, h, hi)], // −x
            [vec3(hi, 0.0, lo), vec3(hi, 0.0, hi), vec3(hi, h, hi), vec3(hi, h, lo)], // +x
        ];
        faces.into_iter().map(outwards).collect()
    }

    fn probe<'a>(accel: &'a Accel, tracing: &'a TracingTriangles) -> ContactProbe<'a> {
        ContactProbe { accel, tracing, offset: 1e-5, contact_distance: 1e-4 }
    }

    #[test]
    fn the_box_faces_face_out() {
        let t = tracing_of(&open_bottom_box());
        let centre = vec3(0.5, 0.2, 0.5);
        for tri in &t.triangles {
            let [a, b, c] = tri.map(|v| t.positions[v as usize]);
            assert!((b - a).cross(c - a).dot(a - centre) > 0.0, "a face of the test box faces in");
        }
    }

    #[test]
    fn a_floor_point_under_a_box_is_enclosed_and_one_beside_it_is_not() {
        let t = tracing_of(&open_bottom_box());
        let accel = Accel::build(&t.positions, &t.triangles);
        let p = probe(&accel, &t);
        assert!(p.enclosed(vec3(0.5, 0.0, 0.5), Vec3::Y));
        assert!(p.enclosed(vec3(0.31, 0.0, 0.69), Vec3::Y));
        assert!(!p.enclosed(vec3(0.29, 0.0, 0.5), Vec3::Y));
        assert!(!p.enclosed(vec3(0.9, 0.0, 0.9), Vec3::Y));
    }

    #[test]
    fn a_ceiling_point_behind_a_lamp_panel_is_enclosed_but_one_under_a_shelf_is_not() {
        // A lamp panel facing down 0.1 mm below a ceiling at y = 1: the ceiling above it sees only its
        // back. A shelf facing up 0.5 m above the floor: a floor point under it sees its back straight
        // up, but light comes in from the sides.
        let lamp = [vec3(0.4, 0.9999, 0.4), vec3(0.6, 0.9999, 0.4), vec3(0.6, 0.9999, 0.6), vec3(0.4, 0.9999, 0.6)];
        let shelf = [vec3(0.4, 0.5, 0.4), vec3(0.4, 0.5, 0.6), vec3(0.6, 0.5, 0.6), vec3(0.6, 0.5, 0.4)];
        let t = tracing_of(&[lamp, shelf]);
        let accel = Accel::build(&t.positions, &t.triangles);
        let p = probe(&accel, &t);
        assert!(p.enclosed(vec3(0.5, 1.0, 0.5), -Vec3::Y));
        assert!(!p.enclosed(vec3(0.5, 0.0, 0.5), Vec3::Y));
    }

    /// A floor triangle (half of the unit square) split at the contacts of `open_bottom_box` down to
    /// 1/4⁵ of its area: the nodes, the floor's node, the minimum area and the stats.
    fn floor_split_under_open_bottom_box() -> (Nodes, u32, f32, ContactStats) {
        let t = tracing_of(&open_bottom_box());
        let accel = Accel::build(&t.positions, &t.triangles);
        let p = probe(&accel, &t);
        let mut nodes = Nodes::default();
        let floor = [vec3(0.0, 0.0, 0.0), vec3(0.0, 0.0, 1.0), vec3(1.0, 0.0, 1.0)];
        let e = nodes.push_element(floor, 0, 0, Vec3::splat(0.5), Vec3::ZERO);
        let min_area = 0.5 / 4f32.powi(5);
        let stats = split_at_contacts(&mut nodes, &[e], &p, min_area, usize::MAX);
        (nodes, e, min_area, stats)
    }

    #[test]
    fn a_floor_element_crossed_by_a_box_base_is_split_to_the_minimum_size_along_it() {
        let (nodes, e, min_area, stats) = floor_split_under_open_bottom_box();
        assert!(stats.split > 0 && stats.hidden_leaves > 0);
        let inside = |c: Vec3| c.x > 0.3 && c.x < 0.7 && c.z > 0.3 && c.z < 0.7;
        let mut crossing = 0;
        for n in 0..nodes.len() {
            if !nodes.is_leaf(n) {
                continue;
            }
            let k = nodes.corners[n];
            let corners_inside = k.iter().filter(|&&c| inside(c)).count();
            let centre = nodes.centre[n];
            if corners_inside == 0 && !inside(centre) {
                assert_eq!(nodes.open_area[n], nodes.area[n], "leaf {n} outside the box");
            } else if corners_inside == 3 {
                assert_eq!(nodes.open_area[n], 0.0, "leaf {n} under the box");
            } else {
                // At the minimum size or one level above it: a leaf the line only clips can keep all
                // its probes on one side (see `plan`).
                crossing += 1;
                assert!(nodes.area[n] <= 4.0 * min_area, "leaf {n} crosses the box's base at area {}", nodes.area[n]);
            }
        }
        assert!(crossing > 0);
        // Inner nodes hold the sums; the root's open area is the floor's minus the footprint's share.
        let footprint = 0.4f32 * 0.4 / 2.0; // the triangle covers half of the box's base
        let open = nodes.open_area[e as usize];
        assert!((open - (0.5 - footprint)).abs() < 0.01, "{open}");
    }

    #[test]
    fn a_minimum_size_leaf_on_the_contact_line_gets_a_fractional_open_share() {
        // With one probe per minimum-size leaf every leaf on the box's base line would be all open
        // or all hidden; with 4^LEAF_PROBE_LEVELS probes the leaves the line cuts through are partly open.
        let (nodes, _, min_area, _) = floor_split_under_open_bottom_box();
        let partly_open = (0..nodes.len())
            .filter(|&n| nodes.is_leaf(n) && nodes.area[n] < 4.0 * min_area)
            .filter(|&n| nodes.open_area[n] > 0.0 && nodes.open_area[n] < nodes.area[n])
            .count();
        assert!(partly_open > 0, "no minimum-size leaf has a fractional open share");
    }

    #[test]
    fn nothing_is_split_or_hidden_without_contacts() {
        let t = tracing_of(&open_bottom_box());
        let accel = Accel::build(&t.positions, &t.triangles);
        let p = probe(&accel, &t);
        let mut nodes = Nodes::default();
        let wall = [vec3(0.0, 0.0, 2.0), vec3(1.0, 0.0, 2.0), vec3(1.0, 1.0, 2.0)];
        let e = nodes.push_element(wall, 0, 0, Vec3::splat(0.5), Vec3::ZERO);
        let stats = split_at_contacts(&mut nodes, &[e], &p, 1e-4, usize::MAX);
        assert_eq!(stats, ContactStats::default());
        assert_eq!(nodes.len(), 1);
        assert_eq!(nodes.open_area[0], nodes.area[0]);
    }
}
