//! The shards' checkpoints checked before the merge: one whole run of the scene with
//! the same numbers, each shard complete and given once.

use super::{Checkpoint, Numbers};
use crate::accel::RayCaster;
use crate::run::{self, RunOptions, RunResult};
use crate::scene::{fingerprint, Estimator, Scene};
use crate::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

/// Merges the shards' checkpoints (any order) into the run they split ([`run::merge`]),
/// once they are checked to make that run; `options` must carry the shards' numbers
/// (seed, estimator, backend).
pub fn merge_shards(
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    mut shards: Vec<(PathBuf, Checkpoint)>,
) -> Result<RunResult> {
    check_shards(scene, options, &mut shards)?;
    let mut records = Vec::with_capacity(shards.len());
    for (path, c) in shards {
        records.push(c.into_progress(path.display().to_string())?);
    }
    run::merge(scene, options, caster, setup, &records)
}

/// The options of the run the shards split: the scene's, with the first shard's
/// numbers (seed, photons, backend, estimator); `path` is where it was read, for
/// messages.
pub fn merged_options(scene: &Scene, first: &Checkpoint, path: &Path) -> Result<RunOptions> {
    let mut options = RunOptions::from_scene(scene);
    options.seed = first.numbers.seed;
    options.stop.photons = first.photons_goal;
    options.backend = first.numbers.backend.parse()?;
    options.qmc = first.numbers.qmc;
    options.estimator = match first.numbers.estimator.as_deref() {
        None => None,
        Some(name) => Some(saved_estimator(name).ok_or_else(|| {
            Error::input(
                path.display().to_string(),
                format!("unknown estimator `{name}`"),
            )
        })?),
    };
    Ok(options)
}

/// The estimator a checkpoint names (it keeps the Debug spelling, `NextEvent`).
fn saved_estimator(name: &str) -> Option<Estimator> {
    Estimator::ALL
        .into_iter()
        .find(|e| format!("{e:?}") == name)
}

/// Refuses shards that do not make one whole run of `scene` with `options`' numbers
/// (one line naming the shard at fault); sorts them by index.
fn check_shards(
    scene: &Scene,
    options: &RunOptions,
    shards: &mut [(PathBuf, Checkpoint)],
) -> Result<()> {
    let Some((first_path, first)) = shards.first() else {
        return Err(Error::input("merge", "no shard directories given"));
    };
    let origin = |p: &Path| p.display().to_string();
    let count = match first.shard {
        Some(s) => s.count,
        None => {
            return Err(Error::input(
                origin(first_path),
                "not a shard's checkpoint (run with --shard I/N)",
            ))
        }
    };
    let goal = first.photons_goal;
    let print = fingerprint::run(scene);
    for (path, c) in shards.iter() {
        let Some(s) = c.shard else {
            return Err(Error::input(origin(path), "not a shard's checkpoint"));
        };
        if s.count != count || c.photons_goal != goal {
            return Err(Error::input(
                origin(path),
                format!(
                    "shard {}/{} of {:?} photons does not belong with shard {}/{count} of {goal:?}",
                    s.index, s.count, c.photons_goal, 0
                ),
            ));
        }
        if c.scene_fingerprint != print {
            return Err(Error::input(
                origin(path),
                format!("was made from another scene than {}", scene.path.display()),
            ));
        }
        if let Some(d) = c.numbers.difference(&Numbers::of(options)) {
            return Err(Error::input(origin(path), d));
        }
        if c.photons() != s.end_photon - s.first_photon {
            return Err(Error::input(
                origin(path),
                format!(
                    "shard {}/{} is incomplete: {} of {} photons (resume it first)",
                    s.index,
                    s.count,
                    c.photons(),
                    s.end_photon - s.first_photon
                ),
            ));
        }
    }
    shards.sort_by_key(|(_, c)| c.shard.map(|s| s.index));
    for (k, (path, c)) in shards.iter().enumerate() {
        let index = c.shard.map_or(0, |s| s.index);
        if index as usize != k {
            let missing = if (index as usize) < k {
                index
            } else {
                k as u32
            };
            return Err(Error::input(
                origin(path),
                format!(
                    "shard {missing}/{count} is {}",
                    if (index as usize) < k {
                        "given twice"
                    } else {
                        "missing"
                    }
                ),
            ));
        }
    }
    if shards.len() != count as usize {
        return Err(Error::input(
            "merge",
            format!("{} of {count} shards given", shards.len()),
        ));
    }
    Ok(())
}
