//! The row sums of the hierarchy's transport operator, and the bound the sweeps need.
//!
//! A leaf i gathers G_i = Σ_j F_ij B_j over every link that reaches it: its own, and its ancestors'
//! handed down by the push (`gather::push_step`). With every node sending B ≡ 1 the push gives the
//! leaf's row sum
//!
//! R_i = Σ_j F_ij,
//!
//! the share of its hemisphere the links say it sees. A surface sees at most its whole hemisphere,
//! so R_i ≤ 1 (= 1 inside a closed room). Link estimates overshoot it: near links between overlapping
//! clusters, leaf-pair sums over stacked sources clamped at 1 each. Where a leaf's row comes to
//! ρ_i·R_i ≥ 1 (ρ_i its largest channel), the leaf would reflect at least all it gathers from
//! sources as bright as itself, and the sweeps diverge: Crytek Sponza with its large triangles
//! pre-split into 328k had a leaf of ρ 0.47 at R = 2.7 and exitance 1e14 after 100 sweeps
//! (session 24). Once a solve's exitance passes `solve::exitance_limit` (twice what any leaf could
//! reach with every row in its hemisphere), `solve::solve_until` bounds the rows
//! (`ArrivalScales::bound_rows`): such a leaf's gathering is scaled by its gain
//!
//! g_i = 1 / R_i  where ρ_i·R_i ≥ 1,  else g_i = 1,
//!
//! so that it sees exactly its hemisphere, every row of ρ·g·F sums to less than 1 (ρ < 1) and the
//! Jacobi iteration is a contraction; and the sweeps start again from the emission.
//!
//! Only then, and only those rows: the rows above 1 are wrong too, but on the unsplit Sponza, whose
//! sweeps converge, 116k of 588k leaves have R > 1 (up to 462) and bounding them made the image
//! worse, the estimates' errors going both ways and partly cancelling (radiosity-mode relMSE 0.078;
//! every row to R ≤ 1: 0.120; the rows with ρ·R ≥ 1 from the first sweep: 0.086).

use glam::DVec3;

use super::gather::{gather_into, push_step, ArrivalScales, Pushed};
use super::links::Links;
use super::nodes::{Nodes, NONE};

/// Per node: R_n for a leaf (see the module), 0 for inner nodes. Walks every tree (each node whose
/// parent is `NONE`) depth-first with the sweep's own gather and push (`solve::sweep`), reading
/// exitance 1 everywhere and writing nothing. Serial and in a fixed order, like the sweep.
pub fn row_sums(nodes: &Nodes, links: &Links, scales: &ArrivalScales) -> Vec<f64> {
    let unit = vec![DVec3::ONE; nodes.len()];
    let mut sums = vec![0.0f64; nodes.len()];
    let (mut arrivals, mut direct) = (Vec::new(), Vec::new());
    let mut pending = vec![DVec3::ZERO; nodes.len()];
    for root in (0..nodes.len()).filter(|&n| nodes.parent[n] == NONE) {
        let mut stack: Vec<(usize, Pushed)> = vec![(root, Pushed::default())];
        while let Some((n, down)) = stack.pop() {
            arrivals.truncate(down.hi);
            let (own_uniform, _) = gather_into(nodes, links, scales, n, &unit, None, &mut arrivals, &mut direct);
            for (m, g) in direct.drain(..) {
                pending[m] += g;
            }
            let g = push_step(nodes, n, down, own_uniform, std::mem::take(&mut pending[n]), &arrivals);
            if nodes.is_leaf(n) {
                sums[n] = g.uniform.max_element();
            } else {
                stack.extend(nodes.children(n).rev().map(|c| (c, g)));
            }
        }
    }
    sums
}

/// The gain of a leaf of row sum `row_sum` and largest reflectance channel `reflectance`: 1 / R
/// where ρ·R ≥ 1, else 1 (see the module).
pub fn gain(row_sum: f64, reflectance: f64) -> f64 {
    if reflectance * row_sum >= 1.0 {
        1.0 / row_sum
    } else {
        1.0
    }
}

/// The gains of the leaves whose row breaks the bound, and the largest row sum.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct LeafGains {
    /// (leaf, g) for every leaf with g < 1, in node order.
    pub scaled: Vec<(u32, f32)>,
    /// The largest row sum over all leaves.
    pub max_row_sum: f64,
}

impl LeafGains {
    /// From the `row_sums` of `nodes`.
    pub fn new(nodes: &Nodes, sums: &[f64]) -> LeafGains {
        let scaled = (0..sums.len())
            .filter(|&n| nodes.is_leaf(n))
            .map(|n| (n as u32, gain(sums[n], nodes.reflectance[n].max_element() as f64)))
            .filter(|&(_, g)| g < 1.0)
            .map(|(n, g)| (n, g as f32))
            .collect();
        LeafGains { scaled, max_row_sum: sums.iter().copied().fold(0.0, f64::max) }
    }

    /// The gains as a per-node vector of `node_count` (1 where nothing is scaled).
    pub fn per_node(&self, node_count: usize) -> Vec<f32> {
        let mut g = vec![1.0f32; node_count];
        for &(n, gain) in &self.scaled {
            g[n as usize] = gain;
        }
        g
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_leaf_that_reflects_less_than_it_gathers_keeps_its_row() {
        assert_eq!(gain(0.0, 0.8), 1.0);
        assert_eq!(gain(1.0, 0.8), 1.0);
        // Beyond its hemisphere but still contracting: left as it is.
        assert_eq!(gain(1.2, 0.8), 1.0);
        assert_eq!(gain(400.0, 0.0), 1.0);
    }

    #[test]
    fn a_leaf_that_would_reflect_all_it_gathers_sees_exactly_its_hemisphere() {
        // ρ·R = 1.25: every source at B = 1 would bring G = 2.5; scaled, g·G = 1 and ρ·g·R = 0.5.
        assert!((2.5 * gain(2.5, 0.5) - 1.0).abs() < 1e-15);
        assert_eq!(gain(2.0, 0.5), 0.5);
    }
}
