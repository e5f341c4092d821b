//! A run: epochs of photons traced in parallel, merged in photon order, evaluated,
//! forecast and checked against the stop criteria; everything traced is in the result.

use crate::accel::{self, Backend, Bvh, RayCaster};
use crate::criteria::{self, StopCriteria};
use crate::distributed::Distributor;
use crate::scene::{Estimator, Scene};
use crate::stats::forecast::{forecast, Forecast, HistoryPoint};
use crate::stats::stop::{min_hits, receiver_target_error, unreachable, StopReason, Target};
use crate::stats::{map_stats, MapKind};
use crate::tally::{ChunkTally, Tallies};
use crate::trace::direct::{
    relative_variances, replicate_floor, samples_per_replicate, DirectSchedule, PILOT_REPLICATES,
};
use crate::trace::{Scratch, Tracer, CHUNK_PHOTONS};
use crate::{Error, Result};
use rayon::prelude::*;
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::Instant;

mod start;
pub use start::{ChunkRecord, Resumed, ShardRange, Start};

thread_local! {
    /// A worker thread's batch buffers: reused by every chunk it traces (their contents
    /// never affect results).
    static SCRATCH: std::cell::RefCell<Scratch> = std::cell::RefCell::new(Scratch::default());
}

pub use crate::criteria::DEFAULT_PHOTONS;

/// How a run is made and when it stops.
#[derive(Clone, Debug)]
pub struct RunOptions {
    pub stop: StopCriteria,
    pub seed: u64,
    pub threads: usize,
    pub backend: Backend,
    /// Which BVH the backend builds (`--bvh`).
    pub bvh: Bvh,
    /// Overrides every receiver's `estimator` (`--estimator`).
    pub estimator: Option<Estimator>,
}

impl RunOptions {
    /// The scene's `[simulation]` settings, for the command line to override.
    pub fn from_scene(scene: &Scene) -> RunOptions {
        RunOptions {
            stop: scene.simulation.stop.clone(),
            seed: scene.simulation.seed,
            threads: std::thread::available_parallelism().map_or(1, |n| n.get()),
            backend: Backend::Embree,
            bvh: Bvh::Auto,
            estimator: None,
        }
    }

    /// [`RunOptions::from_scene`] stopping at `photons` (and on the scene's other
    /// criteria).
    pub fn with_photons(scene: &Scene, photons: u64) -> RunOptions {
        let mut options = RunOptions::from_scene(scene);
        options.stop.photons = Some(photons);
        options
    }
}

/// Called after every epoch with the run's state (progress display, periodic saving).
pub trait Observer {
    fn epoch(&mut self, state: &RunState<'_>);
}

impl Observer for () {
    fn epoch(&mut self, _: &RunState<'_>) {}
}

/// What a run settles before its first photon, constant while it runs.
#[derive(Clone, Debug)]
pub struct RunSetup {
    /// Seconds before the photon pass: BVH build and deterministic direct light.
    pub setup_s: f64,
    pub total_flux_lm: f64,
    pub light_flux_lm: Vec<f64>,
    pub bounce_cap: u32,
    /// ρ_max^cap, the a-priori bound on the light the cap drops; `None` for lossless
    /// materials (`trace::bounce_cap_a_priori_bound`).
    pub bounce_cap_a_priori: Option<f64>,
    pub threads: usize,
    /// Per receiver: what `auto` (or `--estimator`) resolved to.
    pub estimators: Vec<Estimator>,
}

impl RunSetup {
    /// What `tracer` settled, `setup` being when the run's set-up began.
    pub(crate) fn new(setup: Instant, tracer: &Tracer<'_>, threads: usize) -> RunSetup {
        RunSetup {
            setup_s: setup.elapsed().as_secs_f64(),
            total_flux_lm: tracer.emitters.total_flux_lm,
            light_flux_lm: tracer.emitters.flux_lm.clone(),
            bounce_cap: tracer.max_bounces,
            bounce_cap_a_priori: tracer.bounce_cap_a_priori,
            threads,
            estimators: tracer.receivers.iter().map(|g| g.estimator).collect(),
        }
    }
}

/// A pool of `threads` workers for a run's chunks (or a render's tiles).
pub fn thread_pool(threads: usize) -> Result<rayon::ThreadPool> {
    rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build()
        .map_err(|e| Error::Unsupported(format!("cannot start {threads} threads: {e}")))
}

/// Makes rayon's global pool `threads` wide, so that work outside a run's own pool
/// (loading, writing the outputs, merging shards) keeps to `--threads` as well; only a
/// call before anything used the global pool counts.
pub fn limit_global_threads(threads: usize) {
    let _ = rayon::ThreadPoolBuilder::new()
        .num_threads(threads)
        .build_global();
}

/// The state of a run after an epoch.
pub struct RunState<'a> {
    pub scene: &'a Scene,
    pub options: &'a RunOptions,
    pub setup: &'a RunSetup,
    pub target: &'a Target,
    pub tallies: &'a Tallies,
    pub history: &'a [HistoryPoint],
    pub forecast: Option<Forecast>,
    pub elapsed_s: f64,
    /// Seconds spent on statistics, forecasts and stop checks, on merging the chunks'
    /// tallies and on the next-event receivers' direct light (all epochs; the direct
    /// light's pilot replicates count in `setup.setup_s` too).
    pub stats_s: f64,
    pub merge_s: f64,
    pub direct_s: f64,
    /// Set on the last epoch.
    pub stop_reason: Option<StopReason>,
    /// What a checkpoint needs besides the tallies (see `checkpoint`).
    pub resumable: Resumable<'a>,
}

/// The state a checkpoint saves besides the tallies and history: the direct light's
/// schedule and, for a shard, its range and per-chunk partials.
#[derive(Clone, Copy)]
pub struct Resumable<'a> {
    pub direct_per_photon: f64,
    pub shard: Option<ShardRange>,
    pub chunks: &'a [ChunkRecord],
}

/// What a finished run hands to the outputs.
pub struct RunResult {
    pub setup: RunSetup,
    pub tallies: Tallies,
    pub history: Vec<HistoryPoint>,
    pub forecast: Option<Forecast>,
    pub target: Target,
    pub stop_reason: StopReason,
    pub elapsed_s: f64,
    pub stats_s: f64,
    pub merge_s: f64,
    pub direct_s: f64,
    pub direct_per_photon: f64,
    pub shard: Option<ShardRange>,
    pub chunks: Vec<ChunkRecord>,
}

impl RunResult {
    /// The finished run seen as its last state, for the outputs.
    pub fn state<'a>(&'a self, scene: &'a Scene, options: &'a RunOptions) -> RunState<'a> {
        RunState {
            scene,
            options,
            setup: &self.setup,
            target: &self.target,
            tallies: &self.tallies,
            history: &self.history,
            forecast: self.forecast,
            elapsed_s: self.elapsed_s,
            stats_s: self.stats_s,
            merge_s: self.merge_s,
            direct_s: self.direct_s,
            stop_reason: Some(self.stop_reason),
            resumable: Resumable {
                direct_per_photon: self.direct_per_photon,
                shard: self.shard,
                chunks: &self.chunks,
            },
        }
    }
}

/// Runs the photon pass until a stop criterion is met or `interrupt` is set.
pub fn run(
    scene: &Scene,
    options: &RunOptions,
    interrupt: &AtomicBool,
    observer: &mut dyn Observer,
) -> Result<RunResult> {
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    run_from(
        scene,
        options,
        caster.as_ref(),
        setup,
        interrupt,
        observer,
        Start::default(),
    )
}

/// [`run`] over a ray caster already built (`setup` is when building started), from a
/// checkpoint's state (`start.resumed`) and/or over a shard's photon range only (`start.shard`: no direct light, chunk partials kept for the merge).
/// Validate, set up, then epochs until a stop criterion is met.
pub fn run_from(
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    interrupt: &AtomicBool,
    observer: &mut dyn Observer,
    start: Start,
) -> Result<RunResult> {
    let (target, max_photons) = validate(scene, options)?;
    let engine = Engine::new(scene, options, caster)?;
    let mut run = Epochs::set_up(&engine, scene, options, (target, max_photons), start);
    let run_setup = engine.setup(setup);
    let clock = Instant::now();
    loop {
        let epoch_start = Instant::now();
        let count = run.trace();
        let elapsed_s = run.elapsed_before_s + clock.elapsed().as_secs_f64();
        let reason = run.evaluate(elapsed_s, interrupt);
        observer.epoch(&run.state(&run_setup, elapsed_s, reason));
        if let Some(reason) = reason {
            let elapsed_s = run.elapsed_before_s + clock.elapsed().as_secs_f64();
            return Ok(run.finish(run_setup, reason, elapsed_s));
        }
        run.size_next_epoch(count, epoch_start.elapsed().as_secs_f64(), elapsed_s);
    }
}

/// What traces a run (or a merge of shards): its worker threads and the tracer, which
/// also computes the next-event receivers' direct light.
pub(crate) struct Engine<'s> {
    pub(crate) tracer: Tracer<'s>,
    pub(crate) pool: rayon::ThreadPool,
    pub(crate) threads: usize,
    /// Per next-event receiver (in order), its cells' points per side in a direct
    /// replicate (`DirectLight::cell_sides`), computed at the first replicates.
    direct_sides: std::sync::OnceLock<Vec<Vec<u32>>>,
}

impl<'s> Engine<'s> {
    pub(crate) fn new(
        scene: &'s Scene,
        options: &RunOptions,
        caster: &'s dyn RayCaster,
    ) -> Result<Engine<'s>> {
        let threads = options.threads.max(1);
        let tracer = Tracer::new(scene, caster, options.seed, options.estimator);
        let flux = tracer.emitters.total_flux_lm;
        if !flux.is_finite() {
            return Err(Error::input(
                format!("{}: lights", scene.path.display()),
                format!(
                    "their total flux, {flux} lm, is beyond f64's range ({:e}): scale the \
                     lights down (results scale with them)",
                    f64::MAX
                ),
            ));
        }
        crate::trace::endless::refuse_endless(scene, &tracer.emitters)?;
        Ok(Engine {
            pool: thread_pool(threads)?,
            tracer,
            threads,
            direct_sides: std::sync::OnceLock::new(),
        })
    }

    /// What the set-up settled, `setup` being when it began.
    pub(crate) fn setup(&self, setup: Instant) -> RunSetup {
        RunSetup::new(setup, &self.tracer, self.threads)
    }

    /// The direct light after the photons reached `tallies.photons`: at a schedule
    /// point (`CHUNK_PHOTONS`·2^k) first the replicates the old schedule wants there,
    /// then the schedule and the floor (`direct::replicate_floor`) re-estimated from
    /// those tallies and the floor's replicates added; then the replicates the schedule
    /// wants. The replicate count and every sum the schedule reads are thus functions
    /// of the photon count alone, whatever the epochs (a resumed run and a merge of
    /// shards pass through the same states). Returns the seconds it took.
    pub(crate) fn top_up_direct(
        &self,
        tallies: &mut Tallies,
        schedule: &mut DirectSchedule,
    ) -> f64 {
        let mut seconds = 0.0;
        if tallies.photons.is_power_of_two() && tallies.photons >= CHUNK_PHOTONS {
            let wanted = schedule.wanted(tallies.photons, tallies.direct_replicates);
            seconds += self.add_direct(tallies, wanted);
            let floor;
            (*schedule, floor) = self.schedule_direct(tallies);
            seconds += self.add_direct(tallies, floor);
        }
        let wanted = schedule.wanted(tallies.photons, tallies.direct_replicates);
        seconds + self.add_direct(tallies, wanted)
    }

    /// Tops the next-event receivers' direct light up to `wanted` replicates; returns
    /// the seconds it took.
    pub(crate) fn add_direct(&self, tallies: &mut Tallies, wanted: u64) -> f64 {
        let first = tallies.direct_replicates;
        if wanted <= first {
            return 0.0;
        }
        let start = Instant::now();
        let direct = self.tracer.direct_light();
        let grids = || {
            self.tracer
                .receivers
                .iter()
                .filter(|g| g.estimator.direct_by_replicates())
        };
        for (grid, sides) in grids().zip(self.direct_sides()) {
            let cells = &mut tallies.cells[grid.first_cell as usize..][..grid.cell_count()];
            tallies.direct_rays += self
                .pool
                .install(|| direct.add_replicates(grid, sides, cells, first, wanted - first));
        }
        tallies.direct_replicates = wanted;
        start.elapsed().as_secs_f64()
    }

    /// Per next-event receiver (in order), its cells' points per side in a direct
    /// replicate, computed at the first call.
    fn direct_sides(&self) -> &[Vec<u32>] {
        self.direct_sides.get_or_init(|| {
            let direct = self.tracer.direct_light();
            self.pool.install(|| {
                self.tracer
                    .receivers
                    .iter()
                    .filter(|g| g.estimator.direct_by_replicates())
                    .map(|g| direct.cell_sides(g))
                    .collect()
            })
        })
    }

    /// The direct light's replicates per photon and its floor (replicates), from the
    /// tallies at a schedule point. A replicate's cost is its samples plus its shadow
    /// rays so far on average, a photon's its rays.
    fn schedule_direct(&self, tallies: &Tallies) -> (DirectSchedule, u64) {
        let (mut a, mut b, mut samples, mut floor) = (0.0, 0.0, 0, 0);
        for (grid, sides) in self
            .tracer
            .receivers
            .iter()
            .filter(|g| g.estimator.direct_by_replicates())
            .zip(self.direct_sides())
        {
            let cells = &tallies.cells[grid.first_cell as usize..][..grid.cell_count()];
            let (ga, gb) = relative_variances(cells, tallies.photons, tallies.direct_replicates);
            (a, b) = (a + ga, b + gb);
            samples += samples_per_replicate(sides);
            floor = floor.max(replicate_floor(cells, tallies.direct_replicates));
        }
        let schedule = DirectSchedule::from_variances(
            a,
            b,
            samples as f64 + tallies.direct_rays as f64 / tallies.direct_replicates.max(1) as f64,
            tallies.rays as f64 / tallies.photons.max(1) as f64,
        );
        (schedule, floor)
    }
}

/// A run from epoch to epoch: what it has traced and measured so far.
struct Epochs<'r, 's> {
    engine: &'r Engine<'s>,
    scene: &'s Scene,
    options: &'r RunOptions,
    target: Target,
    distributor: Option<Box<dyn Distributor>>,
    shard: Option<ShardRange>,
    /// This run traces photons `first_photon .. first_photon + max_photons`.
    first_photon: u64,
    max_photons: u64,
    /// Photons of the next epoch, and the threads of every process sharing it.
    epoch_photons: u64,
    workers: usize,
    tallies: Tallies,
    schedule: DirectSchedule,
    history: Vec<HistoryPoint>,
    forecast: Option<Forecast>,
    /// The fewest hits in a cell of the target after the last epoch, when `--min-hits`
    /// asks and the target is a receiver's.
    fewest_hits: Option<u64>,
    /// A shard's per-chunk partials, for the merge.
    chunk_log: Vec<ChunkRecord>,
    /// Chunk tallies reused from epoch to epoch (in chunk order, so the merge order
    /// never changes).
    buffers: Vec<ChunkTally>,
    /// Seconds: traced before this process took the run over (a resumed run), and
    /// spent on the direct light, statistics and merging.
    elapsed_before_s: f64,
    direct_s: f64,
    stats_s: f64,
    merge_s: f64,
}

impl<'r, 's> Epochs<'r, 's> {
    /// The set-up: the tallies (a resumed run's, or empty) and the direct light's pilot
    /// (none for a shard, which leaves the direct light to the merge; a resumed run has
    /// it already).
    fn set_up(
        engine: &'r Engine<'s>,
        scene: &'s Scene,
        options: &'r RunOptions,
        (target, max_photons): (Target, u64),
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
        let resumed = start
            .resumed
            .unwrap_or_else(|| Resumed::fresh(engine.tracer.new_tallies()));
        let mut tallies = resumed.tallies;
        let pilot = if shard.is_some() { 0 } else { PILOT_REPLICATES };
        let pilot_s = engine.add_direct(&mut tallies, pilot);
        Epochs {
            engine,
            scene,
            options,
            target,
            distributor: start.distributor,
            shard,
            first_photon,
            max_photons,
            epoch_photons: CHUNK_PHOTONS * workers as u64,
            workers,
            tallies,
            schedule: DirectSchedule {
                per_photon: resumed.direct_per_photon,
            },
            history: resumed.history,
            forecast: None,
            fewest_hits: None,
            chunk_log: resumed.chunks,
            buffers: Vec::new(),
            elapsed_before_s: resumed.elapsed_s,
            direct_s: pilot_s + resumed.direct_s,
            stats_s: resumed.stats_s,
            merge_s: resumed.merge_s,
        }
    }

    /// Traces the next epoch and folds it in (epochs end at every schedule point, so
    /// every run passes through them), then tops the direct light up (not for a shard);
    /// returns the photons traced.
    fn trace(&mut self) -> u64 {
        let done = self.tallies.photons;
        let count = self
            .epoch_photons
            .min(self.max_photons - done)
            .min(next_schedule_point(done) - done);
        let merge_start = self.trace_chunks(self.first_photon + done, count);
        self.merge_s += merge_start.elapsed().as_secs_f64();
        if self.shard.is_none() {
            self.direct_s += self
                .engine
                .top_up_direct(&mut self.tallies, &mut self.schedule);
        }
        count
    }

    /// Traces photons `first .. first + count` in fixed chunks (on this process's
    /// threads, or shared out by the distributor) and folds them into the tallies in
    /// chunk order (and, for a shard, their records into the chunk log); returns when
    /// the merge began.
    fn trace_chunks(&mut self, first: u64, count: u64) -> Instant {
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
            pool.install(|| {
                chunks
                    .par_iter()
                    .zip(results.par_iter_mut())
                    .for_each(|(&(first, n), tally)| {
                        SCRATCH.with_borrow_mut(|scratch| {
                            tracer.trace_chunk_into(first, n, scratch, tally)
                        })
                    })
            })
        };
        match self.distributor.as_deref_mut() {
            Some(d) => d.trace(&chunks, results, &mut local),
            None => local(&chunks, results),
        }
        let merge_start = Instant::now();
        let log = self.shard.is_some();
        for (chunk, &(_, n)) in results.iter().zip(&chunks) {
            self.tallies.accumulate(chunk, n as u64);
            if log {
                self.chunk_log.push(ChunkRecord::of(chunk, n));
            }
        }
        merge_start
    }

    /// The statistics after an epoch: the target's error into the history, with the
    /// forecast when there is an error target, and the fewest hits when `--min-hits`
    /// asks; then the stop check.
    fn evaluate(&mut self, elapsed_s: f64, interrupt: &AtomicBool) -> Option<StopReason> {
        let stats_start = Instant::now();
        let scene = self.scene;
        let stop = &self.options.stop;
        let error = self.engine.pool.install(|| {
            target_error(
                scene,
                &self.target,
                &self.tallies,
                self.engine.tracer.emitters.total_flux_lm,
                stop.absolute,
            )
        });
        let mut point = HistoryPoint {
            elapsed_s,
            photons: self.tallies.photons,
            rel_error: error,
            forecast_s: None,
            forecast_photons: None,
        };
        self.history.push(point);
        if let Some(goal) = stop.target_error {
            self.forecast = forecast(&self.history, goal);
            point.forecast_s = self.forecast.map(|f| f.total_s);
            point.forecast_photons = self.forecast.map(|f| f.photons);
            *self.history.last_mut().expect("pushed above") = point;
        }
        // One pass over the target's cells, read by the stop check and the next
        // epoch's size.
        self.fewest_hits = match (stop.min_hits, self.target.receiver()) {
            (Some(_), Some(r)) => Some(min_hits(
                &self.target,
                &scene.receivers,
                self.tallies.receiver_cells(&scene.receivers, r),
            )),
            _ => None,
        };
        let unreachable = stop.stop_if_unreachable
            && target_unreachable(
                scene,
                self.options,
                &self.target,
                &self.tallies,
                &self.history,
                self.forecast,
            )
            .is_some();
        // The budgets first: a run at its limit stopped on it, whatever the forecast.
        let reason = self
            .stop_reason(error, elapsed_s, interrupt)
            .or(unreachable.then_some(StopReason::Unreachable));
        self.stats_s += stats_start.elapsed().as_secs_f64();
        reason
    }

    /// The first stop criterion met after an epoch, if any (the target's `error` now).
    fn stop_reason(
        &self,
        error: f64,
        elapsed_s: f64,
        interrupt: &AtomicBool,
    ) -> Option<StopReason> {
        let stop = &self.options.stop;
        if stop.target_error.is_some_and(|goal| error <= goal) {
            Some(StopReason::TargetError)
        } else if stop
            .min_hits
            .is_some_and(|n| self.fewest_hits.is_some_and(|h| h >= n))
        {
            Some(StopReason::MinHits)
        } else if self.tallies.photons >= self.max_photons {
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
        let hits_goal = self.options.stop.min_hits.and_then(|n| {
            let fewest = self.fewest_hits?;
            (fewest > 0).then(|| (self.tallies.photons as f64 * n as f64 / fewest as f64) as u64)
        });
        [self.forecast.map(|f| f.photons), hits_goal]
            .into_iter()
            .flatten()
            .min()
    }

    /// Sizes the next epoch from the last one's `count` photons in `epoch_s` seconds.
    fn size_next_epoch(&mut self, count: u64, epoch_s: f64, elapsed_s: f64) {
        self.epoch_photons = next_epoch_photons(
            self.tallies.photons,
            count,
            epoch_s,
            elapsed_s,
            self.options.stop.time_limit_s,
            self.goal_photons(),
            self.workers,
        );
    }

    /// The state after an epoch, for the observer.
    fn state<'a>(
        &'a self,
        setup: &'a RunSetup,
        elapsed_s: f64,
        stop_reason: Option<StopReason>,
    ) -> RunState<'a> {
        RunState {
            scene: self.scene,
            options: self.options,
            setup,
            target: &self.target,
            tallies: &self.tallies,
            history: &self.history,
            forecast: self.forecast,
            elapsed_s,
            stats_s: self.stats_s,
            merge_s: self.merge_s,
            direct_s: self.direct_s,
            stop_reason,
            resumable: Resumable {
                direct_per_photon: self.schedule.per_photon,
                shard: self.shard,
                chunks: &self.chunk_log,
            },
        }
    }

    fn finish(self, setup: RunSetup, stop_reason: StopReason, elapsed_s: f64) -> RunResult {
        RunResult {
            setup,
            tallies: self.tallies,
            history: self.history,
            forecast: self.forecast,
            target: self.target,
            stop_reason,
            elapsed_s,
            stats_s: self.stats_s,
            merge_s: self.merge_s,
            direct_s: self.direct_s,
            direct_per_photon: self.schedule.per_photon,
            shard: self.shard,
            chunks: self.chunk_log,
        }
    }
}

/// Checks the options a run needs beyond the scene's own checks; returns the error
/// target's subject and the photons to stop at.
fn validate(scene: &Scene, options: &RunOptions) -> Result<(Target, u64)> {
    check_indexes(scene, options.threads)?;
    let target = Target::chosen(options.stop.target.as_deref(), &scene.receivers)?;
    if options.stop.min_hits.is_some() && target == Target::Global {
        return Err(Error::input(
            "--min-hits",
            "needs a receiver target (--target receiver:NAME)",
        ));
    }
    options.stop.validate(criteria::flag)?;
    let max_photons = options.stop.max_photons();
    Ok((target, max_photons))
}

/// Most worker threads a run accepts: more would only cost memory (every worker keeps
/// its own scratch) and, past 65 536, break epoch sizing.
pub const MAX_THREADS: usize = 1024;

/// The numbers the engine indexes with fixed-width integers: receiver cells (u32 over
/// all receivers) and worker threads.
pub fn check_indexes(scene: &Scene, threads: usize) -> Result<()> {
    let cells: u64 = scene
        .receivers
        .iter()
        .map(|r| r.cells[0] as u64 * r.cells[1] as u64)
        .fold(0, u64::saturating_add);
    if cells > u32::MAX as u64 {
        return Err(Error::input(
            format!("{}: receivers", scene.path.display()),
            format!(
                "{cells} cells in all; at most {} (cells are numbered with 32 bits)",
                u32::MAX
            ),
        ));
    }
    check_threads(threads)
}

/// At most [`MAX_THREADS`] worker threads.
pub fn check_threads(threads: usize) -> Result<()> {
    if threads > MAX_THREADS {
        return Err(Error::input(
            "--threads",
            format!("{threads} is more than {MAX_THREADS}"),
        ));
    }
    Ok(())
}

/// The next photon count after `done` at which the direct light's schedule is revised:
/// `CHUNK_PHOTONS`·2^k.
fn next_schedule_point(done: u64) -> u64 {
    let mut point = CHUNK_PHOTONS;
    while point <= done {
        match point.checked_mul(2) {
            Some(p) => point = p,
            None => return u64::MAX,
        }
    }
    point
}

/// Why the run's error target cannot be met, if it cannot ([`unreachable`]): nothing has
/// scored in the target's cells, or the forecast is beyond the photon or time budget.
/// Never once the target is met.
pub fn target_unreachable(
    scene: &Scene,
    options: &RunOptions,
    target: &Target,
    tallies: &Tallies,
    history: &[HistoryPoint],
    forecast: Option<Forecast>,
) -> Option<String> {
    let nothing_scored = !tallies.dark
        && target.receiver().is_some_and(|r| {
            let cells = tallies.receiver_cells(&scene.receivers, r);
            match target {
                Target::Block { .. } => target
                    .cells(&scene.receivers)
                    .iter()
                    .all(|&k| cells[k].hits == 0),
                _ => cells.iter().all(|c| c.hits == 0),
            }
        });
    let met = options
        .stop
        .target_error
        .is_some_and(|goal| history.last().is_some_and(|p| p.rel_error <= goal));
    if met {
        return None;
    }
    unreachable(
        options.stop.target_error,
        history,
        forecast,
        nothing_scored,
        options.stop.max_photons(),
        options.stop.time_limit_s,
    )
}

/// The target's error now: the global map's odd/even error, or the receiver's.
pub(crate) fn target_error(
    scene: &Scene,
    target: &Target,
    tallies: &Tallies,
    total_flux_lm: f64,
    absolute: bool,
) -> f64 {
    match target.receiver() {
        None => {
            let m = map_stats(tallies, MapKind::Total, &scene.geometry, total_flux_lm);
            if absolute {
                m.sigma_lx
            } else {
                m.rel_error.arithmetic
            }
        }
        Some(r) => receiver_target_error(
            target,
            &scene.receivers,
            tallies.receiver_cells(&scene.receivers, r),
            tallies.counts(),
            absolute,
        ),
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
