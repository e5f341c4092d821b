//! `luxtally info`: a scene's statistics (triangles, materials, lights, receivers,
//! bounds).

use luxtally::Result;
use std::path::Path;

pub fn command(path: &Path) -> Result<()> {
    let scene = luxtally::scene::load(path)?;
    let g = &scene.geometry;
    println!(
        "scene {}: {} triangles, {:.3} m² of surface",
        scene.name,
        g.triangle_count(),
        g.total_area_m2()
    );
    if !g.instanced.is_empty() {
        println!(
            "  unmapped: {} instances of {} prototypes ({} triangles stored, {} if flattened)",
            g.instanced.instances.len(),
            g.instanced.prototypes.len(),
            g.instanced.stored_triangle_count(),
            g.instanced.flattened_triangle_count()
        );
    }
    if let Some((lo, hi)) = g.world_bounds() {
        println!("  bounds {:.3?} → {:.3?}", lo.to_array(), hi.to_array());
    }
    for m in &scene.materials {
        println!("  material {}: {}", m.name, m.describe());
    }
    for l in &scene.lights {
        println!("  {}: {}", l.label, l.kind.describe());
    }
    for r in &scene.receivers {
        let rule = r.grid.map_or(String::new(), |g| {
            format!(
                " (EN 12464-1 grid, band {} m, rounded {})",
                g.band_m,
                g.rounding.name()
            )
        });
        println!(
            "  receiver {}: {}×{} cells of {:.4} m²{rule}",
            r.name,
            r.cells[0],
            r.cells[1],
            r.cell_area_m2()
        );
    }
    Ok(())
}
