//! The row-block file: finished form-factor rows (`PartialRows`) with the keys of the scene they
//! belong to, shared by checkpoints (`OUT.partial`) and the parts of a sharded pass one. Written to a
//! temporary file and renamed (atomic); read whole and checked (magic, version, checksum, bounds)
//! before anything is trusted.
//!
//! Layout, little-endian: `RADRAYRW`, version u32, kind u8 (0 checkpoint, 1 shard part, 2 hierarchy
//! checkpoint), mesh fingerprint u64, form-factor key u64, shard index u32, shard count u32, then the
//! payload, and FNV-1a 64 of everything before it. The container (header, checksum, atomic write,
//! bounds-checked reading: `write_container`, `parse_container`) is shared with the hierarchy's
//! link-estimate log (`hierarchy::links_file`); the rows payload is: elements n u64, a bitset of the
//! done rows (⌈n/8⌉ bytes), then per done row: plain length u32, length u32, columns u32 × length,
//! values f32 × length; specular pixels, rays, entries u64.

use std::io::Write;
use std::path::{Path, PathBuf};

use super::partial::PartialRows;
use super::FormFactors;
use crate::radiosity::fingerprint::Fnv1a64;
use crate::radiosity::specular::SpecularStats;

const MAGIC: &[u8; 8] = b"RADRAYRW";
/// The version this build writes and reads (2: hierarchy shard parts carry near links' leaf shapes,
/// so a part written by an older radray is refused by version instead of as damaged).
pub const VERSION: u32 = 2;

/// What a row-block file is for.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum RowsKind {
    /// A run's own checkpoint, possibly incomplete.
    Checkpoint,
    /// One shard's finished rows (`solve --shard K/N`).
    ShardPart,
    /// A hierarchical solve's checkpoint: its log of link estimates (`hierarchy::links_file`).
    HierarchyCheckpoint,
    /// One shard's pure link estimates of a hierarchical pass one (`hierarchy::part_file`).
    HierarchyShardPart,
}

impl RowsKind {
    fn byte(self) -> u8 {
        match self {
            RowsKind::Checkpoint => 0,
            RowsKind::ShardPart => 1,
            RowsKind::HierarchyCheckpoint => 2,
            RowsKind::HierarchyShardPart => 3,
        }
    }

    /// What a file of this kind holds, for messages.
    pub fn describe(self) -> &'static str {
        match self {
            RowsKind::Checkpoint => "a form-factor checkpoint",
            RowsKind::ShardPart => "a form-factor shard part",
            RowsKind::HierarchyCheckpoint => "a hierarchical solve's checkpoint (link estimates)",
            RowsKind::HierarchyShardPart => "a hierarchical shard part (link estimates)",
        }
    }

    /// Whether files of this kind hold matrix rows (`read`, `write_rows`).
    pub fn holds_rows(self) -> bool {
        matches!(self, RowsKind::Checkpoint | RowsKind::ShardPart)
    }
}

/// Which scene and which part of its rows a file holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct RowsHeader {
    pub kind: RowsKind,
    /// `fingerprint::fingerprint` of the mesh and materials.
    pub fingerprint: u64,
    /// `fingerprint::form_factor_key` (geometry and hemicube settings).
    pub form_factor_key: u64,
    /// Shard K of N (0 of 1 for an unsharded run).
    pub shard_index: u32,
    pub shard_count: u32,
}

/// Why a row-block file cannot be used; every message names the file.
#[derive(Debug, thiserror::Error)]
pub enum RowsFileError {
    #[error("{}: {source}", path.display())]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{}: not a radray row-block file (no RADRAYRW header)", path.display())]
    NotARowsFile { path: PathBuf },
    #[error("{}: row-block version {version}, but this radray reads version {VERSION}", path.display())]
    UnsupportedVersion { path: PathBuf, version: u32 },
    #[error("{}: damaged: checksum mismatch (the file was cut short or altered)", path.display())]
    Checksum { path: PathBuf },
    #[error("{}: damaged at byte {offset}: {what}", path.display())]
    Damaged { path: PathBuf, offset: usize, what: String },
    #[error("{}: {} where {expected} was expected", path.display(), found.describe())]
    WrongKind { path: PathBuf, found: RowsKind, expected: &'static str },
}

/// Writes `rows` of a matrix of `elements` rows under `header` to `path` (rows past `rows.len()` are
/// not done): streamed to `dir/.name.tmp-PID`, synced, then renamed, so a reader sees the old file or
/// the new one, never a half-written one.
pub fn write(path: &Path, header: &RowsHeader, rows: &PartialRows, elements: usize) -> Result<(), RowsFileError> {
    write_rows(path, header, &rows.ff, &rows.done, rows.specular, elements)
}

/// `write` from the parts of a `PartialRows`: matrix rows `ff` (a prefix of `elements`), which are
/// done, and their ray statistics.
pub fn write_rows(
    path: &Path,
    header: &RowsHeader,
    ff: &FormFactors,
    done: &[bool],
    specular: SpecularStats,
    elements: usize,
) -> Result<(), RowsFileError> {
    assert!(done.len() <= elements && ff.len() == done.len(), "a prefix of the matrix's rows");
    if !header.kind.holds_rows() {
        return Err(RowsFileError::WrongKind { path: path.to_path_buf(), found: header.kind, expected: "rows" });
    }
    write_container(path, header, &mut |out| {
        out.write_all(&(elements as u64).to_le_bytes())?;
        let mut bits = vec![0u8; elements.div_ceil(8)];
        for (i, _) in done.iter().enumerate().filter(|(_, &d)| d) {
            bits[i / 8] |= 1 << (i % 8);
        }
        out.write_all(&bits)?;
        for i in (0..done.len()).filter(|&i| done[i]) {
            let (columns, values) = ff.row(i);
            out.write_all(&(ff.row_plain(i).0.len() as u32).to_le_bytes())?;
            out.write_all(&(columns.len() as u32).to_le_bytes())?;
            for c in columns {
                out.write_all(&c.to_le_bytes())?;
            }
            for v in values {
                out.write_all(&v.to_bits().to_le_bytes())?;
            }
        }
        for x in [specular.pixels, specular.rays, specular.entries] {
            out.write_all(&x.to_le_bytes())?;
        }
        Ok(())
    })
}

/// Writes a file of this family: the header, the payload `payload` writes, and the checksum;
/// streamed to `dir/.name.tmp-PID`, synced, then renamed, so a reader sees the old file or the new
/// one, never a half-written one.
pub fn write_container(
    path: &Path,
    header: &RowsHeader,
    payload: &mut dyn FnMut(&mut dyn Write) -> std::io::Result<()>,
) -> Result<(), RowsFileError> {
    let tmp = crate::output::temporary_path(path);
    let io = |source| RowsFileError::Io { path: path.to_path_buf(), source };
    let result = (|| {
        let file = std::fs::File::create(&tmp)?;
        let mut out =
            HashingWriter { inner: std::io::BufWriter::with_capacity(1 << 20, file), hash: Fnv1a64::default() };
        out.write_all(MAGIC)?;
        out.write_all(&VERSION.to_le_bytes())?;
        out.write_all(&[header.kind.byte()])?;
        out.write_all(&header.fingerprint.to_le_bytes())?;
        out.write_all(&header.form_factor_key.to_le_bytes())?;
        out.write_all(&header.shard_index.to_le_bytes())?;
        out.write_all(&header.shard_count.to_le_bytes())?;
        payload(&mut out)?;
        let checksum = out.hash.finish();
        let mut inner = out.inner;
        inner.write_all(&checksum.to_le_bytes())?;
        let file = inner.into_inner().map_err(|e| e.into_error())?;
        file.sync_all()?;
        std::fs::rename(&tmp, path)
    })();
    if result.is_err() {
        let _ = std::fs::remove_file(&tmp);
    }
    result.map_err(io)
}

/// Reads a row-block file, checking its magic, version, checksum and every index against the element
/// count (a damaged file is an error, never a panic or a huge allocation).
pub fn read(path: &Path) -> Result<(RowsHeader, PartialRows), RowsFileError> {
    let bytes = std::fs::read(path).map_err(|source| RowsFileError::Io { path: path.to_path_buf(), source })?;
    parse(path, &bytes)
}

/// `read` over bytes already in memory; `path` names them in errors.
pub fn parse(path: &Path, bytes: &[u8]) -> Result<(RowsHeader, PartialRows), RowsFileError> {
    let (header, mut r) = parse_container(path, bytes)?;
    if !header.kind.holds_rows() {
        return Err(RowsFileError::WrongKind { path: path.to_path_buf(), found: header.kind, expected: "rows" });
    }
    let body = r.bytes;
    let n = r.u64()?;
    // Every element takes at least one bit: a count beyond the file's size is damage, not a request
    // for memory.
    if n > (body.len() as u64).saturating_mul(8) || n > u32::MAX as u64 {
        return Err(r.damaged(format!("{n} elements in a file of {} bytes", bytes.len())));
    }
    let n = n as usize;
    let bits = r.take(n.div_ceil(8))?;
    let done: Vec<bool> = (0..n).map(|i| bits[i / 8] & (1 << (i % 8)) != 0).collect();
    let mut ff = FormFactors { row_start: vec![0], ..Default::default() };
    for &row_done in &done {
        if row_done {
            let plain = r.u32()? as usize;
            let len = r.u32()? as usize;
            if plain > len || len > n {
                return Err(r.damaged(format!("row of {len} entries ({plain} plain) among {n} elements")));
            }
            let columns = r.take(len * 4)?;
            let values = r.take(len * 4)?;
            for c in columns.chunks_exact(4) {
                let c = u32::from_le_bytes([c[0], c[1], c[2], c[3]]);
                if c as usize >= n {
                    return Err(r.damaged(format!("column {c} of {n}")));
                }
                ff.column.push(c);
            }
            for v in values.chunks_exact(4) {
                let v = f32::from_le_bytes([v[0], v[1], v[2], v[3]]);
                if !v.is_finite() {
                    return Err(r.damaged(format!("form factor {v}")));
                }
                ff.value.push(v);
            }
            ff.plain_end.push(ff.column.len() - len + plain);
        } else {
            ff.plain_end.push(ff.column.len());
        }
        ff.row_start.push(ff.column.len());
    }
    let specular = SpecularStats { pixels: r.u64()?, rays: r.u64()?, entries: r.u64()? };
    r.finish()?;
    Ok((header, PartialRows { ff, done, specular }))
}

/// Checks a file of this family (magic, version, checksum, header) and returns its header and a
/// reader over its payload.
pub fn parse_container<'a>(path: &'a Path, bytes: &'a [u8]) -> Result<(RowsHeader, Payload<'a>), RowsFileError> {
    let path_buf = || path.to_path_buf();
    if bytes.len() < MAGIC.len() || &bytes[..MAGIC.len()] != MAGIC {
        return Err(RowsFileError::NotARowsFile { path: path_buf() });
    }
    let mut r = Payload { path, bytes, at: MAGIC.len() };
    let version = r.u32()?;
    if version != VERSION {
        return Err(RowsFileError::UnsupportedVersion { path: path_buf(), version });
    }
    if bytes.len() < 8 + MAGIC.len() {
        return Err(RowsFileError::Checksum { path: path_buf() });
    }
    let (body, stored) = bytes.split_at(bytes.len() - 8);
    let mut hash = Fnv1a64::default();
    hash.write(body);
    if stored != hash.finish().to_le_bytes() {
        return Err(RowsFileError::Checksum { path: path_buf() });
    }
    r.bytes = body;
    let kind = match r.take(1)?[0] {
        0 => RowsKind::Checkpoint,
        1 => RowsKind::ShardPart,
        2 => RowsKind::HierarchyCheckpoint,
        3 => RowsKind::HierarchyShardPart,
        k => return Err(r.damaged(format!("unknown kind {k}"))),
    };
    let fingerprint = r.u64()?;
    let form_factor_key = r.u64()?;
    let shard_index = r.u32()?;
    let shard_count = r.u32()?;
    if shard_count == 0 || shard_index >= shard_count {
        return Err(r.damaged(format!("shard {shard_index} of {shard_count}")));
    }
    Ok((RowsHeader { kind, fingerprint, form_factor_key, shard_index, shard_count }, r))
}

/// A writer that hashes what passes through it (for the trailing checksum).
struct HashingWriter<W: Write> {
    inner: W,
    hash: Fnv1a64,
}

impl<W: Write> Write for HashingWriter<W> {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let written = self.inner.write(buf)?;
        self.hash.write(&buf[..written]);
        Ok(written)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        self.inner.flush()
    }
}

/// A bounds-checked cursor over a file's payload (the checksum excluded).
pub struct Payload<'a> {
    path: &'a Path,
    bytes: &'a [u8],
    at: usize,
}

impl<'a> Payload<'a> {
    /// A cursor over `bytes` from their start; `path` names them in errors.
    pub fn over(path: &'a Path, bytes: &'a [u8]) -> Self {
        Payload { path, bytes, at: 0 }
    }

    /// The bytes not read yet, without reading them.
    pub fn rest(&self) -> &'a [u8] {
        &self.bytes[self.at..]
    }

    /// An error naming the file and the current offset.
    pub fn damaged(&self, what: String) -> RowsFileError {
        RowsFileError::Damaged { path: self.path.to_path_buf(), offset: self.at, what }
    }

    /// Bytes not read yet.
    pub fn remaining(&self) -> usize {
        self.bytes.len() - self.at
    }

    /// Refuses bytes after the last section.
    pub fn finish(&self) -> Result<(), RowsFileError> {
        match self.remaining() {
            0 => Ok(()),
            extra => Err(self.damaged(format!("{extra} bytes after the last section"))),
        }
    }

    pub fn take(&mut self, len: usize) -> Result<&'a [u8], RowsFileError> {
        let end = self.at.checked_add(len).filter(|&e| e <= self.bytes.len());
        let Some(end) = end else {
            return Err(self.damaged(format!("{len} bytes needed, {} left", self.bytes.len() - self.at)));
        };
        let slice = &self.bytes[self.at..end];
        self.at = end;
        Ok(slice)
    }

    pub fn u8(&mut self) -> Result<u8, RowsFileError> {
        Ok(self.take(1)?[0])
    }

    pub fn u32(&mut self) -> Result<u32, RowsFileError> {
        let b = self.take(4)?;
        Ok(u32::from_le_bytes([b[0], b[1], b[2], b[3]]))
    }

    pub fn u64(&mut self) -> Result<u64, RowsFileError> {
        let b = self.take(8)?;
        Ok(u64::from_le_bytes([b[0], b[1], b[2], b[3], b[4], b[5], b[6], b[7]]))
    }
}

/// Checks that `refused` refuses every truncation of `bytes` and every copy with one byte flipped
/// (the checksum and the bounds checks of a file of this family).
#[cfg(test)]
pub(crate) fn assert_every_damage_refused(bytes: &[u8], refused: impl Fn(&[u8]) -> bool) {
    for len in 0..bytes.len() {
        assert!(refused(&bytes[..len]), "truncated to {len} bytes");
    }
    for at in 0..bytes.len() {
        let mut damaged = bytes.to_vec();
        damaged[at] ^= 0x10;
        assert!(refused(&damaged), "byte {at} flipped");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn sample() -> (RowsHeader, PartialRows) {
        let ff = FormFactors {
            row_start: vec![0, 2, 2, 3],
            column: vec![1, 2, 0],
            value: vec![0.25, 0.5, 0.125],
            plain_end: vec![1, 2, 3],
        };
        let header = RowsHeader {
            kind: RowsKind::ShardPart,
            fingerprint: 7,
            form_factor_key: 9,
            shard_index: 1,
            shard_count: 3,
        };
        let specular = SpecularStats { pixels: 4, rays: 5, entries: 1 };
        (header, PartialRows { ff, done: vec![true, false, true], specular })
    }

    #[test]
    fn rows_survive_a_round_trip_with_their_plain_and_extended_parts() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rows.part");
        let (header, rows) = sample();
        write(&path, &header, &rows, 3).unwrap();
        let (read_header, read_rows) = read(&path).unwrap();
        assert_eq!(read_header, header);
        assert_eq!(read_rows, rows);
    }

    #[test]
    fn every_truncation_and_every_flipped_byte_is_refused() {
        let dir = tempfile::tempdir().unwrap();
        let path = dir.path().join("rows.part");
        let (header, rows) = sample();
        write(&path, &header, &rows, 3).unwrap();
        let bytes = std::fs::read(&path).unwrap();
        assert_every_damage_refused(&bytes, |b| parse(&path, b).is_err());
    }
}
