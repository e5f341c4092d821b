//! A run's numbers into Python: the summary (what summary.json holds) as a dict, and
//! every receiver's per-cell vectors moved, not copied, into numpy arrays shaped like
//! the grid (rows along v, columns along u: summary.json's index j · cells[0] + i is
//! `[j, i]`).

use crate::errors::{IntoPy, LuxtallyError};
use crate::run::RunHandle;
use luxtally::output::summary::{ReceiverSummary, Summary};
use luxtally::scene::adjacency::VertexFaces;
use luxtally::stats::CellStatus;
use numpy::ndarray::Array2;
use numpy::{IntoPyArray, PyArray2};
use pyo3::prelude::*;
use pyo3::types::PyDict;
use std::path::PathBuf;
use std::time::Instant;

/// The finished run as a `luxtally.Result`.
/// Its `summary_s` is the seconds the summary's statistics took (what the CLI computes
/// for summary.json), `transfer_s` those of handing them to Python: the arrays and the
/// dict (BENCHMARKS.md, "Python").
pub fn run_result(py: Python<'_>, handle: RunHandle) -> PyResult<Py<PyAny>> {
    let began = Instant::now();
    let state = handle.result.state(&handle.scene, &handle.options);
    let summary = py.detach(|| luxtally::output::summary::build(&state));
    let summary_s = began.elapsed().as_secs_f64();
    let handle = Py::new(py, handle)?;
    let result = wrap(py, summary, Some(handle.into_any()))?;
    result.setattr(py, "transfer_s", began.elapsed().as_secs_f64() - summary_s)?;
    result.setattr(py, "summary_s", summary_s)?;
    Ok(result)
}

/// `Result.load(out_dir)`: a CLI run's summary.json read back (as `luxtally report`
/// reads it), as a `luxtally.Result` without tallies.
#[pyfunction]
pub fn load_result(py: Python<'_>, out_dir: PathBuf) -> PyResult<Py<PyAny>> {
    let summary = py
        .detach(|| luxtally::output::read_summary(&out_dir))
        .py_err()?;
    wrap(py, summary, None)
}

/// `luxtally.Result(summary_dict, arrays, handle)`.
fn wrap(py: Python<'_>, mut summary: Summary, handle: Option<Py<PyAny>>) -> PyResult<Py<PyAny>> {
    let arrays = PyDict::new(py);
    for (name, r) in summary.receivers.iter_mut() {
        arrays.set_item(name, receiver_arrays(py, r)?)?;
    }
    // Only the numbers the arrays did not take: fast to parse even for 10⁶ cells.
    let json = serde_json::to_string(&summary)
        .map_err(|e| LuxtallyError::new_err(format!("summary: {e}")))?;
    let dict = py.import("json")?.call_method1("loads", (json,))?;
    let class = py.import("luxtally._result")?.getattr("Result")?;
    Ok(class.call1((dict, arrays, handle))?.unbind())
}

/// A receiver's per-cell vectors taken out of its summary into grid-shaped arrays.
fn receiver_arrays<'py>(py: Python<'py>, r: &mut ReceiverSummary) -> PyResult<Bound<'py, PyDict>> {
    let shape = (r.cells[1] as usize, r.cells[0] as usize);
    let d = PyDict::new(py);
    let reliable: Vec<bool> = (r.status.iter())
        .map(|s| *s == CellStatus::Reliable)
        .collect();
    let dark: Vec<bool> = r.status.iter().map(|s| *s == CellStatus::Dark).collect();
    d.set_item("values", grid(py, shape, std::mem::take(&mut r.values))?)?;
    d.set_item("sigma", grid(py, shape, std::mem::take(&mut r.sigma))?)?;
    d.set_item("hits", grid(py, shape, std::mem::take(&mut r.hits))?)?;
    d.set_item("direct", grid(py, shape, std::mem::take(&mut r.direct))?)?;
    let direct_sigma = std::mem::take(&mut r.direct_sigma);
    d.set_item("direct_sigma", grid(py, shape, direct_sigma)?)?;
    d.set_item("vov", grid(py, shape, std::mem::take(&mut r.vov))?)?;
    d.set_item(
        "upper_bound",
        grid(py, shape, std::mem::take(&mut r.upper_bound))?,
    )?;
    d.set_item("dof", grid(py, shape, std::mem::take(&mut r.dof))?)?;
    let histories = std::mem::take(&mut r.scoring_histories);
    d.set_item("scoring_histories", grid(py, shape, histories)?)?;
    d.set_item("reliable", grid(py, shape, reliable)?)?;
    d.set_item("dark", grid(py, shape, dark)?)?;
    // The statuses are the flags above (a word per cell would be a Python object each).
    r.status.clear();
    Ok(d)
}

/// `cells` as a `rows × columns` array (the vector's memory becomes the array's), or
/// None when the summary has no such vector for this receiver (e.g. no direct part).
fn grid<'py, T: numpy::Element>(
    py: Python<'py>,
    shape: (usize, usize),
    cells: Vec<T>,
) -> PyResult<Option<Bound<'py, PyArray2<T>>>> {
    if cells.len() != shape.0 * shape.1 {
        return Ok(None);
    }
    let array =
        Array2::from_shape_vec(shape, cells).map_err(|e| LuxtallyError::new_err(e.to_string()))?;
    Ok(Some(array.into_pyarray(py)))
}

/// The scene map of a run, as `scene_map.ply` holds it but in f64: world vertices,
/// triangles, per-triangle total and indirect illuminance and relative error.
pub fn scene_map<'py>(py: Python<'py>, h: &RunHandle) -> PyResult<Bound<'py, PyDict>> {
    let state = h.result.state(&h.scene, &h.options);
    let g = &h.scene.geometry;
    let faces = py.detach(|| {
        let adjacent = VertexFaces::by_position(&g.triangles, &g.vertices);
        luxtally::output::ply::face_map(&state, &adjacent)
    });
    let vertices: Vec<f64> = (g.vertices.iter())
        .flat_map(|v| (g.origin + v.as_dvec3()).to_array())
        .collect();
    let triangles: Vec<u32> = g.triangles.iter().flatten().copied().collect();
    let d = PyDict::new(py);
    d.set_item("vertices", grid(py, (g.vertices.len(), 3), vertices)?)?;
    d.set_item("triangles", grid(py, (g.triangle_count(), 3), triangles)?)?;
    d.set_item("illuminance_lx", faces.illuminance_lx.into_pyarray(py))?;
    d.set_item("indirect_lx", faces.indirect_lx.into_pyarray(py))?;
    d.set_item("rel_error", faces.rel_error.into_pyarray(py))?;
    Ok(d)
}
