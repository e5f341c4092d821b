//! Limits that fail cleanly: before a run or a render allocates anything large, the
//! memory it needs is estimated from the scene and the options, and a run that would not
//! fit stops with one line naming the receiver, map, geometry or camera at fault and the
//! figure, instead of aborting half-way with "memory allocation failed" (or leaving an
//! empty output folder behind).
//!
//! Estimates add up the parts a run holds: receiver tallies, the workers' scratch and
//! chunk tallies, the triangle maps, the geometry and its BVH, the outputs, the render's
//! image and ray buffers. Fixed-size parts are counted from their types' sizes; the rest
//! (BVH, outputs) from constants measured as peak RSS, each documented where defined.
//! The sum is compared with `--max-memory`, else with the memory available now
//! (`MemAvailable`, capped by a cgroup v2 limit).
//!
//! [`check_run`] also makes the run's own checks that keep user numbers from overflowing
//! the engine's index types ([`crate::run::check_indexes`]), before anything is allocated.

use crate::accel::{Backend, Bvh};
use crate::render::TILE_PIXELS;
use crate::run::RunOptions;
use crate::scene::file::{self, Source};
use crate::scene::{Camera, Scene};
use crate::tally::{CellPartial, CellSums, CODES_PER_TRIANGLE};
/// The tracer's per-triangle hit-surface table, counted for runs of up to
/// [`SURFACE_TABLE_MAX_TRIANGLES`] mapped triangles (≤ 2.6 MB).
pub use crate::trace::SURFACE_TABLE_BYTES_PER_TRIANGLE;
use crate::trace::{CHUNK_PHOTONS, SURFACE_TABLE_MAX_TRIANGLES};
use crate::{Error, Result};
use std::mem::size_of;
use std::path::Path;

/// Geometry and BVH per triangle with Embree (bytes): the scene's own arrays (which
/// Embree reads in place), Embree's BVH (build quality medium, with its build's peak)
/// and the per-triangle outputs (scene_map.ply, the checkpoint's copy of the triangle
/// maps). Measured: runs of 4 and 8 spheres of subdivision 8 (5.2 M and 10.5 M
/// triangles, 100,000 photons) peaked at 699 and 1328 MiB RSS: 126 bytes per triangle,
/// less the triangle maps' 32 (159 before areas, normals and the u32 material and object
/// ids stopped being stored per triangle).
pub const GEOMETRY_BYTES_PER_TRIANGLE_EMBREE: f64 = 94.0;

/// The same with Embree's compact BVH (`--bvh compact`, or `auto` when the fast one
/// would not fit): the same runs with the compact BVH peaked at 136 bytes per triangle,
/// less the maps' 32, before the per-triangle arrays shrank; 16 spheres (21 M
/// triangles) then peaked at 2628 MiB and now at 2069 MiB, 28 bytes per triangle less.
pub const GEOMETRY_BYTES_PER_TRIANGLE_EMBREE_COMPACT: f64 = 76.0;

/// The same with obvhs (its CWBVH build holds more while it builds): 1514 and 2994 MiB
/// for the same scenes as Embree's, 296 bytes per triangle, less the triangle maps' 32.
pub const GEOMETRY_BYTES_PER_TRIANGLE_OBVHS: f64 = 264.0;

/// Per instance of a `map = false` object (bytes): Embree's instance geometry and its
/// share of the top-level BVH, our `Instance` (transform, normal matrix, bounds).
/// Measured: 10⁶ instances of the bunny peaked at 538.9 MiB, 10² at 33.8 MiB (bench-scale,
/// 2026-11-27; 504 MiB the day before): 530 bytes per instance, rounded up for the
/// top-level build's variation; obvhs's top-level BVH over instance bounds is smaller
/// than Embree's.
pub const BYTES_PER_INSTANCE: f64 = 560.0;

/// Outputs per receiver cell at their peak (bytes): summary.json (the summary, its
/// pretty JSON text), report.html (the summary as JSON data, then as text), the EXR, CSV
/// and PNGs. Measured (2026-12-01): a 2000 × 2000-cell receiver peaked at 3.96 GB RSS at
/// the end of a 2-thread run, 991 bytes per cell, of which 96 are the tallies
/// (`CellSums`) and 112 the workers' scratch (2 × `CellPartial`): the per-cell status
/// arrays (scoring histories, VOV, dof, status, upper bound) more than tripled the
/// outputs' 240 bytes of before.
pub const OUTPUT_BYTES_PER_CELL: f64 = 790.0;

/// Chunk tallies a worker keeps from epoch to epoch (an epoch lasts up to 2 s, about
/// 1 M photons per thread in the office scene: 256 chunks of 4096 photons). An epoch
/// also lasts at most a quarter of the time run before it, so it holds at most a
/// quarter of a run's photons.
const CHUNKS_PER_THREAD: f64 = 256.0;

/// A chunk's receiver scores (distinct cells a photon of the chunk scores in: a few
/// crossings, or next-event connections) and triangle deposits (surface hits), per photon.
const SCORES_PER_PHOTON: f64 = 4.0;
const DEPOSITS_PER_PHOTON: f64 = 4.0;

/// Image buffers per pixel (bytes): the luminance, the tiles' copy of it and the
/// tone-mapping and PNG buffers. Measured: 4096 × 4096 and 2048 × 2048 renders with one
/// sample per pixel peaked 251 MiB apart, 21 bytes per pixel.
pub const IMAGE_BYTES_PER_PIXEL: f64 = 24.0;

/// A worker's eye-pass buffers per sample of its tile (bytes): eye rays (32), hits (28),
/// paths (16), the specular continuations (32 + 16) and the sample's luminance (8).
/// Measured: 169 bytes per sample with one point light (this + one shadow ray: 181).
const EYE_BYTES_PER_SAMPLE: f64 = 132.0;

/// Per shadow ray queued at an eye-ray hit: the ray (32), its gain (16), occluded (1).
const BYTES_PER_SHADOW_RAY: f64 = 49.0;

/// What a run may use: `--max-memory`, else the memory available.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Budget {
    /// `None`: unknown (no `--max-memory` and no /proc/meminfo): nothing is refused.
    pub bytes: Option<u64>,
    /// The bytes came from `--max-memory`.
    pub from_flag: bool,
}

impl Budget {
    /// `--max-memory` when given (e.g. `512M`, `8G`, `8GiB`, plain bytes), else the
    /// memory available now.
    pub fn new(max_memory: Option<&str>) -> Result<Budget> {
        Ok(match max_memory {
            Some(text) => Budget {
                bytes: Some(parse_size(text)?),
                from_flag: true,
            },
            None => Budget {
                bytes: available_bytes(),
                from_flag: false,
            },
        })
    }

    /// No limit (library use, tests).
    pub fn unlimited() -> Budget {
        Budget {
            bytes: None,
            from_flag: false,
        }
    }

    /// Whether `estimate` fits (always, when the budget is unknown).
    pub fn fits(&self, estimate: &Estimate) -> bool {
        self.bytes
            .is_none_or(|limit| estimate.total_bytes() <= limit as f64)
    }

    /// Errs with one line naming the largest part (and the total when the other parts
    /// matter) when `estimate` needs more than the budget. `origin` prefixes the message.
    pub fn check(&self, origin: &str, estimate: &Estimate) -> Result<()> {
        let Some(limit) = self.bytes else {
            return Ok(());
        };
        if self.fits(estimate) {
            return Ok(());
        }
        let total = estimate.total_bytes();
        let Some(largest) = estimate
            .parts
            .iter()
            .max_by(|a, b| a.bytes.total_cmp(&b.bytes))
        else {
            return Ok(());
        };
        let in_all = if total > 1.05 * largest.bytes {
            format!(" ({} for the whole run)", format_bytes(total))
        } else {
            String::new()
        };
        let limit_text = if self.from_flag {
            format!("{} allowed by --max-memory", format_bytes(limit as f64))
        } else {
            format!(
                "{} available (--max-memory to change)",
                format_bytes(limit as f64)
            )
        };
        Err(Error::input(
            origin,
            format!(
                "{} need {} {}{in_all}; {limit_text}",
                largest.what,
                format_bytes(largest.bytes),
                largest.of
            ),
        ))
    }
}

/// One part of a run's memory.
#[derive(Clone, Debug, PartialEq)]
pub struct Part {
    /// Who needs it, as the scene file names it: `receivers[0] "desk": 64 × 32 cells`.
    pub what: String,
    /// What the bytes hold: `of tallies and outputs`.
    pub of: &'static str,
    pub bytes: f64,
}

/// The parts of a run's memory (f64 bytes: user numbers multiply without overflow).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Estimate {
    pub parts: Vec<Part>,
}

impl Estimate {
    pub fn total_bytes(&self) -> f64 {
        self.parts.iter().map(|p| p.bytes).sum()
    }

    fn push(&mut self, what: String, of: &'static str, bytes: f64) {
        self.parts.push(Part { what, of, bytes });
    }
}

/// Geometry and BVH of `mapped` triangles (flattened, each with a triangle map; their
/// BVH the `layout` one, `Auto` counting as fast) and `prototypes` triangles (stored
/// once for the instances of `map = false` objects, in BVHs of their own, no map), the
/// mapped triangles' maps, and the tracer's hit-surface table when it has one.
pub fn geometry_estimate(mapped: u64, prototypes: u64, backend: Backend, layout: Bvh) -> Estimate {
    // Only the mapped triangles' (top) BVH is ever compact.
    let per_triangle = |compact: bool| match backend {
        Backend::Embree if compact => GEOMETRY_BYTES_PER_TRIANGLE_EMBREE_COMPACT,
        Backend::Embree => GEOMETRY_BYTES_PER_TRIANGLE_EMBREE,
        Backend::Obvhs => GEOMETRY_BYTES_PER_TRIANGLE_OBVHS,
    };
    let compact = layout == Bvh::Compact;
    let triangles = mapped.saturating_add(prototypes);
    let what = match prototypes {
        0 => format!("objects: {triangles} triangles"),
        _ => format!("objects: {triangles} triangles ({prototypes} in instanced prototypes)"),
    };
    let mut e = Estimate::default();
    e.push(
        what,
        match backend {
            Backend::Embree => "of geometry and embree BVH",
            Backend::Obvhs => "of geometry and obvhs BVH",
        },
        mapped as f64 * per_triangle(compact) + prototypes as f64 * per_triangle(false),
    );
    e.push(
        format!("triangle map: {mapped} triangles × {CODES_PER_TRIANGLE} slots"),
        "of tallies",
        // u32 counts (`tally::TriangleCounts`; u64 only past 4.3·10⁹ hits in a slot).
        mapped as f64 * (CODES_PER_TRIANGLE * size_of::<u32>()) as f64,
    );
    if mapped > 0 && mapped <= SURFACE_TABLE_MAX_TRIANGLES as u64 {
        e.push(
            format!("tracer: {mapped} triangles' hit surfaces"),
            "of surface table",
            (mapped * SURFACE_TABLE_BYTES_PER_TRIANGLE as u64) as f64,
        );
    }
    e
}

/// The photon pass besides the geometry: every receiver's tallies, its share of the
/// workers' scratch and its outputs, and the chunk tallies the workers keep.
pub fn photon_pass_estimate(scene: &Scene, options: &RunOptions) -> Estimate {
    let threads = options.threads.max(1) as f64;
    let per_cell = size_of::<CellSums>() as f64
        + threads * size_of::<CellPartial>() as f64
        + OUTPUT_BYTES_PER_CELL;
    let mut e = Estimate::default();
    for (i, r) in scene.receivers.iter().enumerate() {
        e.push(
            format!(
                "receivers[{i}] \"{}\": {} × {} cells",
                r.name, r.cells[0], r.cells[1]
            ),
            "of tallies and outputs",
            r.cells[0] as f64 * r.cells[1] as f64 * per_cell,
        );
    }
    let cells: f64 = scene
        .receivers
        .iter()
        .map(|r| r.cells[0] as f64 * r.cells[1] as f64)
        .sum();
    let photons = CHUNK_PHOTONS as f64;
    let mut chunks = threads * CHUNKS_PER_THREAD;
    if let Some(n) = options.stop.photons {
        chunks = chunks.min((0.25 * n as f64 / photons).ceil());
    }
    let per_chunk = cells.min(photons * SCORES_PER_PHOTON) * size_of::<CellPartial>() as f64
        + photons * DEPOSITS_PER_PHOTON * size_of::<u32>() as f64;
    e.push(
        format!("chunk tallies: {chunks} chunks of {CHUNK_PHOTONS} photons"),
        "of scores and deposits",
        chunks * per_chunk,
    );
    e
}

/// The eye pass: the image, and each worker's ray buffers for one tile of `samples`
/// samples per pixel (with the shadow rays of every light at each hit).
pub fn render_estimate(scene: &Scene, camera: &Camera, threads: usize) -> Estimate {
    let [w, h] = camera.resolution.map(|x| x as f64);
    let samples = camera.samples as f64;
    let shadow_rays: f64 = scene
        .lights
        .iter()
        .map(|l| l.kind.eye_shadow_rays(camera.area_light_samples))
        .sum();
    let tile = (w * h).min(TILE_PIXELS as f64);
    let threads = threads.max(1);
    let mut e = Estimate::default();
    e.push(
        format!(
            "camera: {} × {} pixels",
            camera.resolution[0], camera.resolution[1]
        ),
        "of image buffers",
        w * h * IMAGE_BYTES_PER_PIXEL,
    );
    e.push(
        format!(
            "camera: {} samples per pixel × {TILE_PIXELS}-pixel tiles × {threads} threads",
            camera.samples
        ),
        "of ray buffers",
        threads as f64
            * tile
            * samples
            * (EYE_BYTES_PER_SAMPLE + shadow_rays * BYTES_PER_SHADOW_RAY),
    );
    e
}

/// Checks a run of `scene` with `options` (and, for `render`, the eye pass of `camera`
/// after it, or alone with `photon_pass == false`) against `budget`, and the numbers
/// the engine indexes ([`crate::run::check_indexes`]). Call before allocating anything large: building
/// the BVH, tallies, the output folder.
pub fn check_run(
    scene: &Scene,
    options: &RunOptions,
    camera: Option<&Camera>,
    photon_pass: bool,
    budget: &Budget,
) -> Result<Bvh> {
    crate::run::check_threads(options.threads)?;
    let origin = scene.path.display().to_string();
    let g = &scene.geometry;
    let (mapped, prototypes) = (
        g.triangle_count() as u64,
        g.instanced.stored_triangle_count() as u64,
    );
    let run = photon_pass.then(|| photon_pass_estimate(scene, options));
    let eye = camera.map(|c| render_estimate(scene, c, options.threads));
    // The photon pass's tallies are gone when the eye pass starts: the larger counts.
    let rest = match (run, eye) {
        (Some(r), Some(e)) if e.total_bytes() > r.total_bytes() => e,
        (Some(r), _) => r,
        (None, e) => e.unwrap_or_default(),
    };
    let instances = g.instanced.instances.len();
    let with_layout = |layout| {
        let mut estimate = geometry_estimate(mapped, prototypes, options.backend, layout);
        if instances > 0 {
            estimate.push(
                format!("objects: {instances} instances"),
                "of instance transforms and BVH",
                instances as f64 * BYTES_PER_INSTANCE,
            );
        }
        estimate.parts.extend(rest.parts.iter().cloned());
        estimate
    };
    let layout = choose_bvh(options.bvh, options.backend, |l| {
        budget.fits(&with_layout(l))
    });
    budget.check(&origin, &with_layout(layout))?;
    crate::run::check_indexes(scene, options.threads)?;
    Ok(layout)
}

/// The BVH a run builds: `choice`, unless `Auto`, which takes Embree's fast BVH when
/// the run `fits` with it and the compact one otherwise (obvhs has one layout). When
/// neither fits, the compact one: the refusal then names the smaller need.
pub fn choose_bvh(choice: Bvh, backend: Backend, fits: impl Fn(Bvh) -> bool) -> Bvh {
    match (choice, backend) {
        (Bvh::Auto, Backend::Obvhs) => Bvh::Fast,
        (Bvh::Auto, Backend::Embree) if fits(Bvh::Fast) => Bvh::Fast,
        (Bvh::Auto, Backend::Embree) => Bvh::Compact,
        (chosen, _) => chosen,
    }
}

/// Before tessellating: the triangles the scene file's built-in shapes will make (mesh
/// files are counted once loaded, by [`check_run`]) against `budget`, so a file of many
/// finely subdivided spheres is refused before the loader builds them: a mapped shape's
/// triangles with a map for every copy, an instanced one's once without. A file that
/// does not parse passes: the loader reports it.
pub fn check_scene_file(path: &Path, backend: Backend, layout: Bvh, budget: &Budget) -> Result<()> {
    if budget.bytes.is_none() {
        return Ok(());
    }
    let Ok(text) = std::fs::read_to_string(path) else {
        return Ok(());
    };
    let origin = path.display().to_string();
    let Ok(raw) = file::parse(&text, &origin) else {
        return Ok(());
    };
    let (mut mapped, mut prototypes) = (0u64, 0u64);
    for value in raw.objects {
        let Ok(entry) = file::object(value, &origin, "objects") else {
            continue;
        };
        let Source::Shape(shape) = &entry.source else {
            continue;
        };
        let Some(triangles) = shape.triangle_count() else {
            continue;
        };
        if entry.object.mapped() {
            let copies = triangles.saturating_mul(entry.object.copy_count());
            mapped = mapped.saturating_add(copies);
        } else {
            prototypes = prototypes.saturating_add(triangles);
        }
    }
    // Refused only if the smallest BVH the run may choose would not fit.
    let smallest = choose_bvh(layout, backend, |_| false);
    let estimate = geometry_estimate(mapped, prototypes, backend, smallest);
    budget.check(&origin, &estimate)
}

/// Memory available to this process now (bytes): `MemAvailable` of /proc/meminfo,
/// capped by the cgroup v2 limit less what the cgroup uses. `None` when unreadable.
pub fn available_bytes() -> Option<u64> {
    let meminfo = std::fs::read_to_string("/proc/meminfo").ok()?;
    let available = meminfo
        .lines()
        .find_map(|l| l.strip_prefix("MemAvailable:"))
        .and_then(|rest| rest.trim().strip_suffix("kB"))
        .and_then(|kib| kib.trim().parse::<u64>().ok())?
        .saturating_mul(1024);
    let read = |name: &str| -> Option<u64> {
        std::fs::read_to_string(Path::new("/sys/fs/cgroup").join(name))
            .ok()?
            .trim()
            .parse()
            .ok()
    };
    Some(match (read("memory.max"), read("memory.current")) {
        (Some(max), Some(used)) => available.min(max.saturating_sub(used)),
        _ => available,
    })
}

/// A size as users write it: plain bytes, or a number with a unit: `K`, `M`, `G`, `T`
/// (optionally with `B`: `kB`, `MB`...) are powers of 1000, `KiB`, `MiB`, `GiB`, `TiB`
/// (or `Ki`...) powers of 1024; case does not matter, fractions are allowed (`1.5G`).
pub fn parse_size(text: &str) -> Result<u64> {
    let bad = || {
        Error::input(
            "--max-memory",
            format!("`{text}` is not a size (e.g. 512M, 8G, 8GiB or plain bytes)"),
        )
    };
    let t = text.trim();
    let split = t
        .find(|c: char| !(c.is_ascii_digit() || c == '.'))
        .unwrap_or(t.len());
    let (number, unit) = t.split_at(split);
    let unit = unit.trim().to_ascii_lowercase();
    let unit = unit.strip_suffix('b').unwrap_or(&unit);
    let (power, base) = match unit.strip_suffix('i') {
        Some(u) => (u, 1024f64),
        None => (unit, 1000f64),
    };
    let exponent = match power {
        "" if base == 1000.0 => 0,
        "k" => 1,
        "m" => 2,
        "g" => 3,
        "t" => 4,
        "p" => 5,
        _ => return Err(bad()),
    };
    let value: f64 = number.parse().map_err(|_| bad())?;
    let bytes = (value * base.powi(exponent)).round();
    if bytes.is_nan() || bytes < 1.0 {
        return Err(Error::input(
            "--max-memory",
            format!("`{text}` is not more than 0 bytes"),
        ));
    }
    // f64 → u64 saturates: sizes past 16 EiB are as good as unlimited.
    Ok(bytes as u64)
}

/// Bytes in decimal units with one decimal: `880.0 GB`.
pub fn format_bytes(bytes: f64) -> String {
    const UNITS: [&str; 7] = ["B", "kB", "MB", "GB", "TB", "PB", "EB"];
    let mut value = bytes;
    let mut unit = 0;
    while value >= 1000.0 && unit + 1 < UNITS.len() {
        value /= 1000.0;
        unit += 1;
    }
    if unit == 0 {
        format!("{value:.0} B")
    } else {
        format!("{value:.1} {}", UNITS[unit])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sizes_parse_in_decimal_and_binary_units() {
        assert_eq!(parse_size("1024").unwrap(), 1024);
        assert_eq!(parse_size("512M").unwrap(), 512_000_000);
        assert_eq!(parse_size("8G").unwrap(), 8_000_000_000);
        assert_eq!(parse_size("8gb").unwrap(), 8_000_000_000);
        assert_eq!(parse_size("8GiB").unwrap(), 8 << 30);
        assert_eq!(parse_size("8 Gi").unwrap(), 8 << 30);
        assert_eq!(parse_size("1.5k").unwrap(), 1500);
        assert_eq!(parse_size("100000T").unwrap(), 100_000_000_000_000_000);
        for bad in ["", "M", "8X", "8GG", "-1G", "0", "1..5G", "8 B B", "nan"] {
            assert!(parse_size(bad).is_err(), "{bad:?} parsed");
        }
    }

    #[test]
    fn bytes_print_in_decimal_units() {
        assert_eq!(format_bytes(880e9), "880.0 GB");
        assert_eq!(format_bytes(999.0), "999 B");
        assert_eq!(format_bytes(23.1e9), "23.1 GB");
        assert_eq!(format_bytes(4.24e12), "4.2 TB");
    }

    #[test]
    fn the_largest_part_is_named_with_the_whole_run() {
        let mut e = Estimate::default();
        e.push(
            "receivers[0] \"desk\": 2 × 2 cells".into(),
            "of tallies and outputs",
            3e9,
        );
        e.push(
            "objects: 12 triangles".into(),
            "of geometry and embree BVH",
            1e9,
        );
        let budget = Budget {
            bytes: Some(2_000_000_000),
            from_flag: true,
        };
        let message = budget.check("s.toml", &e).unwrap_err().to_string();
        assert_eq!(
            message,
            "s.toml: receivers[0] \"desk\": 2 × 2 cells need 3.0 GB of tallies and outputs \
             (4.0 GB for the whole run); 2.0 GB allowed by --max-memory"
        );
        assert!(Budget::unlimited().check("s.toml", &e).is_ok());
        let roomy = Budget {
            bytes: Some(4_000_000_000),
            from_flag: false,
        };
        assert!(roomy.check("s.toml", &e).is_ok());
    }

    #[test]
    fn memory_available_is_read_on_linux() {
        if Path::new("/proc/meminfo").exists() {
            assert!(available_bytes().is_some_and(|b| b > 0));
        }
    }
}
