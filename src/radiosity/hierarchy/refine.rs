//! Link refinement (Hanrahan, Salzman and Aupperle 1991; clusters as in Sillion 1995): a link whose
//! error `links::refinement_error` (W) exceeds `RefineSettings::allowed_error_w` is replaced by links from the children of its
//! larger end, subdividing an element 1→4 when needed, until the error is small, the ends reach the
//! minimum element area, or the memory budget is spent (then the coarser link is kept and the budget
//! flag raised, never an allocation beyond it).

use rayon::prelude::*;

use super::estimates::{estimate_links, EstimateHooks, EstimateKind, EstimateLog, Stopped};
use super::links::{
    link_error_power, near_form_factor, near_push_spread, refinement_error, source_variation_power, LinkRecord, Links,
    LINK_BYTES,
};
use super::nodes::{Nodes, NODE_BYTES};
use super::shards::estimate_shared;
use super::tree_path::{extend_paths, TreePath};
use super::visibility::VisibilityContext;

/// Settings of one refinement pass.
#[derive(Clone, Copy, Debug)]
pub struct RefineSettings {
    /// Largest error a link may keep per square metre of its receiver, W/m² (ε × the scene's mean
    /// emitted exitance); see `allowed_error_w`.
    pub threshold: f64,
    /// Receivers smaller than this area (m²) are judged by power: their allowed error is that of a
    /// receiver of this area.
    pub floor_area: f32,
    /// Elements are not split into children smaller than this area.
    pub min_element_area: f32,
    /// Bytes the nodes and links may take.
    pub budget_bytes: usize,
    /// Ē, the scene's mean emitted exitance (W/m²) that `threshold` is ε times.
    pub reference_exitance: f64,
    /// δ of `dark_receiver_share`: the least share of the allowed error a receiver darker than Ē
    /// keeps; 1 judges every receiver alike (the first pass, which knows no exitance but the
    /// emission).
    pub dark_receiver_floor: f64,
}

impl RefineSettings {
    /// The error (W) a link to a receiver of area `receiver_area` and exitance `receiver_exitance`
    /// (W/m², mean channel) may keep:
    ///
    /// ε_max = threshold · max(A_R, floor_area) · s(B_R),
    ///
    /// s the `dark_receiver_share`. Above the floor this is the exitance criterion ρ_R·B_S·ΔF ≤ ε·Ē
    /// (each receiver resolved to the same relative accuracy, which the furnace and per-surface
    /// agreement need); below it, a power criterion A_R·ρ_R·B_S·ΔF ≤ ε·Ē·A_floor, so that the many
    /// tiny input triangles of a tessellated object are served by their clusters' links and the link
    /// count does not grow with the triangle count. A dark link (B_S = 0 or ρ_R = 0) has error 0 and
    /// is never refined.
    pub fn allowed_error_w(&self, receiver_area: f32, receiver_exitance: f64) -> f64 {
        let share = dark_receiver_share(receiver_exitance, self.reference_exitance, self.dark_receiver_floor);
        self.threshold * receiver_area.max(self.floor_area) as f64 * share
    }
}

/// The share of the allowed error ε·Ē a receiver of exitance B_R keeps:
///
/// s = clamp(B_R / Ē, δ, 1),
///
/// Ē the scene's mean emitted exitance and δ = `floor` (1: every receiver alike). A receiver at
/// least as bright as Ē keeps the whole error; a darker one is held to the same error *relative to
/// its own exitance*, down to δ·ε·Ē. An absolute error ε·Ē is a large relative one where the light
/// is dim: in gap_room's second room, every path of which passes a door gap, the median exitance is
/// 0.34 W/m² against Ē = 5.2 W/m², so ε·Ē was 8% of it; the image showed bright concave edges and
/// streaks fanning from the gap. The pixel error a viewer sees, and the relMSE of the accuracy suite,
/// are relative (docs/accuracy.md, session 41).
pub fn dark_receiver_share(receiver_exitance: f64, reference_exitance: f64, floor: f64) -> f64 {
    if !(floor < 1.0) || !(reference_exitance > 0.0) {
        return 1.0;
    }
    (receiver_exitance / reference_exitance).clamp(floor, 1.0)
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
/// (the parent's spread times the child's share), which keeps the total error from growing. A near
/// link's measured deviation may exceed it (`links::estimate`).
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

/// Refines `records` (already estimated links) and the self-links of the clusters in `self_links`
/// (clusters whose contents interact among themselves), which become near records first. A link
/// whose `refinement_error` is above the threshold is split: a self-link into the links between all
/// pairs of its cluster's children (and their own self-links), any other link at one end
/// (`choose_split`). Links below it are kept, near ones with `links::near_form_factor`: dark links
/// are never refined, and receivers below the floor area are judged by power, which bounds the links
/// by the scene's power over the threshold rather than by its triangle count (Sillion 1995's lazy cluster linking).
///
/// Breadth-first: each round decides for all its links in parallel (`decide`, pure reads of `nodes`),
/// applies the decisions in link order (budget, subdivisions, new links), and then estimates the
/// kept links that still lack a form factor and the new links, in parallel and in a fixed order, so
/// the result is the same for any thread count.
///
/// Every estimate goes through `hooks.log` (`estimates`): taken from it while it lasts (a resumed
/// solve), else computed and appended, so the same log replays to the same links. Stops with the log
/// up to date when `hooks.stop` asks (polled between chunks of estimates).
pub fn refine_logged(
    nodes: &mut Nodes,
    ctx: &VisibilityContext,
    records: Vec<LinkRecord>,
    self_links: Vec<u32>,
    settings: &RefineSettings,
    hooks: &mut EstimateHooks,
    on_round: &mut dyn FnMut(u32, usize, usize),
) -> Result<RefineOutcome, Stopped> {
    let mut work = records;
    for c in self_links {
        if nodes.is_cluster[c as usize] {
            work.push(LinkRecord { receiver: c, source: c, form_factor: f32::NAN, spread: 1.0 });
        }
    }
    let mut out = RefineOutcome { error_before_w: total_error(nodes, &work), ..Default::default() };
    let mut kept: Vec<LinkRecord> = Vec::with_capacity(work.len());
    // A shard's or merge's tree paths of the nodes (the keys of shared estimates), kept up to date.
    let mut paths: Vec<Option<TreePath>> = Vec::new();
    loop {
        let mut next: Vec<Pending> = Vec::new();
        // Pieces made by this round's splits get their texture means after the round (in parallel).
        let first_piece = nodes.len();
        // The links of this round still to be decided count against the budget too.
        let work_len = work.len();
        // Every decision reads only what the round started with (see `decide`), so they are made in
        // parallel and applied below in link order.
        let decisions: Vec<Decision> = {
            let nodes: &Nodes = nodes;
            work.par_iter().with_min_len(1024).map(|link| decide(nodes, link, settings)).collect()
        };
        // Kept near links still without a form factor (positions in `kept`), estimated after the loop.
        let mut unestimated: Vec<usize> = Vec::new();
        let mut keep = |link: LinkRecord, kept: &mut Vec<LinkRecord>| {
            if link.form_factor.is_nan() {
                unestimated.push(kept.len());
            }
            kept.push(link);
        };
        for (link, decision) in work.drain(..).zip(decisions) {
            let r = link.receiver as usize;
            let side = match decision {
                Decision::Keep => {
                    keep(link, &mut kept);
                    continue;
                }
                Decision::Split(side) => side,
                Decision::Expand => {
                    // A cluster's self-link: the pairs of its children, each child's own self-link included.
                    let children = nodes.children(r);
                    let bytes = budget_bytes(nodes.len(), kept.len() + next.len() + children.len().pow(2) + work_len);
                    if bytes > settings.budget_bytes {
                        out.budget_exceeded = true;
                        keep(link, &mut kept);
                        continue;
                    }
                    out.peak_bytes = out.peak_bytes.max(bytes);
                    let parent_area = nodes.area[r] as f64;
                    for i in children.clone() {
                        for j in children.clone() {
                            if i == j && !nodes.is_cluster[i] {
                                continue; // a flat element does not see itself
                            }
                            let share = (link.spread as f64 * nodes.area[j] as f64 / parent_area) as f32;
                            next.push(Pending { receiver: i as u32, source: j as u32, spread_cap: share });
                        }
                    }
                    continue;
                }
            };
            let split = match side {
                Split::Receiver => r,
                Split::Source => link.source as usize,
            };
            let new_nodes = if nodes.is_leaf(split) { 4 } else { 0 };
            let child_links = if nodes.is_leaf(split) { 4 } else { nodes.children(split).len() };
            let bytes = budget_bytes(nodes.len() + new_nodes, kept.len() + next.len() + child_links + work_len);
            if bytes > settings.budget_bytes {
                out.budget_exceeded = true;
                keep(link, &mut kept);
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
        estimate_kept_near(nodes, ctx, &mut kept, &unestimated, hooks)?;
        nodes.assign_texture_means(first_piece);
        if let Some(shared) = hooks.shared {
            // A shard of pass one refines only its own receivers' links (`shards`).
            next.retain(|p| shared.refines_receiver(nodes, p.receiver as usize));
        }
        if next.is_empty() {
            break;
        }
        out.rounds += 1;
        on_round(out.rounds, kept.len(), nodes.len());
        out.estimated += next.len() as u64;
        if hooks.shared.is_some() {
            extend_paths(nodes, &mut paths);
        }
        let estimates: Vec<Option<(f32, f32)>> = {
            let nodes: &Nodes = nodes;
            let pairs: Vec<(u32, u32)> = next.iter().map(|p| (p.receiver, p.source)).collect();
            let shared = hooks.shared;
            let compute = |i: usize| {
                let p = &next[i];
                let (r, s) = (p.receiver as usize, p.source as usize);
                let threshold_w = settings.allowed_error_w(nodes.area[r], nodes.exitance_mean[r]);
                estimate_shared(shared, &paths, nodes, ctx, r, s, p.spread_cap, threshold_w, settings.min_element_area)
            };
            estimate_links(EstimateKind::Link, &pairs, &compute, hooks)?
        };
        if let Some(shared) = hooks.shared {
            shared.record(nodes, &paths, next.iter().map(|p| (p.receiver, p.source, p.spread_cap)), &estimates);
        }
        work = next
            .iter()
            .zip(estimates)
            .filter_map(|(p, e)| {
                e.map(|(f, spread)| LinkRecord { receiver: p.receiver, source: p.source, form_factor: f, spread })
            })
            .collect();
    }
    out.error_after_w = total_error(nodes, &kept);
    out.peak_bytes = out.peak_bytes.max(budget_bytes(nodes.len(), kept.len()));
    out.links = Links::from_records(nodes.len(), kept);
    Ok(out)
}

/// `refine_logged` that keeps no log and is never stopped.
pub fn refine(
    nodes: &mut Nodes,
    ctx: &VisibilityContext,
    records: Vec<LinkRecord>,
    self_links: Vec<u32>,
    settings: &RefineSettings,
    on_round: &mut dyn FnMut(u32, usize, usize),
) -> RefineOutcome {
    let mut log = EstimateLog::default();
    let mut hooks = EstimateHooks { log: &mut log, stop: &|| false, after_chunk: &mut |_, _| {}, shared: None };
    match refine_logged(nodes, ctx, records, self_links, settings, &mut hooks, on_round) {
        Ok(outcome) => outcome,
        Err(Stopped) => unreachable!("never stopped"),
    }
}

/// What refinement does with one link this round.
enum Decision {
    Keep,
    /// Replace a cluster's self-link by the links between its children.
    Expand,
    Split(Split),
}

/// The decision for `link` from the state the round started with: kept while its `refinement_error`
/// is within the allowed error, else expanded (a self-link) or split at the end `choose_split` picks,
/// kept when nothing can be split. A pure read of `nodes`: the splits made earlier in the same round
/// only add children, which inherit their parent's exitance, to leaf elements, and neither that
/// (source variation 0, like a leaf's) nor the subdivision itself (made only where `choose_split`
/// allowed it) changes any decision, so deciding all links of a round at once and in parallel gives
/// the decisions of a loop that decides one link at a time. Only the memory budget depends on the order; it is checked
/// when the decisions are applied, in link order.
fn decide(nodes: &Nodes, link: &LinkRecord, settings: &RefineSettings) -> Decision {
    let (r, s) = (link.receiver as usize, link.source as usize);
    if !(refinement_error(nodes, link) > settings.allowed_error_w(nodes.area[r], nodes.exitance_mean[r])) {
        return Decision::Keep;
    }
    if r == s {
        return Decision::Expand;
    }
    let source_varies_most =
        source_variation_power(nodes, r, s, link.form_factor) > link_error_power(nodes, r, s, link.spread);
    match choose_split(nodes, r, s, settings.min_element_area, source_varies_most) {
        Some(side) => Decision::Split(side),
        None => Decision::Keep,
    }
}

/// Gives the kept near links at positions `unestimated` of `kept` (kept without a form factor: they
/// were expected to split, but cannot or may not) their form factor, `links::near_form_factor` plus
/// `near_push_spread`, in parallel and in order through the log like every estimate, with the nodes
/// as the round left them; drops those whose ends cannot exchange light.
fn estimate_kept_near(
    nodes: &Nodes,
    ctx: &VisibilityContext,
    kept: &mut Vec<LinkRecord>,
    unestimated: &[usize],
    hooks: &mut EstimateHooks,
) -> Result<(), Stopped> {
    if unestimated.is_empty() {
        return Ok(());
    }
    let pairs: Vec<(u32, u32)> = unestimated.iter().map(|&k| (kept[k].receiver, kept[k].source)).collect();
    let compute = |i: usize| {
        let (r, s) = (pairs[i].0 as usize, pairs[i].1 as usize);
        near_form_factor(nodes, ctx, r, s).map(|f| (f, near_push_spread(nodes, ctx, r, s, f)))
    };
    let values = estimate_links(EstimateKind::KeptNear, &pairs, &compute, hooks)?;
    let mut dropped = false;
    for (&k, value) in unestimated.iter().zip(values) {
        match value {
            Some((f, push)) => {
                kept[k].form_factor = f;
                kept[k].spread += push;
            }
            None => dropped = true, // stays NaN: every other kept link has its form factor by now
        }
    }
    if dropped {
        kept.retain(|l| !l.form_factor.is_nan());
    }
    Ok(())
}

/// Bytes `nodes` nodes and `links` link records take: each node also costs its row offset in `Links`.
fn budget_bytes(nodes: usize, links: usize) -> usize {
    nodes * (NODE_BYTES + std::mem::size_of::<u32>()) + links * LINK_BYTES
}

/// Σ over links of `link_error_power` (watts): the global error estimate.
pub fn total_error(nodes: &Nodes, records: &[LinkRecord]) -> f64 {
    records.iter().map(|l| link_error_power(nodes, l.receiver as usize, l.source as usize, l.spread)).sum()
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
        } else if source_has_children && source_variation_power(nodes, r, s, 1.0) > 0.0 {
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
