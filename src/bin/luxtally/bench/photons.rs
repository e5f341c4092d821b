//! `luxtally bench-photons`: photon-tracing throughput against raw ray casting on the
//! same scene and backend.

use super::timing::{rust_mrays, split, thread_cpu_seconds, CHUNK};
use crate::progress::Progress;
use luxtally::accel::{Backend, RayCaster};
use luxtally::fixtures::{lit_scene, local_bounds, procedural_geometry, random_rays};
use luxtally::run::{run, RunOptions};
use luxtally::scene::{Estimator, Scene};
use luxtally::Result;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

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
        lit_scene("procedural", procedural_geometry(1_000_000))
    } else {
        luxtally::scene::load(&args.scene)?
    };
    let spinner = Progress::spinner();
    let table = bench_photons(
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

/// Photon-tracing throughput against raw ray casting on the same scene and backend:
/// closest-hit rays per second of the photon pass (track estimator, so every ray is a
/// closest-hit ray) over the backend's rays per second on incoherent random rays through
/// the same API, both wall time on 1 and on `threads` threads, and both CPU time of one
/// thread. Returns a Markdown table.
/// `progress` is told each measurement as it starts.
fn bench_photons(
    scene: &Scene,
    photons: u64,
    threads: usize,
    backend: Backend,
    progress: &dyn Fn(&str),
) -> Result<String> {
    let caster = luxtally::accel::build(backend, &scene.geometry)?;
    // Steady-state rays: after the BVH's huge pages are in place.
    luxtally::accel::huge_pages::wait_for_collapse();
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
        let pool = luxtally::run::thread_pool(t)?;
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
        let traced = result.progress.tallies.rays as f64 / result.progress.times.elapsed_s / 1e6;
        let _ = writeln!(
            out,
            "| {t} | {raw:.2} | {traced:.2} | {:.2} M | {:.2} |",
            result.progress.tallies.photons as f64 / result.progress.times.elapsed_s / 1e6,
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
fn photon_pass_cpu(scene: &Scene, caster: &dyn RayCaster, photons: u64) -> (u64, f64) {
    use luxtally::tally::ChunkTally;
    use luxtally::trace::{Scratch, Tracer, CHUNK_PHOTONS};
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
