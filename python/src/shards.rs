//! `luxtally.merge`: shards' checkpoints folded into the whole run, as `luxtally merge`.

use crate::errors::IntoPy;
use crate::run::RunHandle;
use crate::scene::Scene;
use crate::transfer;
use luxtally::accel;
use luxtally::checkpoint::{merge_shards, merged_options, Checkpoint};
use pyo3::prelude::*;
use std::path::PathBuf;
use std::sync::Arc;
use std::time::Instant;

/// The shards in `dirs` (each a `checkpoint=` directory of a `shard=` run) merged into
/// the run they split, as a `luxtally.Result`; `scene` (a `luxtally.Scene`, or a path)
/// defaults to the scene file the shards recorded. The same numbers as one unsharded
/// run.
/// The scene a merge is given: one loaded in Python (as `set` left it), or a file.
enum Given {
    Loaded(Arc<luxtally::scene::Scene>),
    File(PathBuf),
}

#[pyfunction]
#[pyo3(signature = (dirs, scene = None, threads = None))]
pub fn merge(
    py: Python<'_>,
    dirs: Vec<PathBuf>,
    scene: Option<&Bound<'_, PyAny>>,
    threads: Option<usize>,
) -> PyResult<Py<PyAny>> {
    let given = match scene {
        None => None,
        Some(s) => Some(match s.extract::<PyRef<'_, Scene>>() {
            Ok(loaded) => Given::Loaded(loaded.scene.clone()),
            Err(_) => Given::File(s.extract::<PathBuf>()?),
        }),
    };
    let handle = py
        .detach(|| -> luxtally::Result<RunHandle> {
            let mut shards = Vec::new();
            for dir in &dirs {
                let (c, path) = Checkpoint::load(dir)?;
                shards.push((path, c));
            }
            let Some((first_path, first)) = shards.first() else {
                return Err(luxtally::Error::input(
                    "merge",
                    "no shard directories given",
                ));
            };
            let scene = match given {
                Some(Given::Loaded(scene)) => scene,
                Some(Given::File(path)) => Arc::new(luxtally::scene::load(&path)?),
                None => Arc::new(luxtally::scene::load(&PathBuf::from(&first.scene_path))?),
            };
            let mut options = merged_options(&scene, first, first_path)?;
            if let Some(t) = threads {
                if t == 0 {
                    return Err(luxtally::Error::input("--threads", "must be at least 1"));
                }
                luxtally::run::check_threads(t)?;
                options.threads = t;
            }
            let setup = Instant::now();
            let caster = accel::build_with(options.backend, options.bvh, &scene.geometry)?;
            let result = merge_shards(&scene, &options, caster.as_ref(), setup, shards)?;
            Ok(RunHandle {
                scene,
                options,
                result,
            })
        })
        .py_err()?;
    transfer::run_result(py, handle)
}
