//! `luxtally render`: the photon pass (or the indirect map of a finished run), then the
//! eye pass from the scene's camera.

use crate::photon_pass::{finish_run, photon_pass};
use crate::progress::{self, Progress};
use crate::run::{budget_for, limit_threads, note_bvh, outputs_of, run_options, OutDir, RunArgs};
use luxtally::accel;
use luxtally::limits;
use luxtally::output::{self, Finished, IndirectMap, Outputs, MAP_FILE};
use luxtally::render;
use luxtally::run::RunOptions;
use luxtally::scene::{Camera, Scene};
use luxtally::{Error, Result};
use std::path::{Path, PathBuf};
use std::time::Instant;

#[derive(clap::Args)]
pub struct RenderArgs {
    #[command(flatten)]
    pub run: RunArgs,
    /// Reuse the indirect map of a finished run in this directory (no photon pass; the
    /// stop flags are then ignored). Images go to --out, else to this directory.
    #[arg(long, value_name = "OUT_DIR")]
    pub from: Option<PathBuf>,
    /// Show the raw per-triangle indirect map (overrides the camera's `interpolate`).
    #[arg(long)]
    pub no_interpolation: bool,
}

pub fn command(args: RenderArgs) -> Result<()> {
    limit_threads(args.run.threads)?;
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
    let out = args.run.out.as_deref().or(args.from.as_deref());
    let dir = OutDir::create(out.or(args.run.resume.as_deref()), &scene)?;
    dir.keep_on(render_into(
        &args, outputs, &scene, &options, &camera, &dir.path,
    ))
}

/// `render` once its output folder exists: the photon pass (or the saved map), then
/// the image.
fn render_into(
    args: &RenderArgs,
    outputs: Outputs,
    scene: &Scene,
    options: &RunOptions,
    camera: &Camera,
    out: &Path,
) -> Result<()> {
    let setup = Instant::now();
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    let map = match &args.from {
        Some(dir) => IndirectMap::load(&dir.join(MAP_FILE), scene)?,
        None => {
            let result = photon_pass(&args.run, scene, options, caster.as_ref(), setup, out, None)?;
            finish_run(&args.run, out, scene, options, &result, outputs)?;
            IndirectMap::from_tallies(scene, &result.progress.tallies, result.setup.total_flux_lm)
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
    let finished = Finished {
        run: None,
        image: Some(&r.image),
    };
    output::write_all(out, finished, outputs)?;
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
