//! The log of link estimates a refinement made, in the order it made them: the unit of finished work
//! of a hierarchical solve, kept in its checkpoint (`links_file`). Refinement is deterministic given
//! its estimates (the decisions are applied in a fixed order, see `refine::refine_logged`), so a resumed solve
//! replays the whole refinement, taking each estimate from the log while it lasts and computing the
//! rest: the nodes it subdivides, their indices and the links are those of an uninterrupted run, and
//! so are the bytes. Only the cheap parts (decisions, sweeps) are done again.

use rayon::prelude::*;

use super::shards::SharedEstimates;

/// Which estimator produced a logged value.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EstimateKind {
    /// `links::estimate` of a new link: (form factor, spread), `None` when nothing passes.
    Link,
    /// The form factor of a near link kept unestimated (`links::near_form_factor` plus its push
    /// spread): (form factor, added spread), `None` when the link is dropped.
    KeptNear,
}

/// One logged estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LoggedEstimate {
    pub kind: EstimateKind,
    pub receiver: u32,
    pub source: u32,
    pub value: Option<(f32, f32)>,
}

/// The estimates of a solve in the order refinement asked for them, and how far a resumed solve has
/// replayed them. `EstimateLog::default()` records nothing (it only counts): a run without a
/// checkpoint does not pay the memory (about 24 bytes per estimate).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct EstimateLog {
    pub entries: Vec<LoggedEstimate>,
    /// Whether computed estimates are appended to `entries`.
    record: bool,
    /// Entries replayed so far (the rest of `entries` was computed by this run).
    cursor: usize,
    /// Entries this run computed.
    pub computed: usize,
    /// A logged entry did not match the link refinement asked for (the log belongs to another
    /// refinement); it and every entry after it were dropped and computed afresh.
    pub diverged: bool,
}

/// Stopped on request (`EstimateHooks::stop`) with the log up to date.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Stopped;

/// Links estimated in parallel between two looks at `EstimateHooks::stop` (and two calls of
/// `after_chunk`): small enough that a stop is prompt, large enough to keep both cores busy.
pub const CHUNK_LINKS: usize = 4096;

/// How a solve is stopped and its log saved: `stop` is polled before each chunk of estimates and
/// between sweeps; `after_chunk` sees the log after each chunk with the number of entries it computed
/// (a checkpoint writer, the cancellation test hook). `shared`: a shard or merge of pass one
/// (`shards`), `None` for a whole solve.
pub struct EstimateHooks<'a> {
    pub log: &'a mut EstimateLog,
    pub stop: &'a (dyn Fn() -> bool + Sync),
    pub after_chunk: &'a mut dyn FnMut(&EstimateLog, usize),
    pub shared: Option<&'a SharedEstimates>,
}

impl EstimateLog {
    /// A log read from a checkpoint, to be replayed.
    pub fn resumed(entries: Vec<LoggedEstimate>) -> Self {
        EstimateLog { entries, record: true, ..Default::default() }
    }

    /// An empty log that records (for a run that keeps a checkpoint).
    pub fn recording() -> Self {
        EstimateLog::resumed(Vec::new())
    }

    /// Entries taken from the log so far.
    pub fn replayed(&self) -> usize {
        self.cursor
    }

    /// The logged value of the next estimate if it is (kind, receiver, source); on a mismatch the
    /// log from here on is dropped.
    fn replay(&mut self, kind: EstimateKind, receiver: u32, source: u32) -> Option<Option<(f32, f32)>> {
        let entry = *self.entries.get(self.cursor)?;
        if (entry.kind, entry.receiver, entry.source) != (kind, receiver, source) {
            self.entries.truncate(self.cursor);
            self.diverged = true;
            return None;
        }
        self.cursor += 1;
        Some(entry.value)
    }

    fn push(&mut self, kind: EstimateKind, receiver: u32, source: u32, value: Option<(f32, f32)>) {
        if self.record {
            self.entries.push(LoggedEstimate { kind, receiver, source, value });
            self.cursor = self.entries.len();
        }
        self.computed += 1;
    }
}

/// Estimates of `kind` of the links `pairs` (receiver, source), in order: each from the log while it
/// lasts, the rest by `compute(index into pairs)` in parallel chunks of `CHUNK_LINKS`, polling
/// `hooks.stop` before each chunk. The values do not depend on the chunking or the threads (each
/// estimate is a pure function of its link).
pub fn estimate_links(
    kind: EstimateKind,
    pairs: &[(u32, u32)],
    compute: &(dyn Fn(usize) -> Option<(f32, f32)> + Sync),
    hooks: &mut EstimateHooks,
) -> Result<Vec<Option<(f32, f32)>>, Stopped> {
    let mut values = Vec::with_capacity(pairs.len());
    while values.len() < pairs.len() {
        let (r, s) = pairs[values.len()];
        if let Some(value) = hooks.log.replay(kind, r, s) {
            values.push(value);
            continue;
        }
        if (hooks.stop)() {
            return Err(Stopped);
        }
        let chunk = values.len()..(values.len() + CHUNK_LINKS).min(pairs.len());
        let computed: Vec<Option<(f32, f32)>> = chunk.clone().into_par_iter().map(compute).collect();
        let count = computed.len();
        for (i, value) in chunk.zip(computed) {
            let (r, s) = pairs[i];
            hooks.log.push(kind, r, s, value);
            values.push(value);
        }
        (hooks.after_chunk)(hooks.log, count);
    }
    Ok(values)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn hooks_run(log: &mut EstimateLog, pairs: &[(u32, u32)], stop_after: Option<usize>) -> Result<Vec<f32>, Stopped> {
        let calls = std::sync::atomic::AtomicUsize::new(0);
        let stop = || stop_after.is_some_and(|n| calls.load(std::sync::atomic::Ordering::SeqCst) >= n);
        let mut after = |_: &EstimateLog, n: usize| _ = calls.fetch_add(n, std::sync::atomic::Ordering::SeqCst);
        let mut hooks = EstimateHooks { log, stop: &stop, after_chunk: &mut after, shared: None };
        let compute = |i: usize| Some((pairs[i].0 as f32 * 0.5, pairs[i].1 as f32));
        estimate_links(EstimateKind::Link, pairs, &compute, &mut hooks)
            .map(|v| v.iter().map(|e| e.unwrap().0).collect())
    }

    #[test]
    fn a_stopped_log_resumes_to_the_values_of_an_uninterrupted_one() {
        let pairs: Vec<(u32, u32)> = (0..3 * CHUNK_LINKS as u32 + 7).map(|i| (i, i + 1)).collect();
        let whole = hooks_run(&mut EstimateLog::default(), &pairs, None).unwrap();
        let mut log = EstimateLog::recording();
        assert_eq!(hooks_run(&mut log, &pairs, Some(CHUNK_LINKS)), Err(Stopped));
        assert_eq!(log.entries.len(), CHUNK_LINKS, "one chunk done before the stop");
        let mut resumed = EstimateLog::resumed(log.entries);
        assert_eq!(hooks_run(&mut resumed, &pairs, None).unwrap(), whole);
        assert_eq!((resumed.replayed(), resumed.computed), (pairs.len(), pairs.len() - CHUNK_LINKS));
        assert!(!resumed.diverged);
    }

    #[test]
    fn a_log_of_other_links_is_dropped_where_it_disagrees() {
        let pairs: Vec<(u32, u32)> = (0..10).map(|i| (i, 2 * i)).collect();
        let mut log = EstimateLog::recording();
        hooks_run(&mut log, &pairs, None).unwrap();
        log.entries[4].source = 99;
        let mut resumed = EstimateLog::resumed(log.entries);
        let values = hooks_run(&mut resumed, &pairs, None).unwrap();
        assert_eq!(values, hooks_run(&mut EstimateLog::default(), &pairs, None).unwrap());
        assert!(resumed.diverged);
        assert_eq!(resumed.computed, 6);
    }
}
