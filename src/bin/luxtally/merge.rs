//! `luxtally merge`: the checkpoints of `run --shard I/N` runs folded into the outputs of
//! the whole run.

use crate::run::limit_threads;
use luxtally::accel;
use luxtally::checkpoint::Checkpoint;
use luxtally::output::{self, Finished, Outputs};
use luxtally::{Error, Result};
use std::path::PathBuf;
use std::time::Instant;

#[derive(clap::Args)]
pub struct MergeArgs {
    /// The shards' output directories (each with checkpoint.bin).
    #[arg(required = true)]
    pub dirs: Vec<PathBuf>,
    #[arg(long)]
    pub out: PathBuf,
    /// The scene file (default: the one the shards recorded).
    #[arg(long)]
    pub scene: Option<PathBuf>,
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn command(args: MergeArgs) -> Result<()> {
    limit_threads(args.threads)?;
    let mut shards = Vec::new();
    for dir in &args.dirs {
        let (c, path) = Checkpoint::load(dir)?;
        shards.push((path, c));
    }
    let scene_path = match &args.scene {
        Some(p) => p.clone(),
        None => PathBuf::from(&shards[0].1.scene_path),
    };
    let scene = luxtally::scene::load(&scene_path)?;
    let (first_path, first) = &shards[0];
    let mut options = luxtally::checkpoint::merged_options(&scene, first, first_path)?;
    if let Some(t) = args.threads {
        options.threads = t;
    }
    let out = &args.out;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    let result =
        luxtally::checkpoint::merge_shards(&scene, &options, caster.as_ref(), setup, shards)?;
    let state = result.state(&scene, &options);
    let finished = Finished {
        run: Some(&state),
        image: None,
    };
    output::write_all(out, finished, Outputs::ALL)?;
    println!(
        "merged {} shards: {} photons; results in {}",
        args.dirs.len(),
        result.progress.tallies.photons,
        out.display()
    );
    Ok(())
}
