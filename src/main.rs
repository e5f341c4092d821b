//! The `luxtally` command line: parses, calls the library, prints one line on error.

mod progress;

use clap::{Parser, Subcommand};
use luxtally::accel::{self, Backend, Bvh, RayCaster};
use luxtally::checkpoint::{Checkpoint, Checkpointer};
use luxtally::criteria::StopCriteria;
use luxtally::distributed::Distributor;
use luxtally::input::one_line;
use luxtally::limits;
use luxtally::output::{save_summary, summary, write_atomic};
use luxtally::render::{self, IndirectMap, MAP_FILE};
use luxtally::run::{run_from, Observer, RunOptions, RunResult, RunState};
use luxtally::scene::{Estimator, Scene};
use luxtally::{Error, Result};
use progress::Progress;
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

#[derive(Parser)]
#[command(
    name = "luxtally",
    version,
    about = "Forward photon tracing that reports, forecasts and controls its own error"
)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand)]
enum Command {
    /// Trace photons through a scene and write summary.json (and more) to --out.
    Run(RunArgs),
    /// Photon pass (as `run`), then the eye pass from the scene's [camera]: render.exr,
    /// render.png and render_false_colour.png in --out.
    Render(RenderArgs),
    /// Combine the checkpoints of `run --shard I/N` runs into the outputs of the whole
    /// run, bit-identical to one run with the same seed and photons.
    Merge {
        /// The shards' output directories (each with checkpoint.bin).
        #[arg(required = true)]
        dirs: Vec<PathBuf>,
        #[arg(long)]
        out: PathBuf,
        /// The scene file (default: the one the shards recorded).
        #[arg(long)]
        scene: Option<PathBuf>,
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Print a scene's statistics: triangles, materials, lights, receivers, bounds.
    Info { scene: PathBuf },
    /// Rebuild report.html and the receivers' PNG previews from OUT_DIR/summary.json.
    Report { out_dir: PathBuf },
    /// Read a photometric file (IES LM-63 or EULUMDAT), print its flux, light output
    /// ratio, peak and opening, and write its polar diagram (cd/klm) as PNG.
    Photometry {
        file: PathBuf,
        /// The diagram's path (default: FILE's stem + `_polar.png` in the current directory).
        #[arg(long, value_name = "PNG")]
        out: Option<PathBuf>,
    },
    /// Ray throughput of every backend and ray API on a scene (incoherent random rays),
    /// with Embree's own C loop over the same rays for comparison.
    BenchRays {
        scene: PathBuf,
        /// Rays per measurement.
        #[arg(long, default_value_t = 250_000)]
        rays: usize,
        /// Threads for the multi-threaded columns (default: all cores).
        #[arg(long)]
        threads: Option<usize>,
    },
    /// Photon-tracing throughput against raw ray casting on the same scene and backend.
    /// SCENE `procedural` is a generated scene of 1,000,000 triangles.
    BenchPhotons {
        scene: PathBuf,
        #[arg(long, default_value_t = 2_000_000)]
        photons: u64,
        #[arg(long)]
        threads: Option<usize>,
        #[arg(long, default_value = "embree")]
        backend: String,
    },
    /// Scale: set-up time, peak memory, Mrays/s and photons/s for 10²…10⁶ instances of a
    /// mesh against 10⁴…10⁷ flattened triangles (one child process per case).
    BenchScale {
        /// The instanced mesh.
        #[arg(long, default_value = "scenes/meshes/stanford-bunny.obj")]
        mesh: PathBuf,
        #[arg(long, default_value_t = 200_000)]
        photons: u64,
        #[arg(long)]
        threads: Option<usize>,
        /// Largest instance count (a power of ten).
        #[arg(long, default_value_t = 1_000_000)]
        max_instances: u64,
        /// Largest flattened triangle count (a power of ten).
        #[arg(long, default_value_t = 100_000_000)]
        max_triangles: u64,
        /// Run one case in this process (instanced:N, flattened:N, or glb:N: the flattened
        /// scene loaded from a GLB file written first) and print its JSON.
        #[arg(long)]
        case: Option<String>,
        /// BVH layout: auto (fast when the memory available holds it), fast or compact.
        #[arg(long, default_value = "auto")]
        bvh: String,
        /// Also write the plot of the results (SVG) to this file.
        #[arg(long, value_name = "FILE")]
        plot: Option<PathBuf>,
    },
    /// Time to accuracy on a receiver: error against time, measured and forecast, time
    /// to 5, 2 and 1 %, FOM, forecast accuracy and the cost of the statistics.
    BenchAccuracy {
        scene: PathBuf,
        /// The receiver (default: the scene's first).
        #[arg(long)]
        receiver: Option<String>,
        #[arg(long, default_value_t = 0.01)]
        target_error: f64,
        #[arg(long, default_value_t = 300.0)]
        time_limit: f64,
        /// track, next_event or auto (default: the receiver's own).
        #[arg(long)]
        estimator: Option<String>,
        #[arg(long)]
        threads: Option<usize>,
    },
}

#[derive(clap::Args)]
struct RunArgs {
    /// The scene file (TOML).
    scene: PathBuf,
    /// Output directory (default: out/<scene name>/).
    #[arg(long)]
    out: Option<PathBuf>,
    // When to stop: overrides the scene's `[simulation]` key by key.
    #[command(flatten)]
    stop: StopCriteria,
    /// Random seed (default: the scene's [simulation] seed, else 1): the same seed and
    /// photons give the same numbers whatever --threads.
    #[arg(long)]
    seed: Option<u64>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long)]
    threads: Option<usize>,
    /// Ray-casting backend: embree or obvhs.
    #[arg(long)]
    backend: Option<String>,
    /// BVH layout: fast, compact (Embree: about half the memory, rays ≈ 35 % slower) or
    /// auto (fast when the run fits --max-memory or the memory available with it).
    #[arg(long, value_name = "LAYOUT")]
    bvh: Option<String>,
    /// Scores every receiver with this estimator: track, next_event or auto
    /// (default: each receiver's own `estimator`).
    #[arg(long)]
    estimator: Option<String>,
    /// No progress line.
    #[arg(long)]
    quiet: bool,
    /// Rewrite report.html every SECONDS during the run (the page reloads itself).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    report_every: Option<f64>,
    /// Refuse to start when the run is estimated to need more memory than SIZE (512M,
    /// 8G, 8GiB or bytes; default: the memory available now).
    #[arg(long, value_name = "SIZE")]
    max_memory: Option<String>,
    /// Save the run's whole state to OUT/checkpoint.bin this often, and when it ends.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, default_value_t = luxtally::checkpoint::DEFAULT_PERIOD_S)]
    checkpoint_every: f64,
    /// Go on from OUT_DIR/checkpoint.bin (same scene, seed, estimator and backend;
    /// --photons may grow). Outputs go to OUT_DIR unless --out says otherwise.
    #[arg(long, value_name = "OUT_DIR")]
    resume: Option<PathBuf>,
    /// Trace only shard I of N of the photon range (needs --photons); combine the shards
    /// with `luxtally merge`.
    #[arg(long, value_name = "I/N")]
    shard: Option<String>,
    /// Files to write besides summary.json, comma-separated: receivers, map
    /// (scene_map.ply), report, indirect (the map render --from reuses), render; or all,
    /// none (default: all).
    #[arg(long, value_name = "LIST")]
    outputs: Option<String>,
}

#[derive(clap::Args)]
struct RenderArgs {
    #[command(flatten)]
    run: RunArgs,
    /// Reuse the indirect map of a finished run in this directory (no photon pass; the
    /// stop flags are then ignored). Images go to --out, else to this directory.
    #[arg(long, value_name = "OUT_DIR")]
    from: Option<PathBuf>,
    /// Show the raw per-triangle indirect map (overrides the camera's `interpolate`).
    #[arg(long)]
    no_interpolation: bool,
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        // --help and --version are not errors.
        Err(e) if !e.use_stderr() => {
            let _ = e.print();
            return ExitCode::SUCCESS;
        }
        Err(e) => {
            // clap's message is several lines (tip, usage): keep one.
            let text = e.to_string();
            let first = text.lines().next().unwrap_or("bad arguments");
            let tip = text
                .lines()
                .find_map(|l| l.trim().strip_prefix("tip: "))
                .map(|t| format!(" ({t})"))
                .unwrap_or_default();
            eprintln!(
                "luxtally: {}{tip}; see luxtally --help",
                first.trim_start_matches("error: ")
            );
            return ExitCode::from(2);
        }
    };
    let result = match cli.command {
        Command::Run(args) => run_command(args),
        Command::Render(args) => render_command(args),
        Command::Merge {
            dirs,
            out,
            scene,
            threads,
        } => merge_command(&dirs, &out, scene.as_deref(), threads),
        Command::Info { scene } => info_command(&scene),
        Command::Report { out_dir } => luxtally::output::rebuild_report(&out_dir),
        Command::Photometry { file, out } => photometry_command(&file, out),
        Command::BenchRays {
            scene,
            rays,
            threads,
        } => bench_rays_command(&scene, rays, threads),
        Command::BenchPhotons {
            scene,
            photons,
            threads,
            backend,
        } => bench_photons_command(&scene, photons, threads, &backend),
        Command::BenchScale {
            mesh,
            photons,
            threads,
            max_instances,
            max_triangles,
            case,
            bvh,
            plot,
        } => bench_scale_command(
            &mesh,
            photons,
            threads.unwrap_or_else(all_cores),
            (max_instances, max_triangles),
            case.as_deref(),
            (&bvh, plot.as_deref()),
        ),
        Command::BenchAccuracy {
            scene,
            receiver,
            target_error,
            time_limit,
            estimator,
            threads,
        } => bench_accuracy_command(
            &scene,
            receiver,
            (target_error, time_limit),
            estimator.as_deref(),
            threads,
        ),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            eprintln!("luxtally: {}", one_line(&e.to_string()));
            ExitCode::FAILURE
        }
    }
}

/// Errors are printed on one line, whatever their source wrote.
/// The run's options: the scene's `[simulation]`, overridden by the command line.
fn run_options(args: &RunArgs, scene: &Scene) -> Result<RunOptions> {
    let mut options = RunOptions::from_scene(scene);
    options.stop = options.stop.overridden_by(&args.stop);
    if let Some(seed) = args.seed {
        options.seed = seed;
    }
    if let Some(threads) = args.threads {
        if threads == 0 {
            return Err(Error::input("--threads", "must be at least 1"));
        }
        options.threads = threads;
    }
    if let Some(b) = &args.backend {
        options.backend = b.parse::<Backend>()?;
    }
    if let Some(b) = &args.bvh {
        options.bvh = b.parse::<Bvh>()?;
    }
    if let Some(e) = &args.estimator {
        options.estimator = Some(parse_estimator(e)?);
    }
    if let Some(s) = args.report_every {
        if !(s > 0.0 && s.is_finite()) {
            return Err(Error::input(
                "--report-every",
                format!("{s} is not a positive number of seconds"),
            ));
        }
    }
    Ok(options)
}

/// `--out`, or `out/<scene name>/`, created (after the checks that can refuse a run).
fn out_dir(out: Option<&Path>, scene: &Scene) -> Result<OutDir> {
    let path = out.map_or_else(|| Path::new("out").join(&scene.name), Path::to_path_buf);
    let created = !path.exists();
    std::fs::create_dir_all(&path).map_err(|e| Error::io(&path, e))?;
    Ok(OutDir { path, created })
}

/// An output folder, and whether this command created it.
struct OutDir {
    path: PathBuf,
    created: bool,
}

impl OutDir {
    /// `result`, after removing the folder if the command created it, failed and left
    /// it empty (a failed run leaves no empty output folder behind).
    fn keep_on<T>(&self, result: Result<T>) -> Result<T> {
        if result.is_err() && self.created {
            // Fails, as it should, when the folder is not empty.
            let _ = std::fs::remove_dir(&self.path);
        }
        result
    }
}

/// The memory budget of `run` and `render` (`--max-memory`, else the memory available),
/// checked against the scene file's built-in shapes before the loader tessellates them.
fn budget_for(args: &RunArgs) -> Result<limits::Budget> {
    let budget = limits::Budget::new(args.max_memory.as_deref())?;
    let backend = match &args.backend {
        Some(b) => b.parse::<Backend>()?,
        None => Backend::default(),
    };
    let layout = match &args.bvh {
        Some(b) => b.parse::<Bvh>()?,
        None => Bvh::default(),
    };
    limits::check_scene_file(&args.scene, backend, layout, &budget)?;
    Ok(budget)
}

/// Says so when `--bvh auto` (`asked`) chose the compact BVH: the run fits, but traces
/// slower.
fn note_bvh(args: &RunArgs, asked: Bvh, chosen: Bvh) {
    if asked == Bvh::Auto && chosen == Bvh::Compact && !args.quiet {
        eprintln!(
            "luxtally: the fast BVH would not fit the memory budget: building the compact \
             one (about half the memory, rays ≈ 35 % slower; --bvh to choose)"
        );
    }
}

/// The photon pass shared by `run` and `render`: runs with all stop criteria, saving
/// checkpoints into `out`; `finish_run` writes its outputs.
fn photon_pass(
    args: &RunArgs,
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    out: &Path,
    distributor: Option<Box<dyn Distributor>>,
) -> Result<RunResult> {
    let interrupt = Arc::new(AtomicBool::new(false));
    {
        let flag = interrupt.clone();
        // A second Ctrl-C ends the process at once.
        let _ = ctrlc::set_handler(move || {
            if flag.swap(true, Ordering::SeqCst) {
                std::process::exit(130);
            }
        });
    }
    let (mut start, checkpoint) = luxtally::checkpoint::resume::start(
        scene,
        options,
        args.resume.as_deref(),
        args.shard.as_deref(),
    )?;
    if let (Some(path), Some(dir)) = (checkpoint, &args.resume) {
        if dir != out && !args.quiet {
            eprintln!(
                "resuming from {}; outputs in {}",
                path.display(),
                out.display()
            );
        }
    }
    start.distributor = distributor;
    let shard = start.shard;
    if args.checkpoint_every.is_nan() || args.checkpoint_every <= 0.0 {
        return Err(Error::input(
            "--checkpoint-every",
            format!(
                "{} is not a positive number of seconds",
                args.checkpoint_every
            ),
        ));
    }
    let mut observer = CliObserver {
        progress: Progress::new(args.quiet, PER_MILLE, progress::RUN_TEMPLATE),
        out: out.to_path_buf(),
        last_save: Instant::now(),
        save_error: None,
        report_every_s: args.report_every,
        last_report: None,
        checkpoints: Some(Checkpointer::new(out, args.checkpoint_every, scene)),
    };
    let result = run_from(
        scene,
        options,
        caster,
        setup,
        &interrupt,
        &mut observer,
        start,
    )?;
    if let Some(c) = &observer.checkpoints {
        if let Some(cost) = c.last_cost {
            observer.progress.println(format!(
                "checkpoint: {:.1} MB written in {:.3} s; the run waited {:.3} s \
                 for it, {:.3} s for all {} saves",
                cost.bytes as f64 / 1e6,
                cost.written_s,
                cost.waited_s,
                c.total_s,
                c.saves
            ));
        }
    }
    let interrupted = result.stop_reason == luxtally::stats::stop::StopReason::Interrupted;
    observer
        .progress
        .finish(!interrupted, progress_line(&result.state(scene, options)));
    if let Some(e) = observer.save_error {
        return Err(e);
    }
    if let Some(s) = shard {
        // A shard's tallies alone mean nothing: its checkpoint is its output.
        if !args.quiet {
            eprintln!(
                "shard {}/{}: photons {}..{} traced; checkpoint in {}",
                s.index,
                s.count,
                s.first_photon,
                s.end_photon,
                out.display()
            );
        }
    }
    Ok(result)
}

/// summary.json and the files `outputs` asks for, then the run's printed lines; nothing
/// for a shard, whose checkpoint is its output.
fn finish_run(
    args: &RunArgs,
    out: &Path,
    scene: &Scene,
    options: &RunOptions,
    result: &RunResult,
    outputs: luxtally::output::Outputs,
) -> Result<()> {
    if result.shard.is_none() {
        let s = render::write_outputs(out, scene, options, result, outputs)?;
        print_run(args, &s, out);
    }
    Ok(())
}

/// `--outputs`, all files when absent.
fn outputs_of(args: &RunArgs) -> Result<luxtally::output::Outputs> {
    args.outputs.as_deref().map_or(
        Ok(luxtally::output::Outputs::ALL),
        luxtally::output::Outputs::parse,
    )
}

/// `merge`: the shards' checkpoints folded into the outputs of the whole run.
fn merge_command(
    dirs: &[PathBuf],
    out: &Path,
    scene: Option<&Path>,
    threads: Option<usize>,
) -> Result<()> {
    limit_global_threads(threads)?;
    let mut shards = Vec::new();
    for dir in dirs {
        let (c, path) = Checkpoint::load(dir)?;
        shards.push((path, c));
    }
    let scene_path = match scene {
        Some(p) => p.to_path_buf(),
        None => PathBuf::from(&shards[0].1.scene_path),
    };
    let scene = luxtally::scene::load(&scene_path)?;
    let numbers = &shards[0].1.numbers;
    let mut options = RunOptions::from_scene(&scene);
    options.seed = numbers.seed;
    options.stop.photons = shards[0].1.photons_goal;
    options.backend = numbers.backend.parse()?;
    // The checkpoint keeps the estimator's Debug spelling (`NextEvent`).
    options.estimator = match numbers.estimator.as_deref() {
        None => None,
        Some(name) => Some(
            Estimator::ALL
                .into_iter()
                .find(|e| format!("{e:?}") == name)
                .ok_or_else(|| {
                    Error::input(
                        shards[0].0.display().to_string(),
                        format!("unknown estimator `{name}`"),
                    )
                })?,
        ),
    };
    if let Some(t) = threads {
        options.threads = t.max(1);
    }
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    let result = luxtally::checkpoint::merge(&scene, &options, caster.as_ref(), setup, shards)?;
    let _ = render::write_outputs(
        out,
        &scene,
        &options,
        &result,
        luxtally::output::Outputs::ALL,
    )?;
    println!(
        "merged {} shards: {} photons; results in {}",
        dirs.len(),
        result.tallies.photons,
        out.display()
    );
    Ok(())
}

/// `--threads` for all the process's parallel work (loading, outputs), not only the
/// photon pass's own pool: set before anything runs in parallel (a count above
/// `run::MAX_THREADS` is refused here, before any thread starts).
fn limit_global_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads.filter(|&t| t > 0) {
        luxtally::run::check_threads(t)?;
        luxtally::run::limit_global_threads(t);
    }
    Ok(())
}

fn run_command(args: RunArgs) -> Result<()> {
    limit_global_threads(args.threads)?;
    let budget = budget_for(&args)?;
    let scene = luxtally::scene::load(&args.scene)?;
    let mut options = run_options(&args, &scene)?;
    let outputs = outputs_of(&args)?;
    let asked = options.bvh;
    options.bvh = limits::check_run(&scene, &options, None, true, &budget)?;
    note_bvh(&args, asked, options.bvh);
    let dir = out_dir(args.out.as_deref().or(args.resume.as_deref()), &scene)?;
    dir.keep_on(run_into(&args, outputs, &scene, &options, &dir.path))
}

/// `run` once its output folder exists.
fn run_into(
    args: &RunArgs,
    outputs: luxtally::output::Outputs,
    scene: &Scene,
    options: &RunOptions,
    out: &Path,
) -> Result<()> {
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    #[cfg(feature = "mpi")]
    let cluster = cluster::Cluster::join();
    #[allow(unused_mut)]
    let mut distributor: Option<Box<dyn Distributor>> = None;
    #[cfg(feature = "mpi")]
    if let Some(c) = &cluster {
        if c.rank() != 0 {
            return c.serve(scene, options, caster.as_ref());
        }
        distributor = Some(Box::new(c.root(!args.quiet)));
    }
    let result = photon_pass(
        args,
        scene,
        options,
        caster.as_ref(),
        setup,
        out,
        distributor,
    )?;
    finish_run(args, out, scene, options, &result, outputs)
}

/// `render`: the photon pass (or a saved map with --from), then the eye pass.
fn render_command(args: RenderArgs) -> Result<()> {
    limit_global_threads(args.run.threads)?;
    let budget = budget_for(&args.run)?;
    let mut scene = luxtally::scene::load(&args.run.scene)?;
    let mut options = run_options(&args.run, &scene)?;
    // Checked before the photon pass, which may be long.
    let outputs = outputs_of(&args.run)?;
    let mut camera = render::camera_of(&scene)?.clone();
    if args.no_interpolation {
        camera.interpolate = false;
    }
    scene.camera = Some(camera.clone());
    if args.run.shard.is_some() {
        return Err(Error::input(
            "--shard",
            "render needs the whole run: merge the shards, then render --from",
        ));
    }
    let asked = options.bvh;
    options.bvh = limits::check_run(
        &scene,
        &options,
        Some(&camera),
        args.from.is_none(),
        &budget,
    )?;
    note_bvh(&args.run, asked, options.bvh);
    let dir = out_dir(
        args.run
            .out
            .as_deref()
            .or(args.from.as_deref())
            .or(args.run.resume.as_deref()),
        &scene,
    )?;
    dir.keep_on(render_into(
        &args, outputs, &scene, &options, &camera, &dir.path,
    ))
}

/// `render` once its output folder exists: the photon pass (or the saved map), then
/// the image.
fn render_into(
    args: &RenderArgs,
    outputs: luxtally::output::Outputs,
    scene: &Scene,
    options: &RunOptions,
    camera: &luxtally::scene::Camera,
    out: &Path,
) -> Result<()> {
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    let map = match &args.from {
        Some(dir) => IndirectMap::load(&dir.join(MAP_FILE), scene)?,
        None => {
            let result = photon_pass(&args.run, scene, options, caster.as_ref(), setup, out, None)?;
            finish_run(&args.run, out, scene, options, &result, outputs)?;
            IndirectMap::from_tallies(scene, &result.tallies, result.setup.total_flux_lm)
        }
    };
    let pixels = camera.resolution.map(u64::from).iter().product::<u64>();
    let progress = Progress::new(args.run.quiet, pixels, progress::RENDER_TEMPLATE);
    let start = Instant::now();
    let line = |done: u64| {
        format!(
            "render: {:.0} % of {pixels} pixels in {:.1} s",
            100.0 * done as f64 / pixels as f64,
            start.elapsed().as_secs_f64()
        )
    };
    let r = render::render_with(
        scene,
        camera,
        &map,
        caster.as_ref(),
        options.seed,
        options.threads,
        &|n| progress.inc(n as u64, line),
    )?;
    progress.finish(true, line(pixels));
    if outputs.render {
        render::output::write_all(&r.image, out)?;
    }
    if !args.run.quiet {
        println!(
            "render: {}×{} px, {} samples/px, {} eye rays + {} shadow rays in {:.2} s \
             ({:.2} M eye rays/s, {:.2} s per megapixel, {} threads); images in {}",
            r.image.width,
            r.image.height,
            camera.samples,
            r.rays.eye,
            r.rays.shadow,
            r.elapsed_s,
            r.eye_rays_per_s() / 1e6,
            r.s_per_megapixel(),
            options.threads,
            out.display()
        );
    }
    Ok(())
}

fn print_run(args: &RunArgs, s: &summary::Summary, out: &Path) {
    if !args.quiet {
        println!(
            "{}: {} photons, {} rays in {:.2} s ({:.1} Mrays/s), stopped on {}; results in {}",
            s.scene,
            s.photons_emitted,
            s.rays_traced,
            s.elapsed_s,
            s.rays_traced as f64 / s.elapsed_s.max(1e-9) / 1e6,
            s.stop_reason.as_deref().unwrap_or("?"),
            out.display()
        );
        for (name, r) in &s.receivers {
            let error = if r.unknown_cells == 0 {
                format!(
                    "error {:.2} % (arithmetic) {:.2} % (quadratic)",
                    100.0 * r.rel_error.arithmetic,
                    100.0 * r.rel_error.quadratic
                )
            } else if r.unknown_cells == r.dark_cells {
                format!(
                    "error {:.2} % (arithmetic) {:.2} % (quadratic) over the {} lit cells",
                    100.0 * r.rel_error_known_cells.arithmetic,
                    100.0 * r.rel_error_known_cells.quadratic,
                    r.values.len() - r.dark_cells
                )
            } else {
                format!(
                    "error unknown: {} of {} cells without a score ({:.2} % over the others)",
                    r.unknown_cells,
                    r.values.len(),
                    100.0 * r.rel_error_known_cells.quadratic
                )
            };
            let mut flags = String::new();
            if r.unreliable_cells > 0 {
                flags += &format!("; {} unreliable cells", r.unreliable_cells);
            }
            if r.dark_cells > 0 {
                flags += &format!(
                    "; {} dark cells (at most {:.4} {})",
                    r.dark_cells, r.dark_upper_bound, r.unit
                );
            }
            println!(
                "  receiver {name}: mean {:.4} {}, {error}{flags}",
                r.mean, r.unit
            );
        }
        if let Some(why) = &s.target_unreachable {
            println!("  target unreachable: {why}");
        }
        println!(
            "  global: {} triangles, mean {:.4} lx, error {:.2} %",
            s.global.triangles,
            s.global.mean_illuminance_lx,
            100.0 * s.global.rel_error.arithmetic
        );
        if s.reliability.bounce_cap_biased {
            println!("  not reliable: {}", bounce_cap_verdict(s));
        }
    }
}

/// Why the bounce cap makes a run's error unreliable, in words.
fn bounce_cap_verdict(s: &summary::Summary) -> String {
    let (k, cap) = (s.photons_killed_by_bounce_cap, s.bounce_cap);
    match s.bounce_cap_bias_bound {
        None => format!(
            "{k} photons stopped by the bounce cap of {cap} bounces in a scene with lossless \
             materials: the light they dropped is unknown"
        ),
        Some(b) => format!(
            "the light the bounce cap of {cap} bounces can have dropped, {b:.3e} of it \
             ({k} photons stopped), is not below 1 % of the error"
        ),
    }
}

/// Progress on stderr and a summary.json saved every few seconds, so a long run never
/// loses the work already done.
struct CliObserver {
    progress: Progress,
    out: PathBuf,
    last_save: Instant,
    save_error: Option<Error>,
    /// `--report-every`: report.html is rewritten this often during the run.
    report_every_s: Option<f64>,
    last_report: Option<Instant>,
    checkpoints: Option<Checkpointer>,
}

const SAVE_EVERY_S: f64 = 10.0;

/// A run's progress bar counts thousandths of the run.
const PER_MILLE: u64 = 1000;

/// Seconds until the run's first stop criterion is met, as far as they can be told: the
/// accuracy forecast, the photons left at the current rate, the time limit.
fn remaining_s(state: &RunState<'_>) -> Option<f64> {
    let rate = state.tallies.photons as f64 / state.elapsed_s.max(1e-9);
    let by_forecast = state.forecast.map(|f| f.total_s - state.elapsed_s);
    let by_photons = state
        .options
        .stop
        .photons
        .map(|n| n.saturating_sub(state.tallies.photons) as f64 / rate);
    let by_time = state.options.stop.time_limit_s.map(|t| t - state.elapsed_s);
    [by_forecast, by_photons, by_time]
        .into_iter()
        .flatten()
        .filter(|s| !s.is_nan())
        .reduce(f64::min)
        .map(|s| s.max(0.0))
}

/// The progress line: elapsed time, the target's error → its goal and when the run
/// should end first (what a narrow terminal cuts is the rest: photons, ray rate).
fn progress_line(state: &RunState<'_>) -> String {
    let error = state.history.last().map_or(f64::NAN, |p| p.rel_error);
    let unit = if state.options.stop.absolute {
        ""
    } else {
        " %"
    };
    let scale = if state.options.stop.absolute {
        1.0
    } else {
        100.0
    };
    let goal = state
        .options
        .stop
        .target_error
        .map(|g| format!(" → {:.3}{unit}", g * scale))
        .unwrap_or_default();
    let eta = match (state.stop_reason, remaining_s(state)) {
        (Some(reason), _) => format!(", stopped on {}", reason.as_str()),
        (None, Some(r)) => format!(", done in ~{r:.1} s"),
        (None, None) => String::new(),
    };
    let unreachable = luxtally::run::target_unreachable(
        state.scene,
        state.options,
        state.target,
        state.tallies,
        state.history,
        state.forecast,
    )
    .map(|why| format!(", target unreachable: {why}"))
    .unwrap_or_default();
    format!(
        "{:.1} s  {}: {:.3}{unit}{goal}{eta}{unreachable}  {} photons  {:.1} Mrays/s",
        state.elapsed_s,
        state.target.describe(&state.scene.receivers),
        error * scale,
        state.tallies.photons,
        state.tallies.rays as f64 / state.elapsed_s.max(1e-9) / 1e6,
    )
}

/// How far the run is, in thousandths, by its nearest stop criterion.
fn per_mille(state: &RunState<'_>) -> u64 {
    match remaining_s(state) {
        Some(r) => (PER_MILLE as f64 * state.elapsed_s / (state.elapsed_s + r).max(1e-9)) as u64,
        None => 0,
    }
}

impl Observer for CliObserver {
    fn epoch(&mut self, state: &RunState<'_>) {
        self.progress.set(per_mille(state), || progress_line(state));
        // A shard's tallies alone are no result: its checkpoint is its only output.
        let shard = state.resumable.shard.is_some();
        if !shard
            && state.stop_reason.is_none()
            && self.last_save.elapsed().as_secs_f64() >= SAVE_EVERY_S
        {
            self.last_save = Instant::now();
            if let Err(e) = save_summary(&self.out, &summary::build(state)) {
                self.save_error.get_or_insert(e);
            }
        }
        if let Some(c) = &mut self.checkpoints {
            if let Err(e) = c.epoch(state) {
                self.save_error.get_or_insert(e);
            }
        }
        if let Some(every) = self.report_every_s {
            let due = self
                .last_report
                .is_none_or(|t| t.elapsed().as_secs_f64() >= every);
            if !shard && state.stop_reason.is_none() && due {
                self.last_report = Some(Instant::now());
                let written = luxtally::output::summary_value(state)
                    .and_then(|s| luxtally::output::write_live_report(&self.out, &s, every));
                if let Err(e) = written {
                    self.save_error.get_or_insert(e);
                }
            }
        }
    }
}

fn info_command(path: &Path) -> Result<()> {
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
        println!(
            "  receiver {}: {}×{} cells of {:.4} m²",
            r.name,
            r.cells[0],
            r.cells[1],
            r.cell_area_m2()
        );
    }
    Ok(())
}

/// `photometry`: the file's facts on stdout, its polar diagram as PNG.
fn photometry_command(file: &Path, out: Option<PathBuf>) -> Result<()> {
    use luxtally::photometry;
    let p = photometry::load(file)?;
    let out = out.unwrap_or_else(|| {
        let stem = file
            .file_stem()
            .map_or("luminaire".into(), |s| s.to_string_lossy());
        PathBuf::from(format!("{stem}_polar.png"))
    });
    photometry::polar::write_polar_png(&p, &out)?;
    for line in p.summary_lines() {
        println!("{line}");
    }
    println!("polar diagram: {}", out.display());
    Ok(())
}

/// `bench-scale`: each case in a child process of this binary (its own peak RSS), then
/// the table; with `--case`, that case here, as one JSON line.
fn bench_scale_command(
    mesh: &Path,
    photons: u64,
    threads: usize,
    (max_instances, max_triangles): (u64, u64),
    case: Option<&str>,
    (bvh, plot): (&str, Option<&Path>),
) -> Result<()> {
    use luxtally::bench::{ScaleCase, ScaleResult};
    let layout = bvh.parse::<Bvh>()?;
    if let Some(case) = case {
        let r = luxtally::bench::bench_scale_case(case.parse()?, mesh, photons, threads, layout)?;
        let line = serde_json::to_string(&r)
            .map_err(|e| luxtally::Error::Unsupported(format!("bench-scale: {e}")))?;
        println!("{line}");
        return Ok(());
    }
    let powers = |lo: u64, hi: u64| {
        std::iter::successors(Some(lo), |n| n.checked_mul(10)).take_while(move |n| *n <= hi)
    };
    let cases: Vec<ScaleCase> = powers(100, max_instances)
        .map(ScaleCase::Instanced)
        .chain(powers(10_000, max_triangles).map(ScaleCase::Flattened))
        .collect();
    let exe = std::env::current_exe().map_err(|e| luxtally::Error::io("current_exe", e))?;
    let mut results = Vec::new();
    for case in cases {
        eprintln!("bench-scale: {case} …");
        let out = std::process::Command::new(&exe)
            .args(["bench-scale", "--case", &case.to_string(), "--photons"])
            .arg(photons.to_string())
            .args(["--threads", &threads.to_string(), "--bvh", bvh, "--mesh"])
            .arg(mesh)
            .output()
            .map_err(|e| luxtally::Error::io(&exe, e))?;
        let text = String::from_utf8_lossy(&out.stdout);
        match serde_json::from_str::<ScaleResult>(text.trim()) {
            Ok(r) if out.status.success() => results.push(r),
            _ => eprintln!(
                "bench-scale: {case} failed: {}",
                String::from_utf8_lossy(&out.stderr).trim()
            ),
        }
    }
    print!("{}", luxtally::bench::scale_table(&results, threads));
    if let Some(path) = plot {
        write_atomic(path, luxtally::bench::scale_plot(&results).as_bytes())?;
        println!("plot: {}", path.display());
    }
    Ok(())
}

/// `bench-photons`: photon throughput on a scene file, or on `procedural` geometry.
fn bench_photons_command(
    scene: &Path,
    photons: u64,
    threads: Option<usize>,
    backend: &str,
) -> Result<()> {
    let scene = if scene.as_os_str() == "procedural" {
        luxtally::bench::lit_scene(
            "procedural",
            luxtally::bench::procedural_geometry(1_000_000),
        )
    } else {
        luxtally::scene::load(scene)?
    };
    let spinner = Progress::spinner();
    let table = luxtally::bench::bench_photons(
        &scene,
        photons,
        threads.unwrap_or_else(all_cores),
        backend.parse()?,
        &|what| spinner.message(format!("bench-photons: {what}")),
    );
    spinner.clear();
    print!("{}", table?);
    Ok(())
}

/// `bench-accuracy`: time to `target_error` (or `time_limit` seconds) on a receiver,
/// the scene's first unless named.
fn bench_accuracy_command(
    scene: &Path,
    receiver: Option<String>,
    (target_error, time_limit): (f64, f64),
    estimator: Option<&str>,
    threads: Option<usize>,
) -> Result<()> {
    let scene = luxtally::scene::load(scene)?;
    let receiver = match receiver.or_else(|| scene.receivers.first().map(|r| r.name.clone())) {
        Some(r) => r,
        None => {
            return Err(Error::input(
                scene.path.display().to_string(),
                "the scene has no receiver",
            ))
        }
    };
    let estimator = estimator.map(parse_estimator).transpose()?;
    let spinner = Progress::spinner();
    let report = luxtally::bench::bench_accuracy(
        &scene,
        &receiver,
        estimator,
        target_error,
        time_limit,
        threads.unwrap_or_else(all_cores),
        &|what| spinner.message(format!("bench-accuracy: {what}")),
    );
    spinner.clear();
    print!("{}", report?);
    Ok(())
}

fn bench_rays_command(path: &Path, rays: usize, threads: Option<usize>) -> Result<()> {
    let scene = luxtally::scene::load(path)?;
    if rays == 0 {
        return Err(Error::input("--rays", "must be at least 1"));
    }
    let threads =
        threads.unwrap_or_else(|| std::thread::available_parallelism().map_or(1, |n| n.get()));
    let spinner = Progress::spinner();
    let table = luxtally::bench::bench_rays(
        &scene.geometry,
        &scene.name,
        rays,
        threads,
        cfg!(feature = "obvhs"),
        &|what| spinner.message(format!("bench-rays: {what}")),
    );
    spinner.clear();
    print!("{}", table?);
    Ok(())
}

fn parse_estimator(name: &str) -> Result<Estimator> {
    Estimator::from_name(name).ok_or_else(|| {
        Error::input(
            "--estimator",
            format!(
                "unknown estimator `{name}` (expected {})",
                Estimator::expected()
            ),
        )
    })
}

fn all_cores() -> usize {
    std::thread::available_parallelism().map_or(1, |n| n.get())
}

/// `mpirun -np N luxtally run ...` (feature `mpi`): rank 0 runs, the others trace the
/// chunks it hands out (docs/distributed.md).
#[cfg(feature = "mpi")]
mod cluster {
    use luxtally::accel::RayCaster;
    use luxtally::distributed::mpi::{serve, Root};
    use luxtally::run::RunOptions;
    use luxtally::scene::Scene;
    use luxtally::trace::Tracer;
    use luxtally::Result;
    use mpi::topology::Communicator;

    pub struct Cluster {
        universe: mpi::environment::Universe,
    }

    impl Cluster {
        /// MPI, when started by mpirun with more than one rank (MPI is never initialised
        /// otherwise: a plain run stays a plain process).
        pub fn join() -> Option<Cluster> {
            let launched = ["OMPI_COMM_WORLD_SIZE", "PMI_SIZE", "PMIX_RANK"]
                .iter()
                .any(|v| std::env::var_os(v).is_some());
            if !launched {
                return None;
            }
            let universe = mpi::initialize()?;
            (universe.world().size() > 1).then_some(Cluster { universe })
        }

        pub fn rank(&self) -> i32 {
            self.universe.world().rank()
        }

        pub fn root(&self, report: bool) -> Root {
            Root {
                world: self.universe.world(),
                bytes_received: 0,
                epochs: 0,
                report,
            }
        }

        /// A worker rank: traces what rank 0 hands out until it says stop.
        pub fn serve(
            &self,
            scene: &Scene,
            options: &RunOptions,
            caster: &dyn RayCaster,
        ) -> Result<()> {
            // Ctrl-C reaches every rank: rank 0 decides when to stop.
            let _ = ctrlc::set_handler(|| {});
            let threads = options.threads.max(1);
            let pool = luxtally::run::thread_pool(threads)?;
            let tracer = Tracer::new(scene, caster, options.seed, options.estimator);
            serve(&self.universe.world(), &tracer, &pool);
            Ok(())
        }
    }
}
