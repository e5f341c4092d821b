//! Ray-casting benchmarks and the scenes they run on: a procedural scene of any size,
//! a small OBJ loader for the test meshes, random ray sets, and `bench_rays`, which
//! times every backend and API against the C reference (`benches/c/embree_reference.c`).

use crate::accel::embree::{sys, EmbreeScene};
use crate::accel::{HitBatch, RayApi, RayBatch, RayCaster};
use crate::scene::Geometry;
use crate::stats::forecast::HistoryPoint;
use crate::{Error, Result};
use glam::{DVec3, Vec3};
use rand::Rng;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::path::Path;
use std::time::Instant;

/// Rays per parallel work item in the benchmark.
pub const CHUNK: usize = 4096;

/// A deterministic scene of at least `min_triangles` triangles with real depth
/// complexity: a bumpy 100 m × 100 m heightfield under a field of overlapping spheres of
/// different sizes floating at different heights.
pub fn procedural_geometry(min_triangles: usize) -> Geometry {
    let (verts, tris) = procedural_mesh(min_triangles);
    Geometry::uniform(&verts, tris, 0, 0)
}

/// The world-space vertices and triangles of [`procedural_geometry`], generated in
/// parallel (every vertex and triangle alone, so the values do not depend on the
/// threads; the spheres' random centres and radii are drawn first, in order).
pub fn procedural_mesh(min_triangles: usize) -> (Vec<DVec3>, Vec<[u32; 3]>) {
    // Heightfield: about 40 % of the budget, 2·n² triangles.
    let n = (((min_triangles as f64 * 0.4) / 2.0).sqrt().ceil() as usize).max(2);
    let size = 100.0;
    let field_vertices = (n + 1) * (n + 1);
    let field_triangles = 2 * n * n;

    // Spheres (UV, 48 × 24: 2 208 triangles each) until the budget is reached.
    let (seg, rings) = (48usize, 24usize);
    let sphere_vertices = (rings + 1) * seg;
    let at = |k: usize, s: usize| (k * seg + s % seg) as u32;
    let mut pattern: Vec<[u32; 3]> = Vec::new();
    for k in 0..rings {
        for s in 0..seg {
            // Quads between two rings; fans at the poles.
            // Skip the halves that collapse onto a pole.
            if k + 1 != rings {
                pattern.push([at(k, s), at(k + 1, s), at(k + 1, s + 1)]);
            }
            if k != 0 {
                pattern.push([at(k, s), at(k + 1, s + 1), at(k, s + 1)]);
            }
        }
    }
    let spheres = min_triangles
        .saturating_sub(field_triangles)
        .div_ceil(pattern.len());
    let mut rng = crate::rng::aux_stream(0x5eed);
    let placed: Vec<(DVec3, f64)> = (0..spheres)
        .map(|_| {
            let c = DVec3::new(
                rng.random_range(-45.0..45.0),
                rng.random_range(-45.0..45.0),
                rng.random_range(0.0..12.0),
            );
            (c, rng.random_range(0.3..4.0))
        })
        .collect();

    // Trigonometry by table: the heightfield's factors depend on one coordinate each,
    // a sphere's direction and displacement on the vertex's place in the pattern only
    // (27 M sin/cos calls at 10⁷ triangles were most of the generation's time).
    let coordinate = |i: usize| -size / 2.0 + size * i as f64 / n as f64;
    let (sin_x, cos_y): (Vec<f64>, Vec<f64>) = (0..=n)
        .map(|i| {
            (
                libm::sin(0.31 * coordinate(i)),
                libm::cos(0.23 * coordinate(i)),
            )
        })
        .unzip();
    let unit_sphere: Vec<(DVec3, f64)> = (0..sphere_vertices)
        .map(|index| {
            let (k, s) = (index / seg, index % seg);
            let theta = std::f64::consts::PI * k as f64 / rings as f64;
            let phi = std::f64::consts::TAU * s as f64 / seg as f64;
            let d = DVec3::new(
                libm::sin(theta) * libm::cos(phi),
                libm::sin(theta) * libm::sin(phi),
                libm::cos(theta),
            );
            // A little displacement so no two spheres are alike.
            (
                d,
                1.0 + 0.05 * libm::sin(5.0 * phi) * libm::sin(3.0 * theta),
            )
        })
        .collect();

    let mut verts: Vec<DVec3> = Vec::new();
    (0..field_vertices + spheres * sphere_vertices)
        .into_par_iter()
        .map(|index| {
            if index < field_vertices {
                let (i, j) = (index % (n + 1), index / (n + 1));
                let (x, y) = (coordinate(i), coordinate(j));
                let z = 1.5 * sin_x[i] * cos_y[j] + 0.4 * libm::sin(1.7 * x + 0.9 * y);
                return DVec3::new(x, y, z);
            }
            let index = index - field_vertices;
            let (c, r) = placed[index / sphere_vertices];
            let (d, displacement) = unit_sphere[index % sphere_vertices];
            c + d * r * displacement
        })
        .collect_into_vec(&mut verts);

    let mut tris: Vec<[u32; 3]> = Vec::new();
    let field_at = |i: usize, j: usize| (j * (n + 1) + i) as u32;
    (0..field_triangles + spheres * pattern.len())
        .into_par_iter()
        .map(|index| {
            if index < field_triangles {
                let (i, j) = ((index / 2) % n, (index / 2) / n);
                return if index % 2 == 0 {
                    [field_at(i, j), field_at(i + 1, j), field_at(i + 1, j + 1)]
                } else {
                    [field_at(i, j), field_at(i + 1, j + 1), field_at(i, j + 1)]
                };
            }
            let index = index - field_triangles;
            let base = (field_vertices + index / pattern.len() * sphere_vertices) as u32;
            pattern[index % pattern.len()].map(|v| base + v)
        })
        .collect_into_vec(&mut tris);
    (verts, tris)
}

/// Loads a mesh file (OBJ or glTF) through the scene loader as one `Geometry`,
/// translated by `offset` in world space.
pub fn load_obj_geometry(path: &Path, offset: DVec3) -> Result<Geometry> {
    let file = path.display().to_string().replace('\\', "/");
    let toml = format!(
        "[materials.m]\nreflectance = 0.5\n[[objects]]\nfile = \"{file}\"\nmaterial = \"m\"\ntranslate = [{}, {}, {}]\n",
        offset.x, offset.y, offset.z
    );
    Ok(crate::scene::load_str(&toml, Path::new("."), &file)?.geometry)
}

/// Local-frame bounds of the geometry (zero box when empty).
pub fn local_bounds(g: &Geometry) -> (Vec3, Vec3) {
    let mut it = g.vertices.iter();
    let Some(first) = it.next() else {
        return (Vec3::ZERO, Vec3::ZERO);
    };
    it.fold((*first, *first), |(lo, hi), v| (lo.min(*v), hi.max(*v)))
}

/// Uniform direction on the unit sphere.
fn random_dir(rng: &mut impl Rng) -> Vec3 {
    let z: f32 = rng.random_range(-1.0..1.0);
    let phi: f32 = rng.random_range(0.0..std::f32::consts::TAU);
    let r = (1.0 - z * z).max(0.0).sqrt();
    Vec3::new(r * libm::cosf(phi), r * libm::sinf(phi), z)
}

/// `n` incoherent rays: origins uniform in the bounds, uniform unit directions,
/// `tnear = 0`, `tfar = ∞`.
pub fn random_rays(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> RayBatch {
    let mut rng = crate::rng::aux_stream(seed);
    let mut rays = RayBatch::with_capacity(n);
    for _ in 0..n {
        let o = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let d = random_dir(&mut rng);
        rays.push(o.to_array(), d.to_array(), 0.0, f32::INFINITY);
    }
    rays
}

/// `n` shadow rays between two uniform points of the bounds (unit direction,
/// `tfar` = their distance).
pub fn random_segments(lo: Vec3, hi: Vec3, n: usize, seed: u64) -> RayBatch {
    let mut rng = crate::rng::aux_stream(seed);
    let mut rays = RayBatch::with_capacity(n);
    while rays.len() < n {
        let a = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let b = lo + (hi - lo) * Vec3::new(rng.random(), rng.random(), rng.random());
        let len = (b - a).length();
        if len > 0.0 {
            rays.push(a.to_array(), ((b - a) / len).to_array(), 0.0, len);
        }
    }
    rays
}

/// Splits a batch into consecutive batches of at most `chunk` rays.
pub fn split(rays: &RayBatch, chunk: usize) -> Vec<RayBatch> {
    let mut out = Vec::new();
    let mut start = 0;
    while start < rays.len() {
        let end = (start + chunk).min(rays.len());
        out.push(RayBatch {
            ox: rays.ox[start..end].to_vec(),
            oy: rays.oy[start..end].to_vec(),
            oz: rays.oz[start..end].to_vec(),
            dx: rays.dx[start..end].to_vec(),
            dy: rays.dy[start..end].to_vec(),
            dz: rays.dz[start..end].to_vec(),
            tnear: rays.tnear[start..end].to_vec(),
            tfar: rays.tfar[start..end].to_vec(),
        });
        start = end;
    }
    out
}

/// `VmRSS` and `VmHWM` of this process in MiB (0 where /proc is unavailable).
pub fn memory_mib() -> (f64, f64) {
    let status = std::fs::read_to_string("/proc/self/status").unwrap_or_default();
    let field = |name: &str| -> f64 {
        status
            .lines()
            .find_map(|l| l.strip_prefix(name))
            .and_then(|rest| rest.split_whitespace().next()?.parse::<f64>().ok())
            .map_or(0.0, |kib| kib / 1024.0)
    };
    (field("VmRSS:"), field("VmHWM:"))
}

/// CPU seconds (user + system, all threads) used by this process so far (0 where
/// /proc is unavailable).
pub fn process_cpu_seconds() -> f64 {
    let stat = std::fs::read_to_string("/proc/self/stat").unwrap_or_default();
    // Fields after the parenthesised command name: utime and stime are the 12th and
    // 13th, in clock ticks (100 per second on Linux).
    let fields: Vec<&str> = stat
        .rsplit_once(')')
        .map_or(Vec::new(), |(_, rest)| rest.split_whitespace().collect());
    let ticks = |k: usize| fields.get(k).and_then(|f| f.parse::<f64>().ok());
    match (ticks(11), ticks(12)) {
        (Some(user), Some(system)) => (user + system) / 100.0,
        _ => 0.0,
    }
}

/// The SoA rays as the C reference reads them.
#[repr(C)]
struct CRays {
    ox: *const f32,
    oy: *const f32,
    oz: *const f32,
    dx: *const f32,
    dy: *const f32,
    dz: *const f32,
    tnear: *const f32,
    tfar: *const f32,
}

/// The outputs the C reference writes.
#[repr(C)]
struct CHits {
    t: *mut f32,
    u: *mut f32,
    v: *mut f32,
    ngx: *mut f32,
    ngy: *mut f32,
    ngz: *mut f32,
    prim: *mut u32,
    occluded: *mut u8,
}

extern "C" {
    fn luxtally_c_trace(
        scene: sys::RTCScene,
        rays: *const CRays,
        hits: *mut CHits,
        n: usize,
        api: i32,
        occlusion: i32,
        iterations: i32,
    ) -> f64;
    fn luxtally_thread_cpu_s() -> f64;
}

/// CPU seconds consumed by the calling thread (`CLOCK_THREAD_CPUTIME_ID`).
pub fn thread_cpu_seconds() -> f64 {
    // SAFETY: a plain C function without arguments or shared state.
    unsafe { luxtally_thread_cpu_s() }
}

/// Mrays/s of the C reference over `rays` on one thread (best of `iterations`).
fn c_mrays(
    scene: &EmbreeScene,
    rays: &RayBatch,
    api: RayApi,
    occlusion: bool,
    iterations: i32,
) -> f64 {
    let n = rays.len();
    let mut hits = HitBatch::default();
    hits.reset(n);
    let mut occ = vec![0u8; n];
    let c_rays = CRays {
        ox: rays.ox.as_ptr(),
        oy: rays.oy.as_ptr(),
        oz: rays.oz.as_ptr(),
        dx: rays.dx.as_ptr(),
        dy: rays.dy.as_ptr(),
        dz: rays.dz.as_ptr(),
        tnear: rays.tnear.as_ptr(),
        tfar: rays.tfar.as_ptr(),
    };
    let mut c_hits = CHits {
        t: hits.t.as_mut_ptr(),
        u: hits.u.as_mut_ptr(),
        v: hits.v.as_mut_ptr(),
        ngx: hits.ngx.as_mut_ptr(),
        ngy: hits.ngy.as_mut_ptr(),
        ngz: hits.ngz.as_mut_ptr(),
        prim: hits.tri.as_mut_ptr(),
        occluded: occ.as_mut_ptr(),
    };
    let api = match api {
        RayApi::Single => 0,
        RayApi::Packet8 => 1,
        RayApi::Packet16 => 2,
        RayApi::Stream => 3,
    };
    // SAFETY: the scene is committed and outlives the call; every array holds `n`
    // elements and is not otherwise accessed during the call.
    let seconds = unsafe {
        luxtally_c_trace(
            scene.raw_scene(),
            &c_rays,
            &mut c_hits,
            n,
            api,
            occlusion as i32,
            iterations,
        )
    };
    n as f64 / seconds / 1e6
}

/// Best-of-`iterations` Mrays/s of `caster` through `api` over `chunks`, on the current
/// thread (`pool == None`) or on every thread of `pool`.
fn rust_mrays(
    caster: &dyn RayCaster,
    api: RayApi,
    chunks: &[RayBatch],
    occlusion: bool,
    pool: Option<&rayon::ThreadPool>,
    iterations: usize,
) -> f64 {
    let n: usize = chunks.iter().map(RayBatch::len).sum();
    let run_one = |hits: &mut HitBatch, occ: &mut Vec<bool>, b: &RayBatch| {
        if occlusion {
            caster.occluded_with(api, b, occ);
        } else {
            caster.intersect_with(api, b, hits);
        }
    };
    let mut best = f64::INFINITY;
    for _ in 0..iterations {
        // One thread: its CPU time (robust to other processes on the machine, like the
        // C reference); several threads: wall time.
        let seconds = match pool {
            None => {
                let start = thread_cpu_seconds();
                let (mut hits, mut occ) = (HitBatch::default(), Vec::new());
                for b in chunks {
                    run_one(&mut hits, &mut occ, b);
                }
                thread_cpu_seconds() - start
            }
            Some(pool) => {
                let start = Instant::now();
                pool.install(|| {
                    chunks.par_iter().for_each_init(
                        || (HitBatch::default(), Vec::new()),
                        |(hits, occ), b| run_one(hits, occ, b),
                    )
                });
                start.elapsed().as_secs_f64()
            }
        };
        best = best.min(seconds);
    }
    n as f64 / best / 1e6
}

/// Times every backend and API on `rays` random closest-hit rays and as many shadow
/// rays over `geometry`, on 1 and on `threads` threads, plus the C reference; returns
/// a Markdown section. `progress` is told each measurement as it starts.
pub fn bench_rays(
    geometry: &Geometry,
    label: &str,
    rays: usize,
    threads: usize,
    obvhs: bool,
    progress: &dyn Fn(&str),
) -> Result<String> {
    let (lo, hi) = local_bounds(geometry);
    let set = RaySets::new(
        random_rays(lo, hi, rays, 1),
        random_segments(lo, hi, rays, 2),
    );
    let pool = crate::run::thread_pool(threads.max(1))?;

    let mut out = String::new();
    let _ = writeln!(
        out,
        "### {label}: {} triangles, {rays} rays per measurement\n",
        geometry.triangle_count()
    );
    let _ = writeln!(
        out,
        "| backend | API | closest 1T | closest {threads}T | occlusion 1T | occlusion {threads}T | C closest 1T | Rust/C closest | C occlusion 1T | Rust/C occlusion |"
    );
    let _ = writeln!(out, "|---|---|---:|---:|---:|---:|---:|---:|---:|---:|");

    progress("embree: BVH build");
    let (embree, note) = timed_build("embree", || EmbreeScene::new(geometry))?;
    let mut builds = vec![note];
    let best = embree_rows(&embree, &set, &pool, &mut out, progress);
    drop(embree);

    #[cfg(feature = "obvhs")]
    if obvhs {
        progress("obvhs: BVH build");
        let (bvh, note) =
            timed_build("obvhs", || Ok(crate::accel::bvh::ObvhsScene::new(geometry)))?;
        builds.push(note);
        progress("obvhs: closest and occlusion rays");
        let (c1, o1) = obvhs_row(&bvh, &set, &pool, &mut out);
        builds.push(format!(
            "Embree (best API) / obvhs, 1 thread: closest {:.2}×, occlusion {:.2}×",
            best.0 / c1,
            best.1 / o1
        ));
    }
    #[cfg(not(feature = "obvhs"))]
    if obvhs {
        let _ = best;
        builds.push("obvhs: not in this build (feature `obvhs`)".into());
    }

    let _ = writeln!(out, "\nFigures in Mrays/s. {}.\n", builds.join("; "));
    Ok(out)
}

/// Measurements per figure of `bench_rays` (the best is kept).
const RAY_ITERATIONS: usize = 7;

/// The closest-hit and shadow rays of `bench_rays`, whole (for the C reference) and in
/// chunks of [`CHUNK`] (for the Rust backends).
struct RaySets {
    closest: RayBatch,
    shadow: RayBatch,
    closest_chunks: Vec<RayBatch>,
    shadow_chunks: Vec<RayBatch>,
}

impl RaySets {
    fn new(closest: RayBatch, shadow: RayBatch) -> RaySets {
        let (closest_chunks, shadow_chunks) = (split(&closest, CHUNK), split(&shadow, CHUNK));
        RaySets {
            closest,
            shadow,
            closest_chunks,
            shadow_chunks,
        }
    }
}

/// Builds a backend, timing it and the RSS it adds: (backend, a note for the table).
/// Returns once the BVH's huge pages are in place, so that rays measured next are
/// steady-state rays.
fn timed_build<T>(name: &str, build: impl FnOnce() -> Result<T>) -> Result<(T, String)> {
    let (rss0, _) = memory_mib();
    let start = Instant::now();
    let built = build()?;
    let seconds = start.elapsed().as_secs_f64();
    let collapse = crate::accel::huge_pages::wait_for_collapse()
        .map(|c| format!(", huge pages {:.3} s after", c.seconds))
        .unwrap_or_default();
    let (rss1, hwm1) = memory_mib();
    let note = format!(
        "{name} build {seconds:.3} s{collapse}, +{:.0} MiB RSS (process peak {hwm1:.0} MiB)",
        rss1 - rss0
    );
    Ok((built, note))
}

/// One table row per Embree API: Rust on 1 and on the pool's threads and the C
/// reference, closest and occlusion; returns the best 1-thread (closest, occlusion).
fn embree_rows(
    embree: &EmbreeScene,
    set: &RaySets,
    pool: &rayon::ThreadPool,
    out: &mut String,
    progress: &dyn Fn(&str),
) -> (f64, f64) {
    let (mut best_closest, mut best_occl) = (0.0f64, 0.0f64);
    for api in RayApi::ALL {
        progress(&format!(
            "embree {}: closest and occlusion rays",
            api.name()
        ));
        // Rust 1 thread, C 1 thread and Rust on the pool take turns, best of each kept,
        // so a busy machine skews them alike.
        let mut m = [0.0f64; 6]; // closest: rust1, rustN, C; occlusion: rust1, rustN, C
        for _ in 0..RAY_ITERATIONS {
            for (k, (rays, chunks, occl)) in [
                (&set.closest, &set.closest_chunks, false),
                (&set.shadow, &set.shadow_chunks, true),
            ]
            .into_iter()
            .enumerate()
            {
                m[3 * k] = m[3 * k].max(rust_mrays(embree, api, chunks, occl, None, 1));
                m[3 * k + 2] = m[3 * k + 2].max(c_mrays(embree, rays, api, occl, 1));
                m[3 * k + 1] =
                    m[3 * k + 1].max(rust_mrays(embree, api, chunks, occl, Some(pool), 1));
            }
        }
        let [c1, cn, cc, o1, on, co] = m;
        best_closest = best_closest.max(c1);
        best_occl = best_occl.max(o1);
        let _ = writeln!(
            out,
            "| embree | {} | {c1:.2} | {cn:.2} | {o1:.2} | {on:.2} | {cc:.2} | {:.3} | {co:.2} | {:.3} |",
            api.name(),
            c1 / cc,
            o1 / co
        );
    }
    (best_closest, best_occl)
}

/// The obvhs row (one ray at a time, no C reference); returns its 1-thread (closest,
/// occlusion).
#[cfg(feature = "obvhs")]
fn obvhs_row(
    bvh: &crate::accel::bvh::ObvhsScene,
    set: &RaySets,
    pool: &rayon::ThreadPool,
    out: &mut String,
) -> (f64, f64) {
    let api = RayApi::Single;
    let it = RAY_ITERATIONS;
    let c1 = rust_mrays(bvh, api, &set.closest_chunks, false, None, it);
    let cn = rust_mrays(bvh, api, &set.closest_chunks, false, Some(pool), it);
    let o1 = rust_mrays(bvh, api, &set.shadow_chunks, true, None, it);
    let on = rust_mrays(bvh, api, &set.shadow_chunks, true, Some(pool), it);
    let _ = writeln!(
        out,
        "| obvhs | one ray at a time | {c1:.2} | {cn:.2} | {o1:.2} | {on:.2} | – | – | – | – |"
    );
    (c1, o1)
}

/// A scene for photon benchmarks over `geometry`: one grey Lambertian material
/// (ρ = 0.5) on every triangle and a point light at the centre of the bounds' top tenth.
pub fn lit_scene(name: &str, mut geometry: Geometry) -> crate::scene::Scene {
    use crate::light::Point;
    use crate::scene::{Light, Material, Scene};
    geometry.material = crate::scene::TriangleIds::constant(0, geometry.triangle_count());
    let (lo, hi) = geometry.world_bounds().unwrap_or((DVec3::ZERO, DVec3::ONE));
    let position = DVec3::new(
        (lo.x + hi.x) / 2.0,
        (lo.y + hi.y) / 2.0,
        hi.z - 0.1 * (hi.z - lo.z),
    );
    Scene {
        name: name.to_string(),
        materials: vec![Material::lambertian("grey", 0.5)],
        geometry,
        lights: vec![Light::new(
            "lights[0]",
            Point {
                position,
                intensity_cd: 1000.0,
            },
        )],
        ..Scene::default()
    }
}

/// Photon-tracing throughput against raw ray casting on the same scene and backend:
/// closest-hit rays per second of the photon pass (track estimator, so every ray is a
/// closest-hit ray) over the backend's rays per second on incoherent random rays through
/// the same API, both wall time on 1 and on `threads` threads, and both CPU time of one
/// thread. Returns a Markdown table.
/// `progress` is told each measurement as it starts.
pub fn bench_photons(
    scene: &crate::scene::Scene,
    photons: u64,
    threads: usize,
    backend: crate::accel::Backend,
    progress: &dyn Fn(&str),
) -> Result<String> {
    use crate::run::{run, RunOptions};
    use crate::scene::Estimator;
    use std::sync::atomic::AtomicBool;
    let caster = crate::accel::build(backend, &scene.geometry)?;
    // Steady-state rays: after the BVH's huge pages are in place.
    crate::accel::huge_pages::wait_for_collapse();
    let (lo, hi) = local_bounds(&scene.geometry);
    let chunks = split(&random_rays(lo, hi, 500_000, 7), CHUNK);
    let mut out = String::new();
    let _ = writeln!(
        out,
        "### {}: {} triangles, {} backend\n",
        scene.name,
        scene.geometry.triangle_count(),
        backend.name()
    );
    let _ = writeln!(
        out,
        "| threads | raw Mrays/s | photon pass Mrays/s | photons/s | ratio |"
    );
    let _ = writeln!(out, "|---:|---:|---:|---:|---:|");
    for t in [1, threads.max(1)] {
        let pool = crate::run::thread_pool(t)?;
        progress(&format!("raw rays, {t} threads"));
        let raw = rust_mrays(
            caster.as_ref(),
            caster.default_intersect_api(),
            &chunks,
            false,
            Some(&pool),
            3,
        );
        let options = RunOptions {
            threads: t,
            backend,
            estimator: Some(Estimator::Track),
            ..RunOptions::with_photons(scene, photons)
        };
        progress(&format!("{photons} photons, {t} threads"));
        let result = run(scene, &options, &AtomicBool::new(false), &mut ())?;
        let traced = result.tallies.rays as f64 / result.elapsed_s / 1e6;
        let _ = writeln!(
            out,
            "| {t} | {raw:.2} | {traced:.2} | {:.2} M | {:.2} |",
            result.tallies.photons as f64 / result.elapsed_s / 1e6,
            traced / raw
        );
    }
    // The same ratio in CPU time on one thread (the caller's): robust to other
    // processes on a shared machine, which stretch wall times unevenly.
    progress("raw rays and photons, CPU time of one thread");
    let raw_cpu = rust_mrays(
        caster.as_ref(),
        caster.default_intersect_api(),
        &chunks,
        false,
        None,
        3,
    );
    let (rays, cpu_s) = photon_pass_cpu(scene, caster.as_ref(), photons);
    let traced_cpu = rays as f64 / cpu_s / 1e6;
    let _ = writeln!(
        out,
        "| 1 (CPU time) | {raw_cpu:.2} | {traced_cpu:.2} | {:.2} M | {:.2} |",
        photons as f64 / cpu_s / 1e6,
        traced_cpu / raw_cpu
    );
    Ok(out)
}

/// Traces `photons` photons of `scene` (track estimator) chunk by chunk on the calling
/// thread, folding each chunk into the tallies as a run does: the rays cast and the
/// thread's CPU seconds.
fn photon_pass_cpu(
    scene: &crate::scene::Scene,
    caster: &dyn RayCaster,
    photons: u64,
) -> (u64, f64) {
    use crate::scene::Estimator;
    use crate::tally::ChunkTally;
    use crate::trace::{Scratch, Tracer, CHUNK_PHOTONS};
    let tracer = Tracer::new(scene, caster, 7, Some(Estimator::Track));
    let mut tallies = tracer.new_tallies();
    let (mut scratch, mut chunk) = (Scratch::default(), ChunkTally::default());
    let start = thread_cpu_seconds();
    let mut first = 0;
    while first < photons {
        let n = CHUNK_PHOTONS.min(photons - first);
        tracer.trace_chunk_into(first, n as u32, &mut scratch, &mut chunk);
        tallies.accumulate(&chunk, n);
        first += n;
    }
    (tallies.rays, thread_cpu_seconds() - start)
}

/// Time to accuracy on a receiver: runs `scene` until `target` relative error (eq. 9,
/// quadratic) on `receiver:NAME` or `time_limit_s`, and reports the error-versus-time
/// history with the forecasts made along the way, the times to 5, 2 and 1 %, the FOM,
/// the forecast made once 10 % of the photons were traced against what the run needed,
/// and the share of run time spent on statistics and forecasts. `progress` is told
/// when the run starts.
pub fn bench_accuracy(
    scene: &crate::scene::Scene,
    receiver: &str,
    estimator: Option<crate::scene::Estimator>,
    target: f64,
    time_limit_s: f64,
    threads: usize,
    progress: &dyn Fn(&str),
) -> Result<String> {
    use crate::run::{run, RunOptions};
    use std::sync::atomic::AtomicBool;
    let options = RunOptions {
        stop: crate::criteria::StopCriteria {
            time_limit_s: Some(time_limit_s),
            target_error: Some(target),
            target: Some(format!("receiver:{receiver}")),
            ..Default::default()
        },
        threads,
        estimator,
        ..RunOptions::from_scene(scene)
    };
    progress(&format!(
        "receiver:{receiver} to {:.1} % (at most {time_limit_s} s)",
        100.0 * target
    ));
    let result = run(scene, &options, &AtomicBool::new(false), &mut ())?;
    let state = result.state(scene, &options);
    let summary = crate::output::summary::build(&state);
    let r = summary
        .receivers
        .get(receiver)
        .ok_or_else(|| Error::input("--receiver", format!("no receiver named `{receiver}`")))?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "### {} / {receiver} ({} estimator, target {:.1} %)\n",
        scene.name,
        r.estimator,
        100.0 * target
    );
    let _ = writeln!(out, "{}\n", run_line(&result, &summary));
    let h = &result.history;
    let _ = writeln!(out, "Time to accuracy: {}.\n", times_to_accuracy(h));
    if let Some(line) = forecast_check(h) {
        let _ = writeln!(out, "{line}\n");
    }
    out += &history_table(h);
    Ok(out)
}

/// How the run of `bench_accuracy` went: stop, times, counts, the statistics' share of
/// the run, FOM and VOV.
fn run_line(result: &crate::run::RunResult, summary: &crate::output::summary::Summary) -> String {
    let share = |s: f64| 100.0 * s / result.elapsed_s.max(1e-9);
    format!(
        "Stopped on {} after {:.3} s (set-up {:.3} s), {} photons, {} rays; direct light {:.3} s ({} replicates, {} shadow rays); statistics and forecasts {:.4} s = {:.3} % of the run; merging {:.4} s = {:.3} %; FOM {:.0} (stable: {}), VOV {:.4}.",
        result.stop_reason.as_str(),
        result.elapsed_s,
        result.setup.setup_s,
        result.tallies.photons,
        result.tallies.rays,
        result.direct_s,
        result.tallies.direct_replicates,
        result.tallies.direct_rays,
        result.stats_s,
        share(result.stats_s),
        result.merge_s,
        share(result.merge_s),
        summary.reliability.fom,
        summary.reliability.fom_stable,
        summary.reliability.vov,
    )
}

/// When the error first reached 5, 2 and 1 %.
fn times_to_accuracy(h: &[HistoryPoint]) -> String {
    let reached: Vec<String> = [0.05, 0.02, 0.01]
        .into_iter()
        .map(|goal| match h.iter().find(|p| p.rel_error <= goal) {
            Some(p) => format!(
                "{:.0} %: {:.3} s ({} photons)",
                100.0 * goal,
                p.elapsed_s,
                p.photons
            ),
            None => format!("{:.0} %: not reached", 100.0 * goal),
        })
        .collect();
    reached.join(", ")
}

/// The forecast made once 10 % of the photons were traced against what the run needed
/// (`None` without history or without a forecast then).
fn forecast_check(h: &[HistoryPoint]) -> Option<String> {
    let last = h.last()?;
    let early = h
        .iter()
        .find(|p| p.photons.saturating_mul(10) >= last.photons)?;
    let (fs, fp) = (early.forecast_s?, early.forecast_photons?);
    Some(format!(
        "Forecast made at {:.1} % of the photons ({:.3} s): {:.3} s and {} photons; actual {:.3} s and {} photons: time {:+.2} %, photons {:+.2} %.",
        100.0 * early.photons as f64 / last.photons as f64,
        early.elapsed_s,
        fs,
        fp,
        last.elapsed_s,
        last.photons,
        100.0 * (fs / last.elapsed_s - 1.0),
        100.0 * (fp as f64 / last.photons as f64 - 1.0),
    ))
}

/// The error-versus-time history with the forecasts made along the way (Markdown).
fn history_table(h: &[HistoryPoint]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "| elapsed s | photons | error % | forecast s | forecast photons |"
    );
    let _ = writeln!(out, "|---:|---:|---:|---:|---:|");
    for p in h {
        let _ = writeln!(
            out,
            "| {:.3} | {} | {:.3} | {} | {} |",
            p.elapsed_s,
            p.photons,
            100.0 * p.rel_error,
            p.forecast_s.map_or("–".into(), |f| format!("{f:.3}")),
            p.forecast_photons.map_or("–".into(), |f| f.to_string()),
        );
    }
    out
}

/// One configuration of `luxtally bench-scale`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ScaleCase {
    /// This many instances of the mesh (`map = false`) on a grid, over a mapped floor.
    Instanced(u64),
    /// The procedural scene with at least this many (mapped) triangles.
    Flattened(u64),
    /// The same scene loaded from a GLB file (written before the clock starts), as a
    /// user's mesh would be.
    Glb(u64),
}

impl std::str::FromStr for ScaleCase {
    type Err = Error;
    fn from_str(s: &str) -> Result<Self> {
        let bad = || {
            let expected = "instanced:N, flattened:N or glb:N";
            Error::input("--case", format!("`{s}` is not {expected}"))
        };
        let (kind, n) = s.split_once(':').ok_or_else(bad)?;
        let n: u64 = n.parse().map_err(|_| bad())?;
        match kind {
            "instanced" => Ok(ScaleCase::Instanced(n)),
            "flattened" => Ok(ScaleCase::Flattened(n)),
            "glb" => Ok(ScaleCase::Glb(n)),
            _ => Err(bad()),
        }
    }
}

impl std::fmt::Display for ScaleCase {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            ScaleCase::Instanced(n) => write!(f, "instanced:{n}"),
            ScaleCase::Flattened(n) => write!(f, "flattened:{n}"),
            ScaleCase::Glb(n) => write!(f, "glb:{n}"),
        }
    }
}

/// What one bench-scale case measured (one process per case, so that the peak RSS is
/// the case's own).
#[derive(Clone, Debug, serde::Serialize, serde::Deserialize)]
pub struct ScaleResult {
    pub case: String,
    pub instances: u64,
    /// Triangles held (mapped triangles plus each prototype once).
    pub triangles_stored: u64,
    /// Triangles traced, as if flattened.
    pub triangles_traced: u64,
    /// The BVH built (`fast` or `compact`: `--bvh auto` takes the fast one when the
    /// memory available holds it).
    pub bvh: String,
    /// Scene load (or generation) plus acceleration-structure build, wall seconds.
    pub setup_s: f64,
    /// Of `setup_s`: the scene load or generation (with `Geometry`), and the BVH build.
    pub load_s: f64,
    pub bvh_s: f64,
    /// CPU seconds (all threads, user + system) of the set-up: what it would take on
    /// idle cores, whatever else the machine runs.
    pub setup_cpu_s: f64,
    /// Of `setup_cpu_s`: the scene load or generation (with `Geometry`).
    #[serde(default)]
    pub load_cpu_s: f64,
    /// After the set-up, in the background: collapsing the BVH's memory into huge pages
    /// (`accel::huge_pages`), wall seconds (0 where the build faulted them in at once).
    /// The rays and photons below are measured once it is done.
    #[serde(default)]
    pub huge_pages_s: f64,
    /// `VmHWM` at the end, MiB.
    pub peak_rss_mib: f64,
    /// Peak RSS less the RSS before the scene was made, per triangle stored: geometry,
    /// BVH (with its build's peak), triangle maps and the run's other per-triangle
    /// buffers.
    pub bytes_per_triangle: f64,
    /// Incoherent random closest-hit rays through the scene's bounds, wall time.
    pub mrays_per_s: f64,
    /// Photon pass (track estimator), wall time.
    pub photons_per_s: f64,
    /// Writing every output of the run (summary.json, scene_map.ply, indirect_map.bin,
    /// report.html), wall seconds, and their size in bytes.
    #[serde(default)]
    pub output_s: f64,
    #[serde(default)]
    pub output_bytes: u64,
    /// `VmHWM` after the outputs, MiB (`peak_rss_mib` is before them).
    #[serde(default)]
    pub peak_rss_with_outputs_mib: f64,
}

/// The instanced scene: `n` copies of `mesh` (y up, rotated to z up) on a square-ish
/// grid 0.25 m apart, a mapped grey floor under them and a point light above.
pub fn instanced_scene(mesh: &Path, n: u64) -> Result<crate::scene::Scene> {
    let nx = (n as f64).sqrt().ceil().max(1.0) as u64;
    let ny = n.div_ceil(nx).max(1);
    let (w, d) = (nx as f64 * 0.25, ny as f64 * 0.25);
    let text = format!(
        r#"name = "instanced {n}"
[materials]
grey = {{ reflectance = 0.5 }}

[[objects]]
shape = "rect"
corner = [-0.5, -0.5, -0.01]
u = [{w1}, 0, 0]
v = [0, {d1}, 0]
material = "grey"

[[objects]]
file = "{mesh}"
material = "grey"
rotate_deg = [90, 0, 0]
grid = {{ count = [{nx}, {ny}], spacing = [0.25, 0.25] }}

[[lights]]
type = "point"
position = [{cx}, {cy}, {h}]
intensity_cd = 1000
"#,
        w1 = w + 1.0,
        d1 = d + 1.0,
        mesh = mesh.display(),
        cx = w / 2.0,
        cy = d / 2.0,
        h = 0.2 * w.max(d) + 0.5,
    );
    crate::scene::load_str(&text, Path::new("."), "bench-scale.toml")
}

/// The procedural scene written as a binary glTF file in the temporary directory
/// (removed on drop).
struct ProceduralGlb {
    path: std::path::PathBuf,
}

impl ProceduralGlb {
    fn write(min_triangles: usize) -> Result<ProceduralGlb> {
        let (vertices, triangles) = procedural_mesh(min_triangles);
        // The guard first: a failed write leaves no file behind either.
        let file = ProceduralGlb {
            path: std::env::temp_dir()
                .join(format!("luxtally-bench-scale-{}.glb", std::process::id())),
        };
        write_glb(&file.path, &vertices, &triangles)?;
        Ok(file)
    }

    /// The file through the scene loader, lit as [`lit_scene`] lights the generated scene.
    fn scene(&self) -> Result<crate::scene::Scene> {
        Ok(lit_scene(
            "glb",
            load_obj_geometry(&self.path, DVec3::ZERO)?,
        ))
    }
}

impl Drop for ProceduralGlb {
    fn drop(&mut self) {
        let _ = std::fs::remove_file(&self.path);
    }
}

/// Writes one mesh (f32 positions, u32 indices, one node) as a binary glTF file.
pub fn write_glb(path: &Path, vertices: &[DVec3], triangles: &[[u32; 3]]) -> Result<()> {
    use std::io::Write;
    let mut bin: Vec<u8> = Vec::with_capacity(12 * (vertices.len() + triangles.len()));
    let (mut lo, mut hi) = (Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY));
    for v in vertices {
        let v = v.as_vec3();
        // The accessor's bounds must be numbers in the JSON, whatever the vertices.
        if v.is_finite() {
            (lo, hi) = (lo.min(v), hi.max(v));
        }
        for c in v.to_array() {
            bin.extend_from_slice(&c.to_le_bytes());
        }
    }
    if lo.cmpgt(hi).any() {
        // No finite vertex: bounds that are numbers all the same.
        (lo, hi) = (Vec3::ZERO, Vec3::ZERO);
    }
    let positions_len = bin.len();
    for i in triangles.iter().flatten() {
        bin.extend_from_slice(&i.to_le_bytes());
    }
    let json = format!(
        r#"{{"asset":{{"version":"2.0"}},"scene":0,"scenes":[{{"nodes":[0]}}],"nodes":[{{"mesh":0}}],"meshes":[{{"primitives":[{{"attributes":{{"POSITION":0}},"indices":1}}]}}],"buffers":[{{"byteLength":{total}}}],"bufferViews":[{{"buffer":0,"byteOffset":0,"byteLength":{positions_len}}},{{"buffer":0,"byteOffset":{positions_len},"byteLength":{indices_len}}}],"accessors":[{{"bufferView":0,"componentType":5126,"count":{vertex_count},"type":"VEC3","min":[{},{},{}],"max":[{},{},{}]}},{{"bufferView":1,"componentType":5125,"count":{index_count},"type":"SCALAR"}}]}}"#,
        lo.x,
        lo.y,
        lo.z,
        hi.x,
        hi.y,
        hi.z,
        total = bin.len(),
        indices_len = bin.len() - positions_len,
        vertex_count = vertices.len(),
        index_count = 3 * triangles.len(),
    );
    // Chunks are 4-byte aligned: JSON padded with spaces (the binary chunk already is).
    let mut json = json.into_bytes();
    json.resize(json.len().next_multiple_of(4), b' ');
    let length = u32::try_from(12 + 8 + json.len() + 8 + bin.len())
        .map_err(|_| Error::Unsupported(format!("{}: over 4 GiB", path.display())))?;
    let fail = |e| Error::io(path, e);
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).map_err(fail)?);
    out.write_all(b"glTF").map_err(fail)?;
    out.write_all(&2u32.to_le_bytes()).map_err(fail)?;
    out.write_all(&length.to_le_bytes()).map_err(fail)?;
    out.write_all(&(json.len() as u32).to_le_bytes())
        .map_err(fail)?;
    out.write_all(b"JSON").map_err(fail)?;
    out.write_all(&json).map_err(fail)?;
    out.write_all(&(bin.len() as u32).to_le_bytes())
        .map_err(fail)?;
    out.write_all(b"BIN\0").map_err(fail)?;
    out.write_all(&bin).map_err(fail)?;
    out.flush().map_err(fail)
}

/// Runs one case in this process with the `bvh` layout: set-up, raw rays, photons, peak
/// RSS.
pub fn bench_scale_case(
    case: ScaleCase,
    mesh: &Path,
    photons: u64,
    threads: usize,
    bvh: crate::accel::Bvh,
) -> Result<ScaleResult> {
    use crate::run::{run_from, RunOptions, Start};
    use crate::scene::Estimator;
    use std::sync::atomic::AtomicBool;
    // A GLB case's file is written before the clock starts: its loading is timed.
    let glb = match case {
        ScaleCase::Glb(n) => Some(ProceduralGlb::write(n as usize)?),
        _ => None,
    };
    let (rss_before_mib, _) = memory_mib();
    let cpu_before_s = process_cpu_seconds();
    let start = Instant::now();
    let scene = match (&glb, case) {
        (Some(file), _) => file.scene()?,
        (None, ScaleCase::Instanced(n)) => instanced_scene(mesh, n)?,
        (None, ScaleCase::Flattened(n) | ScaleCase::Glb(n)) => {
            lit_scene("flattened", procedural_geometry(n as usize))
        }
    };
    let load_s = start.elapsed().as_secs_f64();
    let load_cpu_s = process_cpu_seconds() - cpu_before_s;
    let backend = crate::accel::Backend::Embree;
    let options = RunOptions {
        threads,
        backend,
        bvh,
        estimator: Some(Estimator::Track),
        ..RunOptions::with_photons(&scene, photons)
    };
    // The BVH a run would choose against the memory available (or its refusal).
    let budget = crate::limits::Budget::new(None)?;
    let bvh = crate::limits::check_run(&scene, &options, None, true, &budget)?;
    let caster = crate::accel::build_with(backend, bvh, &scene.geometry)?;
    let setup_s = start.elapsed().as_secs_f64();
    let setup_cpu_s = process_cpu_seconds() - cpu_before_s;
    let huge_pages_s = crate::accel::huge_pages::wait_for_collapse().map_or(0.0, |c| c.seconds);
    let g = &scene.geometry;
    let mrays_per_s = scale_mrays(g, caster.as_ref(), threads)?;
    // The photon pass reuses the BVH (a second one would count in the peak RSS).
    let result = run_from(
        &scene,
        &options,
        caster.as_ref(),
        Instant::now(),
        &AtomicBool::new(false),
        &mut (),
        Start::default(),
    )?;
    let triangles_stored = g.triangle_count() as u64 + g.instanced.stored_triangle_count() as u64;
    let peak_rss_mib = memory_mib().1;
    let (output_s, output_bytes) = scale_outputs(&scene, &options, &result)?;
    Ok(ScaleResult {
        case: case.to_string(),
        instances: g.instanced.instances.len() as u64,
        triangles_stored,
        triangles_traced: g.triangle_count() as u64 + g.instanced.flattened_triangle_count(),
        bvh: bvh.name().into(),
        setup_s,
        load_s,
        bvh_s: setup_s - load_s,
        setup_cpu_s,
        load_cpu_s,
        huge_pages_s,
        peak_rss_mib,
        bytes_per_triangle: (peak_rss_mib - rss_before_mib) * 1048576.0
            / triangles_stored.max(1) as f64,
        mrays_per_s,
        photons_per_s: result.tallies.photons as f64 / result.elapsed_s,
        output_s,
        output_bytes,
        peak_rss_with_outputs_mib: memory_mib().1,
    })
}

/// Writes every output of a finished bench-scale run into a temporary folder, as `run`
/// does: (wall seconds, bytes written); the folder is removed.
fn scale_outputs(
    scene: &crate::scene::Scene,
    options: &crate::run::RunOptions,
    result: &crate::run::RunResult,
) -> Result<(f64, u64)> {
    let dir = std::env::temp_dir().join(format!("luxtally-bench-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let start = Instant::now();
    crate::render::write_outputs(&dir, scene, options, result, crate::output::Outputs::ALL)?;
    let seconds = start.elapsed().as_secs_f64();
    let bytes = std::fs::read_dir(&dir)
        .map_err(|e| Error::io(&dir, e))?
        .filter_map(|entry| entry.ok()?.metadata().ok())
        .filter(|m| m.is_file())
        .map(|m| m.len())
        .sum();
    std::fs::remove_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    Ok((seconds, bytes))
}

/// Mrays/s of 200,000 incoherent closest-hit rays through the bounds of everything in
/// `g` (instances included), on `threads` threads, best of 2.
fn scale_mrays(g: &Geometry, caster: &dyn RayCaster, threads: usize) -> Result<f64> {
    let pool = crate::run::thread_pool(threads)?;
    let (lo, hi) = local_bounds(g);
    let (ilo, ihi) = g.instanced.bounds;
    let (lo, hi) = if g.instanced.is_empty() {
        (lo, hi)
    } else {
        (lo.min(ilo), hi.max(ihi))
    };
    let chunks = split(&random_rays(lo, hi, 200_000, 7), CHUNK);
    Ok(rust_mrays(
        caster,
        caster.default_intersect_api(),
        &chunks,
        false,
        Some(&pool),
        2,
    ))
}

/// The bench-scale table (Markdown) from per-case results.
pub fn scale_table(results: &[ScaleResult], threads: usize) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "| case | instances | triangles stored | triangles traced | BVH | set-up s (load + BVH) | set-up CPU s | huge pages s | peak RSS MiB | B/triangle | Mrays/s | photons/s | outputs s | outputs MB | peak with outputs MiB |"
    );
    let _ = writeln!(
        out,
        "|---|---:|---:|---:|---|---:|---:|---:|---:|---:|---:|---:|---:|---:|---:|"
    );
    for r in results {
        let _ = writeln!(
            out,
            "| {} | {} | {} | {:.3e} | {} | {:.2} ({:.2} + {:.2}) | {:.2} | {:.2} | {:.0} | {:.0} | {:.2} | {:.2} M | {:.2} | {:.1} | {:.0} |",
            r.case,
            r.instances,
            r.triangles_stored,
            r.triangles_traced as f64,
            r.bvh,
            r.setup_s,
            r.load_s,
            r.bvh_s,
            r.setup_cpu_s,
            r.huge_pages_s,
            r.peak_rss_mib,
            r.bytes_per_triangle,
            r.mrays_per_s,
            r.photons_per_s / 1e6,
            r.output_s,
            r.output_bytes as f64 / 1e6,
            r.peak_rss_with_outputs_mib
        );
    }
    let _ = writeln!(
        out,
        "\nEmbree, {threads} threads; one process per case (peak RSS = its VmHWM; B/triangle = its \
         growth from before the scene was made, per triangle stored); rays: 200,000 \
         incoherent random closest-hit rays through the bounds; photons: track estimator; \
         outputs: summary.json, scene_map.ply, indirect_map.bin and report.html, as `run` \
         writes them (peak RSS before them, and with them); huge pages: the BVH's memory \
         collapsed into huge pages after the set-up, in the background (rays and photons \
         measured once it is done)."
    );
    out
}

/// The bench-scale plot (SVG): peak memory, set-up time and throughput against the
/// triangles traced, instanced and flattened cases as separate lines.
pub fn scale_plot(results: &[ScaleResult]) -> String {
    use crate::chart::{log_log_svg, Panel, Series};
    let kinds = [
        ("instanced", "instances of the bunny"),
        ("flattened", "flattened"),
    ];
    let series = |name: &str, value: &dyn Fn(&ScaleResult) -> f64| -> Vec<Series> {
        kinds
            .iter()
            .map(|(kind, label)| Series {
                name: format!("{name}{label}"),
                points: results
                    .iter()
                    .filter(|r| r.case.starts_with(kind))
                    .map(|r| (r.triangles_traced as f64, value(r)))
                    .collect(),
            })
            .collect()
    };
    let x_label = "triangles traced (as if flattened)";
    log_log_svg(&[
        Panel {
            title: "Peak memory".into(),
            x_label: x_label.into(),
            y_label: "peak RSS, MiB".into(),
            series: series("", &|r| r.peak_rss_mib),
        },
        Panel {
            title: "Set-up (load + BVH)".into(),
            x_label: x_label.into(),
            y_label: "seconds".into(),
            series: series("", &|r| r.setup_s),
        },
        Panel {
            title: "Throughput".into(),
            x_label: x_label.into(),
            y_label: "per second".into(),
            series: series("photons, ", &|r| r.photons_per_s)
                .into_iter()
                .chain(series("rays, ", &|r| r.mrays_per_s * 1e6))
                .collect(),
        },
    ])
}
