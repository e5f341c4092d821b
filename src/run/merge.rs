//! The merge of shards: the records of `run --shard I/N` runs folded into the run they
//! split, with the same bits as one process (docs/distributed.md).

use super::engine::{is_schedule_point, Engine};
use super::{target_error, Progress, RunOptions, RunResult, Times};
use crate::accel::RayCaster;
use crate::scene::Scene;
use crate::stats::forecast::HistoryPoint;
use crate::stats::stop::{StopReason, Target};
use crate::tally::ChunkTally;
use crate::trace::direct::PILOT_REPLICATES;
use crate::Result;
use std::time::Instant;

/// Merges complete shards' records, given in shard order, into the run they split:
/// every chunk folded in global chunk order with the direct light topped up at every
/// schedule point on the way, then for the total photon count, as one run would.
/// `options` must carry the shards' numbers (seed, estimator, backend); the checkpoints
/// check that (`checkpoint::merge_shards`).
pub fn merge(
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    shards: &[Progress],
) -> Result<RunResult> {
    let target = Target::chosen(options.stop.target.as_deref(), &scene.receivers)?;
    let engine = Engine::new(scene, options, caster)?;
    let mut merged = Progress::fresh(engine.tracer.new_tallies());
    let mut direct_s = engine.add_direct(&mut merged.tallies, PILOT_REPLICATES);
    let run_setup = engine.setup(setup);
    let start = Instant::now();
    let mut chunk = ChunkTally::default();
    let (mut shards_elapsed_s, mut stats_s) = (0.0, 0.0);
    for shard in shards {
        direct_s += fold_shard(&engine, shard, &mut chunk, &mut merged);
        shards_elapsed_s += shard.times.elapsed_s;
        stats_s += shard.times.stats_s;
    }
    direct_s += engine.top_up_direct(&mut merged.tallies, &mut merged.direct_schedule);
    let error = target_error(
        scene,
        &target,
        &merged.tallies,
        run_setup.total_flux_lm,
        options.stop.absolute,
    );
    merged.history.push(HistoryPoint {
        elapsed_s: shards_elapsed_s,
        photons: merged.tallies.photons,
        rel_error: error,
        forecast_s: None,
        forecast_photons: None,
        checks: engine
            .verdicts(scene, &merged.tallies, false)
            .map(|v| v.counts()),
    });
    let merge_s = start.elapsed().as_secs_f64();
    merged.times = Times {
        // The shards' photon passes added up (machine seconds), plus the merge.
        elapsed_s: shards_elapsed_s + merge_s,
        stats_s,
        merge_s,
        direct_s,
    };
    Ok(RunResult {
        setup: run_setup,
        target,
        progress: merged,
        stop_reason: StopReason::Photons,
    })
}

/// Folds `shard` into `merged`: its integer counters as totals (they add in any order),
/// its chunks one by one in chunk order, with the direct light topped up at every
/// schedule point on the way. Returns the direct light's seconds.
fn fold_shard(
    engine: &Engine<'_>,
    shard: &Progress,
    chunk: &mut ChunkTally,
    merged: &mut Progress,
) -> f64 {
    let (total, part) = (&mut merged.tallies, &shard.tallies);
    total.killed_by_bounce_cap += part.killed_by_bounce_cap;
    for (a, b) in total.history_hits.iter_mut().zip(part.history_hits) {
        *a += b;
    }
    total.triangle_hits.add(&part.triangle_hits);
    let mut direct_s = 0.0;
    for record in &shard.chunks {
        record.to_chunk(chunk);
        merged.fold_chunk(chunk, record.photons);
        if is_schedule_point(merged.tallies.photons) {
            direct_s += engine.top_up_direct(&mut merged.tallies, &mut merged.direct_schedule);
        }
    }
    direct_s
}
