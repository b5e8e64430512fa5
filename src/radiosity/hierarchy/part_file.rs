//! A shard part of a hierarchical solve (`solve --shard K/N`): the refinement pass the shard refined,
//! its pure link estimates (`shards`), and the solved state of the pass before it that the shard
//! refined from (`solved_state`: shard 0 carries it, every part its hash), in the row-block container
//! (`matrix::rows_file`, kind `HierarchyShardPart`: same header, checksum and atomic write).
//!
//! Payload, little-endian: pass u32, entries n u64, then per entry: receiver path and source path (each: root
//! u32, depth u32, steps u128), spread cap f32, leaf shapes u8 (1: the receiver's and the source's
//! `near_leaf_shapes` follow, u128 each; 0: both are 0), present u8 (0: the estimate was `None`), form
//! factor f32, spread f32; then the state's hash u64 (FNV-1a 64 of its encoding; 0 in pass 1, which starts
//! from the emission), present u8, and when present the state's encoding to the end.

use std::path::Path;

use super::links_file::{push_value, read_value};
use super::shards::{EstimateKey, SharedEstimate};
use super::solved_state::SolvedState;
use super::tree_path::{TreePath, MAX_EXACT_DEPTH};
use crate::radiosity::fingerprint::{fnv1a64, Fnv1a64};
use crate::radiosity::matrix::rows_file::{self, Payload, RowsFileError, RowsHeader, RowsKind};

/// Bytes of one path and the fewest of one entry (no leaf shapes).
const PATH_BYTES: usize = 4 + 4 + 16;
const ENTRY_BYTES: usize = 2 * PATH_BYTES + 4 + 1 + 1 + 4 + 4;

fn wrong_kind(path: &Path, found: RowsKind) -> RowsFileError {
    RowsFileError::WrongKind { path: path.to_path_buf(), found, expected: "hierarchical link estimates of a shard" }
}

/// What a part holds: the pass its shard refined (1-based), its estimates, and the state of pass
/// `pass` − 1 it refined from: its hash in every part (0 for pass 1), the state itself in one.
#[derive(Clone, Debug, PartialEq)]
pub struct HierarchyPart {
    pub pass: u32,
    pub entries: Vec<SharedEstimate>,
    pub state_hash: u64,
    pub state: Option<SolvedState>,
}

/// The hash a part gives the state it was refined from (see the module header), streamed over its
/// encoding (`SolvedState::write_to`) without building it.
pub fn state_hash(state: &SolvedState) -> u64 {
    let mut sink = HashSink(Fnv1a64::default());
    state.write_to(&mut sink).unwrap_or_else(|_| unreachable!("hashing does not fail"));
    sink.0.finish()
}

/// A `Write` that only hashes what it is given.
struct HashSink(Fnv1a64);

impl std::io::Write for HashSink {
    fn write(&mut self, bytes: &[u8]) -> std::io::Result<usize> {
        self.0.write(bytes);
        Ok(bytes.len())
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

/// Writes `part` under `header` (whose kind must be `HierarchyShardPart`) to `path`, atomically.
pub fn write(path: &Path, header: &RowsHeader, part: &HierarchyPart) -> Result<(), RowsFileError> {
    if header.kind != RowsKind::HierarchyShardPart {
        return Err(wrong_kind(path, header.kind));
    }
    let entries = &part.entries;
    rows_file::write_container(path, header, &mut |out| {
        out.write_all(&part.pass.to_le_bytes())?;
        out.write_all(&(entries.len() as u64).to_le_bytes())?;
        let mut bytes = Vec::with_capacity(ENTRY_BYTES);
        for (key, value) in entries {
            bytes.clear();
            for p in [key.receiver, key.source] {
                bytes.extend_from_slice(&p.root.to_le_bytes());
                bytes.extend_from_slice(&p.depth.to_le_bytes());
                bytes.extend_from_slice(&p.steps.to_le_bytes());
            }
            bytes.extend_from_slice(&key.spread_cap_bits.to_le_bytes());
            let shaped = (key.receiver_leaves, key.source_leaves) != (0, 0);
            bytes.push(shaped as u8);
            if shaped {
                bytes.extend_from_slice(&key.receiver_leaves.to_le_bytes());
                bytes.extend_from_slice(&key.source_leaves.to_le_bytes());
            }
            push_value(&mut bytes, *value);
            out.write_all(&bytes)?;
        }
        out.write_all(&part.state_hash.to_le_bytes())?;
        out.write_all(&[part.state.is_some() as u8])?;
        if let Some(state) = &part.state {
            state.write_to(out)?;
        }
        Ok(())
    })
}

/// Reads a hierarchical shard part: its header, pass and estimates. Damage, another kind of file, or
/// an entry count beyond the file's size is an error, never a panic or a huge allocation.
pub fn read(path: &Path) -> Result<(RowsHeader, HierarchyPart), RowsFileError> {
    let bytes = std::fs::read(path).map_err(|source| RowsFileError::Io { path: path.to_path_buf(), source })?;
    parse(path, &bytes)
}

/// `read` over bytes already in memory; `path` names them in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<(RowsHeader, HierarchyPart), RowsFileError> {
    let (header, mut r) = rows_file::parse_container(path, bytes)?;
    if header.kind != RowsKind::HierarchyShardPart {
        return Err(wrong_kind(path, header.kind));
    }
    let pass = r.u32()?;
    if pass == 0 {
        return Err(r.damaged("pass 0".into()));
    }
    let n = r.u64()?;
    if n.saturating_mul(ENTRY_BYTES as u64) > r.remaining() as u64 {
        return Err(r.damaged(format!("{n} entries in {} bytes", r.remaining())));
    }
    let mut entries = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let receiver = tree_path(&mut r)?;
        let source = tree_path(&mut r)?;
        let spread_cap_bits = r.u32()?;
        let [receiver_leaves, source_leaves] = match r.u8()? {
            0 => [0, 0],
            1 => [u128_of(&mut r)?, u128_of(&mut r)?],
            f => return Err(r.damaged(format!("leaf shapes flag {f}"))),
        };
        let value = read_value(&mut r)?;
        entries.push((EstimateKey { receiver, source, spread_cap_bits, receiver_leaves, source_leaves }, value));
    }
    let state_hash = r.u64()?;
    let state = match r.u8()? {
        0 => None,
        1 => {
            if fnv1a64(r.rest()) != state_hash {
                return Err(r.damaged("a solved state that does not match its hash".into()));
            }
            let state = SolvedState::decode(&mut r)?;
            if state.pass + 1 != pass {
                return Err(r.damaged(format!("a part of pass {pass} with the solved state of pass {}", state.pass)));
            }
            Some(state)
        }
        p => return Err(r.damaged(format!("state flag {p}"))),
    };
    r.finish()?;
    Ok((header, HierarchyPart { pass, entries, state_hash, state }))
}

fn tree_path(r: &mut Payload) -> Result<TreePath, RowsFileError> {
    let root = r.u32()?;
    let depth = r.u32()?;
    let steps = u128_of(r)?;
    if depth > MAX_EXACT_DEPTH {
        return Err(r.damaged(format!("a tree path {depth} levels deep")));
    }
    Ok(TreePath { root, depth, steps })
}

fn u128_of(r: &mut Payload) -> Result<u128, RowsFileError> {
    Ok(u128::from_le_bytes(r.take(16)?.try_into().unwrap_or([0; 16])))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::radiosity::hierarchy::links::LinkRecord;
    use glam::DVec3;

    fn sample() -> (RowsHeader, HierarchyPart) {
        let header = RowsHeader {
            kind: RowsKind::HierarchyShardPart,
            fingerprint: 7,
            form_factor_key: 9,
            shard_index: 1,
            shard_count: 3,
        };
        let path = |root, depth, steps| TreePath { root, depth, steps };
        let key = |r, s, cap: f32| EstimateKey {
            receiver: r,
            source: s,
            spread_cap_bits: cap.to_bits(),
            receiver_leaves: 0,
            source_leaves: 0,
        };
        let near =
            EstimateKey { receiver_leaves: 0b1_0010, source_leaves: 1 << 85, ..key(path(4, 1, 2), path(6, 0, 0), 0.5) };
        let entries = vec![
            (key(path(3, 0, 0), path(4, 2, 0b1110), 1.0), Some((0.25, 0.5))),
            (key(path(5, 64, u128::MAX), path(4, 0, 0), f32::INFINITY), None),
            (near, Some((0.125, 0.75))),
        ];
        let state = SolvedState {
            pass: 1,
            refinement_rounds: 3,
            sweeps: 9,
            converged: true,
            budget_exceeded: false,
            links_estimated: 40,
            peak_bytes: 1 << 20,
            error_after_pass_w: vec![0.5],
            build_nodes: 5,
            subdivided: vec![2],
            links: vec![LinkRecord { receiver: 1, source: 8, form_factor: 0.25, spread: f32::INFINITY }],
            exitance: vec![DVec3::new(1.0, 2.0, 3.0); 9],
            gathered: vec![DVec3::ZERO; 9],
            exitance_mean: vec![2.0; 9],
        };
        let state_hash = state_hash(&state);
        assert_eq!(state_hash, fnv1a64(&state.encode()), "the streamed hash is the encoding's");
        (header, HierarchyPart { pass: 2, entries, state_hash, state: Some(state) })
    }

    #[test]
    fn estimates_survive_a_round_trip_and_every_damage_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part.1");
        let (header, entries) = sample();
        write(&path, &header, &entries).unwrap();
        assert_eq!(read(&path).unwrap(), (header, entries));
        let bytes = std::fs::read(&path).unwrap();
        rows_file::assert_every_damage_refused(&bytes, |b| parse(&path, b).is_err());
        assert!(matches!(rows_file::parse(&path, &bytes), Err(RowsFileError::WrongKind { .. })));
    }

    /// A part whose state is not the pass before its own, or does not match its hash, is refused even
    /// with a valid checksum (a part written by another run or version).
    #[test]
    fn a_state_of_another_pass_or_hash_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("part.0");
        let (header, mut part) = sample();
        part.pass = 3;
        write(&path, &header, &part).unwrap();
        let refused = read(&path).unwrap_err().to_string();
        assert!(refused.contains("part of pass 3 with the solved state of pass 1"), "{refused}");
        let (_, mut part) = sample();
        part.state_hash ^= 1;
        write(&path, &header, &part).unwrap();
        let refused = read(&path).unwrap_err().to_string();
        assert!(refused.contains("does not match its hash"), "{refused}");
    }
}
