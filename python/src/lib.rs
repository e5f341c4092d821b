//! `luxtally._luxtally`: the engine's Python face. The pure-Python package around it
//! (`python/luxtally/`) adds the `Result` wrapper, progress bars and DataFrames; this
//! module only translates: Python values into the engine's scene file and options,
//! the engine's run into arrays, the engine's errors into exceptions. It holds no
//! engine logic of its own (docs/python.md).

// `!(x > 0.0)` is deliberate, as in the engine: it also rejects NaN.
#![allow(clippy::neg_cmp_op_on_partial_ord)]

use pyo3::prelude::*;

mod errors;
mod photometry;
mod run;
mod scene;
mod scene_dict;
mod shards;
mod transfer;

#[pymodule]
fn _luxtally(m: &Bound<'_, PyModule>) -> PyResult<()> {
    let py = m.py();
    m.add("LuxtallyError", py.get_type::<errors::LuxtallyError>())?;
    m.add("SceneError", py.get_type::<errors::SceneError>())?;
    m.add_class::<scene::Scene>()?;
    m.add_class::<run::RunHandle>()?;
    m.add_class::<photometry::Photometry>()?;
    m.add_function(wrap_pyfunction!(shards::merge, m)?)?;
    m.add_function(wrap_pyfunction!(transfer::load_result, m)?)?;
    m.add_function(wrap_pyfunction!(backends, m)?)?;
    m.add("__version__", env!("CARGO_PKG_VERSION"))?;
    Ok(())
}

/// The ray-casting backends built into this package: always `embree`, and `obvhs`
/// when the package was built with its feature.
#[pyfunction]
fn backends() -> Vec<&'static str> {
    let mut names = vec!["embree"];
    if cfg!(feature = "obvhs") {
        names.push("obvhs");
    }
    names
}
