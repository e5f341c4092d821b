//! Ray-casting benchmark: `cargo bench --bench rays --features obvhs`.
//! Prints one Markdown section per scene (office room, Stanford bunny, ≥1M-triangle
//! procedural scene); BENCHMARKS.md records a run.

use glam::DVec3;
use luxtally::bench::{bench_rays, load_obj_geometry, procedural_geometry};
use luxtally::scene::Geometry;
use std::path::Path;

/// A 6 × 5 × 3 m office: the room's six walls (two triangles each) and a 1.6 × 0.8 m
/// table top at 0.75 m.
fn office() -> Geometry {
    let mut verts = Vec::new();
    let mut tris = Vec::new();
    let mut quad = |a: DVec3, b: DVec3, c: DVec3, d: DVec3| {
        let base = verts.len() as u32;
        verts.extend([a, b, c, d]);
        tris.push([base, base + 1, base + 2]);
        tris.push([base, base + 2, base + 3]);
    };
    let (x, y, z) = (6.0, 5.0, 3.0);
    let p = DVec3::new;
    quad(p(0., 0., 0.), p(x, 0., 0.), p(x, y, 0.), p(0., y, 0.)); // floor
    quad(p(0., 0., z), p(0., y, z), p(x, y, z), p(x, 0., z)); // ceiling
    quad(p(0., 0., 0.), p(0., 0., z), p(x, 0., z), p(x, 0., 0.));
    quad(p(0., y, 0.), p(x, y, 0.), p(x, y, z), p(0., y, z));
    quad(p(0., 0., 0.), p(0., y, 0.), p(0., y, z), p(0., 0., z));
    quad(p(x, 0., 0.), p(x, 0., z), p(x, y, z), p(x, y, 0.));
    quad(
        p(2.2, 2.1, 0.75),
        p(3.8, 2.1, 0.75),
        p(3.8, 2.9, 0.75),
        p(2.2, 2.9, 0.75),
    ); // table
    let zeros = vec![0; tris.len()];
    Geometry::from_world(&verts, &tris, &zeros, &zeros)
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let threads = std::thread::available_parallelism().map_or(1, |n| n.get());
    let obvhs = cfg!(feature = "obvhs");
    let rays = 250_000;
    let bunny_path = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/meshes/stanford-bunny.obj");
    let scenes: Vec<(&str, Geometry)> = vec![
        ("office room", office()),
        (
            "Stanford bunny",
            load_obj_geometry(&bunny_path, DVec3::ZERO)?,
        ),
        ("procedural", procedural_geometry(1_000_000)),
    ];
    println!("## Ray casting ({threads} threads available)\n");
    for (label, g) in &scenes {
        print!("{}", bench_rays(g, label, rays, threads, obvhs)?);
    }
    Ok(())
}
