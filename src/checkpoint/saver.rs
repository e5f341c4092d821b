//! Periodic checkpoints: the run waits only for a copy of its state, packed and
//! written on another thread.

use super::{pack_cells, Bytes, Checkpoint};
use crate::run::RunState;
use crate::scene::{fingerprint, Scene};
use crate::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Saves a running state's checkpoint every `period_s` and on the last epoch. For a
/// periodic save the run waits only for a copy of the state, packed and written on
/// another thread; the last save is written from the run's own tallies.
pub struct Checkpointer {
    pub dir: PathBuf,
    pub period_s: f64,
    pub fingerprint: u64,
    last: Instant,
    pending: Option<PendingSave>,
    /// The latest save on disk.
    pub last_cost: Option<SaveCost>,
    /// Seconds the run waited for saves, in all.
    pub total_s: f64,
    /// Saves done.
    pub saves: u64,
}

/// A save being packed and written on another thread (returns seconds and bytes).
struct PendingSave {
    writer: std::thread::JoinHandle<Result<(f64, u64)>>,
    /// Seconds the run waited for the state's copy.
    copy_s: f64,
}

/// What one save cost.
#[derive(Clone, Copy, Debug)]
pub struct SaveCost {
    /// Seconds the run waited for it: the copy, then joining its writer.
    pub waited_s: f64,
    /// Seconds its packing and writing took on the writer's thread.
    pub written_s: f64,
    pub bytes: u64,
}

impl Checkpointer {
    pub fn new(dir: &Path, period_s: f64, scene: &Scene) -> Checkpointer {
        Checkpointer {
            dir: dir.to_path_buf(),
            period_s,
            fingerprint: fingerprint::run(scene),
            last: Instant::now(),
            pending: None,
            last_cost: None,
            total_s: 0.0,
            saves: 0,
        }
    }

    /// Waits for the save under way, which becomes `last_cost`.
    fn finish_pending(&mut self) -> Result<()> {
        let Some(save) = self.pending.take() else {
            return Ok(());
        };
        let t = Instant::now();
        let (written_s, bytes) = save
            .writer
            .join()
            .map_err(|_| Error::Unsupported("the checkpoint writer panicked".into()))??;
        let joined_s = t.elapsed().as_secs_f64();
        self.total_s += joined_s;
        self.last_cost = Some(SaveCost {
            waited_s: save.copy_s + joined_s,
            written_s,
            bytes,
        });
        Ok(())
    }

    /// Saves if due (or on the last epoch, then waiting until it is on disk: written
    /// from the run's own tallies, without the copy a save on another thread needs).
    pub fn epoch(&mut self, state: &RunState<'_>) -> Result<()> {
        let last = state.stop_reason.is_some();
        if !last && self.last.elapsed().as_secs_f64() < self.period_s {
            return Ok(());
        }
        self.finish_pending()?;
        let t = Instant::now();
        if last {
            let bytes = Checkpoint::of(state, self.fingerprint).save(&self.dir)?;
            let seconds = t.elapsed().as_secs_f64();
            self.last_cost = Some(SaveCost {
                waited_s: seconds,
                written_s: seconds,
                bytes,
            });
            self.count_save(seconds);
            return Ok(());
        }
        let (mut c, cells) = Checkpoint::deferred(state, self.fingerprint);
        let dir = self.dir.clone();
        let handle = std::thread::spawn(move || {
            let t = Instant::now();
            c.tallies.cells = Bytes(pack_cells(&cells));
            drop(cells);
            let bytes = c.save(&dir)?;
            Ok((t.elapsed().as_secs_f64(), bytes))
        });
        let copy_s = t.elapsed().as_secs_f64();
        self.pending = Some(PendingSave {
            writer: handle,
            copy_s,
        });
        self.count_save(copy_s);
        Ok(())
    }

    /// Counts a save begun (or done) that the run waited `waited_s` for.
    fn count_save(&mut self, waited_s: f64) {
        self.total_s += waited_s;
        self.saves += 1;
        self.last = Instant::now();
    }
}
