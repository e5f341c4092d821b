//! A run: epochs of photons traced in parallel, merged in photon order, evaluated,
//! forecast and checked against the stop criteria; everything traced is in its record
//! ([`Progress`]), which checkpoints save and the result hands on.

use crate::accel::{self, Backend, Bvh, RayCaster};
use crate::criteria::{self, StopCriteria};
use crate::scene::{Estimator, Scene};
use crate::stats::forecast::{Forecast, HistoryPoint};
use crate::stats::stop::{receiver_target_error, unreachable, StopReason, Target};
use crate::stats::{map_stats, MapKind};
use crate::tally::{ChunkTally, Tallies};
use crate::trace::direct::DirectSchedule;
use crate::trace::{Tracer, CHUNK_PHOTONS};
use crate::{Error, Result};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

mod engine;
mod epochs;
mod merge;
mod start;
use engine::Engine;
use epochs::Epochs;
pub use merge::merge;
pub use start::{ChunkRecord, ShardRange, Start};

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
    /// Points per side of a cell in a direct-light replicate (`None`: by the receiver's
    /// cell count, `trace::direct::points_per_side`). Annual runs lower it for sources
    /// whose direct light is a small part of every hour's variance.
    pub direct_points_per_side: Option<u32>,
    /// Randomised QMC connection points, each chunk of photons one history
    /// (`trace::Tracer::with_qmc`): the photons to stop at must be whole chunks.
    pub qmc: bool,
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
            direct_points_per_side: None,
            qmc: scene.simulation.qmc,
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
    /// Per observer, per luminaire (`stats::ugr::luminaires`): whether its line to the
    /// eye is blocked.
    pub observer_visible: Vec<Vec<f64>>,
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
            observer_visible: Vec::new(),
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

/// The state of a run after an epoch: its record so far, read by the observer, the
/// checkpoints and the outputs.
pub struct RunState<'a> {
    pub scene: &'a Scene,
    pub options: &'a RunOptions,
    pub setup: &'a RunSetup,
    pub target: &'a Target,
    pub progress: &'a Progress,
    /// Set on the last epoch.
    pub stop_reason: Option<StopReason>,
}

/// What a run has traced and measured: the one record its epochs own, a checkpoint
/// saves and reads back, a merge of shards builds, and the result hands on.
#[derive(Clone, Debug)]
pub struct Progress {
    pub tallies: Tallies,
    pub history: Vec<HistoryPoint>,
    /// The error target's forecast after the last epoch (a resumed run makes it anew
    /// at its first epoch).
    pub forecast: Option<Forecast>,
    /// The next-event receivers' direct light: replicates per photon.
    pub direct_schedule: DirectSchedule,
    pub times: Times,
    /// A shard's photon range; `None` for a whole run.
    pub shard: Option<ShardRange>,
    /// A shard's per-chunk partials, for the merge.
    pub chunks: Vec<ChunkRecord>,
}

/// Seconds a run has spent, over every process that took it up (a resumed run goes on
/// from its checkpoint's).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Times {
    /// Since the photon pass began.
    pub elapsed_s: f64,
    /// Statistics, forecasts and stop checks.
    pub stats_s: f64,
    /// Folding the chunks' tallies.
    pub merge_s: f64,
    /// The next-event receivers' direct light (its pilot replicates count in
    /// `RunSetup::setup_s` too).
    pub direct_s: f64,
}

impl Progress {
    /// The record of a run that has traced nothing yet.
    pub fn fresh(tallies: Tallies) -> Progress {
        Progress {
            tallies,
            history: Vec::new(),
            forecast: None,
            direct_schedule: DirectSchedule { per_photon: 0.0 },
            times: Times::default(),
            shard: None,
            chunks: Vec::new(),
        }
    }

    /// Folds a traced chunk of `photons` photons in (the next in chunk order); a
    /// shard keeps its record for the merge.
    pub(crate) fn fold_chunk(&mut self, chunk: &ChunkTally, photons: u32) {
        self.tallies.accumulate(chunk, photons as u64);
        if self.shard.is_some() {
            self.chunks.push(ChunkRecord::of(chunk, photons));
        }
    }
}

/// What a finished run hands to the outputs.
pub struct RunResult {
    pub setup: RunSetup,
    pub target: Target,
    pub progress: Progress,
    pub stop_reason: StopReason,
}

impl RunResult {
    /// The finished run seen as its last state, for the outputs.
    pub fn state<'a>(&'a self, scene: &'a Scene, options: &'a RunOptions) -> RunState<'a> {
        RunState {
            scene,
            options,
            setup: &self.setup,
            target: &self.target,
            progress: &self.progress,
            stop_reason: Some(self.stop_reason),
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
    let mut run = Epochs::set_up(&engine, scene, options, target, max_photons, start);
    let run_setup = engine.setup(setup);
    let clock = Instant::now();
    loop {
        let epoch_start = Instant::now();
        let count = run.trace(interrupt);
        let elapsed_s = run.elapsed_before_s + clock.elapsed().as_secs_f64();
        let reason = run.evaluate(elapsed_s, interrupt);
        observer.epoch(&run.state(&run_setup, reason));
        if let Some(stop_reason) = reason {
            run.progress.times.elapsed_s = run.elapsed_before_s + clock.elapsed().as_secs_f64();
            return Ok(RunResult {
                setup: run_setup,
                target: run.target,
                progress: run.progress,
                stop_reason,
            });
        }
        run.size_next_epoch(count, epoch_start.elapsed().as_secs_f64(), elapsed_s);
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
    if options.stop.until == Some(criteria::Until::Decided) && scene.requirements.is_empty() {
        return Err(Error::input(
            "--until decided",
            "the scene has no [[requirements]] to decide",
        ));
    }
    let max_photons = options.stop.max_photons();
    if options.qmc && max_photons != u64::MAX && !max_photons.is_multiple_of(CHUNK_PHOTONS) {
        return Err(Error::input(
            "--photons",
            format!(
                "{max_photons} is not a whole number of the QMC run's chunks of \
                 {CHUNK_PHOTONS} photons"
            ),
        ));
    }
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

/// Why the run's error target cannot be met, if it cannot ([`unreachable`]): nothing has
/// scored in the target's cells, or the forecast is beyond the photon or time budget.
/// Never once the target is met.
pub fn target_unreachable(
    scene: &Scene,
    options: &RunOptions,
    target: &Target,
    progress: &Progress,
) -> Option<String> {
    let (tallies, history) = (&progress.tallies, &progress.history);
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
        progress.forecast,
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
