//! The hierarchy's refinement split over machines (`solve --shard K/N`, `--merge`), one pass per
//! round of shards: which receivers a shard refines, and the link estimates shards hand to the next
//! round and the merge, keyed by the tree paths of the link's ends (`tree_path`) so that they do not
//! depend on the order in which nodes were subdivided.
//!
//! Refinement is a forest below the root's self-link: a link's children keep its receiver or take a
//! child of it, so a shard that drops the new links of receivers it does not own refines its own
//! receivers' links exactly as far as the whole solve, as long as the decisions do not look beyond the
//! link. They do not (within a pass, the exitance is the one every shard solved alike, and pieces
//! made in it inherit their parent's), except near links, whose form factor integrates over the
//! leaves found below their ends when they are estimated, and the memory budget. So an estimate is
//! keyed by what it depends on (`EstimateKey`): the two paths, the parent's spread cap and, for a
//! near link integrated leaf pair by leaf pair, the shapes of the subdivision below both ends
//! (`links::near_leaf_shapes`), since in its own pass a shard splits only its receivers and may see
//! fewer leaves below a source than the whole solve. A near link about to be split (its F left NaN)
//! depends on the pass's exitance instead; it costs no rays and is neither recorded nor looked up.
//! The merge is the whole solve, taking each estimate from the shards when they hold its key and
//! computing everything else (what the budget or another subdivision made differ): its bytes are
//! those of a single-machine solve by construction.
//!
//! Rounds hand on their solved state (`solved_state`): a shard of round p ≥ 2 starts from the state
//! of pass p − 2 in round p − 1's parts (or from the emission for p = 2), refines pass p − 1 whole
//! with round p − 1's estimates, sweeps it, and puts the resulting state of pass p − 1 in its own
//! part beside its estimates of pass p. So each round, and the merge, does one pass's work for the
//! whole hierarchy (loading, near links, decisions, sweeps) instead of every pass before it.

use std::collections::HashMap;
use std::hash::{BuildHasherDefault, Hasher};
use std::sync::atomic::{AtomicU32, AtomicU64, Ordering};
use std::sync::{Mutex, OnceLock};

use super::links::Links;
use super::links::{estimate, is_near, near_leaf_shapes, near_split_pending};
use super::nodes::Nodes;
use super::solved_state::SolvedState;
use super::tree_path::TreePath;
use super::visibility::VisibilityContext;
use crate::rng::splitmix64;

/// A link estimate's identity: both ends' paths, the spread cap it inherited (`links::estimate`
/// caps its spread there) and, for a near link integrated leaf pair by leaf pair, the subdivision
/// below each end (`links::near_leaf_shapes`; 0 otherwise). Everything else it depends on is fixed by
/// the scene and its settings.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct EstimateKey {
    pub receiver: TreePath,
    pub source: TreePath,
    pub spread_cap_bits: u32,
    pub receiver_leaves: u128,
    pub source_leaves: u128,
}

/// A pure estimate and its value ((form factor, spread), or `None`: the link was dropped).
pub type SharedEstimate = (EstimateKey, Option<(f32, f32)>);

/// Hashes the merge's estimate keys: each word folded in by a multiply and rotate (FxHash's step),
/// finished by `splitmix64` so that every bit of the result depends on every word. Several times
/// faster than the standard SipHash on these 52-byte keys, and the table holds a solve's own keys, so
/// it needs no resistance to chosen collisions.
#[derive(Clone, Copy, Debug, Default)]
pub struct KeyHasher(u64);

impl KeyHasher {
    fn fold(&mut self, word: u64) {
        self.0 = (self.0.rotate_left(5) ^ word).wrapping_mul(0x51_7c_c1_b7_27_22_0a_95);
    }
}

impl Hasher for KeyHasher {
    fn write(&mut self, bytes: &[u8]) {
        for chunk in bytes.chunks(8) {
            let mut word = [0u8; 8];
            word[..chunk.len()].copy_from_slice(chunk);
            self.fold(u64::from_le_bytes(word));
        }
    }

    fn write_u32(&mut self, v: u32) {
        self.fold(v as u64);
    }

    fn write_u64(&mut self, v: u64) {
        self.fold(v);
    }

    fn write_u128(&mut self, v: u128) {
        self.fold(v as u64);
        self.fold((v >> 64) as u64);
    }

    fn finish(&self) -> u64 {
        splitmix64(self.0)
    }
}

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
    known: HashMap<EstimateKey, Option<(f32, f32)>, BuildHasherDefault<KeyHasher>>,
    /// The solved state to start from (`solved_state`), taken by the solve.
    start: Mutex<Option<SolvedState>>,
    /// The state a shard of pass p ≥ 2 refined its pass from (that of pass p − 1).
    captured: Mutex<Option<SolvedState>>,
    /// A shard's pure estimates so far.
    recorded: Mutex<Vec<SharedEstimate>>,
    /// Estimates taken from `known`.
    hits: AtomicU64,
    /// Estimates looked up in `known` and not found (computed here).
    misses: AtomicU64,
}

impl SharedEstimates {
    /// Shard `index` of `count` of pass `pass`: starts from `start` (the state of pass `pass` − 2, or
    /// `None`: from the emission), refines its receivers' links in pass `pass` and records them,
    /// taking the estimates of the last round's parts (`earlier`) where they fit.
    pub fn for_shard(
        index: u32,
        count: u32,
        pass: u32,
        earlier: Vec<SharedEstimate>,
        start: Option<SolvedState>,
    ) -> Self {
        SharedEstimates { shard: Some((index, count)), shard_pass: pass, ..SharedEstimates::for_merge(earlier, start) }
    }

    /// A merge: the whole solve from `start` (or from the emission), taking the estimates of `parts`
    /// where they fit.
    pub fn for_merge(parts: Vec<SharedEstimate>, start: Option<SolvedState>) -> Self {
        let mut known = HashMap::with_capacity_and_hasher(parts.len(), BuildHasherDefault::default());
        for (key, value) in parts {
            known.entry(key).or_insert(value);
        }
        SharedEstimates { known, start: Mutex::new(start), ..Default::default() }
    }

    /// The state to start from, once (the solve takes it).
    pub fn take_start(&self) -> Option<SolvedState> {
        self.start.lock().unwrap_or_else(|e| e.into_inner()).take()
    }

    /// A shard keeps the state it refines its pass from.
    pub fn capture(&self, state: SolvedState) {
        *self.captured.lock().unwrap_or_else(|e| e.into_inner()) = Some(state);
    }

    /// The state a shard refined its pass from (`None` in pass 1).
    pub fn take_captured(&self) -> Option<SolvedState> {
        self.captured.lock().unwrap_or_else(|e| e.into_inner()).take()
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

    /// Estimates looked up in the parts and not found there (near links about to be split, which
    /// cost no rays, are not looked up).
    pub fn misses(&self) -> u64 {
        self.misses.load(Ordering::Relaxed)
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

    /// Groups the receivers of the tree (`nodes` as the build made them, or with the subdivisions of
    /// the state the shard starts from; root `root`) and gives each group to a shard. A group is the
    /// subtree of the topmost cluster holding at most ⌈T / (`GROUPS_PER_SHARD`·N)⌉ of the T input
    /// triangles (or an input triangle); the nodes above are shared. Groups go to shards heaviest
    /// first, each to the shard with the least so far (longest processing time first), plus a
    /// thousandth of the mean weight each so that weightless groups spread too. The weight is the
    /// refinement work a group is expected to bring: from a solved state (`links` of the pass before,
    /// not empty), the links its receivers hold, since a pass re-refines the links of the one before;
    /// from the emission, the power it can reflect (area × largest reflectance channel). Only a shard
    /// needs this, and every shard of a round computes the same assignment.
    pub fn assign_receivers(&self, nodes: &Nodes, root: usize, links: &Links) {
        let Some((_, count)) = self.shard else { return };
        let n = nodes.len();
        // Children have higher indices than their parent: one reverse sweep sums subtrees.
        let mut inputs = vec![0usize; n];
        let mut held = vec![0usize; n];
        for i in (0..n).rev() {
            inputs[i] = if nodes.is_cluster[i] { nodes.children(i).map(|c| inputs[c]).sum() } else { 1 };
            held[i] = links.range(i).len() + nodes.children(i).map(|c| held[c]).sum::<usize>();
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
        let by_links = !links.is_empty();
        let weight = |g: usize| match by_links {
            true => held[g] as f64,
            false => nodes.area[g] as f64 * nodes.reflectance_max[g] as f64,
        };
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

    /// In its pass, a shard records the estimates among `links` (receiver, source, spread cap) with
    /// their `values` under their `estimate_key`, except near links left to be split (NaN), whose
    /// value depends on the pass's exitance; `paths` are the nodes' tree paths
    /// (`tree_path::extend_paths`).
    pub fn record(
        &self,
        nodes: &Nodes,
        paths: &[Option<TreePath>],
        links: impl Iterator<Item = (u32, u32, f32)>,
        values: &[Option<(f32, f32)>],
    ) {
        if !self.in_shard_pass() {
            return;
        }
        let new: Vec<SharedEstimate> = links
            .zip(values)
            .filter(|(_, value)| !value.is_some_and(|(f, _)| f.is_nan()))
            .filter_map(|((r, s, cap), &value)| {
                estimate_key(nodes, paths, r as usize, s as usize, cap).map(|k| (k, value))
            })
            .collect();
        self.recorded.lock().unwrap_or_else(|e| e.into_inner()).extend(new);
    }
}

/// The key of the estimate of link (receiver ← source) with spread cap `spread_cap` (see
/// `EstimateKey`), when both ends' paths are exact; `paths` holds every node's `tree_path`.
pub fn estimate_key(
    nodes: &Nodes,
    paths: &[Option<TreePath>],
    receiver: usize,
    source: usize,
    spread_cap: f32,
) -> Option<EstimateKey> {
    let (receiver_path, source_path) = (paths[receiver]?, paths[source]?);
    let [receiver_leaves, source_leaves] =
        if is_near(nodes, receiver, source) { near_leaf_shapes(nodes, receiver, source) } else { [0, 0] };
    Some(EstimateKey {
        receiver: receiver_path,
        source: source_path,
        spread_cap_bits: spread_cap.to_bits(),
        receiver_leaves,
        source_leaves,
    })
}

/// `links::estimate` of link (receiver ← source), taken from the parts when they hold its key
/// (`paths`: every node's `tree_path`, or empty without `shared`). A near link about to be split is
/// computed (no rays; its value depends on the pass), and so is an element link a part left
/// unestimated.
#[allow(clippy::too_many_arguments)]
pub fn estimate_shared(
    shared: Option<&SharedEstimates>,
    paths: &[Option<TreePath>],
    nodes: &Nodes,
    ctx: &VisibilityContext,
    receiver: usize,
    source: usize,
    spread_cap: f32,
    threshold_w: f64,
    min_element_area: f32,
) -> Option<(f32, f32)> {
    if let Some(shared) = shared.filter(|s| !s.known.is_empty()) {
        let pending = is_near(nodes, receiver, source)
            && near_split_pending(nodes, receiver, source, spread_cap, threshold_w).is_some();
        let known = || estimate_key(nodes, paths, receiver, source, spread_cap).and_then(|k| shared.known.get(&k));
        if !pending {
            // An element link a part left unestimated (F NaN: split there, `links::estimate`) is
            // computed: whether it splits reads the pass's exitance.
            let unestimated_element = |value: &Option<(f32, f32)>| {
                value.is_some_and(|(f, _)| f.is_nan()) && !nodes.is_cluster[receiver] && !nodes.is_cluster[source]
            };
            if let Some(value) = known().filter(|value| !unestimated_element(value)) {
                shared.hits.fetch_add(1, Ordering::Relaxed);
                return *value;
            }
            shared.misses.fetch_add(1, Ordering::Relaxed);
        }
    }
    estimate(nodes, ctx, receiver, source, spread_cap, threshold_w, min_element_area)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::hierarchy::{clusters, procedural};

    /// One refinement pass sharded two ways, then merged: the merge's bytes are the single solve's, and
    /// it takes nearly every estimate from the parts, near links (integrated over the leaves below
    /// their ends) included.
    #[test]
    fn a_merge_takes_near_link_estimates_from_the_shards_and_keeps_the_bytes() {
        use crate::radiosity::hierarchy::estimates::{EstimateHooks, EstimateLog};
        use crate::radiosity::hierarchy::{solve_logged, HierarchyParams};
        let scene = procedural::room_with_objects(600);
        let params = HierarchyParams { refinement_passes: 1, ..HierarchyParams::preview() };
        let run = |shared: Option<&SharedEstimates>| {
            let mut log = EstimateLog::default();
            let mut hooks = EstimateHooks { log: &mut log, stop: &|| false, after_chunk: &mut |_, _| {}, shared };
            let (solution, _) =
                solve_logged(&scene, Default::default(), &params, None, None, &mut hooks, &mut |_| {}).unwrap();
            (solution, log.computed as u64)
        };
        let (single, single_estimates) = run(None);
        let mut parts = Vec::new();
        for k in 0..2 {
            let shard = SharedEstimates::for_shard(k, 2, 1, Vec::new(), None);
            run(Some(&shard));
            parts.extend(shard.take_recorded());
        }
        let near = parts.iter().filter(|(k, _)| k.receiver_leaves != 0).count();
        assert!(near > 0, "the shards record near links integrated leaf pair by leaf pair");
        let merge = SharedEstimates::for_merge(parts, None);
        let (merged, computed) = run(Some(&merge));
        let bits = |s: &crate::radiosity::hierarchy::HierarchicalSolution| {
            s.leaf_exitance.iter().flat_map(|b| b.to_array().map(f32::to_bits)).collect::<Vec<u32>>()
        };
        assert_eq!(bits(&merged), bits(&single), "merged exitance is the single solve's, bit for bit");
        assert_eq!(computed, single_estimates, "the merge asks for the single solve's estimates");
        assert!(merge.misses() * 100 <= merge.hits(), "misses {} of {}", merge.misses(), merge.hits());
    }

    /// From a solved state the groups are weighed by the links their receivers hold: with all the links
    /// on the input triangles of one half of the tree, each shard still gets its share of them.
    #[test]
    fn groups_are_balanced_by_the_links_of_the_pass_before() {
        use crate::radiosity::hierarchy::links::LinkRecord;
        let (nodes, root, _, _) = clusters::build(&procedural::room_with_objects(2000)).unwrap();
        let elements: Vec<usize> = (0..nodes.len()).filter(|&n| !nodes.is_cluster[n]).collect();
        let records: Vec<LinkRecord> = elements[..elements.len() / 2]
            .iter()
            .map(|&e| LinkRecord { receiver: e as u32, source: root, form_factor: 0.1, spread: 0.1 })
            .collect();
        let links = Links::from_records(nodes.len(), records);
        for count in 2..4u32 {
            let mut held = vec![0usize; count as usize];
            for k in 0..count {
                let shard = SharedEstimates::for_shard(k, count, 1, Vec::new(), None);
                shard.assign_receivers(&nodes, root as usize, &links);
                shard.begin_pass(1);
                held[k as usize] =
                    (0..nodes.len()).filter(|&n| shard.refines_receiver(&nodes, n)).map(|n| links.range(n).len()).sum();
            }
            let mean = links.len() as f64 / count as f64;
            // Longest processing time first over ≥ 16 groups a shard: within a group's weight of the mean.
            assert!(held.iter().all(|&h| (h as f64 - mean).abs() < 0.1 * mean), "{count} shards hold {held:?} links");
        }
    }

    /// Every receiver is refined by exactly one shard of N, or by all of them (the shared clusters
    /// above the groups, a small share of the tree); and a merge refines every receiver.
    #[test]
    fn every_receiver_belongs_to_one_shard_or_to_all() {
        let (nodes, root, _, _) = clusters::build(&procedural::room_with_objects(400)).unwrap();
        assert!(SharedEstimates::for_merge(Vec::new(), None).refines_receiver(&nodes, root as usize));
        for count in 1..6u32 {
            let shards: Vec<SharedEstimates> =
                (0..count).map(|k| SharedEstimates::for_shard(k, count, 1, Vec::new(), None)).collect();
            shards.iter().for_each(|s| {
                s.assign_receivers(&nodes, root as usize, &Links::default());
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
