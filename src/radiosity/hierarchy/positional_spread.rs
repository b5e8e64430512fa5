//! The light that reaches an element above the leaves, spread over its leaves by position once the
//! sweeps have converged: the reconstruction of the leaf exitance that the leaf mesh interpolates.
//!
//! Why: the push hands an element's irradiance to its children uniformly (Hanrahan, Salzman and
//! Aupperle 1991), so where refinement stopped at an element above the leaves every leaf below takes
//! the element's mean. Across a wall cut into long slivers the light then steps from one linked
//! element to the next, and the radiosity image shows streaks one linked element wide (stair_hall's
//! plaster wall: bands 7.5 cm wide differing by 3–4%, docs/accuracy.md session 21). The power is
//! right; only its spread over the element is flat.
//!
//! Light T (irradiance) from source S that the push hands to element R (not a leaf, nothing resting
//! on it) uniformly goes to each leaf ℓ below R as
//!
//! T · g(ℓ) / ḡ,  ḡ = Σ_ℓ A_ℓ·g(ℓ) / Σ_ℓ A_ℓ,
//!
//! g(ℓ) the unoccluded form factor from the leaf's centre to the source (`SourceShape`): Lambert's
//! exact point-to-polygon value for an element source (near or far), the point-source irradiance of
//! a far cluster (`gather::PointSource`, as cluster receivers take their arrivals), and for a near
//! cluster of at most `NEAR_CLUSTER_MEMBERS` members the sum of the exact form factors to its
//! members, each times the member's exitance (a larger near cluster stays uniform). Σ_ℓ A_ℓ·T·g(ℓ)/ḡ
//! = A_R·T: the power is kept exactly, only moved between the leaves; the leaf's exitance changes by
//! ρ_ℓ·g_ℓ·Σ T·(g(ℓ)/ḡ − 1) (clamped at 0; g_ℓ the leaf's gain where ρ·R ≥ 1, as in the sweep:
//! `row_sums`). Visibility stays the link's (one value over R). The light
//! spread this way: R's own links (T = F·B_S, as the gather reads it); the far arrivals its clusters
//! pass it (`gather::Arrival`, evaluated at R's centre by the push, T = w·g(R)); and their member
//! shares (`ArrivalScales` shares, T = F·B_S·c_R).

use glam::{DVec3, Vec3};
use rayon::prelude::*;

use super::form_factor::point_to_polygon;
use super::gather::{flat_normals, gather_into, Arrival, ArrivalScales, PointSource};
use super::links::{is_near, Links};
use super::nodes::Nodes;

/// A near cluster source of at most this many members spreads its light by the exact form factors
/// to its members, each weighted by its exitance; a larger one stays uniform.
const NEAR_CLUSTER_MEMBERS: usize = 64;

/// How a link's source is seen from a leaf: its weight g.
enum SourceShape {
    /// An element: Lambert's exact point-to-polygon form factor.
    Element(usize),
    /// A far cluster: its point-source irradiance.
    Point(PointSource),
    /// A near cluster: Σ over its members of the exact form factor × the member's exitance.
    Members(Vec<usize>),
}

impl SourceShape {
    /// The shape of `source` for link (receiver ← source); `None` for a near cluster of more than
    /// `NEAR_CLUSTER_MEMBERS` members.
    fn of_link(nodes: &Nodes, flat: &[Vec3], receiver: usize, source: usize) -> Option<SourceShape> {
        if !nodes.is_cluster[source] {
            Some(SourceShape::Element(source))
        } else if !is_near(nodes, receiver, source) {
            Some(SourceShape::Point(PointSource::of_link(nodes, receiver, source, flat[source])))
        } else if nodes.member_count_within(source, NEAR_CLUSTER_MEMBERS) {
            let mut members = Vec::new();
            nodes.members(source, &mut members);
            Some(SourceShape::Members(members))
        } else {
            None
        }
    }

    /// g at a leaf of centre `centre` and unit normal `normal`.
    fn weight(&self, nodes: &Nodes, centre: Vec3, normal: Vec3) -> f64 {
        match self {
            SourceShape::Element(e) => point_to_polygon(centre, normal, &nodes.corners[*e]),
            SourceShape::Point(p) => p.weight(normal, centre),
            SourceShape::Members(m) => {
                m.iter().map(|&e| point_to_polygon(centre, normal, &nodes.corners[e]) * nodes.exitance_mean[e]).sum()
            }
        }
    }
}

/// The leaves below one element and what the spread moves onto each.
struct LeafSpread {
    leaves: Vec<usize>,
    total_area: f64,
    weight: Vec<f64>,
    delta: Vec<DVec3>,
}

impl LeafSpread {
    /// The leaves below element `node`, depth first, nothing moved yet.
    fn below(nodes: &Nodes, node: usize) -> LeafSpread {
        let (mut leaves, mut stack) = (Vec::new(), vec![node]);
        while let Some(n) = stack.pop() {
            if nodes.is_leaf(n) {
                leaves.push(n);
            } else {
                stack.extend(nodes.children(n).rev());
            }
        }
        let total_area = leaves.iter().map(|&l| nodes.area[l] as f64).sum();
        let count = leaves.len();
        LeafSpread { leaves, total_area, weight: vec![0.0; count], delta: vec![DVec3::ZERO; count] }
    }

    /// Moves irradiance `transfer`, handed to the element uniformly, onto its leaves by `g`:
    /// leaf ℓ gains transfer·(g(ℓ)/ḡ − 1). Nothing moves when ḡ is not positive.
    fn spread(&mut self, nodes: &Nodes, transfer: DVec3, g: impl Fn(Vec3, Vec3) -> f64) {
        if transfer == DVec3::ZERO || !(self.total_area > 0.0) {
            return;
        }
        for (w, &l) in self.weight.iter_mut().zip(&self.leaves) {
            *w = g(nodes.centre[l], nodes.normal[l]);
        }
        let weighted: f64 = self.leaves.iter().zip(&self.weight).map(|(&l, &w)| nodes.area[l] as f64 * w).sum();
        let mean = weighted / self.total_area;
        if !(mean > 0.0) || !mean.is_finite() {
            return;
        }
        for (d, &w) in self.delta.iter_mut().zip(&self.weight) {
            *d += transfer * (w / mean - 1.0);
        }
    }
}

/// What the spread moves onto each node (indexed by node; only leaves are touched).
struct Moves {
    delta: Vec<DVec3>,
    touched: Vec<bool>,
}

impl Moves {
    fn add(&mut self, below: LeafSpread) {
        for (leaf, d) in below.leaves.into_iter().zip(below.delta) {
            self.delta[leaf] += d;
            self.touched[leaf] = true;
        }
    }
}

/// Whether the push hands `node`'s light to leaves below it that the spread can move it between:
/// an element, not a leaf, with nothing resting on it.
fn spreads(nodes: &Nodes, node: usize) -> bool {
    !nodes.is_cluster[node] && !nodes.is_leaf(node) && nodes.open_area[node] >= nodes.area[node]
}

/// The exitance of every leaf below a spread element afterwards (see the module), as (leaf node,
/// new exitance) in node order; leaves nothing moves are left out.
pub fn spread_leaf_exitance(nodes: &Nodes, links: &Links, scales: &ArrivalScales, root: usize) -> Vec<(usize, DVec3)> {
    let flat = flat_normals(nodes);
    let receivers: Vec<usize> = (0..nodes.len()).filter(|&r| spreads(nodes, r) && !links.range(r).is_empty()).collect();
    let moved: Vec<LeafSpread> = receivers.par_iter().map(|&r| link_moves(nodes, links, scales, &flat, r)).collect();
    let mut moves = Moves { delta: vec![DVec3::ZERO; nodes.len()], touched: vec![false; nodes.len()] };
    for below in moved {
        moves.add(below);
    }
    cluster_moves(nodes, links, scales, &flat, root, &mut moves);
    let Moves { delta, touched } = moves;
    (0..nodes.len())
        .filter(|&n| touched[n])
        .map(|n| {
            let moved = delta[n] * scales.leaf_gain(n);
            (n, (nodes.exitance[n] + nodes.reflectance[n].as_dvec3() * moved).max(DVec3::ZERO))
        })
        .collect()
}

/// What element receiver `r`'s own links move between the leaves below it.
fn link_moves(nodes: &Nodes, links: &Links, scales: &ArrivalScales, flat: &[Vec3], r: usize) -> LeafSpread {
    let mut below = LeafSpread::below(nodes, r);
    let mut sent = scales.sent_cursor(r);
    for k in links.range(r) {
        let s = links.source[k] as usize;
        let transfer = sent.sent(nodes, r, s, &nodes.exitance) * links.form_factor[k] as f64;
        if s == r {
            continue;
        }
        if let Some(shape) = SourceShape::of_link(nodes, flat, r, s) {
            below.spread(nodes, transfer, |centre, normal| shape.weight(nodes, centre, normal));
        }
    }
    below
}

/// What clusters hand to the elements below them, moved between those elements' leaves: the push's
/// arrival stack rebuilt depth first from `root` (each cluster's `gather_into`), every far arrival
/// (one with a point source) spread over each top element (an element whose parent is a cluster)
/// by its own weight, and every member share spread by its link's source shape.
fn cluster_moves(nodes: &Nodes, links: &Links, scales: &ArrivalScales, flat: &[Vec3], root: usize, moves: &mut Moves) {
    let (mut arrivals, mut direct) = (Vec::<Arrival>::new(), Vec::new());
    let mut stack = vec![(root, 0usize)];
    while let Some((n, pending)) = stack.pop() {
        arrivals.truncate(pending);
        if !(nodes.open_area[n] > 0.0) {
            continue;
        }
        if nodes.is_cluster[n] {
            direct.clear();
            gather_into(nodes, links, scales, n, &nodes.exitance, None, &mut arrivals, &mut direct);
            share_moves(nodes, links, scales, flat, n, moves);
            let here = arrivals.len();
            stack.extend(nodes.children(n).rev().map(|c| (c, here)));
            continue;
        }
        if !spreads(nodes, n) {
            continue;
        }
        let mut below = LeafSpread::below(nodes, n);
        for a in arrivals.iter().filter(|a| a.source.is_some()) {
            let transfer = a.on_element(nodes.normal[n], nodes.centre[n]);
            below.spread(nodes, transfer, |centre, normal| a.weight(normal, centre));
        }
        moves.add(below);
    }
}

/// What cluster receiver `r`'s member shares move between the leaves of the members they land on.
fn share_moves(nodes: &Nodes, links: &Links, scales: &ArrivalScales, flat: &[Vec3], r: usize, moves: &mut Moves) {
    let reach = scales.receiver(r);
    let mut sent = scales.sent_cursor(r);
    for (i, k) in links.range(r).enumerate() {
        let s = links.source[k] as usize;
        let transfer = sent.sent(nodes, r, s, &nodes.exitance) * links.form_factor[k] as f64;
        if !reach.has_shares(i) {
            continue;
        }
        let Some(shape) = SourceShape::of_link(nodes, flat, r, s) else {
            continue;
        };
        for (m, c) in reach.shares(i) {
            if spreads(nodes, m) {
                let mut below = LeafSpread::below(nodes, m);
                below.spread(nodes, transfer * c as f64, |centre, normal| shape.weight(nodes, centre, normal));
                moves.add(below);
            }
        }
    }
}
