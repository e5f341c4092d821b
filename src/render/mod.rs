//! The eye pass (method.md §1): backward ray tracing from a `[camera]` that turns the
//! photon pass's secondary map into the image a lighting designer looks at. Diffuse
//! surfaces show direct light computed deterministically (eqs. 1–2, shadow rays) plus the
//! interpolated indirect map; mirrors and glass only redirect the eye ray.
//!
//! Data path: scene + `output::IndirectMap` (from the run's tallies or
//! `indirect_map.bin`) → `IndirectField` → `EyePass` over the run's ray caster →
//! `output::Image`, which `output::write_all` writes (EXR, tone-mapped PNG, false-colour
//! PNG).

mod eye;
pub mod map;

pub use eye::{area_samples_per_side, EyePass, RayCounts, Scratch, MAX_AREA_SAMPLES, TILE_PIXELS};
pub use map::IndirectField;

use crate::accel::RayCaster;
use crate::output::{Image, IndirectMap};
use crate::scene::{Camera, Scene};
use crate::{Error, Result};
use rayon::prelude::*;
use std::time::Instant;

/// A rendered image and what it cost.
#[derive(Clone, Debug)]
pub struct Render {
    pub image: Image,
    pub rays: RayCounts,
    pub elapsed_s: f64,
}

impl Render {
    /// Eye rays (primary and specular, not shadow rays) per second.
    pub fn eye_rays_per_s(&self) -> f64 {
        self.rays.eye as f64 / self.elapsed_s.max(1e-9)
    }

    /// Seconds per million pixels.
    pub fn s_per_megapixel(&self) -> f64 {
        self.elapsed_s / (self.image.width * self.image.height) as f64 * 1e6
    }
}

/// The scene's camera, or an error naming the file.
pub fn camera_of(scene: &Scene) -> Result<&Camera> {
    scene.camera.as_ref().ok_or_else(|| {
        Error::input(
            scene.path.display().to_string(),
            "no [camera] table: luxtally render needs one (see docs/render.md)",
        )
    })
}

/// Renders `camera`'s view of `scene` with indirect light from `map`, on `threads`
/// threads. Pixels are split into fixed tiles and each pixel has its own random stream
/// (from `seed`), so the image does not depend on the threads.
pub fn render(
    scene: &Scene,
    camera: &Camera,
    map: &IndirectMap,
    caster: &dyn RayCaster,
    seed: u64,
    threads: usize,
) -> Result<Render> {
    render_with(scene, camera, map, caster, seed, threads, &|_| {})
}

/// [`render`], calling `on_tile(pixels)` from the worker threads as each tile is done
/// (a progress display).
pub fn render_with(
    scene: &Scene,
    camera: &Camera,
    map: &IndirectMap,
    caster: &dyn RayCaster,
    seed: u64,
    threads: usize,
    on_tile: &(dyn Fn(usize) + Sync),
) -> Result<Render> {
    if map.face_lx.len() != scene.geometry.triangle_count() {
        return Err(Error::input(
            scene.path.display().to_string(),
            "the indirect map does not match the scene's triangles",
        ));
    }
    let start = Instant::now();
    let field = IndirectField::new(scene, map, camera.interpolate);
    let pass = EyePass::new(scene, camera, &field, caster, seed);
    let pixels = pass.pixel_count();
    let tiles: Vec<(usize, usize)> = (0..pixels)
        .step_by(TILE_PIXELS)
        .map(|first| (first, TILE_PIXELS.min(pixels - first)))
        .collect();
    let pool = crate::run::thread_pool(threads.max(1))?;
    let results: Vec<(Vec<f64>, RayCounts)> = pool.install(|| {
        tiles
            .par_iter()
            .map_init(Scratch::default, |s, &(first, n)| {
                let tile = pass.render_tile(first, n, s);
                on_tile(n);
                tile
            })
            .collect()
    });
    let mut luminance_cdm2 = Vec::with_capacity(pixels);
    let mut rays = RayCounts::default();
    for (tile, counts) in results {
        luminance_cdm2.extend(tile);
        rays.eye += counts.eye;
        rays.shadow += counts.shadow;
    }
    Ok(Render {
        image: Image {
            width: camera.resolution[0] as usize,
            height: camera.resolution[1] as usize,
            luminance_cdm2,
        },
        rays,
        elapsed_s: start.elapsed().as_secs_f64(),
    })
}
