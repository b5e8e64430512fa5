//! Progress reporting: the only user of indicatif. Bars go to standard error, only when it is a
//! terminal and not `--quiet`; with `-v` each stage ends with a one-line summary.

use indicatif::{MultiProgress, ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::time::{Duration, Instant};

/// How much the user wants to see.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Verbosity {
    Quiet,
    #[default]
    Normal,
    Verbose,
}

/// The set of bars of one run.
#[derive(Clone)]
pub struct Progress {
    multi: MultiProgress,
    draw: bool,
    verbosity: Verbosity,
}

impl Progress {
    pub fn new(verbosity: Verbosity) -> Self {
        let draw = verbosity != Verbosity::Quiet && std::io::stderr().is_terminal();
        let target = if draw { ProgressDrawTarget::stderr() } else { ProgressDrawTarget::hidden() };
        Progress { multi: MultiProgress::with_draw_target(target), draw, verbosity }
    }

    /// Draws nothing and prints nothing (library use, tests).
    pub fn hidden() -> Self {
        Progress {
            multi: MultiProgress::with_draw_target(ProgressDrawTarget::hidden()),
            draw: false,
            verbosity: Verbosity::Quiet,
        }
    }

    pub fn verbosity(&self) -> Verbosity {
        self.verbosity
    }

    /// A bar for a stage with `total` steps of `unit` (elements, sweeps, tiles, jobs).
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
        Stage { bar, name: name.to_string(), start: Instant::now(), verbose: self.verbosity == Verbosity::Verbose }
    }

    /// A message above the bars (warnings); shown unless quiet.
    pub fn note(&self, message: &str) {
        if self.verbosity != Verbosity::Quiet {
            self.multi.suspend(|| eprintln!("{message}"));
        }
    }
}

/// One long stage's bar. `Stage` is `Sync`: worker threads tick it.
pub struct Stage {
    bar: ProgressBar,
    name: String,
    start: Instant,
    verbose: bool,
}

impl Stage {
    pub fn inc(&self, n: u64) {
        self.bar.inc(n);
    }

    pub fn set_position(&self, n: u64) {
        self.bar.set_position(n);
    }

    pub fn set_message(&self, message: String) {
        self.bar.set_message(message);
    }

    pub fn elapsed(&self) -> Duration {
        self.start.elapsed()
    }

    /// Removes the bar; with `-v` prints `name: summary (seconds)`.
    pub fn finish(self, summary: &str) -> Duration {
        self.bar.finish_and_clear();
        let elapsed = self.start.elapsed();
        if self.verbose {
            eprintln!("{:>13}: {summary} ({:.2} s)", self.name, elapsed.as_secs_f64());
        }
        elapsed
    }
}
