//! `luxtally bench-accuracy`: time to accuracy on a receiver.

use crate::progress::Progress;
use luxtally::criteria::StopCriteria;
use luxtally::output::summary::{self, Summary};
use luxtally::run::{run, RunOptions, RunResult};
use luxtally::scene::{Estimator, Scene};
use luxtally::stats::forecast::HistoryPoint;
use luxtally::{Error, Result};
use std::fmt::Write as _;
use std::path::PathBuf;
use std::sync::atomic::AtomicBool;

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
    /// Randomised QMC, as `run --qmc` (default: the scene's [simulation] qmc).
    #[arg(long)]
    pub qmc: bool,
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
    let report = bench_accuracy(
        &scene,
        &receiver,
        (args.estimator, args.qmc),
        args.target_error,
        args.time_limit,
        args.threads.unwrap_or_else(super::all_cores),
        &|what| spinner.message(format!("bench-accuracy: {what}")),
    );
    spinner.clear();
    print!("{}", report?);
    Ok(())
}

/// Time to accuracy on a receiver: runs `scene` until `target` relative error (eq. 9,
/// quadratic) on `receiver:NAME` or `time_limit_s`, and reports the error-versus-time
/// history with the forecasts made along the way, the times to 5, 2 and 1 %, the FOM,
/// the forecast made once 10 % of the photons were traced against what the run needed,
/// the share of run time spent on statistics and forecasts, and the rays to each of
/// 5, 2, 1 and 0.5 % down to `target` ([`rays_to_accuracy`]). `progress` is told
/// when each run starts.
fn bench_accuracy(
    scene: &Scene,
    receiver: &str,
    (estimator, qmc): (Option<Estimator>, bool),
    target: f64,
    time_limit_s: f64,
    threads: usize,
    progress: &dyn Fn(&str),
) -> Result<String> {
    let from_scene = RunOptions::from_scene(scene);
    let options = RunOptions {
        stop: StopCriteria {
            time_limit_s: Some(time_limit_s),
            target_error: Some(target),
            target: Some(format!("receiver:{receiver}")),
            ..Default::default()
        },
        threads,
        estimator,
        qmc: qmc || from_scene.qmc,
        ..from_scene
    };
    progress(&format!(
        "receiver:{receiver} to {:.1} % (at most {time_limit_s} s)",
        100.0 * target
    ));
    let result = run(scene, &options, &AtomicBool::new(false), &mut ())?;
    let state = result.state(scene, &options);
    let summary = summary::build(&state);
    let r = summary
        .receivers
        .get(receiver)
        .ok_or_else(|| Error::input("--receiver", format!("no receiver named `{receiver}`")))?;
    let mut out = String::new();
    let _ = writeln!(
        out,
        "### {} / {receiver} ({} estimator{}, target {:.1} %)\n",
        scene.name,
        r.estimator,
        if options.qmc { ", QMC" } else { "" },
        100.0 * target
    );
    let _ = writeln!(out, "{}\n", run_line(&result, &summary));
    let h = &result.progress.history;
    let _ = writeln!(out, "Time to accuracy: {}.\n", times_to_accuracy(h));
    if let Some(line) = forecast_check(h) {
        let _ = writeln!(out, "{line}\n");
    }
    out += &history_table(h);
    out += &rays_to_accuracy(scene, &options, target, progress)?;
    Ok(out)
}

/// The accuracies [`rays_to_accuracy`] measures, those down to the run's target.
const ACCURACY_GOALS: [f64; 4] = [0.05, 0.02, 0.01, 0.005];

/// Rays to each of [`ACCURACY_GOALS`] down to `target` (Markdown): one run of `options`
/// stopped at each, its photons, photon rays, direct-light rays and wall time. Separate
/// runs, because the direct light's replicates come in steps the history does not
/// record; the same seed, so each is the same run cut at its goal.
fn rays_to_accuracy(
    scene: &Scene,
    options: &RunOptions,
    target: f64,
    progress: &dyn Fn(&str),
) -> Result<String> {
    let mut out = String::from(
        "\n| goal % | photons | photon rays | direct rays | rays | elapsed s | error % |\n\
         |---:|---:|---:|---:|---:|---:|---:|\n",
    );
    for goal in ACCURACY_GOALS
        .into_iter()
        .filter(|&g| g >= target * (1.0 - 1e-9))
    {
        progress(&format!("rays to {:.1} %", 100.0 * goal));
        let mut at_goal = options.clone();
        at_goal.stop.target_error = Some(goal);
        let clock = std::time::Instant::now();
        let result = run(scene, &at_goal, &AtomicBool::new(false), &mut ())?;
        let elapsed = clock.elapsed().as_secs_f64();
        let t = &result.progress.tallies;
        let error = result
            .progress
            .history
            .last()
            .map_or(f64::NAN, |p| p.rel_error);
        let _ = writeln!(
            out,
            "| {:.1} | {} | {} | {} | {} | {elapsed:.3} | {:.3} |",
            100.0 * goal,
            t.photons,
            t.rays,
            t.direct_rays,
            t.rays + t.direct_rays,
            100.0 * error
        );
    }
    Ok(out)
}

/// How the run of `bench_accuracy` went: stop, times, counts, the statistics' share of
/// the run, FOM and VOV.
fn run_line(result: &RunResult, summary: &Summary) -> String {
    let share = |s: f64| 100.0 * s / result.progress.times.elapsed_s.max(1e-9);
    format!(
        "Stopped on {} after {:.3} s (set-up {:.3} s), {} photons, {} rays; direct light {:.3} s ({} replicates, {} shadow rays); statistics and forecasts {:.4} s = {:.3} % of the run; merging {:.4} s = {:.3} %; FOM {:.0} (stable: {}), VOV {:.4}.",
        result.stop_reason.as_str(),
        result.progress.times.elapsed_s,
        result.setup.setup_s,
        result.progress.tallies.photons,
        result.progress.tallies.rays,
        result.progress.times.direct_s,
        result.progress.tallies.direct_replicates,
        result.progress.tallies.direct_rays,
        result.progress.times.stats_s,
        share(result.progress.times.stats_s),
        result.progress.times.merge_s,
        share(result.progress.times.merge_s),
        summary.reliability.fom,
        summary.reliability.fom_stable,
        summary.reliability.vov,
    )
}

/// When the error first reached 5, 2 and 1 %.
fn times_to_accuracy(h: &[HistoryPoint]) -> String {
    let reached: Vec<String> = [0.05, 0.02, 0.01]
        .into_iter()
        .map(|goal| match h.iter().find(|p| p.rel_error <= goal) {
            Some(p) => format!(
                "{:.0} %: {:.3} s ({} photons)",
                100.0 * goal,
                p.elapsed_s,
                p.photons
            ),
            None => format!("{:.0} %: not reached", 100.0 * goal),
        })
        .collect();
    reached.join(", ")
}

/// The forecast made once 10 % of the photons were traced against what the run needed
/// (`None` without history or without a forecast then).
fn forecast_check(h: &[HistoryPoint]) -> Option<String> {
    let last = h.last()?;
    let early = h
        .iter()
        .find(|p| p.photons.saturating_mul(10) >= last.photons)?;
    let (fs, fp) = (early.forecast_s?, early.forecast_photons?);
    Some(format!(
        "Forecast made at {:.1} % of the photons ({:.3} s): {:.3} s and {} photons; actual {:.3} s and {} photons: time {:+.2} %, photons {:+.2} %.",
        100.0 * early.photons as f64 / last.photons as f64,
        early.elapsed_s,
        fs,
        fp,
        last.elapsed_s,
        last.photons,
        100.0 * (fs / last.elapsed_s - 1.0),
        100.0 * (fp as f64 / last.photons as f64 - 1.0),
    ))
}

/// The error-versus-time history with the forecasts made along the way (Markdown).
fn history_table(h: &[HistoryPoint]) -> String {
    let mut out = String::new();
    let _ = writeln!(
        out,
        "| elapsed s | photons | error % | forecast s | forecast photons |"
    );
    let _ = writeln!(out, "|---:|---:|---:|---:|---:|");
    for p in h {
        let _ = writeln!(
            out,
            "| {:.3} | {} | {:.3} | {} | {} |",
            p.elapsed_s,
            p.photons,
            100.0 * p.rel_error,
            p.forecast_s.map_or("–".into(), |f| format!("{f:.3}")),
            p.forecast_photons.map_or("–".into(), |f| f.to_string()),
        );
    }
    out
}
