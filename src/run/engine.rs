//! What traces a run or a merge of shards: the worker threads, the tracer, and the
//! next-event receivers' direct light, topped up by the one schedule rule both follow.

use super::{thread_pool, RunOptions, RunSetup};
use crate::accel::RayCaster;
use crate::scene::Scene;
use crate::tally::Tallies;
use crate::trace::direct::{
    relative_variances, replicate_floor, samples_per_replicate, DirectSchedule,
};
use crate::trace::{Tracer, CHUNK_PHOTONS};
use crate::{Error, Result};
use std::time::Instant;

/// Whether the direct light's schedule is revised when the photons reach `photons`:
/// at `CHUNK_PHOTONS`·2^k. Epochs end at every such point and a merge tops up at each,
/// so every run of the same photons passes through the same direct-light states.
pub(crate) fn is_schedule_point(photons: u64) -> bool {
    photons.is_power_of_two() && photons >= CHUNK_PHOTONS
}

/// The first schedule point ([`is_schedule_point`]) after `done` photons.
pub(crate) fn next_schedule_point(done: u64) -> u64 {
    let mut point = CHUNK_PHOTONS;
    while point <= done {
        match point.checked_mul(2) {
            Some(p) => point = p,
            None => return u64::MAX,
        }
    }
    point
}

/// The worker threads and the tracer, which also computes the next-event receivers'
/// direct light.
pub(crate) struct Engine<'s> {
    pub(crate) tracer: Tracer<'s>,
    pub(crate) pool: rayon::ThreadPool,
    pub(crate) threads: usize,
    /// Per next-event receiver (in order), its cells' points per side in a direct
    /// replicate (`DirectLight::cell_sides`), computed at the first replicates.
    direct_sides: std::sync::OnceLock<Vec<Vec<u32>>>,
    /// [`RunOptions::direct_points_per_side`].
    direct_points: Option<u32>,
    /// Per observer, per luminaire: whether its line to the eye is blocked
    /// (`stats::ugr::occlusion`), for the observers' ratings and `ugr_max` checks.
    pub(crate) observer_visible: Vec<Vec<f64>>,
}

impl<'s> Engine<'s> {
    pub(crate) fn new(
        scene: &'s Scene,
        options: &RunOptions,
        caster: &'s dyn RayCaster,
    ) -> Result<Engine<'s>> {
        let threads = options.threads.max(1);
        if options.estimator == Some(crate::scene::Estimator::Track) {
            if let Some(r) = scene.receivers.iter().find(|r| r.points) {
                return Err(crate::error::Error::input(
                    format!("--estimator track: receiver `{}`", r.name),
                    crate::scene::POINTS_NEED_NEXT_EVENT,
                ));
            }
        }
        let tracer =
            Tracer::new(scene, caster, options.seed, options.estimator).with_qmc(options.qmc);
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
        let observer_visible = crate::stats::ugr::visibility(scene, caster);
        crate::stats::ugr::refuse_unratable_requirements(scene, &observer_visible)?;
        Ok(Engine {
            pool: thread_pool(threads)?,
            tracer,
            threads,
            direct_sides: std::sync::OnceLock::new(),
            direct_points: options.direct_points_per_side,
            observer_visible,
        })
    }

    /// The verdicts on the scene's requirements from `tallies`, on the pool; `None`
    /// without requirements, or for a shard (its tallies lack the direct light).
    pub(crate) fn verdicts(
        &self,
        scene: &Scene,
        tallies: &Tallies,
        shard: bool,
    ) -> Option<crate::stats::verdict::Verdicts> {
        let visible = &self.observer_visible;
        (!scene.requirements.is_empty() && !shard).then(|| {
            self.pool
                .install(|| crate::stats::verdict::verdicts(scene, tallies, visible))
        })
    }

    /// What the set-up settled, `setup` being when it began.
    pub(crate) fn setup(&self, setup: Instant) -> RunSetup {
        let mut s = RunSetup::new(setup, &self.tracer, self.threads);
        s.observer_visible = self.observer_visible.clone();
        s
    }

    /// The direct light after the photons reached `tallies.photons`: at a schedule
    /// point first the replicates the old schedule wants there, then the schedule and
    /// the floor (`direct::replicate_floor`) re-estimated from those tallies and the
    /// floor's replicates added; then the replicates the schedule wants. The replicate
    /// count and every sum the schedule reads are thus functions of the photon count
    /// alone, whatever the epochs (a resumed run and a merge of shards pass through the
    /// same states). Returns the seconds it took.
    pub(crate) fn top_up_direct(
        &self,
        tallies: &mut Tallies,
        schedule: &mut DirectSchedule,
    ) -> f64 {
        let mut seconds = 0.0;
        if is_schedule_point(tallies.photons) {
            let wanted = schedule.wanted(tallies.photons, tallies.direct_replicates);
            seconds += self.add_direct(tallies, wanted);
            let (revised, floor) = self.schedule_direct(tallies);
            // A QMC run's photon variance is unknown over its first blocks: the schedule
            // waits for it.
            if tallies.counts().photon_variance_known() {
                *schedule = revised;
            }
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
                    .map(|g| direct.cell_sides(g, self.direct_points))
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
            let (ga, gb) = relative_variances(
                cells,
                (tallies.photons, tallies.counts().histories),
                tallies.direct_replicates,
            );
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
