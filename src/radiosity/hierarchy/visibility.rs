//! Visibility of a link, measured with rays through `crate::accel::Accel`: the share of rays between
//! stratified, deterministically seeded points of the two ends that reach the other end, each ray
//! weighed by its pair's form-factor kernel.

use glam::Vec3;

use super::form_factor::{clip_above, point_above, point_to_polygon};
use super::nodes::Nodes;
use super::shaft::{shaft_clear, EndHull, MAX_SHAFT_TRIANGLES, SLACK_EPSILONS};
use super::tree_path::path_hash;
use crate::accel::Accel;
use crate::rng::splitmix64;
use crate::sobol::{owen_scramble, sobol_2d_bits};
use crate::transport::hit::leave_surface;

/// What the visibility estimate needs besides the two nodes.
pub struct VisibilityContext<'a> {
    pub accel: &'a Accel,
    /// Rays per link.
    pub rays: u32,
    /// Distance the ray ends are moved off their surfaces (scene units).
    pub offset: f32,
    pub seed: u64,
}

/// A seed for link (receiver, source): a hash of the two nodes' tree paths (`tree_path`) and the
/// solve's seed, so a link's rays never depend on which thread estimates it, when, or in which order
/// the hierarchy was subdivided (a shard of pass one numbers its pieces otherwise than a whole solve).
pub fn link_seed(seed: u64, nodes: &Nodes, receiver: usize, source: usize) -> u64 {
    splitmix64(seed ^ splitmix64(path_hash(nodes, receiver) ^ splitmix64(path_hash(nodes, source) ^ 0x5e)))
}

/// What the rays of one link measured (see `link_visibility`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Visibility {
    /// V: the share of the sample pairs facing each other that nothing blocks, each pair weighed by
    /// its form-factor kernel (what the form factor is multiplied by; for a cluster receiver also the share of its facing members the source
    /// reaches, see `links::push_spread`).
    pub visible: f32,
    /// The sample pairs V was measured over (N, or fewer when fewer faced each other). A V = 0 read
    /// from them still allows a true share of up to about 1/(rays + 1) (`visibility_spread`).
    pub rays: u32,
}

/// The visibility of link (receiver ← source), measured with rays:
///
/// V ≈ Σ_k K_k·[segment x_k → y_k unoccluded] / Σ_k K_k,
///
/// K_k the form-factor kernel of the pair (`pair_kernel`), over N = `ctx.rays` sample pairs that face each other (n_x·(y − x) > 0 and n_y·(x − y) > 0): the form
/// factor already accounts for orientation (Lambert's clipped polygon, a cluster's projected area), so
/// a pair on elements that face away is not a visibility sample; without this rule a convex object's
/// cluster would count its own back faces as occluders and lose half its transfer.
/// x_k and y_k are points k of two `EndPattern`s, one per end (independent scrambles and shuffles, so
/// the pairing of receiver and source points is random): each end's first 2^m points are a 2-D
/// (0, m, 2)-net mapped onto it uniformly by area (`sample_point`), stratified in both directions and
/// across a cluster's members. Up to 4N pairs are drawn to find N facing ones; if none face, V is
/// measured over the member pairs that face (`facing_member_visibility`). Each end is moved `offset`
/// off its surface towards the other.
///
/// Until session 12 x_k was stratified in its first coordinate only (N strata, the second coordinate
/// and a cluster's member picks independent): cornell_original's hierarchical relMSE was 0.00112 on
/// seed 0 against the 0.00106 target, its error dominated by visibility noise (docs/accuracy.md).
pub fn link_visibility(ctx: &VisibilityContext, nodes: &Nodes, receiver: usize, source: usize) -> Visibility {
    link_visibility_with(ctx, nodes, receiver, source, ctx.rays)
}

/// `link_visibility` over N = `rays` sample pairs instead of `ctx.rays`. The pairs are the first N
/// of the link's sequence, so a larger N measures the smaller N's pairs again and more besides
/// (how a link whose rays all came out blocked is confirmed, `links::estimate`).
pub fn link_visibility_with(
    ctx: &VisibilityContext,
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    rays: u32,
) -> Visibility {
    let n = rays.max(1);
    // Two elements wholly in front of each other: every sample pair faces, so all rays would be
    // traced and, when the shaft is clear, all would pass: V = n/n = 1 without sampling.
    let mut clear = None;
    if elements_face_each_other(nodes, receiver, source)
        && *clear.get_or_insert_with(|| link_shaft_clear(ctx, nodes, receiver, source))
    {
        return Visibility { visible: 1.0, rays: n };
    }
    let (at_receiver, at_source) = EndPattern::pair(link_seed(ctx.seed, nodes, receiver, source));
    let softening_sq = pair_kernel_softening_sq(nodes, receiver, source, n);
    let (mut visible, mut weight, mut facing) = (0.0f64, 0.0f64, 0u32);
    for attempt in 0..4 * n {
        if facing == n {
            break;
        }
        let (x, nx) = sample_point(nodes, receiver, at_receiver.point(attempt));
        let (y, ny) = sample_point(nodes, source, at_source.point(attempt));
        let d = y - x;
        if !(ny.dot(d) < 0.0 && nx.dot(d) > 0.0) {
            continue;
        }
        facing += 1;
        let k = pair_kernel(d, nx, ny, softening_sq);
        weight += k;
        if unoccluded(ctx, nodes, receiver, source, &mut clear, (x, nx), (y, ny)) {
            visible += k;
        }
    }
    if !(weight > 0.0) {
        // No facing pair among the uniform ones: measured over the member pairs that face.
        let visible = facing_member_visibility(ctx, nodes, receiver, source, (at_receiver, at_source), &mut clear)
            .unwrap_or_else(|| {
                let clear = *clear.get_or_insert_with(|| link_shaft_clear(ctx, nodes, receiver, source));
                if clear {
                    1.0
                } else {
                    0.0
                }
            });
        return Visibility { visible, rays: n };
    }
    Visibility { visible: (visible / weight).min(1.0) as f32, rays: facing }
}

/// How many times `VisibilityContext::rays` sample pairs a link is measured with again when its
/// first N rays all came out blocked and the light they may have missed matters
/// (`links::estimate`): a pair whose true share is V passes none of N rays with probability
/// (1 − V)ᴺ, so V = 0 read from 8 rays still allows V ≈ 1/9 (docs/accuracy.md, session 40).
pub const BLOCKED_CONFIRM_FACTOR: u32 = 4;

/// Member pairs `facing_member_visibility` searches at most.
pub const FACING_SEARCH_PAIRS: usize = 4096;

/// `link_visibility` of a link none of whose 4N uniform sample pairs faced each other (an element
/// straddling the other's plane with a sliver in front of it, a cluster whose members mostly turn
/// away from the other end):
///
/// V ≈ Σ_k K_k·[x_k → y_k unoccluded] / Σ_k K_k
///
/// over N pairs drawn from the parts of member pairs (r, s) that face each other: r clipped to the
/// half-space in front of s's plane and s to the one in front of r's (`form_factor::clip_above`),
/// the pair picked with probability ∝ the product of the clipped areas and a point uniform on each
/// part, so that every drawn pair faces. `None` when no member pair has facing parts, or when the
/// ends hold more than `FACING_SEARCH_PAIRS` member pairs; the caller then takes V = 1 if the link's
/// shaft is clear and 0 if not.
///
/// Why: until session 20 such a link took V = 1 unmeasured, and its form factor (exact in
/// orientation, so small but not 0) passed walls: two rooms turned 30° about y leaked 1e-4 W through
/// the wall between them (tests/hierarchy.rs `light_does_not_leak_through_a_wall_turned_off_the_axes`).
/// V = 0 instead lost real light: 201 element links of the Cornell box (floor elements under a
/// block's face, lit by a sliver) and relMSE +1–3% on seeds 0–2.
fn facing_member_visibility(
    ctx: &VisibilityContext,
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    (at_receiver, at_source): (EndPattern, EndPattern),
    clear: &mut Option<bool>,
) -> Option<f32> {
    if !nodes.member_count_within(receiver, FACING_SEARCH_PAIRS) {
        return None;
    }
    let (mut rs, mut ss) = (Vec::new(), Vec::new());
    nodes.members(receiver, &mut rs);
    if !nodes.member_count_within(source, FACING_SEARCH_PAIRS / rs.len().max(1)) {
        return None;
    }
    nodes.members(source, &mut ss);
    let front_of =
        |part: usize, other: usize| clip_above(&nodes.corners[part], nodes.corners[other][0], nodes.normal[other]);
    let mut pairs: Vec<FacingParts> = Vec::new();
    let mut total = 0.0f64;
    for &r in &rs {
        for &s in &ss {
            if r == s {
                continue;
            }
            let (part_r, part_s) = (front_of(r, s), front_of(s, r));
            let weight = polygon_area(&part_r) * polygon_area(&part_s);
            if weight > 0.0 {
                total += weight;
                pairs.push(FacingParts {
                    receiver: r,
                    source: s,
                    of_receiver: part_r,
                    of_source: part_s,
                    cumulative: total,
                });
            }
        }
    }
    if !(total > 0.0) {
        return None;
    }
    let n = ctx.rays.max(1);
    let softening_sq = pair_kernel_softening_sq(nodes, receiver, source, n);
    let (mut visible, mut weight) = (0.0f64, 0.0f64);
    for k in 0..n {
        // The pair whose share of the cumulative weight holds u·total, and u rescaled to that share
        // (hierarchical sample warping, as in `sample_element`).
        let [u, v] = at_receiver.point(k);
        let at = pairs.partition_point(|p| p.cumulative <= u * total).min(pairs.len() - 1);
        let pair = &pairs[at];
        let before = if at > 0 { pairs[at - 1].cumulative } else { 0.0 };
        let u = ((u * total - before) / (pair.cumulative - before)).clamp(0.0, 1.0);
        let (x, nx) = (polygon_point(&pair.of_receiver, [u, v]), nodes.normal[pair.receiver]);
        let (y, ny) = (polygon_point(&pair.of_source, at_source.point(k)), nodes.normal[pair.source]);
        let d = y - x;
        if !(ny.dot(d) < 0.0 && nx.dot(d) > 0.0) {
            continue; // on a part's edge, within rounding of the other's plane
        }
        let kernel = pair_kernel(d, nx, ny, softening_sq);
        weight += kernel;
        if unoccluded(ctx, nodes, receiver, source, clear, (x, nx), (y, ny)) {
            visible += kernel;
        }
    }
    (weight > 0.0).then(|| (visible / weight).min(1.0) as f32)
}

/// The parts of member pair (receiver, source) of a link that face each other
/// (`facing_member_visibility`), and the running sum of the products of their areas up to this pair.
struct FacingParts {
    receiver: usize,
    source: usize,
    of_receiver: Vec<Vec3>,
    of_source: Vec<Vec3>,
    cumulative: f64,
}

/// The area of a convex polygon (a fan of triangles from its first vertex).
fn polygon_area(polygon: &[Vec3]) -> f64 {
    (1..polygon.len().saturating_sub(1))
        .map(|i| 0.5 * (polygon[i] - polygon[0]).cross(polygon[i + 1] - polygon[0]).length() as f64)
        .sum()
}

/// A point uniform by area on a convex polygon from (u, v) in [0, 1)²: the fan triangle whose
/// share of the area holds u, u rescaled to it, then `triangle_point`.
fn polygon_point(polygon: &[Vec3], [u, v]: [f64; 2]) -> Vec3 {
    let fan = |i: usize| [polygon[0], polygon[i], polygon[i + 1]];
    let area = |t: [Vec3; 3]| 0.5 * (t[1] - t[0]).cross(t[2] - t[0]).length() as f64;
    let mut pick = u * polygon_area(polygon);
    let last = polygon.len() - 2;
    for i in 1..=last {
        let a = area(fan(i));
        if pick < a || i == last {
            let w = if a > 0.0 { (pick / a).clamp(0.0, 1.0) } else { 0.5 };
            return triangle_point(&fan(i), w as f32, v as f32);
        }
        pick -= a;
    }
    polygon[0]
}

/// The weight of a sample pair (x, y) in `link_visibility`: the point-to-point form-factor kernel,
/// softened where the points come close,
///
/// K(x, y) = cos θ_x · cos θ_y / (|y − x|² + s²),
///
/// cos θ_x = n_x·(y − x)/|y − x|, cos θ_y = −n_y·(y − x)/|y − x| (both positive for a facing pair).
/// With pairs uniform by area on both ends, Σ K·v / Σ K tends to F_occluded / F_unoccluded, the
/// share of the form factor that nothing blocks, whereas the plain share of unblocked pairs weighs
/// a pair far apart like one close by: an end that reaches far behind a wall (Sponza's floor and
/// ceiling triangles run the whole length of the building) then lost the transfer of its visible,
/// near part to the hidden, far part, which contributes little to F (session 18: the links brought
/// Sponza's nave floor 30% and its gallery floor 51% less than cosine rays reading the same exitance).
pub fn pair_kernel(d: Vec3, nx: Vec3, ny: Vec3, softening_sq: f64) -> f64 {
    let d = d.as_dvec3();
    let d2 = d.length_squared();
    if !(d2 > 0.0) {
        return 0.0;
    }
    let cos_x = nx.as_dvec3().dot(d).max(0.0);
    let cos_y = (-ny.as_dvec3().dot(d)).max(0.0);
    cos_x * cos_y / (d2 * (d2 + softening_sq))
}

/// The softening s² of `pair_kernel` for link (receiver ← source) sampled with `rays` pairs: the
/// smaller end's area per sample over π, the squared radius of a disk of that area, about the
/// samples' spacing. Closer than that the unsoftened kernel grows without bound while the samples
/// cannot resolve it; s keeps one close pair from deciding V alone.
fn pair_kernel_softening_sq(nodes: &Nodes, receiver: usize, source: usize, rays: u32) -> f64 {
    nodes.area[receiver].min(nodes.area[source]) as f64 / (std::f64::consts::PI * rays.max(1) as f64)
}

/// Whether the segment between `x` and `y` (points with their unit normals on link (receiver ←
/// source)'s ends), each end moved `ctx.offset` off its surface (`leave_surface`), is unoccluded.
/// The link's shaft (`shaft::shaft_clear`, computed at the first call and kept in `clear`) answers
/// for all its rays when it is clear: then no ray is traced, and the answer is the one the ray would
/// have given (the shaft test is conservative to within the rays' own rounding).
fn unoccluded(
    ctx: &VisibilityContext,
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    clear: &mut Option<bool>,
    (x, nx): (Vec3, Vec3),
    (y, ny): (Vec3, Vec3),
) -> bool {
    let shaft = *clear.get_or_insert_with(|| link_shaft_clear(ctx, nodes, receiver, source));
    if shaft {
        return true;
    }
    let xo = leave_surface(x, nx, ctx.offset);
    let yo = leave_surface(y, ny, ctx.offset);
    !ctx.accel.occluded(xo, yo - xo, 1.0)
}

/// `shaft::shaft_clear` between the ray-end hulls of link (receiver ← source); false without a
/// box query when an end is a cluster of more than `shaft::MAX_SHAFT_TRIANGLES` input triangles:
/// its own members lie in the shaft's box, so the query would exceed its candidate cap anyway (the
/// clusters of a tessellated object, whose shafts paid the query for nothing: procedural:16000
/// +19% CPU-s in session 14).
fn link_shaft_clear(ctx: &VisibilityContext, nodes: &Nodes, receiver: usize, source: usize) -> bool {
    if [receiver, source]
        .iter()
        .any(|&end| nodes.is_cluster[end] && !nodes.member_count_within(end, MAX_SHAFT_TRIANGLES))
    {
        return false;
    }
    let ends = [receiver, source].map(|node| EndHull::of_node(nodes, node, ctx.offset));
    shaft_clear(ctx.accel, &ends[0], &ends[1])
}

/// Whether elements `a` and `b` (not clusters) lie wholly in front of each other, so that every
/// pair of their points passes `link_visibility`'s facing test (n_x·(y − x) > 0 and n_y·(x − y) > 0,
/// evaluated in f32): each one's corners are in front of the other's plane by more than
/// `shaft::SLACK_EPSILONS` ulps of the largest coordinate, which covers the rounding of the sample
/// points and of the test.
pub fn elements_face_each_other(nodes: &Nodes, a: usize, b: usize) -> bool {
    if nodes.is_cluster[a] || nodes.is_cluster[b] {
        return false;
    }
    let (ca, cb) = (nodes.corners[a].map(|p| p.as_dvec3()), nodes.corners[b].map(|p| p.as_dvec3()));
    let magnitude = ca.iter().chain(&cb).fold(0.0f64, |m, p| m.max(p.abs().max_element()));
    let margin = SLACK_EPSILONS * f32::EPSILON as f64 * magnitude;
    let in_front = |corners: &[glam::DVec3; 3], normal: Vec3, others: &[glam::DVec3; 3]| {
        let n = normal.as_dvec3();
        let plane = corners.iter().map(|p| n.dot(*p)).fold(f64::NEG_INFINITY, f64::max);
        others.iter().all(|p| n.dot(*p) > plane + margin)
    };
    in_front(&ca, nodes.normal[a], &cb) && in_front(&cb, nodes.normal[b], &ca)
}

/// The 2-D points one end of a link is sampled with: point k is point σ(k) of the Owen-scrambled
/// Sobol sequence (Burley 2020), σ a nested uniform scramble of the index that maps every aligned
/// block of 2^m indices onto an aligned block. So the first 2^m points are a (0, m, 2)-net: one in
/// each elementary interval of area 2^−m (an N-rooks set and a √N × √N jittered grid at once), each
/// point alone uniform in [0, 1)². Seeded from the link's seed only. (A plain XOR of the index, k ⊕
/// σ, is cheaper and keeps the nets, but pairs the two ends' points in a fixed pattern: one seed of
/// cornell_original went to relMSE 0.0063.)
#[derive(Clone, Copy, Debug)]
pub struct EndPattern {
    shuffle: u32,
    scramble: [u32; 2],
}

impl EndPattern {
    /// The receiver's and the source's patterns of a link of seed `link_seed`.
    pub fn pair(link_seed: u64) -> (EndPattern, EndPattern) {
        let make = |salt: u64| {
            let a = splitmix64(link_seed ^ salt);
            let b = splitmix64(a);
            EndPattern { shuffle: a as u32 ^ (a >> 32) as u32, scramble: [b as u32, (b >> 32) as u32] }
        };
        (make(0x7ece_17e5), make(0x5005_ce5e))
    }

    /// Point k (< 2^16), in [0, 1)² with 32-bit coordinates. The shuffled index keeps its low 16
    /// bits: an aligned block of 2^m ≤ 2^16 indices still maps onto one.
    pub fn point(&self, k: u32) -> [f64; 2] {
        let [x, y] = sobol_2d_bits(owen_scramble(k, self.shuffle) & 0xffff);
        let unit = |b: u32| b as f64 * (1.0 / 4_294_967_296.0);
        [unit(owen_scramble(x, self.scramble[0])), unit(owen_scramble(y, self.scramble[1]))]
    }
}

/// A point uniformly distributed by area on `node` from (u, v) in [0,1)², and the unit normal of the
/// element it lies on (`sample_element`, then `triangle_point`).
pub fn sample_point(nodes: &Nodes, node: usize, uv: [f64; 2]) -> (Vec3, Vec3) {
    let (at, [u, v]) = sample_element(nodes, node, uv);
    (triangle_point(&nodes.corners[at], u as f32, v as f32), nodes.normal[at])
}

/// The element below `node` (down to an input triangle) that (u, v) in [0,1)² picks with probability
/// proportional to its area, and the (u', v) left for a point on it. A cluster is descended with u:
/// the child whose share of the cumulative area holds u·A is taken and u rescaled to that share,
/// u' = (u·A − A_before)/A_child (hierarchical sample warping), so a stratified set of (u, v) stays
/// stratified across the cluster's members.
pub fn sample_element(nodes: &Nodes, node: usize, uv: [f64; 2]) -> (usize, [f64; 2]) {
    let [mut u, v] = uv;
    let mut at = node;
    while nodes.is_cluster[at] {
        let children = nodes.children(at);
        let total: f64 = children.clone().map(|c| nodes.area[c] as f64).sum();
        let mut pick = u * total;
        // Rounding can leave `pick` past the last child: it then takes the last child with area.
        let mut chosen = (children.end - 1, 1.0 - f64::EPSILON);
        for c in children.clone() {
            let a = nodes.area[c] as f64;
            if pick < a {
                chosen = (c, pick / a);
                break;
            }
            pick -= a;
            if a > 0.0 {
                chosen = (c, 1.0 - f64::EPSILON);
            }
        }
        (at, u) = chosen;
    }
    (at, [u, v])
}

/// Uniform point on a triangle from the unit square: p = (1 − √u)·a + √u(1 − v)·b + √u·v·c
/// (Turk 1990; Shirley and Chiu 1997).
pub fn triangle_point(t: &[Vec3; 3], u: f32, v: f32) -> Vec3 {
    let su = u.sqrt();
    t[0] * (1.0 - su) + t[1] * (su * (1.0 - v)) + t[2] * (su * v)
}

/// The weight of node `c` in `sample_element_towards`'s descent towards point `x`:
///
/// w_c = A_c / (|x − c_c|² + min(r_c², A_c)),
///
/// c_c and r_c its bounding sphere (0 for a node without area). The sphere's radius is capped at
/// √A_c: a cluster's sphere can be far larger than its members (`Nodes::set_cluster_children` grows
/// it with depth; 263 m for a 19.6 m² cluster of the rotunda), and A_c/r_c² would then weight
/// siblings by how much their spheres grew rather than by how near they are (with r_c uncapped the
/// rotunda's radiosity relMSE went 0.00355 → 0.00446 on seed 1).
fn kernel_weight(nodes: &Nodes, x: Vec3, c: usize) -> f64 {
    let a = nodes.area[c] as f64;
    if !(a > 0.0) {
        return 0.0;
    }
    let (d2, r) = (x.distance_squared(nodes.centre[c]) as f64, nodes.radius[c] as f64);
    a / (d2 + (r * r).min(a)).max(f64::MIN_POSITIVE)
}

/// The element below `node` (down to an input triangle) that u in [0, 1) picks with probability
/// proportional to a bounded kernel towards point `x`, and u rescaled for a point on it. A cluster is
/// descended child by child with weights w_c (`kernel_weight`), u rescaled to the chosen child's share
/// of Σ w as in `sample_element`, so a stratified u stays stratified. w_c follows the point-to-node
/// form factor ≈ A_c cos θ cos θ' / (π d²) where a node is small beside its distance and stays
/// bounded (≤ 1) where x touches it. Its probability is `towards_probability`.
pub fn sample_element_towards(nodes: &Nodes, node: usize, x: Vec3, u: f64) -> (usize, f64) {
    let (mut at, mut u) = (node, u);
    while nodes.is_cluster[at] {
        let children = nodes.children(at);
        let total: f64 = children.clone().map(|c| kernel_weight(nodes, x, c)).sum();
        if !(total > 0.0) {
            return (at, u);
        }
        let mut pick = u * total;
        // Rounding can leave `pick` past the last child: it then takes the last child with weight.
        let mut chosen = (children.end - 1, 1.0 - f64::EPSILON);
        for c in children.clone() {
            let w = kernel_weight(nodes, x, c);
            if pick < w {
                chosen = (c, pick / w);
                break;
            }
            pick -= w;
            if w > 0.0 {
                chosen = (c, 1.0 - f64::EPSILON);
            }
        }
        (at, u) = chosen;
    }
    (at, u)
}

/// The probability that `sample_element_towards(nodes, node, x, ·)` picks `element` (below `node`):
/// the product of its ancestors' shares w_a / Σ_siblings w up to `node`.
pub fn towards_probability(nodes: &Nodes, node: usize, x: Vec3, element: usize) -> f64 {
    let mut probability = 1.0f64;
    let mut at = element;
    while at != node {
        let parent = nodes.parent[at] as usize;
        let total: f64 = nodes.children(parent).map(|c| kernel_weight(nodes, x, c)).sum();
        if !(total > 0.0) {
            return 0.0;
        }
        probability *= kernel_weight(nodes, x, at) / total;
        at = parent;
    }
    probability
}

/// Samples of `sampled_form_factor` per visibility ray of a link (`VisibilityContext::rays`). A near
/// link's error is read from its samples (`SampledFormFactor::deviation`), and 8 of them over a pair
/// of building-sized clusters judge it poorly. At 4 × 8 the rooms came out 1–27% lower in relMSE
/// and cornell_original seed 0 42%, for 0.94–1.23× the CPU time (the vault hall got cheaper: noisy
/// deviations split fewer links needlessly); cornell seed 3 +8% and cornell_empty +30%, whose
/// errors are a tenth of the rooms' (session 19, docs/accuracy.md). 6 × 8 (session 27): Sponza
/// 0.0720 → 0.0616 in relMSE for +13% CPU-s, where 12 visibility rays or a threshold of 3.5e-3
/// cost +50% for −21%; the rooms within ±2.6%. Refinement reads the deviation, and its noise decides
/// which near links are split: the same 32 samples with the deviation from their second half only
/// gave Sponza 0.0850. 8 × 8: 0.0595 for +29%.
pub const NEAR_SAMPLES_PER_RAY: u32 = 6;

/// A sampled form factor for links whose ends are too near for the cluster formula (overlapping
/// bounding spheres, or a cluster straddling an element's plane), and for a cluster's self-link:
/// Monte Carlo over the receiver, exact in each sampled source element:
///
/// F_RS ≈ (1/N) Σ_k F(x_k → t_k) / p_k(t_k) · V_k
///
/// over N = `NEAR_SAMPLES_PER_RAY` × `ctx.rays` samples: x_k point k of the receiver's `EndPattern` (uniform by area), t_k
/// the source element that the first coordinate of point k of the source's pattern picks with
/// probability p_k(t) ∝ a bounded kernel towards x_k (`sample_element_towards`, p_k from
/// `towards_probability`), F(x → t) Lambert's
/// exact unoccluded point-to-polygon form factor (`form_factor::point_to_polygon`, one-sided,
/// clipped to x's hemisphere), which is bounded, so ends that touch need no regularisation. V_k is
/// the ray x_k → y_k, y_k the pattern's point on t_k (uniform on it), when the two face each other; a
/// sample whose y_k does not (it lies in the part of t_k the clipping removed) takes the
/// kernel-weighted visibility of the others, V̄ = Σ F_k V_k / Σ F_k. When no sample has a ray, V̄
/// is measured over those samples with rays to the part of t_k above x_k's plane
/// (`form_factor::point_above`), and is 0 when none faces; until session 20 it was 1 unmeasured,
/// which let two rooms turned off the axes pass light through the wall between them
/// (`facing_member_visibility` tells the rest). Unbiased without occluders. The estimate is capped at 1 (F_RS ≤ 1).
/// Also returns the samples with F(x_k → t_k) > 0 and the estimate's deviation over the receiver
/// (`SampledFormFactor`).
///
/// Until session 15 t_k was picked by area (p = A_t/A_S): where the ends touch, F(x → t)·A_S/A_t is
/// up to A_S/A_t for an x beside t, a heavy tail that 8 samples seldom reach and that the cap at 1
/// cut off where they did. Perpendicular rectangles sharing an edge came out 14–23% low (mean of 64
/// seeds; over 4096 seeds −2% to −7% with the cap, within 1.2% without it) and disks r 1 → 2 at
/// separation 0.5 13% low (all of it the cap); not one ray was blocked in those cases
/// (tests/hierarchy.rs). With the kernel every case is within 2.9% and 1.2 standard errors (64 seeds).
///
/// Until session 12 this was Wallace, Elmquist and Haines' (1989) disk estimator,
/// A_S cos θ_x cos θ_y V / (π d² + A_S/N) per point pair: its disk term biased touching ends low by
/// 18–42% (tests/hierarchy.rs), which darkened cornell_original's floor between the blocks; it took
/// 2 × `ctx.rays` pairs, which the bounded kernel does not need (seeds 0–7 of cornell_original: mean
/// relMSE 0.00071 at N, 0.00074 at 2N, docs/accuracy.md).
pub fn sampled_form_factor(
    ctx: &VisibilityContext,
    nodes: &Nodes,
    receiver: usize,
    source: usize,
) -> SampledFormFactor {
    sampled_form_factor_reads(ctx, nodes, receiver, source, &mut Vec::new())
}

/// `sampled_form_factor`, also writing into `reads` each sample's source element t_k and its part
/// of N·F_RS (F_k V_k, or F_k V̄ for a sample without a ray): Σ_k w_k B(t_k) / Σ_k w_k is the
/// exitance the samples see of the source.
pub fn sampled_form_factor_reads(
    ctx: &VisibilityContext,
    nodes: &Nodes,
    receiver: usize,
    source: usize,
    reads: &mut Vec<(usize, f64)>,
) -> SampledFormFactor {
    reads.clear();
    let n = ctx.rays.max(1) * NEAR_SAMPLES_PER_RAY;
    let (at_receiver, at_source) = EndPattern::pair(link_seed(ctx.seed ^ 0x5eed_f0f0, nodes, receiver, source));
    // Σ F_k V_k and Σ F_k over samples with a visibility ray; Σ F_k over samples without one.
    let (mut seen, mut tested, mut untested) = (0.0f64, 0.0f64, 0.0f64);
    let mut facing = 0u32;
    let mut clear = None;
    // f_k, unoccluded (0 where x_k faces none of the source), for the deviation.
    let mut unoccluded_f = Vec::with_capacity(n as usize);
    // The samples without a visibility ray: (x_k, n_x, t_k, f_k).
    let mut without_ray: Vec<(Vec3, Vec3, usize, f64)> = Vec::new();
    for k in 0..n {
        let (x, nx) = sample_point(nodes, receiver, at_receiver.point(k));
        let [u, v] = at_source.point(k);
        let (t, u) = sample_element_towards(nodes, source, x, u);
        let probability = towards_probability(nodes, source, x, t);
        if !(probability > 0.0) || nodes.is_cluster[t] {
            continue;
        }
        let corners = &nodes.corners[t];
        let f = point_to_polygon(x, nx, corners) / probability;
        if !(f > 0.0) {
            continue;
        }
        unoccluded_f.push(f);
        facing += 1;
        let (y, ny) = (triangle_point(corners, u as f32, v as f32), nodes.normal[t]);
        let d = y - x;
        if !(ny.dot(d) < 0.0 && nx.dot(d) > 0.0) {
            untested += f;
            without_ray.push((x, nx, t, f));
            continue;
        }
        tested += f;
        if unoccluded(ctx, nodes, receiver, source, &mut clear, (x, nx), (y, ny)) {
            seen += f;
            reads.push((t, f));
        }
    }
    let mean_visibility = if tested > 0.0 {
        seen / tested
    } else {
        // No sample had a ray: each is measured towards the part of t_k above x_k's plane.
        let (mut seen, mut tested) = (0.0f64, 0.0f64);
        for &(x, nx, t, f) in &without_ray {
            let Some(y) = point_above(&nodes.corners[t], x, nx) else { continue };
            let (d, ny) = (y - x, nodes.normal[t]);
            if ny.dot(d) < 0.0 && nx.dot(d) > 0.0 {
                tested += f;
                if unoccluded(ctx, nodes, receiver, source, &mut clear, (x, nx), (y, ny)) {
                    seen += f;
                }
            }
        }
        if tested > 0.0 {
            seen / tested
        } else {
            0.0
        }
    };
    reads.extend(without_ray.iter().map(|&(_, _, t, f)| (t, f * mean_visibility)));
    let form_factor = ((seen + untested * mean_visibility) / n as f64).min(1.0);
    let unoccluded_mean = (tested + untested) / n as f64;
    let deviation = mean_visibility * receiver_deviation(&unoccluded_f, n as usize)
        + unoccluded_mean * visibility_spread(mean_visibility, n);
    SampledFormFactor { form_factor, facing, deviation }
}

/// The error of a visible fraction V measured with N rays, as a fraction of the unoccluded form
/// factor: 2 max(min(V, 1 − V), 1/(N + 1)). A receiver partly in shadow gets one mean irradiance
/// (2 min(V, 1 − V), the term of an element link in `links::estimate`), and N rays that all agree
/// still leave a gap or a thin occluder of about 1/(N + 1) unseen (a door gap that no ray of a
/// near link passed would otherwise be kept dark with no error at all).
pub fn visibility_spread(visible: f64, rays: u32) -> f64 {
    2.0 * visible.min(1.0 - visible).max(1.0 / (rays as f64 + 1.0))
}

/// What `sampled_form_factor` measures of a near link.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SampledFormFactor {
    /// F_RS, visibility included, capped at 1.
    pub form_factor: f64,
    /// Samples with F(x_k → t_k) > 0: 0 means the ends cannot exchange light at all (a convex
    /// object's own cluster, a flat cluster), and the link can be dropped.
    pub facing: u32,
    /// How far a uniform F_RS over the receiver is from the truth, as a form factor (a link pushes
    /// one irradiance to all of its receiver): `receiver_deviation` of the unoccluded samples f_k
    /// times the mean visibility V̄, plus F̄ `visibility_spread`(V̄) (F̄ the unoccluded mean).
    pub deviation: f64,
}

/// The error of standing for the point-to-source form factors f_k (N samples, uniform over the
/// receiver by area; `samples` holds the nonzero ones) by their mean f̄, plus the error of f̄
/// itself:
///
/// ΔF = (1/N) Σ_k |f_k − f̄| + s/√N,   s² = Σ_k (f_k − f̄)² / (N − 1),
///
/// the mean absolute deviation being the L1 error of a constant F over the receiver, which is what
/// a link's error power A_R ρ_R B_S ΔF (`links::link_error_power`) charges. It overstates where the
/// source's sampling adds noise to f_k: the link is then refined sooner, never later.
pub fn receiver_deviation(samples: &[f64], n: usize) -> f64 {
    if n == 0 {
        return 0.0;
    }
    let zeros = n.saturating_sub(samples.len()) as f64;
    let mean = samples.iter().sum::<f64>() / n as f64;
    let absolute = samples.iter().map(|f| (f - mean).abs()).sum::<f64>() + zeros * mean;
    let square = samples.iter().map(|f| (f - mean).powi(2)).sum::<f64>() + zeros * mean * mean;
    let standard_error = if n > 1 { (square / (n - 1) as f64 / n as f64).sqrt() } else { mean };
    absolute / n as f64 + standard_error
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `receiver_deviation`: no deviation when every sample agrees; for samples half 0 and half
    /// 2c (two halves of a receiver, one lit), the mean absolute deviation c plus the standard
    /// error c·√(N/(N − 1))/√N of the mean.
    #[test]
    fn receiver_deviation_is_the_mean_absolute_deviation_plus_the_standard_error() {
        assert_eq!(receiver_deviation(&[0.3; 8], 8), 0.0);
        assert_eq!(receiver_deviation(&[], 8), 0.0);
        let c = 0.2;
        let got = receiver_deviation(&[2.0 * c; 4], 8);
        let want = c + c * (8.0f64 / 7.0).sqrt() / 8.0f64.sqrt();
        assert!((got - want).abs() < 1e-12, "{got} vs {want}");
    }

    /// Points 0..2^m of an end pattern put one point in every elementary interval of area 2^−m (every
    /// 2^a × 2^(m−a) grid): the (0, m, 2)-net the visibility estimate's stratification rests on, for
    /// any link seed.
    #[test]
    fn an_end_patterns_first_power_of_two_points_are_a_net() {
        for seed in 0..50u64 {
            let (receiver, source) = EndPattern::pair(seed);
            for pattern in [receiver, source] {
                for m in 0..=6u32 {
                    let points: Vec<[f64; 2]> = (0..1u32 << m).map(|k| pattern.point(k)).collect();
                    for a in 0..=m {
                        let (nx, ny) = (1usize << a, 1usize << (m - a));
                        let mut seen = vec![false; nx * ny];
                        for p in &points {
                            let cell = (p[1] * ny as f64) as usize * nx + (p[0] * nx as f64) as usize;
                            assert!(!std::mem::replace(&mut seen[cell], true), "seed {seed}, m {m}, a {a}");
                        }
                    }
                }
            }
        }
    }
}
