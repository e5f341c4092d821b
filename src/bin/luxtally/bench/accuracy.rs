//! `luxtally bench-accuracy`: time to accuracy on a receiver.

use crate::progress::Progress;
use luxtally::scene::Estimator;
use luxtally::{Error, Result};
use std::path::PathBuf;

#[derive(clap::Args)]
pub struct BenchAccuracyArgs {
    pub scene: PathBuf,
    /// The receiver (default: the scene's first).
    #[arg(long)]
    pub receiver: Option<String>,
    #[arg(long, default_value_t = 0.01)]
    pub target_error: f64,
    #[arg(long, default_value_t = 300.0)]
    pub time_limit: f64,
    /// track, next_event or auto (default: the receiver's own).
    #[arg(long, hide_possible_values = true)]
    pub estimator: Option<Estimator>,
    #[arg(long)]
    pub threads: Option<usize>,
}

/// Time to `--target-error` (or `--time-limit` seconds) on a receiver, the scene's
/// first unless named.
pub fn command(args: BenchAccuracyArgs) -> Result<()> {
    let scene = luxtally::scene::load(&args.scene)?;
    let first = scene.receivers.first().map(|r| r.name.clone());
    let Some(receiver) = args.receiver.or(first) else {
        return Err(Error::input(
            scene.path.display().to_string(),
            "the scene has no receiver",
        ));
    };
    let spinner = Progress::spinner();
    let report = luxtally::bench::bench_accuracy(
        &scene,
        &receiver,
        args.estimator,
        args.target_error,
        args.time_limit,
        args.threads.unwrap_or_else(super::all_cores),
        &|what| spinner.message(format!("bench-accuracy: {what}")),
    );
    spinner.clear();
    print!("{}", report?);
    Ok(())
}
