//! Timing ray casting: rays per second of a backend through one ray API, on one
//! thread (its CPU time) or on a pool (wall time), Embree's own C loop over the same rays
//! (`benches/c/embree_reference.c`, built with the feature `bench`), and `bench_rays`,
//! the table of every backend and API. Shared by the `bench-*` commands and
//! `cargo bench --bench rays` (which includes this file).

use luxtally::accel::embree::EmbreeScene;
use luxtally::accel::{HitBatch, RayApi, RayBatch, RayCaster};
use luxtally::fixtures::{local_bounds, random_rays, random_segments};
use luxtally::scene::Geometry;
use luxtally::Result;
use rayon::prelude::*;
use std::fmt::Write as _;
use std::time::Instant;

/// Rays per parallel work item in the benchmark.
pub const CHUNK: usize = 4096;

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

/// Embree's own C loop over the same rays (`benches/c/embree_reference.c`): what the
/// Rust wrapper's overhead is measured against.
#[cfg(feature = "bench")]
mod c_reference {
    use luxtally::accel::embree::EmbreeScene;
    use luxtally::accel::{HitBatch, RayApi, RayBatch};
    use std::ffi::c_void;

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
            scene: *mut c_void,
            rays: *const CRays,
            hits: *mut CHits,
            n: usize,
            api: i32,
            occlusion: i32,
            iterations: i32,
        ) -> f64;
    }

    /// Mrays/s of the C reference over `rays` on one thread (best of `iterations`).
    pub fn mrays(
        scene: &EmbreeScene,
        rays: &RayBatch,
        api: RayApi,
        occlusion: bool,
        iterations: i32,
    ) -> Option<f64> {
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
        Some(n as f64 / seconds / 1e6)
    }
}

/// Without the feature `bench`, the C reference is not built: its columns stay empty.
#[cfg(not(feature = "bench"))]
mod c_reference {
    use luxtally::accel::embree::EmbreeScene;
    use luxtally::accel::{RayApi, RayBatch};

    pub fn mrays(_: &EmbreeScene, _: &RayBatch, _: RayApi, _: bool, _: i32) -> Option<f64> {
        None
    }
}

/// The C reference is in this build (feature `bench`).
const C_REFERENCE: bool = cfg!(feature = "bench");

/// CPU seconds consumed by the calling thread (`CLOCK_THREAD_CPUTIME_ID`): one-thread
/// figures stay meaningful when other processes share the cores.
pub fn thread_cpu_seconds() -> f64 {
    let mut ts = libc::timespec {
        tv_sec: 0,
        tv_nsec: 0,
    };
    // SAFETY: `ts` is a valid, writable timespec; the call only writes it.
    unsafe { libc::clock_gettime(libc::CLOCK_THREAD_CPUTIME_ID, &mut ts) };
    ts.tv_sec as f64 + 1e-9 * ts.tv_nsec as f64
}

/// Best-of-`iterations` Mrays/s of `caster` through `api` over `chunks`, on the current
/// thread (`pool == None`) or on every thread of `pool`.
pub fn rust_mrays(
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
    let pool = luxtally::run::thread_pool(threads.max(1))?;

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
        let (bvh, note) = timed_build("obvhs", || {
            Ok(luxtally::accel::obvhs::ObvhsScene::new(geometry))
        })?;
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

    if !C_REFERENCE {
        builds.push("C reference: not in this build (feature `bench`)".into());
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
    let collapse = luxtally::accel::huge_pages::wait_for_collapse()
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
                if let Some(c) = c_reference::mrays(embree, rays, api, occl, 1) {
                    m[3 * k + 2] = m[3 * k + 2].max(c);
                }
                m[3 * k + 1] =
                    m[3 * k + 1].max(rust_mrays(embree, api, chunks, occl, Some(pool), 1));
            }
        }
        let [c1, cn, cc, o1, on, co] = m;
        best_closest = best_closest.max(c1);
        best_occl = best_occl.max(o1);
        let _ = writeln!(
            out,
            "| embree | {} | {c1:.2} | {cn:.2} | {o1:.2} | {on:.2} | {} | {} |",
            api.name(),
            c_columns(c1, cc),
            c_columns(o1, co)
        );
    }
    (best_closest, best_occl)
}

/// The C reference's figure and Rust's over it, as two table cells (empty without it).
fn c_columns(rust: f64, c: f64) -> String {
    if C_REFERENCE {
        format!("{c:.2} | {:.3}", rust / c)
    } else {
        "– | –".into()
    }
}

/// The obvhs row (one ray at a time, no C reference); returns its 1-thread (closest,
/// occlusion).
#[cfg(feature = "obvhs")]
fn obvhs_row(
    bvh: &luxtally::accel::obvhs::ObvhsScene,
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
