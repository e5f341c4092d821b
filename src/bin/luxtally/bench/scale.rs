//! `luxtally bench-scale`: set-up time, peak memory, Mrays/s and photons/s of instanced
//! against flattened scenes, one child process per case (its own peak RSS).

use luxtally::accel::Bvh;
use luxtally::bench::{ScaleCase, ScaleResult};
use luxtally::output::write_atomic;
use luxtally::{Error, Result};
use std::path::PathBuf;

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
        let r = luxtally::bench::bench_scale_case(
            case.parse()?,
            &args.mesh,
            args.photons,
            threads,
            args.bvh,
        )?;
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
    print!("{}", luxtally::bench::scale_table(&results, threads));
    if let Some(path) = &args.plot {
        write_atomic(path, luxtally::bench::scale_plot(&results).as_bytes())?;
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
