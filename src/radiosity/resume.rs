//! Pass one across processes: the checkpoint a run keeps beside its output (`OUT.partial`, the rows
//! finished so far, rewritten at most every `CHECKPOINT_INTERVAL`), the shard a run computes
//! (`--shard K/N`: every N-th group of receivers) and the parts a merge joins (`--merge`). All of
//! them are row-block files (`matrix::rows_file`), checked against the scene's keys. A hierarchical
//! solve's checkpoint is its log of link estimates in the same container (`hierarchy::links_file`),
//! and so are its shard parts (`hierarchy::part_file`).

use std::path::{Path, PathBuf};
use std::time::{Duration, Instant};

use super::hierarchy::estimates::{EstimateLog, LoggedEstimate};
use super::hierarchy::links_file;
use super::hierarchy::part_file::{self, HierarchyPart};
use super::hierarchy::shards::SharedEstimate;
use super::matrix::rows_file::{self, RowsFileError, RowsHeader, RowsKind};
use super::matrix::{FormFactors, PartialRows};
use crate::interrupt::Cancel;
use crate::progress::Progress;

/// Shortest time between two checkpoint writes.
pub const CHECKPOINT_INTERVAL: Duration = Duration::from_secs(30);

/// Consecutive elements (receivers) that one shard computes together: shard K of N takes the groups
/// g with g mod N = K. Neighbouring elements cost about the same, so the shards stay balanced.
pub const SHARD_GROUP_ELEMENTS: usize = 256;

/// Shard K of N (0 ≤ K < N).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Shard {
    pub index: u32,
    pub count: u32,
}

impl Shard {
    /// The whole matrix: shard 0 of 1.
    pub const WHOLE: Shard = Shard { index: 0, count: 1 };

    /// Whether this shard computes element i's row.
    pub fn selects(&self, element: usize) -> bool {
        (element / SHARD_GROUP_ELEMENTS) % self.count as usize == self.index as usize
    }
}

/// How a single run keeps, finds and splits its pass-one work (the matrix method only; other methods
/// restart, see `PassOneMethod::checkpoints`). `Resume::default()` keeps nothing.
#[derive(Clone, Debug, Default)]
pub struct Resume {
    /// Where the checkpoint lives (`OUT.partial`); `None` keeps none.
    pub checkpoint: Option<PathBuf>,
    /// Shortest time between checkpoint writes (`CHECKPOINT_INTERVAL`; tests use zero).
    pub interval: Duration,
    /// Polled between rows and sweeps; set by SIGINT/SIGTERM or a test.
    pub cancel: Cancel,
    /// Compute only this shard's rows (`--shard`).
    pub shard: Option<Shard>,
    /// Shard parts to merge and solve (`--merge`), checked against the scene by `merge_parts`.
    pub merge: Vec<PathBuf>,
}

impl Resume {
    /// The shard this run computes (the whole matrix when not sharded).
    pub fn shard(&self) -> Shard {
        self.shard.unwrap_or(Shard::WHOLE)
    }

    /// Whether the run shards or merges (the stored matrix or the hierarchy, `method::shard_method`).
    pub fn needs_matrix(&self) -> bool {
        self.shard.is_some() || !self.merge.is_empty()
    }
}

/// `OUT.partial` beside `output`.
pub fn checkpoint_path(output: &Path) -> PathBuf {
    let mut name = output.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(".partial");
    output.with_file_name(name)
}

/// The scene keys a row-block file must carry to be used.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct SceneKeys {
    pub fingerprint: u64,
    pub form_factor_key: u64,
}

/// The checkpoint at `path` if it belongs to this scene and shard; a damaged or stale one is ignored
/// with a warning (and overwritten by the next checkpoint), a missing one silently.
pub fn load_checkpoint(path: &Path, keys: SceneKeys, shard: Shard, progress: &Progress) -> Option<PartialRows> {
    load(path, RowsKind::Checkpoint, keys, shard, progress, rows_file::read)
}

/// The payload `read` finds at `path` if the file is of `kind` and this run's; warns otherwise.
fn load<T>(
    path: &Path,
    kind: RowsKind,
    keys: SceneKeys,
    shard: Shard,
    progress: &Progress,
    read: impl FnOnce(&Path) -> Result<(RowsHeader, T), RowsFileError>,
) -> Option<T> {
    if !path.exists() {
        return None;
    }
    match read(path) {
        Err(e) => {
            progress.note(&format!("warning: ignoring the checkpoint: {e}; starting pass one afresh"));
            None
        }
        Ok((header, payload)) => usable(path, &header, kind, keys, shard, progress).then_some(payload),
    }
}

/// Whether a checkpoint's header is this run's (kind, keys, shard); warns when it is not.
fn usable(
    path: &Path,
    header: &RowsHeader,
    kind: RowsKind,
    keys: SceneKeys,
    shard: Shard,
    progress: &Progress,
) -> bool {
    let matches = header.kind == kind
        && header.fingerprint == keys.fingerprint
        && header.form_factor_key == keys.form_factor_key
        && (header.shard_index, header.shard_count) == (shard.index, shard.count);
    if !matches {
        progress.note(&format!(
            "warning: ignoring the checkpoint {}: it was made for another scene, settings or shard \
             (fingerprint {:016x}, this run {:016x}); starting pass one afresh",
            path.display(),
            header.fingerprint,
            keys.fingerprint
        ));
    }
    matches
}

/// The link estimates of a hierarchical solve's checkpoint at `path` (to replay, see
/// `hierarchy::estimates`) if it belongs to this scene and settings; a damaged or stale one is
/// ignored with a warning, a missing one silently.
pub fn load_hierarchy_checkpoint(path: &Path, keys: SceneKeys, progress: &Progress) -> Option<Vec<LoggedEstimate>> {
    load(path, RowsKind::HierarchyCheckpoint, keys, Shard::WHOLE, progress, links_file::read)
}

/// Writes the checkpoint of a row computation when `CHECKPOINT_INTERVAL` has passed since the last
/// write, and at least ten times as long as that write took (so writing costs under a tenth of the
/// run, however large the matrix).
pub struct Checkpointer {
    path: PathBuf,
    header: RowsHeader,
    elements: usize,
    interval: Duration,
    last: Instant,
    /// The first write error, reported once: a run goes on without checkpoints rather than failing.
    pub error: Option<RowsFileError>,
    pub writes: u32,
    pub write_seconds: f64,
}

impl Checkpointer {
    pub fn new(path: PathBuf, keys: SceneKeys, shard: Shard, elements: usize, interval: Duration) -> Self {
        let header = RowsHeader {
            kind: RowsKind::Checkpoint,
            fingerprint: keys.fingerprint,
            form_factor_key: keys.form_factor_key,
            shard_index: shard.index,
            shard_count: shard.count,
        };
        Checkpointer {
            path,
            header,
            elements,
            interval,
            last: Instant::now(),
            error: None,
            writes: 0,
            write_seconds: 0.0,
        }
    }

    /// Whether a write now would respect the interval.
    pub fn due(&self) -> bool {
        let since = self.last.elapsed();
        since >= self.interval && since.as_secs_f64() >= 10.0 * self.write_seconds / self.writes.max(1) as f64
    }

    /// Writes the checkpoint if it is due.
    pub fn maybe_write(&mut self, rows: &PartialRows) {
        if self.due() {
            self.write(rows);
        }
    }

    /// Writes the checkpoint now (keeping the first error).
    pub fn write(&mut self, rows: &PartialRows) {
        self.write_matrix(&rows.ff, &rows.done);
    }

    /// Writes the checkpoint of matrix rows `ff`, of which `done` are finished, now.
    pub fn write_matrix(&mut self, ff: &FormFactors, done: &[bool]) {
        let elements = self.elements;
        self.timed(|path, header| rows_file::write_rows(path, header, ff, done, Default::default(), elements));
    }

    /// A checkpointer of a hierarchical solve (its log of link estimates).
    pub fn for_hierarchy(path: PathBuf, keys: SceneKeys, interval: Duration) -> Self {
        let mut checkpointer = Checkpointer::new(path, keys, Shard::WHOLE, 0, interval);
        checkpointer.header.kind = RowsKind::HierarchyCheckpoint;
        checkpointer
    }

    /// Writes a hierarchical solve's checkpoint now (see `for_hierarchy`).
    pub fn write_log(&mut self, log: &EstimateLog) {
        self.timed(|path, header| links_file::write(path, header, log));
    }

    /// Writes through `write`, timing it and keeping the first error.
    fn timed(&mut self, write: impl FnOnce(&Path, &RowsHeader) -> Result<(), RowsFileError>) {
        let start = Instant::now();
        match write(&self.path, &self.header) {
            Ok(()) => {
                self.writes += 1;
                self.write_seconds += start.elapsed().as_secs_f64();
            }
            Err(e) => {
                self.error.get_or_insert(e);
            }
        }
        self.last = Instant::now();
    }

    /// Removes the checkpoint once the run's output is written.
    pub fn remove(path: &Path) {
        let _ = std::fs::remove_file(path);
    }
}

/// Why `--shard` or `--merge` cannot go on.
#[derive(Debug, thiserror::Error)]
pub enum ShardError {
    #[error(transparent)]
    File(#[from] RowsFileError),
    #[error("{}: a checkpoint, not a shard part; finish its run (`radray solve ... --shard K/N`) first", path.display())]
    NotAPart { path: PathBuf },
    #[error("{}: made for another scene or other settings (fingerprint {found:016x}, this scene {expected:016x})", path.display())]
    OtherScene { path: PathBuf, found: u64, expected: u64 },
    #[error("{}: shard of {found} parts, but {first} is one of {expected}", path.display(), first = first.display())]
    OtherCount { path: PathBuf, found: u32, first: PathBuf, expected: u32 },
    #[error("shard {index} of {count} given twice: {} and {}", first.display(), second.display())]
    Duplicate { index: u32, count: u32, first: PathBuf, second: PathBuf },
    #[error("shard(s) {missing:?} of {count} missing: --merge needs every part once")]
    Missing { missing: Vec<u32>, count: u32 },
    #[error("the parts disagree on the element count")]
    ElementCounts,
    #[error("--merge needs at least one part")]
    NoParts,
    #[error("the parts of refinement pass {pass} are missing (the parts go up to pass {passes}); run its shards with the parts of the passes before it")]
    MissingPass { pass: u32, passes: u32 },
    #[error("the parts hold all {passes} refinement passes of this scene; merge them without --shard")]
    EveryPassDone { passes: u32 },
    #[error("--shard with --merge shards a later refinement pass of the hierarchical method; the matrix method shards in one round")]
    MatrixRounds,
    #[error("{}: incomplete: {missing} of its rows are missing", path.display())]
    Incomplete { path: PathBuf, missing: usize },
    #[error("{scene}: sharding and merging need the stored matrix ([radiosity] method = \"matrix\", store_form_factors = true) or the hierarchy; this scene uses {method}")]
    NotMatrix { scene: String, method: String },
}

/// The parts at `paths` as `read` finds them.
fn read_parts<T>(
    paths: &[PathBuf],
    read: impl Fn(&Path) -> Result<(RowsHeader, T), RowsFileError>,
) -> Result<Vec<(PathBuf, RowsHeader, T)>, ShardError> {
    paths
        .iter()
        .map(|path| read(path).map(|(header, payload)| (path.clone(), header, payload)))
        .collect::<Result<_, _>>()
        .map_err(ShardError::from)
}

/// Checks parts: every one a `kind` part of this scene, all of the same count N, each K in 0..N
/// exactly once.
fn checked_parts<T>(
    read: Vec<(PathBuf, RowsHeader, T)>,
    keys: SceneKeys,
    kind: RowsKind,
) -> Result<Vec<(PathBuf, RowsHeader, T)>, ShardError> {
    let mut parts: Vec<(PathBuf, RowsHeader, T)> = Vec::with_capacity(read.len());
    for (path, header, payload) in read {
        let path = &path;
        if header.kind != kind {
            return Err(ShardError::NotAPart { path: path.clone() });
        }
        if header.fingerprint != keys.fingerprint || header.form_factor_key != keys.form_factor_key {
            return Err(ShardError::OtherScene {
                path: path.clone(),
                found: header.fingerprint,
                expected: keys.fingerprint,
            });
        }
        if let Some((first, first_header, _)) = parts.first() {
            if first_header.shard_count != header.shard_count {
                return Err(ShardError::OtherCount {
                    path: path.clone(),
                    found: header.shard_count,
                    first: first.clone(),
                    expected: first_header.shard_count,
                });
            }
        }
        if let Some((first, _, _)) = parts.iter().find(|(_, h, _)| h.shard_index == header.shard_index) {
            return Err(ShardError::Duplicate {
                index: header.shard_index,
                count: header.shard_count,
                first: first.clone(),
                second: path.clone(),
            });
        }
        parts.push((path.clone(), header, payload));
    }
    let count = parts.first().ok_or(ShardError::NoParts)?.1.shard_count;
    let missing: Vec<u32> = (0..count).filter(|k| !parts.iter().any(|(_, h, _)| h.shard_index == *k)).collect();
    if !missing.is_empty() {
        return Err(ShardError::Missing { missing, count });
    }
    Ok(parts)
}

/// Joins the parts of a sharded pass one: every part must be a finished shard part of this scene,
/// all of the same count N, each K in 0..N exactly once, and together they must hold every row.
pub fn merge_parts(paths: &[PathBuf], keys: SceneKeys) -> Result<PartialRows, ShardError> {
    let parts = checked_parts(read_parts(paths, rows_file::read)?, keys, RowsKind::ShardPart)?;
    for (path, header, rows) in &parts {
        let shard = Shard { index: header.shard_index, count: header.shard_count };
        let missing = (0..rows.len()).filter(|&i| shard.selects(i) && !rows.done[i]).count();
        if missing > 0 {
            return Err(ShardError::Incomplete { path: path.clone(), missing });
        }
    }
    let rows: Vec<PartialRows> = parts.into_iter().map(|(_, _, rows)| rows).collect();
    PartialRows::union(&rows).ok_or(ShardError::ElementCounts)
}

/// The link estimates of a sharded hierarchical solve: the parts of passes 1..=P, each pass's
/// checked like `merge_parts`'s rows (every part of this scene and settings, each shard once), and
/// no pass missing below P. Returns P and all parts' entries in one list.
pub fn merge_hierarchy_parts(paths: &[PathBuf], keys: SceneKeys) -> Result<(u32, Vec<SharedEstimate>), ShardError> {
    let mut parts = read_parts(paths, part_file::read)?;
    let passes = parts.iter().map(|(_, _, part)| part.pass).max().ok_or(ShardError::NoParts)?;
    let mut entries = Vec::new();
    for pass in (1..=passes).rev() {
        let (this, rest) = parts.into_iter().partition(|(_, _, part)| part.pass == pass);
        parts = rest;
        if Vec::is_empty(&this) {
            return Err(ShardError::MissingPass { pass, passes });
        }
        for (_, _, part) in checked_parts(this, keys, RowsKind::HierarchyShardPart)? {
            entries.extend(part.entries);
        }
    }
    Ok((passes, entries))
}

/// Writes shard `shard`'s pure link estimates of a hierarchical refinement pass as a part for
/// `merge_hierarchy_parts`.
pub fn write_hierarchy_part(
    path: &Path,
    keys: SceneKeys,
    shard: Shard,
    part: &HierarchyPart,
) -> Result<(), RowsFileError> {
    let header = RowsHeader {
        kind: RowsKind::HierarchyShardPart,
        fingerprint: keys.fingerprint,
        form_factor_key: keys.form_factor_key,
        shard_index: shard.index,
        shard_count: shard.count,
    };
    part_file::write(path, &header, part)
}

/// Writes shard `shard`'s finished rows as a part for `merge_parts`.
pub fn write_part(path: &Path, keys: SceneKeys, shard: Shard, rows: &PartialRows) -> Result<(), RowsFileError> {
    let header = RowsHeader {
        kind: RowsKind::ShardPart,
        fingerprint: keys.fingerprint,
        form_factor_key: keys.form_factor_key,
        shard_index: shard.index,
        shard_count: shard.count,
    };
    rows_file::write(path, &header, rows, rows.len())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn shards_cover_every_element_exactly_once() {
        for count in 1..5 {
            for element in 0..3000 {
                let owners = (0..count).filter(|&index| Shard { index, count }.selects(element)).count();
                assert_eq!(owners, 1, "element {element} of {count} shards");
            }
        }
    }

    #[test]
    fn the_checkpoint_sits_beside_the_output() {
        assert_eq!(checkpoint_path(Path::new("out/cornell.radsol")), PathBuf::from("out/cornell.radsol.partial"));
    }
}
