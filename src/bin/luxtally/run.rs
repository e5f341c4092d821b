//! `luxtally run`: its flags, the run's options from the scene and the flags, its output
//! folder; the photon pass itself is `photon_pass`, shared with `render`.

use crate::photon_pass::{finish_run, photon_pass};
use luxtally::accel::{self, Backend, Bvh};
use luxtally::criteria::StopCriteria;
use luxtally::distributed::Distributor;
use luxtally::limits;
use luxtally::output::Outputs;
use luxtally::run::RunOptions;
use luxtally::scene::{Estimator, Quantity, Scene};
use luxtally::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
pub struct RunArgs {
    /// The scene file (TOML).
    pub scene: PathBuf,
    /// Output directory (default: out/<scene name>/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    // When to stop: overrides the scene's `[simulation]` key by key.
    #[command(flatten)]
    pub stop: StopCriteria,
    /// Random seed (default: the scene's [simulation] seed, else 1): the same seed and
    /// photons give the same numbers whatever --threads.
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Ray-casting backend: embree or obvhs.
    #[arg(long, hide_possible_values = true)]
    pub backend: Option<Backend>,
    /// BVH layout: fast, compact (Embree: about half the memory, rays ≈ 35 % slower) or
    /// auto (fast when the run fits --max-memory or the memory available with it).
    #[arg(long, value_name = "LAYOUT", hide_possible_values = true)]
    pub bvh: Option<Bvh>,
    /// Scores every receiver with this estimator: track, next_event or auto
    /// (default: each receiver's own `estimator`).
    #[arg(long, hide_possible_values = true)]
    pub estimator: Option<Estimator>,
    /// Randomised quasi-Monte Carlo emission and connection points to the receivers
    /// (Owen-scrambled Sobol' per block of 2048 photons, each block one history of the
    /// statistics) and direct-light replicates; faster to about 1 % per cell and
    /// beyond on illuminance and cylindrical grids, slower to loose targets and on
    /// luminance meters alone; --photons is rounded up to whole chunks of 4096 (default:
    /// the scene's [simulation] qmc).
    #[arg(long)]
    pub qmc: bool,
    /// No progress line.
    #[arg(long)]
    pub quiet: bool,
    /// Rewrite report.html every SECONDS during the run (the page reloads itself).
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true)]
    pub report_every: Option<f64>,
    /// Refuse to start when the run is estimated to need more memory than SIZE (512M,
    /// 8G, 8GiB or bytes; default: the memory available now).
    #[arg(long, value_name = "SIZE")]
    pub max_memory: Option<String>,
    /// Save the run's whole state to OUT/checkpoint.bin this often, and when it ends.
    #[arg(long, value_name = "SECONDS", allow_negative_numbers = true, default_value_t = luxtally::checkpoint::DEFAULT_PERIOD_S)]
    pub checkpoint_every: f64,
    /// Go on from OUT_DIR/checkpoint.bin (same scene, seed, estimator and backend;
    /// --photons may grow). Outputs go to OUT_DIR unless --out says otherwise.
    #[arg(long, value_name = "OUT_DIR")]
    pub resume: Option<PathBuf>,
    /// Trace only shard I of N of the photon range (needs --photons); combine the shards
    /// with `luxtally merge`.
    #[arg(long, value_name = "I/N")]
    pub shard: Option<String>,
    /// Files to write besides summary.json, comma-separated: receivers, map
    /// (scene_map.ply), report, indirect (the map render --from reuses), render; or all,
    /// none (default: all).
    #[arg(long, value_name = "LIST")]
    pub outputs: Option<String>,
}

pub fn command(args: RunArgs) -> Result<()> {
    limit_threads(args.threads)?;
    let budget = budget_for(&args)?;
    let scene = luxtally::scene::load(&args.scene)?;
    let mut options = run_options(&args, &scene)?;
    let outputs = outputs_of(&args)?;
    let asked = options.bvh;
    options.bvh = limits::check_run(&scene, &options, None, true, &budget)?;
    note_bvh(&args, asked, options.bvh);
    let dir = OutDir::create(args.out.as_deref().or(args.resume.as_deref()), &scene)?;
    dir.keep_on(run_into(&args, outputs, &scene, &options, &dir.path))
}

/// `run` once its output folder exists.
fn run_into(
    args: &RunArgs,
    outputs: Outputs,
    scene: &Scene,
    options: &RunOptions,
    out: &Path,
) -> Result<()> {
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    #[cfg(feature = "mpi")]
    let cluster = crate::cluster::Cluster::join();
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

/// `--threads` for all the process's parallel work (loading, outputs), not only the
/// photon pass's own pool: checked (at least 1, at most `run::MAX_THREADS`) and set
/// before anything runs in parallel.
pub fn limit_threads(threads: Option<usize>) -> Result<()> {
    if let Some(t) = threads {
        if t == 0 {
            return Err(Error::input("--threads", "must be at least 1"));
        }
        luxtally::run::check_threads(t)?;
        luxtally::run::limit_global_threads(t);
    }
    Ok(())
}

/// The run's options: the scene's `[simulation]`, overridden by the command line.
pub fn run_options(args: &RunArgs, scene: &Scene) -> Result<RunOptions> {
    let mut options = RunOptions::from_scene(scene);
    options.stop = options.stop.overridden_by(&args.stop);
    if let Some(seed) = args.seed {
        options.seed = seed;
    }
    if let Some(threads) = args.threads {
        options.threads = threads;
    }
    options.backend = args.backend.unwrap_or(options.backend);
    options.bvh = args.bvh.unwrap_or(options.bvh);
    options.estimator = args.estimator.or(options.estimator);
    options.qmc |= args.qmc;
    let all_meters =
        (scene.receivers.iter()).all(|r| matches!(r.quantity, Quantity::Luminance { .. }));
    if options.qmc && !scene.receivers.is_empty() && all_meters {
        eprintln!(
            "luxtally: qmc: every receiver is a luminance meter, whose directions QMC does \
             not draw: expect no gain over an ordinary run (docs/method.md)"
        );
    }
    if options.qmc {
        // A QMC run traces whole chunks, so whole blocks: its last is never cut short.
        let chunk = luxtally::trace::CHUNK_PHOTONS;
        options.stop.photons = options
            .stop
            .photons
            .map(|p| p.div_ceil(chunk).saturating_mul(chunk));
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

/// The memory budget of `run` and `render` (`--max-memory`, else the memory available),
/// checked against the scene file's built-in shapes before the loader tessellates them.
pub fn budget_for(args: &RunArgs) -> Result<limits::Budget> {
    let budget = limits::Budget::new(args.max_memory.as_deref())?;
    let backend = args.backend.unwrap_or_default();
    let layout = args.bvh.unwrap_or_default();
    limits::check_scene_file(&args.scene, backend, layout, &budget)?;
    Ok(budget)
}

/// Says so when `--bvh auto` (`asked`) chose the compact BVH: the run fits, but traces
/// slower.
pub fn note_bvh(args: &RunArgs, asked: Bvh, chosen: Bvh) {
    if asked == Bvh::Auto && chosen == Bvh::Compact && !args.quiet {
        eprintln!(
            "luxtally: the fast BVH would not fit the memory budget: building the compact \
             one (about half the memory, rays ≈ 35 % slower; --bvh to choose)"
        );
    }
}

/// `--outputs`, all files when absent.
pub fn outputs_of(args: &RunArgs) -> Result<Outputs> {
    args.outputs
        .as_deref()
        .map_or(Ok(Outputs::ALL), Outputs::parse)
}

/// An output folder, and whether this command created it.
pub struct OutDir {
    pub path: PathBuf,
    created: bool,
}

impl OutDir {
    /// `out`, or `out/<scene name>/`, created (after the checks that can refuse a run).
    pub fn create(out: Option<&Path>, scene: &Scene) -> Result<OutDir> {
        let path = out.map_or_else(|| Path::new("out").join(&scene.name), Path::to_path_buf);
        let created = !path.exists();
        std::fs::create_dir_all(&path).map_err(|e| Error::io(&path, e))?;
        Ok(OutDir { path, created })
    }

    /// `result`, after removing the folder if the command created it, failed and left
    /// it empty (a failed run leaves no empty output folder behind).
    pub fn keep_on<T>(&self, result: Result<T>) -> Result<T> {
        if result.is_err() && self.created {
            // Fails, as it should, when the folder is not empty.
            let _ = std::fs::remove_dir(&self.path);
        }
        result
    }
}
