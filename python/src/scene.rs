//! `luxtally.Scene`: a loaded scene, the TOML document it came from (so `set` can change
//! a value and load again through the same loader) and its ray casters, built once per
//! backend and kept across `set` while the geometry stays the same.

use crate::errors::{to_py, IntoPy, SceneError};
use crate::scene_dict::{self, parse_path, set_at, Step};
use luxtally::accel::{self, Backend, Bvh, RayCaster};
use luxtally::criteria::{StopCriteria, Until};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::Instant;

/// Ray casters built over one geometry, by backend and layout.
pub type Casters = Arc<Mutex<Vec<(Backend, Bvh, Arc<dyn RayCaster>)>>>;

/// A scene, ready to run: `Scene.load(path)` or `Scene.from_dict(d)`.
#[pyclass(module = "luxtally")]
pub struct Scene {
    pub scene: Arc<luxtally::scene::Scene>,
    /// The scene file's content, as `set` changes it.
    document: toml::Table,
    base_dir: PathBuf,
    origin: String,
    pub casters: Casters,
}

/// The sections `set` may change: they carry no geometry.
const SETTABLE: [&str; 2] = ["materials", "lights"];

#[pymethods]
impl Scene {
    /// Loads the scene file at `path`, as `luxtally run` does (relative mesh and
    /// photometry paths against the file's directory).
    #[staticmethod]
    fn load(py: Python<'_>, path: PathBuf) -> PyResult<Scene> {
        let text =
            std::fs::read_to_string(&path).map_err(|e| to_py(luxtally::Error::io(&path, e)))?;
        let scene = py.detach(|| luxtally::scene::load(&path)).py_err()?;
        // Loaded, so the text is valid TOML.
        let document: toml::Table = toml::from_str(&text)
            .map_err(|e| SceneError::new_err(format!("{}: {e}", path.display())))?;
        let base_dir = path.parent().unwrap_or(Path::new("")).to_path_buf();
        Ok(Scene::new(
            scene,
            document,
            base_dir,
            path.display().to_string(),
        ))
    }

    /// A scene from a dict with the scene file's schema (what `tomllib.load` gives).
    /// Relative mesh and photometry paths resolve against `base_dir` (default: the
    /// current directory); `origin` prefixes messages and names the scene when `d` has
    /// no `name`, as the file's path does for a file.
    #[staticmethod]
    #[pyo3(signature = (d, base_dir = None, origin = "<dict>".to_string()))]
    fn from_dict(
        py: Python<'_>,
        d: &Bound<'_, PyDict>,
        base_dir: Option<PathBuf>,
        origin: String,
    ) -> PyResult<Scene> {
        let document = scene_dict::table(d, "")?;
        let base_dir = base_dir.unwrap_or_else(|| PathBuf::from("."));
        let scene = load_document(py, &document, &base_dir, &origin)?;
        Ok(Scene::new(scene, document, base_dir, origin))
    }

    /// Sets the value at a key path of the scene file (`"materials.wall.reflectance"`,
    /// `"lights[0].flux_lm"`; only under `materials` and `lights`) and loads the scene
    /// again, keeping the built ray casters: the geometry does not change. The scene
    /// is then the same as a fresh load of the changed file.
    fn set(&mut self, py: Python<'_>, path: &str, value: &Bound<'_, PyAny>) -> PyResult<()> {
        let steps = parse_path(path)
            .ok_or_else(|| SceneError::new_err(format!("set: `{path}` is not a key path")))?;
        let settable =
            matches!(steps.first(), Some(Step::Key(k)) if SETTABLE.contains(&k.as_str()));
        if !settable {
            return Err(SceneError::new_err(format!(
                "set: `{path}`: only keys under materials and lights can change without \
                 rebuilding the scene; load it anew"
            )));
        }
        let mut document = self.document.clone();
        if !set_at(&mut document, &steps, scene_dict::to_toml(value, path)?) {
            return Err(SceneError::new_err(format!(
                "{}: {path}: no such entry in the scene",
                self.origin
            )));
        }
        let mut scene = load_document(py, &document, &self.base_dir, &self.origin)?;
        if !same_geometry(&scene.geometry, &self.scene.geometry) {
            return Err(SceneError::new_err(format!(
                "set: `{path}` changes the geometry; load the scene anew"
            )));
        }
        scene.path = self.scene.path.clone();
        // The geometry the casters were built over (equal, and shared with them).
        scene.geometry = self.scene.geometry.clone();
        self.scene = Arc::new(scene);
        self.document = document;
        Ok(())
    }

    /// Traces photons until the first stop criterion is met; returns a
    /// `luxtally.Result`. Arguments as `luxtally run`'s flags (None: the scene's
    /// `[simulation]`; `until="decided"` as `--until decided`). `checkpoint`: a directory to save the run's state in every
    /// `checkpoint_every` seconds and at its end (also on Ctrl-C), for `resume`.
    /// `resume`: go on from the checkpoint in that directory. `shard`: `"I/N"`, trace
    /// only that part of the photons (needs `photons` and `checkpoint`; combine with
    /// `luxtally.merge`). `progress`: a callable given a dict after every epoch (on
    /// this thread), or True for a progress bar.
    #[pyo3(signature = (*, photons = None, time_limit = None, target_error = None,
        target = None, absolute = false, min_hits = None, stop_if_unreachable = false,
        until = None, seed = None, threads = None, estimator = None, backend = None, bvh = None,
        progress = None, checkpoint = None, checkpoint_every = crate::run::DEFAULT_PERIOD_S,
        resume = None, shard = None))]
    #[allow(clippy::too_many_arguments)]
    fn run(
        &self,
        py: Python<'_>,
        photons: Option<u64>,
        time_limit: Option<f64>,
        target_error: Option<f64>,
        target: Option<String>,
        absolute: bool,
        min_hits: Option<u64>,
        stop_if_unreachable: bool,
        until: Option<String>,
        seed: Option<u64>,
        threads: Option<usize>,
        estimator: Option<String>,
        backend: Option<String>,
        bvh: Option<String>,
        progress: Option<Bound<'_, PyAny>>,
        checkpoint: Option<PathBuf>,
        checkpoint_every: f64,
        resume: Option<PathBuf>,
        shard: Option<String>,
    ) -> PyResult<Py<PyAny>> {
        let stop = StopCriteria {
            photons,
            time_limit_s: time_limit,
            target_error,
            target,
            absolute,
            min_hits,
            stop_if_unreachable,
            until: match until.as_deref() {
                None => None,
                Some("decided") => Some(Until::Decided),
                Some(other) => {
                    return Err(SceneError::new_err(format!(
                        "--until: unknown value `{other}` (expected decided)"
                    )))
                }
            },
        };
        if !(checkpoint_every > 0.0) {
            return Err(SceneError::new_err(format!(
                "--checkpoint-every: {checkpoint_every} is not a positive number of seconds"
            )));
        }
        let options = crate::run::options(
            &self.scene,
            stop,
            seed,
            threads,
            estimator.as_deref(),
            backend.as_deref(),
            bvh.as_deref(),
        )?;
        let request = crate::run::Request {
            options,
            checkpoint_dir: checkpoint,
            checkpoint_every_s: checkpoint_every,
            resume,
            shard,
        };
        let callback = progress_callback(py, progress)?;
        crate::run::run(py, self, request, callback)
    }

    /// The scene's name.
    #[getter]
    fn name(&self) -> String {
        self.scene.name.clone()
    }

    /// The receivers' names, in file order (observers' hidden receivers excluded).
    #[getter]
    fn receivers(&self) -> Vec<String> {
        let hidden = self.scene.observers.len();
        let shown = self.scene.receivers.len() - hidden;
        self.scene.receivers[..shown]
            .iter()
            .map(|r| r.name.clone())
            .collect()
    }

    /// The materials' names.
    #[getter]
    fn materials(&self) -> Vec<String> {
        self.scene
            .materials
            .iter()
            .map(|m| m.name.clone())
            .collect()
    }

    /// Triangles in the scene.
    #[getter]
    fn triangles(&self) -> usize {
        self.scene.geometry.triangle_count()
    }

    /// Ray casters built so far (one per backend and BVH layout used): `set` keeps them.
    #[getter]
    fn casters_built(&self) -> usize {
        self.casters.lock().map_or(0, |c| c.len())
    }

    /// The scene file's content as a dict (with every `set` applied).
    fn to_dict(&self, py: Python<'_>) -> PyResult<Py<PyAny>> {
        let json = serde_json::to_string(&self.document)
            .map_err(|e| SceneError::new_err(e.to_string()))?;
        Ok(py.import("json")?.call_method1("loads", (json,))?.unbind())
    }

    fn __repr__(&self) -> String {
        format!(
            "Scene({:?}: {} triangles, {} lights, {} receivers)",
            self.scene.name,
            self.triangles(),
            self.scene.lights.len(),
            self.receivers().len()
        )
    }
}

impl Scene {
    fn new(
        scene: luxtally::scene::Scene,
        document: toml::Table,
        base_dir: PathBuf,
        origin: String,
    ) -> Scene {
        Scene {
            scene: Arc::new(scene),
            document,
            base_dir,
            origin,
            casters: Arc::default(),
        }
    }
}

/// The ray caster for `backend` and `layout`, built over `scene`'s geometry once;
/// returns it and when its set-up began (now, when it was built before).
pub fn caster(
    casters: &Casters,
    scene: &luxtally::scene::Scene,
    backend: Backend,
    layout: Bvh,
) -> luxtally::Result<(Arc<dyn RayCaster>, Instant)> {
    let setup = Instant::now();
    let mut built = casters.lock().unwrap_or_else(|p| p.into_inner());
    if let Some((_, _, c)) = built.iter().find(|(b, l, _)| *b == backend && *l == layout) {
        return Ok((c.clone(), setup));
    }
    let c: Arc<dyn RayCaster> = accel::build_with(backend, layout, &scene.geometry)?.into();
    built.push((backend, layout, c.clone()));
    Ok((c, setup))
}

/// `document` loaded as the scene file's text would be (the same loader, messages and
/// scene), relative paths against `base_dir`.
fn load_document(
    py: Python<'_>,
    document: &toml::Table,
    base_dir: &Path,
    origin: &str,
) -> PyResult<luxtally::scene::Scene> {
    let text =
        toml::to_string(document).map_err(|e| SceneError::new_err(format!("{origin}: {e}")))?;
    let mut scene = py
        .detach(|| luxtally::scene::load_str(&text, base_dir, origin))
        .py_err()?;
    scene.path = PathBuf::from(origin);
    Ok(scene)
}

/// Whether two loads made the same geometry: what the ray casters were built over
/// (vertices, triangles, instances) and what tallies index by (materials and objects
/// of the triangles).
fn same_geometry(a: &luxtally::scene::Geometry, b: &luxtally::scene::Geometry) -> bool {
    a.origin == b.origin
        && a.vertices == b.vertices
        && a.triangles == b.triangles
        && a.material == b.material
        && a.object == b.object
        && format!("{:?}", a.instanced) == format!("{:?}", b.instanced)
}

/// `progress` as a callable: True gives the package's progress bar (tqdm where
/// installed, else a plain line), False or None nothing.
fn progress_callback(
    py: Python<'_>,
    progress: Option<Bound<'_, PyAny>>,
) -> PyResult<Option<Py<PyAny>>> {
    let Some(p) = progress else {
        return Ok(None);
    };
    if let Ok(on) = p.cast::<pyo3::types::PyBool>() {
        if !on.is_true() {
            return Ok(None);
        }
        let bar = py
            .import("luxtally._progress")?
            .call_method0("default_bar")?;
        return Ok(Some(bar.unbind()));
    }
    Ok(Some(p.unbind()))
}
