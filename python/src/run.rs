//! `Scene.run`: the engine's run on a worker thread with the GIL released (rayon traces
//! the photons), while the calling thread waits for its epochs: it checks for signals
//! (Ctrl-C) every `POLL` and passes each epoch's progress to the Python callback, so
//! neither ever runs on a worker thread.

use crate::errors::{IntoPy, SceneError};
use crate::scene::{caster, Scene};
use crate::transfer;
use luxtally::accel::{Backend, Bvh};
use luxtally::checkpoint::Checkpointer;
use luxtally::criteria::StopCriteria;
use luxtally::output::{self, Finished, Outputs};
use luxtally::run::{run_from, Observer, RunOptions, RunResult, RunState, Start};
use luxtally::scene::Estimator;
use luxtally::stats::stop::StopReason;
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::mpsc;
use std::sync::Arc;
use std::time::Duration;

/// How often the calling thread checks for Ctrl-C while a run goes on. The run itself
/// stops once the chunks it is tracing are done (its epoch cut short at them), after
/// saving its checkpoint.
const POLL: Duration = Duration::from_millis(100);

/// What the calling thread hears of an epoch.
struct Epoch {
    photons: u64,
    elapsed_s: f64,
    rel_error: f64,
    target_error: Option<f64>,
    forecast_s: Option<f64>,
    max_photons: u64,
    time_limit_s: Option<f64>,
    stop_reason: Option<&'static str>,
}

/// Sends each epoch to the calling thread and saves the checkpoints, on the run's
/// thread.
struct ChannelObserver {
    epochs: mpsc::Sender<Epoch>,
    checkpoints: Option<Checkpointer>,
    /// The first save that failed: the run goes on, `run` raises it at the end.
    save_error: Option<luxtally::Error>,
    /// Where an interrupted run without a checkpoint directory saved its checkpoint.
    interrupted_into: Option<PathBuf>,
}

impl Observer for ChannelObserver {
    fn epoch(&mut self, state: &RunState<'_>) {
        if self.checkpoints.is_none() && state.stop_reason == Some(StopReason::Interrupted) {
            // Ctrl-C with no checkpoint asked for: one in a fresh temporary directory,
            // so the work done is not lost (KeyboardInterrupt names it).
            match interrupt_dir() {
                Ok(dir) => {
                    self.checkpoints = Some(Checkpointer::new(&dir, f64::INFINITY, state.scene));
                    self.interrupted_into = Some(dir);
                }
                Err(e) => {
                    self.save_error.get_or_insert(e);
                }
            }
        }
        if let Some(c) = &mut self.checkpoints {
            if let Err(e) = c.epoch(state) {
                self.save_error.get_or_insert(e);
            }
        }
        let last = state.progress.history.last();
        let _ = self.epochs.send(Epoch {
            photons: state.progress.tallies.photons,
            elapsed_s: state.progress.times.elapsed_s,
            rel_error: last.map_or(f64::NAN, |p| p.rel_error),
            target_error: state.options.stop.target_error,
            forecast_s: state.progress.forecast.map(|f| f.total_s),
            max_photons: state.options.stop.max_photons(),
            time_limit_s: state.options.stop.time_limit_s,
            stop_reason: state.stop_reason.map(StopReason::as_str),
        });
    }
}

/// What `Scene.run` was asked, besides the stop criteria.
pub struct Request {
    pub options: RunOptions,
    pub checkpoint_dir: Option<PathBuf>,
    pub checkpoint_every_s: f64,
    pub resume: Option<PathBuf>,
    pub shard: Option<String>,
}

/// A finished run, for `Result.save` and `Result.scene_map` (its tallies stay in Rust).
#[pyclass(module = "luxtally")]
pub struct RunHandle {
    pub scene: Arc<luxtally::scene::Scene>,
    pub options: RunOptions,
    pub result: RunResult,
}

#[pymethods]
impl RunHandle {
    /// Writes the run's outputs into `out` as `luxtally run --out` does (summary.json,
    /// receivers' EXR/CSV/PNG, scene_map.ply, report.html, indirect_map.bin); `outputs`
    /// as `--outputs` (default all).
    #[pyo3(signature = (out, outputs = None))]
    fn save(&self, py: Python<'_>, out: PathBuf, outputs: Option<String>) -> PyResult<()> {
        let outputs = outputs
            .as_deref()
            .map_or(Ok(Outputs::ALL), Outputs::parse)
            .py_err()?;
        py.detach(|| {
            std::fs::create_dir_all(&out).map_err(|e| luxtally::Error::io(&out, e))?;
            let state = self.result.state(&self.scene, &self.options);
            let finished = Finished {
                run: Some(&state),
                image: None,
            };
            output::write_all(&out, finished, outputs).map(|_| ())
        })
        .py_err()
    }

    /// The scene map: world vertices (n × 3), triangles (m × 3), each triangle's
    /// illuminance (lx) and relative error, as numpy arrays.
    fn scene_map<'py>(&self, py: Python<'py>) -> PyResult<Bound<'py, PyDict>> {
        transfer::scene_map(py, self)
    }
}

/// Runs `scene` as `request` says; `progress` (a callable or None) is called on this
/// thread with a dict after every epoch.
pub fn run(
    py: Python<'_>,
    scene: &Scene,
    request: Request,
    progress: Option<Py<PyAny>>,
) -> PyResult<Py<PyAny>> {
    let shared = scene.scene.clone();
    let mut options = request.options.clone();
    let budget = luxtally::limits::Budget::new(None).py_err()?;
    options.bvh = luxtally::limits::check_run(&shared, &options, None, true, &budget).py_err()?;
    let (start, _) = luxtally::checkpoint::resume::start(
        &shared,
        &options,
        request.resume.as_deref(),
        request.shard.as_deref(),
    )
    .py_err()?;
    // What the worker thread needs of the start (a distributor, MPI's, is never Send).
    let Start { resumed, shard, .. } = start;
    let checkpoint_dir = request.checkpoint_dir.clone().or(request.resume.clone());
    if shard.is_some() && checkpoint_dir.is_none() {
        return Err(SceneError::new_err(
            "shard: a shard's checkpoint is its only output: give checkpoint=DIR",
        ));
    }
    if let Some(dir) = &checkpoint_dir {
        std::fs::create_dir_all(dir)
            .map_err(|e| luxtally::Error::io(dir, e))
            .py_err()?;
    }
    let (caster, setup) = py
        .detach(|| caster(&scene.casters, &shared, options.backend, options.bvh))
        .py_err()?;
    let (tx, rx) = mpsc::channel();
    let observer = ChannelObserver {
        epochs: tx,
        checkpoints: checkpoint_dir
            .as_deref()
            .map(|d| Checkpointer::new(d, request.checkpoint_every_s, &shared)),
        save_error: None,
        interrupted_into: None,
    };
    let interrupt = AtomicBool::new(false);
    let mut raised: Option<PyErr> = None;
    let outcome = py.detach(|| {
        std::thread::scope(|s| {
            let worker = s.spawn(|| {
                let mut observer = observer;
                let start = Start {
                    resumed,
                    shard,
                    distributor: None,
                };
                let r = run_from(
                    &shared,
                    &options,
                    caster.as_ref(),
                    setup,
                    &interrupt,
                    &mut observer,
                    start,
                );
                (r, observer.save_error, observer.interrupted_into)
            });
            let rx = rx;
            wait_for_epochs(&rx, &interrupt, progress.as_ref(), &mut raised);
            worker.join()
        })
    });
    let (result, save_error, interrupted_into) =
        outcome.map_err(|_| crate::errors::LuxtallyError::new_err("the run's thread panicked"))?;
    let result = result.py_err()?;
    if let Some(e) = raised {
        // Ctrl-C (or the callback's exception): the run stopped after the chunks it was
        // tracing, and its checkpoint is saved (in a temporary directory if none was
        // asked for, which a KeyboardInterrupt names).
        if let (Some(dir), true) = (
            &interrupted_into,
            e.is_instance_of::<pyo3::exceptions::PyKeyboardInterrupt>(py),
        ) {
            return Err(pyo3::exceptions::PyKeyboardInterrupt::new_err(format!(
                "interrupted after {} photons; checkpoint saved in {}: \
                 run(..., resume=that directory) continues it",
                result.progress.tallies.photons,
                dir.display()
            )));
        }
        return Err(e);
    }
    if let Some(e) = save_error {
        return Err(crate::errors::to_py(e));
    }
    let handle = RunHandle {
        scene: shared,
        options,
        result,
    };
    transfer::run_result(py, handle)
}

/// A new directory under the system's temporary one for an interrupted run's checkpoint.
fn interrupt_dir() -> luxtally::Result<PathBuf> {
    let nanos = (std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH))
        .map_or(0, |d| d.as_nanos());
    let dir = std::env::temp_dir().join(format!(
        "luxtally-interrupted-{}-{nanos}",
        std::process::id()
    ));
    std::fs::create_dir_all(&dir).map_err(|e| luxtally::Error::io(&dir, e))?;
    Ok(dir)
}

/// The calling thread while the run goes on: each epoch to `progress`, signals
/// checked every [`POLL`]; the first exception (KeyboardInterrupt, or the callback's)
/// goes to `raised` and stops the run after the chunks it is tracing.
fn wait_for_epochs(
    rx: &mpsc::Receiver<Epoch>,
    interrupt: &AtomicBool,
    progress: Option<&Py<PyAny>>,
    raised: &mut Option<PyErr>,
) {
    loop {
        let message = rx.recv_timeout(POLL);
        let done = matches!(message, Err(mpsc::RecvTimeoutError::Disconnected));
        Python::attach(|py| {
            let mut failed = py.check_signals().err();
            if let (Ok(epoch), Some(callback), None) = (&message, progress, &raised) {
                failed = failed.or_else(|| call_progress(py, callback, epoch).err());
            }
            if let (Some(e), None) = (failed, &raised) {
                interrupt.store(true, Ordering::SeqCst);
                *raised = Some(e);
            }
        });
        if done {
            return;
        }
    }
}

fn call_progress(py: Python<'_>, callback: &Py<PyAny>, e: &Epoch) -> PyResult<()> {
    let d = PyDict::new(py);
    d.set_item("photons", e.photons)?;
    d.set_item("max_photons", e.max_photons)?;
    d.set_item("elapsed_s", e.elapsed_s)?;
    d.set_item("time_limit_s", e.time_limit_s)?;
    d.set_item("rel_error", e.rel_error)?;
    d.set_item("target_error", e.target_error)?;
    d.set_item("forecast_s", e.forecast_s)?;
    d.set_item("stop_reason", e.stop_reason)?;
    callback.call1(py, (d,))?;
    Ok(())
}

/// The run's options: the scene's `[simulation]`, overridden by `run`'s arguments as
/// the CLI's flags override it.
#[allow(clippy::too_many_arguments)]
pub fn options(
    scene: &luxtally::scene::Scene,
    stop: StopCriteria,
    seed: Option<u64>,
    threads: Option<usize>,
    estimator: Option<&str>,
    backend: Option<&str>,
    bvh: Option<&str>,
) -> PyResult<RunOptions> {
    let mut options = RunOptions::from_scene(scene);
    options.stop = options.stop.overridden_by(&stop);
    if let Some(seed) = seed {
        options.seed = seed;
    }
    if let Some(t) = threads {
        if t == 0 {
            return Err(SceneError::new_err("--threads: must be at least 1"));
        }
        luxtally::run::check_threads(t).py_err()?;
        options.threads = t;
    }
    if let Some(name) = backend {
        options.backend = name.parse::<Backend>().py_err()?;
    }
    if let Some(name) = bvh {
        options.bvh = match name {
            "auto" => Bvh::Auto,
            "fast" => Bvh::Fast,
            "compact" => Bvh::Compact,
            other => {
                return Err(SceneError::new_err(format!(
                    "--bvh: unknown layout `{other}` (expected auto, fast or compact)"
                )))
            }
        };
    }
    if let Some(name) = estimator {
        let e = Estimator::from_name(name).ok_or_else(|| {
            SceneError::new_err(format!(
                "--estimator: unknown estimator `{name}` (expected {})",
                Estimator::expected()
            ))
        })?;
        options.estimator = Some(e);
    }
    Ok(options)
}

pub use luxtally::checkpoint::DEFAULT_PERIOD_S;
