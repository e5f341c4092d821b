//! A run from epoch to epoch: trace an epoch's chunks, fold them in chunk order, top
//! the direct light up, evaluate the error and the stop criteria, size the next epoch.

use super::engine::{next_schedule_point, Engine};
use super::{target_error, target_unreachable, Progress, RunOptions, RunSetup, RunState, Start};
use crate::criteria::Until;
use crate::distributed::Distributor;
use crate::scene::Scene;
use crate::stats::forecast::{forecast, HistoryPoint};
use crate::stats::stop::{min_hits, StopReason, Target};
use crate::tally::ChunkTally;
use crate::trace::direct::PILOT_REPLICATES;
use crate::trace::{Scratch, CHUNK_PHOTONS};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

thread_local! {
    /// A worker thread's batch buffers: reused by every chunk it traces (their contents
    /// never affect results).
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

/// A run between epochs: its record so far and how the next epoch is made.
pub(super) struct Epochs<'r, 's> {
    engine: &'r Engine<'s>,
    scene: &'s Scene,
    options: &'r RunOptions,
    pub(super) target: Target,
    distributor: Option<Box<dyn Distributor>>,
    /// This run traces photons `first_photon .. first_photon + max_photons`.
    first_photon: u64,
    max_photons: u64,
    /// Photons of the next epoch, and the threads of every process sharing it.
    epoch_photons: u64,
    workers: usize,
    pub(super) progress: Progress,
    /// Seconds traced before this process took the run over (a resumed run).
    pub(super) elapsed_before_s: f64,
    /// The fewest hits in a cell of the target after the last epoch, when `--min-hits`
    /// asks and the target is a receiver's.
    fewest_hits: Option<u64>,
    /// Chunk tallies reused from epoch to epoch (in chunk order, so the merge order
    /// never changes).
    buffers: Vec<ChunkTally>,
    /// Which of an epoch's chunks were traced before an interrupt.
    traced: Vec<bool>,
}

impl<'r, 's> Epochs<'r, 's> {
    /// The set-up: the record (a resumed run's, or empty) and the direct light's pilot
    /// (none for a shard, which leaves the direct light to the merge; a resumed run has
    /// it already).
    pub(super) fn set_up(
        engine: &'r Engine<'s>,
        scene: &'s Scene,
        options: &'r RunOptions,
        target: Target,
        max_photons: u64,
        start: Start,
    ) -> Epochs<'r, 's> {
        let shard = start.shard;
        let (first_photon, max_photons) = match shard {
            Some(s) => (s.first_photon, s.end_photon - s.first_photon),
            None => (0, max_photons),
        };
        // Every process's threads share an epoch's chunks.
        let processes = start.distributor.as_ref().map_or(1, |d| d.processes());
        let workers = engine.threads * processes;
        let mut progress = start
            .resumed
            .unwrap_or_else(|| Progress::fresh(engine.tracer.new_tallies()));
        progress.shard = shard;
        let pilot = if shard.is_some() { 0 } else { PILOT_REPLICATES };
        progress.times.direct_s += engine.add_direct(&mut progress.tallies, pilot);
        Epochs {
            engine,
            scene,
            options,
            target,
            distributor: start.distributor,
            first_photon,
            max_photons,
            epoch_photons: CHUNK_PHOTONS * workers as u64,
            workers,
            elapsed_before_s: progress.times.elapsed_s,
            progress,
            fewest_hits: None,
            buffers: Vec::new(),
            traced: Vec::new(),
        }
    }

    /// Traces the next epoch and folds it in (epochs end at every schedule point, so
    /// every run passes through them), then tops the direct light up (not for a shard);
    /// returns the photons traced. An `interrupt` during the epoch ends it early, after
    /// the chunks traced in order so far (as an epoch of that size would have).
    pub(super) fn trace(&mut self, interrupt: &AtomicBool) -> u64 {
        let done = self.progress.tallies.photons;
        let count = self
            .epoch_photons
            .min(self.max_photons - done)
            .min(next_schedule_point(done) - done);
        let (count, merge_start) = self.trace_chunks(self.first_photon + done, count, interrupt);
        let p = &mut self.progress;
        p.times.merge_s += merge_start.elapsed().as_secs_f64();
        if p.shard.is_none() {
            p.times.direct_s += self
                .engine
                .top_up_direct(&mut p.tallies, &mut p.direct_schedule);
        }
        count
    }

    /// Traces photons `first .. first + count` in fixed chunks (on this process's
    /// threads, or shared out by the distributor) and folds them into the tallies in
    /// chunk order (and, for a shard, their records into the chunk log); returns the
    /// photons folded and when the merge began. On this process's threads an
    /// `interrupt` leaves the chunks not yet started untraced, and only those before
    /// the first of them are folded (a Ctrl-C stops within a chunk's time, not an
    /// epoch's; the rest of the epoch's work is dropped).
    fn trace_chunks(&mut self, first: u64, count: u64, interrupt: &AtomicBool) -> (u64, Instant) {
        let chunks: Vec<(u64, u32)> = (0..count.div_ceil(CHUNK_PHOTONS))
            .map(|c| {
                let start = first + c * CHUNK_PHOTONS;
                (start, CHUNK_PHOTONS.min(first + count - start) as u32)
            })
            .collect();
        if self.buffers.len() < chunks.len() {
            self.buffers.resize_with(chunks.len(), ChunkTally::default);
        }
        let results = &mut self.buffers[..chunks.len()];
        let tracer = &self.engine.tracer;
        let pool = &self.engine.pool;
        let mut local = |chunks: &[(u64, u32)], results: &mut [ChunkTally]| {
            let mut traced = vec![false; chunks.len()];
            trace_on(
                pool,
                tracer,
                chunks,
                results,
                &mut traced,
                &AtomicBool::new(false),
            );
        };
        let kept = match self.distributor.as_deref_mut() {
            Some(d) => {
                d.trace(&chunks, results, &mut local);
                chunks.len()
            }
            None => {
                self.traced.clear();
                self.traced.resize(chunks.len(), false);
                trace_on(pool, tracer, &chunks, results, &mut self.traced, interrupt);
                self.traced.iter().take_while(|&&t| t).count()
            }
        };
        let merge_start = Instant::now();
        let mut folded = 0;
        for (chunk, &(_, n)) in results.iter().zip(&chunks).take(kept) {
            self.progress.fold_chunk(chunk, n);
            folded += n as u64;
        }
        (folded, merge_start)
    }

    /// The statistics after an epoch, `elapsed_s` into the run: the target's error into
    /// the history, with the forecast when there is an error target, and the fewest hits
    /// when `--min-hits` asks; then the stop check.
    pub(super) fn evaluate(
        &mut self,
        elapsed_s: f64,
        interrupt: &AtomicBool,
    ) -> Option<StopReason> {
        let stats_start = Instant::now();
        let scene = self.scene;
        let stop = &self.options.stop;
        self.progress.times.elapsed_s = elapsed_s;
        let tallies = &self.progress.tallies;
        let error = self.engine.pool.install(|| {
            target_error(
                scene,
                &self.target,
                tallies,
                self.engine.tracer.emitters.total_flux_lm,
                stop.absolute,
            )
        });
        let verdicts = self
            .engine
            .verdicts(scene, tallies, self.progress.shard.is_some());
        let point = HistoryPoint {
            elapsed_s,
            photons: tallies.photons,
            rel_error: error,
            forecast_s: None,
            forecast_photons: None,
            checks: verdicts.as_ref().map(|v| v.counts()),
        };
        let p = &mut self.progress;
        p.history.push(point);
        if let Some(goal) = stop.target_error {
            p.forecast = forecast(&p.history, goal);
            let last = p.history.last_mut().expect("pushed above");
            last.forecast_s = p.forecast.map(|f| f.total_s);
            last.forecast_photons = p.forecast.map(|f| f.photons);
        }
        // One pass over the target's cells, read by the stop check and the next
        // epoch's size.
        self.fewest_hits = match (stop.min_hits, self.target.receiver()) {
            (Some(_), Some(r)) => Some(min_hits(
                &self.target,
                &scene.receivers,
                p.tallies.receiver_cells(&scene.receivers, r),
            )),
            _ => None,
        };
        let unreachable = stop.stop_if_unreachable
            && target_unreachable(scene, self.options, &self.target, p).is_some();
        // The budgets first: a run at its limit stopped on it, whatever the forecast.
        let decided = verdicts.is_some_and(|v| v.decided());
        let reason = self
            .stop_reason(error, decided, elapsed_s, interrupt)
            .or(unreachable.then_some(StopReason::Unreachable));
        self.progress.times.stats_s += stats_start.elapsed().as_secs_f64();
        reason
    }

    /// The first stop criterion met after an epoch, if any (the target's `error` now,
    /// whether every check is `decided` now).
    fn stop_reason(
        &self,
        error: f64,
        decided: bool,
        elapsed_s: f64,
        interrupt: &AtomicBool,
    ) -> Option<StopReason> {
        let stop = &self.options.stop;
        if stop.target_error.is_some_and(|goal| error <= goal) {
            Some(StopReason::TargetError)
        } else if decided && stop.until == Some(Until::Decided) {
            Some(StopReason::Decided)
        } else if stop
            .min_hits
            .is_some_and(|n| self.fewest_hits.is_some_and(|h| h >= n))
        {
            Some(StopReason::MinHits)
        } else if self.progress.tallies.photons >= self.max_photons {
            Some(StopReason::Photons)
        } else if stop.time_limit_s.is_some_and(|t| elapsed_s >= t) {
            Some(StopReason::Time)
        } else if interrupt.load(Ordering::Relaxed) {
            Some(StopReason::Interrupted)
        } else {
            None
        }
    }

    /// The photon count at which a stop is predicted: the error forecast's, or the
    /// projection of `--min-hits` (hits grow in proportion to photons), whichever is
    /// nearer.
    fn goal_photons(&self) -> Option<u64> {
        let photons = self.progress.tallies.photons;
        let hits_goal = self.options.stop.min_hits.and_then(|n| {
            let fewest = self.fewest_hits?;
            (fewest > 0).then(|| (photons as f64 * n as f64 / fewest as f64) as u64)
        });
        [self.progress.forecast.map(|f| f.photons), hits_goal]
            .into_iter()
            .flatten()
            .min()
    }

    /// Sizes the next epoch from the last one's `count` photons in `epoch_s` seconds.
    pub(super) fn size_next_epoch(&mut self, count: u64, epoch_s: f64, elapsed_s: f64) {
        self.epoch_photons = next_epoch_photons(
            self.progress.tallies.photons,
            count,
            epoch_s,
            elapsed_s,
            self.options.stop.time_limit_s,
            self.goal_photons(),
            self.workers,
        );
    }

    /// The state after an epoch, for the observer.
    pub(super) fn state<'a>(
        &'a self,
        setup: &'a RunSetup,
        stop_reason: Option<StopReason>,
    ) -> RunState<'a> {
        RunState {
            scene: self.scene,
            options: self.options,
            setup,
            target: &self.target,
            progress: &self.progress,
            stop_reason,
        }
    }
}

/// Epoch sizing: each epoch lasts about a quarter of the time run so far (so the first
/// forecast comes within the first percent of a long run and merging stays a small
/// share), between 0.05 s and 2 s, and never runs past the time limit by much. When a
/// stop is predicted within that span (`goal_photons`: the forecast of the error target,
/// or the projection of `--min-hits`), the epoch ends there instead, but never advances
/// less than 1 % of the photons so far: runs stop within about 1 % of the photons their
/// target needs.
fn next_epoch_photons(
    done: u64,
    last_count: u64,
    last_epoch_s: f64,
    elapsed_s: f64,
    time_limit_s: Option<f64>,
    goal_photons: Option<u64>,
    threads: usize,
) -> u64 {
    let rate = last_count as f64 / last_epoch_s.max(1e-6);
    let mut duration = (elapsed_s * 0.25).clamp(0.05, 2.0);
    if let Some(limit) = time_limit_s {
        duration = duration.min((limit - elapsed_s).max(0.0));
    }
    let mut photons = rate * duration;
    if let Some(goal) = goal_photons {
        let to_goal = goal.saturating_sub(done) as f64;
        photons = photons.min(to_goal.max(0.01 * done as f64));
    }
    let chunks = (photons / CHUNK_PHOTONS as f64).ceil() as u64;
    // At least a chunk per thread: a smaller epoch leaves threads idle.
    chunks.clamp(threads as u64, 1 << 16) * CHUNK_PHOTONS
}

/// Traces `chunks` into `results` on `pool`, marking each chunk traced in `traced`; once
/// `interrupt` is set, chunks not yet started stay untraced.
fn trace_on(
    pool: &rayon::ThreadPool,
    tracer: &crate::trace::Tracer<'_>,
    chunks: &[(u64, u32)],
    results: &mut [ChunkTally],
    traced: &mut [bool],
    interrupt: &AtomicBool,
) {
    pool.install(|| {
        (chunks.par_iter().zip(results.par_iter_mut()))
            .zip(traced.par_iter_mut())
            .for_each(|((&(first, n), tally), traced)| {
                if interrupt.load(Ordering::Relaxed) {
                    return;
                }
                SCRATCH
                    .with_borrow_mut(|scratch| tracer.trace_chunk_into(first, n, scratch, tally));
                *traced = true;
            })
    });
}
