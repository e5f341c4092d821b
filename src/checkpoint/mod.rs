//! Checkpoints, resume, shards and their merge (docs/distributed.md).
//!
//! A checkpoint is a run's whole state after an epoch: every tally as raw bits
//! (compensated sums with their compensation terms), the counters, the history, the
//! direct light's schedule, the options that change the numbers and a fingerprint of the
//! scene. Tallies at N photons are chunk partials folded in chunk order, and the direct
//! light is a function of N alone (`run::engine`'s schedule points), so a run resumed from a
//! checkpoint ends bit-identical to one never stopped.
//!
//! Shards: shard I of N traces a contiguous range of whole chunks and keeps each chunk's
//! receiver partials (compensated sums are not associative bit for bit, so shard totals
//! cannot be added); the merge folds every chunk again in global chunk order, adding the
//! integer counters as totals, and computes the direct light from the total photon
//! count, exactly as one run would.
//!
//! The run's record is `run::Progress`; a checkpoint is that record as saved, with what
//! identifies the run (`format.rs`: the file's layout; `saver.rs`: periodic saving off the
//! run's thread; `resume.rs`: where a resumed or sharded run starts; `shards.rs`: the
//! shards' checks before `run::merge`).

use crate::run::{ChunkRecord, Progress, RunOptions, RunState, ShardRange, Times};
use crate::scene::{fingerprint, Scene};
use crate::stats::stop::StopReason;
use crate::tally::CellSums;
use crate::trace::direct::DirectSchedule;
use crate::{Error, Result};
use format::{pack_cells, Bytes, SavedPoint, SavedTallies};
use serde::{Deserialize, Serialize};
use std::borrow::Cow;
use std::path::{Path, PathBuf};

mod format;
pub mod resume;
mod saver;
mod shards;
pub use format::FORMAT_VERSION;
pub use saver::{Checkpointer, SaveCost};
pub use shards::{merge_shards, merged_options};

/// The checkpoint in an output directory, and the one before it.
pub const FILE: &str = "checkpoint.bin";
pub const PREVIOUS_FILE: &str = "checkpoint.prev";
/// Seconds between checkpoints unless `--checkpoint-every` says otherwise.
pub const DEFAULT_PERIOD_S: f64 = 60.0;

/// The options that change the numbers: a checkpoint is only continued, or merged,
/// with the same ones.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Numbers {
    pub seed: u64,
    /// `--estimator`, if any.
    pub estimator: Option<String>,
    /// The backend casts the rays: another one gives other bits.
    pub backend: String,
    /// QMC connection points, and blocks for histories (`RunOptions::qmc`).
    pub qmc: bool,
}

impl Numbers {
    pub fn of(options: &RunOptions) -> Numbers {
        Numbers {
            seed: options.seed,
            estimator: options.estimator.map(|e| format!("{e:?}")),
            backend: options.backend.name().to_string(),
            qmc: options.qmc,
        }
    }

    /// What differs from `other` (the run asked for), in words; `None` if nothing.
    pub fn difference(&self, now: &Numbers) -> Option<String> {
        if self.seed != now.seed {
            return Some(format!(
                "the seed differs (checkpoint {}, now {})",
                self.seed, now.seed
            ));
        }
        if self.estimator != now.estimator {
            let show = |e: &Option<String>| e.clone().unwrap_or_else(|| "none".into());
            return Some(format!(
                "--estimator differs (checkpoint {}, now {})",
                show(&self.estimator),
                show(&now.estimator)
            ));
        }
        if self.qmc != now.qmc {
            let show = |on: bool| if on { "on" } else { "off" };
            return Some(format!(
                "QMC differs (checkpoint {}, now {})",
                show(self.qmc),
                show(now.qmc)
            ));
        }
        if self.backend != now.backend {
            return Some(format!(
                "the backend differs (checkpoint {}, now {})",
                self.backend, now.backend
            ));
        }
        None
    }
}

/// Everything a checkpoint file holds (`'a`: the run's tallies, when it borrows them;
/// a checkpoint read from a file owns everything).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct Checkpoint<'a> {
    /// The scene file, for `merge` (which loads it again and checks the fingerprint).
    pub scene_path: String,
    pub scene_fingerprint: u64,
    pub numbers: Numbers,
    /// `--photons` of the run (a shard's total over all shards).
    pub photons_goal: Option<u64>,
    pub shard: Option<ShardRange>,
    /// The run stopped on a criterion (not interrupted).
    pub finished: bool,
    tallies: SavedTallies<'a>,
    direct_per_photon: f64,
    history: Vec<SavedPoint>,
    /// Seconds: photon pass, statistics, merging, direct light.
    times_s: [f64; 4],
    chunks: Vec<ChunkRecord>,
}

impl<'a> Checkpoint<'a> {
    /// The checkpoint of a run's state after an epoch, borrowing its triangle maps.
    pub fn of(state: &RunState<'a>, scene_fingerprint: u64) -> Checkpoint<'a> {
        let maps = Cow::Borrowed(&state.progress.tallies.triangle_hits);
        let mut c = Checkpoint::unpacked(state, scene_fingerprint, maps);
        c.tallies.cells = Bytes(pack_cells(&state.progress.tallies.cells));
        c
    }

    /// [`Checkpoint::of`] with the triangle maps `maps` and the cells still to pack.
    fn unpacked(
        state: &RunState<'_>,
        scene_fingerprint: u64,
        maps: Cow<'a, crate::tally::TriangleCounts>,
    ) -> Checkpoint<'a> {
        let tallies = SavedTallies::of(&state.progress.tallies, maps, Bytes(Vec::new()));
        Checkpoint {
            scene_path: state.scene.path.display().to_string(),
            scene_fingerprint,
            numbers: Numbers::of(state.options),
            photons_goal: state.options.stop.photons,
            shard: state.progress.shard,
            finished: state
                .stop_reason
                .is_some_and(|r| r != StopReason::Interrupted),
            tallies,
            direct_per_photon: state.progress.direct_schedule.per_photon,
            history: state
                .progress
                .history
                .iter()
                .map(SavedPoint::saved)
                .collect(),
            times_s: {
                let t = state.progress.times;
                [t.elapsed_s, t.stats_s, t.merge_s, t.direct_s]
            },
            chunks: state.progress.chunks.to_vec(),
        }
    }

    /// [`Checkpoint::of`] owning a copy of everything, with the cells still to pack: for
    /// another thread to pack and write while the run goes on.
    fn deferred(
        state: &RunState<'_>,
        scene_fingerprint: u64,
    ) -> (Checkpoint<'static>, Vec<CellSums>) {
        let maps = Cow::Owned(state.progress.tallies.triangle_hits.clone());
        let c = Checkpoint::unpacked(state, scene_fingerprint, maps);
        (c, state.progress.tallies.cells.clone())
    }

    /// Photons traced so far (a shard's own).
    pub fn photons(&self) -> u64 {
        self.tallies.photons
    }

    /// The run's record to go on from; cells that do not read back are refused,
    /// naming `origin`.
    pub fn into_progress(self, origin: String) -> Result<Progress> {
        let [elapsed_s, stats_s, merge_s, direct_s] = self.times_s;
        let tallies = self.tallies.into_tallies().ok_or_else(|| {
            Error::input(
                origin,
                "the checkpoint's cells are corrupt (they do not read back)",
            )
        })?;
        Ok(Progress {
            tallies,
            history: self.history.iter().map(SavedPoint::point).collect(),
            forecast: None,
            direct_schedule: DirectSchedule {
                per_photon: self.direct_per_photon,
            },
            times: Times {
                elapsed_s,
                stats_s,
                merge_s,
                direct_s,
            },
            shard: self.shard,
            chunks: self.chunks,
        })
    }

    /// Refuses a scene or options that would change the numbers; `what` names the file.
    pub fn check(&self, what: &Path, scene: &Scene, options: &RunOptions) -> Result<()> {
        let refuse = |m: String| Err(Error::input(what.display().to_string(), m));
        if self.scene_fingerprint != fingerprint::run(scene) {
            return refuse(format!(
                "the scene differs from the checkpoint's ({} or a file it loads changed)",
                scene.path.display()
            ));
        }
        if let Some(d) = self.numbers.difference(&Numbers::of(options)) {
            return refuse(d);
        }
        Ok(())
    }

    /// Writes `dir/checkpoint.bin` atomically: a temporary file in `dir`, synced, the
    /// old checkpoint renamed to checkpoint.prev, the new one renamed into place, the
    /// directory synced. Returns the bytes written.
    pub fn save(&self, dir: &Path) -> Result<u64> {
        let path = dir.join(FILE);
        let tmp = dir.join(format!("{FILE}.tmp"));
        let write = || -> std::io::Result<u64> {
            let mut f = std::fs::File::create(&tmp)?;
            let bytes = self.write_to(&mut f)?;
            f.sync_all()?;
            Ok(bytes)
        };
        let bytes = write().map_err(|e| {
            // A partial file would only take room (the disk may be full).
            let _ = std::fs::remove_file(&tmp);
            Error::io(&tmp, e)
        })?;
        if path.exists() {
            let prev = dir.join(PREVIOUS_FILE);
            std::fs::rename(&path, &prev).map_err(|e| Error::io(&prev, e))?;
        }
        std::fs::rename(&tmp, &path).map_err(|e| Error::io(&path, e))?;
        if let Ok(d) = std::fs::File::open(dir) {
            let _ = d.sync_all();
        }
        Ok(bytes)
    }

    /// Reads `dir/checkpoint.bin` (or checkpoint.prev when a save was cut between its
    /// two renames).
    pub fn load(dir: &Path) -> Result<(Checkpoint<'static>, PathBuf)> {
        let mut path = dir.join(FILE);
        if !path.exists() && dir.join(PREVIOUS_FILE).exists() {
            path = dir.join(PREVIOUS_FILE);
        }
        let bytes = std::fs::read(&path).map_err(|e| Error::io(&path, e))?;
        Ok((
            Checkpoint::decode(&bytes, &path.display().to_string())?,
            path,
        ))
    }
}
