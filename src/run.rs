//! A run: epochs of photons traced in parallel, merged in photon order, evaluated,
//! forecast and checked against the stop criteria; everything traced is in the result.

use crate::accel::{self, Backend, RayCaster};
use crate::criteria::{self, StopCriteria};
use crate::distributed::Distributor;
use crate::scene::{Estimator, Scene};
use crate::stats::forecast::{forecast, Forecast, HistoryPoint};
use crate::stats::stop::{min_hits, receiver_target_error, StopReason, Target};
use crate::stats::{map_stats, MapKind};
use crate::tally::{ChunkTally, Tallies};
use crate::trace::direct::{relative_variances, DirectLight, DirectSchedule, PILOT_REPLICATES};
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
    let caster = accel::build(options.backend, &scene.geometry)?;
    run_with(scene, options, caster.as_ref(), setup, interrupt, observer)
}

/// [`run`] over a ray caster already built (`setup` is when building started).
pub fn run_with(
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    interrupt: &AtomicBool,
    observer: &mut dyn Observer,
) -> Result<RunResult> {
    run_from(
        scene,
        options,
        caster,
        setup,
        interrupt,
        observer,
        Start::default(),
    )
}

/// [`run_with`] from a checkpoint's state (`start.resumed`) and/or over a shard's photon
/// range only (`start.shard`: no direct light, chunk partials kept for the merge).
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
    let shard = start.shard;
    let mut distributor = start.distributor;
    // Every process's threads share an epoch's chunks.
    let processes = distributor.as_ref().map_or(1, |d| d.processes());
    // A shard traces photons first_photon .. first_photon + max_photons.
    let (first_photon, max_photons) = match shard {
        Some(s) => (s.first_photon, s.end_photon - s.first_photon),
        None => (0, max_photons),
    };
    let threads = options.threads.max(1);
    let pool = thread_pool(threads)?;
    let tracer = Tracer::new(scene, caster, options.seed, options.estimator);
    let total_flux_lm = tracer.emitters.total_flux_lm;
    let resumed = start.resumed;
    let mut tallies = match &resumed {
        Some(r) => r.tallies.clone(),
        None => tracer.new_tallies(),
    };
    let direct = tracer.direct_light();
    let mut direct_schedule = DirectSchedule {
        per_photon: resumed.as_ref().map_or(0.0, |r| r.direct_per_photon),
    };
    // Shards leave the direct light to the merge; a resumed run has its pilot already.
    let pilot = if shard.is_some() { 0 } else { PILOT_REPLICATES };
    let mut direct_s = add_direct(&tracer, &direct, &mut tallies, pilot, &pool);
    let run_setup = RunSetup::new(setup, &tracer, threads);
    let (mut stats_s, mut merge_s) = (0.0, 0.0);
    let mut history: Vec<HistoryPoint> = Vec::new();
    let mut latest_forecast = None;
    let mut chunk_log: Vec<ChunkRecord> = Vec::new();
    // A resumed run goes on from the saved clock and history.
    let mut elapsed_before_s = 0.0;
    if let Some(r) = resumed {
        direct_s += r.direct_s;
        (stats_s, merge_s) = (r.stats_s, r.merge_s);
        history = r.history;
        chunk_log = r.chunks;
        elapsed_before_s = r.elapsed_s;
    }

    // Chunk tallies are reused from epoch to epoch (in chunk order, so the merge order
    // never changes); each worker thread keeps its own scratch buffers.
    let mut buffers: Vec<ChunkTally> = Vec::new();
    let start = Instant::now();
    let mut epoch_photons = CHUNK_PHOTONS * (threads * processes) as u64;
    let stop_reason = loop {
        // Epochs end at every schedule point, so every run passes through them.
        let count = epoch_photons
            .min(max_photons - tallies.photons)
            .min(next_schedule_point(tallies.photons) - tallies.photons);
        let epoch_start = Instant::now();
        let first = first_photon + tallies.photons;
        let merge_start = trace_epoch(
            &tracer,
            &pool,
            first,
            count,
            &mut buffers,
            distributor.as_deref_mut(),
            &mut tallies,
            shard.is_some().then_some(&mut chunk_log),
        );
        merge_s += merge_start.elapsed().as_secs_f64();
        if shard.is_none() {
            direct_s += top_up_direct(&tracer, &direct, &mut tallies, &mut direct_schedule, &pool);
        }
        let elapsed_s = elapsed_before_s + start.elapsed().as_secs_f64();
        let stats_start = Instant::now();

        let error = target_error(
            scene,
            &target,
            &tallies,
            total_flux_lm,
            options.stop.absolute,
        );
        let mut point = HistoryPoint {
            elapsed_s,
            photons: tallies.photons,
            rel_error: error,
            forecast_s: None,
            forecast_photons: None,
        };
        history.push(point);
        if let Some(goal) = options.stop.target_error {
            latest_forecast = forecast(&history, goal);
            point.forecast_s = latest_forecast.map(|f| f.total_s);
            point.forecast_photons = latest_forecast.map(|f| f.photons);
            *history.last_mut().expect("pushed above") = point;
        }

        let reason = stop_reason(
            scene,
            options,
            &target,
            &tallies,
            error,
            max_photons,
            elapsed_s,
            interrupt,
        );
        stats_s += stats_start.elapsed().as_secs_f64();
        observer.epoch(&RunState {
            scene,
            options,
            setup: &run_setup,
            target: &target,
            tallies: &tallies,
            history: &history,
            forecast: latest_forecast,
            elapsed_s,
            stats_s,
            merge_s,
            direct_s,
            stop_reason: reason,
            resumable: Resumable {
                direct_per_photon: direct_schedule.per_photon,
                shard,
                chunks: &chunk_log,
            },
        });
        if let Some(reason) = reason {
            break reason;
        }
        let goal_photons = goal_photons(scene, options, &target, &tallies, latest_forecast);
        epoch_photons = next_epoch_photons(
            tallies.photons,
            count,
            epoch_start.elapsed().as_secs_f64(),
            elapsed_s,
            options.stop.time_limit_s,
            goal_photons,
            threads * processes,
        );
    };
    Ok(RunResult {
        setup: run_setup,
        tallies,
        history,
        forecast: latest_forecast,
        target,
        stop_reason,
        elapsed_s: elapsed_before_s + start.elapsed().as_secs_f64(),
        stats_s,
        merge_s,
        direct_s,
        direct_per_photon: direct_schedule.per_photon,
        shard,
        chunks: chunk_log,
    })
}

/// Checks the options a run needs beyond the scene's own checks; returns the error
/// target's subject and the photons to stop at.
fn validate(scene: &Scene, options: &RunOptions) -> Result<(Target, u64)> {
    check_indexes(scene, options.threads)?;
    let target = match &options.stop.target {
        Some(t) => Target::parse(t, &scene.receivers)?,
        None if scene.receivers.is_empty() => Target::Global,
        None => Target::Receiver { index: 0 },
    };
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

/// Traces photons `first .. first + count` in fixed chunks (on this process's threads,
/// or shared out by `distributor`) and folds them into `tallies` in chunk order (and
/// their records into `chunk_log`, for shards); returns when the merge began.
#[allow(clippy::too_many_arguments)]
fn trace_epoch(
    tracer: &Tracer<'_>,
    pool: &rayon::ThreadPool,
    first: u64,
    count: u64,
    buffers: &mut Vec<ChunkTally>,
    distributor: Option<&mut (dyn Distributor + '_)>,
    tallies: &mut Tallies,
    chunk_log: Option<&mut Vec<ChunkRecord>>,
) -> Instant {
    let chunks: Vec<(u64, u32)> = (0..count.div_ceil(CHUNK_PHOTONS))
        .map(|c| {
            let start = first + c * CHUNK_PHOTONS;
            (start, CHUNK_PHOTONS.min(first + count - start) as u32)
        })
        .collect();
    if buffers.len() < chunks.len() {
        buffers.resize_with(chunks.len(), ChunkTally::default);
    }
    let results = &mut buffers[..chunks.len()];
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
    match distributor {
        Some(d) => d.trace(&chunks, results, &mut local),
        None => local(&chunks, results),
    }
    let merge_start = Instant::now();
    let mut chunk_log = chunk_log;
    for (chunk, &(_, n)) in results.iter().zip(&chunks) {
        tallies.accumulate(chunk, n as u64);
        if let Some(log) = chunk_log.as_deref_mut() {
            log.push(ChunkRecord::of(chunk, n));
        }
    }
    merge_start
}

/// The first stop criterion met after an epoch, if any (the target's `error` now).
#[allow(clippy::too_many_arguments)]
fn stop_reason(
    scene: &Scene,
    options: &RunOptions,
    target: &Target,
    tallies: &Tallies,
    error: f64,
    max_photons: u64,
    elapsed_s: f64,
    interrupt: &AtomicBool,
) -> Option<StopReason> {
    if options.stop.target_error.is_some_and(|goal| error <= goal) {
        Some(StopReason::TargetError)
    } else if options.stop.min_hits.is_some_and(|n| {
        target.receiver().is_some_and(|r| {
            min_hits(
                target,
                &scene.receivers,
                tallies.receiver_cells(&scene.receivers, r),
            ) >= n
        })
    }) {
        Some(StopReason::MinHits)
    } else if tallies.photons >= max_photons {
        Some(StopReason::Photons)
    } else if options.stop.time_limit_s.is_some_and(|t| elapsed_s >= t) {
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
fn goal_photons(
    scene: &Scene,
    options: &RunOptions,
    target: &Target,
    tallies: &Tallies,
    forecast: Option<Forecast>,
) -> Option<u64> {
    let hits_goal = options.stop.min_hits.and_then(|n| {
        let r = target.receiver()?;
        let fewest = min_hits(
            target,
            &scene.receivers,
            tallies.receiver_cells(&scene.receivers, r),
        );
        (fewest > 0).then(|| (tallies.photons as f64 * n as f64 / fewest as f64) as u64)
    });
    [forecast.map(|f| f.photons), hits_goal]
        .into_iter()
        .flatten()
        .min()
}

/// The direct light after the photons reached `tallies.photons`: at a schedule point
/// (`CHUNK_PHOTONS`·2^k) first the replicates the old schedule wants there, then the
/// schedule re-estimated; then the replicates it wants. The replicate count and every
/// sum the schedule reads are thus functions of the photon count alone, whatever the
/// epochs (a resumed run and a merge of shards pass through the same states).
/// Returns the seconds it took.
pub(crate) fn top_up_direct(
    tracer: &Tracer<'_>,
    direct: &DirectLight<'_>,
    tallies: &mut Tallies,
    schedule: &mut DirectSchedule,
    pool: &rayon::ThreadPool,
) -> f64 {
    let mut seconds = 0.0;
    if tallies.photons.is_power_of_two() && tallies.photons >= CHUNK_PHOTONS {
        let wanted = schedule.wanted(tallies.photons, tallies.direct_replicates);
        seconds += add_direct(tracer, direct, tallies, wanted, pool);
        *schedule = schedule_direct(tracer, tallies);
    }
    let wanted = schedule.wanted(tallies.photons, tallies.direct_replicates);
    seconds + add_direct(tracer, direct, tallies, wanted, pool)
}

/// Tops the next-event receivers' direct light up to `wanted` replicates; returns the
/// seconds it took.
pub(crate) fn add_direct(
    tracer: &Tracer<'_>,
    direct: &DirectLight<'_>,
    tallies: &mut Tallies,
    wanted: u64,
    pool: &rayon::ThreadPool,
) -> f64 {
    let first = tallies.direct_replicates;
    if wanted <= first {
        return 0.0;
    }
    let start = Instant::now();
    for grid in tracer.receivers.iter().filter(|g| g.next_event()) {
        let cells = &mut tallies.cells[grid.first_cell as usize..][..grid.cell_count()];
        tallies.direct_rays +=
            pool.install(|| direct.add_replicates(grid, cells, first, wanted - first));
    }
    tallies.direct_replicates = wanted;
    start.elapsed().as_secs_f64()
}

/// The direct light's replicates per photon, from the tallies at a schedule point.
fn schedule_direct(tracer: &Tracer<'_>, tallies: &Tallies) -> DirectSchedule {
    let (mut a, mut b) = (0.0, 0.0);
    for grid in tracer.receivers.iter().filter(|g| g.next_event()) {
        let cells = &tallies.cells[grid.first_cell as usize..][..grid.cell_count()];
        let (ga, gb) = relative_variances(cells, tallies.photons, tallies.direct_replicates);
        (a, b) = (a + ga, b + gb);
    }
    DirectSchedule::from_variances(
        a,
        b,
        tallies.direct_rays as f64 / tallies.direct_replicates.max(1) as f64,
        tallies.rays as f64 / tallies.photons.max(1) as f64,
    )
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
            let m = map_stats(
                tallies,
                MapKind::Total,
                &scene.geometry.area_m2,
                total_flux_lm,
            );
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
