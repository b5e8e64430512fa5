//! Visibility of a link, measured with rays through `crate::accel::Accel`: the fraction of rays
//! between stratified, deterministically seeded points of the two ends that reach the other end.

use glam::Vec3;

use super::nodes::Nodes;
use super::tree_path::path_hash;
use crate::accel::Accel;
use crate::rng::splitmix64;
use crate::sobol::{owen_scramble, sobol_2d_bits};

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
    /// V: the fraction of sample pairs facing each other that nothing blocks (what the form factor
    /// is multiplied by; for a cluster receiver also the share of its facing members the source
    /// reaches, see `links::push_spread`).
    pub visible: f32,
}

/// The visibility of link (receiver ← source), measured with rays:
///
/// V ≈ (1/N) Σ_k [segment x_k → y_k unoccluded]
///
/// V over N = `ctx.rays` sample pairs that face each other (n_x·(y − x) > 0 and n_y·(x − y) > 0): the form
/// factor already accounts for orientation (Lambert's clipped polygon, a cluster's projected area), so
/// a pair on elements that face away is not a visibility sample; without this rule a convex object's
/// cluster would count its own back faces as occluders and lose half its transfer.
/// x_k and y_k are points k of two `EndPattern`s, one per end (independent scrambles and shuffles, so
/// the pairing of receiver and source points is random): each end's first 2^m points are a 2-D
/// (0, m, 2)-net mapped onto it uniformly by area (`sample_point`), stratified in both directions and
/// across a cluster's members. Up to 4N pairs are drawn to find N facing ones; if none face, the
/// orientation terms of the form factor are ≈ 0 and V = 1. Each end is moved `offset` off its surface
/// towards the other.
///
/// Until session 12 x_k was stratified in its first coordinate only (N strata, the second coordinate
/// and a cluster's member picks independent): cornell_original's hierarchical relMSE was 0.00112 on
/// seed 0 against the 0.00106 target, its error dominated by visibility noise (docs/accuracy.md).
pub fn link_visibility(ctx: &VisibilityContext, nodes: &Nodes, receiver: usize, source: usize) -> Visibility {
    let n = ctx.rays.max(1);
    let (at_receiver, at_source) = EndPattern::pair(link_seed(ctx.seed, nodes, receiver, source));
    let (mut visible, mut facing) = (0u32, 0u32);
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
        let xo = x + nx * ctx.offset;
        let yo = y + ny * ctx.offset;
        if !ctx.accel.occluded(xo, yo - xo, 1.0) {
            visible += 1;
        }
    }
    Visibility { visible: if facing == 0 { 1.0 } else { visible as f32 / facing as f32 } }
}

/// The 2-D points one end of a link is sampled with: point k is point σ(k) of the Owen-scrambled
/// Sobol sequence (Burley 2020), σ a nested uniform scramble of the index that maps every aligned
/// block of 2^m indices onto an aligned block. So the first 2^m points are a (0, m, 2)-net: one in
/// each elementary interval of area 2^−m (an N-rooks set and a √N × √N jittered grid at once), each
/// point alone uniform in [0, 1)². Seeded from the link's seed only.
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

    /// Point k, in [0, 1)² with 32-bit coordinates.
    pub fn point(&self, k: u32) -> [f64; 2] {
        let [x, y] = sobol_2d_bits(owen_scramble(k, self.shuffle));
        let unit = |b: u32| b as f64 * (1.0 / 4_294_967_296.0);
        [unit(owen_scramble(x, self.scramble[0])), unit(owen_scramble(y, self.scramble[1]))]
    }
}

/// A point uniformly distributed by area on `node` from (u, v) in [0,1)², and the unit normal of the
/// element it lies on. A cluster is descended with u: the child whose share of the cumulative area
/// holds u·A is taken and u rescaled to that share, u' = (u·A − A_before)/A_child (hierarchical sample
/// warping), so a stratified set of (u, v) stays stratified across the cluster's members; the input
/// triangle reached gets (u', v) through `triangle_point`.
pub fn sample_point(nodes: &Nodes, node: usize, uv: [f64; 2]) -> (Vec3, Vec3) {
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
    (triangle_point(&nodes.corners[at], u as f32, v as f32), nodes.normal[at])
}

/// Uniform point on a triangle from the unit square: p = (1 − √u)·a + √u(1 − v)·b + √u·v·c
/// (Turk 1990; Shirley and Chiu 1997).
pub fn triangle_point(t: &[Vec3; 3], u: f32, v: f32) -> Vec3 {
    let su = u.sqrt();
    t[0] * (1.0 - su) + t[1] * (su * (1.0 - v)) + t[2] * (su * v)
}

/// A ray-traced form factor for links whose ends are too near for the cluster formula (overlapping
/// bounding spheres, or a cluster straddling an element's plane), and for a cluster's self-link:
///
/// F_RS ≈ (1/N) Σ_k A_S cos θ_x cos θ_y V(x_k, y_k) / (π d_k² + A_S/N)
///
/// over N = 2 × `ctx.rays` point pairs, x_k and y_k points k of the ends' `EndPattern`s (stratified
/// nets, each point uniform by area on its end) (Wallace, Elmquist and Haines 1989: each sample stands for a disk of area A_S/N, which keeps
/// the kernel bounded when the ends touch). Pairs that do not face each other contribute 0. Returns
/// (F, pairs that faced each other): 0 facing pairs means the ends cannot exchange light at all (a
/// convex object's own cluster, a flat cluster), and the link can be dropped.
pub fn sampled_form_factor(ctx: &VisibilityContext, nodes: &Nodes, receiver: usize, source: usize) -> (f64, u32) {
    let n = 2 * ctx.rays.max(1);
    let (at_receiver, at_source) = EndPattern::pair(link_seed(ctx.seed ^ 0x5eed_f0f0, nodes, receiver, source));
    let disk = nodes.area[source] as f64 / n as f64;
    let (mut sum, mut facing) = (0.0f64, 0u32);
    for k in 0..n {
        let (x, nx) = sample_point(nodes, receiver, at_receiver.point(k));
        let (y, ny) = sample_point(nodes, source, at_source.point(k));
        let d = y - x;
        let d2 = d.length_squared() as f64;
        let (cx, cy) = (nx.dot(d) as f64, -ny.dot(d) as f64);
        if !(cx > 0.0 && cy > 0.0 && d2 > 0.0) {
            continue;
        }
        facing += 1;
        let xo = x + nx * ctx.offset;
        let yo = y + ny * ctx.offset;
        if !ctx.accel.occluded(xo, yo - xo, 1.0) {
            // cos θ_x cos θ_y = (n_x·d)(−n_y·d)/d².
            sum += nodes.area[source] as f64 * cx * cy / d2 / (std::f64::consts::PI * d2 + disk);
        }
    }
    ((sum / n as f64).min(1.0), facing)
}
