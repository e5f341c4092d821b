//! Where a run starts when `--resume` and `--shard` say so: the rules that keep a
//! resumed or sharded run's numbers those of one uninterrupted run (docs/distributed.md).

use super::Checkpoint;
use crate::run::{RunOptions, ShardRange, Start};
use crate::scene::Scene;
use crate::{Error, Result};
use std::path::{Path, PathBuf};

/// The start of a run: from the checkpoint in the output directory `resume`, checked
/// against the scene and the options, and over shard `shard` (`I/N`) of the photons, or
/// the checkpoint's shard. Also returns the checkpoint file it read.
pub fn start(
    scene: &Scene,
    options: &RunOptions,
    resume: Option<&Path>,
    shard: Option<&str>,
) -> Result<(Start, Option<PathBuf>)> {
    let Some(dir) = resume else {
        let start = Start {
            shard: shard_range(options, shard, None)?,
            ..Start::default()
        };
        return Ok((start, None));
    };
    let (checkpoint, path) = Checkpoint::load(dir)?;
    let start = start_from(checkpoint, &path, scene, options, shard)?;
    Ok((start, Some(path)))
}

/// [`start`] from `checkpoint`, read from `path`.
fn start_from(
    checkpoint: Checkpoint<'static>,
    path: &Path,
    scene: &Scene,
    options: &RunOptions,
    shard: Option<&str>,
) -> Result<Start> {
    checkpoint.check(path, scene, options)?;
    // A whole run can go on to more photons, never back to fewer.
    if let Some(goal) = options.stop.photons {
        if goal < checkpoint.photons() && checkpoint.shard.is_none() {
            return Err(Error::input(
                "--photons",
                format!(
                    "{goal} is fewer than the {} photons of {}",
                    checkpoint.photons(),
                    path.display()
                ),
            ));
        }
    }
    let shard = shard_range(options, shard, checkpoint.shard)?;
    // A shard's range depends on the total photons: both stay the checkpoint's.
    if checkpoint.shard != shard
        || (shard.is_some() && checkpoint.photons_goal != options.stop.photons)
    {
        return Err(Error::input(
            "--shard",
            "differs from the checkpoint's shard or its --photons",
        ));
    }
    let scene_path = checkpoint.scene_path.clone();
    let resumed = checkpoint.into_progress(scene_path)?;
    Ok(Start {
        resumed: Some(resumed),
        shard,
        distributor: None,
    })
}

/// The photon range of `--shard I/N` (`text`), else the checkpoint's (`saved`). A shard
/// is a fixed range of the photon sequence: it stops on `--photons` alone.
fn shard_range(
    options: &RunOptions,
    text: Option<&str>,
    saved: Option<ShardRange>,
) -> Result<Option<ShardRange>> {
    let Some(text) = text else {
        return Ok(saved);
    };
    if !options.stop.open_ended() {
        return Err(Error::input(
            "--shard",
            "shards stop on --photons only (no --time-limit, --target-error, --min-hits)",
        ));
    }
    let total = options
        .stop
        .photons
        .ok_or_else(|| Error::input("--shard", "needs --photons"))?;
    ShardRange::parse(text, total).map(Some)
}

#[cfg(test)]
mod tests {
    use super::super::{pack_cells, Bytes, Numbers, SavedTallies};
    use super::*;
    use crate::scene::fingerprint;
    use crate::tally::Tallies;
    use crate::trace::CHUNK_PHOTONS;
    use std::borrow::Cow;

    /// A scene, options stopping at `photons`, and a checkpoint of that scene and those
    /// options after `traced` photons over `shard`.
    fn saved_run(
        photons: u64,
        traced: u64,
        shard: Option<ShardRange>,
    ) -> (Scene, RunOptions, Checkpoint<'static>) {
        let scene = Scene::default();
        let options = RunOptions::with_photons(&scene, photons);
        let mut tallies = Tallies::new(2, 3, 1.0);
        tallies.photons = traced;
        let cells = Bytes(pack_cells(&tallies.cells));
        let checkpoint = Checkpoint {
            scene_path: "s.toml".into(),
            scene_fingerprint: fingerprint::run(&scene),
            numbers: Numbers::of(&options),
            photons_goal: Some(photons),
            shard,
            finished: false,
            tallies: SavedTallies::of(&tallies, Cow::Owned(tallies.triangle_hits.clone()), cells),
            direct_per_photon: 0.0,
            history: vec![],
            times_s: [0.0; 4],
            chunks: vec![],
        };
        (scene, options, checkpoint)
    }

    fn refusal(result: Result<Start>) -> String {
        match result {
            Ok(_) => panic!("accepted"),
            Err(e) => e.to_string(),
        }
    }

    #[test]
    fn a_fresh_run_traces_every_photon_or_its_shard() {
        let scene = Scene::default();
        let options = RunOptions::with_photons(&scene, 10 * CHUNK_PHOTONS);
        let (whole, read) = start(&scene, &options, None, None).unwrap();
        assert!(whole.resumed.is_none() && whole.shard.is_none() && read.is_none());
        let (one, _) = start(&scene, &options, None, Some("1/2")).unwrap();
        let expected = ShardRange::new(1, 2, 10 * CHUNK_PHOTONS).unwrap();
        assert_eq!(one.shard, Some(expected));
    }

    #[test]
    fn a_shard_stops_on_photons_alone() {
        let scene = Scene::default();
        let mut options = RunOptions::from_scene(&scene);
        options.stop.photons = None;
        let e = shard_range(&options, Some("0/2"), None).unwrap_err();
        assert!(e.to_string().contains("needs --photons"), "{e}");
        options.stop.photons = Some(10 * CHUNK_PHOTONS);
        options.stop.time_limit_s = Some(5.0);
        let e = shard_range(&options, Some("0/2"), None).unwrap_err();
        assert!(e.to_string().contains("--photons only"), "{e}");
        options.stop.time_limit_s = None;
        assert!(shard_range(&options, Some("2/2"), None).is_err());
        assert!(shard_range(&options, Some("0/2"), None).unwrap().is_some());
    }

    #[test]
    fn a_resumed_run_goes_on_from_the_checkpoint() {
        let (scene, options, c) = saved_run(10 * CHUNK_PHOTONS, CHUNK_PHOTONS, None);
        let start = start_from(c.clone(), Path::new("c.bin"), &scene, &options, None).unwrap();
        assert_eq!(start.resumed.unwrap().tallies.photons, CHUNK_PHOTONS);
        assert!(start.shard.is_none());
    }

    #[test]
    fn a_whole_run_resumes_to_more_photons_never_fewer() {
        let (scene, mut options, c) = saved_run(10 * CHUNK_PHOTONS, 4 * CHUNK_PHOTONS, None);
        options.stop.photons = Some(20 * CHUNK_PHOTONS);
        assert!(start_from(c.clone(), Path::new("c.bin"), &scene, &options, None).is_ok());
        options.stop.photons = Some(3 * CHUNK_PHOTONS);
        let e = refusal(start_from(
            c.clone(),
            Path::new("c.bin"),
            &scene,
            &options,
            None,
        ));
        assert!(e.contains("--photons") && e.contains("fewer than"), "{e}");
    }

    #[test]
    fn a_shard_resumes_as_the_same_shard_of_the_same_photons() {
        let photons = 10 * CHUNK_PHOTONS;
        let shard = ShardRange::new(0, 2, photons).unwrap();
        let (scene, mut options, c) = saved_run(photons, CHUNK_PHOTONS, Some(shard));
        let path = Path::new("c.bin");
        let kept = start_from(c.clone(), path, &scene, &options, None).unwrap();
        assert_eq!(
            kept.shard,
            Some(shard),
            "the checkpoint's shard without --shard"
        );
        assert!(start_from(c.clone(), path, &scene, &options, Some("0/2")).is_ok());
        let e = refusal(start_from(c.clone(), path, &scene, &options, Some("1/2")));
        assert!(e.contains("differs from the checkpoint's shard"), "{e}");
        options.stop.photons = Some(photons + CHUNK_PHOTONS);
        let e = refusal(start_from(c.clone(), path, &scene, &options, None));
        assert!(e.contains("--shard"), "{e}");
    }

    #[test]
    fn a_whole_run_does_not_resume_as_a_shard() {
        let (scene, options, c) = saved_run(10 * CHUNK_PHOTONS, CHUNK_PHOTONS, None);
        let e = refusal(start_from(
            c.clone(),
            Path::new("c.bin"),
            &scene,
            &options,
            Some("0/2"),
        ));
        assert!(e.contains("differs from the checkpoint's shard"), "{e}");
    }

    #[test]
    fn another_seed_or_scene_is_refused() {
        let (scene, mut options, mut c) = saved_run(10 * CHUNK_PHOTONS, CHUNK_PHOTONS, None);
        options.seed += 1;
        let e = refusal(start_from(
            c.clone(),
            Path::new("c.bin"),
            &scene,
            &options,
            None,
        ));
        assert!(e.contains("c.bin") && e.contains("seed"), "{e}");
        options.seed -= 1;
        c.scene_fingerprint ^= 1;
        let e = refusal(start_from(
            c.clone(),
            Path::new("c.bin"),
            &scene,
            &options,
            None,
        ));
        assert!(e.contains("the scene differs"), "{e}");
    }

    #[test]
    fn cells_that_do_not_read_back_are_refused() {
        let (scene, options, mut c) = saved_run(10 * CHUNK_PHOTONS, CHUNK_PHOTONS, None);
        c.tallies.cells = Bytes(vec![1, 2, 3]);
        let e = refusal(start_from(
            c.clone(),
            Path::new("c.bin"),
            &scene,
            &options,
            None,
        ));
        assert!(e.contains("s.toml") && e.contains("corrupt"), "{e}");
    }
}
