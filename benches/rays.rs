//! Ray-casting benchmark: `cargo bench --bench rays --features obvhs,bench` (without
//! `bench`, no C reference columns). Prints one Markdown section per scene (office room,
//! Stanford bunny, ≥1M-triangle procedural scene); BENCHMARKS.md records a run.

// The measurement of `luxtally bench-rays`, one source for both; the bench commands use
// the rest of it.
#[allow(dead_code)]
#[path = "../src/bin/luxtally/bench/timing.rs"]
mod timing;

use glam::DVec3;
use luxtally::fixtures::{load_obj_geometry, procedural_geometry};
use luxtally::scene::Geometry;
use std::path::Path;
use timing::bench_rays;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let obvhs = cfg!(feature = "obvhs");
    let rays = 250_000;
    let bunny_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/stanford-bunny.obj");
    let scenes: Vec<(&str, Geometry)> = vec![
        (
            "office room",
            luxtally::scene::load(
                &Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/office.toml"),
            )?
            .geometry,
        ),
        (
            "Stanford bunny",
            load_obj_geometry(&bunny_path, DVec3::ZERO)?,
        ),
        ("procedural", procedural_geometry(1_000_000)),
    ];
    println!("## Ray casting ({threads} threads available)\n");
    for (label, g) in &scenes {
        print!("{}", bench_rays(g, label, rays, threads, obvhs, &|_| {})?);
    }
    Ok(())
}
