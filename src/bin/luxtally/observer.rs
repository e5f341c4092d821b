//! What `run` shows and saves while the photon pass runs: the progress line on stderr, a
//! summary.json every few seconds (a long run never loses the work already done), the
//! live report and the checkpoints.

use crate::progress::{self, Progress};
use crate::run::RunArgs;
use luxtally::checkpoint::Checkpointer;
use luxtally::output::{save_summary, summary};
use luxtally::run::{Observer, RunState};
use luxtally::scene::Scene;
use luxtally::stats::stop::StopReason;
use luxtally::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

pub struct CliObserver {
    progress: Progress,
    out: PathBuf,
    last_save: Instant,
    /// The first save that failed: the run goes on, the command fails at its end.
    save_error: Option<Error>,
    /// `--report-every`: report.html is rewritten this often during the run.
    report_every_s: Option<f64>,
    last_report: Option<Instant>,
    checkpoints: Checkpointer,
}

const SAVE_EVERY_S: f64 = 10.0;

/// A run's progress bar counts thousandths of the run.
const PER_MILLE: u64 = 1000;

impl CliObserver {
    /// The observer of a run of `scene` writing into `out`, as `args` ask.
    pub fn new(args: &RunArgs, scene: &Scene, out: &Path) -> CliObserver {
        CliObserver {
            progress: Progress::new(args.quiet, PER_MILLE, progress::RUN_TEMPLATE),
            out: out.to_path_buf(),
            last_save: Instant::now(),
            save_error: None,
            report_every_s: args.report_every,
            last_report: None,
            checkpoints: Checkpointer::new(out, args.checkpoint_every, scene),
        }
    }

    /// Ends the progress line at the run's final `state`, with what the checkpoints
    /// cost; the first save that failed, if one did.
    pub fn finish(self, state: &RunState<'_>) -> Result<()> {
        let c = &self.checkpoints;
        if let Some(cost) = c.last_cost {
            self.progress.println(format!(
                "checkpoint: {:.1} MB written in {:.3} s; the run waited {:.3} s \
                 for it, {:.3} s for all {} saves",
                cost.bytes as f64 / 1e6,
                cost.written_s,
                cost.waited_s,
                c.total_s,
                c.saves
            ));
        }
        let interrupted = state.stop_reason == Some(StopReason::Interrupted);
        self.progress.finish(!interrupted, progress_line(state));
        self.save_error.map_or(Ok(()), Err)
    }
}

impl Observer for CliObserver {
    fn epoch(&mut self, state: &RunState<'_>) {
        self.progress.set(per_mille(state), || progress_line(state));
        // A shard's tallies alone are no result: its checkpoint is its only output.
        let shard = state.progress.shard.is_some();
        if !shard
            && state.stop_reason.is_none()
            && self.last_save.elapsed().as_secs_f64() >= SAVE_EVERY_S
        {
            self.last_save = Instant::now();
            if let Err(e) = save_summary(&self.out, &summary::build(state)) {
                self.save_error.get_or_insert(e);
            }
        }
        if let Err(e) = self.checkpoints.epoch(state) {
            self.save_error.get_or_insert(e);
        }
        if let Some(every) = self.report_every_s {
            let due = self
                .last_report
                .is_none_or(|t| t.elapsed().as_secs_f64() >= every);
            if !shard && state.stop_reason.is_none() && due {
                self.last_report = Some(Instant::now());
                let written = luxtally::output::write_live_report(&self.out, state, every);
                if let Err(e) = written {
                    self.save_error.get_or_insert(e);
                }
            }
        }
    }
}

/// Seconds until the run's first stop criterion is met, as far as they can be told: the
/// accuracy forecast, the photons left at the current rate, the time limit.
fn remaining_s(state: &RunState<'_>) -> Option<f64> {
    let rate = state.progress.tallies.photons as f64 / state.progress.times.elapsed_s.max(1e-9);
    let by_forecast = state
        .progress
        .forecast
        .map(|f| f.total_s - state.progress.times.elapsed_s);
    let by_photons = state
        .options
        .stop
        .photons
        .map(|n| n.saturating_sub(state.progress.tallies.photons) as f64 / rate);
    let by_time = state
        .options
        .stop
        .time_limit_s
        .map(|t| t - state.progress.times.elapsed_s);
    [by_forecast, by_photons, by_time]
        .into_iter()
        .flatten()
        .filter(|s| !s.is_nan())
        .reduce(f64::min)
        .map(|s| s.max(0.0))
}

/// The progress line: elapsed time, the target's error → its goal and when the run
/// should end first (what a narrow terminal cuts is the rest: photons, ray rate).
fn progress_line(state: &RunState<'_>) -> String {
    let error = state
        .progress
        .history
        .last()
        .map_or(f64::NAN, |p| p.rel_error);
    let unit = if state.options.stop.absolute {
        ""
    } else {
        " %"
    };
    let scale = if state.options.stop.absolute {
        1.0
    } else {
        100.0
    };
    let goal = state
        .options
        .stop
        .target_error
        .map(|g| format!(" → {:.3}{unit}", g * scale))
        .unwrap_or_default();
    let eta = match (state.stop_reason, remaining_s(state)) {
        (Some(reason), _) => format!(", stopped on {}", reason.as_str()),
        (None, Some(r)) => format!(", done in ~{r:.1} s"),
        (None, None) => String::new(),
    };
    let unreachable =
        luxtally::run::target_unreachable(state.scene, state.options, state.target, state.progress)
            .map(|why| format!(", target unreachable: {why}"))
            .unwrap_or_default();
    format!(
        "{:.1} s  {}: {:.3}{unit}{goal}{eta}{unreachable}  {} photons  {:.1} Mrays/s",
        state.progress.times.elapsed_s,
        state.target.describe(&state.scene.receivers),
        error * scale,
        state.progress.tallies.photons,
        state.progress.tallies.rays as f64 / state.progress.times.elapsed_s.max(1e-9) / 1e6,
    )
}

/// How far the run is, in thousandths, by its nearest stop criterion.
fn per_mille(state: &RunState<'_>) -> u64 {
    match remaining_s(state) {
        Some(r) => {
            (PER_MILLE as f64 * state.progress.times.elapsed_s
                / (state.progress.times.elapsed_s + r).max(1e-9)) as u64
        }
        None => 0,
    }
}
