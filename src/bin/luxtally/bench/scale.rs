//! `luxtally bench-scale`: set-up time, peak memory, Mrays/s and photons/s of instanced
//! against flattened scenes, one child process per case (its own peak RSS).

use super::timing::{memory_mib, process_cpu_seconds, rust_mrays, split, CHUNK};
use glam::DVec3;
use luxtally::accel::{Bvh, RayCaster};
use luxtally::fixtures::{
    lit_scene, load_obj_geometry, local_bounds, procedural_geometry, procedural_mesh, random_rays,
    write_glb,
};
use luxtally::output::{self, write_atomic, Finished, Outputs};
use luxtally::run::{run_from, RunOptions, RunResult, Start};
use luxtally::scene::{Estimator, Geometry, Scene};
use luxtally::{Error, Result};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::atomic::AtomicBool;
use std::time::Instant;

#[derive(clap::Args)]
pub struct BenchScaleArgs {
    /// The instanced mesh.
    #[arg(long, default_value = "scenes/meshes/stanford-bunny.obj")]
    pub mesh: PathBuf,
    #[arg(long, default_value_t = 200_000)]
    pub photons: u64,
    #[arg(long)]
    pub threads: Option<usize>,
    /// Largest instance count (a power of ten).
    #[arg(long, default_value_t = 1_000_000)]
    pub max_instances: u64,
    /// Largest flattened triangle count (a power of ten).
    #[arg(long, default_value_t = 100_000_000)]
    pub max_triangles: u64,
    /// Run one case in this process (instanced:N, flattened:N, or glb:N: the flattened
    /// scene loaded from a GLB file written first) and print its JSON.
    #[arg(long)]
    pub case: Option<String>,
    /// BVH layout: auto (fast when the memory available holds it), fast or compact.
    #[arg(long, default_value = "auto", hide_possible_values = true)]
    pub bvh: Bvh,
    /// Also write the plot of the results (SVG) to this file.
    #[arg(long, value_name = "FILE")]
    pub plot: Option<PathBuf>,
}

/// Each case in a child process of this binary, then the table; with `--case`, that
/// case here, as one JSON line.
pub fn command(args: BenchScaleArgs) -> Result<()> {
    let threads = args.threads.unwrap_or_else(super::all_cores);
    if let Some(case) = &args.case {
        let r = bench_scale_case(case.parse()?, &args.mesh, args.photons, threads, args.bvh)?;
        let line = serde_json::to_string(&r)
            .map_err(|e| Error::Unsupported(format!("bench-scale: {e}")))?;
        println!("{line}");
        return Ok(());
    }
    let powers = |lo: u64, hi: u64| {
        std::iter::successors(Some(lo), |n| n.checked_mul(10)).take_while(move |n| *n <= hi)
    };
    let cases: Vec<ScaleCase> = powers(100, args.max_instances)
        .map(ScaleCase::Instanced)
        .chain(powers(10_000, args.max_triangles).map(ScaleCase::Flattened))
        .collect();
    let results = cases
        .into_iter()
        .filter_map(|case| case_in_child(&args, case, threads).transpose())
        .collect::<Result<Vec<_>>>()?;
    print!("{}", scale_table(&results, threads));
    if let Some(path) = &args.plot {
        let plot = scale_plot(&results);
        write_atomic(path, |w| std::io::Write::write_all(w, plot.as_bytes()))?;
        println!("plot: {}", path.display());
    }
    Ok(())
}

/// One case measured by a child process of this binary (`--case`); `None`, said on
/// stderr, when it failed.
fn case_in_child(
    args: &BenchScaleArgs,
    case: ScaleCase,
    threads: usize,
) -> Result<Option<ScaleResult>> {
    let exe = std::env::current_exe().map_err(|e| Error::io("current_exe", e))?;
    eprintln!("bench-scale: {case} …");
    let out = std::process::Command::new(&exe)
        .args(["bench-scale", "--case", &case.to_string(), "--photons"])
        .arg(args.photons.to_string())
        .args(["--threads", &threads.to_string(), "--bvh", args.bvh.name()])
        .arg("--mesh")
        .arg(&args.mesh)
        .output()
        .map_err(|e| Error::io(&exe, e))?;
    let text = String::from_utf8_lossy(&out.stdout);
    match serde_json::from_str::<ScaleResult>(text.trim()) {
        Ok(r) if out.status.success() => Ok(Some(r)),
        _ => {
            eprintln!(
                "bench-scale: {case} failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            );
            Ok(None)
        }
    }
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
fn instanced_scene(mesh: &Path, n: u64) -> Result<Scene> {
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
    luxtally::scene::load_str(&text, Path::new("."), "bench-scale.toml")
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
    fn scene(&self) -> Result<Scene> {
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

/// Runs one case in this process with the `bvh` layout: set-up, raw rays, photons, peak
/// RSS.
fn bench_scale_case(
    case: ScaleCase,
    mesh: &Path,
    photons: u64,
    threads: usize,
    bvh: Bvh,
) -> Result<ScaleResult> {
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
    let backend = luxtally::accel::Backend::Embree;
    let options = RunOptions {
        threads,
        backend,
        bvh,
        estimator: Some(Estimator::Track),
        ..RunOptions::with_photons(&scene, photons)
    };
    // The BVH a run would choose against the memory available (or its refusal).
    let budget = luxtally::limits::Budget::new(None)?;
    let bvh = luxtally::limits::check_run(&scene, &options, None, true, &budget)?;
    let caster = luxtally::accel::build_with(backend, bvh, &scene.geometry)?;
    let setup_s = start.elapsed().as_secs_f64();
    let setup_cpu_s = process_cpu_seconds() - cpu_before_s;
    let huge_pages_s = luxtally::accel::huge_pages::wait_for_collapse().map_or(0.0, |c| c.seconds);
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
        photons_per_s: result.progress.tallies.photons as f64 / result.progress.times.elapsed_s,
        output_s,
        output_bytes,
        peak_rss_with_outputs_mib: memory_mib().1,
    })
}

/// Writes every output of a finished bench-scale run into a temporary folder, as `run`
/// does: (wall seconds, bytes written); the folder is removed.
fn scale_outputs(scene: &Scene, options: &RunOptions, result: &RunResult) -> Result<(f64, u64)> {
    let dir = std::env::temp_dir().join(format!("luxtally-bench-scale-{}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| Error::io(&dir, e))?;
    let start = Instant::now();
    let state = result.state(scene, options);
    let finished = Finished {
        run: Some(&state),
        image: None,
    };
    output::write_all(&dir, finished, Outputs::ALL)?;
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
    let pool = luxtally::run::thread_pool(threads)?;
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
fn scale_table(results: &[ScaleResult], threads: usize) -> String {
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
fn scale_plot(results: &[ScaleResult]) -> String {
    use super::chart::{log_log_svg, Panel, Series};
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
