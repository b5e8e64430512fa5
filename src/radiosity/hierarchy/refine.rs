//! Link refinement (Hanrahan, Salzman and Aupperle 1991; clusters as in Sillion 1995): a link whose
//! error `links::link_error` exceeds the threshold is replaced by links from the children of its
//! larger end, subdividing an element 1→4 when needed, until the error is small, the ends reach the
//! minimum element area, or the memory budget is spent (then the coarser link is kept and the budget
//! flag raised, never an allocation beyond it).

use rayon::prelude::*;

use super::links::{admissible, estimate, link_error, link_error_power, LinkRecord, Links, LINK_BYTES};
use super::nodes::{Nodes, NODE_BYTES};
use super::visibility::VisibilityContext;

/// Settings of one refinement pass.
#[derive(Clone, Copy, Debug)]
pub struct RefineSettings {
    /// Largest error a link may keep, in exitance units W/m² (ε × the brightest emitted exitance).
    pub threshold: f64,
    /// Elements are not split into children smaller than this area.
    pub min_element_area: f32,
    /// Bytes the nodes and links may take.
    pub budget_bytes: usize,
}

/// What a refinement pass produced.
#[derive(Clone, Debug, Default)]
pub struct RefineOutcome {
    pub links: Links,
    /// Σ link_error over the links before and after (watts, at the exitance the pass saw).
    pub error_before_w: f64,
    pub error_after_w: f64,
    /// Breadth-first rounds of the pass.
    pub rounds: u32,
    /// A refinement was refused because the budget would have been exceeded.
    pub budget_exceeded: bool,
    /// Largest nodes + links bytes during the pass.
    pub peak_bytes: usize,
    /// Links estimated (each one traces `rays` rays).
    pub estimated: u64,
}

/// A link to be estimated: its ends, and the cap on its error spread inherited from its parent link
/// (the parent's spread times the child's share), which keeps the total error from growing.
#[derive(Clone, Copy)]
struct Pending {
    receiver: u32,
    source: u32,
    spread_cap: f32,
}

/// Which end of a link to split.
enum Split {
    Receiver,
    Source,
}

/// Refines `records` (already estimated links) and expands the self-links of `self_links` (clusters
/// whose contents interact among themselves; a self-link is always split into the links between all
/// pairs of its children). Breadth-first: each round estimates its new links in parallel (pure reads
/// of `nodes`, in a fixed order) and then decides, serially and in order, which to split, so the result
/// is the same for any thread count.
pub fn refine(
    nodes: &mut Nodes,
    ctx: &VisibilityContext,
    records: Vec<LinkRecord>,
    self_links: Vec<u32>,
    settings: &RefineSettings,
    on_round: &mut dyn FnMut(u32, usize, usize),
) -> RefineOutcome {
    let mut out = RefineOutcome { error_before_w: total_error(nodes, &records), ..Default::default() };
    let mut kept: Vec<LinkRecord> = Vec::with_capacity(records.len());
    let mut work = records;
    let mut pending_self = self_links;
    loop {
        let mut next: Vec<Pending> = Vec::new();
        let mut next_self = Vec::new();
        for c in pending_self.drain(..) {
            let children = nodes.children(c as usize);
            for i in children.clone() {
                for j in children.clone() {
                    if i == j {
                        if nodes.is_cluster[i] {
                            next_self.push(i as u32);
                        }
                        // A flat element does not see itself.
                    } else {
                        next.push(Pending { receiver: i as u32, source: j as u32, spread_cap: f32::INFINITY });
                    }
                }
            }
        }
        // The links of this round still to be decided count against the budget too.
        let work_len = work.len();
        for link in work.drain(..) {
            let (r, s) = (link.receiver as usize, link.source as usize);
            let geometric = link_error(nodes, r, s, link.spread);
            let source_variation = source_variation_error(nodes, r, s, link.form_factor);
            let must_split = !admissible(nodes, r, s);
            if !must_split && !(geometric + source_variation > settings.threshold) {
                kept.push(link);
                continue;
            }
            let Some(side) = choose_split(nodes, r, s, settings.min_element_area, source_variation > geometric) else {
                kept.push(link);
                continue;
            };
            let split = match side {
                Split::Receiver => r,
                Split::Source => s,
            };
            let new_nodes = if nodes.is_leaf(split) { 4 } else { 0 };
            let child_links = if nodes.is_leaf(split) { 4 } else { nodes.children(split).len() };
            let bytes = (nodes.len() + new_nodes) * NODE_BYTES
                + (kept.len() + next.len() + child_links + work_len) * LINK_BYTES;
            if bytes > settings.budget_bytes {
                out.budget_exceeded = true;
                kept.push(link);
                continue;
            }
            out.peak_bytes = out.peak_bytes.max(bytes);
            if nodes.is_leaf(split) {
                nodes.subdivide(split);
            }
            let parent_area = nodes.area[split] as f64;
            for c in nodes.children(split) {
                match side {
                    Split::Receiver => {
                        next.push(Pending { receiver: c as u32, source: link.source, spread_cap: link.spread })
                    }
                    Split::Source => next.push(Pending {
                        receiver: link.receiver,
                        source: c as u32,
                        spread_cap: (link.spread as f64 * nodes.area[c] as f64 / parent_area) as f32,
                    }),
                }
            }
        }
        if next.is_empty() && next_self.is_empty() {
            break;
        }
        out.rounds += 1;
        on_round(out.rounds, kept.len(), nodes.len());
        out.estimated += next.len() as u64;
        let estimates: Vec<Option<(f32, f32)>> = {
            let nodes: &Nodes = nodes;
            next.par_iter().map(|p| estimate(nodes, ctx, p.receiver as usize, p.source as usize)).collect()
        };
        work = next
            .iter()
            .zip(estimates)
            .filter_map(|(p, e)| {
                e.map(|(f, spread)| LinkRecord {
                    receiver: p.receiver,
                    source: p.source,
                    form_factor: f,
                    spread: spread.min(p.spread_cap),
                })
            })
            .collect();
        pending_self = next_self;
    }
    out.error_after_w = total_error(nodes, &kept);
    out.peak_bytes = out.peak_bytes.max(nodes.len() * NODE_BYTES + kept.len() * LINK_BYTES);
    out.links = Links::from_records(nodes.len(), kept);
    out
}

/// Σ over links of `link_error_power` (watts): the global error estimate.
pub fn total_error(nodes: &Nodes, records: &[LinkRecord]) -> f64 {
    records.iter().map(|l| link_error_power(nodes, l.receiver as usize, l.source as usize, l.spread)).sum()
}

/// The part of a link's error that comes from the source's exitance varying over it (W/m²):
/// ρ_R · F_RS · max_c |B_c − B_S| over the source's children (0 for a leaf source, whose exitance is
/// one value). Splitting the source removes it.
pub fn source_variation_error(nodes: &Nodes, receiver: usize, source: usize, form_factor: f32) -> f64 {
    let b = nodes.exitance_mean[source];
    let spread = nodes.children(source).map(|c| (nodes.exitance_mean[c] - b).abs()).fold(0.0, f64::max);
    nodes.reflectance_max[receiver] as f64 * form_factor as f64 * spread
}

/// Which end to split. Element ← element links: the source when its exitance variation dominates the
/// error, otherwise the receiver (the estimator integrates the source exactly, so splitting the source
/// cannot reduce the receiver-side quadrature error); the other end as a fallback only for a varying
/// source. Links with a cluster end (Sillion 1995; Hanrahan et al. 1991): the end with the larger area
/// (a cluster's is its contents'), else the other. A leaf element splits only if its quarters keep at
/// least `min_area`; `None` when nothing useful can be split.
fn choose_split(nodes: &Nodes, r: usize, s: usize, min_area: f32, source_varies_most: bool) -> Option<Split> {
    let can = |n: usize| nodes.is_cluster[n] || !nodes.is_leaf(n) || nodes.area[n] * 0.25 >= min_area;
    if !nodes.is_cluster[r] && !nodes.is_cluster[s] {
        let source_has_children = !nodes.is_leaf(s);
        return if source_varies_most && source_has_children {
            Some(Split::Source)
        } else if can(r) {
            Some(Split::Receiver)
        } else if source_has_children && source_variation_error(nodes, r, s, 1.0) > 0.0 {
            Some(Split::Source)
        } else {
            None
        };
    }
    let (first, second) = if nodes.area[r] >= nodes.area[s] {
        (Split::Receiver, Split::Source)
    } else {
        (Split::Source, Split::Receiver)
    };
    let node_of = |side: &Split| match side {
        Split::Receiver => r,
        Split::Source => s,
    };
    if can(node_of(&first)) {
        Some(first)
    } else if can(node_of(&second)) {
        Some(second)
    } else {
        None
    }
}
