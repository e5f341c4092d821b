//! Progress of the command line's long steps on stderr (a module of the `luxtally`
//! binary, not of the library). On a terminal: a live indicatif bar redrawn in place.
//! Otherwise (a log file, a pipe, CI): a plain line every [`LINE_EVERY_S`] seconds and
//! one at the end, never a carriage return. With `--quiet`: nothing.

use indicatif::{ProgressBar, ProgressDrawTarget, ProgressStyle};
use std::io::IsTerminal;
use std::sync::atomic::{AtomicU64, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

/// Seconds between two plain progress lines when stderr is not a terminal.
pub const LINE_EVERY_S: f64 = 5.0;

/// How often a live bar redraws itself (its spinner and elapsed time move between
/// updates too).
const TICK: Duration = Duration::from_millis(200);

/// The bar of a run (thousandths of the run; the message is the progress line), of a
/// render (pixels) and the spinner of a benchmark measurement, in indicatif's syntax.
pub const RUN_TEMPLATE: &str = "{spinner} {bar:10} {wide_msg}";
pub const RENDER_TEMPLATE: &str =
    "{spinner} render {bar:20} {percent:>3} %  {elapsed} elapsed, ~{eta} to go";
const SPINNER_TEMPLATE: &str = "{spinner} {elapsed:>4} {wide_msg}";

/// A step's progress: `len` units of work (per mille of a run, pixels of a render).
pub struct Progress {
    mode: Mode,
    /// Units done (the bar keeps its own on a terminal).
    done: AtomicU64,
}

enum Mode {
    Quiet,
    Live(ProgressBar),
    /// When the last plain line was printed (or the step started).
    Lines(Mutex<Instant>),
}

impl Progress {
    /// A bar of `len` units drawn with `template` (indicatif's syntax) on a terminal,
    /// plain lines elsewhere, nothing when `quiet`.
    pub fn new(quiet: bool, len: u64, template: &str) -> Progress {
        let mode = if quiet {
            Mode::Quiet
        } else if std::io::stderr().is_terminal() {
            Mode::Live(live_bar(len, template))
        } else {
            Mode::Lines(Mutex::new(Instant::now()))
        };
        Progress {
            mode,
            done: AtomicU64::new(0),
        }
    }

    /// A spinner with a message on a terminal, nothing elsewhere: for steps whose
    /// results are printed anyway (the bench commands).
    pub fn spinner() -> Progress {
        let mode = if std::io::stderr().is_terminal() {
            Mode::Live(live_bar(0, SPINNER_TEMPLATE))
        } else {
            Mode::Quiet
        };
        Progress {
            mode,
            done: AtomicU64::new(0),
        }
    }

    /// Sets the units done to `done` and the text: the bar's message on a terminal,
    /// the plain line (when one is due) elsewhere.
    pub fn set(&self, done: u64, line: impl FnOnce() -> String) {
        self.done.store(done, Ordering::Relaxed);
        match &self.mode {
            Mode::Quiet => {}
            Mode::Live(bar) => {
                bar.set_position(done);
                bar.set_message(line());
            }
            Mode::Lines(last) => print_if_due(last, line),
        }
    }

    /// Adds `units` done (from any thread); `line` gets the units done so far and makes
    /// the plain line when one is due (the bar draws its own).
    pub fn inc(&self, units: u64, line: impl FnOnce(u64) -> String) {
        let done = self.done.fetch_add(units, Ordering::Relaxed) + units;
        match &self.mode {
            Mode::Quiet => {}
            Mode::Live(bar) => bar.inc(units),
            Mode::Lines(last) => print_if_due(last, || line(done)),
        }
    }

    /// The message of a spinner.
    pub fn message(&self, text: String) {
        if let Mode::Live(bar) = &self.mode {
            bar.set_message(text);
        }
    }

    /// A line of its own, above a live bar (plain elsewhere; nothing when quiet).
    pub fn println(&self, text: String) {
        match &self.mode {
            Mode::Quiet => {}
            Mode::Live(bar) => bar.println(text),
            Mode::Lines(_) => eprintln!("{text}"),
        }
    }

    /// Ends the step with `line`: left on the terminal (the bar full when `complete`,
    /// else where it stopped), printed as the last plain line elsewhere.
    pub fn finish(&self, complete: bool, line: String) {
        match &self.mode {
            Mode::Quiet => {}
            Mode::Live(bar) => {
                if complete {
                    bar.finish_with_message(line);
                } else {
                    bar.abandon_with_message(line);
                }
                // The bar leaves the cursor on its line: what follows starts below it.
                eprintln!();
            }
            Mode::Lines(_) => eprintln!("{line}"),
        }
    }

    /// Removes a spinner (what it measured is printed next).
    pub fn clear(&self) {
        if let Mode::Live(bar) = &self.mode {
            bar.finish_and_clear();
        }
    }
}

fn live_bar(len: u64, template: &str) -> ProgressBar {
    let bar = ProgressBar::with_draw_target(Some(len), ProgressDrawTarget::stderr());
    // The templates are constants of this binary (tested): never fails in practice.
    let style = ProgressStyle::with_template(template)
        .unwrap_or_else(|_| ProgressStyle::default_bar())
        .progress_chars("=> ");
    bar.set_style(style);
    bar.enable_steady_tick(TICK);
    bar
}

/// Prints `line` when [`LINE_EVERY_S`] have passed since the last line (or the start).
fn print_if_due(last: &Mutex<Instant>, line: impl FnOnce() -> String) {
    // A worker that finds another printing skips its turn: lines are only periodic.
    let Ok(mut last) = last.try_lock() else {
        return;
    };
    if last.elapsed().as_secs_f64() >= LINE_EVERY_S {
        *last = Instant::now();
        eprintln!("{}", line());
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn templates_are_valid() {
        for t in [RUN_TEMPLATE, RENDER_TEMPLATE, SPINNER_TEMPLATE] {
            assert!(ProgressStyle::with_template(t).is_ok(), "{t}");
        }
    }
}
