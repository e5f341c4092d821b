//! `luxtally annual`: a year of daylight from the scene's `[annual]` table.

use luxtally::accel::{self, Backend};
use luxtally::run::RunOptions;
use luxtally::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct AnnualArgs {
    /// The scene file (TOML) with an `[annual]` table.
    pub scene: PathBuf,
    /// Output directory (default: out/<scene name>_annual/).
    #[arg(long)]
    pub out: Option<PathBuf>,
    /// Photons of the first round over all sources (default: the table's `photons`).
    #[arg(long)]
    pub photons: Option<u64>,
    /// At most this many photons over all sources (default: the table's `max_photons`).
    #[arg(long)]
    pub max_photons: Option<u64>,
    /// Stop once every analysed receiver's sDA300/50 % interval is at most ± this
    /// (area fraction; default: the table's `sda_halfwidth`, else one round).
    #[arg(long, value_name = "FRACTION")]
    pub sda_halfwidth: Option<f64>,
    /// Random seed (default: the scene's [simulation] seed).
    #[arg(long)]
    pub seed: Option<u64>,
    /// Worker threads (default: all cores). Results do not depend on it.
    #[arg(long)]
    pub threads: Option<usize>,
    /// Ray-casting backend: embree or obvhs.
    #[arg(long, hide_possible_values = true)]
    pub backend: Option<Backend>,
    /// No progress lines.
    #[arg(long)]
    pub quiet: bool,
    /// Go on from the per-source checkpoints in OUT/annual_checkpoints (every source is
    /// saved there as soon as a round has traced it): the same seed and photons give the
    /// same bits as an uninterrupted run.
    #[arg(long)]
    pub resume: bool,
}

pub fn command(args: AnnualArgs) -> Result<()> {
    crate::run::limit_threads(args.threads)?;
    let mut scene = luxtally::scene::load(&args.scene)?;
    let Some(annual) = scene.annual.as_mut() else {
        return Err(Error::input(
            args.scene.display().to_string(),
            "has no [annual] table",
        ));
    };
    if let Some(p) = args.photons {
        annual.photons = p;
        annual.max_photons = annual.max_photons.max(p);
    }
    if let Some(p) = args.max_photons {
        if p < annual.photons {
            return Err(Error::input(
                "--max-photons",
                format!(
                    "must be at least the first round's {} photons",
                    annual.photons
                ),
            ));
        }
        annual.max_photons = p;
    }
    if let Some(h) = args.sda_halfwidth {
        if !(h > 0.0 && h < 1.0) {
            return Err(Error::input(
                "--sda-halfwidth",
                format!("must be within (0, 1), got {h}"),
            ));
        }
        annual.sda_halfwidth = Some(h);
    }
    let mut options = RunOptions::from_scene(&scene);
    if options.qmc {
        eprintln!(
            "luxtally: [simulation] qmc is not used by annual runs (their sources' photons \
             are not whole blocks)"
        );
        options.qmc = false;
    }
    options.seed = args.seed.unwrap_or(options.seed);
    options.threads = args.threads.unwrap_or(options.threads);
    options.backend = args.backend.unwrap_or(options.backend);
    let out = args
        .out
        .clone()
        .unwrap_or_else(|| PathBuf::from("out").join(format!("{}_annual", scene.name)));
    let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
    let interrupt = crate::photon_pass::interrupt_on_ctrl_c();
    let checkpoints = out.join("annual_checkpoints");
    if args.resume && !checkpoints.is_dir() {
        return Err(Error::input(
            "--resume",
            format!("{} holds no annual checkpoints", checkpoints.display()),
        ));
    }
    let storage = luxtally::annual::Storage {
        free_bytes: luxtally::limits::available_bytes().map(|b| b as f64),
        checkpoints: Some(&checkpoints),
        resume: args.resume,
    };
    let quiet = args.quiet;
    let result = luxtally::annual::run(
        &scene,
        &options,
        caster.as_ref(),
        &storage,
        &interrupt,
        &mut |round| {
            if !quiet {
                eprintln!("{}", luxtally::annual::round_line(round));
            }
        },
    )?;
    luxtally::output::annual::write_annual(&out, &scene, &result)?;
    print!("{}", luxtally::annual::result_text(&scene, &result, &out));
    Ok(())
}
