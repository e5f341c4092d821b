//! The `luxtally` command line: parses, hands each command to its module, prints one
//! line on error. The commands call the library, which does the work.

mod annual;
mod bench;
#[cfg(feature = "mpi")]
mod cluster;
mod info;
mod merge;
mod observer;
mod photometry;
mod photon_pass;
mod progress;
mod render;
mod run;
mod ugr_table;

use clap::error::{ContextKind, ContextValue, ErrorKind};
use clap::{Parser, Subcommand};
use luxtally::input::{one_line, or_list};
use std::path::PathBuf;
use std::process::ExitCode;

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
    Run(run::RunArgs),
    /// Photon pass (as `run`), then the eye pass from the scene's [camera]: render.exr,
    /// render.png and render_false_colour.png in --out.
    Render(render::RenderArgs),
    /// Combine the checkpoints of `run --shard I/N` runs into the outputs of the whole
    /// run, bit-identical to one run with the same seed and photons.
    Merge(merge::MergeArgs),
    /// Print a scene's statistics: triangles, materials, lights, receivers, bounds.
    Info { scene: PathBuf },
    /// Rebuild report.html and the receivers' PNG previews from OUT_DIR/summary.json.
    Report { out_dir: PathBuf },
    /// Read a photometric file (IES LM-63 or EULUMDAT), print its flux, light output
    /// ratio, peak and opening, and write its polar diagram (cd/klm) as PNG.
    Photometry(photometry::PhotometryArgs),
    /// The CIE 190:2010 UGR table of a photometric file (IES LM-63 or EULUMDAT): 19
    /// rooms, crosswise and endwise, 5 reflectance sets, at 1000 lm; CSV and plot if asked.
    UgrTable(ugr_table::UgrTableArgs),
    /// Print each sky's and sun's model, zenith luminance, horizontal illuminance, sun
    /// position and ground luminance (the `type = "sky"` and `"sun"` lights of SCENE).
    /// With --patches MF, also each sky's Reinhart MF:n sky vector (MF 1 = Tregenza's
    /// 145 patches): its horizontal illuminance from the patches' centre and mean
    /// luminances against the exact integral, and with --vector FILE the patches as CSV.
    Sky {
        scene: PathBuf,
        #[arg(long, value_name = "MF")]
        patches: Option<u32>,
        #[arg(long, value_name = "FILE", requires = "patches")]
        vector: Option<PathBuf>,
    },
    /// A year of daylight from the scene's `[annual]` table: daylight coefficients per
    /// sky patch and sun bin, every hour's illuminance with its σ, and DA, cDA, UDI,
    /// sDA300/50 %, ASE1000,250 and EN 17037's levels with their intervals.
    Annual(annual::AnnualArgs),
    /// Read a weather file, EPW or WEA by its extension (.epw, .wea), and print its site,
    /// hours, missing hours and annual radiation sums.
    Weather { file: PathBuf },
    /// List the EN 12464-1 task types a requirement's `task` can name, with their values.
    Tasks,
    /// Ray throughput of every backend and ray API on a scene (incoherent random rays),
    /// with Embree's own C loop over the same rays for comparison.
    BenchRays(bench::rays::BenchRaysArgs),
    /// Photon-tracing throughput against raw ray casting on the same scene and backend.
    /// SCENE `procedural` is a generated scene of 1,000,000 triangles.
    BenchPhotons(bench::photons::BenchPhotonsArgs),
    /// Scale: set-up time, peak memory, Mrays/s and photons/s for 10²…10⁶ instances of a
    /// mesh against 10⁴…10⁷ flattened triangles (one child process per case).
    BenchScale(bench::scale::BenchScaleArgs),
    /// Time to accuracy on a receiver: error against time, measured and forecast, time
    /// to 5, 2 and 1 %, FOM, forecast accuracy and the cost of the statistics.
    BenchAccuracy(bench::accuracy::BenchAccuracyArgs),
}

fn main() -> ExitCode {
    let cli = match Cli::try_parse() {
        Ok(cli) => cli,
        Err(e) => return usage_error(e),
    };
    let result = match cli.command {
        Command::Run(args) => run::command(args),
        Command::Render(args) => render::command(args),
        Command::Merge(args) => merge::command(args),
        Command::Info { scene } => info::command(&scene),
        Command::Report { out_dir } => luxtally::output::rebuild_report(&out_dir),
        Command::Photometry(args) => photometry::command(args),
        Command::UgrTable(args) => ugr_table::command(args),
        Command::Sky {
            scene,
            patches,
            vector,
        } => sky_command(&scene, patches, vector.as_deref()),
        Command::Annual(args) => annual::command(args),
        Command::Weather { file } => {
            luxtally::weather::read_weather(&file).map(|w| print!("{}", w.summary()))
        }
        Command::Tasks => {
            print!("{}", luxtally::scene::tasks::table_text());
            Ok(())
        }
        Command::BenchRays(args) => bench::rays::command(args),
        Command::BenchPhotons(args) => bench::photons::command(args),
        Command::BenchScale(args) => bench::scale::command(args),
        Command::BenchAccuracy(args) => bench::accuracy::command(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(e) => {
            // Errors are printed on one line, whatever their source wrote.
            eprintln!("luxtally: {}", one_line(&e.to_string()));
            ExitCode::FAILURE
        }
    }
}

/// `luxtally sky SCENE [--patches MF [--vector FILE]]`: the scene's daylight sources,
/// described, and each sky's patches.
fn sky_command(
    path: &std::path::Path,
    patches: Option<u32>,
    vector: Option<&std::path::Path>,
) -> luxtally::Result<()> {
    use luxtally::light::{Sky, Sun};
    let scene = luxtally::scene::load(path)?;
    let patches = (patches
        .map(|mf| luxtally::light::patches::SkyPatches::reinhart(mf, "--patches")))
    .transpose()?;
    let mut csv = String::new();
    let mut any = false;
    for l in &scene.lights {
        let text = match (l.get::<Sky>(), l.get::<Sun>()) {
            (Some(sky), _) => sky.describe_full(),
            (None, Some(sun)) => luxtally::light::Light::describe(sun),
            _ => continue,
        };
        println!("{}: {text}", l.label);
        any = true;
        if let (Some(p), Some(sky)) = (&patches, l.get::<Sky>()) {
            let luminance = |w| sky.luminance(w);
            let summary = p.vector_summary(&luminance, sky.horizontal_lx);
            println!("{}: {summary}", l.label);
            csv += &p.vector_csv(&l.label, &luminance);
        }
    }
    if !any {
        println!("{}: no type = \"sky\" or \"sun\" lights", path.display());
    }
    if let Some(file) = vector {
        let header = "light,patch,altitude_low_deg,altitude_high_deg,azimuth_low_deg,\
                      azimuth_high_deg,solid_angle_sr,centre_cdm2,mean_cdm2\n";
        std::fs::write(file, format!("{header}{csv}")).map_err(|e| {
            luxtally::Error::input(file.display().to_string(), format!("cannot write: {e}"))
        })?;
    }
    Ok(())
}

/// What clap refused, on one line: exit 2 for bad usage; exit 1, as for any bad input,
/// for a value that is none of a flag's names (`--backend optix`). --help and
/// --version are not errors.
fn usage_error(e: clap::Error) -> ExitCode {
    if !e.use_stderr() {
        let _ = e.print();
        return ExitCode::SUCCESS;
    }
    if e.kind() == ErrorKind::InvalidValue {
        if let Some(line) = unknown_name(&e) {
            eprintln!("luxtally: {line}");
            return ExitCode::FAILURE;
        }
    }
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
    ExitCode::from(2)
}

/// `--backend: unknown value `optix` (expected embree or obvhs)`, for a value outside a
/// flag's names.
fn unknown_name(e: &clap::Error) -> Option<String> {
    let text = |kind| match e.get(kind) {
        Some(ContextValue::String(s)) => Some(s.clone()),
        _ => None,
    };
    // "--backend <BACKEND>": the flag alone.
    let flag = text(ContextKind::InvalidArg)?;
    let flag = flag.split_whitespace().next()?.to_string();
    let value = text(ContextKind::InvalidValue)?;
    let Some(ContextValue::Strings(names)) = e.get(ContextKind::ValidValue) else {
        return None;
    };
    Some(format!(
        "{flag}: unknown value `{value}` (expected {})",
        or_list(names)
    ))
}
