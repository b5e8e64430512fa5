//! Progress reporting: the only user of indicatif. On a terminal, bars go to standard error; when
//! standard error is not a terminal (batch jobs, CI, cluster schedulers), each long stage prints a log
//! line about every ten seconds instead. `--quiet` silences both; with `-v` each stage ends with a
//! one-line summary.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::{IsTerminal, Write};
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::mpsc::{self, RecvTimeoutError, Sender};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

/// How much the user wants to see.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Verbosity {
    Quiet,
    #[default]
    Normal,
    Verbose,
}

/// Where log lines go when no bar is drawn: standard error, or a buffer (tests).
pub type LogSink = Arc<Mutex<dyn Write + Send>>;

/// Seconds between two log lines of one stage when standard error is not a terminal.
pub const LOG_INTERVAL: Duration = Duration::from_secs(10);

/// Periodic log lines for non-terminal output.
#[derive(Clone)]
struct LogLines {
    interval: Duration,
    sink: LogSink,
}

/// The set of bars (or log lines) of one run.
#[derive(Clone)]
pub struct Progress {
    multi: MultiProgress,
    draw: bool,
    log: Option<LogLines>,
    verbosity: Verbosity,
}

impl Progress {
    /// Bars on a terminal; log lines every [`LOG_INTERVAL`] otherwise; nothing when quiet.
    pub fn new(verbosity: Verbosity) -> Self {
        let terminal = std::io::stderr().is_terminal();
        let draw = verbosity != Verbosity::Quiet && terminal;
        let target = if draw { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        let log = (verbosity != Verbosity::Quiet && !terminal)
            .then(|| LogLines { interval: LOG_INTERVAL, sink: Arc::new(Mutex::new(std::io::stderr())) });
        Progress { multi: MultiProgress::with_draw_target(target), draw, log, verbosity }
    }

    /// No bars; a log line per long stage every `interval`, written to `sink`.
    pub fn logging(verbosity: Verbosity, interval: Duration, sink: LogSink) -> Self {
        let multi = MultiProgress::with_draw_target(ProgressDrawTarget::hidden());
        Progress { multi, draw: false, log: Some(LogLines { interval, sink }), verbosity }
    }

    /// Draws nothing and prints nothing (library use, tests).
    pub fn hidden() -> Self {
        Progress {
            multi: MultiProgress::with_draw_target(ProgressDrawTarget::hidden()),
            draw: false,
            log: None,
            verbosity: Verbosity::Quiet,
        }
    }

    pub fn verbosity(&self) -> Verbosity {
        self.verbosity
    }

    /// A bar (or a logged stage) with `total` steps of `unit` (elements, sweeps, tiles, jobs).
    pub fn stage(&self, name: &str, total: u64, unit: &str) -> Stage {
        let bar = if self.draw {
            let bar = self.multi.add(ProgressBar::new(total));
            let template =
                format!("{{prefix:>13}} [{{bar:30}}] {{pos}}/{{len}} {unit} ({{per_sec}}, ETA {{eta}}) {{msg}}");
            if let Ok(style) = ProgressStyle::with_template(&template) {
                bar.set_style(style.progress_chars("=> "));
            }
            bar.set_prefix(name.to_string());
            bar.enable_steady_tick(Duration::from_millis(200));
            bar
        } else {
            ProgressBar::hidden()
        };
        let start = Instant::now();
        let state = Arc::new(StageState { position: AtomicU64::new(0), message: Mutex::new(String::new()) });
        let ticker = self.log.as_ref().map(|log| {
            let line = LineParts { name: name.to_string(), unit: unit.to_string(), total, start };
            Ticker::start(log.clone(), line, Arc::clone(&state))
        });
        Stage { bar, name: name.to_string(), start, verbose: self.verbosity == Verbosity::Verbose, state, ticker }
    }

    /// A message above the bars (warnings); shown unless quiet.
    pub fn note(&self, message: &str) {
        if self.verbosity != Verbosity::Quiet {
            self.multi.suspend(|| eprintln!("{message}"));
        }
    }
}

/// What worker threads update and the log ticker reads.
struct StageState {
    position: AtomicU64,
    message: Mutex<String>,
}

/// The fixed parts of a stage's log line.
struct LineParts {
    name: String,
    unit: String,
    total: u64,
    start: Instant,
}

/// The log line of a stage: `name: 45% (123/456 unit), 12 s elapsed, ETA 15 s [message]`.
/// The ETA assumes the remaining steps take as long as the finished ones: t·(total − done)/done.
fn log_line(parts: &LineParts, done: u64, elapsed: Duration, message: &str) -> String {
    let seconds = elapsed.as_secs_f64();
    let percent = if parts.total > 0 { 100.0 * done as f64 / parts.total as f64 } else { 0.0 };
    let eta = if done > 0 && done <= parts.total {
        format!("ETA {:.0} s", seconds * (parts.total - done) as f64 / done as f64)
    } else {
        "ETA unknown".to_string()
    };
    let message = if message.is_empty() { String::new() } else { format!(" {message}") };
    format!(
        "{}: {percent:.0}% ({done}/{} {}), {seconds:.0} s elapsed, {eta}{message}",
        parts.name, parts.total, parts.unit
    )
}

/// A thread that writes a stage's log line every interval until the stage ends.
struct Ticker {
    stop: Sender<()>,
    thread: JoinHandle<()>,
}

impl Ticker {
    fn start(log: LogLines, parts: LineParts, state: Arc<StageState>) -> Ticker {
        let (stop, stopped) = mpsc::channel::<()>();
        let thread = std::thread::spawn(move || {
            while let Err(RecvTimeoutError::Timeout) = stopped.recv_timeout(log.interval) {
                let done = state.position.load(Ordering::Relaxed);
                let message = state.message.lock().map(|m| m.clone()).unwrap_or_default();
                let line = log_line(&parts, done, parts.start.elapsed(), &message);
                if let Ok(mut sink) = log.sink.lock() {
                    let _ = writeln!(sink, "{line}");
                }
            }
        });
        Ticker { stop, thread }
    }

    fn stop(self) {
        let _ = self.stop.send(());
        let _ = self.thread.join();
    }
}

/// One long stage's bar. `Stage` is `Sync`: worker threads tick it.
pub struct Stage {
    bar: ProgressBar,
    name: String,
    start: Instant,
    verbose: bool,
    state: Arc<StageState>,
    ticker: Option<Ticker>,
}

impl Stage {
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
        self.state.position.fetch_add(n, Ordering::Relaxed);
    }

    pub fn set_position(&self, n: u64) {
        self.bar.set_position(n);
        self.state.position.store(n, Ordering::Relaxed);
    }

    pub fn set_message(&self, message: String) {
        if self.ticker.is_some() {
            if let Ok(mut m) = self.state.message.lock() {
                m.clone_from(&message);
            }
        }
        self.bar.set_message(message);
    }

    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }

    /// Removes the bar; with `-v` prints `name: summary (seconds)`.
    pub fn finish(mut self, summary: &str) -> Duration {
        if let Some(ticker) = self.ticker.take() {
            ticker.stop();
        }
        self.bar.finish_and_clear();
        let elapsed = self.start.elapsed();
        if self.verbose {
            eprintln!("{:>13}: {summary} ({:.2} s)", self.name, elapsed.as_secs_f64());
        }
        elapsed
    }
}

impl Drop for Stage {
    fn drop(&mut self) {
        if let Some(ticker) = self.ticker.take() {
            ticker.stop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_line_gives_percentage_elapsed_and_eta() {
        let parts =
            LineParts { name: "form factors".into(), unit: "elements".into(), total: 400, start: Instant::now() };
        let line = log_line(&parts, 100, Duration::from_secs(10), "");
        assert_eq!(line, "form factors: 25% (100/400 elements), 10 s elapsed, ETA 30 s");
        let line = log_line(&parts, 0, Duration::from_secs(3), "warming up");
        assert_eq!(line, "form factors: 0% (0/400 elements), 3 s elapsed, ETA unknown warming up");
    }

    #[test]
    fn a_logged_stage_writes_lines_while_it_runs_and_none_after() {
        let buffer = Arc::new(Mutex::new(Vec::<u8>::new()));
        let progress = Progress::logging(Verbosity::Normal, Duration::from_millis(20), buffer.clone());
        let stage = progress.stage("solving", 10, "sweeps");
        stage.set_position(5);
        // Wait for two lines (at most 5 s, so a loaded machine cannot make this flaky).
        let waited = Instant::now();
        while String::from_utf8_lossy(&buffer.lock().unwrap()).lines().count() < 2 && waited.elapsed().as_secs() < 5 {
            std::thread::sleep(Duration::from_millis(5));
        }
        stage.finish("done");
        let lines_at_finish = String::from_utf8(buffer.lock().unwrap().clone()).unwrap().lines().count();
        std::thread::sleep(Duration::from_millis(80));
        let text = String::from_utf8(buffer.lock().unwrap().clone()).unwrap();
        assert!(lines_at_finish >= 2, "expected periodic lines, got {text:?}");
        assert_eq!(text.lines().count(), lines_at_finish, "a finished stage must stop logging");
        assert!(text.lines().all(|l| l.starts_with("solving: 50% (5/10 sweeps)")), "{text}");
    }

    #[test]
    fn quiet_and_hidden_progress_log_nothing() {
        let progress = Progress::hidden();
        let stage = progress.stage("x", 1, "steps");
        assert!(stage.ticker.is_none());
    }
}
