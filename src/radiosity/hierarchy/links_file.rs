//! A hierarchical solve's checkpoint: its `EstimateLog` in the row-block container
//! (`matrix::rows_file`, kind `HierarchyCheckpoint`: same header, checksum and atomic write).
//!
//! Payload, little-endian: entries n u64, then per entry: kind u8 (0 link, 1 kept near link),
//! receiver u32, source u32, present u8 (0: the estimate was `None`), form factor f32, spread f32.

use std::path::Path;

use super::estimates::{EstimateKind, EstimateLog, LoggedEstimate};
use crate::radiosity::matrix::rows_file::{self, Payload, RowsFileError, RowsHeader, RowsKind};

/// Bytes of one entry.
const ENTRY_BYTES: usize = 1 + 4 + 4 + 1 + 4 + 4;

/// Writes `log`'s entries under `header` (whose kind must be `HierarchyCheckpoint`) to `path`,
/// atomically.
pub fn write(path: &Path, header: &RowsHeader, log: &EstimateLog) -> Result<(), RowsFileError> {
    if header.kind != RowsKind::HierarchyCheckpoint {
        return Err(RowsFileError::WrongKind {
            path: path.to_path_buf(),
            found: header.kind,
            expected: "link estimates",
        });
    }
    rows_file::write_container(path, header, &mut |out| {
        out.write_all(&(log.entries.len() as u64).to_le_bytes())?;
        let mut bytes = Vec::with_capacity(ENTRY_BYTES);
        for e in &log.entries {
            bytes.clear();
            bytes.push(match e.kind {
                EstimateKind::Link => 0,
                EstimateKind::KeptNear => 1,
            });
            bytes.extend_from_slice(&e.receiver.to_le_bytes());
            bytes.extend_from_slice(&e.source.to_le_bytes());
            push_value(&mut bytes, e.value);
            out.write_all(&bytes)?;
        }
        Ok(())
    })
}

/// Reads a hierarchical checkpoint: its header and its log entries (to replay, see
/// `EstimateLog::resumed`). Damage, another kind of file, or an entry count beyond the file's size is
/// an error, never a panic or a huge allocation.
pub fn read(path: &Path) -> Result<(RowsHeader, Vec<LoggedEstimate>), RowsFileError> {
    let bytes = std::fs::read(path).map_err(|source| RowsFileError::Io { path: path.to_path_buf(), source })?;
    parse(path, &bytes)
}

/// `read` over bytes already in memory; `path` names them in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<(RowsHeader, Vec<LoggedEstimate>), RowsFileError> {
    let (header, mut r) = rows_file::parse_container(path, bytes)?;
    if header.kind != RowsKind::HierarchyCheckpoint {
        return Err(RowsFileError::WrongKind {
            path: path.to_path_buf(),
            found: header.kind,
            expected: "link estimates",
        });
    }
    let n = r.u64()?;
    if n.saturating_mul(ENTRY_BYTES as u64) != r.remaining() as u64 {
        return Err(r.damaged(format!("{n} entries in {} bytes", r.remaining())));
    }
    let mut entries = Vec::with_capacity(n as usize);
    for _ in 0..n {
        let kind = match r.u8()? {
            0 => EstimateKind::Link,
            1 => EstimateKind::KeptNear,
            k => return Err(r.damaged(format!("unknown estimate kind {k}"))),
        };
        let receiver = r.u32()?;
        let source = r.u32()?;
        let value = read_value(&mut r)?;
        entries.push(LoggedEstimate { kind, receiver, source, value });
    }
    r.finish()?;
    Ok((header, entries))
}

/// Appends an estimate's value: present u8 (0: `None`), form factor f32, spread f32 (9 bytes).
pub(super) fn push_value(bytes: &mut Vec<u8>, value: Option<(f32, f32)>) {
    let (present, (f, spread)) = match value {
        Some(v) => (1u8, v),
        None => (0u8, (0.0, 0.0)),
    };
    bytes.push(present);
    bytes.extend_from_slice(&f.to_bits().to_le_bytes());
    bytes.extend_from_slice(&spread.to_bits().to_le_bytes());
}

/// Reads what `push_value` wrote.
pub(super) fn read_value(r: &mut Payload) -> Result<Option<(f32, f32)>, RowsFileError> {
    let present = r.u8()?;
    let f = f32::from_bits(r.u32()?);
    let spread = f32::from_bits(r.u32()?);
    match present {
        0 => Ok(None),
        1 => Ok(Some((f, spread))),
        p => Err(r.damaged(format!("presence flag {p}"))),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (RowsHeader, EstimateLog) {
        let header = RowsHeader {
            kind: RowsKind::HierarchyCheckpoint,
            fingerprint: 7,
            form_factor_key: 9,
            shard_index: 0,
            shard_count: 1,
        };
        let entries = vec![
            LoggedEstimate { kind: EstimateKind::Link, receiver: 3, source: 4, value: Some((0.25, f32::NAN)) },
            LoggedEstimate { kind: EstimateKind::Link, receiver: 5, source: 4, value: None },
            LoggedEstimate { kind: EstimateKind::KeptNear, receiver: 1, source: 1, value: Some((0.5, 0.125)) },
        ];
        (header, EstimateLog::resumed(entries))
    }

    #[test]
    fn estimates_survive_a_round_trip_bit_for_bit() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.partial");
        let (header, log) = sample();
        write(&path, &header, &log).unwrap();
        let (read_header, entries) = read(&path).unwrap();
        assert_eq!(read_header, header);
        let bits = |e: &[LoggedEstimate]| {
            e.iter()
                .map(|e| (e.kind, e.receiver, e.source, e.value.map(|(f, s)| (f.to_bits(), s.to_bits()))))
                .collect::<Vec<_>>()
        };
        assert_eq!(bits(&entries), bits(&log.entries));
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_refused_and_rows_readers_refuse_it() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("h.partial");
        let (header, log) = sample();
        write(&path, &header, &log).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        rows_file::assert_every_damage_refused(&bytes, |b| parse(&path, b).is_err());
        assert!(matches!(rows_file::parse(&path, &bytes), Err(RowsFileError::WrongKind { .. })));
    }
}
