//! The photon pass of `run` and `render`: Ctrl-C, the start (fresh, resumed, a shard),
//! checkpoints and progress while it runs, then the run's outputs and printed lines.

use crate::observer::CliObserver;
use crate::run::RunArgs;
use luxtally::accel::RayCaster;
use luxtally::distributed::Distributor;
use luxtally::output::{self, summary, Finished, Outputs};
use luxtally::run::{run_from, RunOptions, RunResult, Start};
use luxtally::scene::Scene;
use luxtally::{Error, Result};
use std::path::Path;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::Arc;
use std::time::Instant;

/// Runs with all stop criteria, saving checkpoints into `out`; [`finish_run`] writes
/// its outputs.
pub fn photon_pass(
    args: &RunArgs,
    scene: &Scene,
    options: &RunOptions,
    caster: &dyn RayCaster,
    setup: Instant,
    out: &Path,
    distributor: Option<Box<dyn Distributor>>,
) -> Result<RunResult> {
    let interrupt = interrupt_on_ctrl_c();
    let mut start = start_of(args, scene, options, out)?;
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
    let mut observer = CliObserver::new(args, scene, out);
    let result = run_from(
        scene,
        options,
        caster,
        setup,
        &interrupt,
        &mut observer,
        start,
    )?;
    observer.finish(&result.state(scene, options))?;
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

/// Where the run starts (`--resume`, `--shard`: `checkpoint::resume` decides), saying
/// so when it resumes from another folder than `out`.
fn start_of(args: &RunArgs, scene: &Scene, options: &RunOptions, out: &Path) -> Result<Start> {
    let resume = args.resume.as_deref();
    let (start, checkpoint) =
        luxtally::checkpoint::resume::start(scene, options, resume, args.shard.as_deref())?;
    if let (Some(path), Some(dir)) = (checkpoint, resume) {
        if dir != out && !args.quiet {
            eprintln!(
                "resuming from {}; outputs in {}",
                path.display(),
                out.display()
            );
        }
    }
    Ok(start)
}

/// summary.json and the files `outputs` asks for, then the run's printed lines; nothing
/// for a shard, whose checkpoint is its output.
pub fn finish_run(
    args: &RunArgs,
    out: &Path,
    scene: &Scene,
    options: &RunOptions,
    result: &RunResult,
    outputs: Outputs,
) -> Result<()> {
    if result.progress.shard.is_none() {
        let state = result.state(scene, options);
        let finished = Finished {
            run: Some(&state),
            image: None,
        };
        let s = output::write_all(out, finished, outputs)?;
        if let (Some(s), false) = (s, args.quiet) {
            print_run(&s, out);
        }
    }
    Ok(())
}

/// The run's lines on stdout: totals, each receiver, the global map, what makes the
/// error unreliable.
fn print_run(s: &summary::Summary, out: &Path) {
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
        println!("  receiver {name}: {}", receiver_line(r));
    }
    if let Some(why) = &s.target_unreachable {
        println!("  target unreachable: {why}");
    }
    if let Some(v) = &s.verdicts {
        print_verdicts(v);
    }
    for (name, o) in s.observers.iter().flatten() {
        println!("  observer {name}: {}", observer_line(o));
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

/// The overall verdict and one line per check.
fn print_verdicts(v: &luxtally::stats::verdict::Verdicts) {
    let word = |o| {
        serde_json::to_value(o)
            .ok()
            .and_then(|x| x.as_str().map(String::from))
    };
    println!(
        "  verdict: {} at {} % confidence over {} checks (anytime-valid bounds)",
        word(v.overall).unwrap_or_default(),
        100.0 * v.confidence,
        v.checks.len()
    );
    for (i, c) in v.checks.iter().enumerate() {
        let first_of_requirement = i == 0 || v.checks[i - 1].requirement != c.requirement;
        if let (true, Some(basis)) = (first_of_requirement, &c.basis) {
            println!("    {}: limits from {basis}", c.requirement);
        }
        let expected = if c.reliable {
            c.decision_photons
                .map(|n| format!(", decided by about {n} photons"))
                .unwrap_or_default()
        } else {
            ", σ not yet reliable".to_string()
        };
        println!(
            "    {} {} {}: {} ({:.4}, bounds {:.4} to {:.4}, margin {:+.1}σ{expected})",
            c.requirement,
            c.figure,
            c.limit_text(),
            word(c.outcome).unwrap_or_default(),
            c.value,
            c.low,
            c.high,
            c.margin_sigma
        );
    }
}

/// A receiver's mean and error (over the cells that have one), and its cells that are
/// unreliable or dark.
fn receiver_line(r: &summary::ReceiverSummary) -> String {
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
    if let Some(df) = &r.daylight_factor {
        flags += &format!(
            "; daylight factor {:.3} % ({} % in {:.3}–{:.3} %, least cell {:.3} %)",
            df.mean.value,
            100.0 * r.figures.confidence,
            df.mean.low,
            df.mean.high,
            df.min.value
        );
    }
    format!("mean {:.4} {}, {error}{flags}", r.mean, r.unit)
}

/// An observer's UGR and σ, or why it has none.
fn observer_line(o: &luxtally::output::observers::ObserverSummary) -> String {
    let value = match (o.ugr, o.ugr_sigma) {
        (Some(u), Some(s)) => format!("UGR {u:.1} ± {s:.1}"),
        (Some(u), None) => format!("UGR {u:.1} (error unknown)"),
        _ => "UGR undefined".to_string(),
    };
    match &o.invalid_reason {
        Some(why) => format!("{value} (not valid: {why})"),
        None => value,
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

/// A flag the first Ctrl-C sets (the run stops at its next chunk and writes its
/// outputs); a second one ends the process at once.
pub fn interrupt_on_ctrl_c() -> Arc<AtomicBool> {
    let interrupt = Arc::new(AtomicBool::new(false));
    let flag = interrupt.clone();
    let _ = ctrlc::set_handler(move || {
        if flag.swap(true, Ordering::SeqCst) {
            std::process::exit(130);
        }
    });
    interrupt
}
