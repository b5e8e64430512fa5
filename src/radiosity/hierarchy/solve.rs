//! Gauss-Seidel with overrelaxation over the hierarchy: one sweep walks the tree depth-first; each
//! node gathers over its links when it is reached (reading exitances in place, so later receivers see
//! this sweep's values), pushes its irradiance to its children, and pulls their exitance back up as
//! soon as they are done. Jacobi, for comparison, walks the same way but gathers from the exitance
//! the previous sweep left (`SweepOrder`).

use super::gather::{gather_into, leaf_exitance, pulled, push_step, Arrival, ArrivalScales, Pushed};
use super::links::Links;
use super::lobes::Lobes;
use super::nodes::{mean_channel, Nodes};
use glam::DVec3;

/// What a sweep changed: the largest change of a leaf's exitance (any channel) and the largest leaf
/// exitance after it (W/m²).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct SweepChange {
    pub max_change: f64,
    pub max_exitance: f64,
}

/// Which exitance a sweep's receivers gather.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SweepOrder {
    /// In place, with overrelaxation: later receivers see this sweep's values.
    #[default]
    GaussSeidel,
    /// From the values the previous sweep left (ω is not used): after k sweeps from B = S every leaf
    /// holds exactly the light of k bounces over the links, B^{k+1} = S + ρ·g·G(B^k), the truncated
    /// von Neumann series of the matrix path's Jacobi.
    Jacobi,
}

impl SweepOrder {
    /// The scene's `solver` value for this order.
    pub fn name(self) -> &'static str {
        match self {
            SweepOrder::GaussSeidel => "gauss-seidel",
            SweepOrder::Jacobi => "jacobi",
        }
    }
}

/// One sweep over the tree below `root` in `order`, with relaxation factor ω for Gauss-Seidel:
///
/// G_n = G_parent + Σ_{S linked to n} F_nS B_S (a cluster's links as arrivals that each element below
/// takes by its own cosine, see `gather::Irradiance`);  leaves: B ← B + ω(S + ρ·g·G − B), g the leaf's
/// gain (1, or 1/R where its row sum R has ρ·R ≥ 1 once the rows are bounded: `row_sums`,
/// `ArrivalScales::leaf_gain`), S = E + ρ·E_c
/// the emission and reflected caustic light (`Nodes::source_exitance`);
/// inner nodes: B = Σ_c A_c B_c / Σ_c A_c (after their children).
///
/// `scales` are the links' `ArrivalScales`; `lobes` the clusters' directional exitance (`Lobes`),
/// pulled with the exitance, which links from clusters to ends outside them send. Serial and in a
/// fixed order, so the result does not depend on threads. Updates `exitance`, `exitance_mean` and
/// `gathered` (own links only) of every node.
pub fn sweep(
    nodes: &mut Nodes,
    links: &Links,
    scales: &ArrivalScales,
    lobes: &mut Lobes,
    root: usize,
    order: SweepOrder,
    relaxation: f64,
) -> SweepChange {
    let mut change = SweepChange::default();
    // Jacobi gathers from a copy of the exitance and lobes as the sweep found them.
    let previous = (order == SweepOrder::Jacobi).then(|| (nodes.exitance.clone(), lobes.clone()));
    let relaxation = if order == SweepOrder::Jacobi { 1.0 } else { relaxation };
    // The pending arrivals of the current path (`gather::Pushed` holds each node's range of it).
    let mut arrivals: Vec<Arrival> = Vec::new();
    // Irradiance member shares put on elements not yet reached (`ArrivalScales`).
    let mut direct: Vec<(usize, DVec3)> = Vec::new();
    let mut pending = vec![DVec3::ZERO; nodes.len()];
    // Explicit stack: (node, what its parent pushed, children visited?).
    let mut stack: Vec<(usize, Pushed, bool)> = vec![(root, Pushed::default(), false)];
    while let Some((n, down, expanded)) = stack.pop() {
        if expanded {
            let b = pulled(nodes, n, &nodes.exitance);
            nodes.exitance[n] = b;
            nodes.exitance_mean[n] = mean_channel(nodes.exitance[n]);
            lobes.pull(nodes, n);
            continue;
        }
        arrivals.truncate(down.hi);
        let (sent, sent_lobes) = match &previous {
            Some((exitance, lobes)) => (exitance.as_slice(), lobes),
            None => (nodes.exitance.as_slice(), &*lobes),
        };
        let (own_uniform, own_mean) =
            gather_into(nodes, links, scales, n, sent, Some(sent_lobes), &mut arrivals, &mut direct);
        nodes.gathered[n] = own_mean;
        for (m, g) in direct.drain(..) {
            pending[m] += g;
        }
        let g = push_step(nodes, n, down, own_uniform, std::mem::take(&mut pending[n]), &arrivals);
        if nodes.is_leaf(n) {
            let old = nodes.exitance[n];
            let gathered = scales.corrected(n, g.uniform * scales.leaf_gain(n));
            let new =
                leaf_exitance(nodes.source_exitance(n), nodes.reflectance[n].as_dvec3(), gathered, old, relaxation);
            nodes.exitance[n] = new;
            nodes.exitance_mean[n] = mean_channel(new);
            change.max_change = change.max_change.max((new - old).abs().max_element());
            change.max_exitance = change.max_exitance.max(new.max_element());
        } else {
            stack.push((n, down, true));
            for c in nodes.children(n).rev() {
                stack.push((c, g, false));
            }
        }
    }
    change
}

/// What each leaf below `root` gathers over its links (before its gain) with every node sending
/// `exitance`: the irradiance G_i = Σ_j F_ij B_j a sweep would push to it (`sweep`'s gather and push,
/// `lobes` the clusters' directional exitance or none), without changing anything. Zero for inner
/// nodes. Serial and in a fixed order.
pub fn leaf_irradiance(
    nodes: &Nodes,
    links: &Links,
    scales: &ArrivalScales,
    exitance: &[DVec3],
    lobes: Option<&Lobes>,
    root: usize,
) -> Vec<DVec3> {
    let mut out = vec![DVec3::ZERO; nodes.len()];
    let (mut arrivals, mut direct) = (Vec::new(), Vec::new());
    let mut pending = vec![DVec3::ZERO; nodes.len()];
    let mut stack: Vec<(usize, Pushed)> = vec![(root, Pushed::default())];
    while let Some((n, down)) = stack.pop() {
        arrivals.truncate(down.hi);
        let (own_uniform, _) = gather_into(nodes, links, scales, n, exitance, lobes, &mut arrivals, &mut direct);
        for (m, g) in direct.drain(..) {
            pending[m] += g;
        }
        let g = push_step(nodes, n, down, own_uniform, std::mem::take(&mut pending[n]), &arrivals);
        if nodes.is_leaf(n) {
            out[n] = g.uniform;
        } else {
            stack.extend(nodes.children(n).rev().map(|c| (c, g)));
        }
    }
    out
}

/// Sweeps until the largest leaf change is below `tolerance` × the largest leaf exitance, or
/// `max_sweeps` are done. Returns the sweeps made and whether it converged.
pub fn solve(
    nodes: &mut Nodes,
    links: &Links,
    root: usize,
    relaxation: f64,
    tolerance: f64,
    max_sweeps: u32,
    on_sweep: &mut dyn FnMut(u32, SweepChange),
) -> (u32, bool) {
    let mut scales = ArrivalScales::new(nodes, links);
    let order = SweepOrder::GaussSeidel;
    solve_until(nodes, links, &mut scales, root, order, relaxation, tolerance, max_sweeps, on_sweep, &|| false)
        .expect("never stopped")
}

/// `solve` in `order` over the links' `scales` (`ArrivalScales`, which the caller keeps from one
/// refinement pass to the next) that looks at `stop` before each sweep: `None` when it asked (the
/// exitance is then that of the last finished sweep).
///
/// A solve whose largest leaf exitance passes `exitance_limit` is diverging (some leaves' links
/// overshoot their hemisphere so far that ρ·R ≥ 1): its rows are then bounded
/// (`ArrivalScales::bound_rows`, `row_sums`) and the sweeps start again from the emission.
#[allow(clippy::too_many_arguments)]
pub fn solve_until(
    nodes: &mut Nodes,
    links: &Links,
    scales: &mut ArrivalScales,
    root: usize,
    order: SweepOrder,
    relaxation: f64,
    tolerance: f64,
    max_sweeps: u32,
    on_sweep: &mut dyn FnMut(u32, SweepChange),
    stop: &dyn Fn() -> bool,
) -> Option<(u32, bool)> {
    let limit = exitance_limit(nodes, root);
    let mut lobes = Lobes::new(nodes, links, root);
    for k in 1..=max_sweeps {
        if stop() {
            return None;
        }
        let c = sweep(nodes, links, scales, &mut lobes, root, order, relaxation);
        on_sweep(k, c);
        if c.max_exitance > limit && !scales.rows_bounded() {
            scales.bound_rows(nodes, links);
            reset_to_emission(nodes, root);
            lobes = Lobes::new(nodes, links, root);
            continue;
        }
        if c.max_change <= tolerance * c.max_exitance {
            return Some((k, true));
        }
    }
    Some((max_sweeps, false))
}

/// Twice the largest exitance a leaf below `root` can reach while every row keeps its hemisphere
/// (R ≤ 1): B ≤ S_max / (1 − ρ_max), S the leaves' emission and reflected caustic light
/// (`Nodes::source_exitance`) and ρ_max the largest reflectance channel (at most 0.99 here). Above
/// it the sweeps are diverging, not converging slowly.
pub fn exitance_limit(nodes: &Nodes, root: usize) -> f64 {
    let (mut source, mut reflectance) = (0.0f64, 0.0f64);
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        if nodes.is_leaf(n) {
            source = source.max(nodes.source_exitance(n).max_element());
            reflectance = reflectance.max(nodes.reflectance[n].max_element() as f64);
        } else {
            stack.extend(nodes.children(n));
        }
    }
    2.0 * source / (1.0 - reflectance.min(0.99))
}

/// Sets every leaf to its emission and reflected caustic light and pulls the means up: the exitance
/// that the first refinement pass measures link errors with (B = S = E + ρ·E_c before any bounce over
/// links).
pub fn reset_to_emission(nodes: &mut Nodes, root: usize) {
    set_leaves(nodes, root, |nodes, n| nodes.source_exitance(n));
}

/// Sets every leaf below `root` to `leaf(nodes, n)` and pulls the open-area-weighted means up
/// (`gather::pulled`).
pub fn set_leaves(nodes: &mut Nodes, root: usize, leaf: impl Fn(&Nodes, usize) -> DVec3) {
    let mut order = Vec::new();
    let mut stack = vec![root];
    while let Some(n) = stack.pop() {
        order.push(n);
        stack.extend(nodes.children(n));
    }
    for &n in order.iter().rev() {
        let b = if nodes.is_leaf(n) { leaf(nodes, n) } else { pulled(nodes, n, &nodes.exitance) };
        nodes.exitance[n] = b;
        nodes.exitance_mean[n] = mean_channel(b);
    }
}
