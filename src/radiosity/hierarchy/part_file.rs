//! A shard part of a hierarchical solve (`solve --shard K/N`): the refinement pass the shard refined
//! and its pure link estimates (`shards`), in the row-block container (`matrix::rows_file`, kind
//! `HierarchyShardPart`: same header, checksum and atomic write).
//!
//! Payload, little-endian: pass u32, entries n u64, then per entry: receiver path and source path (each: root
//! u32, depth u32, steps u128), spread cap f32, present u8 (0: the estimate was `None`), form factor
//! f32, spread f32.

use std::path::Path;

use super::links_file::{push_value, read_value};
use super::shards::{EstimateKey, SharedEstimate};
use super::tree_path::{TreePath, MAX_EXACT_DEPTH};
use crate::radiosity::matrix::rows_file::{self, Payload, RowsFileError, RowsHeader, RowsKind};

/// Bytes of one path and of one entry.
const PATH_BYTES: usize = 4 + 4 + 16;
const ENTRY_BYTES: usize = 2 * PATH_BYTES + 4 + 1 + 4 + 4;

fn wrong_kind(path: &Path, found: RowsKind) -> RowsFileError {
    RowsFileError::WrongKind { path: path.to_path_buf(), found, expected: "hierarchical link estimates of a shard" }
}

/// What a part holds: the pass its shard refined (1-based) and its estimates.
#[derive(Clone, Debug, PartialEq)]
pub struct HierarchyPart {
    pub pass: u32,
    pub entries: Vec<SharedEstimate>,
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
            push_value(&mut bytes, *value);
            out.write_all(&bytes)?;
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
    if n.saturating_mul(ENTRY_BYTES as u64) != r.remaining() as u64 {
        return Err(r.damaged(format!("{n} entries in {} bytes", r.remaining())));
    }
    let mut entries = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let receiver = tree_path(&mut r)?;
        let source = tree_path(&mut r)?;
        let spread_cap_bits = r.u32()?;
        let value = read_value(&mut r)?;
        entries.push((EstimateKey { receiver, source, spread_cap_bits }, value));
    }
    r.finish()?;
    Ok((header, HierarchyPart { pass, entries }))
}

fn tree_path(r: &mut Payload) -> Result<TreePath, RowsFileError> {
    let root = r.u32()?;
    let depth = r.u32()?;
    let steps = u128::from_le_bytes(r.take(16)?.try_into().unwrap_or([0; 16]));
    if depth > MAX_EXACT_DEPTH {
        return Err(r.damaged(format!("a tree path {depth} levels deep")));
    }
    Ok(TreePath { root, depth, steps })
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (RowsHeader, HierarchyPart) {
        let header = RowsHeader {
            kind: RowsKind::HierarchyShardPart,
            fingerprint: 7,
            form_factor_key: 9,
            shard_index: 1,
            shard_count: 3,
        };
        let path = |root, depth, steps| TreePath { root, depth, steps };
        let key = |r, s, cap: f32| EstimateKey { receiver: r, source: s, spread_cap_bits: cap.to_bits() };
        let entries = vec![
            (key(path(3, 0, 0), path(4, 2, 0b1110), 1.0), Some((0.25, 0.5))),
            (key(path(5, 64, u128::MAX), path(4, 0, 0), f32::INFINITY), None),
        ];
        (header, HierarchyPart { pass: 2, entries })
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
}
