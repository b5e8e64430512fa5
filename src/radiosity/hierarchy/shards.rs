//! The hierarchy's refinement split over machines (`solve --shard K/N`, `--merge`), one pass per
//! round of shards: which receivers a shard refines, and the link estimates shards hand to the next
//! round and the merge, keyed by the tree paths of the link's ends (`tree_path`) so that they do not
//! depend on the order in which nodes were subdivided.
//!
//! Refinement is a forest below the root's self-link: a link's children keep its receiver or take a
//! child of it, so a shard that drops the new links of receivers it does not own refines its own
//! receivers' links exactly as far as the whole solve, as long as the decisions do not look beyond the
//! link. They do not (within a pass, the exitance is the one every shard solved alike, and pieces
//! made in it inherit their parent's), except near links, whose form
//! factor integrates over the leaves found below their ends when they are estimated, and the memory
//! budget. So a shard records only *pure* estimates: links that are not near (element ← element, far
//! links with a cluster end), a function of the two paths, the parent's spread cap and the scene. The
//! merge is the whole solve, taking each pure estimate from the shards when they hold it and computing
//! everything else (near links, later passes, what the budget or a near link made differ): its bytes
//! are those of a single-machine solve by construction.

use std::collections::HashMap;
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};

use super::links::{estimate, is_near};
use super::nodes::Nodes;
use super::tree_path::{tree_path, TreePath};
use super::visibility::VisibilityContext;

/// A link estimate's identity: both ends' paths and the spread cap it inherited (`links::estimate`
/// caps its spread there). Everything else it depends on is fixed by the scene and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EstimateKey {
    pub receiver: TreePath,
    pub source: TreePath,
    pub spread_cap_bits: u32,
}

/// A pure estimate and its value ((form factor, spread), or `None`: the link was dropped).
pub type SharedEstimate = (EstimateKey, Option<(f32, f32)>);

/// Receivers grouped for sharding: a shard of N aims at about this many groups per shard, so that
/// assigning whole groups keeps the shards balanced.
pub const GROUPS_PER_SHARD: usize = 16;

/// Build nodes above the groups: their links are refined by every shard.
const SHARED: u32 = u32::MAX;

/// What a sharded solve shares: a shard's receivers and the pure estimates it records, and the
/// estimates a shard or merge takes from the parts of earlier rounds.
///
/// Rounds: the passes after the first re-refine with the exitance solved over every link, so shard
/// K of N refines one pass, `shard_pass`: it runs the passes before it whole (taking their pure
/// estimates from the earlier rounds' parts, computing the rest and sweeping), then refines that
/// pass for its own receivers and stops. Round p's shards need the parts of rounds 1..p; the merge
/// needs all of them.
#[derive(Debug, Default)]
pub struct SharedEstimates {
    /// (K, N) for shard K of N; `None` for a merge.
    shard: Option<(u32, u32)>,
    /// The pass a shard refines for its receivers (1-based).
    shard_pass: u32,
    /// The pass the solve is in (`begin_pass`).
    pass: AtomicU32,
    /// Per build node (`Nodes` before refinement): the shard that refines the links it receives, or
    /// `SHARED`. Set by `assign_receivers`.
    owners: OnceLock<Vec<u32>>,
    /// A merge's estimates from the parts.
    known: HashMap<EstimateKey, Option<(f32, f32)>>,
    /// A shard's pure estimates so far.
    recorded: Mutex<Vec<SharedEstimate>>,
    /// Estimates a merge took from `known`.
    hits: AtomicU64,
}

impl SharedEstimates {
    /// Shard `index` of `count` of pass `pass`: refines its receivers' links in that pass and records
    /// them, taking the estimates of the earlier passes' parts (`earlier`) where they fit.
    pub fn for_shard(index: u32, count: u32, pass: u32, earlier: impl IntoIterator<Item = SharedEstimate>) -> Self {
        SharedEstimates { shard: Some((index, count)), shard_pass: pass, ..SharedEstimates::for_merge(earlier) }
    }

    /// A merge: the whole solve, taking the estimates of `parts` where they fit.
    pub fn for_merge(parts: impl IntoIterator<Item = SharedEstimate>) -> Self {
        let mut known = HashMap::new();
        for (key, value) in parts {
            known.entry(key).or_insert(value);
        }
        SharedEstimates { known, ..Default::default() }
    }

    /// The pass a shard refines for its receivers (and stops after); `None` for a merge.
    pub fn shard_pass(&self) -> Option<u32> {
        self.shard.map(|_| self.shard_pass)
    }

    /// The solve enters refinement pass `pass` (1-based).
    pub fn begin_pass(&self, pass: u32) {
        self.pass.store(pass, Ordering::Relaxed);
    }

    /// Whether the solve is in the pass this shard refines for its receivers.
    fn in_shard_pass(&self) -> bool {
        self.shard.is_some() && self.pass.load(Ordering::Relaxed) == self.shard_pass
    }

    /// Estimates taken from the parts so far.
    pub fn hits(&self) -> u64 {
        self.hits.load(Ordering::Relaxed)
    }

    /// Estimates the parts hold.
    pub fn known_len(&self) -> usize {
        self.known.len()
    }

    /// A shard's recorded estimates, sorted by key and without repeats.
    pub fn take_recorded(&self) -> Vec<SharedEstimate> {
        let mut recorded = std::mem::take(&mut *self.recorded.lock().unwrap_or_else(|e| e.into_inner()));
        recorded.sort_by_key(|e| e.0);
        recorded.dedup_by_key(|e| e.0);
        recorded
    }

    /// Groups the receivers of the built tree (`nodes` before any refinement, root `root`) and gives
    /// each group to a shard. A group is the subtree of the topmost node holding at most
    /// ⌈T / (`GROUPS_PER_SHARD`·N)⌉ of the T input triangles; the nodes above are shared. Groups go
    /// to shards largest first, each to the shard with the least so far (longest processing time
    /// first), weighed by the power they can reflect (area × largest reflectance channel, plus a
    /// thousandth of the mean so black groups spread too). Only a shard needs this.
    pub fn assign_receivers(&self, nodes: &Nodes, root: usize) {
        let Some((_, count)) = self.shard else { return };
        let n = nodes.len();
        let mut inputs = vec![0usize; n];
        for i in (0..n).rev() {
            inputs[i] = if nodes.is_cluster[i] { nodes.children(i).map(|c| inputs[c]).sum() } else { 1 };
        }
        let limit = inputs[root].div_ceil(GROUPS_PER_SHARD * count as usize).max(1);
        let mut owners = vec![SHARED; n];
        let mut groups = Vec::new();
        let mut stack = vec![root];
        while let Some(at) = stack.pop() {
            if inputs[at] <= limit || !nodes.is_cluster[at] {
                groups.push(at);
            } else {
                stack.extend(nodes.children(at));
            }
        }
        let weight = |g: usize| nodes.area[g] as f64 * nodes.reflectance_max[g] as f64;
        let floor = groups.iter().map(|&g| weight(g)).sum::<f64>() / groups.len().max(1) as f64 * 1e-3;
        groups.sort_by(|&a, &b| weight(b).total_cmp(&weight(a)).then(a.cmp(&b)));
        let mut load = vec![0.0f64; count as usize];
        for g in groups {
            let shard = (0..load.len()).min_by(|&a, &b| load[a].total_cmp(&load[b]).then(a.cmp(&b))).unwrap_or(0);
            load[shard] += weight(g) + floor;
            let mut stack = vec![g];
            while let Some(at) = stack.pop() {
                owners[at] = shard as u32;
                stack.extend(nodes.children(at));
            }
        }
        let _ = self.owners.set(owners);
    }

    /// Whether this run refines the links that `receiver` receives: always for a merge and outside a
    /// shard's pass; in it, when the build node the receiver lies in is shared or the shard's.
    pub fn refines_receiver(&self, nodes: &Nodes, receiver: usize) -> bool {
        let (Some((index, _)), Some(owners)) = (self.shard, self.owners.get()) else { return true };
        if !self.in_shard_pass() {
            return true;
        }
        let mut at = receiver;
        while at >= owners.len() {
            at = nodes.parent[at] as usize;
        }
        owners[at] == SHARED || owners[at] == index
    }

    /// In its pass, a shard records the pure estimates among `links` (receiver, source, spread cap)
    /// with their `values`.
    pub fn record(&self, nodes: &Nodes, links: impl Iterator<Item = (u32, u32, f32)>, values: &[Option<(f32, f32)>]) {
        if !self.in_shard_pass() {
            return;
        }
        let new: Vec<SharedEstimate> = links
            .zip(values)
            .filter_map(|((r, s, cap), &value)| pure_key(nodes, r as usize, s as usize, cap).map(|k| (k, value)))
            .collect();
        self.recorded.lock().unwrap_or_else(|e| e.into_inner()).extend(new);
    }
}

/// The key of link (receiver ← source) with spread cap `spread_cap` if its estimate is pure (not a
/// near link, both ends' paths exact).
pub fn pure_key(nodes: &Nodes, receiver: usize, source: usize, spread_cap: f32) -> Option<EstimateKey> {
    if is_near(nodes, receiver, source) {
        return None;
    }
    Some(EstimateKey {
        receiver: tree_path(nodes, receiver)?,
        source: tree_path(nodes, source)?,
        spread_cap_bits: spread_cap.to_bits(),
    })
}

/// `links::estimate` of link (receiver ← source), taken from a merge's parts when they hold it.
pub fn estimate_shared(
    shared: Option<&SharedEstimates>,
    nodes: &Nodes,
    ctx: &VisibilityContext,
    receiver: usize,
    source: usize,
    spread_cap: f32,
    threshold_w: f64,
) -> Option<(f32, f32)> {
    if let Some(shared) = shared.filter(|s| !s.known.is_empty()) {
        if let Some(value) = pure_key(nodes, receiver, source, spread_cap).and_then(|k| shared.known.get(&k)) {
            shared.hits.fetch_add(1, Ordering::Relaxed);
            return *value;
        }
    }
    estimate(nodes, ctx, receiver, source, spread_cap, threshold_w)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::hierarchy::{clusters, procedural};

    /// Every receiver is refined by exactly one shard of N, or by all of them (the shared clusters
    /// above the groups, a small share of the tree); and a merge refines every receiver.
    #[test]
    fn every_receiver_belongs_to_one_shard_or_to_all() {
        let (nodes, root, _, _) = clusters::build(&procedural::room_with_objects(400)).unwrap();
        assert!(SharedEstimates::for_merge(Vec::new()).refines_receiver(&nodes, root as usize));
        for count in 1..6u32 {
            let shards: Vec<SharedEstimates> =
                (0..count).map(|k| SharedEstimates::for_shard(k, count, 1, Vec::new())).collect();
            shards.iter().for_each(|s| {
                s.assign_receivers(&nodes, root as usize);
                s.begin_pass(1);
            });
            let mut shared = 0;
            let mut per_shard = vec![0usize; count as usize];
            for n in 0..nodes.len() {
                let owners: Vec<usize> =
                    (0..count as usize).filter(|&k| shards[k].refines_receiver(&nodes, n)).collect();
                match owners.len() {
                    1 => per_shard[owners[0]] += 1,
                    c if c == count as usize => shared += 1,
                    c => panic!("node {n} refined by {c} of {count} shards"),
                }
            }
            assert!(shared * 4 < nodes.len(), "{shared} of {} nodes shared by {count} shards", nodes.len());
            assert!(count == 1 || per_shard.iter().all(|&n| n > 0), "every shard has receivers: {per_shard:?}");
        }
    }
}
