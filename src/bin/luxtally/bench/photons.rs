//! `luxtally bench-photons`: photon-tracing throughput against raw ray casting on the
//! same scene and backend.

use crate::progress::Progress;
use luxtally::accel::Backend;
use luxtally::Result;
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct BenchPhotonsArgs {
    pub scene: PathBuf,
    #[arg(long, default_value_t = 2_000_000)]
    pub photons: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    #[arg(long, default_value = "embree", hide_possible_values = true)]
    pub backend: Backend,
}

/// Photon throughput on a scene file, or on `procedural` geometry.
pub fn command(args: BenchPhotonsArgs) -> Result<()> {
    let scene = if args.scene.as_os_str() == "procedural" {
        luxtally::bench::lit_scene(
            "procedural",
            luxtally::bench::procedural_geometry(1_000_000),
        )
    } else {
        luxtally::scene::load(&args.scene)?
    };
    let spinner = Progress::spinner();
    let table = luxtally::bench::bench_photons(
        &scene,
        args.photons,
        args.threads.unwrap_or_else(super::all_cores),
        args.backend,
        &|what| spinner.message(format!("bench-photons: {what}")),
    );
    spinner.clear();
    print!("{}", table?);
    Ok(())
}
