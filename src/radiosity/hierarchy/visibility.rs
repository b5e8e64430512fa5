//! Visibility of a link, measured with rays through `crate::accel::Accel`: the fraction of rays
//! between stratified, deterministically seeded points of the two ends that reach the other end.

use glam::Vec3;

use super::nodes::Nodes;
use super::tree_path::path_hash;
use crate::accel::Accel;
use crate::rng::{splitmix64, Pcg32};
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
/// x_k is stratified over the receiver (stratum k of N in the first coordinate), y_k over the source
/// with a scrambled stratum order, both uniform by area; a cluster end is sampled by descending its
/// tree with probabilities proportional to area, down to an input triangle. Up to 4N pairs are drawn
/// to find N facing ones; if none face, the orientation terms of the form factor are ≈ 0 and V = 1.
/// Each end is moved
/// `offset` off its surface towards the other.
pub fn link_visibility(ctx: &VisibilityContext, nodes: &Nodes, receiver: usize, source: usize) -> Visibility {
    let n = ctx.rays.max(1);
    let mut rng = Pcg32::new(link_seed(ctx.seed, nodes, receiver, source), 0);
    let shift = rng.next_u32() % n;
    let (mut visible, mut facing) = (0u32, 0u32);
    for attempt in 0..4 * n {
        if facing == n {
            break;
        }
        let k = attempt % n;
        let ur = (k as f32 + rng.next_f32()) / n as f32;
        let us = (((k + shift) % n) as f32 + rng.next_f32()) / n as f32;
        let (x, nx) = sample_point(nodes, receiver, ur, rng.next_f32(), &mut rng);
        let (y, ny) = sample_point(nodes, source, us, rng.next_f32(), &mut rng);
        let d = y - x;
        if !(ny.dot(d) < 0.0 && nx.dot(d) > 0.0) {
            continue;
        }
        facing += 1;
        let xo = leave_surface(x, nx, ctx.offset);
        let yo = leave_surface(y, ny, ctx.offset);
        if !ctx.accel.occluded(xo, yo - xo, 1.0) {
            visible += 1;
        }
    }
    Visibility { visible: if facing == 0 { 1.0 } else { visible as f32 / facing as f32 } }
}

/// A point uniformly distributed by area on `node` from (u, v) in [0,1)² (descending clusters with
/// fresh random numbers), and the unit normal of the element it lies on.
fn sample_point(nodes: &Nodes, node: usize, u: f32, v: f32, rng: &mut Pcg32) -> (Vec3, Vec3) {
    let mut at = node;
    while nodes.is_cluster[at] {
        let children = nodes.children(at);
        let total: f32 = children.clone().map(|c| nodes.area[c]).sum();
        let mut pick = rng.next_f32() * total;
        let mut chosen = children.end - 1;
        for c in children {
            if pick < nodes.area[c] {
                chosen = c;
                break;
            }
            pick -= nodes.area[c];
        }
        at = chosen;
    }
    (triangle_point(&nodes.corners[at], u, v), nodes.normal[at])
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
/// over N = 2 × `ctx.rays` stratified point pairs, x_k uniform on the receiver and y_k uniform on the
/// source (Wallace, Elmquist and Haines 1989: each sample stands for a disk of area A_S/N, which keeps
/// the kernel bounded when the ends touch). Pairs that do not face each other contribute 0. Returns
/// (F, pairs that faced each other): 0 facing pairs means the ends cannot exchange light at all (a
/// convex object's own cluster, a flat cluster), and the link can be dropped.
pub fn sampled_form_factor(ctx: &VisibilityContext, nodes: &Nodes, receiver: usize, source: usize) -> (f64, u32) {
    let n = 2 * ctx.rays.max(1);
    let mut rng = Pcg32::new(link_seed(ctx.seed ^ 0x5eed_f0f0, nodes, receiver, source), 0);
    let shift = rng.next_u32() % n;
    let disk = nodes.area[source] as f64 / n as f64;
    let (mut sum, mut facing) = (0.0f64, 0u32);
    for k in 0..n {
        let ur = (k as f32 + rng.next_f32()) / n as f32;
        let us = (((k + shift) % n) as f32 + rng.next_f32()) / n as f32;
        let (x, nx) = sample_point(nodes, receiver, ur, rng.next_f32(), &mut rng);
        let (y, ny) = sample_point(nodes, source, us, rng.next_f32(), &mut rng);
        let d = y - x;
        let d2 = d.length_squared() as f64;
        let (cx, cy) = (nx.dot(d) as f64, -ny.dot(d) as f64);
        if !(cx > 0.0 && cy > 0.0 && d2 > 0.0) {
            continue;
        }
        facing += 1;
        let xo = leave_surface(x, nx, ctx.offset);
        let yo = leave_surface(y, ny, ctx.offset);
        if !ctx.accel.occluded(xo, yo - xo, 1.0) {
            // cos θ_x cos θ_y = (n_x·d)(−n_y·d)/d².
            sum += nodes.area[source] as f64 * cx * cy / d2 / (std::f64::consts::PI * d2 + disk);
        }
    }
    ((sum / n as f64).min(1.0), facing)
}
