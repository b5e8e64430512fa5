//! The light of an element receiver's links spread over its leaves by position, once the sweeps
//! have converged: the reconstruction of the leaf exitance that the leaf mesh interpolates.
//!
//! Why: the push hands an element's irradiance to its children uniformly (Hanrahan, Salzman and
//! Aupperle 1991), so where refinement stopped at an element above the leaves every leaf below takes
//! the element's mean. Across a wall cut into long slivers the light then steps from one linked
//! element to the next, and the radiosity image shows streaks one linked element wide (stair_hall's
//! plaster wall: bands 7.5 cm wide differing by 3–4%, docs/accuracy.md session 21). The link's power
//! is right; only its spread over the receiver is flat.
//!
//! A link l of element receiver R (not a leaf, nothing resting on it) from source S carries the
//! irradiance T_l = F_l·B_S (as the gather reads it). Each leaf ℓ below R gets instead
//!
//! T_l · g_l(ℓ) / ḡ_l,  ḡ_l = Σ_ℓ A_ℓ·g_l(ℓ) / Σ_ℓ A_ℓ,
//!
//! g_l(ℓ) the unoccluded form factor from the leaf's centre to the source: Lambert's exact
//! point-to-polygon value for an element source (near or far), the point source of a far cluster
//! (`gather::PointSource`, as cluster receivers take their arrivals); near cluster sources stay
//! uniform. Σ_ℓ A_ℓ·T_l·g_l(ℓ)/ḡ_l = A_R·T_l: each link's power is conserved exactly, only moved
//! between the leaves. The leaf's exitance changes by ρ_ℓ·Σ_l T_l·(g_l(ℓ)/ḡ_l − 1) (clamped at 0).
//! Visibility stays the link's (one value over R).

use glam::DVec3;
use rayon::prelude::*;

use super::form_factor::point_to_polygon;
use super::gather::{flat_normals, ArrivalScales, PointSource};
use super::links::{is_near, Links};
use super::nodes::Nodes;

/// The exitance of every leaf below an element receiver after the spread (see the module), as
/// (leaf node, new exitance) in node order; leaves no link moves are left out.
pub fn spread_leaf_exitance(nodes: &Nodes, links: &Links, scales: &ArrivalScales) -> Vec<(usize, DVec3)> {
    let flat = flat_normals(nodes);
    let receivers: Vec<usize> = (0..nodes.len())
        .filter(|&r| {
            !nodes.is_cluster[r]
                && !nodes.is_leaf(r)
                && nodes.open_area[r] >= nodes.area[r]
                && !links.range(r).is_empty()
        })
        .collect();
    let moved: Vec<Vec<(usize, DVec3)>> =
        receivers.par_iter().map(|&r| receiver_moves(nodes, links, scales, &flat, r)).collect();
    let mut delta = vec![DVec3::ZERO; nodes.len()];
    let mut touched = vec![false; nodes.len()];
    for (leaf, d) in moved.into_iter().flatten() {
        delta[leaf] += d;
        touched[leaf] = true;
    }
    (0..nodes.len())
        .filter(|&n| touched[n])
        .map(|n| (n, (nodes.exitance[n] + nodes.reflectance[n].as_dvec3() * delta[n]).max(DVec3::ZERO)))
        .collect()
}

/// The irradiance each leaf below element receiver `r` gains or loses (Σ_l T_l·(g_l/ḡ_l − 1)).
fn receiver_moves(
    nodes: &Nodes,
    links: &Links,
    scales: &ArrivalScales,
    flat: &[glam::Vec3],
    r: usize,
) -> Vec<(usize, DVec3)> {
    let leaves = leaves_below(nodes, r);
    let total_area: f64 = leaves.iter().map(|&l| nodes.area[l] as f64).sum();
    let mut delta = vec![DVec3::ZERO; leaves.len()];
    let mut weight = vec![0.0f64; leaves.len()];
    let mut sent = scales.sent_cursor(r);
    for k in links.range(r) {
        let s = links.source[k] as usize;
        let transfer = sent.sent(nodes, r, s, &nodes.exitance) * links.form_factor[k] as f64;
        if s == r || transfer == DVec3::ZERO || !(total_area > 0.0) {
            continue;
        }
        let point_source = nodes.is_cluster[s].then(|| PointSource::of_link(nodes, r, s, flat[s]));
        if point_source.is_some() && is_near(nodes, r, s) {
            continue;
        }
        for (w, &l) in weight.iter_mut().zip(&leaves) {
            let (centre, normal) = (nodes.centre[l], nodes.normal[l]);
            *w = match &point_source {
                Some(p) => p.weight(normal, centre),
                None => point_to_polygon(centre, normal, &nodes.corners[s]),
            };
        }
        let mean = leaves.iter().zip(&weight).map(|(&l, &w)| nodes.area[l] as f64 * w).sum::<f64>() / total_area;
        if !(mean > 0.0) || !mean.is_finite() {
            continue;
        }
        for (d, &w) in delta.iter_mut().zip(&weight) {
            *d += transfer * (w / mean - 1.0);
        }
    }
    leaves.into_iter().zip(delta).collect()
}

/// The leaves below element `node`, depth first.
fn leaves_below(nodes: &Nodes, node: usize) -> Vec<usize> {
    let (mut out, mut stack) = (Vec::new(), vec![node]);
    while let Some(n) = stack.pop() {
        if nodes.is_leaf(n) {
            out.push(n);
        } else {
            stack.extend(nodes.children(n).rev());
        }
    }
    out
}
