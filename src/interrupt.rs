//! Interruption by SIGINT or SIGTERM: the only user of `signal-hook`. A `Cancel` token records which
//! signal arrived; work that can save itself (matrix rows, solver sweeps) polls it and stops, and work
//! that cannot is ended at once with the signal's exit code once `Cancel::exit_at_once` arms it.

use std::sync::atomic::{AtomicBool, AtomicUsize, Ordering};
use std::sync::Arc;

/// SIGINT's number (POSIX).
pub const SIGINT: usize = 2;
/// SIGTERM's number (POSIX).
pub const SIGTERM: usize = 15;

/// A request to stop, shared by the signal handlers and the work loops (cloning shares it).
///
/// `requested` holds the number of the signal that asked (0: none). `at_once`, when set, makes a
/// signal end the process immediately with 128 + its number: for stages with nothing left to save.
/// `row_budget` is a test hook: the request is made by itself after that many `row_done` calls.
#[derive(Clone, Debug, Default)]
pub struct Cancel {
    requested: Arc<AtomicUsize>,
    at_once: Arc<AtomicBool>,
    row_budget: Option<(Arc<AtomicUsize>, usize)>,
}

/// Why the handlers could not be installed.
#[derive(Debug, thiserror::Error)]
#[error("cannot install the SIGINT/SIGTERM handlers: {0}")]
pub struct InstallError(#[from] std::io::Error);

impl Cancel {
    /// A token no signal reaches (batch jobs, tests, library callers).
    pub fn never() -> Self {
        Cancel::default()
    }

    /// A token that requests a stop (as if by `signal`) after `rows` rows were reported done: a
    /// deterministic interruption for tests.
    pub fn after_rows(rows: usize, signal: usize) -> Self {
        Cancel { row_budget: Some((Arc::new(AtomicUsize::new(rows)), signal)), ..Default::default() }
    }

    /// Installs SIGINT and SIGTERM handlers that set this token. Until `exit_at_once(true)`, the
    /// process keeps running after a signal so that the work loops can save and stop; after it, a
    /// signal ends the process with 130 (SIGINT) or 143 (SIGTERM) at once.
    pub fn install_signal_handlers(&self) -> Result<(), InstallError> {
        for signal in [SIGINT, SIGTERM] {
            let number = signal as i32;
            // Registered first, so it sees `at_once` before the flag is set by the second action.
            signal_hook::flag::register_conditional_shutdown(number, 128 + number, self.at_once.clone())?;
            signal_hook::flag::register_usize(number, self.requested.clone(), signal)?;
        }
        Ok(())
    }

    /// Whether a stop was requested.
    pub fn is_requested(&self) -> bool {
        self.requested.load(Ordering::SeqCst) != 0
    }

    /// The signal that asked for the stop, if any.
    pub fn signal(&self) -> Option<usize> {
        match self.requested.load(Ordering::SeqCst) {
            0 => None,
            s => Some(s),
        }
    }

    /// Counts one finished row towards the test budget (`after_rows`); no effect otherwise.
    pub fn row_done(&self) {
        if let Some((budget, signal)) = &self.row_budget {
            let before = budget.fetch_update(Ordering::SeqCst, Ordering::SeqCst, |b| Some(b.saturating_sub(1)));
            if before == Ok(1) || before == Ok(0) {
                self.requested.store(*signal, Ordering::SeqCst);
            }
        }
    }

    /// Arms (or disarms) the immediate exit: while armed, a signal ends the process at once.
    pub fn exit_at_once(&self, armed: bool) {
        self.at_once.store(armed, Ordering::SeqCst);
    }
}

/// The exit code of a run stopped by `signal`: 128 + its number (130 for SIGINT, 143 for SIGTERM).
pub fn exit_code(signal: usize) -> i32 {
    128 + signal as i32
}

/// A signal's name for messages.
pub fn signal_name(signal: usize) -> &'static str {
    match signal {
        SIGINT => "SIGINT",
        SIGTERM => "SIGTERM",
        _ => "a signal",
    }
}
