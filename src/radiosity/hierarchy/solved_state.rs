//! The state of a hierarchical solve after a refinement pass and its sweeps: which elements were
//! subdivided (in order, so node indices come back the same), every link with its form factor and
//! spread, every node's exitance, and the statistics so far. A sharded solve's round hands it to the
//! next round in its parts (`part_file`), so that a shard or merge starts from it instead of replaying
//! the passes before (`shards`); restored, it gives the next pass exactly the inputs it has in a
//! single-machine solve, bit for bit.
//!
//! Encoding, little-endian: pass u32; rounds u32, sweeps u32, converged u8, budget exceeded u8,
//! links estimated u64, peak bytes u64, passes' errors n u32 then n f64; build nodes u64, subdivided
//! elements n u64 then n u32; links n u64 then per link receiver u32, source u32, form factor f32,
//! spread f32; then per node exitance 3 f64, gathered 3 f64, exitance mean f64.

use glam::DVec3;

use super::links::{LinkRecord, Links};
use super::nodes::Nodes;
use super::HierarchyStats;
use crate::radiosity::matrix::rows_file::{Payload, RowsFileError};

/// Bytes of one link and of one node's exitance.
const LINK_BYTES: usize = 16;
const NODE_BYTES: usize = 7 * 8;

/// A solve's state after refinement pass `pass` and its sweeps (see the module header).
#[derive(Clone, Debug, PartialEq)]
pub struct SolvedState {
    pub pass: u32,
    pub refinement_rounds: u32,
    pub sweeps: u32,
    pub converged: bool,
    pub budget_exceeded: bool,
    pub links_estimated: u64,
    pub peak_bytes: u64,
    pub error_after_pass_w: Vec<f64>,
    /// Nodes the build made (before any subdivision).
    pub build_nodes: u64,
    /// The elements `Nodes::subdivide` split, in the order it split them.
    pub subdivided: Vec<u32>,
    /// Every link, receiver by receiver (`Links::to_records`).
    pub links: Vec<LinkRecord>,
    pub exitance: Vec<DVec3>,
    pub gathered: Vec<DVec3>,
    pub exitance_mean: Vec<f64>,
}

/// Why a state does not fit the hierarchy it is restored into.
#[derive(Debug, thiserror::Error, PartialEq)]
#[error("the solved state of pass {pass} does not fit this scene's hierarchy: {what}")]
pub struct StateMismatch {
    pub pass: u32,
    pub what: String,
}

impl SolvedState {
    /// The state of `nodes` (built with `build_nodes` nodes, then subdivided) and `links` after pass
    /// `pass`, with the statistics so far.
    pub fn capture(nodes: &Nodes, build_nodes: usize, links: &Links, stats: &HierarchyStats, pass: u32) -> Self {
        // `subdivide` appends four children at a time, the first naming its parent.
        let subdivided = (build_nodes..nodes.len()).step_by(4).map(|first| nodes.parent[first]).collect();
        SolvedState {
            pass,
            refinement_rounds: stats.refinement_rounds,
            sweeps: stats.sweeps,
            converged: stats.converged,
            budget_exceeded: stats.budget_exceeded,
            links_estimated: stats.links_estimated,
            peak_bytes: stats.peak_bytes as u64,
            error_after_pass_w: stats.error_after_pass_w.clone(),
            build_nodes: build_nodes as u64,
            subdivided,
            links: links.to_records(),
            exitance: nodes.exitance.clone(),
            gathered: nodes.gathered.clone(),
            exitance_mean: nodes.exitance_mean.clone(),
        }
    }

    /// Puts the state into freshly built `nodes` (no subdivision yet) and `stats`, and returns the
    /// links. Everything is checked against the hierarchy first, so a state that does not fit is an
    /// error, never a panic.
    pub fn restore(&self, nodes: &mut Nodes, stats: &mut HierarchyStats) -> Result<Links, StateMismatch> {
        let fail = |what: String| Err(StateMismatch { pass: self.pass, what });
        if self.build_nodes != nodes.len() as u64 {
            return fail(format!("{} nodes built, the state's build had {}", nodes.len(), self.build_nodes));
        }
        for &element in &self.subdivided {
            let e = element as usize;
            if e >= nodes.len() || nodes.is_cluster[e] || !nodes.is_leaf(e) {
                return fail(format!("node {element} cannot be subdivided"));
            }
            nodes.subdivide(e);
        }
        nodes.assign_texture_means(self.build_nodes as usize);
        let n = nodes.len();
        if [self.exitance.len(), self.gathered.len(), self.exitance_mean.len()] != [n; 3] {
            return fail(format!("{n} nodes, exitance for {}", self.exitance.len()));
        }
        if let Some(l) = self.links.iter().find(|l| l.receiver as usize >= n || l.source as usize >= n) {
            return fail(format!("a link {} ← {} beyond the {n} nodes", l.receiver, l.source));
        }
        nodes.exitance.clone_from(&self.exitance);
        nodes.gathered.clone_from(&self.gathered);
        nodes.exitance_mean.clone_from(&self.exitance_mean);
        stats.refinement_passes = self.pass;
        stats.refinement_rounds = self.refinement_rounds;
        stats.sweeps = self.sweeps;
        stats.converged = self.converged;
        stats.budget_exceeded = self.budget_exceeded;
        stats.links_estimated = self.links_estimated;
        stats.peak_bytes = self.peak_bytes as usize;
        stats.error_after_pass_w.clone_from(&self.error_after_pass_w);
        Ok(Links::from_records(n, self.links.clone()))
    }

    /// The encoding of the module header.
    pub fn encode(&self) -> Vec<u8> {
        let n = self.exitance.len();
        let mut out =
            Vec::with_capacity(64 + self.subdivided.len() * 4 + self.links.len() * LINK_BYTES + n * NODE_BYTES);
        self.write_to(&mut out).unwrap_or_else(|_| unreachable!("writing to a Vec does not fail"));
        out
    }

    /// Streams the encoding of the module header to `out` (a file being written, or a hash: the
    /// encoding is never held whole), a link or node at a time.
    pub fn write_to(&self, out: &mut dyn std::io::Write) -> std::io::Result<()> {
        out.write_all(&self.pass.to_le_bytes())?;
        out.write_all(&self.refinement_rounds.to_le_bytes())?;
        out.write_all(&self.sweeps.to_le_bytes())?;
        out.write_all(&[self.converged as u8, self.budget_exceeded as u8])?;
        out.write_all(&self.links_estimated.to_le_bytes())?;
        out.write_all(&self.peak_bytes.to_le_bytes())?;
        out.write_all(&(self.error_after_pass_w.len() as u32).to_le_bytes())?;
        for e in &self.error_after_pass_w {
            out.write_all(&e.to_bits().to_le_bytes())?;
        }
        out.write_all(&self.build_nodes.to_le_bytes())?;
        out.write_all(&(self.subdivided.len() as u64).to_le_bytes())?;
        for s in &self.subdivided {
            out.write_all(&s.to_le_bytes())?;
        }
        out.write_all(&(self.links.len() as u64).to_le_bytes())?;
        let mut link = [0u8; LINK_BYTES];
        for l in &self.links {
            for (k, word) in [l.receiver, l.source, l.form_factor.to_bits(), l.spread.to_bits()].iter().enumerate() {
                link[4 * k..4 * k + 4].copy_from_slice(&word.to_le_bytes());
            }
            out.write_all(&link)?;
        }
        let mut node = [0u8; NODE_BYTES];
        for i in 0..self.exitance.len() {
            let (b, g) = (self.exitance[i], self.gathered[i]);
            for (k, v) in [b.x, b.y, b.z, g.x, g.y, g.z, self.exitance_mean[i]].iter().enumerate() {
                node[8 * k..8 * k + 8].copy_from_slice(&v.to_bits().to_le_bytes());
            }
            out.write_all(&node)?;
        }
        Ok(())
    }

    /// Reads what `encode` wrote from `r`, to its end. Counts beyond the bytes left are refused
    /// before anything is allocated.
    pub fn decode(r: &mut Payload) -> Result<Self, RowsFileError> {
        let pass = r.u32()?;
        let refinement_rounds = r.u32()?;
        let sweeps = r.u32()?;
        let flag = |r: &mut Payload, what: &str| match r.u8()? {
            0 => Ok(false),
            1 => Ok(true),
            f => Err(r.damaged(format!("{what} flag {f}"))),
        };
        let converged = flag(r, "converged")?;
        let budget_exceeded = flag(r, "budget")?;
        let links_estimated = r.u64()?;
        let peak_bytes = r.u64()?;
        let f64_of = |r: &mut Payload| r.u64().map(f64::from_bits);
        let count = |r: &mut Payload, n: u64, size: usize| {
            if n.saturating_mul(size as u64) > r.remaining() as u64 {
                Err(r.damaged(format!("{n} entries of {size} bytes in {} bytes", r.remaining())))
            } else {
                Ok(n as usize)
            }
        };
        let errors = r.u32()? as u64;
        let errors = count(r, errors, 8)?;
        let error_after_pass_w = (0..errors).map(|_| f64_of(r)).collect::<Result<_, _>>()?;
        let build_nodes = r.u64()?;
        let subdivided = r.u64()?;
        let subdivided = count(r, subdivided, 4)?;
        let subdivided = (0..subdivided).map(|_| r.u32()).collect::<Result<_, _>>()?;
        let links = r.u64()?;
        let links = count(r, links, LINK_BYTES)?;
        let mut records = Vec::with_capacity(links);
        for _ in 0..links {
            let (receiver, source) = (r.u32()?, r.u32()?);
            let (form_factor, spread) = (f32::from_bits(r.u32()?), f32::from_bits(r.u32()?));
            records.push(LinkRecord { receiver, source, form_factor, spread });
        }
        if !r.remaining().is_multiple_of(NODE_BYTES) {
            return Err(r.damaged(format!("{} bytes of node exitance", r.remaining())));
        }
        let n = r.remaining() / NODE_BYTES;
        let (mut exitance, mut gathered, mut exitance_mean) =
            (Vec::with_capacity(n), Vec::with_capacity(n), Vec::with_capacity(n));
        for _ in 0..n {
            let mut v = [0.0f64; 7];
            for x in &mut v {
                *x = f64_of(r)?;
            }
            exitance.push(DVec3::new(v[0], v[1], v[2]));
            gathered.push(DVec3::new(v[3], v[4], v[5]));
            exitance_mean.push(v[6]);
        }
        Ok(SolvedState {
            pass,
            refinement_rounds,
            sweeps,
            converged,
            budget_exceeded,
            links_estimated,
            peak_bytes,
            error_after_pass_w,
            build_nodes,
            subdivided,
            links: records,
            exitance,
            gathered,
            exitance_mean,
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::hierarchy::{clusters, procedural, solve};

    /// A state captured after some subdivisions restores, into a fresh build, the same nodes (indices,
    /// geometry, exitance), links and statistics; its encoding round-trips; a state that does not fit
    /// is refused.
    #[test]
    fn a_captured_state_restores_the_same_hierarchy_into_a_fresh_build() {
        let scene = procedural::room_with_objects(60);
        let (mut nodes, root, _, _) = clusters::build(&scene).unwrap();
        let build = nodes.len();
        solve::reset_to_emission(&mut nodes, root as usize);
        let leaf = (0..build).find(|&n| !nodes.is_cluster[n]).unwrap();
        let first = nodes.subdivide(leaf) as usize;
        nodes.subdivide(first + 2);
        nodes.exitance[first + 1] = DVec3::new(1.0, 2.0, 3.0);
        let records = vec![
            LinkRecord { receiver: first as u32, source: root, form_factor: 0.25, spread: 0.125 },
            LinkRecord { receiver: root, source: root, form_factor: 0.5, spread: 1.0 },
        ];
        let links = Links::from_records(nodes.len(), records);
        let stats =
            HierarchyStats { sweeps: 7, error_after_pass_w: vec![2.5], links_estimated: 11, ..Default::default() };
        let state = SolvedState::capture(&nodes, build, &links, &stats, 1);
        assert_eq!(state.subdivided, vec![leaf as u32, (first + 2) as u32]);

        let bytes = state.encode();
        let path = std::path::Path::new("state");
        let decoded = SolvedState::decode(&mut Payload::over(path, &bytes)).unwrap();
        assert_eq!(decoded, state);

        let (mut fresh, _, _, _) = clusters::build(&scene).unwrap();
        let mut restored_stats = HierarchyStats::default();
        let restored = state.restore(&mut fresh, &mut restored_stats).unwrap();
        assert_eq!(fresh.len(), nodes.len());
        assert_eq!(fresh.parent, nodes.parent);
        assert_eq!(fresh.corners, nodes.corners);
        assert_eq!(fresh.exitance, nodes.exitance);
        assert_eq!(restored.to_records(), links.to_records());
        assert_eq!((restored_stats.sweeps, restored_stats.links_estimated), (7, 11));

        let refuse = |bad: SolvedState| {
            let (mut other, _, _, _) = clusters::build(&scene).unwrap();
            bad.restore(&mut other, &mut HierarchyStats::default()).unwrap_err().what
        };
        let other_build = SolvedState { build_nodes: state.build_nodes + 1, ..state.clone() };
        assert!(refuse(other_build).contains("nodes built"));
        let cluster_split = SolvedState { subdivided: vec![root], ..state.clone() };
        assert!(refuse(cluster_split).contains(&format!("node {root} cannot be subdivided")));
        let short = SolvedState { exitance: state.exitance[1..].to_vec(), ..state.clone() };
        assert!(refuse(short).contains("exitance for"));
    }
}
