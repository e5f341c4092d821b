//! `luxtally bench-rays`: ray throughput of every backend and ray API on a scene, and of
//! Embree's C loop over the same rays when built with the feature `bench`.

use super::timing::bench_rays;
use crate::progress::Progress;
use luxtally::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct BenchRaysArgs {
    pub scene: PathBuf,
    /// Rays per measurement.
    #[arg(long, default_value_t = 250_000)]
    pub rays: usize,
    /// Threads for the multi-threaded columns (default: all cores).
    #[arg(long)]
    pub threads: Option<usize>,
}

pub fn command(args: BenchRaysArgs) -> Result<()> {
    let scene = luxtally::scene::load(&args.scene)?;
    if args.rays == 0 {
        return Err(Error::input("--rays", "must be at least 1"));
    }
    let spinner = Progress::spinner();
    let table = bench_rays(
        &scene.geometry,
        &scene.name,
        args.rays,
        args.threads.unwrap_or_else(super::all_cores),
        cfg!(feature = "obvhs"),
        &|what| spinner.message(format!("bench-rays: {what}")),
    );
    spinner.clear();
    print!("{}", table?);
    Ok(())
}
